"""Nonlinear truth-plant kernels (core/longitudinal/nonlinear.py) and Dryden gusts (core/shared/dryden.py).

Tolerances:
- Numba derivatives/outputs vs the textbook twin of tests/naive.py (with and
  without wind): 1e-12 of each quantity's scale (rounding only); one RK4
  period: 1e-12 relative.
- Trim hold: 60 s at trim commands, no wind: velocities (u, w, q) stay within
  1e-9 of trim (the trim residual is ~1e-15 and the airframe modes are stable).
- Doublet vs linear discrete model: 2 % of the peak pitch-rate response.
- RK4 order 3.5 .. 4.5 between n_sub 5/10 and 10/20 (reference n_sub = 40);
  n_sub = 10 within 2e-5 of the peak velocity response of the reference
  (measured 7e-6 relative, 6e-7 absolute: the requested 1e-8 absolute is NOT
  met at n_sub = 10; it needs n_sub ~ 30, see test_rk4_convergence).
- Dryden PSDs: 15 % on frequency-band averages well below Nyquist; variances 5 %
  (1e6 samples, fixed seed; the statistical spread of the u variance is ~1.6 %).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate
import scipy.signal

import naive
from ftc_mc.core.shared.dryden import gust_record, gust_step
from ftc_mc.core.longitudinal.nonlinear import (derivatives_nb, make_work, outputs_nb, propagate)
from ftc_mc.model import dynamics
from ftc_mc.model.linear import build_plant
from ftc_mc.model.turbulence import dryden_model, psd_q, psd_u, psd_w

DT = 0.1
ZERO_WIND = np.zeros(3)


@pytest.fixture(scope="module")
def plant():
    return build_plant()


def _near_trim(rng, tp, n):
    scale = np.array([1.0, 1.0, 0.2, 5.0, 5.0, 0.05, 0.1, 0.05, 0.05])
    for _ in range(n):
        x = tp.x0 + scale * rng.standard_normal(9)
        x[6] = min(max(x[6], 0.0), 1.0)
        cmd = tp.u0 + np.array([0.1, 0.05, 0.05]) * rng.standard_normal(3)
        yield x, cmd


def test_derivatives_and_outputs_match_the_twin(plant):
    """The kernels (the one source of the X8 equations) against the textbook
    twin of tests/naive.py (wind-axes forces rotated into body axes), with and
    without wind: 1e-12 of the magnitude of each quantity."""
    tp = plant.trim
    rng = np.random.default_rng(0)
    dx_nb = np.empty(9)
    y_nb = np.empty(12)
    # scale of each derivative and output (m/s^2, rad/s^2, m/s, rad/s, 1/s, g, rad)
    d_scale = np.array([10.0, 10.0, 10.0, 20.0, 20.0, 1.0, 1.0, 1.0, 1.0])
    y_scale = np.array([20.0, 20.0, 1.0, 10.0, 10.0, 1.0, 1.0, 1.0, 1.0, 1.0, 20.0, 20.0])
    for i, (x, cmd) in enumerate(_near_trim(rng, tp, 200)):
        wind = ZERO_WIND if i % 2 == 0 else rng.normal(0.0, [2.0, 2.0, 0.1])
        derivatives_nb(x, cmd, tp.params, wind, dx_nb)
        dx_ref = naive.x8_derivatives_ref(x, cmd, tp.params, wind)
        np.testing.assert_allclose(dx_nb, dx_ref, rtol=0, atol=1e-12 * d_scale.max())
        assert np.all(np.abs(dx_nb - dx_ref) <= 1e-12 * d_scale)
        outputs_nb(x, tp.params, wind, y_nb)
        y_ref = naive.x8_outputs_ref(x, tp.params, wind)
        assert np.all(np.abs(y_nb - y_ref) <= 1e-12 * y_scale), (y_nb - y_ref)
    # model.dynamics evaluates the same kernels in still air, to the bit
    x, cmd = next(_near_trim(rng, tp, 1))
    dx_dyn = np.empty(9)
    dynamics.derivatives(x, cmd, tp.params, dx_dyn)
    derivatives_nb(x, cmd, tp.params, ZERO_WIND, dx_nb)
    assert np.array_equal(dx_dyn, dx_nb)


def test_propagate_matches_the_rk4_twin(plant):
    """One control period of 10 RK4 sub-steps in a gust, against the NumPy RK4
    on the twin's equations: 1e-12 relative on the state."""
    tp = plant.trim
    rng = np.random.default_rng(1)
    work = make_work()
    for x, cmd in _near_trim(rng, tp, 20):
        wind = rng.normal(0.0, [2.0, 2.0, 0.1])
        x_nb = x.copy()
        propagate(x_nb, cmd, tp.params, wind, DT, 10, work)
        x_ref = naive.rk4_ref(x, cmd, tp.params, wind, DT, 10)
        err = np.linalg.norm(x_nb - x_ref) / np.linalg.norm(x_ref)
        assert err < 1e-12, err
        assert np.linalg.norm(x_nb - x) > 1e-3  # the state did move


