"""The 6-DOF side monitor: which elevon failed, read from roll and pitch.

On the 6-DOF plant the paper's scheme keeps its longitudinal filter, which sees
a locked elevon only through pitch (``docs/findings/sixdof-side-monitor.md``).  Beside it, the
flight computer runs this monitor on the sensors it has: an augmented Kalman
filter of the 6-DOF model (linear, or the airframe's equations) with a fault
of each actuator, and a windowed GLR test per fault direction that names the
actuator.  It records its
decisions and estimates, so that a campaign measures how well roll tells left
from right, and how soon; it keeps the first elevon it names and that
elevon's position estimate (``LaneState.mside``, ``mpos``), on which a
``controller: lock_turn`` design flies on (:mod:`ftc_mc.core.sixdof.lockturn`).
In a ``controller: lock_turn_selected`` design it names none there: the
selection chooses the side (:mod:`ftc_mc.core.sixdof.selection`), and reads
the belief from the monitor's estimate.

**Filter** (the paper's eqs. 4-11 on the 6-DOF model, per actuator).  The
estimate is ``X = [x (14), b0 (3), b1 (3)]``: the 6-DOF states but the
cross-track position (``layout.MONITOR_STATES``), then a lock offset and an
effectiveness of the throttle, the left and the right elevon
(``layout.MONITOR_PARAMS``)::

    x_{k+1} = A x_k + B (u_k - u_ff) + B b0_k - B diag(u_k + u0) b1_k + w_k
    b_{k+1} = b_k + w^b_k
    z_{k+1} = C x_{k+1} + v_k

``A``, ``B``, ``C`` the discrete 6-DOF linear model at the 6-DOF trim (rows
and columns of the monitor's states; a gust-aware monitor appends the 8 states
of the longitudinal and lateral Dryden models to ``x``, entering ``A`` through
``B_w C_d`` and ``C`` through ``D_w C_d``, with their noise ``B_d B_d^T`` in
``Q``: ``monitor.design_turbulence``), ``u_k`` the commands sent (deviations
from the longitudinal trim ``u0``, lateral loop included), ``u_ff`` the 6-DOF
trim's commands less ``u0``: with eq. (2) per actuator the 6-DOF model's input
is ``u0 + e - u0_6 = (u - u_ff) + b0 - diag(u + u0) b1``.  ``z`` holds the
12 longitudinal outputs the paper's filter reads and the 5 lateral ones of
the lateral loop (bank, side velocity, roll and yaw rates, heading), each a
deviation from the 6-DOF trim, with their sensors' noise ``R``.  Predict
``P = F P F^T + Q`` (``F`` the Jacobian in ``X``); then one scalar update per
measurement in order, ``P`` kept exactly symmetric; then the projection:
``b1`` clipped to [0, 1], ``b0`` to the command range about the trim.

**Nonlinear prediction** (``monitor.prediction: nonlinear``, the default on
the nonlinear plant without gust states; an extended Kalman filter with the trim Jacobians, as the
longitudinal ``prediction: nonlinear``).  The states are predicted by flying
the airframe's equations over the period from ``x0 + x`` under the commands
``b0 + (1 - b1)(u + u0)`` (:func:`nonlinear_prediction`; the gust states
stay linear), and each innovation is ``z_r - h_r(x_pred) - c_r (x - x_pred)``
with ``h`` the airframe's outputs (:func:`nonlinear_offsets`): the linear
model misses the propeller's torque, quadratic in the throttle, and the
moments off the trim airspeed, and reads them as a differential elevon
(``docs/findings/sixdof-side-monitor.md``).  ``F``, ``C`` and the directions stay the trim's.

**Extended filter** (``monitor.prediction: extended``, the default on the
nonlinear plant with gust states; :func:`extended_filter`).  As the nonlinear
prediction, but the gust states' wind ``mon.wind g`` is flown through the
equations and the outputs, as the truth flies its gusts, and ``F``, ``C``
and the directions are the Jacobians at each lane's estimate, taken anew at
every step by forward differences.  In moderate turbulence the trim's do not
hold at the excursions the gusts cause (bank RMS about 10 deg): on its own
model's data the nonlinear prediction's throttle projection has about 20
times its variance (``scripts/studies/study_monitor_consistency.py``).

**Directions.**  A fault of actuator ``j`` starting during step ``k`` moves
the prediction by ``B_j delta`` (``b0``; a loss moves it along the same
column).  The sequential updates see it as mean shifts ``m_jr delta`` of the
normalised innovations ``e_r = nu_r / sqrt(S_r)``: with the error ``s``
started at ``B_j`` and updated by each gain, ``m_jr = c_r s / sqrt(S_r)``,
``s <- s - K_r c_r s``.  The projection ``d_j = sum_r m_jr e_r / |m_j|`` is
standard normal under no fault (sequential innovations are independent) and
shifted by ``|m_j| delta`` under the fault of ``j``: a left elevon pitches and
rolls one way, the right one pitches the same way and rolls the other, and the
throttle moves the airspeed and the load factors.

**Test.**  The windowed GLR of :mod:`ftc_mc.core.shared.glr` on each ``d_j``
(Willsky & Jones 1976, with the one-step signature above in place of their
full signature over the window).  When the largest statistic passes the
threshold (the design's, ``Detection.side_thresholds``: a design may set its
own, ``monitor_threshold``, and the throttle's apart), after the start-up,
the monitor decides direction ``j`` (of several, the one passing its
threshold by the largest factor): it
resets that actuator's block (``b0_j``, ``b1_j``: no correlation, variance
``reset_var``) and restarts every window.  The first decision at or after the
switch step and its step are recorded, and the decisions before it and in all
counted; so
is the estimate ``snap`` steps after that decision (or at the last step flown,
if earlier or without a decision): ``b0``, ``b1`` and each actuator's estimated
position ``b0 + (1 - b1)(u + u0)``, what eq. (2) makes of the command.  Under a
lock that is the lock position whatever the split between ``b0`` and ``b1``,
which only a varying command separates.

Plain-NumPy twin: ``tests/naive_sixdof.py::SideMonitorRef``.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import kernel
from ..shared.glr import glr_lanes, glr_restart
from .kinds import SELECTED_TURN
from .layout import N_OUTPUT, N_STATE, N_WIND
from .plant import N_WORK, outputs, propagate

SideMonitor = namedtuple("SideMonitor", [
    "on",         # 1: the monitor runs; 0: off (every array below may be empty)
    "A",          # (ns, ns) discrete 6-DOF model on the monitor's states (gust states last)
    "B",          # (ns, 3) its commands' columns
    "C",          # (m, ns) its measured outputs (12 longitudinal, then 5 lateral)
    "u0",         # (3,) the longitudinal trim commands (the commands' reference)
    "u_ff",       # (3,) the 6-DOF trim commands less u0
    "lo", "hi",   # (3,) command range about u0 (the b0 projection)
    "P0",         # (n, n) initial covariance (the estimate starts at 0: trim, no fault)
    "Q",          # (n, n) process noise covariance of X (diagonal but a gust block)
    "r",          # (m,) measurement noise variances (diagonal)
    "reset_var",  # (6,) variance of each fault parameter after its block's reset
    "window",     # GLR window [steps] (LaneState.mbuf's rows)
    "min_window", # shortest change tested [steps]
    "startup",    # steps from the start before a decision may be made
    "snap",       # steps after the first decision at or after the switch at which the
                  # estimate is recorded (TrialRecord.mon_b)
    "turn",       # LockTurnTable: the lock-turn designs a lock_turn design flies once
                  # the monitor names an elevon (core/sixdof/lockturn.py)
    "nonlinear",  # 1: the airframe's equations predict the states and the measurements
                  # (flight.plant's p, x0, y0, dt); 0: the linear model A, B, C;
                  # EXTENDED: the equations with the gusts' wind, Jacobians per lane
    "states",     # (14,) int64: the 6-DOF state of each of the monitor's (gust states not)
    "outs",       # (m,) int64: the 6-DOF output of each measurement
    "n_sub",      # RK4 sub-steps of the nonlinear prediction over one period
    "wind",       # (6, ng) the wind [u_g, v_g, w_g, p_g, q_g, r_g] of the gust states
                  # (C_d of both Dryden models, by name; ng = 0 without them)
])
"""Kernel settings of the side monitor (module docstring); built by
:func:`ftc_mc.sim.monitor.side_monitor`."""

EXTENDED = 2
"""``SideMonitor.nonlinear`` of the extended filter (``monitor.prediction: extended``)."""

JACOBIAN_STEP = 1e-6
"""Forward-difference step of the extended filter's Jacobians (states in their
units: m, rad, m/s, rad/s; commands; wind in m/s and rad/s)."""


@kernel(inline="always")
def position(mon, x, ns, nu, a, l, u):
    """Lane ``l``'s estimated absolute position of actuator ``a``,
    ``b0 + (1 - b1)(u + u0)``: what eq. (2) makes of the command sent."""
    return follows(x[ns + a, l], x[ns + nu + a, l], u[a, l] + mon.u0[a])


@kernel(inline="always")
def follows(b0, b1, command):
    """The absolute position an actuator with the faults ``b0``, ``b1`` takes
    under the absolute ``command``: ``b0 + (1 - b1) command`` (eq. 2)."""
    return b0 + (1.0 - b1) * command


@kernel(inline="always")
def lock_position(mon, x, ns, nu, st, work):
    """``st.mpos``: the estimated :func:`position` of the elevon each lane's
    monitor named first (``st.mside``; lanes without one are left alone)."""
    for l in range(x.shape[1]):
        b = st.mside[l]
        if b > 0:
            st.mpos[l] = position(mon, x, ns, nu, b - 1, l, work.u)


@kernel(inline="always")
def on_trim(mon, pl, v, x6):
    """The 6-DOF state ``x0 + v`` (absolute) of one lane's estimate ``v`` on the
    monitor's rows, over ``x6`` (15,)."""
    for i in range(x6.shape[0]):
        x6[i] = pl.x0[i]
    for i in range(mon.states.shape[0]):
        x6[mon.states[i]] += v[i]


