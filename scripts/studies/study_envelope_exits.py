"""Why the paper's nominal loop c0 leaves the validity envelope in moderate turbulence.

Flies the nonlinear X8 (the package's equations, RK4, 10 sub-steps per 0.1 s)
fault-free for 50 s in MIL-F-8785C moderate Dryden turbulence at 100 m, under
several nominal control laws, on **the same gust, process- and measurement-noise
draws as fault-free flight i of ``ftc-mc endurance --seed SEED``** (common random
numbers: ``ftc_mc.sim.inputs.draw_lanes``), without the filter, so the control
law is separated from the estimator.  A flight leaves the envelope when its
air-relative airspeed leaves 12-30 m/s or its angle of attack -8..12 deg (the
validity section of ``configs/robust_moderate.yaml``; the check the kernels make,
on the state after each step with the next step's gust); it stops there.

Candidates (``--laws``, comma-separated keys of :data:`LAWS`):

* ``c0``: the paper's discounted LQR (Q = diag on x: tan^2 gamma0, z: 1;
  R = 0.1 I; alpha 0.999) on the true state, as the kernels feed it: inertial
  (ground-relative) body velocities u, w and the along-track position x measured
  from a point moving at the trim speed;
* ``c0_meas``: c0 on the noisy measurements of u, w, q, x, z, theta (a stand-in
  for the estimate, without the filter);
* ``c0_unsat``: c0 with the command limits lifted (throttle and elevons
  unbounded);
* ``c0_linear``: c0 on the linear plant of eq. (1) with the gust input matrices
  (the linear design met by linear dynamics: the nonlinearity's share);
* ``c0_air``: c0's gain fed air-relative u - u_g, w - w_g (what an airspeed
  sensor gives) instead of inertial u, w;
* ``c0_nox``: the paper's weights without the along-track position (Q on z only),
  inertial feedback;
* ``bryson``: an LQR re-weighted for gust rejection by Bryson's rule on the
  air-relative airspeed deviation (2 m/s), the height (3 m), pitch (10 deg) and
  pitch rate (30 deg/s), commands throttle 0.3 and elevon 0.1 rad, no
  along-track position, fed air-relative u, w;
* ``bryson_unsat``: the same with the command limits lifted;
* ``bryson_ground``: Bryson's weights but fed inertial u, w (airspeed weight on
  the ground-relative speed);
* ``bryson_va1``, ``bryson_va4``, ``bryson_z1``: Bryson's rule with 1 or 4 m/s
  on the airspeed, or 1 m on the height;
* ``c0_va10``: c0 judged against an airspeed floor of 10 m/s instead of 12;
* ``pyfly_pid``: PyFly's ``PIDController`` (airspeed PI by throttle, pitch PID)
  on this X8, at PyFly's 100 Hz; ``pid_height``: the same with a height loop
  setting the pitch reference;
* ``tecs``: a TECS-like energy law (:data:`TECS_GAINS`).

Prints, per law, the exits per 1,000 flights with 95 % Wilson intervals, by
airspeed and by angle of attack, the share of steps with the throttle at a
limit, the RMS height error and the lowest airspeed of a flight (1 % and 10 %
quantiles), and writes ``--out``/exits.npz (with c0's time histories when at
most 2,000 flights are flown).  ``--pyfly IDS`` also flies those flights on
PyFly's own X8 with its own PID; ``--figures-from`` draws the figures of
docs/findings/turbulence-envelope.md into docs/figures/ from saved runs.

    .venv/bin/python scripts/studies/study_envelope_exits.py --flights 2000 \
        --seed 777 [--laws c0,c0_unsat,...|none] [--turbulence severe] \
        [--pyfly 20,37] [--out DIR]
    .venv/bin/python scripts/studies/study_envelope_exits.py \
        --figures-from DIR/exits.npz
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import ftc_mc  # noqa: F401 -- the package first (its numba settings)
import numpy as np
import scipy.linalg

from ftc_mc.config.load import load_config, with_overrides
from ftc_mc.conventions import LONGITUDINAL, OUT_ALPHA, OUT_VA
from ftc_mc.core.longitudinal import nonlinear as nl
from ftc_mc.design.lqr import discounted_lqr, paper_q_lqr
from ftc_mc.model.wind import plant_wind_matrices
from ftc_mc.sim.inputs import FLIGHT_FAULT_RANGE, draw_lanes
from ftc_mc.sim.setup import build_setup

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "robust_moderate.yaml"
IU, IW, IQ, IX, IZ, ITH, ITHR = (LONGITUDINAL.state(n) for n in
                                 ("u", "w", "q", "x", "z", "theta", "thrust"))


# ------------------------------------------------------------------ the plant, lanes last
def derivatives(x, cmd, p, wind):
    """``ftc_mc.core.longitudinal.nonlinear.derivatives_nb`` on lanes (last axis)."""
    u = x[0] - wind[0]
    w = x[1] - wind[1]
    q = x[2] - wind[2]
    Va = np.sqrt(u * u + w * w)
    alpha = np.arctan2(w, u)
    de = 0.5 * (x[7] + x[8])
    qbar_S = 0.5 * p[nl.P_RHO] * Va * Va * p[nl.P_S]
    qhat = p[nl.P_C] * q / (2.0 * Va)
    CL = p[nl.P_CL0] + p[nl.P_CLA] * alpha + p[nl.P_CLQ] * qhat + p[nl.P_CLDE] * de
    CD = (p[nl.P_CD0] + p[nl.P_CDA] * alpha + p[nl.P_CDA2] * alpha * alpha
          + p[nl.P_CDDE2] * de * de)
    Cm = p[nl.P_CM0] + p[nl.P_CMA] * alpha + p[nl.P_CMQ] * qhat + p[nl.P_CMDE] * de
    ca, sa = np.cos(alpha), np.sin(alpha)
    Vd = Va + x[6] * (p[nl.P_KMOTOR] - Va)
    thrust = 0.5 * p[nl.P_RHO] * p[nl.P_SPROP] * p[nl.P_CPROP] * Vd * (Vd - Va)
    X = qbar_S * (-CD * ca + CL * sa) + thrust
    Z = qbar_S * (-CD * sa - CL * ca)
    M = qbar_S * p[nl.P_C] * Cm
    m, g = p[nl.P_MASS], p[nl.P_G]
    st, ct = np.sin(x[5]), np.cos(x[5])
    dx = np.empty_like(x)
    dx[0] = -x[2] * x[1] + X / m - g * st
    dx[1] = x[2] * x[0] + Z / m + g * ct
    dx[2] = M / p[nl.P_JY]
    dx[3] = x[0] * ct + x[1] * st - p[nl.P_V0] * math.cos(p[nl.P_GAMMA0])
    dx[4] = -x[0] * st + x[1] * ct + p[nl.P_V0] * math.sin(p[nl.P_GAMMA0])
    dx[5] = x[2]
    dx[6] = (cmd[0] - x[6]) / p[nl.P_TAUT]
    dx[7] = (cmd[1] - x[7]) / p[nl.P_TAUE]
    dx[8] = (cmd[2] - x[8]) / p[nl.P_TAUE]
    return dx


def air(x, wind):
    """Airspeed and angle of attack of every lane."""
    u = x[0] - wind[0]
    w = x[1] - wind[1]
    return np.sqrt(u * u + w * w), np.arctan2(w, u)


def propagate(x, cmd, p, wind, dt, n_sub=10):
    """RK4 over one period on every lane (commands and wind held)."""
    h = dt / n_sub
    for _ in range(n_sub):
        k1 = derivatives(x, cmd, p, wind)
        k2 = derivatives(x + 0.5 * h * k1, cmd, p, wind)
        k3 = derivatives(x + 0.5 * h * k2, cmd, p, wind)
        k4 = derivatives(x + h * k3, cmd, p, wind)
        x = x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return x


def check_against_kernel(plant, rng):
    """The lane twin agrees with the package's kernel (max abs difference)."""
    tp = plant.trim
    L = 4
    x = tp.x0[:, None] + 0.3 * rng.standard_normal((9, L))
    x[6] = np.clip(x[6], 0, 1)
    cmd = tp.u0[:, None] + 0.1 * rng.standard_normal((3, L))
    wind = np.array([2.0, 1.0, 0.05])[:, None] * rng.standard_normal((3, L))
    mine = propagate(x.copy(), cmd, tp.params, wind, plant.dt)
    worst = 0.0
    work = nl.make_work()
    for l in range(L):
        xl = np.ascontiguousarray(x[:, l])
        nl.propagate(xl, np.ascontiguousarray(cmd[:, l]), tp.params,
                     np.ascontiguousarray(wind[:, l]), plant.dt, 10, work)
        worst = max(worst, float(np.max(np.abs(xl - mine[:, l]))))
    return worst


