"""The actuator fault kinds beyond lock and loss: the truth's generic fault
model against its twin, each kind's rows and draws, their recording and
scoring, and the refusal of bad fault specifications."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import ftc_mc
import naive
from ftc_mc.campaign.chunk import chunk_spec, trial_inputs
from ftc_mc.campaign.kinds import KIND_STREAM, kind_transition
from ftc_mc.campaign.signals import KIND_COLUMNS, signal_files
from ftc_mc.campaign.transitions import TRANSITION_TABLE, transition_of
from ftc_mc.cli import cli
from ftc_mc.config import load_config
from ftc_mc.conventions import (ACTUATOR_FAULT_KINDS, ACTUATOR_NAMES, FAULT_PARAM_NEUTRAL,
                                FP_DELAY, FP_FLOAT, FP_FLOAT_ANGLE, FP_FLOAT_GAIN,
                                FP_OSC_AMP, FP_OSC_FREQ, FP_OSC_PHASE, FP_RATE, FP_RUNAWAY,
                                KIND_NONE, KIND_TRANSITIONS, KINDS_BEYOND, LONGITUDINAL,
                                MODE_NAMES, MODE_NOMINAL, N_CMD_HIST, N_FAULT_PARAM)
from ftc_mc.core.longitudinal.plant import actuator_effect
from ftc_mc.model.faults import effect
from ftc_mc.sim.inputs import neutral_params

L = 7
U0 = np.array([0.33, 0.057, 0.057])
LO = np.array([0.0, -0.5236, -0.5236]) - U0
HI = np.array([1.0, 0.5236, 0.5236]) - U0
DT = 0.1

CFG = {"campaign": {"trials": 6, "chunk_size": 3, "seed": 2026, "signature": "both"},
       "controller": {"kind": "reconfiguring"},
       "model": {"airframe": "x8-gryte2018"},
       "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}
"""A small run on the golden cases' linear path (its kernels already compiled)."""


def _random_params(rng):
    """Every kind beyond lock and loss on some lane and actuator, several at once
    on a few, neutral elsewhere."""
    fp = neutral_params(1, L)[0]
    fp[FP_DELAY, 1, 0] = 3
    fp[FP_RATE, 2, 1] = 0.2
    fp[FP_OSC_AMP, 0, 2], fp[FP_OSC_FREQ, 0, 2], fp[FP_OSC_PHASE, 0, 2] = 0.1, 1.3, 0.7
    fp[FP_RUNAWAY, 1, 3] = -0.05
    fp[FP_FLOAT, 2, 4], fp[FP_FLOAT_ANGLE, 2, 4], fp[FP_FLOAT_GAIN, 2, 4] = 1.0, 0.02, -0.6
    fp[FP_DELAY, 1, 5], fp[FP_RATE, 1, 5], fp[FP_RUNAWAY, 1, 5] = 12, 0.3, 0.5
    fp[FP_RATE, :, 6] = rng.uniform(0.01, 0.1, 3)
    return fp


def test_actuator_model_matches_its_twin_over_many_steps():
    """The kernel against ``naive.actuator_model_ref`` step by step (the ring,
    the last followed command and the effect, bit for bit), with locks and
    losses on some lanes and a true angle of attack for the float."""
    rng = np.random.default_rng(3)
    fp = _random_params(rng)
    b0 = np.zeros((3, L))
    b1 = np.zeros((3, L))
    b1[0, 1], b1[1, 6], b0[1, 6] = 0.4, 1.0, 0.1
    uhist = np.zeros((N_CMD_HIST, 3, L))
    uprev = np.zeros((3, L))
    ref_hist, ref_prev = uhist.copy(), uprev.copy()
    e = np.zeros((3, L))
    for k in range(40):
        u = rng.uniform(LO[:, None], HI[:, None], (3, L))
        alpha = rng.uniform(-0.1, 0.2, L)
        actuator_effect(U0, LO, HI, b0, b1, fp, 5, k, DT, alpha, uhist, uprev, u, e)
        want, ref_hist, ref_prev = naive.actuator_model_ref(
            u, U0, LO, HI, b0, b1, fp, 5, k, DT, alpha, ref_hist, ref_prev)
        np.testing.assert_array_equal(uhist, ref_hist)
        np.testing.assert_array_equal(uprev, ref_prev)
        np.testing.assert_allclose(e, want, rtol=0, atol=1e-15)