@kernel(internal=True)
def nonlinear_prediction(mon, pl, x, ns, nu, u, xn):
    """The nonlinear prediction of the states (``monitor.prediction:
    nonlinear``), written over ``xn`` (ns, L).

    Each lane's state ``x0 + x`` flies one period of the airframe's equations
    (:func:`~ftc_mc.core.sixdof.plant.propagate`, ``mon.n_sub`` RK4 steps, no
    wind) under the commands eq. (2) makes of the estimate,
    ``b0 + (1 - b1)(u + u0)`` (:func:`position`); the gust states and their
    effect stay linear (``A``'s gust columns and rows, the gust states' ``B``
    rows are zero).  ``pl`` the
    :class:`~ftc_mc.core.sixdof.truth.SixDofTruth` (``p``, ``x0``, ``dt``)."""
    L = x.shape[1]
    nx = mon.states.shape[0]
    x6 = np.empty(N_STATE)
    cmd = np.empty(nu)
    wd = np.zeros(N_WIND)
    rk = np.empty((N_WORK, N_STATE))
    for l in range(L):
        on_trim(mon, pl, x[:, l], x6)
        for a in range(nu):
            cmd[a] = position(mon, x, ns, nu, a, l, u)
        propagate(x6, cmd, pl.p, wd, pl.dt, mon.n_sub, rk)
        for i in range(nx):
            j = mon.states[i]
            acc = x6[j] - pl.x0[j]
            for c in range(nx, ns):
                acc += mon.A[i, c] * x[c, l]
            xn[i, l] = acc
        for i in range(nx, ns):
            acc = 0.0
            for c in range(nx, ns):
                acc += mon.A[i, c] * x[c, l]
            xn[i, l] = acc