def test_wind_is_air_relative(plant):
    """A gust equal to the aircraft velocity and pitch rate leaves no aero force."""
    tp = plant.trim
    x = tp.x0.copy()
    x[2] = 0.1
    wind = np.array([x[0] - 20.0, x[1] - 0.5, 0.1])  # air-relative (20, 0.5, 0)
    xa = x.copy()
    xa[:3] = [20.0, 0.5, 0.0]
    y = np.empty(12)
    ya = np.empty(12)
    outputs_nb(x, tp.params, wind, y)
    dynamics.outputs(xa, tp.params, ya)
    np.testing.assert_allclose(y[6:], ya[6:], rtol=0, atol=1e-12)
    # kinematics stay inertial: dtheta/dt is the inertial q
    dx = np.empty(9)
    derivatives_nb(x, tp.u0, tp.params, wind, dx)
    assert dx[5] == x[2]


def test_trim_is_held(plant):
    tp = plant.trim
    x = tp.x0.copy()
    work = make_work()
    dev = 0.0
    for _ in range(600):  # 60 s
        propagate(x, tp.u0, tp.params, ZERO_WIND, DT, 10, work)
        dev = max(dev, np.max(np.abs(x[:3] - tp.x0[:3])))
    assert dev < 1e-9


def _doublet(k, amp=0.01):
    """Symmetric elevon doublet: +amp for 1 s, -amp for 1 s, then 0 [rad]."""
    return amp if 0 <= k < 10 else (-amp if 10 <= k < 20 else 0.0)


def _nonlinear_doublet(plant, n_sub, n_steps=100):
    tp = plant.trim
    x = tp.x0.copy()
    work = make_work()
    traj = np.empty((n_steps + 1, 9))
    traj[0] = x
    cmd = np.empty(3)
    for k in range(n_steps):
        d = _doublet(k)
        cmd[:] = tp.u0 + np.array([0.0, d, d])
        propagate(x, cmd, tp.params, ZERO_WIND, DT, n_sub, work)
        traj[k + 1] = x
    return traj - tp.x0


def test_doublet_matches_linear_model(plant):
    n = 100
    dev_nl = _nonlinear_doublet(plant, 10, n)
    xl = np.zeros(9)
    dev_lin = np.empty((n + 1, 9))
    dev_lin[0] = xl
    for k in range(n):
        d = _doublet(k)
        xl = plant.A @ xl + plant.B @ np.array([0.0, d, d])
        dev_lin[k + 1] = xl
    q_peak = np.max(np.abs(dev_lin[:, 2]))
    assert q_peak > 1e-3  # a real response
    err = np.max(np.abs(dev_nl[:, 2] - dev_lin[:, 2]))
    assert err < 0.02 * q_peak, (err, q_peak)


def test_rk4_convergence(plant):
    ref = _nonlinear_doublet(plant, 40)
    subs = [1, 2, 5, 10, 20]
    err = {n: np.max(np.abs(_nonlinear_doublet(plant, n)[:, :3] - ref[:, :3]))
           for n in subs}
    order = {(a, b): math.log(err[a] / err[b]) / math.log(b / a)
             for a, b in zip(subs[:-1], subs[1:])}
    # errors shrink monotonically
    assert all(err[a] > err[b] for a, b in zip(subs[:-1], subs[1:])), err
    for pair in [(5, 10), (10, 20)]:
        assert 3.5 < order[pair] < 4.5, (order, err)
    # n_sub = 10: 6e-7 absolute (7e-6 of the peak w/q response) on this 0.01 rad
    # doublet; the brief's 1e-8 absolute would need n_sub ~ 30 (the elevon lag,
    # tau = 0.05 s, h/tau = 0.2, dominates the RK4 truncation error).
    peak = np.max(np.abs(ref[:, :3]))
    assert err[10] < 2e-5 * peak, (err, peak)
    err30 = np.max(np.abs(_nonlinear_doublet(plant, 30)[:, :3] - ref[:, :3]))
    assert err30 < 1e-8, err30


def test_zero_throttle_glide(plant):
    tp = plant.trim
    x = tp.x0.copy()
    work = make_work()
    cmd = np.array([0.0, tp.u0[1], tp.u0[2]])
    y = np.empty(12)
    sink_ref = tp.V0 * math.sin(-tp.gamma0)  # reference point's descent rate
    Va = []
    for _ in range(300):  # 30 s
        propagate(x, cmd, tp.params, ZERO_WIND, DT, 10, work)
        outputs_nb(x, tp.params, ZERO_WIND, y)
        Va.append(y[11])
    T = 30.0
    z_abs = x[4] + sink_ref * T  # absolute down position change [m]
    assert z_abs > 0.5 * sink_ref * T  # the aircraft descends (altitude drops)
    assert x[4] > 0  # and falls below the -3 deg glide path without thrust
    Va = np.array(Va)
    assert np.all(np.isfinite(x))
    assert 10.0 < Va.min() and Va.max() < 30.0, (Va.min(), Va.max())