def test_neutral_parameters_are_eq2_to_the_bit():
    """With the neutral parameters the effect is eq. (2)'s arithmetic exactly,
    whatever the ring and the last command hold."""
    rng = np.random.default_rng(4)
    fp = neutral_params(1, L)[0]
    assert tuple(fp[:, 0, 0]) == FAULT_PARAM_NEUTRAL and fp.shape[0] == N_FAULT_PARAM
    b0 = rng.uniform(-0.2, 0.2, (3, L))
    b1 = rng.uniform(0, 1, (3, L))
    uhist = rng.standard_normal((N_CMD_HIST, 3, L))
    uprev = rng.standard_normal((3, L))
    u = rng.uniform(LO[:, None], HI[:, None], (3, L))
    e = np.zeros((3, L))
    actuator_effect(U0, LO, HI, b0, b1, fp, 0, 9, DT, rng.standard_normal(L), uhist, uprev,
                    u, e)
    want = np.column_stack([effect(u[:, l], U0, b0[:, l], b1[:, l]) for l in range(L)])
    assert np.array_equal(e.view(np.uint64), want.view(np.uint64))
    assert np.array_equal(uprev, u)


def test_each_kind_behaves_as_named():
    """Delay, rate limit, limit cycle, runaway to the stop and float, one actuator each."""
    steps = 60
    fp = neutral_params(1, 5)[0]
    fp[FP_DELAY, 1, 0] = 4
    fp[FP_RATE, 1, 1] = 0.2  # rad/s
    fp[FP_OSC_AMP, 1, 2], fp[FP_OSC_FREQ, 1, 2] = 0.05, 1.0
    fp[FP_RUNAWAY, 1, 3] = 0.5  # rad/s: reaches the stop
    fp[FP_FLOAT, 1, 4], fp[FP_FLOAT_ANGLE, 1, 4], fp[FP_FLOAT_GAIN, 1, 4] = 1.0, 0.01, -0.5
    b = np.zeros((3, 5))
    uhist, uprev = np.zeros((N_CMD_HIST, 3, 5)), np.zeros((3, 5))
    us, es = [], []
    alpha = np.full(5, 0.04)
    for k in range(steps):
        u = np.zeros((3, 5))
        u[1] = 0.1 * math.sin(0.3 * k)
        e = np.zeros((3, 5))
        actuator_effect(U0, LO, HI, b, b, fp, 0, k, DT, alpha, uhist, uprev, u, e)
        us.append(u[1].copy())
        es.append(e[1].copy())
    us, es = np.array(us), np.array(es)
    np.testing.assert_array_equal(es[4:, 0], us[:-4, 0])  # delayed by 4 steps
    assert not es[:4, 0].any()  # trim before the first step
    assert np.abs(np.diff(es[:, 1])).max() <= 0.2 * DT + 1e-15  # rate limited
    t = np.arange(steps) * DT
    np.testing.assert_allclose(es[:, 2], us[:, 2] + 0.05 * np.sin(2 * np.pi * t), atol=1e-15)
    assert es[-1, 3] == HI[1]  # ran away to the stop
    np.testing.assert_allclose(es[:, 4], 0.01 - 0.5 * 0.04 - U0[1], atol=1e-15)  # floats