# ------------------------------------------------------------------ the laws
def bryson_q(plant, va_max=2.0, z_max=3.0, theta_max_deg=10.0, q_max_deg=30.0):
    """Bryson's rule on the air-relative airspeed (the linear model's Va row, in
    still air), the height, pitch and pitch rate; no along-track position."""
    c_va = plant.C[OUT_VA]
    Q = np.outer(c_va, c_va) / va_max ** 2
    Q[IZ, IZ] += 1.0 / z_max ** 2
    Q[ITH, ITH] += 1.0 / math.radians(theta_max_deg) ** 2
    Q[IQ, IQ] += 1.0 / math.radians(q_max_deg) ** 2
    return Q


def bryson_r(thr_max=0.3, elevon_max=0.1):
    return np.diag([1.0 / thr_max ** 2, 1.0 / elevon_max ** 2, 1.0 / elevon_max ** 2])


def gains(plant, alpha=0.999, r_lqr=0.1):
    """The gain of each weighting."""
    Q0 = paper_q_lqr(plant.trim.gamma0)
    R0 = r_lqr * np.eye(3)
    Qz = np.zeros((9, 9))
    Qz[IZ, IZ] = 1.0
    out = {"paper": discounted_lqr(plant.A, plant.B, Q0, R0, alpha)[0],
           "nox": discounted_lqr(plant.A, plant.B, Qz, R0, alpha)[0],
           "bryson": discounted_lqr(plant.A, plant.B, bryson_q(plant), bryson_r(), alpha)[0],
           "bryson_va1": discounted_lqr(plant.A, plant.B, bryson_q(plant, va_max=1.0),
                                        bryson_r(), alpha)[0],
           "bryson_z1": discounted_lqr(plant.A, plant.B, bryson_q(plant, z_max=1.0),
                                       bryson_r(), alpha)[0],
           "bryson_va4": discounted_lqr(plant.A, plant.B, bryson_q(plant, va_max=4.0),
                                        bryson_r(), alpha)[0]}
    return out


