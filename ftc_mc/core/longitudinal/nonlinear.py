"""The nonlinear X8 longitudinal equations with wind: the one source of them.

:mod:`ftc_mc.model.dynamics` evaluates these same kernels (with zero wind) for
trim and numerical linearisation, and the truth plant of the trials integrates
them, so the aerodynamics are written once, here.  Allocation-free scalar code
on float64 arrays (``math`` only).

State (9, paper section 2.3.1 order), all absolute except positions::

    0 u      body-axis forward velocity          [m/s]
    1 w      body-axis downward velocity         [m/s]
    2 q      pitch rate                          [rad/s]
    3 x      horizontal position error           [m]  (forward, along the track)
    4 z      vertical position error             [m]  (down positive)
    5 theta  pitch angle                         [rad]
    6 dt     throttle (engine state)             [-]  in [0, 1]
    7 dl     left elevon deflection              [rad]
    8 dr     right elevon deflection             [rad]

x and z are measured from a reference point that moves along the straight glide
path at the trim airspeed ``V0`` and flight-path angle ``gamma0``; they are zero
at trim.  Commands are the absolute *effective* commands (throttle, left, right
elevon) after the fault of eq. (2).  Outputs (12, the paper's order)::

    u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va

with ``n_x`` and ``n_z`` the body-axis specific forces divided by ``g``
(``n_z`` positive up, about 1 in level flight).  Parameters come packed in one
float64 vector (:data:`N_PARAM` entries in the order of the ``P_*`` indices,
built by :func:`ftc_mc.model.dynamics.pack_parameters`).

Wind: ``wind = [u_g, w_g, q_g]``, body-axis gust velocities [m/s] and gust pitch
rate [rad/s] (for example from :mod:`ftc_mc.core.shared.dryden`).  The aerodynamic and
propeller forces see the air-relative ``u - u_g``, ``w - w_g`` and ``q - q_g``
(airspeed, angle of attack, ``qhat``); the kinematics (Coriolis terms, position
and attitude rates) use the inertial ``u``, ``w``, ``q``.  The wind is frozen in
body axes over one step; its own time derivative is not fed into the equations
(the usual Dryden-gust convention).  A caller that has the gust in another frame
rotates it before the call.  ``outputs_nb`` gives ``alpha``, ``gamma`` (then the
air-path angle), ``CAS`` and ``Va`` air-relative; ``n_x``, ``n_z`` depend on the
air-relative velocity through the aerodynamics.

Integration: classical fourth-order Runge-Kutta with commands and wind held
constant over one control period ``dt`` (zero-order hold, as the linear model of
:mod:`ftc_mc.model.linear`).  **Chosen sub-step: dt/10** (``n_sub = 10``, 0.01 s
at dt = 0.1 s).  The fastest mode is the elevon actuator (tau 0.05 s, h/tau =
0.2, well inside RK4's stability region); ``tests/test_nonlinear.py`` measures
the convergence order (about 4) and the error of ``n_sub = 10`` against
``n_sub = 40`` on a doublet response, far below any sensor noise of the
campaigns.  The plain-NumPy twin of these equations is ``tests/naive.py``
(``x8_derivatives_ref``, written in wind axes with rotation matrices).
"""

from __future__ import annotations

import math

import numpy as np

from ...conventions import N_X as N_STATE
from ...conventions import N_Z as N_OUTPUT
from ...conventions import OUT_ALPHA, OUT_NX, OUT_NZ, OUT_VA, OUTPUT_NAMES
from ..jit import kernel

OUT_GAMMA = OUTPUT_NAMES.index("gamma")
OUT_CAS = OUTPUT_NAMES.index("CAS")
N_DIRECT = OUTPUT_NAMES.index("n_x")
"""The outputs before ``n_x`` are the first states themselves."""

# Index of each entry of the packed parameter vector (model/dynamics.pack_parameters).
(P_MASS, P_JY, P_S, P_C, P_RHO, P_G, P_CL0, P_CLA, P_CLQ, P_CLDE, P_CD0, P_CDA,
 P_CDA2, P_CDDE2, P_CM0, P_CMA, P_CMQ, P_CMDE, P_SPROP, P_KMOTOR, P_CPROP,
 P_TAUT, P_TAUE, P_V0, P_GAMMA0) = range(25)
N_PARAM = 25

N_WORK = 5
"""Rows of the ``work`` array of :func:`propagate` (four RK4 slopes, one stage state)."""

(D_XU, D_XW, D_XQ, D_XE, D_XT, D_ZU, D_ZW, D_ZQ, D_ZE, D_MU, D_MW, D_MQ, D_ME,
 D_COS, D_SIN, D_CA, D_SA, D_VA) = range(18)
