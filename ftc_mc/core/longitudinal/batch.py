"""Many independent augmented filters at once, lane-interleaved (paper eqs. 5-11).

Each kernel here is the lane-wise twin of a single-trajectory kernel of
``tests/single_trajectory.py``, :mod:`ftc_mc.core.longitudinal.signature` and
``tests/single_trajectory.py::filter_step``: lane ``l`` of every array is one trajectory, stored with
the lane index *last* (``xa[n, L]``, ``P[n, n, L]``, ``u[3, L]``, ``z[12, L]``;
``n = 14`` for the paper's filter, taken from the arrays' shapes)
so that the innermost loops run over lanes and compile to 512-bit vector code
(2.3x the best per-trajectory layout when measured; ``scripts/benchmarks/bench_core.py``).
``L`` is a run-time shape.

Every lane is computed with the same floating-point operations, in the same
order, as the single-trajectory kernel, so a lane agrees with
``tests/single_trajectory.py::filter_step`` bit for bit (fastmath stays off).  What
differs is only the order in which *independent* results are produced:

* lane-invariant coefficients (rows of ``A``, ``C``) are copied into tuples
  before a lane loop, so the loop reads them from registers and the vectoriser
  needs few run-time alias checks;
* ``T = [A Phi] P`` is formed three rows at a time and ``P_xx`` three rows at
  a time (entry ``(i, k)`` stored at ``[k, i]``, then mirrored), each loaded
  ``P``/``T`` entry feeding three products.  Loops that store to several
  entries of one array only vectorise when those entries differ in the *first*
  index (LLVM rejects unknown distances along the others), hence the layouts;
* the update keeps only the upper triangle of ``P`` while it works and mirrors
  once at the end.  Consecutive unit rows of ``C`` (the first six outputs) are
  taken as one group: their gains are formed lazily from the group's starting
  ``P`` (``h_q = P_{q-1}[:, s_q]`` with the earlier rank-one terms subtracted
  in the sequential order), then all the group's rank-one terms are applied in
  one pass over the triangle.  The dense rows are processed one at a time as
  in the single kernel;
* a reset re-predicts from ``P_{k|k}``, which stays in ``P`` (the prediction
  goes to a work array), only for the lanes that reset when they are few.

Measured on the paper's problem, one core (``scripts/benchmarks/bench_core.py``): about
1.6-1.7 M filter steps/s at 64-192 lanes, about 4x ``step.filter_step``.  The
lane rows should start on 64-byte boundaries (``tests/lane_workspace.py::lane_zeros``,
``L`` a multiple of 8): NumPy's default placement cost 20 % here.

Work arrays are passed in (``tests/lane_workspace.py::new_lane_workspace`` in the tests and the benchmark),
so no kernel allocates.
"""

from __future__ import annotations

import numpy as np

from ..jit import kernel
from .signature import NO_RESET, in_block, signature_lanes

from ...conventions import N_AUG, N_B0, N_B1, N_U, N_X, RESIDUAL_OUTPUTS
from ...conventions import N_FAULT as N_F

# Lane-invariant rows are read into tuples of a fixed length (_row_x, _row_b0,
# _row_b, _neg_row_b): a tuple's length must be written out, so these helpers are the
# one place that spells the plant's dimensions, checked here.
assert (N_X, N_B0, N_B1, N_U) == (9, 2, 3, 3), "update the _row_* helpers"

GROUP = 6
"""Unit rows of ``C`` updated per pass (longer runs are split, shorter padded)."""

UPDATE_ROWS = 2 * GROUP + 1
"""First dimension of the update's work array ``h[UPDATE_ROWS, n, L]``."""


@kernel(internal=True)
def step_rows(n_aug):
    """First dimension of :func:`filter_step_lanes`' work array
    ``work[step_rows(n), n, L]``: the prediction (``n`` rows), the update's
    gains (``UPDATE_ROWS``) and ``x_{k|k}`` (one row)."""
    return n_aug + UPDATE_ROWS + 1


STEP_ROWS = step_rows.py_func(N_AUG)
"""``step_rows`` of the paper's filter (``N_AUG = 14`` states)."""

SERIAL_REPREDICT = 8
"""Up to this many reset lanes are re-predicted one run of lanes at a time;
more re-predict every lane (identical results for the lanes without a reset)."""