LAWS = {
    # key: (gain, feedback of u and w, saturated, plant, measured)
    "c0": ("paper", "inertial", True, "nonlinear", False),
    "c0_meas": ("paper", "inertial", True, "nonlinear", True),
    "c0_unsat": ("paper", "inertial", False, "nonlinear", False),
    "c0_linear": ("paper", "inertial", True, "linear", False),
    "c0_air": ("paper", "air", True, "nonlinear", False),
    "c0_nox": ("nox", "inertial", True, "nonlinear", False),
    "bryson": ("bryson", "air", True, "nonlinear", False),
    "bryson_unsat": ("bryson", "air", False, "nonlinear", False),
    "bryson_ground": ("bryson", "inertial", True, "nonlinear", False),
    "bryson_va1": ("bryson_va1", "air", True, "nonlinear", False),
    "bryson_va4": ("bryson_va4", "air", True, "nonlinear", False),
    "bryson_z1": ("bryson_z1", "air", True, "nonlinear", False),
    "c0_va10": ("paper", "inertial", True, "nonlinear", False),
    "pyfly_pid": ("pyfly_pid", "air", True, "nonlinear", False),
    "pid_height": ("pid_height", "air", True, "nonlinear", False),
    "tecs": ("tecs", "air", True, "nonlinear", False),
}

PID_GAINS = dict(kp_v=0.5, ki_v=0.1, kp_th=4.0, ki_th=0.75, kd_th=0.1, kp_h=0.03, ki_h=0.005)
"""PyFly's PIDController (``pyfly/pid_controller.py``): throttle PI on the
air-relative airspeed, elevator PID on pitch (its signs: a positive elevator
pitches down, as the X8's elevons here), run at 0.1 s; ``pid_height`` adds a
height loop that sets the pitch reference (PI, 0.03 rad/m, 0.005 rad/(m s)),
successive loop closure as in Beard and McLain ch. 6."""


TECS_GAINS = dict(k_h=0.01, k_v=0.33, k_tp=1.0, k_ti=0.3, k_bp=0.0, k_bi=0.2, s_t=0.258,
                  th_lim=0.26)
"""A TECS-like law (Lambregts' total energy control, as PX4 and ArduPilot fly it):
flight-path demand from the height error (0.01 rad/m: 5 s at 20 m/s),
acceleration demand from the air-relative airspeed error (1/3 per s); the
throttle closes the total energy rate error (PI, scaled by the throttle's
effect on V'/g at trim, 0.258 per unit), the pitch reference the energy
balance rate error (integral only, limited to +-15 deg: a proportional path
feeds the angle of attack back into the pitch and oscillates) through PyFly's
pitch PID, at 100 Hz.  Flight-path angle and V' from the true state and the
equations.  Gains set by hand on one still-air step, not tuned further."""


def tecs_command(x, wind, tp, st, dt):
    """Commands of the TECS-like law on every lane (``st``: integrators, last command)."""
    g = TECS_GAINS
    grav = tp.params[nl.P_G]
    va, _ = air(x, wind)
    dx = derivatives(x, st["cmd"], tp.params, wind)
    v_in = np.sqrt(x[IU] ** 2 + x[IW] ** 2)
    vdot = (x[IU] * dx[IU] + x[IW] * dx[IW]) / v_in  # inertial speed rate
    gamma = x[ITH] - np.arctan2(x[IW], x[IU])       # inertial flight path
    h_err = x[IZ] - tp.x0[IZ]  # z is down: below the path, climb
    gamma_c = tp.gamma0 + np.clip(g["k_h"] * h_err, -0.2, 0.2)
    vdot_c = g["k_v"] * (tp.V0 - va)
    e_g, e_v = gamma_c - gamma, (vdot_c - vdot) / grav
    e_t, e_b = e_g + e_v, e_g - e_v
    st["it"] += dt * e_t
    st["ib"] += dt * e_b
    thr = tp.u0[0] + (g["k_tp"] * e_t + g["k_ti"] * st["it"]) / g["s_t"]
    th_ref = tp.x0[ITH] + np.clip(g["k_bp"] * e_b + g["k_bi"] * st["ib"], -g["th_lim"], g["th_lim"])
    e_th = x[ITH] - th_ref
    st["ith"] += dt * e_th
    pg = PID_GAINS
    de = tp.u0[1] + pg["kp_th"] * e_th + pg["ki_th"] * st["ith"] + pg["kd_th"] * x[IQ]
    cmd = np.stack([thr, de, de])
    return cmd


