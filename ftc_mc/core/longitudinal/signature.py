"""Residual signature (paper Table 1) and covariance reset (section 3.2.2).

Table 1 as printed (``swapped = 0``)::

    thrust  : (r_nx >= t_nx and r_q <  t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz >= r_nx)
    elevons : (r_nx <  t_nx and r_q >= t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz <  r_nx)

``swapped = 1`` exchanges the ``r_nz`` comparison of the third clause (an
elevon fault drives ``r_q`` and ``r_nz`` far above ``r_nx``, which the printed
rule sends to the thrust block; see ``docs/paper-map.md``).
"""

from __future__ import annotations

from ...conventions import (ELEVON_BLOCK, NO_RESET, RESET_ELEVONS,  # noqa: F401
                           RESET_THRUST, THRUST_BLOCK)
from ..jit import kernel


@kernel
def in_block(j, block):
    """Whether fault parameter ``j`` of ``[b0_T, b0_e, b1_T, b1_L, b1_R]`` is in a block.

    The thrust block is ``{b0_T, b1_T}``; the elevon block ``{b0_e, b1_L, b1_R}``
    (:data:`ftc_mc.conventions.THRUST_BLOCK`, :data:`~ftc_mc.conventions.ELEVON_BLOCK`).
    """
    if block == RESET_THRUST:
        for m in THRUST_BLOCK:
            if j == m:
                return True
    elif block == RESET_ELEVONS:
        for m in ELEVON_BLOCK:
            if j == m:
                return True
    return False


@kernel
def signature(r_q, r_nx, r_nz, t_q, t_nx, swapped):
    """Which covariance block Table 1 resets.

    Parameters
    ----------
    r_q, r_nx, r_nz : float
        Normalised residuals (eqs. 9-11).
    t_q, t_nx : float
        Thresholds (paper: 25).
    swapped : int
        0 for Table 1 as printed, 1 for the swapped third clause.

    Returns
    -------
    int
        ``NO_RESET``, ``RESET_THRUST`` or ``RESET_ELEVONS``.
    """
    nx_hit = r_nx >= t_nx
    q_hit = r_q >= t_q
    if nx_hit and not q_hit:
        return RESET_THRUST
    if q_hit and not nx_hit:
        return RESET_ELEVONS
    if nx_hit and q_hit:
        nz_big = r_nz >= r_nx
        if swapped != 0:
            nz_big = not nz_big
        return RESET_THRUST if nz_big else RESET_ELEVONS
    return NO_RESET


