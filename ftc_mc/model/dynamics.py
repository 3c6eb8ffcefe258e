"""Nonlinear longitudinal equations of motion of the X8 with first-order actuators.

The equations themselves are written once, in the Numba kernels of
:mod:`ftc_mc.core.longitudinal.nonlinear` (which also serve the nonlinear truth plant); this
module packs the parameters and evaluates those kernels in still air for trim
and numerical linearisation (:mod:`ftc_mc.model.linear`).  State, command,
output and parameter conventions are those of :mod:`ftc_mc.core.longitudinal.nonlinear`:

State (9, paper section 2.3.1 order)::

    u, w [m/s], q [rad/s], x, z [m], theta [rad], throttle [-], left, right elevon [rad]

Outputs (12, the paper's order, section 2.3.1)::

    u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va
"""

from __future__ import annotations

import numpy as np

from .airframe import Airframe

from ..core.longitudinal import nonlinear as nl
from ..core.longitudinal.nonlinear import air_forces, derivatives_nb, outputs_nb

_STILL_AIR = np.zeros(3)


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
        Shape (``N_PARAM``,), each value at its ``P_*`` index of
        :mod:`ftc_mc.core.longitudinal.nonlinear`.
    """
    a = airframe
    p = np.full(nl.N_PARAM, np.nan)
    for i, v in ((nl.P_MASS, a.mass), (nl.P_JY, a.Jy), (nl.P_S, a.S), (nl.P_C, a.c),
                 (nl.P_RHO, a.rho), (nl.P_G, a.g), (nl.P_CL0, a.CL0), (nl.P_CLA, a.CLa),
                 (nl.P_CLQ, a.CLq), (nl.P_CLDE, a.CLde), (nl.P_CD0, a.CD0),
                 (nl.P_CDA, a.CDa), (nl.P_CDA2, a.CDa2), (nl.P_CDDE2, a.CDde2),
                 (nl.P_CM0, a.Cm0), (nl.P_CMA, a.Cma), (nl.P_CMQ, a.Cmq),
                 (nl.P_CMDE, a.Cmde), (nl.P_SPROP, a.S_prop), (nl.P_KMOTOR, a.k_motor),
                 (nl.P_CPROP, a.C_prop), (nl.P_TAUT, a.tau_thrust),
                 (nl.P_TAUE, a.tau_elevon), (nl.P_V0, V0), (nl.P_GAMMA0, gamma0)):
        p[i] = v
    assert not np.isnan(p).any(), "every parameter packed"
    return p


def _c(a):
    """C-contiguous float64 view or copy (one compiled signature per kernel)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def _write(out, values):
    """``out[:] = values`` where ``values`` was computed into a contiguous buffer."""
    if out is not values:
        out[:] = values


def _buffer(out):
    return out if (out.dtype == np.float64 and out.flags.c_contiguous
                   and out.flags.writeable) else np.empty(out.shape)


def forces(x, p, out):
    """Aerodynamic and propulsive forces and moment in body axes, still air.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State (see module docstring).
    p : ndarray, shape (25,)
        Packed parameters (:func:`pack_parameters`).
    out : ndarray, shape (6,)
        Written with ``[X, Z, M, alpha, Va, thrust]``: body forces [N] (aerodynamic
        plus thrust, no gravity), pitch moment [N m], angle of attack [rad],
        airspeed [m/s], thrust [N] (:func:`ftc_mc.core.longitudinal.nonlinear.air_forces`).
    """
    out[:] = air_forces(_c(x), _c(p), _STILL_AIR)


def derivatives(x, cmd, p, dx):
    """Time derivative of the state, ``dx = f(x, cmd)``, in still air.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State.
    cmd : ndarray, shape (3,)
        Absolute effective commands (throttle [-], left and right elevon [rad]).
    p : ndarray, shape (25,)
        Packed parameters.
    dx : ndarray, shape (9,)
        Written with the derivative (:func:`ftc_mc.core.longitudinal.nonlinear.derivatives_nb`).
    """
    buf = _buffer(dx)
    derivatives_nb(_c(x), _c(cmd), _c(p), _STILL_AIR, buf)
    _write(dx, buf)


def outputs(x, p, y):
    """The 12 measured outputs of the paper (section 2.3.1), absolute, still air.

    Parameters
    ----------
    x : ndarray, shape (9,)
        State.
    p : ndarray, shape (25,)
        Packed parameters.
    y : ndarray, shape (12,)
        Written with ``u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va``
        (:func:`ftc_mc.core.longitudinal.nonlinear.outputs_nb`).
    """
    buf = _buffer(y)
    outputs_nb(_c(x), _c(p), _STILL_AIR, buf)
    _write(y, buf)
