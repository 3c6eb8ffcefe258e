"""The gust-aware augmented filter on every lane (issue 13; DESIGN.md section 9).

The paper's filter (:mod:`ftc_mc.core.batch`) models turbulence as white process
noise, which it is not: the Dryden gusts are coloured, and in moderate
turbulence the normalised residuals average 190 / 19 / 1220 instead of 1.
This filter carries the shaping filter's states ``g`` (``core/dryden.py``)
after the fault parameters, ``X = [x (9), b (5), g (ng)]``:

    x_{k+1} = A x_k + B u_k + Phi(u_k) b_k + G g_k + w_k      G  = B_w C_d
    b_{k+1} = b_k + w^b_k                                      (eq. 3)
    g_{k+1} = A_d g_k + B_d eta_k                              Qg = B_d B_d^T
    z_{k+1} = C x_{k+1} + D_g g_{k+1} + v_k                    D_g = D_w C_d

with ``B_w``, ``D_w`` the wind Jacobians the truth plant uses
(``ftc_mc/model/wind.py``) and the Dryden model at a *design* turbulence level.
The steps are those of the paper's filter (eqs. 5-11, Table 1, section 3.2.2,
eqs. 6-8): predict, residuals on the three outputs, reset of a block of
``P_{k|k}`` and a re-prediction, sequential scalar updates with the 12 outputs
in order, projection of the fault parameters.  The matrices are dense here
(``C`` rows gain gust columns), so the loops are plain ``F P F^T`` and
``P c^T`` over every lane, lane index innermost; ``P`` is kept exactly
symmetric.

Plain-NumPy twin: ``tests/naive.py::gust_filter_step_ref``.
"""

from __future__ import annotations

import numpy as np

from ..conventions import N_AUG, N_B0, N_U, N_X, RESIDUAL_OUTPUTS
from ..conventions import N_FAULT as N_F
from .batch import UPDATE_ROWS, project_lanes, reset_lanes
from .jit import kernel


@kernel
def _c_row(fm, r, crow):
    """Row ``r`` of ``C_aug = [C, 0, D_g]`` into ``crow`` (n,)."""
    n = crow.shape[0]
    for j in range(n):
        crow[j] = 0.0
    for j in range(N_X):
        crow[j] = fm.C[r, j]
    for g in range(n - N_AUG):
        crow[N_AUG + g] = fm.Dg[r, g]


