"""Sensor faults: schema, kernel vs twin, campaign rows, CLI and report."""

from __future__ import annotations

import math
from collections import namedtuple
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from click.testing import CliRunner

import naive
from ftc_mc.campaign.chunk import chunk_spec, run_chunk, trial_inputs
from ftc_mc.campaign.transitions import transition_of
from ftc_mc.cli import cli
from ftc_mc.config import Config
from ftc_mc.config.load import parse_config
from ftc_mc.conventions import NO_SENSOR_FAULT, OUTPUT_NAMES, SENSOR_FAULT_KINDS
from ftc_mc.core.longitudinal.plant import sensor_fault
from ftc_mc.errors import UserError
from ftc_mc.sim.inputs import draw_lanes

SMALL = {"timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}


def small(transitions, trials=6, **extra):
    return {"campaign": {"transitions": list(transitions), "trials": trials,
                         "chunk_size": 4, "signature": "paper"}, **SMALL, **extra}


# ------------------------------------------------------------------ schema
@pytest.mark.parametrize("data, where, what", [
    (small(["sensor_bias:qq"]), "campaign.transitions.0", "unknown output 'qq'"),
    (small(["elevon_lock", "sensor_stuck:pitch"]), "campaign.transitions.1", "outputs are"),
    (small(["sensor_flip:q"]), "campaign.transitions.0", "sensor_<kind>:<output>"),
    (small(["sensor_bias"]), "campaign.transitions.0", "sensor_<kind>:<output>"),
    (small(["sensor_bias:q"], sensor_draws={"bias": {"q": [-0.1, 0.1]}}),
     "sensor_draws.bias.q", "greater than or equal to 0"),
    (small(["sensor_bias:q"], sensor_draws={"bias": {"q": [0.0, float("nan")]}}),
     "sensor_draws.bias.q", "(got nan)"),
    (small(["sensor_bias:q"], sensor_draws={"bias": {"q": [0.2, 0.1]}}),
     "sensor_draws.bias", "low < high"),
    (small(["sensor_bias:q"], sensor_draws={"bias": {"pitch": [0.0, 0.1]}}),
     "sensor_draws.bias", "unknown output 'pitch'"),
    (small(["sensor_drift:q"], sensor_draws={"drift_per_s": float("inf")}),
     "sensor_draws.drift_per_s", "finite"),
    (small(["sensor_noise:q"], sensor_draws={"noise_factor": [-1.0, 2.0]}),
     "sensor_draws.noise_factor", "greater than or equal to 0"),
    (small(["sensor_noise:q"], noise={"measurement_scale": 0.0}),
     "campaign.transitions.0", "measurement_scale is 0"),
])
def test_bad_sensor_config_is_one_line(data, where, what):
    with pytest.raises(UserError) as e:
        parse_config(data)
    msg = str(e.value)
    assert "\n" not in msg and where in msg and what in msg, msg


def test_sensor_names_and_partial_ranges():
    cfg = parse_config(small(["sensor_bias:q", "sensor_stuck:n_z", "sensor_drift:alpha",
                              "sensor_noise:Va"], sensor_draws={"bias": {"q": [0.0, 0.5]}}))
    assert cfg.sensor_draws.size_range("bias", "q") == (0.0, 0.5)
    assert cfg.sensor_draws.size_range("bias", "n_z") == (0.02, 0.08)  # default kept
    assert cfg.sensor_draws.size_range("drift", "q") == pytest.approx((0.0, 0.05))
    tr = transition_of("sensor_stuck:n_z")
    assert (tr.output, tr.kind, tr.out_index) == ("n_z", "stuck", OUTPUT_NAMES.index("n_z"))


# ------------------------------------------------------------------ kernel vs twin
Inp = namedtuple("Inp", "sensor_out sensor_kind sensor_size sensor_k")
"""The trial inputs the kernel reads: one class for every kind, so that the
kernel is compiled once for all of them."""


@pytest.mark.parametrize("kind", SENSOR_FAULT_KINDS)
def test_sensor_fault_kernel_matches_twin(kind):
    """Each kind, before, at and after the onset, on every output, against
    ``naive.sensor_fault_ref`` (exact: the same few operations)."""
    rng = np.random.default_rng(7)
    L, n, dt, ks = 24, 12, 0.1, 5
    out = np.arange(L) % 12
    out[-2:] = NO_SENSOR_FAULT
    size = rng.uniform(0.0, 3.0, L) if kind == "noise" else rng.uniform(-1.0, 1.0, L)
    inp = Inp(out.astype(np.int64), np.full(L, SENSOR_FAULT_KINDS.index(kind), np.int64),
              size, np.full(L, ks, np.int64))
    zhold = rng.standard_normal(L)
    zh_ref = zhold.copy()
    changed = False
    for k in range(n):
        v = rng.standard_normal((12, L))
        z = rng.standard_normal((12, L)) + v
        want = np.empty_like(z)
        for l in range(L):
            want[:, l], zh_ref[l] = naive.sensor_fault_ref(
                z[:, l], v[:, l], zh_ref[l], k, dt, int(out[l]), inp.sensor_kind[l],
                size[l], ks)
        got = z.copy()
        sensor_fault(inp, k, dt, v, zhold, got)
        assert np.array_equal(got, want), (kind, k)
        assert np.array_equal(zhold, zh_ref)
        if k < ks:
            assert np.array_equal(got, z)  # healthy before the onset
        else:
            changed |= not np.array_equal(got, z)
            assert np.array_equal(got[:, -2:], z[:, -2:])  # lanes without a fault
    assert changed


# ------------------------------------------------------------------ campaign
@pytest.fixture(scope="module")
def sensor_run():
    cfg = Config.model_validate(small(["sensor_bias:q", "sensor_stuck:n_z",
                                       "sensor_drift:alpha", "elevon_lock"], trials=8))
    import ftc_mc
    return ftc_mc.run_campaign(cfg, jobs=1)


def test_sensor_draws_keep_the_streams():
    """A sensor transition's first draw is the size; the noise after it is the
    actuator transitions' (common random numbers), and the faults are in range."""
    spec = chunk_spec(Config.model_validate(small(["sensor_bias:q", "sensor_stuck:n_z",
                                                   "elevon_lock"])))
    ids = np.arange(6)
    inp_s, sizes = trial_inputs(spec, "sensor_bias:q", ids)
    inp_a, _ = trial_inputs(spec, "elevon_lock", ids)
    assert np.array_equal(inp_s.v, inp_a.v) and np.array_equal(inp_s.w, inp_a.w)
    lo, hi = spec.sensor_ranges["sensor_bias:q"]
    assert np.all((np.abs(sizes) >= lo) & (np.abs(sizes) <= hi))
    assert (sizes > 0).any() and (sizes < 0).any()
    assert np.all(inp_s.sensor_out == OUTPUT_NAMES.index("q"))
    assert np.all(inp_s.sensor_k == spec.setup.tim.k_fault)
    assert np.all(inp_s.b1 == 0) and np.all(inp_s.mode_post == 0)
    assert np.all(inp_a.sensor_out == NO_SENSOR_FAULT)
    first = draw_lanes(spec.setup, ids, spec.seed, (-1.0, 1.0)).fault
    assert np.allclose(np.abs(sizes), lo + np.abs(first) * (hi - lo))
    _, stuck = trial_inputs(spec, "sensor_stuck:n_z", ids)
    assert np.isnan(stuck).all()


def test_sensor_rows_of_a_small_campaign(sensor_run):
    s, t = sensor_run.summary, sensor_run.trials
    sens = s[s["transition"].str.startswith("sensor_")].set_index("transition")
    assert list(sens.index) == ["sensor_bias:q", "sensor_stuck:n_z", "sensor_drift:alpha"]
    for col in ("actuator_reset_rate", "wrong_mode_rate", "controller_switch_rate",
                "first_action_median_s", "envelope_exit_rate", "misattributed_rate"):
        assert col in sens
    # a stuck n_z (the residual r_nz) is misread on every trial; the counts match the trials
    assert sens.loc["sensor_stuck:n_z", "actuator_reset_rate"] == 1.0
    for name, r in sens.iterrows():
        g = t[(t["transition"] == name) & t["judged"].astype(bool)]
        assert r["actuator_reset"] == g["actuator_reset"].astype(bool).sum()
        assert r["wrong_mode"] == g["wrong_mode"].astype(bool).sum()
        assert r["controller_switch"] == g["controller_switch"].astype(bool).sum()
        acted = g["first_action_s"].dropna()
        assert (acted > 0).all()
        assert math.isnan(r["first_action_median_s"]) == acted.empty
        assert pd.isna(r["paper_trials"]) and pd.isna(r["inappropriate_rate"])
    act = s[s["transition"] == "elevon_lock"].iloc[0]
    assert pd.isna(act["actuator_reset_rate"]) and act["correct_rate"] > 0.5


def test_actuator_rows_unchanged_by_sensor_rows(sensor_run):
    """An actuator row is the same with and without sensor rows in the run."""
    import ftc_mc
    alone = ftc_mc.run_campaign(Config.model_validate(small(["elevon_lock"], trials=8)),
                                jobs=1)
    from ftc_mc.campaign.summary import actuator_rows
    mixed = actuator_rows(sensor_run.summary).reset_index(drop=True)
    pd.testing.assert_frame_equal(mixed, alone.summary[mixed.columns])
    t = sensor_run.trials
    t = t[t["transition"] == "elevon_lock"].reset_index(drop=True)
    for c in ("correct", "inappropriate", "first_reset_s", "b1_hat_end"):
        assert np.array_equal(t[c].to_numpy(dtype=float),
                              alone.trials[c].to_numpy(dtype=float), equal_nan=True), c


def test_run_chunk_of_sensor_transition_sees_the_fault():
    """A large q bias is misread (resets follow the fault); with a zero-size range
    the same trials are quiet: the fault, not the noise, causes the resets."""
    big = chunk_spec(Config.model_validate(small(
        ["sensor_bias:q"], sensor_draws={"bias": {"q": [0.2, 0.3]}})))
    zero = chunk_spec(Config.model_validate(small(
        ["sensor_bias:q"], sensor_draws={"bias": {"q": [0.0, 1e-12]}})))
    ids = np.arange(4)
    tb = run_chunk(big, "sensor_bias:q", ids)["trials"]
    tz = run_chunk(zero, "sensor_bias:q", ids)["trials"]
    assert tb["actuator_reset"].all() and not tz["actuator_reset"].any()


# ------------------------------------------------------------------ CLI and report
def test_cli_run_prints_misattribution_table_and_report_has_it(tmp_path):
    cfg = tmp_path / "sens.yaml"
    cfg.write_text(yaml.safe_dump(small(["sensor_bias:q", "sensor_drift:n_x"], trials=4)))
    out = tmp_path / "run"
    res = CliRunner().invoke(cli, ["run", str(cfg), "--jobs", "1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "Sensor faults" in res.output and "sensor_bias:q" in res.output
    assert "actuator reset %" in res.output and "inappr." not in res.output
    s = pd.read_parquet(out / "summary.parquet")
    assert {"actuator_reset_rate", "wrong_mode_rate", "controller_switch_rate"} <= set(s)
    assert "sensor_drift:n_x" in (out / "summary.md").read_text()
    rep = tmp_path / "report.md"
    res = CliRunner().invoke(cli, ["report", str(out), "-o", str(rep)])
    assert res.exit_code == 0, res.output
    text = rep.read_text()
    assert "Sensor faults: what the actuator FDI does with them" in text
    line = next(x for x in text.splitlines() if "`sensor_bias:q`" in x)
    assert "/4 (" in line  # k/n (rate, Wilson CI)


@pytest.mark.parametrize("bad", [["sensor_bias:nope"], ["sensor_stuck:pitch"]])
def test_cli_bad_sensor_name_exit_2_nothing_written(tmp_path, bad):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump(small(bad)))
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out)])
    assert res.exit_code == 2, res.output
    assert len(res.output.strip().splitlines()) == 1 and "campaign.transitions.0" in res.output
    assert not out.exists()


