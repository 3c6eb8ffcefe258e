"""Residual signature (paper Table 1) and covariance reset (section 3.2.2).

Table 1 as printed (variant ``paper``)::

    thrust  : (r_nx >= t_nx and r_q <  t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz >= r_nx)
    elevons : (r_nx <  t_nx and r_q >= t_q) or (r_nx >= t_nx and r_q >= t_q and r_nz <  r_nx)

Variant ``swapped`` exchanges the ``r_nz`` comparison of the third clause (an
elevon fault drives ``r_q`` and ``r_nz`` far above ``r_nx``, which the printed
rule sends to the thrust block; see ``docs/reference/paper-map.md``).

The kernel reads Table 1 as data the family supplies (``conventions.TABLE1``,
``Layout.thresholded``, ``Layout.decisions``):

* a threshold per residual channel (``Detection.thresholds``; ``inf`` for a
  channel that is only compared, ``r_nz``);
* a decision table (``Detection.table``), one row per hit pattern of the
  channels (bit ``i`` set when channel ``i`` reaches its threshold):
  ``(block_if, block_else, cmp_a, cmp_b)``, ``block_if`` when the row compares
  nothing (``cmp_a`` -1) or ``r[cmp_a] >= r[cmp_b]``, else ``block_else``.
  The third clause of Table 1 is such a comparison (``r_nz`` against
  ``r_nx``), and ``paper`` and ``swapped`` differ only in its two blocks;
* block membership (``Layout.block_params``).

:func:`signature_lanes` reads them for any number of channels and blocks, so another
plant family (the 6-DOF one, with a roll channel and separate left and right
elevon blocks) brings new data, not new kernel code.  The paper's names stay as
read-only views for the code outside the kernels (``Detection.t_q``, ``.t_nx``,
``.swapped``, and ``_replace(t_q=...)``).  Checked exhaustively around the
thresholds and ties, and on random residuals, against Table 1 written clause by
clause (``tests/naive.py::signature_ref``).
"""

from __future__ import annotations

from ...conventions import (ELEVON_BLOCK, NO_RESET, RESET_ELEVONS,  # noqa: F401
                           RESET_THRUST, THRUST_BLOCK)
from ..jit import kernel


@kernel(internal=True)
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


@kernel(inline="always")
def signature_lanes(res, det, block):
    """Which covariance block Table 1 resets, on every lane, from its data.

    Each lane's hit pattern (bit ``i`` set when channel ``i`` reached its
    threshold), computed a channel at a time so the loops vectorise over the
    lanes; then its row ``(block_if, block_else, cmp_a, cmp_b)`` of the
    decision table: ``block_if`` when ``cmp_a < 0`` or ``r[cmp_a] >=
    r[cmp_b]``, else ``block_else`` (``conventions.TABLE1``: the module
    docstring's rules, per variant).  The decision is written out here, not
    called per lane: a call that passes arrays costs two reference-count
    updates per lane, which made this stage 150 times slower
    (``docs/findings/performance.md``, lesson 12).

    Parameters
    ----------
    res : ndarray, shape (3, L)
        Normalised residuals ``[r_q, r_nx, r_nz]`` of every lane (eqs. 9-11).
    det : Detection
        ``thresholds`` (3,): each channel's (paper: 25, 25; ``inf`` for
        ``r_nz``, which is only compared); ``table`` (8, 4) int64: the
        variant's decision table.
    block : ndarray of int64, shape (L,)
        Written with ``NO_RESET``, ``RESET_THRUST`` or ``RESET_ELEVONS``.
    """
    thresholds = det.thresholds
    table = det.table
    L = res.shape[1]
    for l in range(L):
        block[l] = 0
    for i in range(thresholds.shape[0]):
        t = thresholds[i]
        bit = 1 << i
        for l in range(L):
            if res[i, l] >= t:
                block[l] |= bit
    for l in range(L):
        p = block[l]
        a = table[p, 2]
        if a < 0 or res[a, l] >= res[table[p, 3], l]:
            block[l] = table[p, 0]
        else:
            block[l] = table[p, 1]