def pid_command(gain, x, wind, tp, st, dt):
    """Commands of the PID laws on every lane; ``st`` holds their integrators."""
    if gain == "tecs":
        return tecs_command(x, wind, tp, st, dt)
    g = PID_GAINS
    va, _ = air(x, wind)
    e_v = va - tp.V0
    st["iv"] += dt * e_v
    thr = tp.u0[0] - g["kp_v"] * e_v - g["ki_v"] * st["iv"]
    th_ref = tp.x0[ITH]
    if gain == "pid_height":
        dz = x[IZ] - tp.x0[IZ]
        st["iz"] += dt * dz
        th_ref = th_ref + np.clip(g["kp_h"] * dz + g["ki_h"] * st["iz"], -0.26, 0.26)
    e_th = x[ITH] - th_ref
    st["ith"] += dt * e_th
    de = tp.u0[1] + g["kp_th"] * e_th + g["ki_th"] * st["ith"] + g["kd_th"] * x[IQ]
    return np.stack([thr, de, de])


# ------------------------------------------------------------------ flights
def fly(law, setup, K, draws, record=False):
    """Fly every lane of ``draws`` under ``law``; exits and statistics."""
    gain, feed, saturated, kind, measured = LAWS[law]
    pid = gain in ("pyfly_pid", "pid_height", "tecs")
    K = None if pid else K[gain]
    plant = setup.plant
    tp = plant.trim
    gm = setup.gust
    val = setup.val
    n = setup.tim.n_steps
    L = draws.w.shape[2]
    va_min = 10.0 if law == "c0_va10" else val.va_min  # the envelope's own bound
    lo = plant.u_lower[:, None] if saturated else -np.inf
    hi = plant.u_upper[:, None] if saturated else np.inf
    Bw, Dw = plant_wind_matrices(plant)
    x = np.repeat(tp.x0[:, None], L, axis=1)  # absolute (nonlinear) state
    dxl = np.zeros((9, L))                  # deviation (linear plant)
    s = draws.g0.copy()
    pst = {"iv": np.zeros(L), "ith": np.zeros(L), "iz": np.zeros(L), "it": np.zeros(L),
           "ib": np.zeros(L), "cmd": np.repeat(tp.u0[:, None], L, axis=1)}
    exit_step = np.full(L, -1)
    exit_kind = np.zeros(L, dtype=int)      # 1 airspeed low, 2 high, 3 alpha
    at_limit = np.zeros(L)
    dz2 = np.zeros(L)
    va_lo = np.full(L, np.inf)
    alive = np.ones(L, dtype=bool)
    hist = {k: np.full((n, L), np.nan) for k in
            ("va", "alpha", "thr", "elev", "theta", "ug", "wg", "x", "z", "u")} if record else None
    for k in range(n):
        wind = gm.Cd @ s
        s = gm.Ad @ s + gm.Bd @ draws.eta[k]
        wind_next = gm.Cd @ s
        dev = (x - tp.x0[:, None]) if kind == "nonlinear" else dxl.copy()
        if measured:  # the first six outputs are the first six states plus noise
            dev[:6] += draws.v[k - 1, :6] if k > 0 else 0.0
        if feed == "air":
            dev[IU] -= wind[0]
            dev[IW] -= wind[1]
        if pid:  # PyFly's rate, 100 Hz: unstable at 10 Hz; the gust held over 0.1 s
            xs = x if kind == "nonlinear" else tp.x0[:, None] + dxl
            for _ in range(10):
                cmd = np.clip(pid_command(gain, xs, wind, tp, pst, 0.1 * plant.dt), lo, hi)
                pst["cmd"] = cmd
                xs = propagate(xs, cmd, tp.params, wind, 0.1 * plant.dt, 1)
        else:
            cmd = np.clip(tp.u0[:, None] + (-K @ dev), lo, hi)
        at_limit += alive & ((cmd[0] <= plant.u_lower[0] + 1e-9) |
                             (cmd[0] >= plant.u_upper[0] - 1e-9))
        if pid:
            xn = xs + draws.w[k]
            va, al = air(xn, wind_next)
        elif kind == "nonlinear":
            xn = propagate(x, cmd, tp.params, wind, plant.dt) + draws.w[k]
            va, al = air(xn, wind_next)
        else:
            dxl = plant.A @ dxl + plant.B @ (cmd - tp.u0[:, None]) + Bw @ wind + draws.w[k]
            va = val.va_trim + plant.C[OUT_VA] @ dxl + Dw[OUT_VA] @ wind_next
            al = val.alpha_trim + plant.C[OUT_ALPHA] @ dxl + Dw[OUT_ALPHA] @ wind_next
            xn = tp.x0[:, None] + dxl
        if record:
            for key, v_ in (("va", va), ("alpha", al), ("thr", cmd[0]), ("elev", 0.5 * (cmd[1] + cmd[2])),
                            ("theta", xn[ITH]), ("ug", wind_next[0]), ("wg", wind_next[1]),
                            ("x", xn[IX] - tp.x0[IX]), ("z", xn[IZ] - tp.x0[IZ]),
                            ("u", xn[IU])):
                hist[key][k] = np.where(alive, v_, np.nan)
        dz2 += np.where(alive, (xn[IZ] - tp.x0[IZ]) ** 2, 0.0)
        va_lo = np.where(alive, np.minimum(va_lo, va), va_lo)
        bad = alive & ~((va >= va_min) & (va <= val.va_max)
                        & (al >= val.alpha_min) & (al <= val.alpha_max))
        exit_kind[bad] = np.where(va[bad] < va_min, 1,
                                  np.where(va[bad] > val.va_max, 2, 3))
        exit_step[bad] = k + 1
        alive &= ~bad
        x = np.where(alive, xn, x)
    steps_flown = np.where(exit_step < 0, n, exit_step)
    return dict(exit_step=exit_step, exit_kind=exit_kind,
                thr_limit_share=float(at_limit.sum() / steps_flown.sum()),
                z_ms=float(dz2.sum() / steps_flown.sum()), va_min=va_lo, hist=hist)


