"""The single-trajectory filter and controller selection: references of the lane kernels.

The package runs many trials at once (``ftc_mc/core/longitudinal/batch.py``,
``control.select_controllers_lanes``); each lane there must equal these
kernels on one trajectory, in the same operations and order, so they live
with the tests that compare them (``tests/test_batch.py``,
``tests/test_stages.py``), the oracles (``tests/test_filter_oracles.py``,
``tests/test_core_vs_naive.py``, ``tests/test_soak.py``) and
``scripts/benchmarks/bench_core.py``.  They are Numba kernels like the package's, and
structure-exploiting; the plain-NumPy twins are in ``tests/naive.py``.

The augmented filter (paper eqs. 5-11): Augmented state ``X = [x (9), b0 (2), b1 (3)]`` (indices in
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

One full estimator step (:func:`filter_step`): Order within a step ``k -> k+1``:

1. predict ``X_{k+1|k}``, ``P_{k+1|k}`` with the command ``u_k`` (eq. 5);
2. residuals ``r_q, r_nx, r_nz`` on the prediction (eqs. 9-11);
3. Table 1 signature; if it fires, the suspected block is reset in ``P_{k|k}``
   (section 3.2.2) and ``P_{k+1|k}`` is predicted again from it;
4. measurement update with ``z_{k+1}``;
5. active-set projection of the state (eqs. 6-8); ``P`` stays unconstrained
   (semi-closed loop).

Why step 3 resets ``P_{k|k}`` and predicts again rather than zeroing the block of
``P_{k+1|k}`` directly: zeroing the block's rows and columns in ``P_{k+1|k}``
also zeroes its covariance with the plant state, so the update's gain for the
suspected parameters is exactly zero on that step.  While the residuals stay
above threshold the reset repeats every step and the parameters never move
(measured on elevon locks 0.2 rad from trim: in 6 of 8 seeds the elevon
parameters stayed frozen for the whole 60 s).  Predicting from the reset
``P_{k|k}`` gives ``P_{k+1|k}`` the block's reset variances (plus ``Q^b``) and the
cross-covariances ``Phi(u) P_bb`` through which the update can move them; the
printed reset variances and the zeroed correlations are kept.
"""

from __future__ import annotations

import dataclasses
import math
from collections import namedtuple

import numpy as np

from ftc_mc.conventions import (N_AUG, N_B0, N_B1, N_CONTROLLERS, N_MODES, N_U, N_X, N_Z,
                                RESIDUAL_OUTPUTS)
from ftc_mc.conventions import N_FAULT
from ftc_mc.conventions import N_FAULT as N_F
from ftc_mc.core.jit import kernel
from ftc_mc.core.longitudinal.control import controller_command
from ftc_mc.core.longitudinal.signature import (NO_RESET, RESET_ELEVONS, RESET_THRUST,
                                                in_block, signature_lanes)
from ftc_mc.core.shared.belief import belief_update
from ftc_mc.core.shared.excitation import saturate


# ------------------------------------------------------------------ the filter
@kernel
def _paper_dim(xa):
    """``N_AUG``, the augmented dimension of the paper's filter, after checking it.

    The loops of :func:`predict` and :func:`update` run to this compile-time
    constant: with the dimension read from the array instead, the controller
    selection (which predicts with these kernels) ran 19 % slower.  A filter
    of another dimension gets a clear error here rather than wrong numbers.
    """
    if xa.shape[0] != N_AUG:
        raise ValueError("single_trajectory: the augmented state must have N_AUG entries")
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


@kernel
def reset_covariance(P, block, reset_var):
    """Reset one fault block of a covariance (section 3.2.2; the filter step
    applies it to ``P_{k|k}``, see ``tests/single_trajectory.py::filter_step``).

    The rows and columns of the block's fault parameters are zeroed and their
    variances set to ``reset_var``: thrust ``((u_max - u_min)/t_nx)^2`` for b0 and
    ``1/t_nx^2`` for b1; elevons the same with ``t_q``.

    Parameters
    ----------
    P : ndarray, shape (n, n)
        Updated in place; the fault parameters are entries ``N_X .. N_X + 4``.
    block : int
        ``RESET_THRUST`` or ``RESET_ELEVONS`` (``NO_RESET`` does nothing).
    reset_var : ndarray, shape (5,)
        Variance of each fault parameter after its block is reset.
    """
    if block != RESET_THRUST and block != RESET_ELEVONS:
        return
    n = P.shape[0]
    for j in range(N_FAULT):
        if in_block(j, block):
            i = N_X + j
            for k in range(n):
                P[i, k] = 0.0
                P[k, i] = 0.0
            P[i, i] = reset_var[j]


