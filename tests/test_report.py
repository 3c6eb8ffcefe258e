"""``ftc_mc.report.build_report``: one Markdown report of run and scenario dirs.

What is checked, on a small real run (4 trials, nominal controller) and the
paper scenario, both made once per module through the CLI:

* the report holds the paper's counts and ours (with Wilson intervals), the
  verdict whether ours agree with the paper's as ``summary.parquet`` recorded
  it, the scenario timeline beside the paper's, and the provenance of every
  input;
* the scenario's controller names come from its files' metadata, with the
  code that builds them from the config made to fail (and the bare codes for a
  result written before they were recorded); so do Fig. 11's;
* every image link is relative and points to a non-empty PNG;
* the report rebuilds from the Parquet files alone, to the same text;
* refusals (no results, mixed versions or revisions) write nothing;
  ``allow_mixed`` builds the report with a warning;
* the signature-variant verdict and the exclusion reasons on synthetic trials.
"""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import ftc_mc.sim.setup
from ftc_mc.campaign.summary import agreement_text
from ftc_mc.campaign.transitions import PAPER_TABLES, TRANSITION_TABLE
from ftc_mc.cli import cli
from ftc_mc.errors import UserError
from ftc_mc.io.lock import acquire
from ftc_mc.io.results import read_metadata, write_parquet
from ftc_mc.report import build_report, exclusion_table, variant_comparison
from ftc_mc.stats import agrees, two_proportion_p, wilson

from result_dirs import copy_dir, same_stamp

ROOT = Path(__file__).resolve().parents[1]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)]+)\)")


def _count(k, n):
    lo, hi = wilson(k, n)
    return f"{k}/{n} ({100 * k / n:.1f} %, {100 * lo:.1f}-{100 * hi:.1f})"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """A finished run and a finished scenario directory."""
    base = tmp_path_factory.mktemp("report_inputs")
    run, scen = base / "run", base / "scen"
    res = CliRunner().invoke(cli, ["run", str(ROOT / "configs" / "paper_tables.yaml"),
                                   "--trials", "4", "--controller", "nominal", "--jobs", "1",
                                   "--quiet", "--out", str(run)])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(cli, ["scenario", str(ROOT / "configs" / "paper_scenario.yaml"),
                                   "--out", str(scen)])
    assert res.exit_code == 0, res.output
    same_stamp(run, scen)
    return run, scen


@pytest.fixture(scope="module")
def report(inputs, tmp_path_factory):
    """The report of both inputs, in a folder of its own."""
    out = tmp_path_factory.mktemp("report_out") / "report.md"
    assert build_report(list(inputs), out) == out
    return out


def _rows(text: str, heading: str) -> list:
    """Cells of the body rows of the first Markdown table after ``heading``."""
    lines = text.split(heading + "\n", 1)[1].splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("|"))
    table = []
    for line in lines[first:]:
        if not line.startswith("|"):
            break
        table.append([c.strip() for c in line.strip("|").split("|")])
    return table[2:]


def test_report_has_paper_and_our_numbers(inputs, report):
    text = report.read_text(encoding="utf-8")
    summary = pd.read_parquet(inputs[0] / "summary.parquet")
    for variant, g in summary.groupby("variant"):
        rows = {r[0]: r for r in _rows(text, f"#### Signature `{variant}`")}
        assert len(rows) == len(g) == len(PAPER_TABLES)
        for r in g.itertuples():
            n, inap, no_reset = PAPER_TABLES[r.transition]
            row = rows[TRANSITION_TABLE[r.transition].label]
            assert row[1] == str(r.trials)
            assert row[3] == _count(inap, n) and row[5] == _count(no_reset, n)
            if r.trials:
                assert row[2] == _count(r.inappropriate, r.trials)
                assert row[4] == _count(r.no_reset, r.trials)
            assert row[-1] == agreement_text(summary.loc[r.Index])
    for heading in ("#### Signature `paper`", "#### Signature `swapped`",
                    "### Excluded trials", "### Which signature variant is better",
                    "### Event timeline beside the paper", "## Provenance"):
        assert heading in text