@kernel(internal=True)
def nonlinear_offsets(mon, pl, x, ns):
    """``h(x) - C x`` (m, L) at each lane's predicted estimate ``x``: the
    airframe's outputs (:func:`~ftc_mc.core.sixdof.plant.outputs`, no wind)
    less the trim's, on the measured rows, less their linear model; the gust
    states' feed-through is linear and cancels."""
    L = x.shape[1]
    nx = mon.states.shape[0]
    m = mon.C.shape[0]
    x6 = np.empty(N_STATE)
    wd = np.zeros(N_WIND)
    y = np.empty(N_OUTPUT)
    off = np.empty((m, L))
    for l in range(L):
        on_trim(mon, pl, x[:, l], x6)
        outputs(x6, pl.p, wd, y)
        for r in range(m):
            o = mon.outs[r]
            acc = y[o] - pl.y0[o]
            for j in range(nx):
                acc -= mon.C[r, j] * x[j, l]
            off[r, l] = acc
    return off


@kernel(inline="always")
def gust_wind(mon, x, nx, wd):
    """The wind (6,) of the gust states ``x[nx:nx + ng]`` of one lane's estimate, over ``wd``."""
    for i in range(wd.shape[0]):
        acc = 0.0
        for j in range(mon.wind.shape[1]):
            acc += mon.wind[i, j] * x[nx + j]
        wd[i] = acc


