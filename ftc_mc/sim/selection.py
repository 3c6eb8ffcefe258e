"""Settings of the selection among the four 6-DOF controllers.

A ``controller: lock_turn_selected`` design (:mod:`ftc_mc.core.sixdof.selection`)
keeps the paper's belief and selection, read on the 6-DOF model:

* **Belief** (:func:`sixdof_belief`): the paper's mode boxes
  (:func:`ftc_mc.sim.estimator.belief_settings`) per actuator on the side
  monitor's six fault parameters ``[b0_T, b0_L, b0_R, b1_T, b1_L, b1_R]``: in
  the nominal mode each ``b1`` in ``[0, beta]`` and each ``b0`` within
  ``+-b0_nominal`` (the elevon's for both elevons); in mode ``m1``, ``m2``,
  ``m3`` the throttle's, the left or the right elevon's ``b1`` in
  ``[beta, 1]`` and its ``b0`` over the paper's box (the throttle's command
  range, or the elevon one the paper takes for both elevons); the paper's
  ``T_M``.
  The paper's longitudinal filter carries the two elevons' ``b0`` as one sum;
  the monitor has one per elevon, which roll tells apart.
* **Weights** (:func:`sixdof_q_lqr`): the paper's ``Q_lqr`` on the 6-DOF
  states of the same names (``x``, ``z``), nothing on the others.
* **Terminal costs** (:func:`sixdof_terminal_costs`): ``J^N(m, a)`` as the
  paper's (:mod:`ftc_mc.design.terminal`: the mean discounted cost of ``a``
  over ``controller.terminal_horizon_s`` from trim, with the fault and the
  state known, over representative faults of mode ``m``; as regrets), flown
  by :func:`ftc_mc.core.sixdof.selection.action_cost` on the plant's model
  (the linear 6-DOF model, or the airframe's equations: the model the
  lock-turn table is designed on).  A flight whose state the equations no
  longer hold finite (the aircraft departed) costs as much as the most
  expensive finite flight of the table.  The elevon locks are :data:`SIXDOF_ELEVON_OFFSETS_DEG`
  from the 6-DOF trim, where a controller can fly on
  (``docs/findings/sixdof-survival.md``, "Which locks can be flown steadily"); the engine's
  locks and every loss are the paper's.
"""

from __future__ import annotations

import math

import numpy as np

from ..conventions import LONGITUDINAL
from ..core.longitudinal.settings import Belief, Reconfig
from ..core.sixdof.layout import COMMAND, N_STATE, STATE, sixdof_name
from ..core.sixdof.lockturn import SELECTED_TURN
from ..core.sixdof.selection import N_SELECTED, action_cost
from ..design.terminal import ENGINE_LOCKS, representative_faults

SIXDOF_ELEVON_OFFSETS_DEG = (-4.0, -2.0, 0.0, 2.0, 4.0)
"""Representative elevon locks of the 6-DOF terminal costs [deg from the
6-DOF trim]: inside the linear model's trimmable set of ``x8-pyfly``
(-4.9 to +5.7 deg on the left)."""


def sixdof_belief(paper: Belief) -> Belief:
    """The four modes' boxes on the side monitor's six fault parameters, from
    the paper's on its five (``[b0_T, b0_e, b1_T, b1_L, b1_R]``; module
    docstring)."""
    cols = [0, 1, 1, 2, 3, 4]  # each monitor parameter's column among the paper's
    lo = paper.lo[:, cols].copy()
    hi = paper.hi[:, cols].copy()
    # the paper's elevon b0 column is free in modes 2 and 3; per elevon only
    # the faulty one's is, the other keeps the nominal box
    for m, free, other in ((2, 1, 2), (3, 2, 1)):
        lo[m, other], hi[m, other] = paper.lo[0, 1], paper.hi[0, 1]
        assert hi[m, free] > hi[0, 1]
    return Belief(TM=paper.TM.copy(), lo=np.ascontiguousarray(lo),
                  hi=np.ascontiguousarray(hi))


def sixdof_q_lqr(q_lqr: np.ndarray) -> np.ndarray:
    """The paper's ``Q_lqr`` diagonal (9, longitudinal states) on the 6-DOF
    states of the same names (15); zero on the others."""
    q = np.zeros(N_STATE)
    for i, name in enumerate(LONGITUDINAL.states):
        q[STATE[sixdof_name(name)]] = q_lqr[i]
    return q


def _flight_costs(truth, ctl, eng, rc: Reconfig, n_steps: int) -> list:
    """Per mode and action, the costs of the action's flights over the mode's
    representative faults from the 6-DOF trim, state and faults known
    (module docstring)."""
    mon = truth.monitor
    trim = mon.u0 + mon.u_ff
    elevon = [tuple(trim[COMMAND[side]] + math.radians(d) for d in SIXDOF_ELEVON_OFFSETS_DEG)
              for side in ("left", "right")]
    faults = representative_faults((ENGINE_LOCKS, elevon[0], elevon[1]))
    mlr = np.zeros(2)
    costs = [[[action_cost(truth, ctl, eng, rc, a, truth.x0, mlr, b, b, n_steps)
               for b in (np.concatenate(f) for f in mode_faults)]
              for a in range(N_SELECTED)] for mode_faults in faults]
    return costs


def sixdof_terminal_costs(truth, ctl, eng, rc: Reconfig, n_steps: int) -> np.ndarray:
    """``J^N`` regrets as a (4, 4) array: modes (nominal, engine, left, right)
    by controllers (c0, c1, left and right lock-turn); module docstring.

    Parameters
    ----------
    truth : SixDofTruth
        The plant's model, its trim, the lateral loop, and its side monitor's
        lock-turn table.
    ctl : Controller
    eng : EngineTables
    rc : Reconfig
        ``alpha``, ``q_lqr`` (15,), ``r_lqr``.
    n_steps : int
        Steps of the simulated rest of the mission.
    """
    costs = _flight_costs(truth, ctl, eng, rc, n_steps)
    worst = max(c for mode in costs for a in mode for c in a if math.isfinite(c))
    JN = np.array([[np.mean([c if math.isfinite(c) else worst for c in a]) for a in mode]
                   for mode in costs])
    return JN - JN.min(axis=1, keepdims=True)


def selection_settings(truth, ctl, eng, rc: Reconfig, paper: Belief, n_steps: int):
    """``(Reconfig, Belief)`` of a ``lock_turn_selected`` design: ``rc`` with
    its kind, the 6-DOF weights, the (4, 4) terminal costs and the
    (4, 4) switching penalty (``rc``'s off-diagonal value); and the
    six-parameter belief (module docstring)."""
    pen = float(rc.penalty[0, 1])
    six = rc._replace(kind=SELECTED_TURN, q_lqr=sixdof_q_lqr(rc.q_lqr),
                      penalty=pen * (1.0 - np.eye(N_SELECTED)))
    six = six._replace(JN=sixdof_terminal_costs(truth, ctl, eng, six, n_steps))
    return six, sixdof_belief(paper)