# ------------------------------------------------------------------ one step
@kernel
def filter_step(xa, P, u, z, fm, det, phi, T, h, res, x_prev, P_prev):
    """Advance the augmented filter by one sampling period.

    Parameters
    ----------
    xa : ndarray, shape (14,)
        Augmented estimate, updated in place.
    P : ndarray, shape (14, 14)
        Covariance, updated in place.
    u : ndarray, shape (3,)
        Command deviation applied during the step.
    z : ndarray, shape (12,)
        Measurement deviation from trim outputs at the end of the step.
    fm : FilterModel
    det : Detection
    phi, T, h : ndarray
        Work arrays of shapes (9, 5), (9, 14), (14,).
    res : ndarray, shape (3,)
        Written with ``[r_q, r_nx, r_nz]``.
    x_prev, P_prev : ndarray
        Work arrays of shapes (14,) and (14, 14): ``X_{k|k}`` and ``P_{k|k}``.

    Returns
    -------
    int
        The block reset this step (``signature.NO_RESET`` if none).
    """
    n = xa.shape[0]
    for i in range(n):
        x_prev[i] = xa[i]
        for j in range(n):
            P_prev[i, j] = P[i, j]
    predict(xa, P, u, fm, phi, T)
    residuals(xa, P, z, fm, res)
    one = np.zeros(1, dtype=np.int64)
    signature_lanes(np.ascontiguousarray(res.reshape(-1, 1)), det, one)
    block = one[0]
    if block != NO_RESET:
        reset_covariance(P_prev, block, det.reset_var)
        for i in range(n):
            xa[i] = x_prev[i]
            for j in range(n):
                P[i, j] = P_prev[i, j]
        predict(xa, P, u, fm, phi, T)
    update(xa, P, z, fm, h)
    project(xa, fm)
    return block


# ------------------------------------------------------------------ work arrays
@dataclasses.dataclass
class Workspace:
    """Work arrays of one trajectory's filter step."""

    phi: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((9, 5)))
    T: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((9, 14)))
    h: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(14))
    res: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    belief: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(8))
    x_prev: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(14))
    P_prev: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((14, 14)))


SelectionWork = namedtuple("SelectionWork", [
    "xs",      # (n,) estimate predicted over the horizon
    "Ps",      # (n, n) its covariance
    "belief",  # (N_MODES,) belief updated with the prediction (eq. 47)
    "U",       # (N_U,) command of the controller under test
    "z",       # (N_Z,) predicted measurement (zero innovation)
    "h",       # (n,) gain of one scalar update (kalman.update)
    "bvar",    # (N_FAULT,) predicted variances of the fault parameters
    "bwork",   # (2 N_MODES,) work of belief.belief_update
    "phi",     # (N_X, N_FAULT) Phi(u) (kalman.predict)
    "T",       # (N_X, n) [A Phi] P (kalman.predict)
    "obj",     # (N_CONTROLLERS,) objective of each controller (eq. 47)
])
"""Scratch of the rolling-horizon controller selection (paper eqs. 45-47)."""


@kernel
def new_selection_work(n):
    """Zeroed :class:`SelectionWork` for an augmented dimension ``n``."""
    return SelectionWork(xs=np.zeros(n), Ps=np.zeros((n, n)), belief=np.zeros(N_MODES),
                         U=np.zeros(N_U), z=np.zeros(N_Z), h=np.zeros(n),
                         bvar=np.zeros(N_FAULT), bwork=np.zeros(2 * N_MODES),
                         phi=np.zeros((N_X, N_FAULT)), T=np.zeros((N_X, n)),
                         obj=np.zeros(N_CONTROLLERS))


# ------------------------------------------------------------------ controller selection
@kernel
def horizon_cost(c, xs, Ps, scheme, work):
    """Predict ``H`` steps with controller ``c``; return the discounted cost (eq. 45).

    ``I(c) = sum_{k'=1..H} alpha^k' (x_k'^T Q_lqr x_k' + u_k'^T R_lqr u_k')`` on
    the predicted state and the saturated commands (eq. 16); ``xs`` and ``Ps``
    are advanced in place to ``X_{k+H|k}`` and ``P_{k+H|k+H}`` (zero
    innovations: each step is a prediction, a measurement update with the
    predicted measurement, and the projection of eqs. 6-8).

    Parameters
    ----------
    c : int
        Controller (``C_NOMINAL``, ``C_ENGINE``, ``C_ELEVON``).
    xs : ndarray, shape (n,)
        Augmented estimate, advanced in place.
    Ps : ndarray, shape (n, n)
        Its covariance, advanced in place.
    scheme : Scheme
        Reads ``filter``, ``controller`` (gain and limits), ``reconfig``
        (``horizon``, ``alpha``, ``q_lqr``, ``r_lqr``) and ``engine``.
    work : SelectionWork
        Scratch (``U``, ``z``, ``h``, ``phi``, ``T``).

    Returns
    -------
    float
        The discounted short-horizon cost.
    """
    ctl = scheme.controller
    return _predicted_cost(c, xs, Ps, scheme.filter, scheme.reconfig, scheme.engine, ctl.K,
                           ctl.lo_dev, ctl.hi_dev, work.U, work.z, work.h, work.phi, work.T)