def test_rows_apply_where_they_should():
    """Each kind on the engine and both elevons, float on the elevons only; one
    label, the faulty actuator's block and mode."""
    assert len(KIND_TRANSITIONS) == 3 * len(KINDS_BEYOND) - 1
    assert "engine_float" not in KIND_TRANSITIONS
    for name in KIND_TRANSITIONS:
        tr = transition_of(name)
        assert TRANSITION_TABLE[name] is not None and tr.kind in ACTUATOR_FAULT_KINDS
        assert tr.correct_block == LONGITUDINAL.actuator_block[tr.actuator]
        assert tr.other_block != tr.correct_block
        assert MODE_NAMES[tr.fault_mode] == ACTUATOR_NAMES[tr.actuator]
    assert kind_transition("elevon_slow").actuator == ACTUATOR_NAMES.index("left_elevon")
    assert kind_transition("right_elevon_float").actuator == ACTUATOR_NAMES.index("right_elevon")


@pytest.mark.parametrize("name", ["elevon_hardover", "engine_delayed", "right_elevon_float",
                                  "elevon_intermittent"])
def test_draws_keep_the_streams_and_stay_in_range(name):
    """A kind row flies the paper rows' noise (common random numbers); its
    parameters come from their own stream and lie in the configured ranges."""
    cfg = ftc_mc.api.campaign_config(CFG | {"campaign": CFG["campaign"] | {"transitions": [name]}})
    spec = chunk_spec(cfg)
    ids = np.arange(5)
    inp, values = trial_inputs(spec, name, ids)
    ref, _ = trial_inputs(spec, "elevon_lock", ids)
    assert np.array_equal(inp.w, ref.w) and np.array_equal(inp.v, ref.v)
    tr = transition_of(name)
    a, kf = tr.actuator, spec.setup.tim.k_fault
    assert (inp.mode_pre == MODE_NOMINAL).all() and (inp.mode_post == tr.fault_mode).all()
    assert not inp.b1[0].any() and (inp.fp[0] == neutral_params(1, 5)[0]).all()
    lo, hi = spec.setup.plant.u_lower[a], spec.setup.plant.u_upper[a]
    if tr.kind == "hardover":
        assert set(inp.b0[1, a]) <= {lo, hi} and (inp.b1[1, a] == 1).all()
    elif tr.kind == "delayed":
        d = inp.fp[1, FP_DELAY, a]
        assert ((d >= 2) & (d <= 10)).all()
        np.testing.assert_allclose(values[:, 0], d * 0.1)
    elif tr.kind == "float":
        g = inp.fp[1, FP_FLOAT_GAIN, a]
        assert ((g >= -1.0) & (g <= -0.3)).all() and (inp.fp[1, FP_FLOAT, a] == 1).all()
    elif tr.kind == "intermittent":
        assert inp.k_switch[1] == kf and (np.diff(inp.k_switch[1:]) == 5).all()
        on = inp.b1[1:, a] == 1
        assert on[0].all() and (~on).any()  # starts stuck, works in between
        np.testing.assert_allclose(values[:, 1], on.mean(axis=0))
    # the kind's first draw is the first of its own stream
    m = np.random.default_rng([0, cfg.campaign.seed, KIND_STREAM]).uniform()
    if tr.kind == "float":
        assert g[0] == pytest.approx(-1.0 + m * 0.7)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("kinds") / "run"
    cfg = CFG | {"campaign": CFG["campaign"] | {
        "transitions": ["elevon_runaway", "engine_intermittent", "right_elevon_oscillatory"]}}
    ftc_mc.run_campaign(cfg, out=out, record="signals", jobs=1, progress=False)
    return out