# ------------------------------------------------------------------ helpers
@kernel(internal=True)
def _row_x(M, i):
    """Row ``i`` of a ``(m, N_X)`` matrix as a tuple (lane-invariant coefficients)."""
    return (M[i, 0], M[i, 1], M[i, 2], M[i, 3], M[i, 4], M[i, 5], M[i, 6], M[i, 7],
            M[i, 8])


@kernel(internal=True)
def _row_b0(M, i):
    """Row ``i`` of a ``(m, N_B0)`` matrix as a tuple (``B_b0``, eq. 4)."""
    return (M[i, 0], M[i, 1])


@kernel(internal=True)
def _row_b(M, i):
    """Row ``i`` of a ``(m, N_U)`` matrix as a tuple (``B_i``, eq. 1)."""
    return (M[i, 0], M[i, 1], M[i, 2])


@kernel(internal=True)
def _neg_row_b(M, i):
    """Negated row ``i`` of a ``(m, N_U)`` matrix as a tuple (``-B_i``, eq. 4)."""
    return (-M[i, 0], -M[i, 1], -M[i, 2])


@kernel(internal=True)
def _mirror(P, l0, l1):
    """Copy the upper triangle of ``P[:, :, l0:l1]`` onto the lower one."""
    n = P.shape[0]
    for i in range(n):
        for k in range(i + 1, n):
            for l in range(l0, l1):
                P[k, i, l] = P[i, k, l]


@kernel(internal=True)
def _mirror_x(P, l0, l1):
    """Copy the upper triangle of the plant-state block ``P[:9, :9]`` downwards."""
    for i in range(N_X):
        for k in range(i + 1, N_X):
            for l in range(l0, l1):
                P[k, i, l] = P[i, k, l]


@kernel(internal=True)
def _symmetric_copy(P, Pout, L):
    """``Pout <- P`` from the upper triangle of ``P`` (both triangles written)."""
    n = P.shape[0]
    for i in range(n):
        for k in range(i, n):
            for l in range(L):
                Pout[i, k, l] = P[i, k, l]
        for k in range(i + 1, n):
            for l in range(L):
                Pout[k, i, l] = P[i, k, l]


# ------------------------------------------------------------------ predict
ALL_LANES_FROM = 0
"""First lane of a prediction over every lane: the literal ``0``, on purpose.
Numba types a literal argument as a signature of its own, so the by-address
:func:`_predict` is compiled twice, specialised on the first lane ``0`` for
every step's prediction and the selection's, and for any first lane for the
serial re-prediction of a run of lanes that reset (1.6-1.8 s of the default
path's cold compile).  The specialised copy is the fast one: with an int64
first lane everywhere ``configs/paper_tables.yaml`` (1000 trials a row, ``--jobs
2``) ran at 0.76-0.78 M trial steps/s nominal against 1.05-1.12 M with it, and
0.41 M reconfiguring against 0.61 M (``docs/findings/performance.md``,
lesson 20)."""


@kernel(inline="always")
def _predict_state(xa, u, fm, phi, T, l0, l1):
    """The state half of eq. (5) on lanes ``l0:l1``: ``phi <- Phi(u)`` and
    ``x <- A x + B u + Phi(u) b`` in place (``b`` unchanged, a random walk,
    eq. 3), with ``T[:9, 0]`` as scratch.  :func:`_predict` and
    :func:`predict_state_lanes` both run it, so the two agree to the bit."""
    u00 = fm.u0[0]
    u01 = fm.u0[1]
    u02 = fm.u0[2]
    # Phi(u) = [B_b0, B diag(-u - u0)] (eqs. 4-5), kept for the caller; the
    # products of _predict recompute it
    for i in range(N_X):
        bb = _row_b0(fm.Bb0, i)
        nb = _neg_row_b(fm.B, i)
        for l in range(l0, l1):
            phi[i, 0, l] = bb[0]
            phi[i, 1, l] = bb[1]
            phi[i, N_B0, l] = nb[0] * (u[0, l] + u00)
            phi[i, N_B0 + 1, l] = nb[1] * (u[1, l] + u01)
            phi[i, N_B0 + 2, l] = nb[2] * (u[2, l] + u02)
    # state: x <- A x + B u + Phi b ; b unchanged (random walk, eq. 3)
    for i in range(N_X):
        a = _row_x(fm.A, i)
        b = _row_b(fm.B, i)
        for l in range(l0, l1):
            acc = 0.0
            for j in range(N_X):
                acc += a[j] * xa[j, l]
            for j in range(N_U):
                acc += b[j] * u[j, l]
            for j in range(N_F):
                acc += phi[i, j, l] * xa[N_X + j, l]
            T[i, 0, l] = acc
    for i in range(N_X):
        for l in range(l0, l1):
            xa[i, l] = T[i, 0, l]