def test_summary_of_a_small_run_records_the_verdict(inputs):
    summary = pd.read_parquet(inputs[0] / "summary.parquet")
    assert len(summary) == 2 * len(PAPER_TABLES)
    for col in ("paper_agrees_inappropriate", "paper_agrees_no_reset", "paper_agrees"):
        assert str(summary[col].dtype) == "boolean", col
    for _, r in summary.iterrows():
        n, *paper = PAPER_TABLES[r["transition"]]
        each = []
        for q, k in zip(("inappropriate", "no_reset"), paper):
            p = two_proportion_p(r[q], r["trials"], k, n)
            assert r[f"paper_p_{q}"] == p
            assert r[f"paper_agrees_{q}"] == agrees(p)
            each.append(agrees(p))
        assert r["paper_agrees"] == all(each)
    text = (inputs[0] / "summary.md").read_text(encoding="utf-8")
    for _, r in summary.iterrows():
        assert f"| {agreement_text(r)} " in text


def test_report_shows_the_recorded_verdict(inputs, tmp_path):
    """The report prints the verdict the summary holds; it does not judge again."""
    run = copy_dir(inputs[0], tmp_path / "run")
    path = run / "summary.parquet"
    meta, summary = read_metadata(path), pd.read_parquet(path)
    flipped = ~summary["paper_agrees"]  # the opposite of what the p-values say
    forged = summary.assign(paper_p_inappropriate=0.5, paper_p_no_reset=0.25,
                            paper_agrees_inappropriate=flipped, paper_agrees_no_reset=flipped,
                            paper_agrees=flipped)
    write_parquet(forged, path, meta)
    text = build_report([run], tmp_path / "a.md").read_text(encoding="utf-8")
    for variant, g in forged.groupby("variant"):
        rows = _rows(text, f"#### Signature `{variant}`")
        for row, (_, r) in zip(rows, g.iterrows()):
            assert row[-1] == agreement_text(r)
            assert row[-1] == ("agrees (p 0.5 / 0.25)" if r["paper_agrees"] else
                               "differs: inappropriate, no reset (p 0.5 / 0.25)")
    assert forged["paper_agrees"].any() and not forged["paper_agrees"].all()
    old = summary.drop(columns=[c for c in summary if c.startswith(("paper_p_",
                                                                    "paper_agrees"))])
    write_parquet(old, path, meta)
    text = build_report([run], tmp_path / "b.md").read_text(encoding="utf-8")
    for variant in forged["variant"].unique():
        assert {row[-1] for row in _rows(text, f"#### Signature `{variant}`")} == {
            "not recorded"}


def _no_setup(*args, **kwargs):
    raise AssertionError("the controller names were rebuilt from the config")


def test_report_names_the_recorded_controllers(inputs, tmp_path, monkeypatch):
    monkeypatch.setattr(ftc_mc.sim.setup, "controller_names", _no_setup)
    monkeypatch.setattr(ftc_mc.sim.setup, "build_setup", _no_setup)
    scen = copy_dir(inputs[1], tmp_path / "scen")
    meta = read_metadata(scen / "events.parquet")
    assert meta["controller_names"] == ["c0 nominal", "c1 engine fault", "c2 elevon fault"]

    def section(name):
        text = build_report([scen], tmp_path / f"{name}.md").read_text(encoding="utf-8")
        return text.split(f"## Scenario `{scen}`", 1)[1].split("\n## ", 1)[0]

    assert ("Controllers flown (recorded with the result): `c0 nominal`, "
            "`c1 engine fault`, `c2 elevon fault`.") in section("as_written")
    for path in scen.glob("*.parquet"):  # other names recorded: the report prints them
        m = read_metadata(path)
        write_parquet(pd.read_parquet(path), path, {**m, "controller_names": ["k0 a", "k1 b"]})
    assert "recorded with the result): `k0 a`, `k1 b`." in section("other")
    for path in scen.glob("*.parquet"):  # a result written before the names were recorded
        m = read_metadata(path)
        m.pop("controller_names")
        write_parquet(pd.read_parquet(path), path, m)
    assert ("Controllers flown: `c0`, `c1`, `c2`, `c3` (codes only: the result was written "
            "before `ftc-mc scenario` recorded their names).") in section("old")