@kernel(inline="always")
def times_wind(mon, J, out, col0):
    """``out[:, col0:col0 + ng] = J @ mon.wind``: a Jacobian in the wind (rows, 6)
    made one in the gust states."""
    for i in range(J.shape[0]):
        for c in range(mon.wind.shape[1]):
            acc = 0.0
            for w in range(mon.wind.shape[0]):
                acc += J[i, w] * mon.wind[w, c]
            out[i, col0 + c] = acc


@kernel(internal=True)
def extended_filter(mon, pl, x, P, u, z, lat, num, den):
    """Predict and update every lane with the extended filter
    (``monitor.prediction: extended``), one lane at a time, dense; writes the
    direction sums ``num``, ``den`` (3, L) as the other predictions do.

    Each lane's state ``x0 + x`` flies the airframe's equations over the
    period (:func:`~ftc_mc.core.sixdof.plant.propagate`, ``mon.n_sub`` RK4
    steps) under the commands ``b0 + (1 - b1)(u + u0)`` and the wind of its
    gust states (``mon.wind``), held over the period; the gust states follow
    their Dryden models (``A``'s gust block).  The Jacobians of that map with
    respect to the states, the commands and the wind, and those of the
    outputs (:func:`~ftc_mc.core.sixdof.plant.outputs`, at the predicted
    state and wind) with respect to the states and the wind, are taken at the
    lane's estimate by forward differences of step :data:`JACOBIAN_STEP`;
    they replace the trim's ``A``, ``B``, ``C`` in ``F P F^T + Q``, in the
    gains and in the direction signatures.  Each innovation is
    ``z_r - h_r(X_pred) - c_r (X - X_pred)``.
    """
    L = x.shape[1]
    n = x.shape[0]
    ns = mon.A.shape[0]
    nu = mon.B.shape[1]
    nx = mon.states.shape[0]
    ng = ns - nx
    m = mon.C.shape[0]
    nz = z.shape[0]
    nw = mon.wind.shape[0]
    eps = JACOBIAN_STEP
    x6 = np.empty(N_STATE)
    xb = np.empty(N_STATE)
    f0 = np.empty(N_STATE)
    cmd = np.empty(nu)
    cb = np.empty(nu)
    wd = np.zeros(N_WIND)
    wb = np.zeros(N_WIND)
    y0 = np.empty(N_OUTPUT)
    yb = np.empty(N_OUTPUT)
    rk = np.empty((N_WORK, N_STATE))
    xl = np.empty(n)
    xp = np.empty(n)
    F = np.zeros((n, n))
    C = np.zeros((m, ns))
    Jw = np.empty((nx, N_WIND))
    Hw = np.empty((m, N_WIND))
    FP = np.empty((n, n))
    Pl = np.empty((n, n))
    pc = np.empty(n)
    sig = np.empty((nu, n))
    cs = np.empty(nu)
    hp = np.empty(m)
    for l in range(L):
        for i in range(n):
            xl[i] = x[i, l]
        for a in range(nu):
            cmd[a] = position(mon, x, ns, nu, a, l, u)
        gust_wind(mon, xl, nx, wd)
        on_trim(mon, pl, xl, x6)
        # the prediction and its Jacobians in the states, the commands and the wind
        for i in range(N_STATE):
            f0[i] = x6[i]
        propagate(f0, cmd, pl.p, wd, pl.dt, mon.n_sub, rk)
        for i in range(n):
            for j in range(n):
                F[i, j] = 0.0
        # one column per state, command and wind component: fly the period
        # from the estimate with that one perturbed by eps
        for col in range(nx + nu + (nw if ng > 0 else 0)):
            for i in range(N_STATE):
                xb[i] = x6[i]
            for b in range(nu):
                cb[b] = cmd[b]
            for b in range(nw):
                wb[b] = wd[b]
            if col < nx:
                xb[mon.states[col]] += eps
            elif col < nx + nu:
                cb[col - nx] += eps
            else:
                wb[col - nx - nu] += eps
            propagate(xb, cb, pl.p, wb, pl.dt, mon.n_sub, rk)
            for i in range(nx):
                j = mon.states[i]
                d = (xb[j] - f0[j]) / eps
                if col < nx:
                    F[i, col] = d
                elif col < nx + nu:
                    a = col - nx
                    F[i, ns + a] = d
                    F[i, ns + nu + a] = -d * (u[a, l] + mon.u0[a])
                else:
                    Jw[i, col - nx - nu] = d
        if ng > 0:
            times_wind(mon, Jw, F, nx)
            for i in range(nx, ns):
                for c in range(nx, ns):
                    F[i, c] = mon.A[i, c]
        for i in range(ns, n):
            F[i, i] = 1.0
        for i in range(nx):
            xp[i] = f0[mon.states[i]] - pl.x0[mon.states[i]]
        for i in range(nx, ns):
            acc = 0.0
            for c in range(nx, ns):
                acc += mon.A[i, c] * xl[c]
            xp[i] = acc
        for i in range(ns, n):
            xp[i] = xl[i]
        # P = F P F^T + Q
        for i in range(n):
            for j in range(n):
                Pl[i, j] = P[i, j, l]
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for c in range(n):
                    f = F[i, c]
                    if f != 0.0:
                        acc += f * Pl[c, j]
                FP[i, j] = acc
        for i in range(n):
            for j in range(i, n):
                acc = mon.Q[i, j]
                for c in range(n):
                    f = F[j, c]
                    if f != 0.0:
                        acc += FP[i, c] * f
                Pl[i, j] = acc
                Pl[j, i] = acc
        # the outputs at the prediction and their Jacobians in the states and the wind
        on_trim(mon, pl, xp, x6)
        gust_wind(mon, xp, nx, wd)
        outputs(x6, pl.p, wd, y0)
        for r in range(m):
            hp[r] = y0[mon.outs[r]] - pl.y0[mon.outs[r]]
        for c in range(nx):
            for i in range(N_STATE):
                xb[i] = x6[i]
            xb[mon.states[c]] += eps
            outputs(xb, pl.p, wd, yb)
            for r in range(m):
                C[r, c] = (yb[mon.outs[r]] - y0[mon.outs[r]]) / eps
        if ng > 0:
            for w in range(nw):
                for b in range(nw):
                    wb[b] = wd[b]
                wb[w] += eps
                outputs(x6, pl.p, wb, yb)
                for r in range(m):
                    Hw[r, w] = (yb[mon.outs[r]] - y0[mon.outs[r]]) / eps
            times_wind(mon, Hw, C, nx)
        # sequential scalar updates, the direction signatures carried beside
        for d in range(nu):
            for i in range(n):
                sig[d, i] = F[i, ns + d] if i < ns else 0.0
        for i in range(n):
            xl[i] = xp[i]
        for r in range(m):
            sv = mon.r[r]
            nu_r = (z[r, l] if r < nz else lat[r - nz, l]) - hp[r]
            for i in range(n):
                acc = 0.0
                for j in range(ns):
                    acc += C[r, j] * Pl[i, j]
                pc[i] = acc
            for j in range(ns):
                sv += C[r, j] * pc[j]
                nu_r -= C[r, j] * (xl[j] - xp[j])
            rs = 1.0 / np.sqrt(sv)
            for d in range(nu):
                acc = 0.0
                for j in range(ns):
                    acc += C[r, j] * sig[d, j]
                mu = acc * rs
                num[d, l] += mu * nu_r * rs
                den[d, l] += mu * mu
                cs[d] = acc / sv
            for d in range(nu):
                for i in range(n):
                    sig[d, i] -= pc[i] * cs[d]
            gk = nu_r / sv
            for i in range(n):
                xl[i] += pc[i] * gk
            for i in range(n):
                for j in range(i, n):
                    v = Pl[i, j] - pc[i] * pc[j] / sv
                    Pl[i, j] = v
                    Pl[j, i] = v
        for i in range(n):
            x[i, l] = xl[i]
            for j in range(n):
                P[i, j, l] = Pl[i, j]


