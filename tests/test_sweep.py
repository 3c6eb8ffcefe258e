"""Threshold sweeps: shared trials are bit-identical to separate runs; bad specs."""

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign.sweep import parse_spec, run_sweep, threshold_points
from ftc_mc.cli import cli
from ftc_mc.config import Config
from ftc_mc.errors import UserError
from ftc_mc.io.results import read_metadata

CFG = Config.model_validate({
    "campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 12,
                 "chunk_size": 6},
    "controller": {"kind": "nominal"},
    "timing": {"fault_time_s": 5, "window_s": 5, "duration_s": 15}})


@pytest.fixture(scope="module")
def sweep():
    return run_sweep(CFG, threshold_points("4,12,25"), flights=6, jobs=1, progress=False)


def _assert_shared_equals_alone(cfg, res, thresholds):
    """Each point's trials in the sweep ``res`` equal a campaign run at that point."""
    for t in thresholds:
        est = cfg.estimator.model_copy(update={"t_q": t, "t_nx": t})
        alone = ftc_mc.run_campaign(cfg.model_copy(update={"estimator": est}), jobs=1,
                                    progress=False).trials
        shared = res.trials[res.trials.t_q == t].drop(columns=["t_q", "t_nx"])
        pd.testing.assert_frame_equal(alone, shared.reset_index(drop=True), check_exact=True)
    assert res.simulated_steps < res.alone_steps


def test_shared_trials_equal_separate_runs(sweep):
    _assert_shared_equals_alone(CFG, sweep, (4.0, 12.0, 25.0))


def test_table_rows_and_false_reset_rates(sweep):
    t = sweep.table
    assert len(t) == 3 * 2 * 2  # points x transitions x variants
    low = t[t.t_q == 4.0]["false_resets_per_hour"]
    high = t[t.t_q == 25.0]["false_resets_per_hour"]
    # lower thresholds cannot produce fewer false resets on the same flights
    assert (low.to_numpy() >= high.to_numpy()).all() and low.max() > 0
    r = t.iloc[0]
    assert r["false_resets_per_hour_ci_low"] <= r["false_resets_per_hour"] <= \
        r["false_resets_per_hour_ci_high"]


def test_results_do_not_depend_on_jobs(sweep):
    b = run_sweep(CFG, threshold_points("4,12,25"), flights=6, jobs=2, progress=False)
    pd.testing.assert_frame_equal(sweep.table, b.table, check_exact=True)


@pytest.mark.parametrize("spec,values", [("5:20:5", [5, 10, 15, 20]), ("25", [25]),
                                         ("10,5,10", [5, 10]), ("1:2:0.5", [1, 1.5, 2])])
def test_parse_spec(spec, values):
    assert parse_spec(spec, "--thresholds") == values


@pytest.mark.parametrize("spec,needle", [("", "empty"), ("20:5:5", "reversed"),
                                         ("5:20:0", "step"), ("0,5", "> 0"),
                                         ("-5:5:5", "> 0"), ("a,b", "expected"),
                                         ("1:2", "expected"), ("nan", "finite")])
def test_bad_spec(spec, needle):
    with pytest.raises(UserError, match=needle):
        parse_spec(spec, "--thresholds")


def test_cli_sweep(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("campaign:\n  transitions: [elevon_lock]\ncontroller:\n  kind: nominal\n"
                   "timing:\n  fault_time_s: 5\n  window_s: 5\n  duration_s: 15\n")
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["sweep", str(cfg), "--thresholds", "10,25", "--trials",
                                   "4", "--out", str(out), "--quiet", "--jobs", "1"])
    assert res.exit_code == 0, res.output
    table = pd.read_parquet(out / "sweep.parquet")
    assert sorted(table.t_q.unique()) == [10.0, 25.0]
    meta = read_metadata(out / "sweep.parquet")
    assert meta["kind"] == "sweep" and meta["points"] == [[10.0, 10.0], [25.0, 25.0]]
    for args, needle in ([["--thresholds", "30:10:5"], "reversed"],
                         [["--thresholds", "0"], "> 0"],
                         [["--tq", "10"], "--tnx"],
                         [["--thresholds", "10", "--transitions", "elevon_flutter"],
                          "campaign.transitions"]):
        bad = tmp_path / "bad"
        r = CliRunner().invoke(cli, ["sweep", str(cfg), *args, "--out", str(bad)])
        assert r.exit_code == 2 and needle in r.output, r.output
        assert len(r.output.strip().splitlines()) == 1 and not bad.exists()
    r = CliRunner().invoke(cli, ["sweep", str(cfg), "--thresholds", "10", "--out", str(out)])
    assert r.exit_code == 2 and "already holds results" in r.output
    assert np.isfinite(table["inappropriate_rate"]).all()
    # the report plots the trade-off and names a threshold
    rep = tmp_path / "rep" / "report.md"
    r = CliRunner().invoke(cli, ["report", str(out), "-o", str(rep)])
    assert r.exit_code == 0, r.output
    text = rep.read_text()
    assert "Recommended threshold" in text and "t_q = " in text
    png = rep.parent / "report_figures" / "out_sweep.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000


def test_shared_trials_equal_separate_runs_on_a_turbulent_nonlinear_plant():
    """The shared start carries the gust state (LaneState.gust) and the nonlinear
    truth: continuing from it must equal running each point alone."""
    cfg = CFG.model_copy(update={"plant": CFG.plant.model_copy(
        update={"kind": "nonlinear", "turbulence": "light"})})
    points = threshold_points("3000,20000")  # light gusts: r_q reaches ~3e3 per flight
    res = run_sweep(cfg, points, flights=6, jobs=1, progress=False)
    _assert_shared_equals_alone(cfg, res, [t for t, _ in points])