@kernel
def _predicted_cost(c, xs, Ps, fm, rc, eng, K, lo, hi, U, z, h, phi, T):
    """The loop of :func:`horizon_cost` on unpacked settings and scratch.

    The settings are unpacked once, outside the loop: reading them from the
    whole ``Scheme`` inside it made the reconfiguring trial about 8 % slower
    (128 lanes of ``configs/paper_tables.yaml``, one core).
    """
    cost = 0.0
    disc = 1.0
    for _ in range(rc.horizon):
        controller_command(c, xs, K, eng, fm.u0, U)
        for i in range(N_U):
            U[i] = saturate(U[i], 0.0, 0.0, lo[i], hi[i])
        predict(xs, Ps, U, fm, phi, T)
        for r in range(z.shape[0]):
            s = fm.c_ident[r]
            if s >= 0:
                z[r] = xs[s]
            else:
                acc = 0.0
                for j in range(N_X):
                    acc += fm.C[r, j] * xs[j]
                z[r] = acc
        update(xs, Ps, z, fm, h)
        project(xs, fm)
        disc *= rc.alpha
        stage = 0.0
        for j in range(N_X):
            stage += rc.q_lqr[j] * xs[j] * xs[j]
        for i in range(N_U):
            stage += rc.r_lqr[i] * U[i] * U[i]
        cost += disc * stage
    return cost


@kernel
def controller_objectives(current, xa, P, belief, scheme, work):
    """The objective of eq. (47) for every controller, into ``work.obj``.

    ``obj(a) = I(a) + sum_m b_{k+H|k+H}(m) (J^N(m, a) + P(c, a))``: the
    short-horizon cost (eq. 45, :func:`horizon_cost`), the belief updated with
    the predicted fault parameters and their variances (eqs. 12-14), the
    terminal cost and the switching penalty (eq. 46).

    Parameters
    ----------
    current : int
        Controller in use ``c`` (for the switching penalty ``P(c, a)``).
    xa : ndarray, shape (n,)
        Augmented estimate.
    P : ndarray, shape (n, n)
        Its covariance.
    belief : ndarray, shape (4,)
        Current mode probabilities.
    scheme : Scheme
        Reads ``filter``, ``belief``, ``controller``, ``reconfig`` and ``engine``.
    work : SelectionWork
        Scratch; ``work.obj`` (3,) is written.
    """
    n = xa.shape[0]
    rc = scheme.reconfig
    xs = work.xs
    Ps = work.Ps
    bl = work.belief
    bv = work.bvar
    for a in range(N_CONTROLLERS):
        for i in range(n):
            xs[i] = xa[i]
            for j in range(n):
                Ps[i, j] = P[i, j]
        obj = horizon_cost(a, xs, Ps, scheme, work)
        for m in range(N_MODES):
            bl[m] = belief[m]
        for j in range(N_FAULT):
            bv[j] = Ps[N_X + j, N_X + j]
        belief_update(bl, scheme.belief, xs[N_X:N_X + N_FAULT], bv, work.bwork)
        for m in range(N_MODES):
            obj += bl[m] * (rc.JN[m, a] + rc.penalty[current, a])
        work.obj[a] = obj


@kernel
def select_controller(current, xa, P, belief, scheme, work):
    """Rolling-horizon choice of the controller (eqs. 45-47) for one trajectory.

    The controller with the smallest objective of :func:`controller_objectives`
    (the first of equal ones); the current one when no objective is finite.

    Parameters
    ----------
    current : int
        Controller in use (for the switching penalty ``P(c, a)``).
    xa : ndarray, shape (n,)
    P : ndarray, shape (n, n)
    belief : ndarray, shape (4,)
        Current mode probabilities.
    scheme : Scheme
    work : SelectionWork

    Returns
    -------
    int
        The selected controller.
    """
    controller_objectives(current, xa, P, belief, scheme, work)
    best = current
    best_obj = math.inf
    for a in range(N_CONTROLLERS):
        if work.obj[a] < best_obj:
            best_obj = work.obj[a]
            best = a
    return best