@kernel(by_address=True)
def _predict(xa, P, Pn, u, fm, phi, T, l0, l1):
    """Eq. (5) on lanes ``l0:l1``: ``Pn <- A_aug P A_aug^T + Q`` (``Pn`` may be ``P``).

    Reads the full symmetric ``P`` and writes the full symmetric ``Pn``; ``xa``
    is advanced in place.  Operation order per lane as in
    ``tests/single_trajectory.py::predict``.
    """
    n = P.shape[0]
    _predict_state(xa, u, fm, phi, T, l0, l1)
    # T = [A Phi] P, three rows of A_aug at a time
    for i in range(0, N_X, 3):
        a0 = _row_x(fm.A, i)
        a1 = _row_x(fm.A, i + 1)
        a2 = _row_x(fm.A, i + 2)
        for c in range(n):
            for l in range(l0, l1):
                acc0 = 0.0
                acc1 = 0.0
                acc2 = 0.0
                for j in range(N_X):
                    p = P[j, c, l]
                    acc0 += a0[j] * p
                    acc1 += a1[j] * p
                    acc2 += a2[j] * p
                for j in range(N_F):
                    p = P[N_X + j, c, l]
                    acc0 += phi[i, j, l] * p
                    acc1 += phi[i + 1, j, l] * p
                    acc2 += phi[i + 2, j, l] * p
                T[i, c, l] = acc0
                T[i + 1, c, l] = acc1
                T[i + 2, c, l] = acc2
    # P_bb unchanged (copied when predicting out of place)
    for i in range(N_X, n):
        for k in range(i, n):
            for l in range(l0, l1):
                Pn[i, k, l] = P[i, k, l]
    # P_xx = T_x A^T + T_b Phi^T, entry (i, k) stored at [k, i] for three k
    # at a time (one T_i row load feeds three products); every block that
    # reaches the lower triangle of column i is formed (its entries right of
    # the diagonal are overwritten when the lower triangle is mirrored up)
    for k in range(0, N_X, 3):
        a0 = _row_x(fm.A, k)
        a1 = _row_x(fm.A, k + 1)
        a2 = _row_x(fm.A, k + 2)
        for i in range(k + 3):
            for l in range(l0, l1):
                acc0 = 0.0
                acc1 = 0.0
                acc2 = 0.0
                for j in range(N_X):
                    t = T[i, j, l]
                    acc0 += t * a0[j]
                    acc1 += t * a1[j]
                    acc2 += t * a2[j]
                for j in range(N_F):
                    t = T[i, N_X + j, l]
                    acc0 += t * phi[k, j, l]
                    acc1 += t * phi[k + 1, j, l]
                    acc2 += t * phi[k + 2, j, l]
                Pn[k, i, l] = acc0
                Pn[k + 1, i, l] = acc1
                Pn[k + 2, i, l] = acc2
    # P_xb = T_b
    for i in range(N_X):
        for j in range(N_F):
            for l in range(l0, l1):
                Pn[i, N_X + j, l] = T[i, N_X + j, l]
    for i in range(n):
        qi = fm.q_diag[i]
        for l in range(l0, l1):
            Pn[i, i, l] += qi
    for i in range(N_X):
        for k in range(i + 1, N_X):
            for l in range(l0, l1):
                Pn[i, k, l] = Pn[k, i, l]
        for k in range(N_X, n):
            for l in range(l0, l1):
                Pn[k, i, l] = Pn[i, k, l]
    for i in range(N_X, n):
        for k in range(i + 1, n):
            for l in range(l0, l1):
                Pn[k, i, l] = Pn[i, k, l]


