"""The three controllers and the rolling-horizon controller selection (section 4).

Controllers (command deviations before the saturation and excitation of eq. 15):

* ``c0`` nominal: ``U = -K x_hat`` (eq. 19);
* ``c1`` engine fault: ``U = -K(b0_T, b1_T) x_hat - k(b0_T, b1_T)`` with Theorem
  4.1's gain and affine term interpolated in the offline tables (eq. 44);
* ``c2`` redundant-elevon fault: thrust ``-K_1 x_hat``, elevons by the
  minimum-norm allocation of eqs. 20-25 (eq. 25 corrected, see
  :func:`elevon_allocation`).

Selection (eqs. 45-47), every reconfiguration period: for each controller ``a``
the estimate and covariance are predicted ``H`` steps ahead with ``a`` in the
loop (zero innovations: the covariance gets its measurement updates, the state
follows the model), giving the short-horizon cost ``I(a)`` (eq. 45) and
``P_{k+H|k+H}``; the belief is updated with it (eqs. 13-14) and the controller
minimising ``I(a) + sum_m b_{k+H}(m) (J^N(m, a) + P(c, a))`` (eqs. 46-47) is
chosen.

The trial loop selects for all its lanes at once
(:func:`select_controllers_lanes`): each controller's horizon is predicted for
every lane with the lane-interleaved filter kernels of :mod:`ftc_mc.core.longitudinal.batch`,
then belief and objective follow per lane.  Per lane this is
``tests/single_trajectory.py::select_controller`` bit for bit (``tests/test_stages.py``); measured on a
chunk of 128 lanes of ``configs/paper_tables.yaml``, one core: 2.9 ms per
selection against 9.3 ms one lane at a time (of which the measurement updates
take about 60 %, the predictions 35 %).

Plain-NumPy twins: ``tests/naive.py`` (``controller_command_ref``,
``horizon_cost_ref``, ``controller_objectives_ref``), compared in
``tests/test_stages.py``.
"""

from __future__ import annotations

import math

import numpy as np

from ..shared.belief import belief_update
from ..shared.excitation import saturate
from ..shared.interp import engine_controller
from ..jit import kernel
from .batch import predict_lanes, project_lanes, update_lanes

from ...conventions import (C_ELEVON, C_ENGINE, C_NOMINAL, I_B0_ELEVONS,  # noqa: F401
                           I_B0_THRUST, I_B1_LEFT, I_B1_RIGHT, I_B1_THRUST, INPUT_NAMES,
                           N_AUG, N_CONTROLLERS, N_FAULT, N_MODES, N_U, N_X)

U_THRUST = INPUT_NAMES.index("throttle")
U_LEFT = INPUT_NAMES.index("elevon_left")
U_RIGHT = INPUT_NAMES.index("elevon_right")
"""Rows of the command vector ``u`` (:data:`ftc_mc.conventions.INPUT_NAMES`)."""


