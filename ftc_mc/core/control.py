"""The three controllers and the rolling-horizon controller selection (section 4).

Controllers (command deviations before the saturation and excitation of eq. 15):

* ``c0`` nominal: ``U = -K x_hat`` (eq. 19);
* ``c1`` engine fault: ``U = -K(b0_T, b1_T) x_hat - k(b0_T, b1_T)`` with Theorem
  4.1's gain and affine term interpolated in the offline tables (eq. 44);
* ``c2`` redundant-elevon fault: thrust ``-K_1 x_hat``, elevons by the
  minimum-norm allocation of eqs. 20-25 (eq. 25 corrected, see
  :func:`ftc_mc.design.theorem41.elevon_allocation`).

Selection (eqs. 45-47), every reconfiguration period: for each controller ``a``
the estimate and covariance are predicted ``H`` steps ahead with ``a`` in the
loop (zero innovations: the covariance gets its measurement updates, the state
follows the model), giving the short-horizon cost ``I(a)`` (eq. 45) and
``P_{k+H|k+H}``; the belief is updated with it (eqs. 13-14) and the controller
minimising ``I(a) + sum_m b_{k+H}(m) (J^N(m, a) + P(c, a))`` (eqs. 46-47) is
chosen.
"""

from __future__ import annotations

import math

import numpy as np

from .belief import belief_update
from .excitation import saturate
from .interp import engine_controller
from .jit import kernel
from .kalman import predict, project, update

from ..conventions import C_ELEVON, C_ENGINE, C_NOMINAL  # noqa: E402,F401


@kernel
def elevon_allocation(K2x, b0e, b1L, b1R, u0L, u0R):
    """Minimum-norm elevon commands with ``Phi = 0`` (eqs. 20-25, eq. 25 corrected).

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


@kernel
def controller_command(c, xa, K, eng, u0, U):
    """Command of controller ``c`` from an augmented estimate (no saturation).

    Parameters
    ----------
    c : int
        ``C_NOMINAL``, ``C_ENGINE`` or ``C_ELEVON``.
    xa : ndarray, shape (14,)
        Augmented estimate ``[x, b0_T, b0_e, b1_T, b1_L, b1_R]``.
    K : ndarray, shape (3, 9)
        Nominal gain.
    eng : EngineTables
    u0 : ndarray, shape (3,)
        Trim commands.
    U : ndarray, shape (3,)
        Written with the command deviation.
    """
    if c == C_ENGINE:
        engine_controller(eng, xa[9], xa[11], xa, U)
        return
    for i in range(3):
        acc = 0.0
        for j in range(9):
            acc -= K[i, j] * xa[j]
        U[i] = acc
    if c == C_ELEVON:
        U[1], U[2] = elevon_allocation(-U[1], xa[10], xa[12], xa[13], u0[1], u0[2])


@kernel
def horizon_cost(c, xs, Ps, fm, rc, eng, K, lo, hi, work, phi, T):
    """Predict ``H`` steps with controller ``c``; return the discounted cost (eq. 45).

    ``xs`` and ``Ps`` are advanced in place to ``X_{k+H|k}`` and
    ``P_{k+H|k+H}`` (zero innovations).

    Parameters
    ----------
    c : int
    xs : ndarray, shape (14,)
    Ps : ndarray, shape (14, 14)
    fm : FilterModel
    rc : Reconfig
    eng : EngineTables
    K : ndarray, shape (3, 9)
    lo, hi : ndarray, shape (3,)
        Command limits as deviations.
    work : ndarray, shape (4, 14)
        Work rows (command, predicted measurement, update gain).
    phi, T : ndarray, shape (9, 5) and (9, 14)
        Work arrays of :func:`ftc_mc.core.kalman.predict`.
    """
    U = work[0, :3]
    z = work[1, :12]
    h = work[2]
    cost = 0.0
    disc = 1.0
    for _ in range(rc.horizon):
        controller_command(c, xs, K, eng, fm.u0, U)
        for i in range(3):
            U[i] = saturate(U[i], 0.0, 0.0, lo[i], hi[i])
        predict(xs, Ps, U, fm, phi, T)
        for r in range(12):
            s = fm.c_ident[r]
            if s >= 0:
                z[r] = xs[s]
            else:
                acc = 0.0
                for j in range(9):
                    acc += fm.C[r, j] * xs[j]
                z[r] = acc
        update(xs, Ps, z, fm, h)
        project(xs, fm)
        disc *= rc.alpha
        stage = 0.0
        for j in range(9):
            stage += rc.q_lqr[j] * xs[j] * xs[j]
        for i in range(3):
            stage += rc.r_lqr[i] * U[i] * U[i]
        cost += disc * stage
    return cost


@kernel
def select_controller(current, xa, P, belief, fm, bs, rc, eng, K, lo, hi, xs, Ps, bl, work,
                      phi, T):
    """Rolling-horizon choice of the controller (eqs. 45-47) for one trajectory.

    Parameters
    ----------
    current : int
        Controller in use (for the switching penalty ``P(c, a)``).
    xa : ndarray, shape (14,)
    P : ndarray, shape (14, 14)
    belief : ndarray, shape (4,)
        Current mode probabilities.
    fm : FilterModel
    bs : Belief
    rc : Reconfig
    eng : EngineTables
    K : ndarray, shape (3, 9)
    lo, hi : ndarray, shape (3,)
    xs, Ps, bl, work, phi, T : ndarray
        Scratch of shapes (14,), (14, 14), (4,), (4, 14), (9, 5), (9, 14).

    Returns
    -------
    int
        The selected controller.
    """
    best = current
    best_obj = math.inf
    bv = work[3, :5]
    bw = work[3, 5:13]
    for a in range(3):
        for i in range(14):
            xs[i] = xa[i]
            for j in range(14):
                Ps[i, j] = P[i, j]
        obj = horizon_cost(a, xs, Ps, fm, rc, eng, K, lo, hi, work, phi, T)
        for m in range(4):
            bl[m] = belief[m]
        for j in range(5):
            bv[j] = Ps[9 + j, 9 + j]
        belief_update(bl, bs, xs[9:], bv, bw)
        for m in range(4):
            obj += bl[m] * (rc.JN[m, a] + rc.penalty[current, a])
        if obj < best_obj:
            best_obj = obj
            best = a
    return best


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
    xa = np.zeros(14)
    for j in range(5):
        xa[9 + j] = best[j]
    x = np.zeros(9)
    xn = np.zeros(9)
    U = np.zeros(3)
    e = np.zeros(3)
    cost = 0.0
    disc = 1.0
    for _ in range(n_steps):
        for j in range(9):
            xa[j] = x[j]
        controller_command(c, xa, K, eng, fm.u0, U)
        stage = 0.0
        for i in range(3):
            U[i] = saturate(U[i], 0.0, 0.0, lo[i], hi[i])
            e[i] = b0[i] + (1.0 - b1[i]) * U[i] - b1[i] * fm.u0[i]
            stage += r_lqr[i] * U[i] * U[i]
        for j in range(9):
            stage += q_lqr[j] * x[j] * x[j]
        cost += disc * stage
        disc *= alpha
        for i in range(9):
            acc = 0.0
            for j in range(9):
                acc += fm.A[i, j] * x[j]
            for j in range(3):
                acc += fm.B[i, j] * e[j]
            xn[i] = acc
        for i in range(9):
            x[i] = xn[i]
    return cost