N_PARTIAL = 18
"""Entries written by :func:`derivatives_partials_nb`: the partials of ``X / m``,
``Z / m`` and ``M / J_y`` in the air-relative ``u - u_g``, ``w - w_g``,
``q - q_g`` (``U``, ``W``, ``Q``), the elevons' mean ``de`` (``E``) and, for
``X`` only, the throttle state (``T``); then ``cos theta``, ``sin theta``,
``U / Va``, ``W / Va`` (cosine and sine of the angle of attack) and ``Va``."""


@kernel
def air_forces(x, p, wind):
    """Aerodynamic and propulsive forces and moment in body axes (air-relative).

    Parameters
    ----------
    x : ndarray, shape (9,)
        State (module docstring).
    p : ndarray, shape (25,)
        Packed parameters.
    wind : ndarray, shape (3,)
        ``[u_g, w_g, q_g]`` [m/s, m/s, rad/s].

    Returns
    -------
    (X, Z, M, alpha, Va, thrust) : tuple of float
        Body forces [N] (aerodynamic plus thrust, no gravity), pitch moment
        [N m], angle of attack [rad], airspeed [m/s], thrust [N].
    """
    u = x[0] - wind[0]
    w = x[1] - wind[1]
    q = x[2] - wind[2]
    Va = math.sqrt(u * u + w * w)
    alpha = math.atan2(w, u)
    de = 0.5 * (x[7] + x[8])  # pitch effect of the elevons is their mean
    qbar_S = 0.5 * p[P_RHO] * Va * Va * p[P_S]
    qhat = p[P_C] * q / (2.0 * Va)
    CL = p[P_CL0] + p[P_CLA] * alpha + p[P_CLQ] * qhat + p[P_CLDE] * de
    CD = p[P_CD0] + p[P_CDA] * alpha + p[P_CDA2] * alpha * alpha + p[P_CDDE2] * de * de
    Cm = p[P_CM0] + p[P_CMA] * alpha + p[P_CMQ] * qhat + p[P_CMDE] * de
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    # Beard & McLain propeller model: T = 0.5 rho S_prop C_prop Vd (Vd - Va),
    # Vd = Va + throttle (k_motor - Va) (model/airframe.py)
    Vd = Va + x[6] * (p[P_KMOTOR] - Va)
    thrust = 0.5 * p[P_RHO] * p[P_SPROP] * p[P_CPROP] * Vd * (Vd - Va)
    X = qbar_S * (-CD * ca + CL * sa) + thrust
    Z = qbar_S * (-CD * sa - CL * ca)
    M = qbar_S * p[P_C] * Cm
    return X, Z, M, alpha, Va, thrust


@kernel(inline="always")
def _kinematics(x, cmd, p, X, Z, M, dx):
    """``dx`` from the body forces and moment ``X``, ``Z``, ``M`` (the equations
    of :func:`derivatives_nb`); returns ``cos theta``, ``sin theta``."""
    return _kinematics_at(x, cmd, p, X, Z, M, p[P_V0] * math.cos(p[P_GAMMA0]),
                          p[P_V0] * math.sin(p[P_GAMMA0]), dx)


@kernel(inline="always")
def _kinematics_at(x, cmd, p, X, Z, M, vx0, vz0, dx):
    """:func:`_kinematics` with the reference point's velocity ``V0 cos gamma0``,
    ``V0 sin gamma0`` given (the same numbers, so the same ``dx``)."""
    m = p[P_MASS]
    g = p[P_G]
    u = x[0]
    w = x[1]
    q = x[2]
    th = x[5]
    st = math.sin(th)
    ct = math.cos(th)
    dx[0] = -q * w + X / m - g * st
    dx[1] = q * u + Z / m + g * ct
    dx[2] = M / p[P_JY]
    dx[3] = u * ct + w * st - vx0
    dx[4] = -u * st + w * ct + vz0
    dx[5] = q
    dx[6] = (cmd[0] - x[6]) / p[P_TAUT]
    dx[7] = (cmd[1] - x[7]) / p[P_TAUE]
    dx[8] = (cmd[2] - x[8]) / p[P_TAUE]
    return ct, st


@kernel
def derivatives_nb(x, cmd, p, wind, dx):
    """Time derivative ``dx = f(x, cmd, wind)`` (writes ``dx``, shape (9,)).

    Parameters
    ----------
    x : ndarray, shape (9,)
        State (module docstring).
    cmd : ndarray, shape (3,)
        Absolute effective commands (throttle [-], left, right elevon [rad]).
    p : ndarray, shape (25,)
        Packed parameters.
    wind : ndarray, shape (3,)
        ``[u_g, w_g, q_g]`` body-axis gust velocities [m/s] and gust pitch rate
        [rad/s].
    dx : ndarray, shape (9,)
        Output [state units / s].
    """
    X, Z, M, alpha, Va, thrust = air_forces(x, p, wind)
    _kinematics(x, cmd, p, X, Z, M, dx)


