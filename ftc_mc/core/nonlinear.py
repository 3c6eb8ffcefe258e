"""Numba kernels of the nonlinear X8 longitudinal plant with wind (truth plant).

Allocation-free transcriptions of :mod:`ftc_mc.model.dynamics` (same state,
command, output and packed-parameter conventions; see that module) with a
longitudinal wind input::

    wind = [u_g, w_g, q_g]

the body-axis gust velocities [m/s] and the gust pitch rate [rad/s] (for
example from :mod:`ftc_mc.core.dryden`).  The aerodynamic and propeller forces
see the air-relative quantities ``u - u_g``, ``w - w_g`` and ``q - q_g``
(airspeed, angle of attack, ``qhat``), the kinematics (Coriolis terms, position
and attitude rates) use the inertial ``u``, ``w``, ``q``.  With ``wind = 0`` the
kernels agree with :func:`ftc_mc.model.dynamics.derivatives` and
:func:`~ftc_mc.model.dynamics.outputs` to rounding (tests/test_nonlinear.py:
1e-12).  The wind is taken as frozen in body axes over one step; its own time
derivative is not fed into the equations (the usual Dryden-gust convention).

Integration: classical fourth-order Runge-Kutta with commands and wind held
constant over one control period ``dt`` (zero-order hold, as the linear model of
:mod:`ftc_mc.model.linear`).  **Chosen sub-step: dt/10** (``n_sub = 10``, 0.01 s
at dt = 0.1 s).  The fastest mode is the elevon actuator (tau 0.05 s, h/tau =
0.2, well inside RK4's stability region); the tests measure the convergence
order (about 4) and that ``n_sub = 10`` is within 1e-8 of ``n_sub = 40`` on a
doublet response, far below any sensor noise of the campaigns.

``wind`` is in body axes: a caller that has the gust in another frame rotates
it before the call.  ``outputs_nb`` gives ``alpha``, ``gamma``, ``CAS`` and
``Va`` air-relative (``gamma = theta - alpha`` is then the air-path angle);
``n_x``, ``n_z`` are the specific forces, which depend on the air-relative
velocity through the aerodynamics.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.dynamics import (N_OUTPUT, N_STATE, P_C, P_CD0, P_CDA, P_CDA2,
                              P_CDDE2, P_CL0, P_CLA, P_CLDE, P_CLQ, P_CM0, P_CMA,
                              P_CMDE, P_CMQ, P_CPROP, P_G, P_GAMMA0, P_JY,
                              P_KMOTOR, P_MASS, P_RHO, P_S, P_SPROP, P_TAUE,
                              P_TAUT, P_V0)
from .jit import kernel

#: number of rows of the ``work`` array of :func:`propagate`
N_WORK = 5


@kernel
def _air_forces(x, p, wind):
    """Body forces X, Z [N] (aero + thrust), moment M [N m], alpha, Va (air-relative).

    Returns a tuple (no allocation); same expressions as
    :func:`ftc_mc.model.dynamics.forces` on the air-relative velocities.
    """
    u = x[0] - wind[0]
    w = x[1] - wind[1]
    q = x[2] - wind[2]
    Va = math.sqrt(u * u + w * w)
    alpha = math.atan2(w, u)
    de = 0.5 * (x[7] + x[8])
    qbar_S = 0.5 * p[P_RHO] * Va * Va * p[P_S]
    qhat = p[P_C] * q / (2.0 * Va)
    CL = p[P_CL0] + p[P_CLA] * alpha + p[P_CLQ] * qhat + p[P_CLDE] * de
    CD = p[P_CD0] + p[P_CDA] * alpha + p[P_CDA2] * alpha * alpha + p[P_CDDE2] * de * de
    Cm = p[P_CM0] + p[P_CMA] * alpha + p[P_CMQ] * qhat + p[P_CMDE] * de
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    Vd = Va + x[6] * (p[P_KMOTOR] - Va)
    thrust = 0.5 * p[P_RHO] * p[P_SPROP] * p[P_CPROP] * Vd * (Vd - Va)
    X = qbar_S * (-CD * ca + CL * sa) + thrust
    Z = qbar_S * (-CD * sa - CL * ca)
    M = qbar_S * p[P_C] * Cm
    return X, Z, M, alpha, Va


@kernel
def derivatives_nb(x, cmd, p, wind, dx):
    """Time derivative ``dx = f(x, cmd, wind)`` (writes ``dx``, shape (9,)).

    Parameters
    ----------
    x : ndarray, shape (9,)
        State (:mod:`ftc_mc.model.dynamics`).
    cmd : ndarray, shape (3,)
        Absolute effective commands (throttle, left, right elevon [rad]).
    p : ndarray, shape (25,)
        Packed parameters (:func:`ftc_mc.model.dynamics.pack_parameters`).
    wind : ndarray, shape (3,)
        ``[u_g, w_g, q_g]`` body-axis gust velocities [m/s] and gust pitch rate
        [rad/s].
    dx : ndarray, shape (9,)
        Output.
    """
    X, Z, M, alpha, Va = _air_forces(x, p, wind)
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
    dx[3] = u * ct + w * st - p[P_V0] * math.cos(p[P_GAMMA0])
    dx[4] = -u * st + w * ct + p[P_V0] * math.sin(p[P_GAMMA0])
    dx[5] = q
    dx[6] = (cmd[0] - x[6]) / p[P_TAUT]
    dx[7] = (cmd[1] - x[7]) / p[P_TAUE]
    dx[8] = (cmd[2] - x[8]) / p[P_TAUE]


@kernel
def outputs_nb(x, p, wind, y):
    """The 12 outputs ``u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va``.

    As :func:`ftc_mc.model.dynamics.outputs`; ``alpha``, ``gamma`` (air path),
    ``CAS`` and ``Va`` are air-relative.  Writes ``y``, shape (12,).
    """
    X, Z, M, alpha, Va = _air_forces(x, p, wind)
    mg = p[P_MASS] * p[P_G]
    for i in range(6):
        y[i] = x[i]
    y[6] = X / mg
    y[7] = -Z / mg
    y[8] = alpha
    y[9] = x[5] - alpha
    y[10] = Va  # sea level: calibrated airspeed equals true airspeed
    y[11] = Va


@kernel
def rk4_step(x, cmd, p, wind, h, k1, k2, k3, k4, xt):
    """One classical RK4 step of length ``h`` in place on ``x``.

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


@kernel
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


@kernel
def make_work():
    """A work array for :func:`propagate`, shape ``(N_WORK, N_STATE)`` (callable
    from Python and from kernels)."""
    return np.zeros((N_WORK, N_STATE))


__all__ = ["derivatives_nb", "outputs_nb", "rk4_step", "propagate", "make_work",
           "N_WORK", "N_STATE", "N_OUTPUT"]