def test_kind_rows_are_judged_and_recorded(recorded):
    """The rows' trials carry the kind and its parameters; the signals carry each
    step's kind as truth columns (-1 while healthy, an intermittent's off-spells too)."""
    t = pd.read_parquet(recorded / "trials.parquet")
    assert set(t["fault_kind"]) == {"runaway", "intermittent", "oscillatory"}
    assert np.isfinite(t["fault_param"]).all()
    assert (t["mode_post"] == t["transition"].map(
        lambda n: MODE_NAMES[transition_of(n).fault_mode])).all()
    sig = pd.concat([pd.read_parquet(f) for f in signal_files(recorded)], ignore_index=True)
    kf = 50
    for name, act, kind in (("elevon_runaway", "left_elevon", "runaway"),
                            ("engine_intermittent", "engine", "intermittent"),
                            ("right_elevon_oscillatory", "right_elevon", "oscillatory")):
        g = sig[sig["transition"] == name]
        col = g[f"kind_{act}"].to_numpy()
        before = g["step"].to_numpy() <= kf
        assert (col[before] == KIND_NONE).all()
        after = col[~before]
        code = ACTUATOR_FAULT_KINDS.index(kind)
        assert set(np.unique(after)) <= {code, KIND_NONE} and (after == code).any()
        if kind == "intermittent":
            assert (after == KIND_NONE).any()  # off between spells
        else:
            assert (after == code).all()
        for other in KIND_COLUMNS:
            if other != f"kind_{act}":
                assert (g[other] == KIND_NONE).all()


def test_a_detector_is_scored_on_kind_rows(recorded, tmp_path):
    """``ftc-mc score`` on the kind rows: a detector alarming on a large pitch
    innovation, judged against each row's correct block."""
    def spike(signals, names, dt):
        q = signals[:, :, names.index("innov_q")]
        hit = np.abs(q) > 3.0
        first = np.where(hit.any(axis=1), hit.argmax(axis=1) * dt, np.nan)
        return first

    res = ftc_mc.score_detector(recorded, spike, out=tmp_path / "s")
    s = res["summary"]
    assert set(s["transition"]) == {"elevon_runaway", "engine_intermittent",
                                    "right_elevon_oscillatory"}
    assert {"alfa_precision", "alfa_recall", "correct_rate"} <= set(s.columns)


BAD = [
    ({"kind_draws": {"delay_s": [0.5, 0.2]}}, "kind_draws.delay_s"),
    ({"kind_draws": {"delay_s": [0.2, 5.0]}}, "kind_draws.delay_s"),
    ({"kind_draws": {"delay_s": [0.01, 0.5]}}, "kind_draws.delay_s"),
    ({"kind_draws": {"elevon_rate_limit_deg_s": [-5, 30]}}, "kind_draws.elevon_rate_limit_deg_s"),
    ({"kind_draws": {"osc_freq_hz": [0.5, 8.0]}}, "kind_draws.osc_freq_hz"),
    ({"kind_draws": {"float_gain": [0.3, 1.0]}}, "kind_draws.float_gain"),
    ({"kind_draws": {"intermittent_on_s": [0.1, 1.0]}}, "kind_draws.intermittent_on_s"),
    ({"kind_draws": {"engine_osc_amp": [0.1]}}, "kind_draws.engine_osc_amp"),
    ({"kind_draws": {"flutter": [1, 2]}}, "kind_draws.flutter"),
    ({"campaign": {"transitions": ["engine_float"]}}, "campaign.transitions"),
    ({"campaign": {"transitions": ["elevon_wobbly"]}}, "campaign.transitions"),
]


@pytest.mark.parametrize("over,field", BAD)
def test_bad_fault_specifications_are_refused(tmp_path, over, field):
    """Each bad fault specification: one line naming the field, exit 2, nothing written."""
    cfg = json.loads(json.dumps(CFG))
    for k, v in over.items():
        cfg[k] = cfg.get(k, {}) | v
    path = tmp_path / "bad.yaml"
    path.write_text(json.dumps(cfg))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["run", str(path), "--out", str(out)])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and field in lines[0], r.output
    assert not out.exists()


