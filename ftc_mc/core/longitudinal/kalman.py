"""Augmented Kalman filter of one trajectory (paper eqs. 5-11), structure-exploiting.

Augmented state ``X = [x (9), b0 (2), b1 (3)]`` (indices in
:mod:`ftc_mc.conventions`; the kernels take the augmented dimension ``n`` from
the arrays' shapes, so a design with more states appended after the fault
parameters keeps these kernels) with
``A_aug(u) = [[A, Phi(u)], [0, I]]``, ``Phi(u) = [B_b0, B diag(-u - u0)]`` and
``C_aug = [C, 0]`` (eq. 5).  The kernels never form ``A_aug`` or ``C_aug``:

* predict: ``T = [A Phi] P[:9, :]`` (9 x 14), then ``P_xx = T[:, :9] A^T +
  T[:, 9:] Phi^T``, ``P_xb = T[:, 9:]``, ``P_bb`` unchanged, plus the diagonal Q;
* update: ``R`` is diagonal, so the 12 measurements are processed one at a time
  (sequential scalar updates, algebraically identical to the batch update);
  unit rows of ``C`` (the first six outputs) cost no multiply at all;
* only the upper triangle of ``P`` is computed, then mirrored, so ``P`` stays
  exactly symmetric.

All arrays are float64; work arrays come from the caller so no kernel allocates.
"""

from __future__ import annotations

from ...conventions import N_AUG, N_B0, N_B1, N_U, N_X, RESIDUAL_OUTPUTS
from ...conventions import N_FAULT as N_F
from ..jit import kernel


@kernel
def _paper_dim(xa):
    """``N_AUG``, the augmented dimension of the paper's filter, after checking it.

    The loops of :func:`predict` and :func:`update` run to this compile-time
    constant: with the dimension read from the array instead, the controller
    selection (which predicts with these kernels) ran 19 % slower.  A filter
    of another dimension gets a clear error here rather than wrong numbers.
    """
    if xa.shape[0] != N_AUG:
        raise ValueError("core.longitudinal.kalman: the augmented state must have N_AUG entries")
    return N_AUG


@kernel
def fault_matrix(fm, u, phi):
    """``Phi(u) = [B_b0, B diag(-u - u0)]`` (eqs. 4-5).

    Parameters
    ----------
    fm : FilterModel
    u : ndarray, shape (3,)
        Command deviation applied during the step.
    phi : ndarray, shape (9, 5)
        Written with Phi.
    """
    for i in range(N_X):
        for j in range(N_B0):
            phi[i, j] = fm.Bb0[i, j]
        for j in range(N_B1):
            phi[i, N_B0 + j] = -fm.B[i, j] * (u[j] + fm.u0[j])


@kernel
def predict(xa, P, u, fm, phi, T):
    """Time update ``X <- A_aug X + B_aug u``, ``P <- A_aug P A_aug^T + Q`` (eq. 5).

    Parameters
    ----------
    xa : ndarray, shape (n,)
        Augmented state estimate, updated in place (``n = 14`` in the paper).
    P : ndarray, shape (n, n)
        Covariance, symmetric, updated in place.
    u : ndarray, shape (3,)
        Command deviation from trim applied during the step.
    fm : FilterModel
    phi : ndarray, shape (9, 5)
        Work array.
    T : ndarray, shape (9, n)
        Work array.
    """
    n = _paper_dim(xa)
    fault_matrix(fm, u, phi)
    # state: x <- A x + B u + Phi b ; b unchanged (random walk, eq. 3)
    for i in range(N_X):
        acc = 0.0
        for j in range(N_X):
            acc += fm.A[i, j] * xa[j]
        for j in range(N_U):
            acc += fm.B[i, j] * u[j]
        for j in range(N_F):
            acc += phi[i, j] * xa[N_X + j]
        T[i, 0] = acc
    for i in range(N_X):
        xa[i] = T[i, 0]
    # T = [A Phi] P[:, :]  (rows 0..8 of A_aug times P), a row at a time: each
    # T[i, c] sums its terms from 0.0 in the same order as a dot product would
    # (bit-identical), and the loop over c vectorises
    for i in range(N_X):
        a = fm.A[i, 0]
        for c in range(n):
            T[i, c] = 0.0 + a * P[0, c]
        for j in range(1, N_X):
            a = fm.A[i, j]
            for c in range(n):
                T[i, c] += a * P[j, c]
        for j in range(N_F):
            f = phi[i, j]
            for c in range(n):
                T[i, c] += f * P[N_X + j, c]
    # P_xx = T_x A^T + T_b Phi^T (upper triangle), P_xb = T_b
    for i in range(N_X):
        for k in range(i, N_X):
            acc = 0.0
            for j in range(N_X):
                acc += T[i, j] * fm.A[k, j]
            for j in range(N_F):
                acc += T[i, N_X + j] * phi[k, j]
            P[i, k] = acc
        for j in range(N_F):
            P[i, N_X + j] = T[i, N_X + j]
    for i in range(n):
        P[i, i] += fm.q_diag[i]
        for k in range(i + 1, n):
            P[k, i] = P[i, k]