@kernel(inline="always")
def trim_filter(mon, pl, x, P, u, z, lat, num, den):
    """Predict and update every lane with the trim's Jacobians (the linear and
    the nonlinear predictions), lanes innermost; writes the direction sums
    ``num``, ``den`` (3, L)."""
    n = x.shape[0]
    L = x.shape[1]
    ns = mon.A.shape[0]
    nu = mon.B.shape[1]
    m = mon.C.shape[0]
    nz = z.shape[0]
    nd = nu
    # predict (eq. 5): X = F X + [B (u - u_ff); 0], F = [[A, B, B G], [0, I, 0], [0, 0, I]]
    # with G = diag(g), g = -(u + u0) per lane; every loop runs over the lanes innermost
    g = np.empty((nu, L))
    for a in range(nu):
        for l in range(L):
            g[a, l] = -(u[a, l] + mon.u0[a])
    xn = np.zeros((ns, L))
    if mon.nonlinear:
        nonlinear_prediction(mon, pl, x, ns, nu, u, xn)
    else:
        for i in range(ns):
            for c in range(ns):
                f = mon.A[i, c]
                if f != 0.0:
                    for l in range(L):
                        xn[i, l] += f * x[c, l]
            for a in range(nu):
                f = mon.B[i, a]
                if f != 0.0:
                    for l in range(L):
                        xn[i, l] += f * (u[a, l] - mon.u_ff[a] + x[ns + a, l]
                                         + g[a, l] * x[ns + nu + a, l])
    for i in range(ns):
        for l in range(L):
            x[i, l] = xn[i, l]
    T = np.zeros((ns, n, L))  # the rows of F P that differ from P's
    for i in range(ns):
        for c in range(ns):
            f = mon.A[i, c]
            if f != 0.0:
                for j in range(n):
                    for l in range(L):
                        T[i, j, l] += f * P[c, j, l]
        for a in range(nu):
            f = mon.B[i, a]
            if f != 0.0:
                for j in range(n):
                    for l in range(L):
                        T[i, j, l] += f * (P[ns + a, j, l] + g[a, l] * P[ns + nu + a, j, l])
    acc = np.empty(L)
    for i in range(n):
        for j in range(i, n):
            if j < ns:  # (F P F^T)[i, j] = sum_c (F P)[i, c] F[j, c]
                for l in range(L):
                    acc[l] = 0.0
                for c in range(ns):
                    f = mon.A[j, c]
                    if f != 0.0:  # i <= j < ns: T holds row i
                        for l in range(L):
                            acc[l] += f * T[i, c, l]
                for a in range(nu):
                    f = mon.B[j, a]
                    if f != 0.0:
                        for l in range(L):
                            acc[l] += f * (T[i, ns + a, l] + g[a, l] * T[i, ns + nu + a, l])
            elif i < ns:
                for l in range(L):
                    acc[l] = T[i, j, l]
            else:
                for l in range(L):
                    acc[l] = P[i, j, l]
            q = mon.Q[i, j]
            for l in range(L):
                P[i, j, l] = acc[l] + q  # the lower triangle is copied below
    for i in range(n):
        for j in range(i + 1, n):
            for l in range(L):
                P[j, i, l] = P[i, j, l]
    # sequential scalar updates (eqs. 6-8), the direction signatures carried beside
    sig = np.zeros((nd, n, L))
    for d in range(nd):
        for i in range(ns):
            for l in range(L):
                sig[d, i, l] = mon.B[i, d]
    pc = np.empty((n, L))
    sv = np.empty(L)
    gain = np.empty(L)
    cs = np.empty((nd, L))
    # each row's h(x_pred) - C x_pred; innovation z - h(x_pred) - C (x - x_pred)
    if mon.nonlinear:
        off = nonlinear_offsets(mon, pl, x, ns)
    else:
        off = np.zeros((0, L))
    for r in range(m):
        for i in range(n):
            for l in range(L):
                pc[i, l] = 0.0
        for j in range(ns):
            c = mon.C[r, j]
            if c != 0.0:
                for i in range(n):
                    for l in range(L):
                        pc[i, l] += c * P[i, j, l]
        for l in range(L):
            sv[l] = mon.r[r]
            gain[l] = z[r, l] if r < nz else lat[r - nz, l]
        if mon.nonlinear:
            for l in range(L):
                gain[l] -= off[r, l]
        for d in range(nd):
            for l in range(L):
                cs[d, l] = 0.0
        for j in range(ns):
            c = mon.C[r, j]
            if c != 0.0:
                for l in range(L):
                    sv[l] += c * pc[j, l]
                    gain[l] -= c * x[j, l]
                for d in range(nd):
                    for l in range(L):
                        cs[d, l] += c * sig[d, j, l]
        # gain: the innovation nu_r, then nu_r / S
        for d in range(nd):
            for l in range(L):
                rs = 1.0 / np.sqrt(sv[l])
                mu = cs[d, l] * rs
                num[d, l] += mu * gain[l] * rs
                den[d, l] += mu * mu
                cs[d, l] /= sv[l]
        for l in range(L):
            gain[l] /= sv[l]
        for d in range(nd):
            for i in range(n):
                for l in range(L):
                    sig[d, i, l] -= pc[i, l] * cs[d, l]
        for i in range(n):
            for l in range(L):
                x[i, l] += pc[i, l] * gain[l]
        for i in range(n):
            for j in range(i, n):
                for l in range(L):
                    v = P[i, j, l] - pc[i, l] * pc[j, l] / sv[l]
                    P[i, j, l] = v
                    P[j, i, l] = v