@pytest.fixture(scope="module")
def gust_record_moderate():
    m = dryden_model("moderate", V=20.0, altitude_m=100.0, dt=DT)
    rng = np.random.default_rng(12345)
    n = 1_000_000
    state = m.P0_chol @ rng.standard_normal(4)
    etas = rng.standard_normal((n, 4))
    rec = np.empty((n, 3))
    gust_record(state, etas, m.Ad, m.Bd, m.Cd, rec)
    return m, rec


def test_gust_step_matches_matrices():
    m = dryden_model("severe", dt=0.05)
    rng = np.random.default_rng(3)
    s = rng.standard_normal(4)
    eta = rng.standard_normal(4)
    out = np.empty(3)
    s0 = s.copy()
    gust_step(s, eta, m.Ad, m.Bd, m.Cd, out)
    np.testing.assert_allclose(out, m.Cd @ s0, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(s, m.Ad @ s0 + m.Bd @ eta, rtol=1e-14, atol=1e-15)
    none = dryden_model("none")
    assert not none.Bd.any() and not none.P0.any()


def test_dryden_scales():
    m = dryden_model("moderate", V=20.0, altitude_m=100.0, dt=DT)
    h = 100.0 / 0.3048
    k = 0.177 + 0.000823 * h
    assert m.L_w == pytest.approx(100.0)
    assert m.L_u == pytest.approx(h / k ** 1.2 * 0.3048)
    assert m.sigma_w == pytest.approx(0.1 * 30 * 1852 / 3600)
    assert m.sigma_u == pytest.approx(m.sigma_w / k ** 0.4)
    # the stationary variances of the shaping filters are the MIL-F-8785C sigmas,
    # and sigma_q equals the integral of the analytic pitch-gust PSD
    var = np.diag(m.Cc @ m.P0 @ m.Cc.T)
    np.testing.assert_allclose(var[:2], [m.sigma_u ** 2, m.sigma_w ** 2], rtol=1e-9)
    q_int = scipy.integrate.quad(lambda w: psd_q(w, m), 0, np.inf, limit=500)[0]
    assert var[2] == pytest.approx(q_int, rel=1e-6)
    for lvl, ratio in (("light", 0.5), ("severe", 1.5)):
        assert dryden_model(lvl).sigma_w == pytest.approx(ratio * m.sigma_w)
    with pytest.raises(ValueError):
        dryden_model("extreme")
    with pytest.raises(ValueError):
        dryden_model("light", altitude_m=500.0)


def _band_ratios(f_hz, P_hz, psd, m, lo, hi, n_bands):
    """Ratio of estimated to analytic PSD averaged over log-spaced bands [rad/s]."""
    omega = 2 * math.pi * f_hz
    est = P_hz / (2 * math.pi)  # one-sided per Hz -> one-sided per rad/s
    ana = psd(omega, m)
    edges = np.geomspace(lo, hi, n_bands + 1)
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (omega >= a) & (omega < b)
        assert sel.sum() >= 2
        out.append(est[sel].mean() / ana[sel].mean())
    return np.array(out)


def test_dryden_spectra(gust_record_moderate):
    m, rec = gust_record_moderate
    # variances (sampling is exact: the sampled process has the continuous variance)
    np.testing.assert_allclose(rec.var(axis=0),
                               [m.sigma_u ** 2, m.sigma_w ** 2, m.sigma_q ** 2],
                               rtol=0.05)
    f, P = scipy.signal.welch(rec, fs=1.0 / DT, nperseg=8192, axis=0)
    # u and w: the analytic continuous one-sided angular spectra; in 0.05 .. 3
    # rad/s (Nyquist 31.4 rad/s) the aliasing of the sampled process is < 1 %.
    r_u = _band_ratios(f, P[:, 0], psd_u, m, 0.05, 3.0, 6)
    r_w = _band_ratios(f, P[:, 1], psd_w, m, 0.05, 3.0, 6)
    # q: Phi_q rises as omega^2 at low frequency and stays flat-ish up to
    # 1/T_q = 7.5 rad/s, so aliasing matters even far below Nyquist (about x2 at
    # 0.07 rad/s, 4 % at 3 rad/s): compare with the folded spectrum of the
    # sampled process, sum_k Phi_q(|omega + k omega_s|).
    ws = 2 * math.pi / DT

    def psd_q_folded(omega, model):
        return sum(psd_q(np.abs(omega + k * ws), model) for k in range(-200, 201))

    r_q = _band_ratios(f, P[:, 2], psd_q_folded, m, 0.05, 3.0, 6)
    for r in (r_u, r_w, r_q):
        assert np.all(np.abs(r - 1) < 0.15), (r_u, r_w, r_q)
    # unfolded vs folded q spectrum at 3 rad/s: the aliasing is real
    assert psd_q_folded(np.array([3.0]), m)[0] > 1.02 * psd_q(3.0, m)