@kernel
def innovation(xa, P, z, fm, r):
    """Innovation ``mu_r`` and its variance ``C_r P C_r^T + R_rr`` of output ``r``.

    Parameters
    ----------
    xa : ndarray, shape (n,)
    P : ndarray, shape (n, n)
        Predicted covariance ``P_{k+1|k}``.
    z : ndarray, shape (12,)
        Measurement (deviation from the trim outputs).
    fm : FilterModel
    r : int
        Output index.

    Returns
    -------
    (float, float)
        ``mu_r`` and ``s_r``.
    """
    s_idx = fm.c_ident[r]
    if s_idx >= 0:
        return z[r] - xa[s_idx], P[s_idx, s_idx] + fm.r_diag[r]
    pred = 0.0
    s = 0.0
    for j in range(N_X):
        cj = fm.C[r, j]
        pred += cj * xa[j]
        acc = 0.0
        for k in range(N_X):
            acc += P[j, k] * fm.C[r, k]
        s += cj * acc
    return z[r] - pred, s + fm.r_diag[r]


@kernel
def residuals(xa, P, z, fm, out):
    """Normalised residuals ``r_q, r_nx, r_nz`` (eqs. 9-11) on the prediction.

    Parameters
    ----------
    xa : ndarray, shape (n,)
        Predicted augmented state ``X_{k+1|k}``.
    P : ndarray, shape (n, n)
        Predicted covariance ``P_{k+1|k}``.
    z : ndarray, shape (12,)
        Measurement deviation from trim outputs.
    fm : FilterModel
    out : ndarray, shape (3,)
        Written with ``[r_q, r_nx, r_nz]`` (:data:`ftc_mc.conventions.RESIDUAL_NAMES`;
        each chi-square with one degree of freedom when the model holds).
    """
    for o in range(len(RESIDUAL_OUTPUTS)):
        mu, s = innovation(xa, P, z, fm, RESIDUAL_OUTPUTS[o])
        out[o] = mu * mu / s


@kernel
def update(xa, P, z, fm, h):
    """Measurement update with the 12 outputs, one scalar update each.

    With diagonal ``R`` this equals the batch update ``K = P C^T S^-1``; each
    scalar step is ``h = P c^T``, ``s = c h + R_rr``, ``X += h mu / s``,
    ``P -= h h^T / s``.

    Parameters
    ----------
    xa : ndarray, shape (n,)
        Updated in place.
    P : ndarray, shape (n, n)
        Updated in place (kept exactly symmetric).
    z : ndarray, shape (12,)
        Measurement deviation from trim outputs.
    fm : FilterModel
    h : ndarray, shape (n,)
        Work array.
    """
    n = _paper_dim(xa)
    # only the upper triangle is updated (entry (a, b) read as P[min, max]);
    # it is mirrored once at the end
    for r in range(z.shape[0]):
        s_idx = fm.c_ident[r]
        if s_idx >= 0:
            for a in range(s_idx):
                h[a] = P[a, s_idx]
            for a in range(s_idx, n):
                h[a] = P[s_idx, a]
            pred = xa[s_idx]
        else:
            pred = 0.0
            for j in range(N_X):
                pred += fm.C[r, j] * xa[j]
            for a in range(n):
                acc = 0.0
                for j in range(N_X):
                    if j < a:
                        acc += P[j, a] * fm.C[r, j]
                    else:
                        acc += P[a, j] * fm.C[r, j]
                h[a] = acc
        s = fm.r_diag[r]
        if s_idx >= 0:
            s += h[s_idx]
        else:
            for j in range(N_X):
                s += fm.C[r, j] * h[j]
        g = (z[r] - pred) / s
        inv_s = 1.0 / s
        for a in range(n):
            xa[a] += h[a] * g
        for a in range(n):
            ha = h[a] * inv_s
            for b in range(a, n):
                P[a, b] -= ha * h[b]
    for a in range(n):
        for b in range(a + 1, n):
            P[b, a] = P[a, b]


@kernel
def project(xa, fm):
    """Active-set projection of the fault parameters onto their box (eqs. 6-8).

    Every violated bound becomes an equality row of ``E`` (a unit row); as these
    rows are orthonormal, ``L = E^T (E E^T)^-1 = E^T`` and eq. (8) sets each
    violated parameter to its bound and leaves the rest unchanged.  Only the state
    is projected; the covariance stays unconstrained (semi-closed loop, Fig. 2).

    Parameters
    ----------
    xa : ndarray, shape (n,)
        Updated in place.
    fm : FilterModel

    Returns
    -------
    int
        Number of active constraints.
    """
    active = 0
    for j in range(N_F):
        v = xa[N_X + j]
        if v < fm.lo[j]:
            xa[N_X + j] = fm.lo[j]
            active += 1
        elif v > fm.hi[j]:
            xa[N_X + j] = fm.hi[j]
            active += 1
    return active