@kernel(inline="always")
def monitor_start(mon, k, st):
    """At step 0 every lane's estimate starts at zero with ``P0``; returns the
    direction sums ``num``, ``den`` (3, L), zero."""
    x = st.mx
    P = st.mP
    n = x.shape[0]
    L = x.shape[1]
    if k == 0:
        for l in range(L):
            for i in range(n):
                x[i, l] = 0.0
                for j in range(n):
                    P[i, j, l] = mon.P0[i, j]
    nd = mon.B.shape[1]
    return np.zeros((nd, L)), np.zeros((nd, L))


@kernel(inline="always")
def monitor_decide(mon, flight, k, st, work, rec, num, den, names, thresholds):
    """After the update: the projection of the fault parameters, the windowed
    GLR of each direction, the decisions with their resets (this step's in
    ``st.mnow``, the latest in ``st.mlast``), and the record;
    with ``names`` (every design but a ``lock_turn_selected`` one, whose
    selection sets them) the first elevon named is kept in ``st.mside`` and
    the step in ``st.mturn``.  ``thresholds``: the design's GLR threshold of
    each direction (``Detection.side_thresholds``); of the directions whose
    statistic passes its threshold, the one passing it by the largest factor
    is decided (the first of equal ones)."""
    x = st.mx
    P = st.mP
    n = x.shape[0]
    L = x.shape[1]
    ns = mon.A.shape[0]
    nu = mon.B.shape[1]
    nd = nu
    for l in range(L):
        for a in range(nu):
            b0 = x[ns + a, l]
            x[ns + a, l] = min(mon.hi[a], max(mon.lo[a], b0))
            b1 = x[ns + nu + a, l]
            x[ns + nu + a, l] = min(1.0, max(0.0, b1))
    # the test: the windowed GLR of each direction's projection
    innov = np.empty((nd, L))
    for d in range(nd):
        for l in range(L):
            innov[d, l] = num[d, l] / np.sqrt(den[d, l]) if den[d, l] > 0.0 else 0.0
    if k < rec.hist_mon.shape[0]:  # a kept history (recorded signals)
        for d in range(nd):
            for l in range(L):
                rec.hist_mon[k, d, l] = innov[d, l]
    stat = np.empty((nd, L))
    kn = k + 1
    if kn <= mon.startup:
        for l in range(L):
            st.mcount[l] = 0
            st.mnow[l] = 0
        return
    glr_lanes(innov, st.mbuf, st.mcount, k, mon.min_window, np.inf, stat)
    block = np.zeros(L, dtype=np.int64)
    for l in range(L):
        best = 0.0  # the largest factor by which a statistic passes its threshold
        for d in range(nd):
            t = thresholds[d]
            if stat[d, l] > t and stat[d, l] / t > best:
                best = stat[d, l] / t
                block[l] = d + 1
        b = block[l]
        st.mnow[l] = b
        if b == 0:
            continue
        for pidx in (ns + b - 1, ns + nu + b - 1):
            for j in range(n):
                P[pidx, j, l] = 0.0
                P[j, pidx, l] = 0.0
            P[pidx, pidx, l] = mon.reset_var[pidx - ns]
        st.mlast[l] = b
        if names and b > 1 and st.mside[l] == 0:  # the first elevon named (lockturn.py)
            st.mside[l] = b
            st.mturn[l] = kn
        if st.alive[l]:
            rec.side_n[l] += 1
            if kn >= flight.timing.k_fault:
                if rec.side_k[l] < 0:
                    rec.side_k[l] = kn
                    rec.side_block[l] = b
            else:
                rec.side_pre[l] += 1
    glr_restart(block, st.mcount)
    lock_position(mon, x, ns, nu, st, work)
    for l in range(L):
        if st.alive[l] and (rec.side_k[l] < 0 or kn <= rec.side_k[l] + mon.snap):
            for i in range(2 * nu):
                rec.mon_b[i, l] = x[ns + i, l]
            for a in range(nu):
                rec.mon_b[2 * nu + a, l] = position(mon, x, ns, nu, a, l, work.u)