@kernel(inline="always")
def predict_lanes(xa, P, u, fm, phi, T):
    """Time update of every lane (eq. 5), as ``tests/single_trajectory.py::predict``.

    ``X <- A_aug(u) X + B_aug u`` and ``P <- A_aug(u) P A_aug(u)^T + Q`` with
    ``A_aug(u) = [[A, Phi(u)], [0, I]]``, ``Phi(u) = [B_b0, B diag(-u - u0)]``;
    only ``P_xx`` and ``P_xb`` change besides the diagonal ``Q``.

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Augmented estimates, updated in place.
    P : ndarray, shape (n, n, L)
        Covariances, symmetric, updated in place (stay exactly symmetric).
    u : ndarray, shape (3, L)
        Command deviations from trim applied during the step.
    fm : FilterModel
    phi : ndarray, shape (9, 5, L)
        Work array; holds ``Phi(u)`` of each lane on return.
    T : ndarray, shape (9, n, L)
        Work array.
    """
    _predict(xa, P, P, u, fm, phi, T, ALL_LANES_FROM, xa.shape[1])


@kernel(inline="always")
def predict_state_lanes(xa, u, fm, phi, T):
    """The state half of :func:`predict_lanes` (eq. 5) without the covariance:
    ``X <- A_aug(u) X + B_aug u``, bit for bit the state :func:`predict_lanes`
    leaves.  The controller selection predicts its short-horizon costs with it
    (:func:`ftc_mc.core.longitudinal.control.controller_objectives_lanes`).

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Augmented estimates, updated in place.
    u : ndarray, shape (3, L)
        Command deviations from trim applied during the step.
    fm : FilterModel
    phi : ndarray, shape (9, 5, L)
        Work array; holds ``Phi(u)`` of each lane on return.
    T : ndarray, shape (9, n, L)
        Work array.
    """
    _predict_state(xa, u, fm, phi, T, ALL_LANES_FROM, xa.shape[1])


# ------------------------------------------------------------------ residuals
@kernel(internal=True)
def _normalised_lanes(xa, P, z, fm, out, signed):
    """``mu_i^2 / S_ii`` (``signed`` false) or ``mu_i / sqrt(S_ii)`` (true) of the
    residual outputs of every lane into ``out`` (3, L); see :func:`residuals_lanes`.

    One loop body for both, so the two agree on ``mu_i`` and ``S_ii`` to the bit;
    ``signed`` is a constant in each caller, so the branch leaves the lane loop.
    """
    L = xa.shape[1]
    for o in range(len(RESIDUAL_OUTPUTS)):
        r = RESIDUAL_OUTPUTS[o]
        s_idx = fm.c_ident[r]
        rr = fm.r_diag[r]
        if s_idx >= 0:
            for l in range(L):
                mu = z[r, l] - xa[s_idx, l]
                s = P[s_idx, s_idx, l] + rr
                if signed:
                    out[o, l] = mu / np.sqrt(s)
                else:
                    out[o, l] = mu * mu / s
        else:
            c = _row_x(fm.C, r)
            for l in range(L):
                pred = 0.0
                s = 0.0
                for j in range(N_X):
                    pred += c[j] * xa[j, l]
                    acc = 0.0
                    for k in range(N_X):
                        acc += P[j, k, l] * c[k]
                    s += c[j] * acc
                mu = z[r, l] - pred
                s = s + rr
                if signed:
                    out[o, l] = mu / np.sqrt(s)
                else:
                    out[o, l] = mu * mu / s


@kernel(inline="always")
def residuals_lanes(xa, P, z, fm, res):
    """Normalised residuals ``r_q, r_nx, r_nz`` of every lane (eqs. 9-11).

    As ``tests/single_trajectory.py::residuals``: ``r_i = mu_i^2 / (C_i P C_i^T + R_ii)``
    on the prediction.

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Predicted augmented states ``X_{k+1|k}``.
    P : ndarray, shape (n, n, L)
        Predicted covariances ``P_{k+1|k}`` (symmetric).
    z : ndarray, shape (12, L)
        Measurement deviations from the trim outputs.
    fm : FilterModel
    res : ndarray, shape (3, L)
        Written with ``[r_q, r_nx, r_nz]`` of each lane (outputs
        :data:`ftc_mc.conventions.RESIDUAL_OUTPUTS`).
    """
    _normalised_lanes(xa, P, z, fm, res, False)