def wilson_ci(k, n, z=1.959963984540054):
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(c - h, 0.0), min(c + h, 1.0)


# ------------------------------------------------------------------ linear analysis
def closed_loop(plant, gm, K, feed):
    """Augmented closed loop ``[x (9), s (4)]`` of the linear plant with the
    Dryden gust model, without saturation; returns (F, G, c_va, c_al)."""
    Bw, Dw = plant_wind_matrices(plant)
    Cd = gm.Cd
    n, ng = 9, 4
    F = np.zeros((n + ng, n + ng))
    Kx = K
    Ks = np.zeros((3, ng))
    if feed == "air":  # U = -K (x - E wind), E puts u_g, w_g on u, w
        E = np.zeros((9, 3))
        E[IU, 0] = E[IW, 1] = 1.0
        Ks = K @ E @ Cd
    F[:n, :n] = plant.A - plant.B @ Kx
    F[:n, n:] = plant.B @ Ks + Bw @ Cd
    F[n:, n:] = gm.Ad
    G = np.zeros((n + ng, 4))
    G[n:] = gm.Bd
    c_va = np.concatenate([plant.C[OUT_VA], Dw[OUT_VA] @ Cd])
    c_al = np.concatenate([plant.C[OUT_ALPHA], Dw[OUT_ALPHA] @ Cd])
    c_thr = np.concatenate([-Kx[0], Ks[0]])
    return F, G, c_va, c_al, c_thr


def linear_sigmas(plant, gm, K, feed):
    """Stationary standard deviations of Va, alpha and the throttle command under
    the linear closed loop in the gusts (discrete Lyapunov equation)."""
    F, G, c_va, c_al, c_thr = closed_loop(plant, gm, K, feed)
    P = scipy.linalg.solve_discrete_lyapunov(F, G @ G.T)
    return tuple(float(math.sqrt(c @ P @ c)) for c in (c_va, c_al, c_thr))


def gust_to_va(plant, gm, K, feed, omegas):
    """|Va / u_g| of the linear closed loop at each angular frequency [rad/s]."""
    Bw, Dw = plant_wind_matrices(plant)
    A = plant.A - plant.B @ K
    bu = Bw[:, 0].copy()
    if feed == "air":
        e = np.zeros(9)
        e[IU] = 1.0
        bu = bu + plant.B @ K @ e
    out = []
    for om in omegas:
        zz = np.exp(1j * om * plant.dt)
        h = plant.C[OUT_VA] @ np.linalg.solve(zz * np.eye(9) - A, bu) + Dw[OUT_VA, 0] * zz
        out.append(abs(h))
    return np.array(out)


def phugoid(plant, K):
    """Closed-loop eigenvalues (continuous equivalent) of the slowest mode."""
    ev = np.linalg.eigvals(plant.A - plant.B @ K)
    s = np.log(ev.astype(complex)) / plant.dt
    return s[np.argsort(np.abs(s))]


# ------------------------------------------------------------------ PyFly as an outside reference
def gust_series(setup, draws, lane):
    """The gust ``[u_g, w_g, q_g]`` of every 0.1 s step of one lane (the kernels' recursion)."""
    gm = setup.gust
    s = draws.g0[:, lane].copy()
    out = np.empty((draws.eta.shape[0], 3))
    for k in range(draws.eta.shape[0]):
        out[k] = gm.Cd @ s
        s = gm.Ad @ s + gm.Bd @ draws.eta[k, :, lane]
    return out


