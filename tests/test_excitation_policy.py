"""A design's excitation policy and the cost of flying: validation,
the kernels' settings, the design key that keeps a sweep's shared starts
apart, the cost columns against the trial's own history, and a policy's
effect on a small campaign."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from ftc_mc import api
from ftc_mc.campaign.chunk import COST_COLUMNS, chunk_spec, height_columns, trial_inputs
from ftc_mc.campaign.sweep import run_sweep, threshold_points
from ftc_mc.config import Config
from ftc_mc.config.load import validate_model
from ftc_mc.conventions import (COST_TRACK_MAX, COST_TRACK_SQ, COST_U2, EXCITE_AMBIGUOUS,
                                EXCITE_NONE, EXCITE_PERIODIC, LONGITUDINAL)
from ftc_mc.errors import UserError
from ftc_mc.sim.designs import NO_POLICY
from ftc_mc.sim.lanes import run_alone
from test_designs import assert_shared_start_exact

PERIODIC = {"excitation_policy": "periodic", "excitation_period_s": 4.0,
            "excitation_phase_s": 1.0}
AMBIGUOUS = {"excitation_policy": "ambiguous", "excitation_period_s": 3.0,
             "excitation_belief": 0.9, "excitation_residual": 6.0}
SHORT = {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 12.0}


def config(transitions=("elevon_loss",), trials=8, **over):
    data = {"designs": {"per": PERIODIC, "amb": AMBIGUOUS},
            "campaign": {"transitions": list(transitions), "trials": trials, "chunk_size": 8,
                         "signature": "swapped", "designs": ["per", "amb"]},
            "controller": {"kind": "nominal"}, "timing": SHORT,
            "model": {"airframe": "x8-gryte2018"}}
    data.update(over)
    return validate_model(Config, data, "test.yaml")


@pytest.mark.parametrize("design, needle", [
    ({"excitation_policy": "always"}, "designs.x.excitation_policy"),
    ({"excitation_policy": "periodic", "excitation_period_s": 3.0},
     "designs.x.excitation_period_s: must be at least twice the longer excitation signal (4 s)"),
    ({"excitation_policy": "periodic", "excitation_period_s": 4.05},
     "designs.x.excitation_period_s: must be a positive multiple of model.dt_s"),
    ({"excitation_policy": "periodic", "excitation_phase_s": 0.25},
     "designs.x.excitation_phase_s: must be a positive multiple of model.dt_s"),
    ({"excitation_policy": "periodic", "excitation_phase_s": 5.0},
     "designs.x.excitation_phase_s: must be below excitation_period_s (5 s)"),
    ({"excitation_policy": "ambiguous", "excitation_belief": 1.5}, "designs.x.excitation_belief"),
    ({"excitation_policy": "ambiguous", "excitation_residual": 0.0},
     "designs.x.excitation_residual"),
    ({"s3211_floor": 1.5}, "designs.x.s3211_floor"),
    ({"s3211_floor": -0.1}, "designs.x.s3211_floor"),
    ({"doublet_amplitude": 0.0}, "designs.x.doublet_amplitude"),
    ({"doublet_amplitude": 0.6}, "designs.x.doublet_amplitude"),
    ({"s3211_amplitude_rad": 0.4}, "designs.x.s3211_amplitude_rad"),
    ({"policy_s3211_amplitude_rad": 0.1}, "designs.x.policy_s3211_amplitude_rad: only with"),
    ({"excitation_pause_belief": 0.5}, "designs.x.excitation_pause_belief: only with"),
    ({**PERIODIC, "excitation_pause_belief": 1.0}, "designs.x.excitation_pause_belief"),
    ({**PERIODIC, "policy_doublet_amplitude": 0.7}, "designs.x.policy_doublet_amplitude"),
    ({"s3211_amplitude_rad": float("nan")}, "designs.x.s3211_amplitude_rad"),
])
def test_bad_policies_are_one_line(design, needle):
    with pytest.raises(UserError) as exc:
        validate_model(Config, {"designs": {"x": design}}, "test.yaml")
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg, msg


def test_policy_reaches_the_kernels_as_data():
    """The design's policy fills ``Excitation``'s policy fields (steps); the
    paper's designs keep :data:`NO_POLICY`; the policy is part of the design key,
    so a sweep never shares a start between designs that fly differently before
    any reset; every field has the same type (one compile path for all)."""
    setup = chunk_spec(config()).setup
    per, amb, sw = (setup.scheme(n).excitation for n in ("per", "amb", "swapped"))
    assert (per.policy, per.period, per.phase) == (EXCITE_PERIODIC, 40, 10)
    assert (amb.policy, amb.period, amb.belief_max, amb.suspect) == (EXCITE_AMBIGUOUS, 30,
                                                                     0.9, 6.0)
    assert sw._asdict() == {**setup.exc._asdict(), **NO_POLICY} and sw.policy == EXCITE_NONE
    assert math.isinf(sw.suspect)
    assert [type(v) for v in per] == [type(v) for v in sw] == [type(v) for v in amb]
    keys = {n: setup.designs[n].key for n in ("per", "amb", "swapped")}
    assert len(set(keys.values())) == 3


def test_s3211_floor_reaches_the_kernels():
    """A design's ``s3211_floor`` fills ``Excitation.s3211_floor`` as a
    float, with or without a policy; the built-in designs keep 0 (eq. 23); it is
    part of the design key."""
    cfg = config(designs={"per": {**PERIODIC, "s3211_floor": 0.5},
                          "fl": {"signature": "swapped", "s3211_floor": 0.2},
                          "amb": AMBIGUOUS},
                 campaign={"transitions": ["elevon_unlock"], "trials": 8, "chunk_size": 8,
                           "signature": "swapped", "designs": ["per", "fl"]})
    setup = chunk_spec(cfg).setup
    per, fl, sw = (setup.scheme(n).excitation for n in ("per", "fl", "swapped"))
    assert (per.s3211_floor, fl.s3211_floor, sw.s3211_floor) == (0.5, 0.2, 0.0)
    assert fl._asdict() == {**sw._asdict(), "s3211_floor": 0.2}
    assert type(sw.s3211_floor) is type(fl.s3211_floor) is float
    assert setup.designs["fl"].key != setup.designs["swapped"].key


def test_a_design_s_own_amplitudes_reach_the_kernels_and_fly():
    """A design's ``doublet_amplitude`` and ``s3211_amplitude_rad``
    replace the excitation section's in its ``Excitation`` only, as floats, and
    are part of the design key.  A design that sets the section's own values
    flies bit for bit as one that sets none; a larger 3211 on the same policy
    flies differently (more elevon energy)."""
    same = {**PERIODIC, "doublet_amplitude": 0.1, "s3211_amplitude_rad": 0.05}
    big = {**PERIODIC, "s3211_amplitude_rad": 0.15}
    cfg = config(designs={"per": PERIODIC, "same": same, "big": big},
                 campaign={"transitions": ["elevon_loss"], "trials": 8, "chunk_size": 8,
                           "signature": "swapped", "designs": ["per", "same", "big"]})
    spec = chunk_spec(cfg)
    setup = spec.setup
    assert (setup.exc.doublet_amp, setup.exc.s3211_amp) == (0.1, 0.05)  # the section's
    per, same_x, big_x, sw = (setup.scheme(n).excitation for n in ("per", "same", "big",
                                                                   "swapped"))
    assert per._asdict() == same_x._asdict()
    assert big_x._asdict() == {**per._asdict(), "s3211_amp": 0.15, "policy_s3211_amp": 0.15}
    assert (sw.doublet_amp, sw.s3211_amp) == (0.1, 0.05)
    assert [type(v) for v in big_x] == [type(v) for v in sw]
    assert len({setup.designs[n].key for n in ("per", "same", "big")}) == 3
    inp, _ = trial_inputs(spec, "elevon_loss", np.arange(8))
    recs = {n: run_alone(setup, n, setup.det[n], inp, 64) for n in ("per", "same", "big")}
    for f in recs["per"]._fields:
        np.testing.assert_array_equal(getattr(recs["same"], f), getattr(recs["per"], f),
                                      err_msg=f)
    left = COST_U2 + LONGITUDINAL.inputs.index("elevon_left")
    assert recs["big"].cost[left].sum() > recs["per"].cost[left].sum()


def test_the_policy_s_own_amplitudes_and_its_pause_reach_the_kernels_and_fly():
    """``policy_*_amplitude`` set the policy's signals only (a reset's stay the
    design's); ``excitation_pause_belief`` reaches the kernels as a float (inf
    when unset). On the elevon-unlock row the belief starts on the locked
    elevon, so a design paused at 0.5 sends no periodic 3211 while it holds:
    less elevon energy than the same policy unpaused, as much as one with
    policy amplitudes of the section's values."""
    small = {**PERIODIC, "policy_s3211_amplitude_rad": 0.2}
    paused = {**small, "excitation_pause_belief": 0.5}
    cfg = config(transitions=("elevon_unlock",),
                 designs={"per": PERIODIC, "small": small, "paused": paused},
                 campaign={"transitions": ["elevon_unlock"], "trials": 8, "chunk_size": 8,
                           "signature": "swapped", "designs": ["per", "small", "paused"]})
    spec = chunk_spec(cfg)
    setup = spec.setup
    per, sm, pa = (setup.scheme(n).excitation for n in ("per", "small", "paused"))
    assert (sm.s3211_amp, sm.policy_s3211_amp, sm.doublet_amp, sm.policy_doublet_amp) == (
        0.05, 0.2, 0.1, 0.1)
    assert per.pause_belief == sm.pause_belief == math.inf and pa.pause_belief == 0.5
    assert pa._asdict() == {**sm._asdict(), "pause_belief": 0.5}
    inp, _ = trial_inputs(spec, "elevon_unlock", np.arange(8))
    right = COST_U2 + LONGITUDINAL.inputs.index("elevon_right")
    energy = {n: run_alone(setup, n, setup.det[n], inp, 64).cost[right].sum()
              for n in ("per", "small", "paused")}
    assert energy["small"] > energy["per"] > energy["paused"], energy


