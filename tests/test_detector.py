"""Recorded signals (``--record signals``) and detectors of your own scored on them."""

from __future__ import annotations

import hashlib
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign.detector import batches, table1_detector
from ftc_mc.campaign.signals import KEYS, TRUTH_COLUMNS, signal_columns, signal_files
from ftc_mc.cli import cli
from ftc_mc.conventions import LONGITUDINAL as LAY

ROOT = Path(__file__).resolve().parents[1]

CFG = {"campaign": {"transitions": ["elevon_lock", "engine_loss", "elevon_loss_recover"],
                    "trials": 8, "chunk_size": 4, "seed": 2026, "signature": "both"},
       "controller": {"kind": "reconfiguring"},
       "model": {"airframe": "x8-gryte2018"},
       "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}
"""A small run on the golden cases' linear path (its kernels already compiled)."""


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec") / "run"
    ftc_mc.run_campaign(CFG, out=out, record="signals", jobs=1, progress=False)
    return out


def _digest(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_recording_leaves_the_results_alone(recorded, tmp_path):
    plain = ftc_mc.run_campaign(CFG, out=tmp_path / "plain", jobs=1, progress=False)
    a = pd.read_parquet(recorded / "trials.parquet")
    pd.testing.assert_frame_equal(a, plain.trials)
    pd.testing.assert_frame_equal(pd.read_parquet(recorded / "resets.parquet"), plain.resets)
    assert not (tmp_path / "plain" / "signals").exists()


def test_signals_layout_and_join(recorded):
    files = signal_files(recorded)
    assert len(files) == 3 * 2  # one per chunk: 3 transitions x 2 chunks of 4
    sig = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
    assert tuple(sig.columns) == KEYS + signal_columns()
    schema = pq.read_schema(files[0])
    assert str(schema.field("z_q").type) == "float"
    assert str(schema.field("innov_q").type) == "float"
    assert str(schema.field("r_q").type) == "double"
    trials = pd.read_parquet(recorded / "trials.parquet")
    n_steps = round(CFG["timing"]["duration_s"] / 0.1)
    per = sig.groupby(["transition", "variant", "trial_id"], observed=True)["step"].agg(
        ["count", "min", "max"]).reset_index()
    j = trials.merge(per, on=["transition", "variant", "trial_id"], how="left")
    assert j["count"].notna().all()
    flown = np.where(j["stop_s"].notna(), np.round(j["stop_s"] / 0.1) - 1, n_steps)
    assert (j["count"] == flown).all() and (j["min"] == 1).all()
    # the truth: nominal before the switch, the final mode after it
    row = sig[(sig["transition"] == "elevon_lock") & (sig["step"] > 51)]
    assert (row["mode"] == "left_elevon").all()
    assert (sig[(sig["transition"] == "elevon_lock") & (sig["step"] <= 50)]["mode"]
            == "nominal").all()
    # the paper filter's innovations squared are its one-step residuals
    for r, i in zip(LAY.residuals, ["innov_q", "innov_nx", "innov_nz"]):
        np.testing.assert_allclose(sig[i].astype(float) ** 2, sig[r], rtol=1e-5, atol=1e-6)


def test_recorded_resets_are_the_reset_log(recorded):
    sig = pd.concat([pd.read_parquet(f, columns=["transition", "variant", "trial_id", "step",
                                                  "reset"]) for f in signal_files(recorded)])
    got = sig[sig["reset"] != 0]
    resets = pd.read_parquet(recorded / "resets.parquet")
    a = sorted(zip(got["transition"].astype(str), got["variant"].astype(str), got["trial_id"],
                   got["step"], [LAY.blocks[b] for b in got["reset"]]))
    b = sorted(zip(resets["transition"], resets["variant"], resets["trial_id"],
                   np.round(resets["time_s"] / 0.1).astype(int), resets["block"]))
    assert a == b


def test_table1_offline_equals_the_closed_loop(recorded, tmp_path):
    """The recording's honest test: Table 1 on the recorded r_q, r_nx, r_nz gives
    every trial's first reset, time and block, as the closed loop did."""
    resets = pd.read_parquet(recorded / "resets.parquet")
    first = resets.groupby(["transition", "variant", "trial_id"]).first().reset_index()
    n = 0
    for variant in ("paper", "swapped"):
        res = ftc_mc.score_detector(recorded, table1_detector(variant), out=tmp_path / variant)
        t = res["trials"]
        t = t[t["design"] == variant].merge(first[first["variant"] == variant],
                                            on=["transition", "trial_id"], how="left")
        np.testing.assert_array_equal(t["alarm_s"].notna(), t["time_s"].notna())
        both = t["time_s"].notna()
        np.testing.assert_allclose(t.loc[both, "alarm_s"], t.loc[both, "time_s"], atol=1e-9)
        assert (t.loc[both, "alarm_block"] == t.loc[both, "block"]).all()
        n += int(both.sum())
    assert n > 10


def test_scores_beside_the_designs(recorded, tmp_path):
    """Table 1 scored offline on its own loop's signals gives the closed loop's
    Tables 2-3 rows where only the first reset matters (no reset in the window)."""
    res = ftc_mc.score_detector(recorded, table1_detector("paper"), out=tmp_path / "t1")
    s = res["summary"]
    assert set(s["variant"]) == {"table1_paper@paper", "table1_paper@swapped"}
    assert (tmp_path / "t1" / "summary.parquet").exists()
    assert {"alfa_precision", "alfa_recall", "correct_rate"} <= set(s.columns)
    md = ftc_mc.build_report([str(recorded)], tmp_path / "r.md").read_text()
    assert "table1_paper@paper" not in md  # written elsewhere with -o: not the run's
    ftc_mc.score_detector(recorded, table1_detector("paper"))
    md = ftc_mc.build_report([str(recorded)], tmp_path / "r2.md").read_text()
    assert "table1_paper@paper" in md


def test_correct_side_of_a_detector_naming_actuators(recorded, tmp_path):
    t1 = table1_detector("paper")

    def sided(signals, names, dt):
        alarm, block = t1(signals, names, dt)
        return alarm, np.where(block == "elevons", "left_elevon", block)

    sided.columns = t1.columns
    t = ftc_mc.score_detector(recorded, sided, out=tmp_path / "s")["trials"]
    lock = t[(t["transition"] == "elevon_lock") & t["judged"]]
    np.testing.assert_array_equal(lock["correct_side"], lock["correct"].astype(float))
    assert t.loc[t["transition"] == "engine_loss", "correct_side"].isna().all()


def test_cusum_example(recorded, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    r = CliRunner().invoke(cli, ["score", str(recorded), "--detector", "examples.cusum:cusum",
                                 "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    s = pd.read_parquet(tmp_path / "c" / "summary.parquet")
    assert len(s) == 3 * 2 and s["trials"].sum() > 0


def test_learned_example(recorded, tmp_path, monkeypatch):
    """The classifier trained on one seed's recorded flights, scored on another's."""
    pytest.importorskip("sklearn")
    monkeypatch.syspath_prepend(str(ROOT))
    from examples.learned import detector_of, train
    cfg = {**CFG, "campaign": {**CFG["campaign"], "seed": 7, "signature": "paper"}}
    ftc_mc.run_campaign(cfg, out=tmp_path / "other", record="signals", jobs=1, progress=False)
    res = ftc_mc.score_detector(tmp_path / "other", detector_of(train(recorded)),
                                name="learned", out=tmp_path / "l")
    s = res["summary"]
    assert list(s["variant"].unique()) == ["learned@paper"]
    assert s["trials"].sum() > 0 and s["correct"].sum() > 0


def test_truth_columns_are_the_truth():
    """One definition of the truth: the mode and every actuator's b0, b1 and fault kind."""
    assert TRUTH_COLUMNS == ("mode", *(f"b{i}_{a}" for i in (0, 1) for a in LAY.actuators),
                             *(f"kind_{a}" for a in LAY.actuators))
    assert set(TRUTH_COLUMNS) <= set(signal_columns())
    seen = [c for c in signal_columns() if c not in TRUTH_COLUMNS]
    assert not [c for c in seen if c == "mode" or c[:3] in ("b0_", "b1_")]


def test_a_detector_sees_what_an_aircraft_sees(recorded, tmp_path):
    """By default the observable columns only; no truth, and not marked."""
    got = []

    def looks(signals, names, dt):
        got.append(names)
        assert signals.shape[2] == len(names)
        return np.full(signals.shape[0], np.nan)

    res = ftc_mc.score_detector(recorded, looks, out=tmp_path / "l")
    observable = tuple(c for c in signal_columns() if c not in TRUTH_COLUMNS)
    assert got and all(n == observable for n in got)
    assert res["columns"] == observable
    s = pd.read_parquet(tmp_path / "l" / "summary.parquet")
    assert "reads_truth" in s and not s["reads_truth"].any()
    assert "truth" not in (tmp_path / "l" / "summary.md").read_text()


def test_the_truth_only_when_asked_and_then_marked(recorded, tmp_path):
    def oracle(signals, names, dt):
        assert names == ("innov_q", "mode")
        m = signals[:, :, 1]
        hit = np.nan_to_num(m) > 0
        return np.where(hit.any(axis=1), (np.argmax(hit, axis=1) + 1) * dt, np.nan)

    oracle.columns = ("innov_q", "mode")
    run = tmp_path / "run"
    shutil.copytree(recorded, run, ignore=shutil.ignore_patterns("detectors"))
    res = ftc_mc.score_detector(run, oracle)
    folder = run / "detectors" / "oracle"
    s = pd.read_parquet(folder / "summary.parquet")
    assert s["reads_truth"].all() and res["summary"]["reads_truth"].all()
    assert "**Reads the truth** (`mode`)" in (folder / "summary.md").read_text()
    md = ftc_mc.build_report([str(run)], tmp_path / "r.md").read_text()
    assert "#### Oracle (a detector that read the truth: mode, b0, b1) `oracle@paper`" in md
    assert "#### Design `oracle@paper`" not in md
    t = res["trials"]  # the truth's first fault: at the switch, in every window
    lock = t[(t["transition"] == "elevon_lock") & t["judged"]]
    assert len(lock) and lock["correct"].all()


def test_batches_keep_the_labels(recorded):
    """Training reads the truth: batches() gives every recorded column."""
    _, _, _, sig, names = next(batches(recorded))
    assert set(TRUTH_COLUMNS) <= set(names) and sig.shape[2] == len(names)
    _, _, _, _, names = next(batches(recorded, truth=False))
    assert not set(TRUTH_COLUMNS) & set(names)


BAD = '''
import numpy as np
def raises(s, names, dt):
    raise RuntimeError("boom")
def shape(s, names, dt):
    return np.zeros(s.shape[0] + 1)
def inf(s, names, dt):
    return np.full(s.shape[0], np.inf)
def block(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], "rudder")
'''


@pytest.mark.parametrize("spec, says", [
    ("baddet:raises", "detector raised RuntimeError"),
    ("baddet:shape", "alarm times (one per trial)"),
    ("baddet:inf", "finite or NaN"),
    ("baddet:block", "block 'rudder'"),
    ("nosuchmodule_xyz:f", "cannot import"),
    ("baddet", "module:function"),
])
def test_bad_detectors(recorded, tmp_path, monkeypatch, spec, says):
    (tmp_path / "baddet.py").write_text(BAD)
    monkeypatch.chdir(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    before = _digest(recorded)
    r = CliRunner().invoke(cli, ["score", str(recorded), "--detector", spec])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and says in lines[0], r.output
    assert _digest(recorded) == before


def test_run_without_signals(tmp_path):
    cfg = {**CFG, "campaign": {**CFG["campaign"], "transitions": ["engine_loss"], "trials": 2,
                               "signature": "paper"}}
    ftc_mc.run_campaign(cfg, out=tmp_path / "plain", jobs=1, progress=False)
    before = _digest(tmp_path / "plain")
    r = CliRunner().invoke(cli, ["score", str(tmp_path / "plain"), "--detector",
                                 "examples.cusum:cusum"])
    assert r.exit_code == 2 and "without signals" in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert _digest(tmp_path / "plain") == before


def test_endurance_records_and_scores(tmp_path, monkeypatch):
    """Fault-free flights recorded: a detector's false alarms per flight hour, in
    the run's condition (plant, turbulence), without thresholds."""
    monkeypatch.chdir(ROOT)
    cfg = {k: v for k, v in CFG.items() if k != "timing"}
    cfg["campaign"] = {**CFG["campaign"], "signature": "paper"}
    ftc_mc.run_endurance(cfg, 0.02, flight_s=15.0, out=tmp_path / "end", record="signals",
                         jobs=1, progress=False)
    assert signal_files(tmp_path / "end")
    res = ftc_mc.score_detector(tmp_path / "end", table1_detector("paper"))
    s = res["summary"].iloc[0]
    flights = pd.read_parquet(tmp_path / "end" / "flights.parquet")
    assert s["variant"] == "table1_paper@paper" and s["judged"] == flights["judged"].sum()
    # Table 1 offline alarms in exactly the flights where the loop reset
    np.testing.assert_array_equal(res["flights"]["false_resets"].to_numpy() > 0,
                                  flights["false_resets"].to_numpy() > 0)
    built_in = pd.read_parquet(tmp_path / "end" / "endurance.parquet").iloc[0]
    for c in ("flight_hours", "false_resets_per_hour_ci_high", "false_resets_per_hour_upper95",
              "plant", "turbulence", "airframe"):
        assert s[c] == built_in[c], c  # first alarm = first reset: the same flights
    r = CliRunner().invoke(cli, ["score", str(tmp_path / "end"), "--detector",
                                 "examples.cusum:cusum", "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    assert "nan" not in r.output and "| cusum@paper | -" in r.output
    md = (tmp_path / "c" / "summary.md").read_text()
    assert f"| {built_in['plant']} / {built_in['turbulence']} " in md and "nan" not in md

    assert (tmp_path / "end" / "detectors" / "table1_paper" / "endurance.parquet").exists()
    md = ftc_mc.build_report([str(tmp_path / "end")], tmp_path / "r.md").read_text()
    assert "table1_paper@paper" in md and "nan / nan" not in md


def test_a_sweep_does_not_record(tmp_path):
    cfg = {**CFG, "campaign": {**CFG["campaign"], "record": "signals"}}
    with pytest.raises(ftc_mc.errors.UserError, match="does not record"):
        ftc_mc.run_sweep(cfg, thresholds="20,30", out=tmp_path / "s")
    assert not (tmp_path / "s").exists()