@kernel
def elevon_allocation(K2x, b0e, b1L, b1R, u0L, u0R):
    """Minimum-norm elevon commands under a redundant-elevon fault (eqs. 20-25).

    Solves (24): ``min 1/2 (U2^2 + U3^2)`` s.t. ``Phi = 0`` (eq. 22) with

        Phi = 2 K2 x + b0e + (1 - b1L) U2 - b1L u0L + (1 - b1R) U3 - b1R u0R,

    i.e. the summed elevon effect equals the nominal ``-2 K2 x`` (eq. 20).  With
    ``a = (1 - b1L, 1 - b1R)`` and ``c = 2 K2 x + b0e - b1L u0L - b1R u0R`` the
    Lagrange conditions give ``U = -lambda a``, ``lambda = c / |a|^2``:
    ``U2 = -lambda (1 - b1L)``, ``U3 = -lambda (1 - b1R)``.

    **Correction of eq. 25**: the paper prints ``U3 = -lambda (1 - b1^2)``, which
    violates ``Phi = 0`` whenever ``b1^2 != b1^3`` (e.g. a locked left elevon,
    ``b1^2 = 1``, would give ``U3 = 0``).  The ``lambda`` printed below eq. 25 is
    right.  When both elevons are fully ineffective (``|a| = 0``) the constraint
    cannot be met; the minimum-norm least-squares answer ``U2 = U3 = 0`` is
    returned.  The estimator carries a single elevon bias, the **sum**
    ``b0e = b0_L + b0_R`` (:mod:`ftc_mc.model.faults`); eq. 22 only needs that
    sum (the paper's ``b0^2``).

    Parameters
    ----------
    K2x : float
        Nominal elevon feedback ``K_2 x_hat`` [rad].
    b0e : float
        Elevon bias sum ``b0_L + b0_R`` [rad].
    b1L, b1R : float
        Effectiveness losses in [0, 1].
    u0L, u0R : float
        Trim commands [rad].

    Returns
    -------
    (float, float)
        ``U2, U3`` [rad]; zero when both elevons are fully ineffective.
    """
    aL = 1.0 - b1L
    aR = 1.0 - b1R
    den = aL * aL + aR * aR
    if not den > 0.0:
        return 0.0, 0.0
    lam = (2.0 * K2x + b0e - b1L * u0L - b1R * u0R) / den
    return -lam * aL, -lam * aR


@kernel(inline="always")
def feedback_lanes(K, x, U):
    """The nominal feedback ``U = -K x`` (eq. 19) of every lane: the one loop of
    c0 and of c2's nominal part, in the trial loop and in the selection.

    Parameters
    ----------
    K : ndarray, shape (3, 9)
        Nominal gain.
    x : ndarray, shape (n, L)
        Estimates (their first 9 states are read).
    U : ndarray, shape (3, L)
        Written with the command deviations.
    """
    L = x.shape[1]
    for i in range(N_U):
        for l in range(L):
            U[i, l] = 0.0
        for j in range(N_X):
            kij = K[i, j]
            for l in range(L):
                U[i, l] -= kij * x[j, l]


@kernel(internal=True)
def controller_command(c, xa, K, eng, u0, U):
    """Command of controller ``c`` from an augmented estimate (no saturation).

    Parameters
    ----------
    c : int
        ``C_NOMINAL``, ``C_ENGINE`` or ``C_ELEVON``.
    xa : ndarray, shape (n,)
        Augmented estimate ``[x, b0_T, b0_e, b1_T, b1_L, b1_R, ...]``
        (:mod:`ftc_mc.conventions`).
    K : ndarray, shape (3, 9)
        Nominal gain.
    eng : EngineTables
    u0 : ndarray, shape (3,)
        Trim commands.
    U : ndarray, shape (3,)
        Written with the command deviation [throttle, rad, rad].
    """
    if c == C_ENGINE:
        engine_controller(eng, xa[I_B0_THRUST], xa[I_B1_THRUST], xa, U)
        return
    for i in range(N_U):
        acc = 0.0
        for j in range(N_X):
            acc -= K[i, j] * xa[j]
        U[i] = acc
    if c == C_ELEVON:
        U[U_LEFT], U[U_RIGHT] = elevon_allocation(
            -U[U_LEFT], xa[I_B0_ELEVONS], xa[I_B1_LEFT], xa[I_B1_RIGHT], u0[U_LEFT],
            u0[U_RIGHT])


