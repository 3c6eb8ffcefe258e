"""``ftc_mc.report``: the truth plant in every header and the plant comparison.

Four small real runs (two transitions, a few trials, nominal controller, 10 s
trials) are made once per module through the CLI:

* ``lin``: linear plant, no turbulence (seed 2026, 6 trials);
* ``lin_b``: the same condition with another seed and trial count;
* ``nl``: nonlinear plant, no turbulence;
* ``nlt``: nonlinear plant, light turbulence (another seed and trial count).

What is checked:

* each run and sweep section names its truth plant and turbulence; results
  written before the ``plant`` section existed read as linear / none;
* the section "Truth plant and turbulence" appears only when two runs differ in
  (plant kind, turbulence); not for one run, nor for two of the same condition;
* its numbers equal those computed here from ``trials.parquet`` (rates,
  false resets per flight hour with the Garwood interval, medians, changes
  against the reference), its rows are in the documented order, repeated
  conditions carry the slug, the excluded trials are counted;
* a config difference beyond ``plant``/``campaign.trials``/``campaign.seed``
  gives one warning line naming the section;
* the figure exists and is linked relatively.
"""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pandas as pd
import pytest
import scipy.stats
import yaml
from click.testing import CliRunner

from ftc_mc.campaign.transitions import TRANSITION_TABLE
from ftc_mc.cli import cli
from ftc_mc.io.results import read_metadata, write_parquet
from ftc_mc.conventions import DEFAULT_AIRFRAME
from ftc_mc.report import (build_report, condition_labels, condition_order,
                           config_differences, reference_index)

from result_dirs import copy_dir, same_stamp

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)]+)\)")
HEADING = "## Truth plant and turbulence"
FAULT_TIME_S = 5.0
BASE = {"campaign": {"transitions": ["elevon_lock", "engine_lock"], "trials": 6,
                     "signature": "swapped", "seed": 2026},
        "controller": {"kind": "nominal"},
        # the authors' strong engine: engine locks leave the envelope, so some
        # trials are excluded (test_excluded_trials_do_not_enter_the_rates)
        "model": {"airframe": "x8-gryte2018"},
        "timing": {"fault_time_s": FAULT_TIME_S, "window_s": 3.0, "duration_s": 10.0}}
RUNS = {
    "lin": ({"kind": "linear"}, {}),
    "lin_b": ({"kind": "linear", "turbulence": "none"}, {"seed": 7, "trials": 4}),
    "nl": ({"kind": "nonlinear"}, {}),
    "nlt": ({"kind": "nonlinear", "turbulence": "light"}, {"seed": 11, "trials": 5}),
}


def _config(plant: dict, campaign: dict) -> dict:
    cfg = {k: dict(v) for k, v in BASE.items()}
    cfg["campaign"].update(campaign)
    cfg["plant"] = plant
    return cfg


def _edit_config(run: Path, edit) -> None:
    """Apply ``edit`` to the config stored in every Parquet file of ``run``."""
    for path in run.glob("*.parquet"):
        meta = read_metadata(path)
        edit(meta["config"])
        write_parquet(pd.read_parquet(path), path, meta)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """The four run directories, by name."""
    base = tmp_path_factory.mktemp("plant_runs")
    out = {}
    for name, (plant, campaign) in RUNS.items():
        cfg_path = base / f"{name}.yaml"
        cfg_path.write_text(yaml.safe_dump(_config(plant, campaign)), encoding="utf-8")
        res = CliRunner().invoke(cli, ["run", str(cfg_path), "--out", str(base / name),
                                       "--quiet", "--jobs", "1"])
        assert res.exit_code == 0, res.output
        out[name] = base / name
    for d in out.values():
        same_stamp(out["lin"], d)
    return out


def _report(dirs, tmp_path: Path) -> str:
    return build_report(list(dirs), tmp_path / "out" / "r.md").read_text(encoding="utf-8")


