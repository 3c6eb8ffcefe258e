"""The nonlinear 6-DOF X8 with wind: forces, derivative, outputs, RK4.

The equations of the authors' simulator (krisgry/x8 ``forces.m`` and
``dynamics.m``; ``docs/reference/airframes.md``, "Six degrees of freedom"), written as
allocation-free scalar Numba code on float64 arrays.  Sizes and indices come
from :mod:`ftc_mc.core.sixdof.layout`; parameters come packed by
:func:`ftc_mc.model.sixdof.pack_parameters`.  The plain-NumPy twin, written in
the matrix form of ``dynamics.m`` (Fossen's rigid-body mass and Coriolis
matrices, rotation matrices), is ``tests/naive_sixdof.py``.

Forces (``forces.m``), air-relative velocity ``(u, v, w) - (u_g, v_g, w_g)``
and rates ``(p, q, r) - (p_g, q_g, r_g)``::

    Va = |v_r|,  alpha = atan2(w_r, u_r),  beta = asin(v_r / Va)
    L  = qS (CL0 + CLa alpha + CLq c q/(2Va) + CLde de)
    D  = qS (CD0 + CDa alpha + CDa2 alpha^2 + C_D_beta1 beta + C_D_beta2 beta^2
             + CDde2 de^2)
    m  = qS c (Cm0 + Cma alpha + Cmq c q/(2Va) + Cmde de)
    Y  = qS (C_Y_0 + C_Y_beta beta + (C_Y_p p + C_Y_r r) b/(2Va) + C_Y_delta_a da)
    l  = qS b (C_l_0 + C_l_beta beta + (C_l_p p + C_l_r r) b/(2Va) + C_l_delta_a da)
    n  = qS b (C_n_0 + C_n_beta beta + (C_n_p p + C_n_r r) b/(2Va) + C_n_delta_a da)
    F_aero = Rzyx(0, alpha, beta)^T [-D, Y, -L]       (body axes)
    T = 0.5 rho S_prop C_prop Vd (Vd - Va),  Vd = Va + throttle (k_motor - Va)
    l_prop = -k_T_P (k_Omega throttle)^2

with ``qS = 0.5 rho Va^2 S``, elevator ``de = (left + right)/2`` and aileron
``da = (left - right)/2``.  ``F_aero`` holds a side force ``+D sin(beta)``: the
authors' (and PyFly's) rotation, kept as they have it.  The files' rudder and
``C_D_q`` terms are zero and left out.  Wind rates are subtracted (as PyFly and
the longitudinal kernels do; ``forces.m`` adds its ``wind(4:6)``, which its
simulator sets to zero).

Rigid body (``dynamics.m`` with ``r_cg = 0``)::

    d(u, v, w)/dt = F / m - omega x (u, v, w) + gravity
    d(p, q, r)/dt = I^-1 (tau - omega x I omega),   I = [[Jx, 0, -Jxz],
                                                         [0, Jy, 0],
                                                         [-Jxz, 0, Jz]]
    d(x, y, z)/dt = Rzyx(phi, theta, psi) (u, v, w) - V0 (cos gamma0, 0, -sin gamma0)
    d(phi, theta, psi)/dt = T(phi, theta) (p, q, r)

Actuators: first order, throttle ``tau_thrust``, each elevon ``tau_elevon``
(as the longitudinal plant).  Integration: classical RK4, commands and wind
held over the control period, ``n_sub`` sub-steps (10 at 0.1 s, as the
longitudinal plant: the fastest mode, the roll subsidence at -38.5 1/s, gives
h lambda = 0.39 at h = 0.01 s, well inside RK4's stability region).

The linear 6-DOF plant (``plant.kind: linear``) steps the discrete model in
deviations from the trim instead (:func:`linear_step`, :func:`linear_output`).
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import kernel
from .layout import (N_STATE, N_RIGID, PARAM, W_P, W_Q, W_R, W_U, W_V, W_W,
                     X_LEFT, X_P, X_PHI, X_PSI, X_Q, X_R, X_RIGHT, X_THETA, X_THR,
                     X_U, X_V, X_W, X_X, X_Y, X_Z, U_LEFT, U_RIGHT, U_THR,
                     Y_ALPHA, Y_BETA, Y_GAMMA, Y_NX, Y_NY, Y_NZ, Y_VA)

P_MASS, P_JX, P_JY, P_JZ, P_JXZ = (PARAM["mass"], PARAM["Jx"], PARAM["Jy"],
                                   PARAM["Jz"], PARAM["Jxz"])
P_S, P_C, P_B, P_RHO, P_G = PARAM["S"], PARAM["c"], PARAM["b"], PARAM["rho"], PARAM["g"]
P_CL0, P_CLA, P_CLQ, P_CLDE = PARAM["CL0"], PARAM["CLa"], PARAM["CLq"], PARAM["CLde"]
P_CD0, P_CDA, P_CDA2, P_CDDE2 = PARAM["CD0"], PARAM["CDa"], PARAM["CDa2"], PARAM["CDde2"]
P_CDB1, P_CDB2 = PARAM["C_D_beta1"], PARAM["C_D_beta2"]
P_CM0, P_CMA, P_CMQ, P_CMDE = PARAM["Cm0"], PARAM["Cma"], PARAM["Cmq"], PARAM["Cmde"]
P_CY0, P_CYB, P_CYP, P_CYR, P_CYDA = (PARAM["C_Y_0"], PARAM["C_Y_beta"], PARAM["C_Y_p"],
                                      PARAM["C_Y_r"], PARAM["C_Y_delta_a"])
P_CLL0, P_CLLB, P_CLLP, P_CLLR, P_CLLDA = (PARAM["C_l_0"], PARAM["C_l_beta"],
                                           PARAM["C_l_p"], PARAM["C_l_r"],
                                           PARAM["C_l_delta_a"])
P_CN0, P_CNB, P_CNP, P_CNR, P_CNDA = (PARAM["C_n_0"], PARAM["C_n_beta"], PARAM["C_n_p"],
                                      PARAM["C_n_r"], PARAM["C_n_delta_a"])
P_SPROP, P_KMOTOR, P_CPROP = PARAM["S_prop"], PARAM["k_motor"], PARAM["C_prop"]
P_KTP, P_KOMEGA = PARAM["k_T_P"], PARAM["k_Omega"]
P_TAUT, P_TAUE, P_V0, P_GAMMA0 = (PARAM["tau_thrust"], PARAM["tau_elevon"], PARAM["V0"],
                                  PARAM["gamma0"])

N_WORK = 5
"""Rows of the ``work`` array of :func:`propagate` (four RK4 slopes, one stage state)."""


@kernel
def air_forces(x, p, wind):
    """Aerodynamic and propulsive forces and moments in body axes (air-relative).

    Parameters
    ----------
    x : ndarray, shape (15,)
        State (:mod:`ftc_mc.core.sixdof.layout`).
    p : ndarray
        Packed parameters (``layout.PARAM_NAMES``).
    wind : ndarray, shape (6,)
        ``[u_g, v_g, w_g, p_g, q_g, r_g]`` [m/s, rad/s], body axes.

    Returns
    -------
    (Fx, Fy, Fz, l, m, n, alpha, beta, Va) : tuple of float
        Body forces [N] (aerodynamic plus thrust, no gravity), moments [N m]
        (aerodynamic plus propeller torque), angle of attack and sideslip
        [rad], airspeed [m/s].
    """
    ur = x[X_U] - wind[W_U]
    vr = x[X_V] - wind[W_V]
    wr = x[X_W] - wind[W_W]
    pr = x[X_P] - wind[W_P]
    qr = x[X_Q] - wind[W_Q]
    rr = x[X_R] - wind[W_R]
    Va = math.sqrt(ur * ur + vr * vr + wr * wr)
    alpha = math.atan2(wr, ur)
    beta = math.asin(vr / Va)
    de = 0.5 * (x[X_LEFT] + x[X_RIGHT])
    da = 0.5 * (x[X_LEFT] - x[X_RIGHT])
    qS = 0.5 * p[P_RHO] * Va * Va * p[P_S]
    c2v = p[P_C] / (2.0 * Va)
    b2v = p[P_B] / (2.0 * Va)
    CL = p[P_CL0] + p[P_CLA] * alpha + p[P_CLQ] * c2v * qr + p[P_CLDE] * de
    CD = (p[P_CD0] + p[P_CDA] * alpha + p[P_CDA2] * alpha * alpha
          + p[P_CDB1] * beta + p[P_CDB2] * beta * beta + p[P_CDDE2] * de * de)
    Cm = p[P_CM0] + p[P_CMA] * alpha + p[P_CMQ] * c2v * qr + p[P_CMDE] * de
    CY = (p[P_CY0] + p[P_CYB] * beta + (p[P_CYP] * pr + p[P_CYR] * rr) * b2v
          + p[P_CYDA] * da)
    Cl = (p[P_CLL0] + p[P_CLLB] * beta + (p[P_CLLP] * pr + p[P_CLLR] * rr) * b2v
          + p[P_CLLDA] * da)
    Cn = (p[P_CN0] + p[P_CNB] * beta + (p[P_CNP] * pr + p[P_CNR] * rr) * b2v
          + p[P_CNDA] * da)
    L = qS * CL
    D = qS * CD
    Y = qS * CY
    # cos and sin of alpha and beta from the velocity (no trigonometric calls)
    uw = math.sqrt(ur * ur + wr * wr)
    if uw > 0.0:
        ca = ur / uw
        sa = wr / uw
    else:  # atan2(0, 0) = 0
        ca = 1.0
        sa = 0.0
    cb = uw / Va
    sb = vr / Va
    # Rzyx(0, alpha, beta)^T [-D, Y, -L]  (forces.m)
    Vd = Va + x[X_THR] * (p[P_KMOTOR] - Va)
    thrust = 0.5 * p[P_RHO] * p[P_SPROP] * p[P_CPROP] * Vd * (Vd - Va)
    Fx = -D * ca * cb + Y * ca * sb + L * sa + thrust
    Fy = D * sb + Y * cb
    Fz = -D * sa * cb + Y * sa * sb - L * ca
    kw = p[P_KOMEGA] * x[X_THR]
    ml = qS * p[P_B] * Cl - p[P_KTP] * kw * kw
    mm = qS * p[P_C] * Cm
    mn = qS * p[P_B] * Cn
    return Fx, Fy, Fz, ml, mm, mn, alpha, beta, Va


@kernel
def derivatives(x, cmd, p, wind, dx):
    """Time derivative ``dx = f(x, cmd, wind)`` (writes ``dx``, shape (15,)).

    Parameters
    ----------
    x : ndarray, shape (15,)
        State (:mod:`ftc_mc.core.sixdof.layout`).
    cmd : ndarray, shape (3,)
        Absolute effective commands: throttle [-], left, right elevon [rad].
    p : ndarray
        Packed parameters.
    wind : ndarray, shape (6,)
        Body-axis gust velocities [m/s] and rates [rad/s].
    dx : ndarray, shape (15,)
        Output [state units / s].
    """
    Fx, Fy, Fz, ml, mm, mn, alpha, beta, Va = air_forces(x, p, wind)
    m = p[P_MASS]
    g = p[P_G]
    u = x[X_U]
    v = x[X_V]
    w = x[X_W]
    pp = x[X_P]
    q = x[X_Q]
    r = x[X_R]
    sph = math.sin(x[X_PHI])
    cph = math.cos(x[X_PHI])
    sth = math.sin(x[X_THETA])
    cth = math.cos(x[X_THETA])
    sps = math.sin(x[X_PSI])
    cps = math.cos(x[X_PSI])
    # position: Rzyx(phi, theta, psi) (u, v, w) minus the reference's velocity
    dx[X_X] = (cps * cth * u + (-sps * cph + cps * sth * sph) * v
               + (sps * sph + cps * cph * sth) * w - p[P_V0] * math.cos(p[P_GAMMA0]))
    dx[X_Y] = (sps * cth * u + (cps * cph + sph * sth * sps) * v
               + (-cps * sph + sth * sps * cph) * w)
    dx[X_Z] = (-sth * u + cth * sph * v + cth * cph * w
               + p[P_V0] * math.sin(p[P_GAMMA0]))
    # Euler angles (TransformationMatrix.m)
    qr_s = q * sph + r * cph
    dx[X_PHI] = pp + qr_s * sth / cth
    dx[X_THETA] = q * cph - r * sph
    dx[X_PSI] = qr_s / cth
    # translation: F/m + gravity - omega x v
    dx[X_U] = r * v - q * w + Fx / m - g * sth
    dx[X_V] = pp * w - r * u + Fy / m + g * cth * sph
    dx[X_W] = q * u - pp * v + Fz / m + g * cth * cph
    # rotation: I^-1 (tau - omega x I omega)
    Jx = p[P_JX]
    Jy = p[P_JY]
    Jz = p[P_JZ]
    Jxz = p[P_JXZ]
    hx = Jx * pp - Jxz * r
    hy = Jy * q
    hz = Jz * r - Jxz * pp
    mx = ml - (q * hz - r * hy)
    my = mm - (r * hx - pp * hz)
    mz = mn - (pp * hy - q * hx)
    det = Jx * Jz - Jxz * Jxz
    dx[X_P] = (Jz * mx + Jxz * mz) / det
    dx[X_Q] = my / Jy
    dx[X_R] = (Jxz * mx + Jx * mz) / det
    # actuators
    dx[X_THR] = (cmd[U_THR] - x[X_THR]) / p[P_TAUT]
    dx[X_LEFT] = (cmd[U_LEFT] - x[X_LEFT]) / p[P_TAUE]
    dx[X_RIGHT] = (cmd[U_RIGHT] - x[X_RIGHT]) / p[P_TAUE]


@kernel
def outputs(x, p, wind, y):
    """The 19 outputs (:mod:`ftc_mc.core.sixdof.layout`), absolute values.

    The first 12 are the rigid-body states; then ``n_x, n_y, n_z`` [g]
    (``n_z`` positive up), ``alpha``, ``beta`` [rad], the air-path angle
    ``gamma = asin(ca cb sth - (sph sb + cph sa cb) cth)`` [rad] and ``Va``
    [m/s], all air-relative.  Writes ``y``, shape (19,).
    """
    Fx, Fy, Fz, ml, mm, mn, alpha, beta, Va = air_forces(x, p, wind)
    mg = p[P_MASS] * p[P_G]
    for i in range(N_RIGID):
        y[i] = x[i]
    y[Y_NX] = Fx / mg
    y[Y_NY] = Fy / mg
    y[Y_NZ] = -Fz / mg
    y[Y_ALPHA] = alpha
    y[Y_BETA] = beta
    sph = math.sin(x[X_PHI])
    cph = math.cos(x[X_PHI])
    sth = math.sin(x[X_THETA])
    cth = math.cos(x[X_THETA])
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    cb = math.cos(beta)
    sb = math.sin(beta)
    y[Y_GAMMA] = math.asin(ca * cb * sth - (sph * sb + cph * sa * cb) * cth)
    y[Y_VA] = Va


@kernel
def rk4_step(x, cmd, p, wind, h, k1, k2, k3, k4, xt):
    """One classical RK4 step of length ``h`` [s] in place on ``x``.

    Commands and wind are held over the step; ``k1 .. k4`` and ``xt`` are work
    arrays of shape (15,).
    """
    n = x.shape[0]
    derivatives(x, cmd, p, wind, k1)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k1[i]
    derivatives(xt, cmd, p, wind, k2)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k2[i]
    derivatives(xt, cmd, p, wind, k3)
    for i in range(n):
        xt[i] = x[i] + h * k3[i]
    derivatives(xt, cmd, p, wind, k4)
    h6 = h / 6.0
    for i in range(n):
        x[i] += h6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@kernel
def propagate(x, cmd, p, wind, dt, n_sub, work):
    """Advance ``x`` in place over one control period ``dt`` by ``n_sub`` RK4 steps.

    Parameters
    ----------
    x : ndarray, shape (15,)
        State, overwritten with the state at ``t + dt``.
    cmd : ndarray, shape (3,)
        Commands held over the period (zero-order hold).
    p : ndarray
        Packed parameters.
    wind : ndarray, shape (6,)
        Wind held over the period.
    dt : float
        Control period [s].
    n_sub : int
        RK4 sub-steps (10 at dt = 0.1 s; module docstring).
    work : ndarray, shape (N_WORK, 15)
        Work array (contents overwritten).
    """
    h = dt / n_sub
    for _ in range(n_sub):
        rk4_step(x, cmd, p, wind, h, work[0], work[1], work[2], work[3], work[4])


@kernel
def simulate(x, cmds, p, winds, dt, n_sub, out):
    """Fly ``cmds.shape[0]`` control periods from ``x`` (in place).

    Parameters
    ----------
    x : ndarray, shape (15,)
        Initial state, overwritten with the final one.
    cmds : ndarray, shape (n, 3)
        Commands of each period.
    p : ndarray
        Packed parameters.
    winds : ndarray, shape (n, 6)
        Wind of each period.
    dt : float
        Control period [s].
    n_sub : int
        RK4 sub-steps per period.
    out : ndarray, shape (n + 1, 15)
        Written with the state at the start of each period and the final one.
    """
    work = np.zeros((N_WORK, N_STATE))
    for i in range(N_STATE):
        out[0, i] = x[i]
    for k in range(cmds.shape[0]):
        propagate(x, cmds[k], p, winds[k], dt, n_sub, work)
        for i in range(N_STATE):
            out[k + 1, i] = x[i]


@kernel(inline="always")
def linear_step(pl, x, cmd, wd, xn):
    """One period of the linear 6-DOF plant: ``xn = A x + B (cmd - u0) + Bw wd``
    (deviations from the trim; ``cmd`` absolute, ``wd`` the held wind) from the
    model's fields of ``pl`` (``A``, ``B``, ``Bw``, ``u0``)."""
    for i in range(N_STATE):
        acc = 0.0
        for j in range(N_STATE):
            acc += pl.A[i, j] * x[j]
        for j in range(cmd.shape[0]):
            acc += pl.B[i, j] * (cmd[j] - pl.u0[j])
        for j in range(wd.shape[0]):
            acc += pl.Bw[i, j] * wd[j]
        xn[i] = acc


@kernel(inline="always")
def linear_output(pl, x, wd, r):
    """Output ``r`` of the linear 6-DOF plant at the deviation ``x``:
    ``y0[r] + C[r] x + Dw[r] wd`` (``pl``'s ``y0``, ``C``, ``Dw``)."""
    acc = pl.y0[r]
    for j in range(N_STATE):
        acc += pl.C[r, j] * x[j]
    for j in range(wd.shape[0]):
        acc += pl.Dw[r, j] * wd[j]
    return acc