def pyfly_flights(setup, draws, lanes, warm_s=20.0):
    """PyFly's own X8 (its 6-DOF equations, its propulsion, scipy's RK45 every
    0.01 s) under its own PIDController, wings level, airspeed 20 m/s and the
    pitch of the package's trim; the gusts are those of the package's flights
    (body axes, held over 0.1 s; PyFly 0.1.2's own ``Wind`` passes the Dryden
    model's arguments in the wrong order, ``Wind.__init__``, so it is bypassed).
    Returns each flight's lowest airspeed and its exit time (NaN: none)."""
    import copy

    from pyfly.pid_controller import PIDController
    from pyfly.pyfly import PyFly

    tp = setup.plant.trim
    val = setup.val
    pf = PyFly(config_kw={"turbulence": True, "turbulence_intensity": "moderate"})
    gust = {"g": np.zeros((1, 3))}

    def turbulence(step, component):
        g = gust["g"][min(step // 10, len(gust["g"]) - 1)]
        return np.array([g[0], 0.0, g[1]]) if component == "linear" else np.array([0.0, g[2], 0.0])

    pf.wind._get_turbulence = turbulence
    pf.seed(0)
    pf.reset(state={"roll": 0.0, "pitch": float(tp.x0[ITH]), "yaw": 0.0, "omega_p": 0.0,
                    "omega_q": 0.0, "omega_r": 0.0, "position_n": 0.0, "position_e": 0.0,
                    "position_d": -100.0, "velocity_u": float(tp.x0[IU]), "velocity_v": 0.0,
                    "velocity_w": float(tp.x0[IW])})
    pid = PIDController(pf.dt)
    pid.set_reference(phi=0.0, theta=float(tp.x0[ITH]), va=float(tp.V0))

    def step():
        st = pf.state
        a = pid.get_action(st["roll"].value, st["pitch"].value, st["Va"].value,
                           [st["omega_p"].value, st["omega_q"].value, st["omega_r"].value])
        ok, _ = pf.step(a)
        return ok

    for _ in range(int(round(warm_s / pf.dt))):  # still air: the PID's integrators settle
        step()
    warm = (pf, pid)
    va_min, t_exit = [], []
    for lane in lanes:
        pf, pid = copy.deepcopy(warm)
        pf.wind._get_turbulence = turbulence
        gust["g"] = gust_series(setup, draws, lane)
        lo, te = np.inf, np.nan
        for k in range(10 * len(gust["g"])):
            ok = step()
            va, al = pf.state["Va"].value, pf.state["alpha"].value
            lo = min(lo, va)
            if not ok or not (val.va_min <= va <= val.va_max
                              and val.alpha_min <= al <= val.alpha_max):
                te = (k + 1) * pf.dt
                break
        va_min.append(lo)
        t_exit.append(te)
        print(f"  PyFly lane {lane}: lowest airspeed {lo:.2f} m/s, exit {te}", flush=True)
    return np.array(va_min), np.array(t_exit)


# ------------------------------------------------------------------ figures
FIG = ROOT / "docs" / "figures"


def figures(paths, setup, K):
    """The four figures of docs/findings/turbulence-envelope.md from saved runs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = {}
    for p_ in paths:
        with np.load(p_) as z:
            d.update({k: z[k] for k in z.files})
    plant, gm = setup.plant, setup.gust
    dt = plant.dt
    H = {k[len("c0_hist_"):]: d[k] for k in d if k.startswith("c0_hist_")}
    es = d["c0_exit_step"]
    n = H["va"].shape[0]
    t = dt * np.arange(1, n + 1)

    # 1. three exit flights of c0
    ex = np.where(es >= 0)[0]
    pick = ex[np.argsort(es[ex])][[len(ex) // 4, len(ex) // 2, 3 * len(ex) // 4]]
    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for i in pick:
        line, = ax[0].plot(t, H["va"][:, i], label=f"flight {i}")
        c = line.get_color()
        ax[1].plot(t, H["ug"][:, i], color=c)
        ax[2].plot(t, H["thr"][:, i], color=c)
        ax[3].plot(t, H["x"][:, i], color=c)
        ax[3].plot(t, np.degrees(H["theta"][:, i]), color=c, ls=":")
    ax[0].axhline(setup.val.va_min, color="k", lw=0.8)
    ax[0].set_ylabel("airspeed [m/s]")
    ax[0].legend(loc="lower left", fontsize=8)
    ax[1].set_ylabel("u_g [m/s]\n(+: tailwind)")
    ax[2].axhline(plant.trim.u0[0], color="k", lw=0.8, ls="--")
    ax[2].set_ylabel("throttle command")
    ax[3].set_ylabel("x [m] (solid)\npitch [deg] (dotted)")
    ax[3].set_xlabel("time [s]")
    ax[0].set_title("c0 on the true state: three flights that leave the envelope (seed 777)")
    fig.tight_layout()
    fig.savefig(FIG / "envelope_c0_exit_flights.png", dpi=110)
    plt.close(fig)

    # 2. gust-to-airspeed response of the linear closed loops
    om = np.logspace(-2.5, 1.3, 300)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for name, feed, lab in (("paper", "inertial", "c0 (paper's weights: x, z)"),
                            ("nox", "inertial", "c0 weights without x (z only)"),
                            ("bryson", "air", "Bryson: airspeed 2 m/s, height 3 m"),
                            ("bryson_z1", "air", "Bryson: airspeed 2 m/s, height 1 m")):
        sv = linear_sigmas(plant, gm, K[name], feed)[0]
        ax.loglog(om, gust_to_va(plant, gm, K[name], feed, om),
                  label=f"{lab}; sigma Va {sv:.2f} m/s")
    ax.axvline(gm.V / gm.L_u, color="k", lw=0.8, ls="--")
    ax.text(gm.V / gm.L_u * 1.1, 0.03, "V / L_u", fontsize=8)
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("|Va / u_g| (linear closed loop)")
    ax.set_ylim(0.02, 3)
    ax.legend(fontsize=8, loc="lower right")
    ax.set_title(f"Horizontal gust to airspeed, moderate Dryden (sigma_u {gm.sigma_u:.2f} m/s)")
    fig.tight_layout()
    fig.savefig(FIG / "envelope_gust_to_airspeed.png", dpi=110)
    plt.close(fig)

    # 3. exit rates by candidate
    laws = [k[:-len("_exit_step")] for k in d if k.endswith("_exit_step")]
    laws = [law for law in LAWS if law in laws]
    rates = []
    for law in laws:
        e = d[f"{law}_exit_step"]
        k_, n_ = int((e >= 0).sum()), len(e)
        lo, hi = wilson_ci(k_, n_)
        rates.append((1000 * k_ / n_, 1000 * lo, 1000 * hi))
    r = np.array(rates)
    fig, ax = plt.subplots(figsize=(7, 0.35 * len(laws) + 1.2))
    y = np.arange(len(laws))[::-1]
    ax.barh(y, r[:, 0], color="tab:blue", alpha=0.6)
    ax.errorbar(r[:, 0], y, xerr=np.clip([r[:, 0] - r[:, 1], r[:, 2] - r[:, 0]], 0, None), fmt="none", ecolor="k")
    ax.set_yticks(y, laws)
    ax.set_xscale("symlog", linthresh=1.0)
    ax.axvline(1.0, color="tab:red", lw=0.8, ls="--")
    ax.set_xlabel("envelope exits per 1,000 fault-free 50 s flights (95 % Wilson)")
    ax.set_title("Nonlinear X8, moderate turbulence, same 2,000 gust draws")
    fig.tight_layout()
    fig.savefig(FIG / "envelope_exit_rates.png", dpi=110)
    plt.close(fig)

    # 4. growth through the flight
    alive = ~np.isnan(H["thr"])
    fig, ax = plt.subplots(3, 1, figsize=(7, 6.5), sharex=True)
    ax[0].plot(t, np.nanmean(np.where(alive, H["thr"] <= 1e-9, np.nan), axis=1))
    ax[0].set_ylabel("share of flights\nthrottle at 0")
    ax[1].plot(t, np.nanstd(H["x"], axis=1), label="x (along track)")
    ax[1].plot(t, np.nanstd(H["va"], axis=1), label="airspeed [m/s]")
    ax[1].plot(t, np.nanstd(H["ug"], axis=1), label="u_g [m/s]")
    ax[1].set_ylabel("standard deviation\nacross flights")
    ax[1].legend(fontsize=8)
    ax[2].plot(t, [(es[es >= 0] <= k).sum() for k in range(1, n + 1)])
    ax[2].set_ylabel("exits so far\n(of 2,000)")
    ax[2].set_xlabel("time [s]")
    ax[0].set_title("c0 on the true state: why the exits grow through the flight")
    fig.tight_layout()
    fig.savefig(FIG / "envelope_growth.png", dpi=110)
    plt.close(fig)
    print("wrote", ", ".join(f"docs/figures/{f}" for f in (
        "envelope_c0_exit_flights.png", "envelope_gust_to_airspeed.png",
        "envelope_exit_rates.png", "envelope_growth.png")))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--flights", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=777)
    ap.add_argument("--laws", default=",".join(LAWS))
    ap.add_argument("--batch", type=int, default=500)
    ap.add_argument("--out", default="/tmp/envelope/study")
    ap.add_argument("--figures", action="store_true")
    ap.add_argument("--pyfly", default=None,
                    help="comma-separated flight ids to fly also on PyFly's own X8 "
                         "(about 3 min each)")
    ap.add_argument("--turbulence", default="moderate", choices=("light", "moderate", "severe"),
                    help="Dryden level (the figures are drawn for moderate)")
    ap.add_argument("--figures-from", default=None,
                    help="comma-separated exits.npz files: only draw the figures from them")
    a = ap.parse_args(argv)
    t0 = time.time()
    cfg = with_overrides(load_config(CONFIG), plant={"turbulence": a.turbulence})
    setup = build_setup(cfg)
    plant = setup.plant
    K = gains(plant)
    print(f"setup {time.time() - t0:.1f} s; lane twin vs kernel, max |dx| = "
          f"{check_against_kernel(plant, np.random.default_rng(0)):.2e}")
    gm = setup.gust
    print(f"Dryden {a.turbulence}: sigma_u {gm.sigma_u:.2f} m/s, sigma_w {gm.sigma_w:.2f} m/s, "
          f"L_u {gm.L_u:.0f} m, L_w {gm.L_w:.0f} m; trim throttle {plant.trim.u0[0]:.3f}, "
          f"limits {plant.u_lower} .. {plant.u_upper}")
    for name, k in K.items():
        feed = "air" if name.startswith("bryson") else "inertial"
        sv, sa, st = linear_sigmas(plant, gm, k, feed)
        print(f"linear {name:7s} ({feed}): sigma Va {sv:.2f} m/s, alpha "
              f"{math.degrees(sa):.2f} deg, throttle {st:.3f}; slowest modes "
              + ", ".join(f"{e.real:+.3f}{e.imag:+.3f}j" for e in phugoid(plant, k)[:4]))
    if a.figures_from:
        figures(a.figures_from.split(","), setup, K)
        return
    laws = [] if a.laws == "none" else a.laws.split(",")
    res = {law: dict(exit_step=[], exit_kind=[], va_min=[], thr=[], z=[], hist=[])
           for law in laws}
    ids = np.arange(a.flights)
    for b0 in range(0, a.flights, a.batch):
        draws = draw_lanes(setup, ids[b0:b0 + a.batch], a.seed, FLIGHT_FAULT_RANGE)
        for law in laws:
            r = fly(law, setup, K, draws, record=(law == "c0" and a.flights <= 2000))
            for key in ("exit_step", "exit_kind", "va_min"):
                res[law][key].append(r[key])
            res[law]["thr"].append(r["thr_limit_share"])
            res[law]["z"].append(r["z_ms"])
            if r["hist"] is not None:
                res[law]["hist"].append(r["hist"])
        print(f"  flights {b0 + len(draws.fault)} of {a.flights}, {time.time() - t0:.0f} s",
              flush=True)
    print(f"\nexits per 1,000 fault-free 50 s flights, {a.turbulence} turbulence, seed {a.seed}, "
          f"flights 0..{a.flights - 1}")
    print("| law | exits | per 1,000 [95 % Wilson] | by airspeed low | high | by alpha "
          "| steps with throttle at a limit | RMS height error [m] "
          "| lowest airspeed of a flight: 1 % / 10 % quantile [m/s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    save = {}
    for law in laws:
        es = np.concatenate(res[law]["exit_step"])
        ek = np.concatenate(res[law]["exit_kind"])
        vm = np.concatenate(res[law]["va_min"])  # an exit flight's lowest before it stops
        save[f"{law}_va_min"] = vm
        n_ex = int((es >= 0).sum())
        lo, hi = wilson_ci(n_ex, a.flights)
        print(f"| {law} | {n_ex} | {1000 * n_ex / a.flights:.1f} [{1000 * lo:.1f}, "
              f"{1000 * hi:.1f}] | {(ek == 1).sum()} | {(ek == 2).sum()} | {(ek == 3).sum()} "
              f"| {100 * np.mean(res[law]['thr']):.1f} % | {math.sqrt(np.mean(res[law]['z'])):.2f} "
              f"| {np.quantile(vm, 0.01):.1f} / {np.quantile(vm, 0.1):.1f} |")
        save[f"{law}_exit_step"] = es
        save[f"{law}_exit_kind"] = ek
    if "c0" in laws and res["c0"]["hist"]:
        for key in res["c0"]["hist"][0]:
            save[f"c0_hist_{key}"] = np.concatenate([h[key] for h in res["c0"]["hist"]], axis=1)
    if a.pyfly:
        pids = [int(i) for i in a.pyfly.split(",")]
        draws = draw_lanes(setup, pids, a.seed, FLIGHT_FAULT_RANGE)
        va_min, t_exit = pyfly_flights(setup, draws, range(len(pids)))
        save["pyfly_ids"], save["pyfly_va_min"], save["pyfly_t_exit"] = pids, va_min, t_exit
        print(f"PyFly X8 + its PID, flights {a.pyfly}: {np.isfinite(t_exit).sum()} exits; "
              f"lowest airspeed per flight: median {np.median(va_min):.2f}, "
              f"min {va_min.min():.2f} m/s")
    np.savez_compressed(out / "exits.npz", **save)
    print(f"wrote {out / 'exits.npz'}; {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main()