@kernel
def derivatives_partials_nb(x, cmd, p, wind, vx0, vz0, dx, d):
    """:func:`derivatives_nb` (the same arithmetic, so the same ``dx`` to the
    bit) and the partials of its forces, analytic, for the Jacobian of ``f``.

    With ``U = u - u_g``, ``W = w - w_g``, ``Q = q - q_g``, ``Va = sqrt(U^2 +
    W^2)``, ``alpha = atan2(W, U)``, ``qhat = c Q / (2 Va)`` and the
    coefficients of :func:`air_forces`, ``X = qS (-CD cos alpha + CL sin
    alpha) + T``, ``Z = qS (-CD sin alpha - CL cos alpha)``, ``M = qS c Cm``
    (``qS = rho Va^2 S / 2``, ``T`` the propeller's thrust).  The rows of ``f``
    that use them are ``f_0 = -q w + X / m - g sin theta``, ``f_1 = q u + Z /
    m + g cos theta``, ``f_2 = M / J_y``; the caller applies the chain rule
    (``d U = d u - d u_g``, ``d de = (d dl + d dr) / 2``).

    Parameters
    ----------
    x, cmd, p, wind, dx : ndarray
        As :func:`derivatives_nb`.
    vx0, vz0 : float
        ``V0 cos gamma0``, ``V0 sin gamma0`` [m/s], computed once by the
        caller (as :func:`derivatives_nb` computes them: the same ``dx``).
    d : ndarray, shape (N_PARTIAL,)
        Written: the ``D_*`` entries, ``d(X/m)/dU`` [1/s], ``d(X/m)/dW`` [1/s],
        ``d(X/m)/dQ`` [m/s per rad], ``d(X/m)/d de`` [m/s^2 per rad],
        ``d(X/m)/d throttle`` [m/s^2], the same of ``Z / m`` (no throttle),
        of ``M / J_y`` [rad/s^2 per unit], then ``cos theta``, ``sin theta``,
        ``U / Va``, ``W / Va`` and ``Va`` [m/s].
    """
    X, Z, M, alpha, Va, thrust = air_forces(x, p, wind)
    ct, st = _kinematics_at(x, cmd, p, X, Z, M, vx0, vz0, dx)
    U = x[0] - wind[0]
    W = x[1] - wind[1]
    Q = x[2] - wind[2]
    de = 0.5 * (x[7] + x[8])
    ca = U / Va
    sa = W / Va
    rho = p[P_RHO]
    c = p[P_C]
    qS = 0.5 * rho * Va * Va * p[P_S]
    qS_v = rho * Va * p[P_S]
    qhat = c * Q / (2.0 * Va)
    qhat_v = -qhat / Va
    qhat_q = c / (2.0 * Va)
    CL = p[P_CL0] + p[P_CLA] * alpha + p[P_CLQ] * qhat + p[P_CLDE] * de
    CD = p[P_CD0] + p[P_CDA] * alpha + p[P_CDA2] * alpha * alpha + p[P_CDDE2] * de * de
    Cm = p[P_CM0] + p[P_CMA] * alpha + p[P_CMQ] * qhat + p[P_CMDE] * de
    CD_a = p[P_CDA] + 2.0 * p[P_CDA2] * alpha
    CD_e = 2.0 * p[P_CDDE2] * de
    # aerodynamic coefficients along body x and z, and their partials
    ax = -CD * ca + CL * sa
    az = -CD * sa - CL * ca
    ax_a = -CD_a * ca + CD * sa + p[P_CLA] * sa + CL * ca
    az_a = -CD_a * sa - CD * ca - p[P_CLA] * ca + CL * sa
    ax_v = p[P_CLQ] * qhat_v * sa
    az_v = -p[P_CLQ] * qhat_v * ca
    ax_q = p[P_CLQ] * qhat_q * sa
    az_q = -p[P_CLQ] * qhat_q * ca
    ax_e = -CD_e * ca + p[P_CLDE] * sa
    az_e = -CD_e * sa - p[P_CLDE] * ca
    # propeller: T = K Vd (Vd - Va), Vd = Va + throttle (k_motor - Va)
    K = 0.5 * rho * p[P_SPROP] * p[P_CPROP]
    dt_ = x[6]
    Vd = Va + dt_ * (p[P_KMOTOR] - Va)
    T_v = K * ((1.0 - dt_) * (Vd - Va) - dt_ * Vd)
    T_t = K * (p[P_KMOTOR] - Va) * (2.0 * Vd - Va)
    # in Va and alpha, then U and W: dVa = ca dU + sa dW, dalpha = (ca dW - sa dU) / Va
    X_v = qS_v * ax + qS * ax_v + T_v
    X_a = qS * ax_a
    Z_v = qS_v * az + qS * az_v
    Z_a = qS * az_a
    M_v = c * (qS_v * Cm + qS * p[P_CMQ] * qhat_v)
    M_a = qS * c * p[P_CMA]
    im = 1.0 / p[P_MASS]
    ij = 1.0 / p[P_JY]
    d[D_XU] = (X_v * ca - X_a * sa / Va) * im
    d[D_XW] = (X_v * sa + X_a * ca / Va) * im
    d[D_XQ] = qS * ax_q * im
    d[D_XE] = qS * ax_e * im
    d[D_XT] = T_t * im
    d[D_ZU] = (Z_v * ca - Z_a * sa / Va) * im
    d[D_ZW] = (Z_v * sa + Z_a * ca / Va) * im
    d[D_ZQ] = qS * az_q * im
    d[D_ZE] = qS * az_e * im
    d[D_MU] = (M_v * ca - M_a * sa / Va) * ij
    d[D_MW] = (M_v * sa + M_a * ca / Va) * ij
    d[D_MQ] = qS * c * p[P_CMQ] * qhat_q * ij
    d[D_ME] = qS * c * p[P_CMDE] * ij
    d[D_COS] = ct
    d[D_SIN] = st
    d[D_CA] = ca
    d[D_SA] = sa
    d[D_VA] = Va