def test_fig11_labels_the_recorded_controllers(inputs, tmp_path, monkeypatch):
    import ftc_mc.plots.scenario as plots
    from ftc_mc.config import ScenarioConfig
    from ftc_mc.scenario import ScenarioResult

    monkeypatch.setattr(ftc_mc.sim.setup, "controller_names", _no_setup)
    drawn = {}

    def keep(fig, path):
        drawn[Path(path).name] = [t.get_text() for t in fig.axes[0].get_yticklabels()]
        return path

    monkeypatch.setattr(plots, "save", keep)
    d = inputs[1]
    res = ScenarioResult(
        timeseries=pd.read_parquet(d / "timeseries.parquet"),
        events=pd.read_parquet(d / "events.parquet"),
        segments=pd.read_parquet(d / "segments.parquet"),
        config=ScenarioConfig.model_validate(read_metadata(d / "events.parquet")["config"]),
        status="ok", controller_names=("c0 first", "c1 second", "c2 third", "c3 fourth"))
    plots.scenario_figures(res, tmp_path)
    assert drawn["fig11_controller.png"] == ["1 first", "2 second", "3 third", "4 fourth"]


def test_report_has_scenario_timeline_and_provenance(inputs, report):
    text = report.read_text(encoding="utf-8")
    seg = pd.read_parquet(inputs[1] / "segments.parquet")
    ev = pd.read_parquet(inputs[1] / "events.parquet")
    rows = _rows(text, "### Event timeline beside the paper")
    assert [r[0] for r in rows] == [f"{t:g}" for t in seg.start_s]
    for r, s in zip(rows, seg.itertuples()):
        for cell, value in ((r[2], s.detection_s), (r[3], s.paper_detection_s)):
            assert cell == ("-" if np.isnan(value) else f"{value:.1f}")
    for detail in ev.loc[ev.kind == "controller_switch", "detail"]:
        assert detail in text
    scenario = text.split(f"## Scenario `{inputs[1]}`", 1)[1].split("\n## ", 1)[0]
    assert "truth plant `linear`, turbulence `none`." in scenario
    for d in inputs:
        meta = read_metadata(next(d.glob("*.parquet")))
        assert str(d) in text
        assert meta["version"] in text and str(meta["git_revision"]) in text
        assert f"seed: {meta['seed']}" in text  # from the YAML config block


def test_figures_exist_with_working_relative_links(inputs, report):
    links = IMAGE.findall(report.read_text(encoding="utf-8"))
    names = {Path(unquote(link)).name for link in links}
    assert "run_delays.png" in names
    assert {p.name for p in inputs[1].glob("fig*.png")} <= names
    for link in links:
        assert not Path(unquote(link)).is_absolute(), link
        target = report.parent / unquote(link)
        assert target.is_file(), link
        assert target.stat().st_size > 1000
        assert target.read_bytes()[:8] == PNG_SIGNATURE
    assert (report.parent / "report_figures" / "run_delays.png").is_file()


def test_rebuild_from_parquet_files_only(inputs, tmp_path):
    run = copy_dir(inputs[0], tmp_path / "run")
    scen = copy_dir(inputs[1], tmp_path / "scen")
    out = tmp_path / "out" / "r.md"
    first = build_report([run, scen], out).read_text(encoding="utf-8")
    for p in list(tmp_path.rglob("*")):
        if p.is_file() and p.suffix != ".parquet":
            p.unlink()
    second = build_report([run, scen], out).read_text(encoding="utf-8")
    assert (tmp_path / "out" / "r_figures" / "run_delays.png").stat().st_size > 1000
    assert "No figures in" in second
    cut = "### Figures"
    assert first.split(cut)[0] == second.split(cut)[0]
    assert first.split("## Provenance")[1] == second.split("## Provenance")[1]