@kernel(inline="always")
def innovations_lanes(xa, P, z, fm, innov):
    """Signed normalised innovations ``mu_i / sqrt(S_ii)`` of every lane, on the
    same prediction as :func:`residuals_lanes` (``r_i = innov_i^2`` up to
    rounding); the GLR test reads them (:mod:`ftc_mc.core.shared.glr`).

    Apart from :func:`residuals_lanes` because the paper's one-step test does
    not need them: written in the same lane loop, they cost 8-15 % of
    :func:`filter_step_lanes` (``scripts/benchmarks/bench_core.py``, 64-128 lanes).

    Parameters
    ----------
    xa, P, z, fm
        As :func:`residuals_lanes`.
    innov : ndarray, shape (3, L)
        Written with the signed normalised innovations.
    """
    _normalised_lanes(xa, P, z, fm, innov, True)


# ------------------------------------------------------------------ signature
@kernel(internal=True)
def reset_lanes(P, block, reset_var):
    """Reset the suspected fault block of each lane (section 3.2.2).

    As :func:`ftc_mc.core.longitudinal.signature.reset_covariance` per lane: the rows and
    columns of the block's fault parameters are zeroed and their variances set
    to ``reset_var``.

    Parameters
    ----------
    P : ndarray, shape (n, n, L)
        Covariances, updated in place.
    block : ndarray of int64, shape (L,)
        Block per lane: ``NO_RESET``, ``RESET_THRUST`` (``{b0_T, b1_T}``) or
        ``RESET_ELEVONS`` (``{b0_e, b1_L, b1_R}``); other codes reset nothing.
    reset_var : ndarray, shape (5,)
        Variance of each fault parameter after its block is reset.
    """
    n = P.shape[0]
    L = P.shape[2]
    for l in range(L):
        b = block[l]
        if b != NO_RESET:
            for j in range(N_F):
                if in_block(j, b):
                    i = N_X + j
                    for k in range(n):
                        P[i, k, l] = 0.0
                        P[k, i, l] = 0.0
                    P[i, i, l] = reset_var[j]


