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
(:func:`select_controllers_lanes`) with the lane-interleaved filter kernels of
:mod:`ftc_mc.core.longitudinal.batch`.  The state follows the model alone
(the update's innovation is zero), so each controller's cost ``I(a)`` is
predicted without the covariance, and it bounds the objective from below; the
covariance's horizon, nearly all the work, is predicted for the controller in
use and for the others whose bound does not rule them out
(:func:`controller_objectives_lanes`): about 1.3 of 3 per lane on
``configs/paper_tables.yaml``.  Per lane the choice, and every objective
computed, is ``tests/single_trajectory.py::select_controller``'s bit for bit
(``tests/test_stages.py``); ``docs/findings/performance.md`` lessons 7 and 19
give the figures.

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
from .batch import predict_lanes, predict_state_lanes, project_lanes, update_lanes

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
    ``tests/single_trajectory.py::_predicted_cost``; the nominal part ``-K x``
    of c0 and c2 runs across lanes (the same products and sums, in the same
    order, per lane).
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
        for l in range(L):
            _engine_lane(xs, l, eng, U, xl, Ul)
    _saturate_lanes(lo, hi, U, L)


@kernel(inline="always")
def _engine_lane(xs, l, eng, U, xl, Ul):
    """c1's command (eq. 44, :func:`engine_controller`) of lane ``l`` of ``xs``
    into column ``l`` of ``U``, through the one-lane buffers ``xl``, ``Ul``."""
    for i in range(xs.shape[0]):
        xl[i] = xs[i, l]
    engine_controller(eng, xl[I_B0_THRUST], xl[I_B1_THRUST], xl, Ul)
    for i in range(N_U):
        U[i, l] = Ul[i]


@kernel(inline="always")
def _saturate_lanes(lo, hi, U, L):
    """The saturation of eq. (16), no excitation, of the first ``L`` columns of ``U``."""
    for i in range(N_U):
        lo_i = lo[i]
        hi_i = hi[i]
        for l in range(L):
            U[i, l] = saturate(U[i, l], 0.0, 0.0, lo_i, hi_i)


@kernel(inline="always")
def controller_commands_lanes(cs, xs, K, eng, u0, U, xl, Ul):
    """:func:`controller_command` of every lane, lane ``p`` with its own
    controller ``cs[p]``, into column ``p`` of ``U`` (no saturation).

    The nominal feedback ``-K x`` (c0, and c2's before its allocation) runs
    across lanes (:func:`feedback_lanes`: the products and sums of
    :func:`controller_command`, in its order); a c1 lane's column is then
    overwritten with its engine command (eq. 44), and a c2 lane's elevons
    with their allocation (eqs. 20-25).  Bit for bit
    :func:`controller_command` per lane.

    Parameters
    ----------
    cs : ndarray of int64, shape (L,)
        Controller of each lane.
    xs : ndarray, shape (n, L)
        Augmented estimates.
    K : ndarray, shape (3, 9)
        Nominal gain.
    eng : EngineTables
    u0 : ndarray, shape (3,)
        Trim commands.
    U : ndarray, shape (3, L)
        Written with the command deviations.
    xl, Ul : ndarray, shapes (n,) and (3,)
        One-lane buffers (c1).
    """
    L = xs.shape[1]
    feedback_lanes(K, xs, U)
    for p in range(L):
        c = cs[p]
        if c == C_ELEVON:
            U[U_LEFT, p], U[U_RIGHT, p] = elevon_allocation(
                -U[U_LEFT, p], xs[I_B0_ELEVONS, p], xs[I_B1_LEFT, p], xs[I_B1_RIGHT, p],
                u0[U_LEFT], u0[U_RIGHT])
        elif c == C_ENGINE:
            _engine_lane(xs, p, eng, U, xl, Ul)


@kernel(internal=True)
def _entry_commands(cs, xs, K, eng, u0, lo, hi, U, xl, Ul):
    """:func:`_lane_commands` with a controller per lane
    (:func:`controller_commands_lanes`, then the saturation of eq. 16): bit
    for bit what :func:`_lane_commands` gives each lane."""
    controller_commands_lanes(cs, xs, K, eng, u0, U, xl, Ul)
    _saturate_lanes(lo, hi, U, xs.shape[1])


@kernel(inline="always")
def _add_stage_cost(xs, U, rc, disc, cost):
    """``cost += disc (x' Q_lqr x + u' R_lqr u)`` per lane (one term of eq. 45)."""
    for l in range(xs.shape[1]):
        stage = 0.0
        for j in range(N_X):
            stage += rc.q_lqr[j] * xs[j, l] * xs[j, l]
        for i in range(N_U):
            stage += rc.r_lqr[i] * U[i, l] * U[i, l]
        cost[l] += disc * stage


@kernel(inline="always")
def _predicted_cost_lanes(cs, xs, Ps, fm, rc, eng, K, lo, hi, sw):
    """``tests/single_trajectory.py::_predicted_cost`` for every lane at once
    (lane-last ``xs``, ``Ps``), controller ``cs[l]`` on lane ``l``.

    Lane ``l`` goes through the same floating-point operations, in the same
    order, as ``_predicted_cost`` on ``xs[:, l]``, ``Ps[:, :, l]``: the
    lane kernels of :mod:`ftc_mc.core.longitudinal.batch` are bit-identical per lane to
    ``tests/single_trajectory.py::predict``, ``tests/single_trajectory.py::update`` and
    ``tests/single_trajectory.py::project``.  The discounted cost of each lane is
    written to ``sw.cost``; ``xs``, ``Ps`` hold ``X_{k+H}``, ``P_{k+H|k+H}``.
    """
    L = xs.shape[1]
    U = sw.U
    z = sw.z
    cost = sw.cost
    for l in range(L):
        cost[l] = 0.0
    disc = 1.0
    for _ in range(rc.horizon):
        _entry_commands(cs, xs, K, eng, fm.u0, lo, hi, U, sw.xl, sw.Ul)
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
        _add_stage_cost(xs, U, rc, disc, cost)


@kernel(inline="always")
def _state_cost_lanes(c, xs, fm, rc, eng, K, lo, hi, sw):
    """The short-horizon cost of eq. (45) of controller ``c`` on every lane,
    from the state alone, into ``sw.cost``.

    The selection's update has zero innovation (the predicted measurement is
    ``C X``), so it leaves the state as it is and only the covariance moves:
    the prediction of the state (:func:`~ftc_mc.core.longitudinal.batch.predict_state_lanes`),
    the projection and the costs are those of :func:`_predicted_cost_lanes`,
    operation for operation.  The cost is therefore that of
    :func:`_predicted_cost_lanes` to the bit whenever the latter is not NaN:
    where it differs, a gain or an innovation of the update was not finite,
    and the update made the state NaN (and with it the objective), or it
    differs in the sign of a zero, which moves no cost.  ``xs`` holds the
    state ``X_{k+H}`` on return.
    """
    L = xs.shape[1]
    U = sw.U
    cost = sw.cost
    for l in range(L):
        cost[l] = 0.0
    disc = 1.0
    for _ in range(rc.horizon):
        _lane_commands(c, xs, K, eng, fm.u0, lo, hi, U, sw.xl, sw.Ul)
        predict_state_lanes(xs, U, fm, sw.phi, sw.T)
        project_lanes(xs, fm)
        disc *= rc.alpha
        _add_stage_cost(xs, U, rc, disc, cost)


FLOOR_MARGIN = 1e-9
"""Relative margin of :func:`objective_floor`, far above the rounding of the
objective's few sums (about 1e-15 relative)."""

FLOOR_TINY = 1e-300
"""Absolute margin of :func:`objective_floor` (products that underflow)."""


@kernel(inline="always")
def objective_floor(cost, rc, c, a):
    """A lower bound of controller ``a``'s objective (eq. 47) from its
    short-horizon cost alone, before the belief is predicted.

    The objective is ``I(a) + sum_m b(m) (J^N(m, a) + P(c, a))`` with a belief
    ``b`` of non-negative probabilities summing to one (to rounding), so it is
    at least ``I(a) + min_m (J^N(m, a) + P(c, a))``; the bound subtracts a
    margin of ``FLOOR_MARGIN`` times the terms' magnitude (and
    ``FLOOR_TINY``), which covers every rounding of the objective's sums.

    Parameters
    ----------
    cost : float
        ``I(a)`` (eq. 45).
    rc : Reconfig
        ``JN`` and ``penalty``.
    c : int
        Controller in use.
    a : int
        Controller under test.

    Returns
    -------
    float
        The bound; ``-inf`` when a term or the bound is not finite (no bound).
    """
    if not math.isfinite(cost):
        return -math.inf
    low = math.inf
    big = abs(cost)
    for m in range(rc.JN.shape[0]):
        t = rc.JN[m, a] + rc.penalty[c, a]
        if not math.isfinite(t):
            return -math.inf
        low = min(low, t)
        big = max(big, abs(t))
    bound = cost + low - (FLOOR_MARGIN * (abs(cost) + big) + FLOOR_TINY)
    return bound if math.isfinite(bound) else -math.inf


@kernel(inline="always")
def _pad_entries(m, L, sw):
    """The first ``m >= 1`` entries of ``sw.cand``, ``sw.lane`` padded with
    copies of the last to ``Lp`` entries, a multiple of 8 or ``L``: lane rows
    of the gathered arrays start on 64-byte boundaries
    (``docs/findings/performance.md`` lesson 2).  Returns ``Lp``."""
    Lp = min(L, (m + 7) // 8 * 8)
    for p in range(m, Lp):
        sw.cand[p] = sw.cand[m - 1]
        sw.lane[p] = sw.lane[m - 1]
    return Lp


@kernel(internal=True)
def _entry_objectives(m, cur, xa, P, belief, scheme, sw):
    """The objective (eq. 47) of the first ``m`` entries of ``sw.cand``,
    ``sw.lane`` (controller ``a`` on lane ``l``) into ``sw.obj[a, l]``.

    Each entry is one lane of a horizon prediction
    (:func:`_predicted_cost_lanes`, lanes gathered from ``xa``, ``P``, padded
    by :func:`_pad_entries`); then the belief update and the objective per
    entry, as ``tests/single_trajectory.py::controller_objectives``.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    rc = scheme.reconfig
    ctl = scheme.controller
    cand = sw.cand
    lane = sw.lane
    bl = sw.bl
    bh = sw.bhat
    bv = sw.bvar
    Lp = _pad_entries(m, L, sw)
    xs = sw.xs[:n * Lp].reshape((n, Lp))
    Ps = sw.Ps[:n * n * Lp].reshape((n, n, Lp))
    for i in range(n):
        for p in range(Lp):
            xs[i, p] = xa[i, lane[p]]
    for i in range(n):
        for j in range(n):
            for p in range(Lp):
                Ps[i, j, p] = P[i, j, lane[p]]
    _predicted_cost_lanes(cand, xs, Ps, scheme.filter, rc, scheme.engine, ctl.K,
                          ctl.lo_dev, ctl.hi_dev, sw)
    for p in range(m):
        a = cand[p]
        l = lane[p]
        obj = sw.cost[p]
        for k in range(N_MODES):
            bl[k] = belief[k, l]
        for j in range(N_FAULT):
            bh[j] = xs[N_X + j, p]
            bv[j] = Ps[N_X + j, N_X + j, p]
        belief_update(bl, scheme.belief, bh, bv, sw.bwork)
        for k in range(N_MODES):
            obj += bl[k] * (rc.JN[k, a] + rc.penalty[cur[l], a])
        sw.obj[a, l] = obj


@kernel(inline="always")
def controller_objectives_lanes(cur, xa, P, belief, scheme, sw):
    """The objectives of :func:`controller_objectives` that can decide each
    lane's choice, into ``sw.obj`` (3, L); ``+inf`` for the others.

    Every lane's objective ``obj(a) = I(a) + sum_m b_{k+H}(m) (J^N(m, a) +
    P(c, a))`` needs the horizon's covariance only through the belief
    ``b_{k+H}``, and the covariance is nearly all the work.  So, per lane:

    1. the short-horizon cost ``I(a)`` of each controller ``a`` other than
       the one in use ``c`` from the state alone (:func:`_state_cost_lanes`,
       exact), and a lower bound of its objective from it
       (:func:`objective_floor`);
    2. the full objective of ``c``: horizon with covariance, belief update,
       terminal cost and penalty (:func:`_entry_objectives`);
    3. the full objective of each other controller whose bound does not
       exceed ``c``'s objective; one whose bound does cannot be the smallest,
       and is left at ``+inf``.

    Steps 1 and 3 run on the lanes that need them, gathered (``sw.lane``), and
    step 3 with a controller per gathered lane (``sw.cand``).  On the trials
    of ``configs/paper_tables.yaml`` about 1.3 of the 3 controllers per lane
    get a full objective (``docs/findings/performance.md`` lesson 19).  Every
    objective written equals ``controller_objectives(cur[l], xa[:, l],
    P[:, :, l], belief[:, l], ...)`` bit for bit, and the smallest is the same
    controller.

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
    floor = sw.floor
    lane = sw.lane
    for a in range(N_CONTROLLERS):
        for l in range(L):
            sw.obj[a, l] = math.inf
            floor[a, l] = -math.inf
    for a in range(N_CONTROLLERS):
        m = 0
        for l in range(L):
            if cur[l] != a:
                lane[m] = l
                m += 1
        if m == 0:
            continue
        Lp = _pad_entries(m, L, sw)
        xs = sw.xs[:n * Lp].reshape((n, Lp))
        for i in range(n):
            for p in range(Lp):
                xs[i, p] = xa[i, lane[p]]
        _state_cost_lanes(a, xs, scheme.filter, rc, scheme.engine, ctl.K, ctl.lo_dev,
                          ctl.hi_dev, sw)
        for p in range(m):
            l = lane[p]
            floor[a, l] = objective_floor(sw.cost[p], rc, cur[l], a)
    for l in range(L):
        sw.cand[l] = cur[l]
        lane[l] = l
    _entry_objectives(L, cur, xa, P, belief, scheme, sw)
    m = np.int64(0)  # not the literal 0: a literal count would be a signature of its own
    for l in range(L):
        c = cur[l]
        for a in range(N_CONTROLLERS):
            if a != c and not floor[a, l] > sw.obj[c, l]:
                sw.cand[m] = a
                lane[m] = l
                m += 1
                if m == L:
                    _entry_objectives(m, cur, xa, P, belief, scheme, sw)
                    m = np.int64(0)
    if m > 0:
        _entry_objectives(m, cur, xa, P, belief, scheme, sw)


@kernel(inline="always")
def select_controllers_lanes(cur, xa, P, belief, scheme, sw):
    """``tests/single_trajectory.py::select_controller`` for every lane; ``cur`` is updated in place.

    The controller with the smallest objective (the first of equal ones), the
    one in use when none is finite; objectives that cannot be the smallest are
    not computed (:func:`controller_objectives_lanes`), which changes no
    choice.  Parameters are those of :func:`controller_objectives_lanes`.
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
