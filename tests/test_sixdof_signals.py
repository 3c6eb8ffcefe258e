"""Recorded signals on the 6-DOF flying wing: the lateral sensors and the side
monitor's projections, and its decisions re-run offline on them; a design whose
resets come from the side monitor."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pytest

import ftc_mc
from ftc_mc.campaign.detector import batches, side_monitor_decisions, side_monitor_detector
from ftc_mc.campaign.signals import (KEYS, lateral_columns, monitor_columns, signal_columns,
                                     signal_files)
from ftc_mc.config.schema import MonitorConfig
from ftc_mc.conventions import LONGITUDINAL as LAY
from ftc_mc.core.sixdof.layout import MONITOR_DIRECTIONS
from ftc_mc.errors import UserError
from golden_cases import CAMPAIGNS

THRESHOLD, THROTTLE = 12.0, 20.0
"""The monitored design's own monitor thresholds (elevons, throttle): below the
run's (30), so that it decides often, false decisions included."""

CFG = copy.deepcopy(CAMPAIGNS["sixdof_moderate"])  # the golden case's path, compiled there
CFG["campaign"].update(signature="paper", designs=["monitored"])
CFG["designs"] = {"monitored": {"signature": "paper", "resets": "side_monitor",
                                "monitor_threshold": THRESHOLD,
                                "monitor_throttle_threshold": THROTTLE}}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec6") / "run"
    ftc_mc.run_campaign(CFG, out=out, record="signals", jobs=1, progress=False)
    return out


def _offline(recorded):
    """``{(transition, variant, trial_id): (steps, decisions)}`` of the
    monitor re-run offline on every recorded trial, at each design's threshold."""
    dt = 0.1
    mc = MonitorConfig()
    steps = lambda s: int(round(s / dt))  # noqa: E731
    out = {}
    for name, design, ids, sig, _ in batches(recorded, columns=monitor_columns()):
        thr = [THROTTLE, THRESHOLD, THRESHOLD] if design == "monitored" else mc.threshold
        dec = side_monitor_decisions(sig, steps(mc.window_s), steps(mc.min_window_s), thr,
                                     steps(mc.startup_s))
        for i, tid in enumerate(ids):
            out[(name, design, int(tid))] = dec[i]
    return out


def test_sixdof_signals_layout(recorded):
    files = signal_files(recorded)
    sig = pd.concat([pd.read_parquet(f) for f in files], ignore_index=True)
    assert tuple(sig.columns) == KEYS + signal_columns(sixdof=True)
    assert set(lateral_columns()) | set(monitor_columns()) <= set(sig.columns)
    # the lateral sensors move in moderate gusts; the projections are the GLR's
    # float64 input (their statistics: tests/test_side_monitor.py)
    assert sig["z_phi"].std() > 0 and sig["z_p"].std() > 0
    for c in monitor_columns():
        assert sig[c].dtype == np.float64 and np.isfinite(sig[c]).all() and sig[c].std() > 0


def test_side_monitor_offline_equals_the_closed_loop(recorded):
    """Every trial's monitor decisions, re-run offline on its recorded
    projections: the first at or after the switch is the closed loop's
    (``side_s``, ``side_block``), those before it are its ``side_false``, and a
    design whose resets come from the monitor reset exactly there."""
    offline = _offline(recorded)
    trials = pd.read_parquet(recorded / "trials.parquet")
    resets = pd.read_parquet(recorded / "resets.parquet")
    k_f = round(CFG["timing"]["fault_time_s"] / 0.1)
    n_first = n_resets = 0
    for t in trials.itertuples():
        dec = offline[(t.transition, t.variant, int(t.trial_id))]
        k = np.flatnonzero(dec) + 1  # the steps decided
        after = k[k >= k_f]
        if np.isnan(t.side_s):
            assert len(after) == 0, t
        else:
            assert len(after) and after[0] == k_f + round(t.side_s / 0.1), t
            assert MONITOR_DIRECTIONS[dec[after[0] - 1] - 1] == t.side_block, t
            n_first += 1
        if t.mode_pre == "nominal":
            assert (k < k_f).sum() == t.side_false, t
        if t.variant == "monitored":
            r = resets[(resets["transition"] == t.transition) & (resets["variant"] == t.variant)
                       & (resets["trial_id"] == t.trial_id)]
            got = list(zip(np.round(r["time_s"] / 0.1).astype(int), r["block"]))
            want = [(int(s), LAY.blocks[LAY.actuator_block[dec[s - 1] - 1]]) for s in k]
            assert got == want, t
            n_resets += len(want)
    assert n_first >= 10 and n_resets >= 10


def test_side_monitor_detector_scores_sides(recorded, tmp_path):
    """The offline monitor scored as a detector: on the paper design's flights
    (the run's threshold) its alarm is the monitor's first decision, naming
    that actuator; ``correct_side`` is judged on it."""
    offline = _offline(recorded)
    res = ftc_mc.score_detector(recorded, side_monitor_detector(), out=tmp_path / "s")
    t = res["trials"]
    t = t[t["variant"] == "side_monitor@paper"]
    assert len(t) == 12
    for r in t.itertuples():
        dec = offline[(r.transition, "paper", int(r.trial_id))]
        k = np.flatnonzero(dec)
        if len(k) == 0:
            assert np.isnan(r.alarm_s) and r.alarm_actuator == "", r
        else:
            assert r.alarm_s == pytest.approx((k[0] + 1) * 0.1), r
            assert r.alarm_actuator == LAY.actuators[dec[k[0]] - 1], r
    assert t["correct_side"].notna().any()


@pytest.mark.parametrize("change, problem", [
    ({"plant": {"kind": "nonlinear", "turbulence": "moderate", "dof": 3}}, "plant.dof 3"),
    ({"monitor": {"enabled": False}}, "monitor.enabled is false")])
def test_monitor_resets_need_the_side_monitor(change, problem):
    from ftc_mc.api import campaign_config
    cfg = {**copy.deepcopy(CFG), **change}
    with pytest.raises(UserError, match=r"designs\.monitored\.resets: side_monitor.*" + problem):
        campaign_config(cfg)


def test_a_sweep_runs_monitor_designs_at_each_point_alone():
    """At sweep thresholds no residual reaches, every Table 1 lane would share
    its start; the monitored design's monitor still resets before the switch
    (false decisions at its low thresholds), with the reset variances of the
    point's thresholds: each point equals a campaign run at it."""
    from ftc_mc.api import campaign_config
    from ftc_mc.campaign.sweep import run_sweep, threshold_points

    cfg = campaign_config(CFG)
    points = threshold_points("1000000,4000000")
    res = run_sweep(cfg, points, flights=2, jobs=1, progress=False)
    for t, _ in points:
        est = cfg.estimator.model_copy(update={"t_q": t, "t_nx": t})
        design = cfg.designs["monitored"].model_copy(update={"t_q": t, "t_nx": t})
        at = cfg.model_copy(update={"estimator": est, "designs": {"monitored": design}})
        alone = ftc_mc.run_campaign(at, jobs=1, progress=False).trials
        alone = alone[alone["variant"] == "monitored"].reset_index(drop=True)
        shared = res.trials[(res.trials["t_q"] == t) & (res.trials["variant"] == "monitored")]
        assert (alone["side_false"] > 0).any()  # monitor resets before the switch
        pd.testing.assert_frame_equal(alone, shared.drop(columns=["t_q", "t_nx"])
                                      .reset_index(drop=True), check_exact=True)