@kernel
def _gpredict(xa, P, Pn, u, fm, phi, T, xn):
    """Time update of every lane: ``X <- F X + B_aug u``, ``Pn <- F P F^T + Q``.

    ``F = [[A, Phi(u), G], [0, I, 0], [0, 0, A_d]]`` and ``Q`` block-diagonal
    (``q_diag`` on ``x`` and ``b``, ``Qg`` on ``g``).  ``P`` is read whole
    (symmetric), ``Pn`` written whole (exactly symmetric; may not be ``P``).
    ``phi`` (9, 5, L) holds ``Phi(u)`` on return; ``T`` (n, n, L) and ``xn``
    (n, L) are work arrays.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    ng = n - N_AUG
    for i in range(N_X):
        for l in range(L):
            phi[i, 0, l] = fm.Bb0[i, 0]
            phi[i, 1, l] = fm.Bb0[i, 1]
            for j in range(N_U):
                phi[i, N_B0 + j, l] = -fm.B[i, j] * (u[j, l] + fm.u0[j])
    # state
    for i in range(N_X):
        for l in range(L):
            acc = 0.0
            for j in range(N_X):
                acc += fm.A[i, j] * xa[j, l]
            for j in range(N_U):
                acc += fm.B[i, j] * u[j, l]
            for j in range(N_F):
                acc += phi[i, j, l] * xa[N_X + j, l]
            for g in range(ng):
                acc += fm.G[i, g] * xa[N_AUG + g, l]
            xn[i, l] = acc
    for a in range(ng):
        for l in range(L):
            acc = 0.0
            for g in range(ng):
                acc += fm.Ad[a, g] * xa[N_AUG + g, l]
            xn[N_AUG + a, l] = acc
    for i in range(N_X):
        for l in range(L):
            xa[i, l] = xn[i, l]
    for a in range(ng):
        for l in range(L):
            xa[N_AUG + a, l] = xn[N_AUG + a, l]
    # T = F P
    for i in range(N_X):
        for c in range(n):
            for l in range(L):
                acc = 0.0
                for j in range(N_X):
                    acc += fm.A[i, j] * P[j, c, l]
                for j in range(N_F):
                    acc += phi[i, j, l] * P[N_X + j, c, l]
                for g in range(ng):
                    acc += fm.G[i, g] * P[N_AUG + g, c, l]
                T[i, c, l] = acc
    for i in range(N_X, N_AUG):
        for c in range(n):
            for l in range(L):
                T[i, c, l] = P[i, c, l]
    for a in range(ng):
        for c in range(n):
            for l in range(L):
                acc = 0.0
                for g in range(ng):
                    acc += fm.Ad[a, g] * P[N_AUG + g, c, l]
                T[N_AUG + a, c, l] = acc
    # Pn = T F^T (upper triangle), + Q, mirrored
    for i in range(n):
        for k in range(i, n):
            if k < N_X:
                for l in range(L):
                    acc = 0.0
                    for j in range(N_X):
                        acc += T[i, j, l] * fm.A[k, j]
                    for j in range(N_F):
                        acc += T[i, N_X + j, l] * phi[k, j, l]
                    for g in range(ng):
                        acc += T[i, N_AUG + g, l] * fm.G[k, g]
                    Pn[i, k, l] = acc
            elif k < N_AUG:
                for l in range(L):
                    Pn[i, k, l] = T[i, k, l]
            else:
                for l in range(L):
                    acc = 0.0
                    for g in range(ng):
                        acc += T[i, N_AUG + g, l] * fm.Ad[k - N_AUG, g]
                    Pn[i, k, l] = acc
    for i in range(N_AUG):
        qi = fm.q_diag[i]
        for l in range(L):
            Pn[i, i, l] += qi
    for a in range(ng):
        for b in range(a, ng):
            qab = fm.Qg[a, b]
            for l in range(L):
                Pn[N_AUG + a, N_AUG + b, l] += qab
    for i in range(n):
        for k in range(i + 1, n):
            for l in range(L):
                Pn[k, i, l] = Pn[i, k, l]


@kernel
def gust_residuals_lanes(xa, P, z, fm, crow, res, innov):
    """Normalised residuals ``r_q, r_nx, r_nz`` (eqs. 9-11) with the gust columns
    of ``C_aug``: ``r_i = mu_i^2 / (c_i P c_i^T + R_ii)``, ``mu_i = z_i - c_i X``.

    ``P`` is the full symmetric prediction; ``crow`` (n,) is work; ``res`` and
    ``innov`` (3, L) are written with ``r_i`` and ``mu_i / sqrt(S_ii)``.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    for o in range(len(RESIDUAL_OUTPUTS)):
        r = RESIDUAL_OUTPUTS[o]
        _c_row(fm, r, crow)
        rr = fm.r_diag[r]
        for l in range(L):
            pred = 0.0
            s = 0.0
            for j in range(n):
                pred += crow[j] * xa[j, l]
                acc = 0.0
                for k in range(n):
                    acc += P[j, k, l] * crow[k]
                s += crow[j] * acc
            mu = z[r, l] - pred
            s = s + rr
            res[o, l] = mu * mu / s
            innov[o, l] = mu / np.sqrt(s)


