"""Nonlinear longitudinal equations of motion of the X8 with first-order actuators.

The functions here are plain scalar code on float64 arrays (``math`` only) so the
same source can be compiled by Numba for the nonlinear truth plant; in this module
they run as ordinary Python and serve trim and numerical linearisation.

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
at trim.  Inputs are the absolute *effective* commands (throttle, left, right
elevon) after the fault of eq. (2).

Outputs (12, the paper's order, section 2.3.1)::

    u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va

with ``n_x`` and ``n_z`` the body-axis specific forces divided by ``g``
(``n_z`` positive up, about 1 in level flight).
"""

from __future__ import annotations

import math

import numpy as np

from .airframe import Airframe

from ..conventions import INPUT_NAMES, OUTPUT_NAMES, STATE_NAMES  # noqa: F401
from ..conventions import N_U as N_INPUT
from ..conventions import N_X as N_STATE
from ..conventions import N_Z as N_OUTPUT

# Index of each entry of the packed parameter vector used by the kernels.
(P_MASS, P_JY, P_S, P_C, P_RHO, P_G, P_CL0, P_CLA, P_CLQ, P_CLDE, P_CD0, P_CDA,
 P_CDA2, P_CDDE2, P_CM0, P_CMA, P_CMQ, P_CMDE, P_SPROP, P_KMOTOR, P_CPROP,
 P_TAUT, P_TAUE, P_V0, P_GAMMA0) = range(25)
N_PARAM = 25


def pack_parameters(airframe: Airframe, V0: float, gamma0: float) -> np.ndarray:
    """Pack an airframe and the reference glide path into a float64 vector.

    Parameters
    ----------
    airframe : Airframe
        Airframe parameters.
    V0 : float
        Reference airspeed of the glide path [m/s].
    gamma0 : float
        Reference flight-path angle [rad] (negative when descending).

    Returns
    -------
    numpy.ndarray
        Shape (25,), in the order of the ``P_*`` constants of this module.
    """
    a = airframe
    return np.array([a.mass, a.Jy, a.S, a.c, a.rho, a.g, a.CL0, a.CLa, a.CLq, a.CLde,
                     a.CD0, a.CDa, a.CDa2, a.CDde2, a.Cm0, a.Cma, a.Cmq, a.Cmde,
                     a.S_prop, a.k_motor, a.C_prop, a.tau_thrust, a.tau_elevon,
                     V0, gamma0], dtype=np.float64)


def forces(x, p, out):
    """Aerodynamic and propulsive forces and moment in body axes.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State (see module docstring).
    p : ndarray, shape (25,)
        Packed parameters (:func:`pack_parameters`).
    out : ndarray, shape (6,)
        Written with ``[X, Z, M, alpha, Va, thrust]``: body forces [N] (aerodynamic
        plus thrust, no gravity), pitch moment [N m], angle of attack [rad],
        airspeed [m/s], thrust [N].
    """
    u = x[0]
    w = x[1]
    q = x[2]
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
    # Beard & McLain propeller model as given in docs/airframes.md
    Vd = Va + x[6] * (p[P_KMOTOR] - Va)
    thrust = 0.5 * p[P_RHO] * p[P_SPROP] * p[P_CPROP] * Vd * (Vd - Va)
    out[0] = qbar_S * (-CD * ca + CL * sa) + thrust
    out[1] = qbar_S * (-CD * sa - CL * ca)
    out[2] = qbar_S * p[P_C] * Cm
    out[3] = alpha
    out[4] = Va
    out[5] = thrust


def derivatives(x, cmd, p, dx):
    """Time derivative of the state, ``dx = f(x, cmd)``.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State.
    cmd : ndarray, shape (3,)
        Absolute effective commands (throttle [-], left and right elevon [rad]).
    p : ndarray, shape (25,)
        Packed parameters.
    dx : ndarray, shape (9,)
        Written with the derivative.
    """
    f = np.empty(6)
    forces(x, p, f)
    m = p[P_MASS]
    g = p[P_G]
    u = x[0]
    w = x[1]
    q = x[2]
    th = x[5]
    st = math.sin(th)
    ct = math.cos(th)
    dx[0] = -q * w + f[0] / m - g * st
    dx[1] = q * u + f[1] / m + g * ct
    dx[2] = f[2] / p[P_JY]
    dx[3] = u * ct + w * st - p[P_V0] * math.cos(p[P_GAMMA0])
    dx[4] = -u * st + w * ct + p[P_V0] * math.sin(p[P_GAMMA0])
    dx[5] = q
    dx[6] = (cmd[0] - x[6]) / p[P_TAUT]
    dx[7] = (cmd[1] - x[7]) / p[P_TAUE]
    dx[8] = (cmd[2] - x[8]) / p[P_TAUE]


def outputs(x, p, y):
    """The 12 measured outputs of the paper (section 2.3.1), absolute values.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State.
    p : ndarray, shape (25,)
        Packed parameters.
    y : ndarray, shape (12,)
        Written with ``u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va``.
    """
    f = np.empty(6)
    forces(x, p, f)
    mg = p[P_MASS] * p[P_G]
    for i in range(6):
        y[i] = x[i]
    y[6] = f[0] / mg
    y[7] = -f[1] / mg
    y[8] = f[3]
    y[9] = x[5] - f[3]
    y[10] = f[4]  # sea level: calibrated airspeed equals true airspeed
    y[11] = f[4]
