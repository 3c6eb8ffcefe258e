"""The paper's loop on the flying wing: its command plus the lateral terms.

On the 6-DOF plant the paper's controllers (c0, c1, c2 of the longitudinal
model) keep flying pitch and speed, and a lateral-directional autopilot
(:mod:`ftc_mc.design.lateral`: wings level, heading hold) adds a differential
elevon command ``da``; with ``controller.coupling: coupled`` c0 and c1 fly the
coupled 6-DOF laws instead (:func:`loop_command`).  The truth stage
(:func:`ftc_mc.core.sixdof.truth.sixdof_truth`) sends this command, and the
selection among the four 6-DOF controllers
(:mod:`ftc_mc.core.sixdof.selection`) predicts with it.
"""

from __future__ import annotations

import numpy as np

from ...conventions import C_ENGINE, C_NOMINAL, N_U, N_X
from ..jit import kernel
from ..shared.interp import engine_controller
from .layout import U_LEFT, U_RIGHT

LATERAL_LOOP = ("phi", "v", "p", "r", "psi", "left", "right")
"""Rows of ``LaneState.lat``: the lateral loop's measured states, then its
model of the commanded elevons (the order of
:data:`ftc_mc.design.lateral.LATERAL_STATES`)."""
N_LAT = len(LATERAL_LOOP)
N_LAT_MEASURED = 5
LAT_LEFT, LAT_RIGHT = LATERAL_LOOP.index("left"), LATERAL_LOOP.index("right")

ELEVON_SIGN = np.zeros(N_U)
ELEVON_SIGN[U_LEFT] = 1.0
ELEVON_SIGN[U_RIGHT] = -1.0
"""Share of the aileron ``da`` in each command (PyFly's mixing)."""


@kernel(inline="always")
def elevon_model(lag, m, u, u_ff):
    """The lateral loop's model of one commanded elevon after a step:
    ``a m + (1 - a) (u - u_ff)``, ``a = exp(-dt / tau_elevon)`` (``lag``),
    ``u`` the command sent less ``u0``."""
    return lag * m + (1.0 - lag) * (u - u_ff)


@kernel(inline="always")
def loop_command(pl, lo_dev, hi_dev, cur, b0_t, b1_t, xl, du, u, l):
    """Column ``l`` of ``u``, the paper's command (less the longitudinal trim
    ``u0``, saturated), made the command the paper's loop sends on the 6-DOF
    plant: ``u + u_ff + [0, da, -da]`` with ``da = -K_lat lat``, or, with the
    coupled laws (``pl.coupled``) while c0 or c1 flies, ``u + u_ff - G0 s``
    (c0) or ``u + u_ff - G1(b0, b1) s - g1(b0, b1)`` (c1); each clipped to the
    command limits.

    Parameters
    ----------
    pl : SixDofTruth
        ``u_ff``, ``K_lat``, ``coupled``, ``G0``, ``G1``.
    lo_dev, hi_dev : ndarray, shape (3,)
        Command limits less ``u0``.
    cur : int
        The paper's controller in use (``C_NOMINAL``, ``C_ENGINE``, ``C_ELEVON``).
    b0_t, b1_t : float
        The thrust's estimated ``b0`` and ``b1`` (c1's tables).
    xl : ndarray, shape (9 + 7,)
        ``s = [x_hat (9), lat (7)]``: the paper's estimate of the longitudinal
        states and the lateral loop's state (:data:`LATERAL_LOOP`).
    du : ndarray, shape (3,)
        Work array.
    u : ndarray, shape (3, L)
        Commands less ``u0``; column ``l`` rewritten.
    l : int
        Lane.
    """
    if pl.coupled != 0 and cur <= C_ENGINE:
        if cur == C_NOMINAL:
            for i in range(N_U):
                acc = 0.0
                for j in range(N_X + N_LAT):
                    acc -= pl.G0[i, j] * xl[j]
                du[i] = acc
        else:
            engine_controller(pl.G1, b0_t, b1_t, xl, du)
        for i in range(N_U):
            ui = u[i, l] + pl.u_ff[i] + du[i]
            u[i, l] = min(hi_dev[i], max(lo_dev[i], ui))
    else:
        da = 0.0
        for j in range(N_LAT):
            da -= pl.K_lat[j] * xl[N_X + j]
        for i in range(N_U):
            ui = u[i, l] + pl.u_ff[i] + ELEVON_SIGN[i] * da
            u[i, l] = min(hi_dev[i], max(lo_dev[i], ui))