def test_shared_start_with_a_policy_equals_running_alone():
    """A sweep's shared start (resets disabled up to the switch) with a policy
    gives every design, at every threshold, the records it gives alone: the
    policy does not read the thresholds.  The policies do start signals
    before the switch, so the designs' pre-fault flights differ."""
    cfg = config(transitions=("engine_loss",))
    spec = chunk_spec(cfg)
    setup = spec.setup
    inp, _ = trial_inputs(spec, "engine_loss", np.arange(8))
    runs = [(n, setup.detection(n, t, t)) for t in (8.0, 25.0) for n in setup.designs]
    _, (alone, _) = assert_shared_start_exact(setup, inp, runs)
    energy = {name: rec.cost[COST_U2].sum() for (name, det), rec in zip(runs, alone)
              if det.t_q == 25.0}
    assert energy["per"] > energy["swapped"] and energy["amb"] > energy["swapped"]


def test_cost_sums_match_the_history():
    """``TrialRecord.cost`` equals the sums over the trial's own history: the
    cross-track error of ``scenario/run.py`` and the commands, over the steps
    flown; the trial columns are their RMS, maximum and energies."""
    spec = chunk_spec(config())
    setup = spec.setup
    inp, _ = trial_inputs(spec, "elevon_loss", np.arange(4))
    rec = run_alone(setup, "per", setup.det["per"], inp, 64, history=True)
    g = setup.plant.trim.gamma0
    x = rec.hist_x[:, LONGITUDINAL.state("x")]
    z = rec.hist_x[:, LONGITUDINAL.state("z")]
    cross = x * math.sin(g) + z * math.cos(g)
    assert (rec.status == 0).all()
    np.testing.assert_allclose(rec.cost[COST_TRACK_SQ], (cross ** 2).sum(axis=0), rtol=1e-12)
    np.testing.assert_array_equal(rec.cost[COST_TRACK_MAX], np.abs(cross).max(axis=0))
    np.testing.assert_allclose(rec.cost[COST_U2:], (rec.hist_u ** 2).sum(axis=0), rtol=1e-12)
    assert np.any(rec.hist_exc[:, 2] == 1.0) and np.any(rec.hist_exc[:, 3] == 1.0)
    # the height marks: z after the switch step and after the last step,
    # and the height lost between them, the glide path's descent included
    kf, n = setup.tim.k_fault, setup.tim.n_steps
    np.testing.assert_array_equal(rec.z_switch_last[0], z[kf - 1])
    np.testing.assert_array_equal(rec.z_switch_last[1], z[n - 1])
    dt, V0 = setup.plant.dt, setup.plant.trim.V0
    height = V0 * math.sin(g) * dt * np.arange(1, n + 1)[:, None] - z  # above the start
    lost = height_columns(rec, setup)["height_lost_m"]
    np.testing.assert_allclose(lost, height[kf - 1] - height[n - 1], rtol=1e-12, atol=1e-12)


