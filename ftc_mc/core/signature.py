"""Residual signature (paper Table 1) and covariance reset (section 3.2.2).

Table 1 as printed (``swapped = 0``)::

    thrust  : (r_nx >= t_nx and r_q <  t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz >= r_nx)
    elevons : (r_nx <  t_nx and r_q >= t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz <  r_nx)

``swapped = 1`` exchanges the ``r_nz`` comparison of the third clause (DESIGN.md
section 4: an elevon fault drives ``r_q`` and ``r_nz`` far above ``r_nx``, which
the printed rule sends to the thrust block).
"""

from __future__ import annotations

from ..conventions import NO_RESET, RESET_ELEVONS, RESET_THRUST  # noqa: F401
from .jit import kernel



@kernel
def in_block(j, block):
    """Whether fault parameter ``j`` of ``[b0_T, b0_e, b1_T, b1_L, b1_R]`` is in a block.

    The thrust block is ``{b0_T, b1_T}``; the elevon block ``{b0_e, b1_L, b1_R}``.
    """
    if block == RESET_THRUST:
        return j == 0 or j == 2
    if block == RESET_ELEVONS:
        return j == 1 or j == 3 or j == 4
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


@kernel
def reset_covariance(P, block, reset_var):
    """Reset one fault block of ``P_{k+1|k}`` (section 3.2.2).

    The rows and columns of the block's fault parameters are zeroed and their
    variances set to ``reset_var``: thrust ``((u_max - u_min)/t_nx)^2`` for b0 and
    ``1/t_nx^2`` for b1; elevons the same with ``t_q``.

    Parameters
    ----------
    P : ndarray, shape (14, 14)
        Updated in place.
    block : int
        ``RESET_THRUST`` or ``RESET_ELEVONS`` (``NO_RESET`` does nothing).
    reset_var : ndarray, shape (5,)
        Variance of each fault parameter after its block is reset.
    """
    if block != RESET_THRUST and block != RESET_ELEVONS:
        return
    n = P.shape[0]
    nx = n - 5
    for j in range(5):
        if in_block(j, block):
            i = nx + j
            for k in range(n):
                P[i, k] = 0.0
                P[k, i] = 0.0
            P[i, i] = reset_var[j]
