"""Work arrays of the lane-interleaved filter kernels (:mod:`ftc_mc.core.longitudinal.batch`).

The benchmark (``scripts/benchmarks/bench_core.py``) and the tests of the lane filter
use them; the trial loop has its own (``core/longitudinal/workspace.py``).

Alignment matters: the kernels load and store 64-byte vectors along the lane
axis, and a lane row that does not start on a 64-byte boundary splits every
vector access over two cache lines.  Measured with ``filter_step_lanes`` at 96
lanes: 1.68 M steps/s with the work arrays 64-byte aligned, 1.33 M with NumPy's
default (16-byte) placement.  So every array here is 64-byte aligned, and with
``L`` a multiple of 8 every lane row is too; allocate the lane arrays of the
state (``xa``, ``P``, ``u``, ``z``) with :func:`ftc_mc.sim.lanes.lane_zeros`, which
the trial loop's lane state uses too, for the same reason.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ftc_mc.conventions import N_AUG, N_FAULT, N_X, RESIDUAL_NAMES
from ftc_mc.core.longitudinal.batch import step_rows
from ftc_mc.sim.lanes import lane_zeros

LaneWorkspace = namedtuple("LaneWorkspace", [
    "phi",    # (9, 5, L)             Phi(u) of each lane (predict)
    "T",      # (9, n, L)             [A Phi] P (predict)
    "work",   # (step_rows(n), n, L)  P_{k+1|k}, the update's gains, x_{k|k}
    "res",    # (3, L)                [r_q, r_nx, r_nz] (eqs. 9-11)
    "block",  # (L,) int64            block reset this step (Table 1)
])
"""Arrays for :func:`ftc_mc.core.longitudinal.batch.filter_step_lanes`, in its argument order:
``filter_step_lanes(xa, P, u, z, fm, det, ws.phi, ws.T, ws.work, ws.res, ws.block)``."""


def new_lane_workspace(L: int, n_aug: int = N_AUG) -> LaneWorkspace:
    """Zeroed, 64-byte aligned work arrays for ``L`` lanes.

    Parameters
    ----------
    L : int
        Number of lanes (trajectories advanced together), >= 1; a multiple of 8
        keeps every lane row aligned (64 to 192 lanes run fastest).
    n_aug : int, optional
        Augmented dimension of the filter (default the paper's 14).

    Returns
    -------
    LaneWorkspace
        ``phi`` (9, 5, L), ``T`` (9, n, L), ``work`` (step_rows(n), n, L),
        ``res`` (3, L) float64 and ``block`` (L,) int64.  ``work[n:n + 13]``
        can serve as the work array ``h`` of
        :func:`~ftc_mc.core.longitudinal.batch.update_lanes`.

    Raises
    ------
    ValueError
        If ``L`` is not a positive integer.
    """
    if isinstance(L, bool) or not isinstance(L, (int, np.integer)) or L < 1:
        raise ValueError(f"lane count 'L' must be an integer >= 1, got {L!r}")
    L = int(L)
    n = int(n_aug)
    return LaneWorkspace(phi=lane_zeros((N_X, N_FAULT, L)), T=lane_zeros((N_X, n, L)),
                         work=lane_zeros((step_rows.py_func(n), n, L)),
                         res=lane_zeros((len(RESIDUAL_NAMES), L)),
                         block=lane_zeros(L, dtype=np.int64))