def _table(text: str, heading: str) -> pd.DataFrame:
    """The first Markdown table after ``heading``, as strings with its header."""
    lines = text.split(heading + "\n", 1)[1].splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("|"))
    rows = []
    for line in lines[first:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return pd.DataFrame(rows[2:], columns=rows[0])


def _section(text: str) -> str:
    return text.split(HEADING, 1)[1].split("\n## ", 1)[0]


def _expected(run: Path) -> pd.DataFrame:
    """Per (transition, variant), computed here from ``trials.parquet``."""
    t = pd.read_parquet(run / "trials.parquet")
    rows = []
    for (name, variant), g in t.groupby(["transition", "variant"]):
        ok = g[g["judged"]]
        # exposure: trials flying nominal before the switch (all of these rows)
        k = int(ok["false_resets"].sum())
        hours = int((ok["mode_pre"] == "nominal").sum()) * FAULT_TIME_S / 3600
        lo = scipy.stats.chi2.ppf(0.025, 2 * k) / 2 / hours if k else 0.0
        hi = scipy.stats.chi2.ppf(0.975, 2 * k + 2) / 2 / hours
        delay = ok["first_reset_s"].dropna()
        det = ok["detection_s"].dropna()
        rows.append({"transition": name, "variant": variant, "judged": len(ok),
                     "inap": 100 * ok["inappropriate"].sum() / len(ok),
                     "no_reset": 100 * ok["no_reset"].sum() / len(ok),
                     "per_h": k / hours, "lo": lo, "hi": hi,
                     "delay": np.median(delay) if len(delay) else np.nan,
                     "det": np.median(det) if len(det) else np.nan})
    return pd.DataFrame(rows).set_index(["transition", "variant"])


def _rate_cell(cell: str):
    m = re.fullmatch(r"(\S+) \((\S+?)-(\S+)\)", cell)
    assert m, cell
    return [float(x.replace(",", "")) for x in m.groups()]


def _fmt(x) -> str:
    return "-" if not np.isfinite(x) else f"{x:.1f}"


def test_every_run_section_names_its_plant(runs, tmp_path):
    text = _report([runs["lin"], runs["nlt"]], tmp_path)
    for name, plant in (("lin", "`linear`, turbulence `none`"),
                        ("nlt", "`nonlinear`, turbulence `light`")):
        section = text.split(f"## Run `{runs[name]}`", 1)[1].split("\n## ", 1)[0]
        assert f"truth plant {plant}." in section


def test_no_plant_section_for_one_run_or_one_condition(runs, tmp_path):
    one = _report([runs["nl"]], tmp_path / "one")
    assert HEADING not in one and "plant_turbulence.png" not in one
    assert "truth plant `nonlinear`, turbulence `none`" in one
    same = _report([runs["lin"], runs["lin_b"]], tmp_path / "same")
    assert HEADING not in same
    assert not (tmp_path / "same" / "out" / "r_figures" / "plant_turbulence.png").exists()


def test_plant_section_numbers_match_trials(runs, tmp_path):
    text = _report([runs["nlt"], runs["lin"], runs["nl"]], tmp_path)
    assert HEADING in text
    table = _table(text, HEADING)
    labels = {"lin": "linear / none", "nl": "nonlinear / none", "nlt": "nonlinear / light"}
    expected = {name: _expected(runs[name]) for name in labels}
    order = [TRANSITION_TABLE[n].label for n in ("elevon_lock", "engine_lock")]
    # grouped by transition in paper order, then the conditions in report order
    assert list(table["transition"]) == [lab for lab in order for _ in range(3)]
    assert list(table["condition"]) == list(labels.values()) * 2
    assert set(table["signature"]) == {"swapped"}
    by_label = {v: k for k, v in labels.items()}
    for _, row in table.iterrows():
        name = next(n for n, t in TRANSITION_TABLE.items() if t.label == row["transition"])
        run = by_label[row["condition"]]
        e = expected[run].loc[(name, "swapped")]
        ref = expected["lin"].loc[(name, "swapped")]
        assert int(row["judged"]) == e["judged"]
        assert row["inappropriate [%]"] == f"{e['inap']:.1f}"
        assert row["no reset [%]"] == f"{e['no_reset']:.1f}"
        rate, lo, hi = _rate_cell(row["false resets / flight h (95 % CI)"])
        for got, want in ((rate, e["per_h"]), (lo, e["lo"]), (hi, e["hi"])):
            assert got == pytest.approx(want, rel=5e-3, abs=1e-9)
        assert row["first reset median [s]"] == _fmt(e["delay"])
        assert row["detection median [s]"] == _fmt(e["det"])
        if run == "lin":
            assert row["Δ inappropriate [pp]"] == row["Δ no reset [pp]"] == "ref"
        else:
            assert row["Δ inappropriate [pp]"] == f"{e['inap'] - ref['inap']:+.1f}"
            assert row["Δ no reset [pp]"] == f"{e['no_reset'] - ref['no_reset']:+.1f}"
    assert f"reference `linear / none` (`{runs['lin']}`)" in text


def test_plant_section_counts_excluded_trials(runs, tmp_path):
    section = _section(_report([runs["lin"], runs["nlt"]], tmp_path))
    note = next(line for line in section.splitlines() if line.startswith("Trials excluded"))
    for name, label in (("lin", "linear / none"), ("nlt", "nonlinear / light")):
        t = pd.read_parquet(runs[name] / "trials.parquet")
        out = t[~t["judged"]]
        assert not out["resets_truncated"].any()  # so the reason is the status
        text = f"`{label}` {len(out)} of {len(t)}"
        if len(out):
            text += " (" + ", ".join(f"{k} {v}" for k, v in
                                     out["status"].value_counts().items()) + ")"
        assert text in note


def test_repeated_condition_is_labelled_with_slug(runs, tmp_path):
    table = _table(_report([runs["lin"], runs["nl"], runs["lin_b"]], tmp_path), HEADING)
    assert list(table["condition"][:3]) == ["linear / none (lin)", "linear / none (lin_b)",
                                            "nonlinear / none"]
    ref = table[table["condition"] == "linear / none (lin)"]
    assert set(ref["Δ inappropriate [pp]"]) == {"ref"}
    other = table[table["condition"] == "linear / none (lin_b)"]
    assert "ref" not in set(other["Δ inappropriate [pp]"])


def test_results_without_plant_section_read_as_linear(runs, tmp_path):
    old = copy_dir(runs["lin"], tmp_path / "old")
    _edit_config(old, lambda cfg: cfg.pop("plant"))
    assert "plant" not in read_metadata(old / "summary.parquet")["config"]
    text = _report([runs["nl"], old], tmp_path)
    section = text.split(f"## Run `{old}`", 1)[1].split("\n## ", 1)[0]
    assert "truth plant `linear`, turbulence `none`." in section
    assert "linear / none" in set(_table(text, HEADING)["condition"])
    assert "Warning" not in _section(text)


def test_config_difference_warning(runs, tmp_path):
    # seed and trial count differ (ignored): no warning
    assert "Warning" not in _section(_report([runs["lin"], runs["nlt"]], tmp_path / "a"))
    changed = copy_dir(runs["nl"], tmp_path / "changed")
    _edit_config(changed, lambda cfg: cfg["estimator"].update(t_q=30.0))
    section = _section(_report([runs["lin"], changed], tmp_path / "b"))
    warnings = [line for line in section.splitlines() if "Warning" in line]
    assert len(warnings) == 1
    assert "`estimator`" in warnings[0] and "`campaign`" not in warnings[0]
    assert "`timing`" not in warnings[0]


def test_plant_figure_exists_and_is_linked(runs, tmp_path):
    out = tmp_path / "rep" / "r.md"
    build_report([runs["lin"], runs["nl"]], out)
    fig = out.parent / "r_figures" / "plant_turbulence.png"
    assert fig.is_file() and fig.stat().st_size > 1000
    assert fig.read_bytes()[:8] == PNG_SIGNATURE
    links = IMAGE.findall(_section(out.read_text(encoding="utf-8")))
    assert [Path(unquote(link)) for link in links] == [Path("r_figures/plant_turbulence.png")]


def test_condition_order_reference_and_differences():
    conds = [("nonlinear", "severe"), ("nonlinear", "light"), ("linear", "moderate"),
             ("nonlinear", "none"), ("linear", "none")]
    assert condition_order(conds) == [4, 2, 3, 1, 0]
    assert reference_index(conds) == 4
    assert reference_index(conds[:4]) == 0
    assert condition_labels([("linear", "none"), ("linear", "none"), ("nonlinear", "none")],
                            ["a", "b", "c"]) == ["linear / none (a)", "linear / none (b)",
                                                 "nonlinear / none"]
    a = {"campaign": {"trials": 5, "seed": 1, "signature": "both"},
         "plant": {"kind": "linear"}, "timing": {"window_s": 10}}
    b = {"campaign": {"trials": 9, "seed": 2, "signature": "both"},
         "plant": {"kind": "nonlinear"}, "timing": {"window_s": 10}}
    assert config_differences([a, b]) == []
    c = {**b, "campaign": {**b["campaign"], "signature": "paper"}, "timing": {"window_s": 5}}
    assert config_differences([a, b, c]) == ["campaign", "timing"]


def test_excluded_trials_do_not_enter_the_rates(runs, tmp_path):
    edited = copy_dir(runs["nl"], tmp_path / "nl")
    path = edited / "trials.parquet"
    t = pd.read_parquet(path)
    out = ~t["judged"]
    assert out.any()  # the nonlinear engine locks leave the envelope in the window
    t.loc[out, ["inappropriate", "no_reset"]] = [False, True]
    t.loc[out, ["false_resets"]] = 1000
    t.loc[out, ["first_reset_s", "detection_s"]] = 99.0
    write_parquet(t, path, read_metadata(path))
    cols = ["judged", "inappropriate [%]", "no reset [%]",
            "false resets / flight h (95 % CI)", "detection median [s]"]
    original = _table(_report([runs["lin"], runs["nl"]], tmp_path / "a"), HEADING)
    changed = _table(_report([runs["lin"], edited], tmp_path / "b"), HEADING)
    pd.testing.assert_frame_equal(original[cols], changed[cols])
    # spread the judged delays so that the excluded ones would move the median
    t.loc[~out, "first_reset_s"] = np.linspace(0.1, 3.0, int((~out).sum()))
    write_parquet(t, path, read_metadata(path))
    changed = _table(_report([runs["lin"], edited], tmp_path / "c"), HEADING)
    rows = changed[changed["condition"] == "nonlinear / none"]
    for label, row in zip(rows["transition"], rows["first reset median [s]"]):
        name = next(n for n, tr in TRANSITION_TABLE.items() if tr.label == label)
        ok = t[(t["transition"] == name) & t["judged"]]
        assert row == _fmt(np.median(ok["first_reset_s"]))


def test_sweep_section_names_its_plant(runs, tmp_path):
    cfg_path = tmp_path / "sweep.yaml"
    cfg = _config({"kind": "nonlinear", "turbulence": "light"}, {"trials": 2})
    cfg_path.write_text(yaml.safe_dump(cfg), encoding="utf-8")
    sweep = tmp_path / "sweep"
    res = CliRunner().invoke(cli, ["sweep", str(cfg_path), "--thresholds", "25",
                                   "--flights", "1", "--jobs", "1", "--quiet",
                                   "--out", str(sweep)])
    assert res.exit_code == 0, res.output
    same_stamp(runs["lin"], sweep)
    text = _report([runs["lin"], sweep], tmp_path)
    section = text.split(f"## Sweep `{sweep}`", 1)[1].split("\n## ", 1)[0]
    assert "truth plant `nonlinear`, turbulence `light`." in section
    assert HEADING not in text  # a sweep is not a run: nothing to compare


def test_runs_on_two_airframes_are_compared_side_by_side(runs, tmp_path):
    # the same config flown on the default airframe: the airframe enters the
    # conditions, the default one is the reference, and no warning is raised
    other = tmp_path / "pyfly"
    cfg_path = tmp_path / "pyfly.yaml"
    data = _config(*RUNS["lin"])
    data["model"] = {"airframe": DEFAULT_AIRFRAME}
    cfg_path.write_text(yaml.safe_dump(data), encoding="utf-8")
    res = CliRunner().invoke(cli, ["run", str(cfg_path), "--out", str(other), "--quiet",
                                   "--jobs", "1"])
    assert res.exit_code == 0, res.output
    same_stamp(runs["lin"], other)
    text = _report([runs["lin"], runs["nl"], other], tmp_path / "r")
    assert "## Airframe, truth plant and turbulence" in text and HEADING not in text
    table = _table(text, "## Airframe, truth plant and turbulence")
    conds = list(dict.fromkeys(table["condition"]))
    assert conds == [f"{DEFAULT_AIRFRAME} / linear / none", "x8-gryte2018 / linear / none",
                     "x8-gryte2018 / nonlinear / none"]
    assert f"reference `{DEFAULT_AIRFRAME} / linear / none`" in text
    assert "Warning: the compared runs also differ" not in text
    assert "airframe `x8-gryte2018`, truth plant `nonlinear`" in text
