"""Terminal costs ``J^N(m, a)`` of the controller selection (eq. 46), by simulation.

``J^N(m, a)`` is the expected discounted cost (eq. 18) of running controller
``a`` for the rest of the mission while the UAV is in mode ``m``.  The paper
computes it "numerically with the indicator of performance off-line" and says
no more; here it is the mean, over a fixed set of representative faults of mode
``m``, of the discounted cost of ``a`` on the noise-free linear plant over
``n_steps`` steps from trim, with perfect knowledge of the state and of the
fault parameters (:func:`ftc_mc.core.longitudinal.control.policy_cost`):

* nominal: no fault (so ``J^N(0, a)`` is zero for every ``a``: from trim, with
  no fault and no noise, no controller has anything to do);
* engine: locks at throttle 0, 0.2, ..., 1 and losses of 0.3, 0.6, 0.9;
* left (right) elevon: locks at -0.4, -0.2, 0, 0.2, 0.4 rad and losses of 0.3,
  0.6, 0.9 of that elevon.

The costs are returned as *regrets*: each mode's row has its smallest entry
subtracted.  Eq. (47) weighs ``J^N(m, a)`` by the belief predicted *under each
action*, ``b_{k+H}(m | a)``, which differs between actions only through the
predicted covariance.  With raw costs, a mode whose cost is large for every
controller (an engine lock far from trim costs about 6e6 over 100 s whatever the
controller, since no controller can stop the drift) turns belief differences of
1e-7 into cost differences above the 0.1 switching penalty, and the selection
switched controller with no fault to justify it (measured: an engine locked at
trim switched c0 -> c2 at 38 s).  Subtracting the part of ``J^N(m, .)`` that no
choice of controller can avoid leaves the differences between controllers,
which are what the selection is about.
"""

from __future__ import annotations

import numpy as np

from ..core.longitudinal.control import policy_cost

ENGINE_LOCKS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)
ELEVON_LOCKS = (-0.4, -0.2, 0.0, 0.2, 0.4)
LOSSES = (0.3, 0.6, 0.9)


def representative_faults(locks=(ENGINE_LOCKS, ELEVON_LOCKS, ELEVON_LOCKS)):
    """Per mode, a list of per-actuator ``(b0, b1)`` truths (module docstring;
    ``locks``: the lock positions of the throttle, the left and the right
    elevon, absolute)."""
    modes = [[(np.zeros(3), np.zeros(3))], [], [], []]
    for m, act in ((1, 0), (2, 1), (3, 2)):
        for p in locks[act]:
            b0, b1 = np.zeros(3), np.zeros(3)
            b0[act], b1[act] = p, 1.0
            modes[m].append((b0, b1))
        for loss in LOSSES:
            b0, b1 = np.zeros(3), np.zeros(3)
            b1[act] = loss
            modes[m].append((b0, b1))
    return modes


def terminal_costs(fm, K, eng, lo, hi, alpha, q_lqr, r_lqr, n_steps):
    """``J^N`` regrets as a (4, 3) array: modes (nominal, engine, left, right) x controllers.

    Parameters
    ----------
    fm : FilterModel
    K : ndarray, shape (3, 9)
        Nominal gain.
    eng : EngineTables
    lo, hi : ndarray, shape (3,)
        Command limits as deviations from trim.
    alpha : float
        Discount factor.
    q_lqr, r_lqr : ndarray
        Diagonals of Q_lqr and R_lqr.
    n_steps : int
        Steps of the simulated rest of the mission.
    """
    JN = np.zeros((4, 3))
    for m, faults in enumerate(representative_faults()):
        for a in range(3):
            costs = []
            for b0, b1 in faults:
                best = np.array([b0[0], b0[1] + b0[2], b1[0], b1[1], b1[2]])
                costs.append(policy_cost(a, fm, K, eng, lo, hi, b0, b1, best, alpha,
                                         q_lqr, r_lqr, n_steps))
            JN[m, a] = float(np.mean(costs))
    return JN - JN.min(axis=1, keepdims=True)