SCENARIO = {"scenario": {"duration_s": 40.0, "schedule": [
    {"time_s": 0.0, "fault": "nominal"},
    {"time_s": 5.0, "fault": "oscillatory", "actuator": "left_elevon", "duration_s": 3.0,
     "amplitude": 0.05, "frequency_hz": 1.0, "phase_rad": 0.0},
    {"time_s": 10.0, "fault": "lock", "actuator": "engine", "position": 0.3,
     "duration_s": 2.0},
    {"time_s": 20.0, "fault": "runaway", "actuator": "right_elevon", "rate": 0.02},
    {"time_s": 30.0, "fault": "nominal"}]}}
"""A scenario of faults that come and go (start, duration, parameters)."""


def test_a_scenario_holds_faults_that_come_and_go():
    """Durations written out as nominal entries; each entry's truth mode is its
    actuator's; the commanded and the flown elevon differ only while it oscillates."""
    from ftc_mc.config.schema import ScenarioConfig, expanded_schedule
    from ftc_mc.sim.inputs import scenario_schedule

    sc = ScenarioConfig.model_validate(SCENARIO)
    ev = expanded_schedule(sc.scenario)
    assert [(e.time_s, e.fault) for e in ev] == [
        (0.0, "nominal"), (5.0, "oscillatory"), (8.0, "nominal"), (10.0, "lock"),
        (12.0, "nominal"), (20.0, "runaway"), (30.0, "nominal")]
    s = scenario_schedule(ev, np.array([0.3, 0.05, 0.05]), 0.1, np.zeros(3), np.ones(3))
    assert list(s.k_switch) == [0, 50, 80, 100, 120, 200, 300]
    assert list(s.mode[:, 0]) == [0, 2, 0, 1, 0, 3, 0]
    assert s.fp[1, FP_OSC_AMP, 1, 0] == 0.05 and s.fp[2, FP_OSC_AMP, 1, 0] == 0.0
    res = ftc_mc.run_scenario(SCENARIO | {"model": {"airframe": "x8-gryte2018"}})
    seg = res.segments
    assert list(seg["truth_mode"]) == ["nominal", "left_elevon", "nominal", "engine",
                                       "nominal", "right_elevon", "nominal"]


BAD_SCENARIOS = [
    ({"time_s": 5.0, "fault": "float", "actuator": "engine", "float_angle": 0.0,
      "float_gain": -0.5}, "actuator"),
    ({"time_s": 5.0, "fault": "slow", "actuator": "engine"}, "rate_limit"),
    ({"time_s": 5.0, "fault": "slow", "actuator": "engine", "rate_limit": 0.1, "b1": 0.5},
     "b1"),
    ({"time_s": 5.0, "fault": "runaway", "actuator": "engine", "rate": 0.1,
      "duration_s": 30.0}, "duration_s"),
    ({"time_s": 5.0, "fault": "delayed", "actuator": "engine", "delay_s": 3.0}, "delay_s"),
    ({"time_s": 5.0, "fault": "oscillatory", "actuator": "engine", "amplitude": 0.1,
      "frequency_hz": 6.0, "phase_rad": 0.0}, "frequency_hz"),
    ({"time_s": 5.0, "fault": "wobble", "actuator": "engine"}, "fault"),
]


@pytest.mark.parametrize("entry,field", BAD_SCENARIOS)
def test_bad_scenario_faults_are_refused(tmp_path, entry, field):
    """A bad fault entry of a scenario: one line naming the field, exit 2, nothing written."""
    cfg = {"scenario": {"duration_s": 40.0, "schedule": [
        {"time_s": 0.0, "fault": "nominal"}, entry, {"time_s": 20.0, "fault": "nominal"}]}}
    path = tmp_path / "bad.yaml"
    path.write_text(json.dumps(cfg))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["scenario", str(path), "--out", str(out)])
    assert r.exit_code == 2, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and field in lines[0] and "schedule" in lines[0], r.output
    assert not out.exists()