@kernel(internal=True)
def _lane_commands(c, xs, K, eng, u0, lo, hi, U, xl, Ul):
    """Saturated command of controller ``c`` for every lane of ``xs`` (eq. 16).

    Per lane exactly :func:`controller_command` then :func:`saturate` as in
    :func:`_predicted_cost`; the nominal part ``-K x`` of c0 and c2 runs across
    lanes (the same products and sums, in the same order, per lane).
    """
    L = xs.shape[1]
    if c != C_ENGINE:
        feedback_lanes(K, xs, U)
        if c == C_ELEVON:
            for l in range(L):
                U[U_LEFT, l], U[U_RIGHT, l] = elevon_allocation(
                    -U[U_LEFT, l], xs[I_B0_ELEVONS, l], xs[I_B1_LEFT, l],
                    xs[I_B1_RIGHT, l], u0[U_LEFT], u0[U_RIGHT])
    else:
        n = xs.shape[0]
        for l in range(L):
            for i in range(n):
                xl[i] = xs[i, l]
            engine_controller(eng, xl[I_B0_THRUST], xl[I_B1_THRUST], xl, Ul)
            for i in range(N_U):
                U[i, l] = Ul[i]
    for i in range(N_U):
        lo_i = lo[i]
        hi_i = hi[i]
        for l in range(L):
            U[i, l] = saturate(U[i, l], 0.0, 0.0, lo_i, hi_i)


@kernel(inline="always")
def _predicted_cost_lanes(c, xs, Ps, fm, rc, eng, K, lo, hi, sw):
    """:func:`_predicted_cost` for every lane at once (lane-last ``xs``, ``Ps``).

    Lane ``l`` goes through the same floating-point operations, in the same
    order, as :func:`_predicted_cost` on ``xs[:, l]``, ``Ps[:, :, l]``: the
    lane kernels of :mod:`ftc_mc.core.longitudinal.batch` are bit-identical per lane to
    ``tests/single_trajectory.py::predict``, ``tests/single_trajectory.py::update`` and
    ``tests/single_trajectory.py::project``.  The discounted cost of each lane is
    written to ``sw.cost``.
    """
    L = xs.shape[1]
    U = sw.U
    z = sw.z
    cost = sw.cost
    for l in range(L):
        cost[l] = 0.0
    disc = 1.0
    for _ in range(rc.horizon):
        _lane_commands(c, xs, K, eng, fm.u0, lo, hi, U, sw.xl, sw.Ul)
        predict_lanes(xs, Ps, U, fm, sw.phi, sw.T)
        for r in range(z.shape[0]):
            s = fm.c_ident[r]
            if s >= 0:
                for l in range(L):
                    z[r, l] = xs[s, l]
            else:
                for l in range(L):
                    acc = 0.0
                    for j in range(N_X):
                        acc += fm.C[r, j] * xs[j, l]
                    z[r, l] = acc
        update_lanes(xs, Ps, z, fm, sw.h)
        project_lanes(xs, fm)
        disc *= rc.alpha
        for l in range(L):
            stage = 0.0
            for j in range(N_X):
                stage += rc.q_lqr[j] * xs[j, l] * xs[j, l]
            for i in range(N_U):
                stage += rc.r_lqr[i] * U[i, l] * U[i, l]
            cost[l] += disc * stage


@kernel(inline="always")
def controller_objectives_lanes(cur, xa, P, belief, scheme, sw):
    """:func:`controller_objectives` of every lane, into ``sw.obj`` (3, L).

    The horizon prediction runs across lanes (:func:`_predicted_cost_lanes`),
    one controller at a time; the belief update and the objective then follow
    per lane as in :func:`controller_objectives`, so ``sw.obj[:, l]`` equals
    ``controller_objectives(cur[l], xa[:, l], P[:, :, l], belief[:, l], ...)``
    bit for bit.

    Parameters
    ----------
    cur : ndarray of int64, shape (L,)
        Controller in use per lane.
    xa : ndarray, shape (n, L)
    P : ndarray, shape (n, n, L)
        Symmetric covariances.
    belief : ndarray, shape (4, L)
        Current mode probabilities per lane.
    scheme : Scheme
    sw : LaneSelectionWork
    """
    n = xa.shape[0]
    L = xa.shape[1]
    rc = scheme.reconfig
    ctl = scheme.controller
    xs = sw.xs
    Ps = sw.Ps
    bl = sw.bl
    bh = sw.bhat
    bv = sw.bvar
    for a in range(N_CONTROLLERS):
        for i in range(n):
            for l in range(L):
                xs[i, l] = xa[i, l]
        for i in range(n):
            for j in range(n):
                for l in range(L):
                    Ps[i, j, l] = P[i, j, l]
        _predicted_cost_lanes(a, xs, Ps, scheme.filter, rc, scheme.engine, ctl.K,
                              ctl.lo_dev, ctl.hi_dev, sw)
        for l in range(L):
            obj = sw.cost[l]
            for m in range(N_MODES):
                bl[m] = belief[m, l]
            for j in range(N_FAULT):
                bh[j] = xs[N_X + j, l]
                bv[j] = Ps[N_X + j, N_X + j, l]
            belief_update(bl, scheme.belief, bh, bv, sw.bwork)
            for m in range(N_MODES):
                obj += bl[m] * (rc.JN[m, a] + rc.penalty[cur[l], a])
            sw.obj[a, l] = obj