# ------------------------------------------------------------------ scenarios
def _scenario_with(sensor_fault, duration_s=20.0):
    from ftc_mc.config import ScenarioConfig

    return ScenarioConfig.model_validate({"scenario": {
        "duration_s": duration_s, "schedule": [{"time_s": 0.0, "fault": "nominal"}],
        "sensor_fault": sensor_fault}})


def test_scenario_sensor_fault_acts_on_its_output_from_its_onset():
    # the same flight without and with a pitch-gyro bias from 10 s: identical
    # before the onset, then the filter sees the bias (its q residual jumps)
    from ftc_mc.scenario import run_scenario

    calm = run_scenario(_scenario_with(None)).timeseries
    res = run_scenario(_scenario_with({"time_s": 10.0, "kind": "bias", "output": "q",
                                       "size": 0.05}))
    ts = res.timeseries
    before = ts.time_s <= 10.0 + 1e-9
    pd.testing.assert_frame_equal(ts[before], calm[before], check_exact=True)
    after = np.isclose(ts.time_s, 10.1)
    assert ts.r_q[after].iloc[0] > 100 * calm.r_q[after].iloc[0]
    ev = res.events
    assert ((ev.kind == "sensor_fault") & (ev.detail == "q bias 0.05")
            & (ev.time_s == 10.0)).sum() == 1