# ------------------------------------------------------------------ update
@kernel(inline="always")
def _unit_group(xa, P, z, fm, hk, vk, gs, r0, q_max):
    """Sequential updates with the unit rows ``r0 .. r0+q-1`` of ``C`` (q <= GROUP).

    The gains are formed lazily: ``h_q = P_{q-1}[:, s_q]`` where each entry of
    ``P_{q-1}`` is the group's starting upper-triangle entry minus the earlier
    rank-one terms ``(h_k[a] / s_k) h_k[b]`` (``a <= b``) in order, which are the
    very operations the single kernel applies to ``P`` one row at a time; the
    state is advanced the same way.  Then one pass over the upper triangle
    subtracts all rank-one terms in order.  Returns ``q``.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    n_z = z.shape[0]
    q = 0
    while q < q_max and r0 + q < n_z and fm.c_ident[r0 + q] >= 0:
        r = r0 + q
        s = fm.c_ident[r]
        rr = fm.r_diag[r]
        for a in range(n):
            lo = min(a, s)
            hi = max(a, s)
            for l in range(L):
                hk[q, a, l] = P[lo, hi, l]
            for k in range(q):
                for l in range(L):
                    hk[q, a, l] -= vk[k, lo, l] * hk[k, hi, l]
        # gs[q] = gain g_q = mu_q / s_q ; gs[GROUP + q] = 1 / s_q
        for l in range(L):
            gs[q, l] = xa[s, l]
        for k in range(q):
            for l in range(L):
                gs[q, l] += hk[k, s, l] * gs[k, l]
        for l in range(L):
            sv = rr + hk[q, s, l]
            gs[q, l] = (z[r, l] - gs[q, l]) / sv
            gs[GROUP + q, l] = 1.0 / sv
        for a in range(n):
            for l in range(L):
                vk[q, a, l] = hk[q, a, l] * gs[GROUP + q, l]
        q += 1
    for k in range(q, GROUP):
        for a in range(n):
            for l in range(L):
                vk[k, a, l] = 0.0
                hk[k, a, l] = 0.0
    for k in range(q):
        for a in range(n):
            for l in range(L):
                xa[a, l] += hk[k, a, l] * gs[k, l]
    for a in range(n):
        for b in range(a, n):
            for l in range(L):
                acc = P[a, b, l]
                for k in range(GROUP):
                    acc -= vk[k, a, l] * hk[k, b, l]
                P[a, b, l] = acc
    return q


@kernel(inline="always")
def _dense_row(xa, P, z, fm, h, v, gs, r):
    """Scalar update with a dense row ``r`` of ``C`` (upper triangle of ``P`` kept)."""
    n = xa.shape[0]
    L = xa.shape[1]
    rr = fm.r_diag[r]
    c = _row_x(fm.C, r)
    _mirror_x(P, 0, L)
    for a in range(N_X):
        for l in range(L):
            acc = 0.0
            for j in range(N_X):
                acc += P[a, j, l] * c[j]
            h[a, l] = acc
    for a in range(N_X, n):
        for l in range(L):
            acc = 0.0
            for j in range(N_X):
                acc += P[j, a, l] * c[j]
            h[a, l] = acc
    for l in range(L):
        pred = 0.0
        for j in range(N_X):
            pred += c[j] * xa[j, l]
        sv = rr
        for j in range(N_X):
            sv += c[j] * h[j, l]
        gs[0, l] = (z[r, l] - pred) / sv
        gs[1, l] = 1.0 / sv
    for a in range(n):
        for l in range(L):
            xa[a, l] += h[a, l] * gs[0, l]
    for a in range(n):
        for l in range(L):
            v[a, l] = h[a, l] * gs[1, l]
    for a in range(n):
        for b in range(a, n):
            for l in range(L):
                P[a, b, l] -= v[a, l] * h[b, l]


@kernel(by_address=True)
def _update(xa, P, z, fm, h):
    """The sequential scalar updates, one per output, on the upper triangle of
    ``P`` (no mirror)."""
    hk = h[0:GROUP]
    vk = h[GROUP:2 * GROUP]
    gs = h[2 * GROUP]
    r = 0
    while r < z.shape[0]:
        if fm.c_ident[r] >= 0:
            r += _unit_group(xa, P, z, fm, hk, vk, gs, r, GROUP)
        else:
            _dense_row(xa, P, z, fm, hk[0], vk[0], gs, r)
            r += 1


@kernel(inline="always")
def update_lanes(xa, P, z, fm, h):
    """Measurement update of every lane with its 12 outputs (eq. 5, R diagonal).

    As ``tests/single_trajectory.py::update``: one scalar update per output,
    ``h = P c^T``, ``s = c h + R_rr``, ``X += h (z_r - c X) / s``,
    ``P -= (h / s) h^T``; a unit row of ``C`` (``fm.c_ident[r] >= 0``) reads a
    column of ``P`` instead of multiplying.  ``P`` stays exactly symmetric.

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Updated in place.
    P : ndarray, shape (n, n, L)
        Updated in place.
    z : ndarray, shape (12, L)
        Measurement deviations from the trim outputs.
    fm : FilterModel
    h : ndarray, shape (UPDATE_ROWS, n, L)
        Work array (``UPDATE_ROWS = 13``).
    """
    _update(xa, P, z, fm, h)
    _mirror(P, 0, xa.shape[1])


# ------------------------------------------------------------------ projection
@kernel(internal=True)
def project_lanes(xa, fm):
    """Active-set projection of every lane's fault parameters (eqs. 6-8).

    As ``tests/single_trajectory.py::project``: each violated bound of
    ``lo <= b <= hi`` becomes an equality, which sets that parameter to its
    bound; ``P`` is not projected (semi-closed loop, Fig. 2).

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Updated in place.
    fm : FilterModel
    """
    L = xa.shape[1]
    for j in range(N_F):
        lo = fm.lo[j]
        hi = fm.hi[j]
        for l in range(L):
            v = xa[N_X + j, l]
            xa[N_X + j, l] = lo if v < lo else (hi if v > hi else v)


# ------------------------------------------------------------------ step
@kernel(inline="always")
def filter_predict_lanes(xa, P, u, z, fm, phi, T, work, res):
    """First half of :func:`filter_step_lanes`: predict (eq. 5) into ``work[:n]``
    and the residuals (eqs. 9-11); ``x_{k|k}`` is kept in ``work`` for a re-prediction.

    ``xa`` holds ``X_{k+1|k}`` on return, ``P`` still ``P_{k|k}`` and
    ``work[:n]`` ``P_{k+1|k}`` (for :func:`innovations_lanes`).  Parameters as
    :func:`filter_step_lanes`.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    Pn = work[0:n]
    x_prev = work[n + UPDATE_ROWS]
    for i in range(N_X):
        for l in range(L):
            x_prev[i, l] = xa[i, l]
    _predict(xa, P, Pn, u, fm, phi, T, ALL_LANES_FROM, L)
    residuals_lanes(xa, Pn, z, fm, res)