def test_campaign_columns_and_summary():
    """Every trial row carries the cost columns; the summary their RMS, maxima
    and mean energies; a periodic policy spends more control energy than the
    same design without it, on the same trials; results do not depend on the
    chunking."""
    res = api.run_campaign(config(), jobs=1, progress=False)
    t = res.trials
    assert set(COST_COLUMNS) <= set(t.columns)
    assert list(t.columns[-len(COST_COLUMNS) - 1:]) == [*COST_COLUMNS, "height_lost_m"]
    assert (t["track_rms_m"] > 0).all() and (t["track_max_m"] >= t["track_rms_m"]).all()
    s = res.summary.set_index("variant")
    for col in ("track_rms_m", "track_max_m_mean", "track_max_m", *COST_COLUMNS[2:]):
        assert np.isfinite(s[col]).all(), col
    for col in COST_COLUMNS[2:]:
        assert s.loc["per", col] > s.loc["swapped", col], col
    again = api.run_campaign(config(campaign={"transitions": ["elevon_loss"], "trials": 8,
                                              "chunk_size": 3, "signature": "swapped",
                                              "designs": ["per", "amb"]}),
                             jobs=1, progress=False)
    pd.testing.assert_frame_equal(t, again.trials, check_exact=True)


def test_sweep_runs_a_policy_like_any_design():
    """``ftc-mc sweep`` with a policy design: each point's trials equal a
    campaign at that point (the shared start is the design's own)."""
    cfg = config(transitions=("engine_loss",), trials=6)
    points = threshold_points("8,25")
    res = run_sweep(cfg, points, flights=4, jobs=1, progress=False)
    assert set(res.table["variant"]) == {"swapped", "per", "amb"}
    for t, _ in points:
        est = cfg.estimator.model_copy(update={"t_q": t, "t_nx": t})
        designs = {n: d.model_copy(update={"t_q": t, "t_nx": t}) for n, d in cfg.designs.items()}
        alone = api.run_campaign(cfg.model_copy(update={"estimator": est, "designs": designs}),
                                 jobs=1, progress=False).trials
        shared = res.trials[res.trials.t_q == t].drop(columns=["t_q", "t_nx"])
        pd.testing.assert_frame_equal(alone, shared.reset_index(drop=True), check_exact=True)


def test_report_shows_the_cost_of_flying():
    """The report's cost table reads the summary's cost columns, one
    row per transition and design; a run written before them gets none."""
    from ftc_mc.report.runs import cost_lines

    summary = pd.DataFrame([
        {"label": "Elevon loss", "variant": v, "track_rms_m": rms, "track_max_m_mean": 0.5,
         "track_max_m": mx, "control_energy_throttle": 0.002,
         "control_energy_elevon_left": 0.117, "control_energy_elevon_right": 0.157}
        for v, rms, mx in (("swapped", 0.025, 0.9), ("per", 0.0312, 1.25))])
    text = "\n".join(cost_lines(summary))
    assert "### Cost of flying" in text
    rows = [line for line in text.splitlines() if line.startswith("| Elevon loss")]
    assert len(rows) == 2 and "per" in rows[1] and "0.0312" in rows[1]
    assert "0.5 / 1.25" in text and "0.117 / 0.157" in text
    assert cost_lines(summary.drop(columns=["track_rms_m"])) == []