@kernel(inline="always")
def select_controllers_lanes(cur, xa, P, belief, scheme, sw):
    """``tests/single_trajectory.py::select_controller`` for every lane; ``cur`` is updated in place.

    Parameters are those of :func:`controller_objectives_lanes`.
    """
    controller_objectives_lanes(cur, xa, P, belief, scheme, sw)
    for l in range(xa.shape[1]):
        best = cur[l]
        best_obj = math.inf
        for a in range(N_CONTROLLERS):
            if sw.obj[a, l] < best_obj:
                best_obj = sw.obj[a, l]
                best = a
        cur[l] = best


@kernel
def policy_cost(c, fm, K, eng, lo, hi, b0, b1, best, alpha, q_lqr, r_lqr, n_steps):
    """Discounted cost of controller ``c`` on the noise-free faulty plant (for J^N).

    The plant is ``x+ = A x + B e`` with the per-actuator fault of eq. (2),
    started at trim (``x = 0``); the controller sees the true state and the
    estimator-convention fault parameters ``best`` (perfect knowledge), and its
    commands are saturated (eq. 16).

    Parameters
    ----------
    c : int
        Controller.
    fm : FilterModel
    K : ndarray, shape (3, 9)
    eng : EngineTables
    lo, hi : ndarray, shape (3,)
        Command limits as deviations.
    b0, b1 : ndarray, shape (3,)
        Per-actuator truth.
    best : ndarray, shape (5,)
        The same fault in the estimator's parameters.
    alpha : float
    q_lqr, r_lqr : ndarray
        Diagonals of Q_lqr (9,) and R_lqr (3,).
    n_steps : int

    Returns
    -------
    float
        ``sum_{k<n} alpha^k (x_k' Q x_k + u_k' R u_k)``.
    """
    xa = np.zeros(N_AUG)
    for j in range(N_FAULT):
        xa[N_X + j] = best[j]
    x = np.zeros(N_X)
    xn = np.zeros(N_X)
    U = np.zeros(N_U)
    e = np.zeros(N_U)
    cost = 0.0
    disc = 1.0
    for _ in range(n_steps):
        for j in range(N_X):
            xa[j] = x[j]
        controller_command(c, xa, K, eng, fm.u0, U)
        stage = 0.0
        for i in range(N_U):
            U[i] = saturate(U[i], 0.0, 0.0, lo[i], hi[i])
            e[i] = b0[i] + (1.0 - b1[i]) * U[i] - b1[i] * fm.u0[i]
            stage += r_lqr[i] * U[i] * U[i]
        for j in range(N_X):
            stage += q_lqr[j] * x[j] * x[j]
        cost += disc * stage
        disc *= alpha
        for i in range(N_X):
            acc = 0.0
            for j in range(N_X):
                acc += fm.A[i, j] * x[j]
            for j in range(N_U):
                acc += fm.B[i, j] * e[j]
            xn[i] = acc
        for i in range(N_X):
            x[i] = xn[i]
    return cost