@kernel(inline="always")
def filter_correct_lanes(xa, P, u, z, fm, det, phi, T, work, block):
    """Second half of :func:`filter_step_lanes`, once ``block`` is decided: reset
    and re-predict the lanes that reset, update, projection.  Parameters as
    :func:`filter_step_lanes`."""
    n = xa.shape[0]
    L = xa.shape[1]
    Pn = work[0:n]
    h = work[n:n + UPDATE_ROWS]
    x_prev = work[n + UPDATE_ROWS]
    n_reset = 0
    for l in range(L):
        if block[l] != 0:
            n_reset += 1
    if n_reset > 0:
        reset_lanes(P, block, det.reset_var)
        for l in range(L):
            if block[l] != 0:
                for i in range(N_X):
                    xa[i, l] = x_prev[i, l]
        if n_reset > SERIAL_REPREDICT:
            for l in range(L):
                if block[l] == 0:
                    for i in range(N_X):
                        xa[i, l] = x_prev[i, l]
            _predict(xa, P, Pn, u, fm, phi, T, ALL_LANES_FROM, L)
        else:
            l = 0
            while l < L:
                if block[l] != 0:
                    l1 = l + 1
                    while l1 < L and block[l1] != 0:
                        l1 += 1
                    _predict(xa, P, Pn, u, fm, phi, T, l, l1)
                    l = l1
                else:
                    l += 1
    _update(xa, Pn, z, fm, h)
    _symmetric_copy(Pn, P, L)
    project_lanes(xa, fm)


@kernel(internal=True)
def filter_step_lanes(xa, P, u, z, fm, det, phi, T, work, res, block):
    """Advance every lane's filter by one sampling period, as
    ``tests/single_trajectory.py::filter_step``.

    Per lane: predict (eq. 5); residuals (eqs. 9-11); Table 1 signature; on a
    reset, reset the block of ``P_{k|k}`` (section 3.2.2) and predict again from
    it; measurement update; projection of the fault parameters (eqs. 6-8).
    The halves :func:`filter_predict_lanes` and :func:`filter_correct_lanes`
    let a windowed test decide the block in between (``core/longitudinal/stages.py``).

    ``P_{k|k}`` stays in ``P`` while the prediction goes to ``work[:n]``, so
    the lanes that reset are re-predicted without a copy of ``P``: up to
    ``SERIAL_REPREDICT`` of them run by run of adjacent lanes, more by
    predicting every lane again (bit-identical for the others).

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        Augmented estimates, updated in place (``n = 14`` in the paper).
    P : ndarray, shape (n, n, L)
        Covariances, updated in place (exactly symmetric).
    u : ndarray, shape (3, L)
        Command deviations applied during the step.
    z : ndarray, shape (12, L)
        Measurement deviations from trim outputs at the end of the step.
    fm : FilterModel
    det : Detection
    phi, T : ndarray
        Work arrays of shapes (9, 5, L) and (9, n, L) (more rows allowed).
    work : ndarray, shape (step_rows(n), n, L)
        Work array (``STEP_ROWS = 28`` rows for the paper's filter).
    res : ndarray, shape (3, L)
        Written with ``[r_q, r_nx, r_nz]`` on the first prediction.
    block : ndarray of int64, shape (L,)
        Written with the block reset this step per lane (0 if none).
    """
    filter_predict_lanes(xa, P, u, z, fm, phi, T, work, res)
    signature_lanes(res, det, block)
    filter_correct_lanes(xa, P, u, z, fm, det, phi, T, work, block)