@pytest.mark.parametrize("fault, message", [
    ({"time_s": 5.0, "kind": "bias", "output": "pitch", "size": 0.1}, "output"),
    ({"time_s": 5.0, "kind": "bias", "output": "q"}, "needs a size"),
    ({"time_s": 5.0, "kind": "stuck", "output": "q", "size": 1.0}, "takes no size"),
    ({"time_s": 5.0, "kind": "noise", "output": "q", "size": -2.0}, "must be > 0"),
    ({"time_s": 5.0, "kind": "drift", "output": "q", "size": float("nan")}, "size"),
    ({"time_s": 5.05, "kind": "bias", "output": "q", "size": 0.1}, "multiple"),
    ({"time_s": 30.0, "kind": "bias", "output": "q", "size": 0.1}, "before"),
])
def test_scenario_sensor_fault_errors_name_the_field(fault, message, tmp_path):
    from ftc_mc.cli import cli

    path = tmp_path / "sc.yaml"
    path.write_text(yaml.safe_dump({"scenario": {
        "duration_s": 20.0, "schedule": [{"time_s": 0.0, "fault": "nominal"}],
        "sensor_fault": fault}}))
    res = CliRunner().invoke(cli, ["scenario", str(path), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    line = res.output.strip().splitlines()
    assert len(line) == 1 and "scenario.sensor_fault" in line[0] and message in line[0], \
        res.output
    assert not (tmp_path / "o").exists()
