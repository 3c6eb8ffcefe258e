"""One Markdown report from finished run, scenario and sweep directories.

:func:`build_report` reads only the Parquet files of each input directory (so a
report can be rebuilt at any time without rerunning anything) and writes a
Markdown file with:

* for each run (``ftc-mc run``): Tables 2-3 beside the paper's counts, per
  signature variant, with 95 % Wilson intervals; the excluded trials and why;
  a paired comparison of the signature variants; a figure of the reset-delay
  and detection-time distributions (``runs.py``);
* for each scenario (``ftc-mc scenario``): the event timeline beside the
  paper's (section 5.2) and links to the scenario's own figures
  (``scenario.py``);
* for each sweep (``ftc-mc sweep``): the threshold trade-off and the
  recommended threshold (``sweep.py``); the operating characteristic of its
  designs (flight hours between false resets against detection delay and
  correct-block rate, the paper's design as the baseline) and the design
  recommended for its truth plant and turbulence (``operating.py``), with the
  hours of a matching endurance run where one is given;
* for each endurance run (``ftc-mc endurance``): false resets per fault-free
  flight hour per design, the one-sided 95 % bound, whether the false-alarm
  target is shown and the hours that would show it (``endurance.py``);
* when at least two runs flew different truth plants or turbulence levels
  (config section ``plant``): their rates side by side per transition, with
  false resets per flight hour and the changes against the reference plant
  (``plants.py``);
* the provenance of every input (kind, version, git revision, seed, config;
  ``provenance.py``).

Every section names the truth plant and turbulence of its input (results
written before the ``plant`` section existed flew the linear plant without
turbulence).  Inputs whose metadata show different package versions or git
revisions are refused unless ``allow_mixed`` is set.  Figures go to
``<out stem>_figures/`` beside the report and are linked by relative paths;
they are drawn by ``ftc_mc/plots/campaign.py``.  Directories are read by
``load.py``; the statistics come from ``ftc_mc/stats.py``.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import UserError
from ..io.atomic import write_text
from .load import (RUN_TABLES, SCENARIO_TABLES, SWEEP_TABLES, ResultDir,
                   load_result_dir, unique_dirs)
from .markdown import DEFAULT_PLANT, plant_condition, slugs
from .plants import (IGNORED_CAMPAIGN_KEYS, PLANT_FIGURE, condition_labels,
                     condition_order, condition_rates, config_differences,
                     plant_conditions_differ, plant_rates, plant_section, reference_index)
from .provenance import (check_provenance, mixed_message, provenance_groups,
                         provenance_section)
from .runs import (SIGNIFICANCE, exclusion_table, paired_counts, paper_tables,
                   run_section, variant_comparison)
from .endurance import endurance_section, matching_endurance
from .operating import (BASELINE_DESIGNS, operating_points, operating_section,
                        recommend_design)
from .scenario import (scenario_section, switches_and_excitations,
                       timeline_table)
from .sweep import FALSE_RESET_TARGET_PER_H, recommend_threshold, sweep_section

__all__ = [
    "build_report",
    # load.py
    "RUN_TABLES", "SCENARIO_TABLES", "SWEEP_TABLES", "ResultDir", "load_result_dir",
    "unique_dirs",
    # markdown.py
    "DEFAULT_PLANT", "plant_condition", "slugs",
    # provenance.py
    "check_provenance", "mixed_message", "provenance_groups", "provenance_section",
    # runs.py
    "SIGNIFICANCE", "exclusion_table", "paired_counts", "paper_tables", "run_section",
    "variant_comparison",
    # scenario.py
    "scenario_section", "switches_and_excitations", "timeline_table",
    # sweep.py
    "FALSE_RESET_TARGET_PER_H", "recommend_threshold", "sweep_section",
    # operating.py
    "BASELINE_DESIGNS", "operating_points", "operating_section", "recommend_design",
    # plants.py
    "IGNORED_CAMPAIGN_KEYS", "PLANT_FIGURE", "condition_labels", "condition_order",
    "condition_rates", "config_differences", "plant_conditions_differ", "plant_rates",
    "plant_section", "reference_index",
]


def _check_out(out: Path) -> None:
    if out.is_dir():
        raise UserError(f"-o/--output: {out} is a directory; give a Markdown file name")


def build_report(dirs: list, out: Path, allow_mixed: bool = False) -> Path:
    """Write one Markdown report of run, scenario and sweep directories.

    Parameters
    ----------
    dirs : list of Path
        Directories written by ``ftc-mc run``, ``ftc-mc scenario`` or
        ``ftc-mc sweep``, in any mix; only their Parquet files are read.
    out : Path
        The Markdown file, written atomically.  Figures go to
        ``<out stem>_figures/`` beside it.  When at least two runs differ in truth
        plant or turbulence, a section compares them (:func:`plant_section`).
    allow_mixed : bool
        Build the report even if the inputs come from different package versions
        or git revisions (a warning is added to the report).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    UserError
        No input, an input without results, or mixed provenance without
        ``allow_mixed``.  Nothing is written then.
    """
    out = Path(out)
    _check_out(out)
    if not dirs:
        raise UserError("no input directories given")
    inputs = [load_result_dir(d) for d in unique_dirs(dirs)]
    warning = check_provenance(inputs, allow_mixed)
    fig_dir = out.parent / f"{out.stem}_figures"
    lines = ["# ftc-mc report", "",
             f"Built from the Parquet files of {len(inputs)} result director"
             f"{'y' if len(inputs) == 1 else 'ies'}; rebuild it at any time with "
             "`ftc-mc report`.", ""]
    if warning:
        lines += [f"> **Warning: mixed inputs.** {warning}.", ""]
    names = slugs(inputs)
    for r, slug in zip(inputs, names):
        if r.kind == "run":
            lines += run_section(r, fig_dir, slug, out)
        elif r.kind == "sweep":
            lines += sweep_section(r, fig_dir, slug, out, matching_endurance(
                [e for e in inputs if e.kind == "endurance"], r.meta.get("config", {})))
        elif r.kind == "endurance":
            lines += endurance_section(r, fig_dir, slug, out)
        else:
            lines += scenario_section(r, out)
    runs = [(r, slug) for r, slug in zip(inputs, names) if r.kind == "run"]
    if plant_conditions_differ([r for r, _ in runs]):
        lines += plant_section([r for r, _ in runs], [s for _, s in runs], fig_dir, out)
    lines += provenance_section(inputs, warning)
    write_text(out, "\n".join(lines))
    return out
