"""A scenario's result files: Parquet tables, Figs. 6-12 and summary.md."""

from __future__ import annotations

from pathlib import Path

from ..io.atomic import write_text
from ..io.results import write_parquet
from .run import ScenarioResult
from .timeline import summary_markdown


def write_scenario(res: ScenarioResult, out: Path, meta: dict) -> list:
    """Write timeseries.parquet, events.parquet, segments.parquet, the figures
    (:func:`ftc_mc.plots.scenario_figures`) and summary.md to ``out``.

    Each Parquet file's metadata is ``meta`` plus ``controller_names``, the
    names of the controller codes flown (:attr:`ScenarioResult.controller_names`),
    which the report reads instead of finding them again.

    Returns
    -------
    list of Path
        The files written.
    """
    from ..plots import scenario_figures  # matplotlib: imported only to write figures

    out.mkdir(parents=True, exist_ok=True)
    meta = {**meta, "controller_names": list(res.controller_names)}
    write_parquet(res.timeseries, out / "timeseries.parquet", meta)
    write_parquet(res.events, out / "events.parquet", meta)
    write_parquet(res.segments, out / "segments.parquet", meta)
    figs = scenario_figures(res, out)
    write_text(out / "summary.md", summary_markdown(res) + "\n## Figures\n\n"
               + "\n".join(f"![{p.stem}]({p.name})" for p in figs) + "\n")
    return [out / f for f in ("timeseries.parquet", "events.parquet", "segments.parquet",
                              "summary.md")] + figs