@kernel
def _gupdate(xa, P, z, fm, crow, h, v, gs):
    """Sequential scalar updates with the 12 outputs in order, on the upper
    triangle of ``P`` (mirrored by the caller): ``h = P c^T``, ``s = c h + R``,
    ``X += h (z - c X) / s``, ``P -= (h / s) h^T``."""
    n = xa.shape[0]
    L = xa.shape[1]
    for r in range(z.shape[0]):
        _c_row(fm, r, crow)
        rr = fm.r_diag[r]
        for a in range(n):
            for l in range(L):
                acc = 0.0
                for j in range(n):
                    cj = crow[j]
                    if j < a:
                        acc += P[j, a, l] * cj
                    else:
                        acc += P[a, j, l] * cj
                h[a, l] = acc
        for l in range(L):
            pred = 0.0
            sv = rr
            for j in range(n):
                pred += crow[j] * xa[j, l]
                sv += crow[j] * h[j, l]
            gs[0, l] = (z[r, l] - pred) / sv
            gs[1, l] = 1.0 / sv
        for a in range(n):
            for l in range(L):
                xa[a, l] += h[a, l] * gs[0, l]
                v[a, l] = h[a, l] * gs[1, l]
        for a in range(n):
            for b in range(a, n):
                for l in range(L):
                    P[a, b, l] -= v[a, l] * h[b, l]


@kernel
def gust_predict_lanes(xa, P, u, z, fm, phi, T, work, crow, res, innov):
    """First half of a gust-aware filter step: predict into ``work[:n]`` and the
    residuals; ``X_{k|k}`` is kept in ``work`` for a re-prediction.

    Parameters
    ----------
    xa : ndarray, shape (n, L)
        ``X_{k|k}``, replaced by ``X_{k+1|k}``.
    P : ndarray, shape (n, n, L)
        ``P_{k|k}`` (left unchanged).
    u : ndarray, shape (3, L)
        Command deviations applied during the step.
    z : ndarray, shape (12, L)
        Measurement deviations from the trim outputs at the end of the step.
    fm : FilterModel
        With the gust fields ``G``, ``Ad``, ``Dg``, ``Qg`` (``ng = n - 14``).
    phi : ndarray, shape (9, 5, L)
    T : ndarray, shape (n, n, L)
    work : ndarray, shape (step_rows(n), n, L)
        ``work[:n]`` gets ``P_{k+1|k}``; rows ``n .. n + 13`` are the update's.
    crow : ndarray, shape (n,)
    res, innov : ndarray, shape (3, L)
        Residuals ``r_q, r_nx, r_nz`` and signed normalised innovations.
    """
    n = xa.shape[0]
    Pn = work[0:n]
    x_prev = work[n + UPDATE_ROWS]
    xn = work[n + 3]
    for i in range(n):
        for l in range(xa.shape[1]):
            x_prev[i, l] = xa[i, l]
    _gpredict(xa, P, Pn, u, fm, phi, T, xn)
    gust_residuals_lanes(xa, Pn, z, fm, crow, res, innov)


@kernel
def gust_correct_lanes(xa, P, u, z, fm, det, phi, T, work, crow, block):
    """Second half, once ``block`` is decided: reset the block of ``P_{k|k}``
    (section 3.2.2) of every lane that resets and predict all lanes again from
    ``X_{k|k}`` (identical for the others), update, projection (eqs. 6-8).
    Parameters as :func:`gust_predict_lanes`; ``P`` gets ``P_{k+1|k+1}``."""
    n = xa.shape[0]
    L = xa.shape[1]
    Pn = work[0:n]
    x_prev = work[n + UPDATE_ROWS]
    xn = work[n + 3]
    n_reset = 0
    for l in range(L):
        if block[l] != 0:
            n_reset += 1
    if n_reset > 0:
        reset_lanes(P, block, det.reset_var)
        for i in range(n):
            for l in range(L):
                xa[i, l] = x_prev[i, l]
        _gpredict(xa, P, Pn, u, fm, phi, T, xn)
    _gupdate(xa, Pn, z, fm, crow, work[n], work[n + 1], work[n + 2])
    for i in range(n):
        for k in range(i, n):
            for l in range(L):
                P[i, k, l] = Pn[i, k, l]
                P[k, i, l] = Pn[i, k, l]
    project_lanes(xa, fm)