@kernel(internal=True)
def sixdof_monitor(plant, scheme, flight, k, st, work, rec):
    """Advance the side monitor of every lane over step ``k -> k+1``.

    Parameters
    ----------
    plant : SixdofPlant
        The path's plant marker (the dispatcher's calling convention).
    scheme : Scheme
        ``reconfig.kind`` (a ``lock_turn`` or ``lock_turn_selected`` design);
        for the selection, ``belief``, ``reconfig``, ``controller``, ``engine``.
    flight : Flight
        ``plant.monitor`` (:class:`SideMonitor`), ``timing.k_fault``.
    k : int
        Step.
    st : LaneState
        ``mx`` (n, L), ``mP`` (n, n, L) (set at step 0: zero and ``P0``),
        the GLR window ``mbuf`` and ``mcount``, the first elevon named
        ``mside`` and its position estimate ``mpos``, the latest decision
        ``mlast``, updated in place; ``lat``
        the lateral loop's measurements of ``k + 1``.
    work : TrialWork
        ``u`` the commands sent over the step, ``z`` the 12 longitudinal
        measurements of ``k + 1``.
    rec : TrialRecord
        ``side_k``, ``side_block``, ``side_pre``, ``side_n`` (on live lanes), ``mon_b``
        (module docstring); while a history is kept, ``hist_mon`` row ``k``:
        each direction's projection, the GLR's input.
    """
    mon = flight.plant.monitor
    if mon.on == 0:
        return
    if mon.nonlinear == EXTENDED:
        raise ValueError("an extended side monitor flies sixdof_monitor_extended")
    num, den = monitor_start(mon, k, st)
    trim_filter(mon, flight.plant, st.mx, st.mP, work.u, work.z, st.lat, num, den)
    monitor_decide(mon, flight, k, st, work, rec, num, den,
                   scheme.reconfig.kind != SELECTED_TURN, scheme.detection.side_thresholds)


@kernel(internal=True)
def sixdof_monitor_extended(plant, scheme, flight, k, st, work, rec):
    """:func:`sixdof_monitor` with the extended filter (:func:`extended_filter`),
    on the ``SIXDOF_EXTENDED_PLANT`` path (``core/shared/paths.py``): the
    other 6-DOF path never compiles it."""
    mon = flight.plant.monitor
    if mon.on == 0:
        return
    num, den = monitor_start(mon, k, st)
    extended_filter(mon, flight.plant, st.mx, st.mP, work.u, work.z, st.lat, num, den)
    monitor_decide(mon, flight, k, st, work, rec, num, den,
                   scheme.reconfig.kind != SELECTED_TURN, scheme.detection.side_thresholds)
