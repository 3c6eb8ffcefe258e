"""The truth plant of the trials: nonlinear X8 and Dryden gusts in
core/trial.advance, the linear plant's gust matrices, streams and the CLI.

Tolerances:
- Trial truth vs a plain-Python twin (model.dynamics + NumPy RK4, same commands
  from the record): 1e-9 absolute on the state deviations (rounding only).
- Gusts vs a NumPy recursion of the same draws: 1e-12.
- Linear vs nonlinear plant in gusts scaled to 1 % of light turbulence: the
  difference stays below 2 % of the response's standard deviation, and shrinks
  about tenfold from 10 % to 1 % amplitude (the linear gust matrices are the
  first-order part of the nonlinear plant; measured 0.93 % and 9.2 % for q).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from ftc_mc.campaign.chunk import chunk_spec, trial_inputs
from ftc_mc.campaign.runner import run_campaign
from ftc_mc.cli import cli
from ftc_mc.config import Config, parse_config
from ftc_mc.sim.lanes import run_trials
from ftc_mc.errors import UserError
from ftc_mc.model import dynamics
from ftc_mc.model.turbulence import dryden_model
from ftc_mc.sim.inputs import draw_lane, flight_inputs, trial_stream
from ftc_mc.sim.lanes import new_record
from ftc_mc.sim.setup import build_setup
from ftc_mc.model.wind import wind_matrices

SHORT = {"fault_time_s": 2.0, "window_s": 2.0, "duration_s": 6.0}


def _cfg(kind="nonlinear", turbulence="none", **extra):
    data = {"campaign": {"transitions": ["elevon_lock"], "trials": 3,
                         "signature": "swapped"},
            "controller": {"kind": "nominal"}, "timing": SHORT,
            "plant": {"kind": kind, "turbulence": turbulence}}
    data.update(extra)
    return Config.model_validate(data)


def _run(setup, inp, L, det=None):
    rec = new_record(setup, L, 256, history=True)
    run_trials(setup.scheme("swapped", det), setup.flight, inp, rec)
    return rec


def _rk4_twin(x, cmd, p, dt, n_sub):
    """Classical RK4 on the plain-Python equations of model/dynamics.py."""
    def f(s):
        d = np.empty(9)
        dynamics.derivatives(s, cmd, p, d)
        return d

    h = dt / n_sub
    for _ in range(n_sub):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


@pytest.mark.parametrize("transition", ["elevon_lock", "engine_loss"])
def test_nonlinear_truth_matches_plain_python_twin(transition):
    spec = dataclasses.replace(chunk_spec(_cfg()), seed=7)
    setup = spec.setup
    ids = np.arange(2)
    inp, _ = trial_inputs(spec, transition, ids)
    rec = _run(setup, inp, 2)
    pl, u0 = setup.truth, setup.fm.u0
    kf = setup.tim.k_fault
    assert pl.kind == 1 and pl.turb == 0 and not rec.hist_wind.any()
    for l in range(2):
        x = pl.x0.copy()
        for k in range(setup.tim.n_steps):
            ev = 1 if k >= kf else 0
            b0, b1 = inp.b0[ev, :, l], inp.b1[ev, :, l]
            e = b0 + (1.0 - b1) * rec.hist_u[k, :, l] - b1 * u0  # eq. (2)
            x = _rk4_twin(x, u0 + e, pl.p, pl.dt, pl.n_sub) + inp.w[k, :, l]
            np.testing.assert_allclose(rec.hist_x[k, :, l], x - pl.x0, rtol=0, atol=1e-9)
    # the fault acted: the plant left trim by more than the noise alone would move it
    assert np.abs(rec.hist_x[:, 7, :]).max() > 0.01


def test_gusts_follow_the_dryden_recursion():
    spec = dataclasses.replace(chunk_spec(_cfg(turbulence="moderate")), seed=3)
    setup = spec.setup
    inp, _ = trial_inputs(spec, "elevon_lock", np.arange(2))
    rec = _run(setup, inp, 2)
    g = setup.gust
    for l in range(2):
        s = inp.g0[:, l].copy()
        for k in range(setup.tim.n_steps):
            np.testing.assert_allclose(rec.hist_wind[k, :, l], g.Cd @ s, rtol=0, atol=1e-12)
            s = g.Ad @ s + g.Bd @ inp.eta[k, :, l]
    # moderate turbulence at 100 m: sigma_w = 1.54 m/s (MIL-F-8785C, model/turbulence.py)
    assert 0.2 < rec.hist_wind[:, 1, :].std() < 5.0


def test_gust_draws_come_after_the_still_air_draws():
    chol = dryden_model("moderate").P0_chol
    q, r = np.full(9, 0.1), np.full(12, 0.2)
    still = draw_lane(trial_stream(5, 11), 40, q, r, fault_range=(0.0, 1.0))
    gusty = draw_lane(trial_stream(5, 11), 40, q, r, chol, fault_range=(0.0, 1.0))
    assert still[3] is None
    assert still[0] == gusty[0]
    assert np.array_equal(still[1], gusty[1]) and np.array_equal(still[2], gusty[2])
    eta, g0 = gusty[3]
    assert eta.shape == (40, 4) and g0.shape == (4,)
    # g0 is drawn from the stationary covariance: check over many draws
    rng = np.random.default_rng(0)
    samples = np.array([chol @ rng.standard_normal(4) for _ in range(20000)])
    P0 = dryden_model("moderate").P0
    np.testing.assert_allclose(np.cov(samples.T), P0, atol=0.05 * np.abs(P0).max())


def test_linear_gust_matrices_follow_the_geometry():
    """At trim, alpha = atan2(w, u) and Va = |(u, w)| of the air-relative velocity,
    so d alpha / d w_g = -cos(alpha) / Va and d Va / d u_g = -cos(alpha); position
    and attitude kinematics use the inertial velocities (no gust term)."""
    setup = build_setup(_cfg(kind="linear"))
    Bw, Dw, Ewc = wind_matrices(setup.plant)
    tp = setup.plant.trim
    Va, al = tp.V0, tp.alpha
    assert Dw[8, 1] == pytest.approx(-math.cos(al) / Va, rel=1e-7)
    assert Dw[8, 0] == pytest.approx(math.sin(al) / Va, rel=1e-6)
    assert Dw[11, 0] == pytest.approx(-math.cos(al), rel=1e-7)
    # q_g enters like -q: same column as the q column of Ac, with the sign flipped,
    # except the kinematic rows (u and w Coriolis terms and theta' = q)
    Ac = setup.plant.Ac
    np.testing.assert_allclose(Ewc[2, 2], -Ac[2, 2], rtol=1e-6)
    assert Bw.shape == (9, 3) and np.abs(Bw).max() > 0


@pytest.mark.parametrize("eps", [0.1, 0.01])
def test_linear_and_nonlinear_agree_for_small_gusts(eps):
    recs = {}
    for kind in ("linear", "nonlinear"):
        cfg = _cfg(kind=kind, turbulence="light",
                   noise={"process_scale": 0.0, "measurement_scale": 0.0},
                   timing={"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 10.0})
        s = build_setup(cfg)
        s = dataclasses.replace(s, truth=s.truth._replace(Bd=s.truth.Bd * eps))
        inp = flight_inputs(s, np.arange(8), 2026)
        inp.g0[:] *= eps
        det = s.detection("swapped", math.inf, math.inf)
        recs[kind] = _run(s, inp, 8, det)
    a, b = recs["linear"].hist_x, recs["nonlinear"].hist_x
    rel = np.abs(a - b).max(axis=(0, 2)) / a.std(axis=(0, 2))
    assert rel.max() < 2.0 * eps
    assert rel.max() > 0.1 * eps  # the plants do differ (nonlinearity is real)


def test_bad_plant_choices_are_refused_by_the_schema():
    # the schema is the only validator; sim/truth.py trusts what it passes
    for plant, field in (({"kind": "quadratic"}, "plant.kind"),
                         ({"turbulence": "stormy"}, "plant.turbulence"),
                         ({"kind": "nonlinear", "substeps": 0}, "plant.substeps")):
        with pytest.raises(UserError, match=field):
            parse_config({"plant": plant})


def test_nonlinear_turbulent_campaign_is_reproducible_across_chunks_and_jobs():
    cfg = _cfg(turbulence="moderate",
               campaign={"transitions": ["elevon_lock", "engine_loss"], "trials": 6,
                         "signature": "both", "chunk_size": 4})
    a = run_campaign(cfg, jobs=1, progress=False).trials
    cfg2 = cfg.model_copy(update={"campaign": cfg.campaign.model_copy(
        update={"chunk_size": 2})})
    b = run_campaign(cfg2, jobs=2, progress=False).trials
    assert a.equals(b)
    c = run_campaign(_cfg(turbulence="none", campaign=cfg.campaign.model_dump()),
                     jobs=1, progress=False).trials
    assert not a["b0_hat_end"].equals(c["b0_hat_end"])  # the gusts did act


def _write(tmp_path, name, data):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


def test_cli_run_and_scenario_take_plant_and_turbulence(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = _write(tmp_path, "tiny.yaml", {
        "campaign": {"transitions": ["elevon_lock"], "trials": 2, "signature": "swapped"},
        "controller": {"kind": "nominal"}, "timing": SHORT})
    runner = CliRunner()
    res = runner.invoke(cli, ["run", str(cfg), "--plant", "nonlinear", "--turbulence",
                              "light", "--quiet", "--jobs", "1"])
    assert res.exit_code == 0, res.output
    out = tmp_path / "results" / "tiny-nonlinear-light"
    assert (out / "trials.parquet").exists()
    from ftc_mc.io.results import read_metadata
    meta = read_metadata(out / "trials.parquet")
    assert meta["config"]["plant"]["kind"] == "nonlinear"
    assert meta["config"]["plant"]["turbulence"] == "light"

    sc = _write(tmp_path, "sc.yaml", {"scenario": {
        "duration_s": 4.0, "schedule": [{"time_s": 0.0, "fault": "nominal"},
                                        {"time_s": 2.0, "fault": "lock",
                                         "actuator": "left_elevon", "position": "trim"}]}})
    res = runner.invoke(cli, ["scenario", str(sc), "--plant", "nonlinear",
                              "--turbulence", "moderate", "--out", str(tmp_path / "s")])
    assert res.exit_code == 0, res.output
    import pandas as pd
    ts = pd.read_parquet(tmp_path / "s" / "timeseries.parquet")
    assert ts["gust_w_mps"].abs().max() > 0.1
    res = runner.invoke(cli, ["scenario", str(sc), "--out", str(tmp_path / "s0")])
    assert res.exit_code == 0, res.output
    assert (pd.read_parquet(tmp_path / "s0" / "timeseries.parquet")["gust_w_mps"] == 0).all()


def test_cli_refuses_a_bad_plant_without_writing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = _write(tmp_path, "bad.yaml", {"plant": {"kind": "quadratic"}})
    res = CliRunner().invoke(cli, ["run", str(cfg)])
    assert res.exit_code == 2
    assert "plant.kind" in res.output and "Traceback" not in res.output
    res = CliRunner().invoke(cli, ["run", str(_write(tmp_path, "ok.yaml", {})),
                                   "--turbulence", "stormy"])
    assert res.exit_code == 2 and "stormy" in res.output
    cfg = _write(tmp_path, "alt.yaml", {"plant": {"altitude_m": 1000.0}})
    res = CliRunner().invoke(cli, ["run", str(cfg)])
    assert res.exit_code == 2 and "plant.altitude_m" in res.output
    assert not (tmp_path / "results").exists()