def test_directory_without_results_is_refused(inputs, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "summary.md").write_text("not a result\n")
    out = tmp_path / "r.md"
    with pytest.raises(UserError, match=re.escape(str(empty))):
        build_report([inputs[0], empty], out)
    with pytest.raises(UserError, match="not a directory"):
        build_report([tmp_path / "missing"], out)
    with pytest.raises(UserError, match="is a directory"):
        build_report([inputs[0]], tmp_path)
    assert not out.exists() and not (tmp_path / "r_figures").exists()


def test_directory_being_written_is_refused(inputs, tmp_path):
    run = copy_dir(inputs[0], tmp_path / "run")
    out = tmp_path / "r.md"
    with acquire(run, command="ftc-mc run test"):
        with pytest.raises(UserError, match="being written by `ftc-mc run test`"):
            build_report([run], out)
    assert not out.exists()
    (tmp_path / "unfinished" / ".chunks").mkdir(parents=True)
    with pytest.raises(UserError, match="--resume"):
        build_report([tmp_path / "unfinished"], out)


@pytest.mark.parametrize("field,value", [("version", "9.9.9"),
                                         ("git_revision", "0" * 40 + "+dirty")])
def test_mixed_provenance_is_refused_unless_allowed(inputs, tmp_path, field, value):
    run = copy_dir(inputs[0], tmp_path / "run")
    path = run / "summary.parquet"
    meta = read_metadata(path)
    meta[field] = value
    write_parquet(pd.read_parquet(path), path, meta)
    out = tmp_path / "out" / "r.md"
    with pytest.raises(UserError) as exc:
        build_report([run, inputs[1]], out)
    msg = str(exc.value)
    assert "--allow-mixed" in msg and value in msg and str(inputs[1]) in msg
    assert str(path) in msg  # only one file of the run differs
    assert "\n" not in msg
    assert not out.exists() and not (tmp_path / "out").exists()
    text = build_report([run, inputs[1]], out, allow_mixed=True).read_text(encoding="utf-8")
    assert "**Warning: mixed inputs.**" in text and value in text


def _synthetic_trials(inap_paper, inap_swapped, n=20):
    rows = []
    for variant, k in (("paper", inap_paper), ("swapped", inap_swapped)):
        for i in range(n):
            rows.append({"transition": "elevon_lock", "variant": variant, "trial_id": i,
                         "inappropriate": i < k, "no_reset": False, "judged": True})
    return pd.DataFrame(rows)


def test_variant_verdict_from_paired_trials():
    text = "\n".join(variant_comparison(_synthetic_trials(15, 0)))
    assert "**`swapped` is better**" in text and "15/20 vs 0/20" in text
    text = "\n".join(variant_comparison(_synthetic_trials(0, 15)))
    assert "**`paper` is better**" in text
    text = "\n".join(variant_comparison(_synthetic_trials(1, 2)))
    assert "Neither variant is better on this data" in text
    one = _synthetic_trials(1, 2)
    assert "nothing to compare" in variant_comparison(one[one.variant == "paper"])[0]


def test_exclusion_reasons():
    trials = pd.DataFrame({
        "transition": "engine_lock", "variant": "paper", "trial_id": range(4),
        "judged": [True, False, False, True],
        "status": ["ok", "airspeed_out_of_bounds", "ok", "alpha_out_of_bounds"],
        "stop_s": [np.nan, 25.0, np.nan, 40.0],
        "resets_truncated": [False, False, True, False]})
    summary = pd.DataFrame([{
        "transition": "engine_lock", "label": "L", "variant": "paper", "trials": 2,
        "excluded": 2, "stopped_nonfinite": 0, "stopped_airspeed_out_of_bounds": 1,
        "stopped_alpha_out_of_bounds": 1}])
    text = "\n".join(exclusion_table(summary, trials, {"timing": {"fault_time_s": 20.0,
                                                                  "window_s": 10.0}}))
    assert "airspeed_out_of_bounds 1, resets_truncated 1" in text
    assert "airspeed_out_of_bounds 1, alpha_out_of_bounds 1" in text