@kernel
def outputs_nb(x, p, wind, y):
    """The 12 outputs ``u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va``.

    ``alpha``, ``gamma`` (air path), ``CAS`` and ``Va`` are air-relative.
    Writes ``y``, shape (12,), absolute values.
    """
    X, Z, M, alpha, Va, thrust = air_forces(x, p, wind)
    mg = p[P_MASS] * p[P_G]
    for i in range(N_DIRECT):
        y[i] = x[i]
    y[OUT_NX] = X / mg
    y[OUT_NZ] = -Z / mg
    y[OUT_ALPHA] = alpha
    y[OUT_GAMMA] = x[5] - alpha
    y[OUT_CAS] = Va  # sea level: calibrated airspeed equals true airspeed
    y[OUT_VA] = Va


@kernel(internal=True)
def rk4_step(x, cmd, p, wind, h, k1, k2, k3, k4, xt):
    """One classical RK4 step of length ``h`` [s] in place on ``x``.

    Commands and wind are held constant over the step; ``k1 .. k4`` and ``xt``
    are work arrays of shape (9,).
    """
    n = x.shape[0]
    derivatives_nb(x, cmd, p, wind, k1)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k1[i]
    derivatives_nb(xt, cmd, p, wind, k2)
    for i in range(n):
        xt[i] = x[i] + 0.5 * h * k2[i]
    derivatives_nb(xt, cmd, p, wind, k3)
    for i in range(n):
        xt[i] = x[i] + h * k3[i]
    derivatives_nb(xt, cmd, p, wind, k4)
    h6 = h / 6.0
    for i in range(n):
        x[i] += h6 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@kernel(internal=True)
def propagate(x, cmd, p, wind, dt, n_sub, work):
    """Advance ``x`` in place over one control period ``dt`` by ``n_sub`` RK4 steps.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State, overwritten with the state at ``t + dt``.
    cmd : ndarray, shape (3,)
        Commands held over the period (zero-order hold).
    p : ndarray, shape (25,)
        Packed parameters.
    wind : ndarray, shape (3,)
        Wind held over the period.
    dt : float
        Control period [s].
    n_sub : int
        Number of RK4 sub-steps (project choice: 10, see module docstring).
    work : ndarray, shape (N_WORK, 9)
        Work array (contents overwritten).
    """
    h = dt / n_sub
    for _ in range(n_sub):
        rk4_step(x, cmd, p, wind, h, work[0], work[1], work[2], work[3], work[4])


@kernel(internal=True)
def make_work():
    """A work array for :func:`propagate`, shape ``(N_WORK, N_STATE)`` (callable
    from Python and from kernels)."""
    return np.zeros((N_WORK, N_STATE))


__all__ = ["air_forces", "derivatives_nb", "derivatives_partials_nb", "N_PARTIAL",
           "outputs_nb", "rk4_step", "propagate",
           "make_work", "N_WORK", "N_STATE", "N_OUTPUT", "N_PARAM"]
