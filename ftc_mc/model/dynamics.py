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

from ..core.longitudinal.nonlinear import (N_PARAM, P_C, P_CD0, P_CDA, P_CDA2,  # noqa: F401
                              P_CDDE2, P_CL0, P_CLA, P_CLDE, P_CLQ, P_CM0, P_CMA,
                              P_CMDE, P_CMQ, P_CPROP, P_G, P_GAMMA0, P_JY, P_KMOTOR,
                              P_MASS, P_RHO, P_S, P_SPROP, P_TAUE, P_TAUT, P_V0,
                              air_forces, derivatives_nb, outputs_nb)

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
        Shape (25,), in the order of the ``P_*`` indices of
        :mod:`ftc_mc.core.longitudinal.nonlinear`.
    """
    a = airframe
    return np.array([a.mass, a.Jy, a.S, a.c, a.rho, a.g, a.CL0, a.CLa, a.CLq, a.CLde,
                     a.CD0, a.CDa, a.CDa2, a.CDde2, a.Cm0, a.Cma, a.Cmq, a.Cmde,
                     a.S_prop, a.k_motor, a.C_prop, a.tau_thrust, a.tau_elevon,
                     V0, gamma0], dtype=np.float64)


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
