"""Endurance runs (``ftc-mc endurance``): fault-free flight hours per design.

* the false resets equal those of the sweep's fault-free flights on the same
  flights and thresholds (another code path: the sweep shares each flight's
  start across points);
* every design flies the same flights; results do not depend on jobs or chunks;
* the rate, its exact interval, the one-sided bound and the hours that would
  show a target follow their formulas (scipy's chi-square, computed here);
* an interrupted run resumes to the same data; a complete one is left alone;
* bad input is one line, exit 2, and nothing is written.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import scipy.stats
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign import parallel
from ftc_mc.campaign.endurance import run_endurance
from ftc_mc.campaign.sweep import run_sweep
from ftc_mc.cli import cli
from ftc_mc.config import Config
from ftc_mc.io.results import read_metadata

FLIGHT_S = 15.0
DATA = {"campaign": {"transitions": ["elevon_lock"], "trials": 2, "chunk_size": 8,
                     "signature": "both"},
        "controller": {"kind": "nominal"},
        # low thresholds: the paper's filter resets in still air too
        "estimator": {"t_q": 4.0, "t_nx": 4.0},
        "timing": {"fault_time_s": 5, "window_s": 5, "duration_s": FLIGHT_S}}
CFG = Config.model_validate(DATA)
HOURS = 24 * FLIGHT_S / 3600  # 24 flights


@pytest.fixture(scope="module")
def endurance():
    return run_endurance(CFG, HOURS, jobs=1, progress=False)


def test_false_resets_equal_the_sweeps_fault_free_flights(endurance):
    sw = run_sweep(CFG, [(4.0, 4.0)], flights=24, jobs=1, progress=False).table
    s = endurance.summary.set_index("variant")
    assert s["false_resets"].sum() > 0  # the test sees resets
    f = endurance.flights
    for v in ("paper", "swapped"):
        row = sw[sw.variant == v].iloc[0]
        # the sweep counts the flights that flew to their end
        whole = f[(f.variant == v) & (f.status == "ok")]
        assert whole["false_resets"].sum() == row["flight_false_resets"]
        assert len(whole) * FLIGHT_S / 3600 == pytest.approx(row["flight_hours"])
        assert s.loc[v, "t_q"] == s.loc[v, "t_nx"] == 4.0


def test_every_design_flies_the_same_flights(endurance):
    f = endurance.flights
    assert len(f) == 2 * 24
    ids = [list(g["flight_id"]) for _, g in f.groupby("variant", sort=False)]
    assert ids[0] == ids[1] == list(range(24))
    # the reset times are those of the flights, from their start, within the flight
    r = endurance.resets
    assert (r["time_s"] > 0).all() and (r["time_s"] <= FLIGHT_S).all()
    per = r.groupby(["variant", "flight_id"]).size()
    stored = f.set_index(["variant", "flight_id"])["false_resets"].clip(upper=64)
    assert (per.reindex(stored.index, fill_value=0) == stored).all()
    first = r.groupby(["variant", "flight_id"])["time_s"].min()
    got = f.set_index(["variant", "flight_id"])["first_false_reset_s"].dropna()
    pd.testing.assert_series_equal(got.sort_index(), first.sort_index(), check_names=False)


def test_rates_follow_their_formulas(endurance):
    for _, r in endurance.summary.iterrows():
        k, h = int(r["false_resets"]), r["flight_hours"]
        f = endurance.flights[endurance.flights.variant == r["variant"]]
        flown = np.where(f["status"] == "ok", FLIGHT_S, f["stop_s"])
        assert h == pytest.approx(flown[f["judged"]].sum() / 3600)
        assert r["false_resets_per_hour"] == pytest.approx(k / h)
        lo = scipy.stats.chi2.ppf(0.025, 2 * k) / 2 / h if k else 0.0
        assert r["false_resets_per_hour_ci_low"] == pytest.approx(lo)
        assert r["false_resets_per_hour_ci_high"] == pytest.approx(
            scipy.stats.chi2.ppf(0.975, 2 * k + 2) / 2 / h)
        up = scipy.stats.chi2.ppf(0.95, 2 * k + 2) / 2 / h
        assert r["false_resets_per_hour_upper95"] == pytest.approx(up)
        assert r["target_shown"] == (up <= r["target_per_h"])
        assert r["hours_to_show"] == pytest.approx(
            scipy.stats.chi2.ppf(0.95, 2 * k + 2) / 2 / r["target_per_h"])


def test_zero_events_need_three_over_the_target():
    from ftc_mc.stats import hours_to_show, poisson_upper

    assert hours_to_show(0, 0.01) == pytest.approx(-math.log(0.05) / 0.01)
    assert poisson_upper(0, 300.0) == pytest.approx(-math.log(0.05) / 300.0)
    assert poisson_upper(0, 300.0) <= 0.01 < poisson_upper(0, 299.0)


def test_results_do_not_depend_on_jobs_or_chunks(endurance):
    other = Config.model_validate({**DATA, "campaign": {**DATA["campaign"], "chunk_size": 5}})
    b = run_endurance(other, HOURS, jobs=2, progress=False)
    pd.testing.assert_frame_equal(endurance.flights, b.flights, check_exact=True)
    pd.testing.assert_frame_equal(endurance.resets, b.resets, check_exact=True)
    pd.testing.assert_frame_equal(endurance.summary, b.summary, check_exact=True)


def test_interrupted_run_resumes_to_the_same_data(endurance, tmp_path, monkeypatch):
    out = tmp_path / "e"
    real = parallel.run_chunk

    def dies_at_third(spec, name, ids):
        if int(ids[0]) == 16:
            raise KeyboardInterrupt
        return real(spec, name, ids)

    monkeypatch.setattr(parallel, "run_chunk", dies_at_third)
    with pytest.raises(KeyboardInterrupt):
        ftc_mc.run_endurance(CFG, HOURS, out=out, progress=False)
    assert not (out / "endurance.parquet").exists()
    monkeypatch.setattr(parallel, "run_chunk", real)
    res = ftc_mc.run_endurance(CFG, HOURS, out=out, resume=True, progress=False)
    pd.testing.assert_frame_equal(res.flights, endurance.flights, check_exact=True)
    stored = pd.read_parquet(out / "false_resets.parquet")
    pd.testing.assert_frame_equal(stored, endurance.resets, check_exact=True)
    meta = read_metadata(out / "endurance.parquet")
    assert meta["kind"] == "endurance" and meta["hours"] == HOURS
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert ftc_mc.run_endurance(CFG, HOURS, out=out, resume=True, progress=False) is None
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before


@pytest.mark.parametrize("args,needle", [
    (["--hours", "0"], "--hours: must be finite and > 0"),
    (["--hours", "-2"], "--hours: must be finite and > 0"),
    (["--hours", "nan"], "--hours: must be finite and > 0"),
    (["--hours", "inf"], "--hours: must be finite and > 0"),
    (["--hours", "ten"], "--hours: expected a number"),
    (["--hours", "1", "--flight-s", "1"], "not longer than the filters' start-up"),
    (["--hours", "1", "--flight-s", "-3"], "--flight-s: must be a finite number"),
    (["--hours", "1", "--flight-s", "10.05"], "--flight-s: must be a multiple of model.dt_s"),
    (["--hours", "1", "--design", "nope"], "--design: unknown design 'nope'"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, args, needle):
    import yaml

    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump(DATA))
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["endurance", str(cfg), "--out", str(out), "--quiet",
                                   *args])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], res.output
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_report_shows_the_endurance_run_and_uses_its_hours(tmp_path):
    """An endurance directory gets its section; a sweep of the same condition and
    designs takes the endurance hours at the matching point."""
    end = tmp_path / "end"
    sw = tmp_path / "sw"
    ftc_mc.run_endurance(CFG, HOURS, out=end, progress=False)
    ftc_mc.run_sweep(CFG, [4.0], flights=6, out=sw, progress=False)
    out = ftc_mc.build_report([sw, end], tmp_path / "rep.md")
    text = out.read_text(encoding="utf-8")
    assert f"## Endurance `{end}`" in text
    assert (tmp_path / "rep_figures" / "end_endurance.png").stat().st_size > 5_000
    summary = pd.read_parquet(end / "endurance.parquet").set_index("variant")
    op = text.split("### Operating characteristic", 1)[1]
    for v in ("paper", "swapped"):
        k, h = int(summary.loc[v, "false_resets"]), summary.loc[v, "flight_hours"]
        assert f"| {k} / {h:.3g} (endurance)" in op
    # not shown: 0.1 h cannot show 0.01 per hour
    assert "**not shown**" in text
