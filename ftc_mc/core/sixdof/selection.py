"""The selection among the four 6-DOF controllers (eqs. 45-47).

A design with ``controller: lock_turn_selected`` keeps the paper's structure
on the flying wing: a mode belief, and every reconfiguration period a
rolling-horizon choice among controllers, now four:

* ``c0``: the paper's nominal controller with the lateral autopilot (or the
  coupled 6-DOF c0, ``controller.coupling``), :func:`~ftc_mc.core.sixdof.loop.loop_command`;
* ``c1``: the paper's engine-fault controller (Theorem 4.1's tables) with the
  lateral autopilot (or the coupled c1);
* ``c2``, ``c3``: the lock-turn controller of the left and of the right elevon
  (:mod:`ftc_mc.core.sixdof.lockturn`): the throttle and the healthy elevon
  fly pitch and roll together.

**Belief** (eqs. 12-14).  The four modes ``m0`` to ``m3`` are read from the
side monitor's estimate of the six fault parameters (``b0`` and ``b1`` of the
throttle, the left and the right elevon), which roll makes separable: the
paper's mode boxes, per actuator (``ftc_mc/sim/selection.py``), and its
``T_M``, updated at the end of each reconfiguration period by
:func:`sixdof_select`, which ``advance`` calls on this design's compile path
only (:func:`ftc_mc.core.longitudinal.trial.six_dof_selection`), before
:func:`ftc_mc.core.longitudinal.stages.reconfigure` (which then only
records it; the paper's 3-controller selection is not compiled there).

**Objective** (eq. 47), per lane and action ``a``::

    I^H(a) + sum_m b(m) (J^N(m, a) + P(c, a))

* ``I^H(a)`` (eq. 45): the discounted cost of ``a`` over the horizon ``H``
  (``controller.horizon_s``), predicted by :func:`action_cost` from the side
  monitor's estimate (on its rows; the trim elsewhere), with its estimated
  faults (eq. 2 per actuator), each law reading the predicted state, on the
  plant's model as the lock-turn law's rollouts fly it
  (:func:`~ftc_mc.core.sixdof.lockturn.rollout_step`: the linear 6-DOF model
  on the linear plant, the airframe's equations with ``ro_sub`` RK4
  sub-steps on the nonlinear one; still air), which is also the model the
  lock-turn table is designed on (``monitor.turn_model: auto``; flown on the
  monitor's linear model instead, the table of the equations diverged and
  the selection never chose it);
* ``J^N(m, a)`` (eq. 46): the regret table of ``a`` in mode ``m``, computed
  off line by the same :func:`action_cost` (``ftc_mc/sim/selection.py``);
* ``P(c, a)``: the switching penalty from the controller in use ``c``;
* ``b(m)``: the belief updated at this period.  The paper weighs ``J^N`` by
  the belief predicted under each action, which differs between actions only
  through the predicted covariance; the prediction here carries no
  covariance, so every action is weighed by the same belief.

The lane then flies the action chosen (``LaneState.cur``, 0 to 3; for ``c2``
and ``c3`` also ``LaneState.mside``, the block code of the elevon, and
``mturn``, the step the law took over), until the next period.  Unlike a
``lock_turn`` design, the monitor's decision does not switch the law in, and
a later period may switch back or to the other side.

**What the prediction flies.**  The lock-turn law without its rollouts
(:func:`~ftc_mc.core.sixdof.lockturn.base_law`: the scheduled LQR where a
steady flight brackets the lock estimate, else the trim commands held), on
the lock position the estimate gives under the law's command to the locked
elevon; the paper's controllers without their excitation, saturated as the
commands stage saturates them.  The lateral loop's elevon model advances as
in the truth stage.  The stage cost (eq. 45) weighs the 6-DOF states by
``Reconfig.q_lqr`` (15: the paper's ``Q_lqr`` on the states of the same
names, along-track and height; zero on the others) and the commands less the
6-DOF trim's by ``r_lqr``.  A probe (``monitor.turn_probe_rad``) rides on the
named elevon as in a ``lock_turn`` design, but no lane hands back on it: the
selection itself may switch back.

Plain-NumPy twins: ``tests/naive_sixdof.py::action_cost_ref``,
``sixdof_select_ref``.
"""

from __future__ import annotations

import math

import numpy as np

from ...conventions import (C_ENGINE, I_B0_ELEVONS, I_B0_THRUST, I_B1_LEFT, I_B1_RIGHT,
                            I_B1_THRUST, N_AUG, N_MODES, N_U, N_X)
from ..jit import kernel
from ..longitudinal.control import controller_command
from ..shared.belief import belief_update_lane
from ..shared.excitation import saturate
from .layout import N_STATE, N_WIND, STATE, U_LEFT, U_RIGHT
from .lockturn import base_law, rollout_step
from .loop import (LAT_LEFT, LAT_RIGHT, LATERAL_LOOP, N_LAT, N_LAT_MEASURED, elevon_model,
                   loop_command)
from .monitor import follows, on_trim, position
from .plant import N_WORK

N_SELECTED = 4
"""The four controllers the selection chooses among: c0, c1, c2 (left elevon),
c3 (right elevon)."""
C_LEFT_TURN = 2
"""The first lock-turn controller: ``c2`` flies side 0 (left), ``c3`` side 1;
a lane flying ``c_a`` holds the block code ``a`` in ``LaneState.mside`` (the
elevon's command index plus one)."""

LAT_STATE = np.array([STATE[n] for n in LATERAL_LOOP[:N_LAT_MEASURED]], dtype=np.int64)
"""The 6-DOF state of each measured row of the lateral loop."""


@kernel(internal=True)
def action_cost(pl, ctl, eng, rc, a, x6, mlr, bhat, btrue, n_steps):
    """Discounted cost (eq. 45) of controller ``a`` flown ``n_steps`` control
    periods (steps) on the plant's model (module docstring).

    Parameters
    ----------
    pl : SixDofTruth
        The plant's model (:func:`~ftc_mc.core.sixdof.lockturn.rollout_step`),
        its trim ``x0``, ``lon_state``, ``u_ff``, ``a_act``, the lateral gains
        and ``monitor`` (``u0``, ``u_ff``, and ``turn``: the lock-turn table
        and the sub-steps ``ro_sub`` of the airframe's equations).
    ctl : Controller
        The paper's nominal gain ``K`` and the command limits ``lo_dev``, ``hi_dev``.
    eng : EngineTables
        c1's tables.
    rc : Reconfig
        ``alpha``, ``q_lqr`` (15,) on the 6-DOF states, ``r_lqr`` (3,).
    a : int
        Controller: 0 to 3 (:data:`N_SELECTED`).
    x6 : ndarray, shape (15,)
        Start: the absolute 6-DOF state.
    mlr : ndarray, shape (2,)
        Start: the lateral loop's model of the left and right elevon commands.
    bhat : ndarray, shape (6,)
        The fault parameters the laws read (``b0``, then ``b1``, of the
        throttle, the left and the right elevon; the monitor's order).
    btrue : ndarray, shape (6,)
        The fault parameters the model flies (eq. 2 per actuator).
    n_steps : int

    Returns
    -------
    float
        ``sum_{k=1..n} alpha^k (x_k' Q x_k + (u_{k-1} - u_ff)' R (u_{k-1} - u_ff))``,
        ``x_k`` the 6-DOF state less the trim; ``inf`` when it is not finite.
    """
    mon = pl.monitor
    tab = mon.turn
    nu = mon.B.shape[1]
    xs = x6.copy()
    dev = np.empty(N_STATE)
    cmd = np.empty(N_U)
    wd = np.zeros(N_WIND)
    rk = np.empty((N_WORK, N_STATE))
    xa = np.zeros(N_AUG)
    xl = np.empty(N_X + N_LAT)
    du = np.empty(N_U)
    up = np.empty(N_U)
    u = np.empty((N_U, 1))
    xa[I_B0_THRUST] = bhat[0]
    xa[I_B0_ELEVONS] = bhat[1] + bhat[2]
    xa[I_B1_THRUST] = bhat[nu]
    xa[I_B1_LEFT] = bhat[nu + 1]
    xa[I_B1_RIGHT] = bhat[nu + 2]
    m_l = mlr[0]
    m_r = mlr[1]
    lag = pl.a_act
    s = a - C_LEFT_TURN
    p = 0.0
    if s >= 0:  # the lock position the estimate gives under the law's command
        j = tab.locked[s]
        p = follows(bhat[j], bhat[nu + j], tab.hold[j] + mon.u0[j])
    for i in range(N_STATE):
        dev[i] = xs[i] - pl.x0[i]
    cost = 0.0
    disc = 1.0
    for _ in range(n_steps):
        if s < 0:
            for i in range(N_X):
                xa[i] = dev[pl.lon_state[i]]
            controller_command(a, xa, ctl.K, eng, mon.u0, up)
            for i in range(N_U):
                u[i, 0] = saturate(up[i], 0.0, 0.0, ctl.lo_dev[i], ctl.hi_dev[i])
            for i in range(N_X):
                xl[i] = xa[i]
            for i in range(N_LAT_MEASURED):
                xl[N_X + i] = dev[LAT_STATE[i]]
            xl[N_X + LAT_LEFT] = m_l
            xl[N_X + LAT_RIGHT] = m_r
            loop_command(pl, ctl.lo_dev, ctl.hi_dev, a, xa[I_B0_THRUST], xa[I_B1_THRUST], xl,
                         du, u, 0)
        else:
            base_law(tab, pl, s, p, xs, ctl.lo_dev, ctl.hi_dev, u, 0)
        m_l = elevon_model(lag, m_l, u[U_LEFT, 0], pl.u_ff[U_LEFT])
        m_r = elevon_model(lag, m_r, u[U_RIGHT, 0], pl.u_ff[U_RIGHT])
        for c in range(nu):  # eq. 2: the absolute position the actuator takes
            cmd[c] = follows(btrue[c], btrue[nu + c], u[c, 0] + mon.u0[c])
        rollout_step(tab, pl, xs, cmd, wd, rk)  # its envelope check is not used here
        disc *= rc.alpha
        stage = 0.0
        for c in range(nu):
            d = u[c, 0] - mon.u_ff[c]
            stage += rc.r_lqr[c] * d * d
        for i in range(N_STATE):
            dev[i] = xs[i] - pl.x0[i]
            stage += rc.q_lqr[i] * dev[i] * dev[i]
        cost += disc * stage
    if not math.isfinite(cost):
        return math.inf
    return cost


@kernel(internal=True)
def select_four(pl, scheme, k, st, work):
    """Eq. 47 among the four controllers, on every live lane at step ``k``
    (module docstring); ``st.cur``, ``st.mside``, ``st.mturn`` and
    ``st.mpos`` updated.

    Parameters
    ----------
    pl : SixDofTruth
    scheme : Scheme
        ``reconfig`` (``horizon``, ``JN`` (4, 4), ``penalty`` (4, 4)),
        ``controller``, ``engine``.
    k : int
        Step (a reconfiguration period's end).
    st : LaneState
        Reads ``mx``, ``lat``, ``belief``, ``alive``.
    work : TrialWork
        ``u``: the commands of the step (:func:`~ftc_mc.core.sixdof.monitor.position`).
    """
    mon = pl.monitor
    rc = scheme.reconfig
    ns = mon.A.shape[0]
    nu = mon.B.shape[1]
    x6 = np.empty(N_STATE)
    mlr = np.empty(2)
    bh = np.empty(2 * nu)
    for l in range(st.mx.shape[1]):
        if not st.alive[l]:
            continue
        on_trim(mon, pl, st.mx[:, l], x6)
        for i in range(2 * nu):
            bh[i] = st.mx[ns + i, l]
        mlr[0] = st.lat[LAT_LEFT, l]
        mlr[1] = st.lat[LAT_RIGHT, l]
        cur = st.cur[l]
        best = cur
        best_obj = math.inf
        for a in range(N_SELECTED):
            obj = action_cost(pl, scheme.controller, scheme.engine, rc, a, x6, mlr, bh, bh,
                              rc.horizon)
            for m in range(N_MODES):
                obj += st.belief[m, l] * (rc.JN[m, a] + rc.penalty[cur, a])
            if obj < best_obj:
                best_obj = obj
                best = a
        st.cur[l] = best
        if best <= C_ENGINE:
            st.mside[l] = 0
        elif st.mside[l] != best:
            st.mside[l] = best
            st.mturn[l] = k
            st.mpos[l] = position(mon, st.mx, ns, nu, best - 1, l, work.u)


@kernel(internal=True)
def sixdof_select(pl, scheme, kn, st, work):
    """At the end of a reconfiguration period (step ``kn``), every lane's
    belief (eqs. 13-14: ``scheme.belief``'s ``T_M`` and its boxes on the side
    monitor's six fault parameters, with their marginal variances; eq. 12)
    and then the selection (:func:`select_four`).  ``st.belief`` is updated
    on every lane, as the paper's is
    (:func:`ftc_mc.core.longitudinal.stages.reconfigure`, which then records
    it)."""
    mon = pl.monitor
    ns = mon.A.shape[0]
    npar = 2 * mon.B.shape[1]
    bl = np.empty(N_MODES)
    bw = np.empty(2 * N_MODES)
    bh = np.empty(npar)
    bv = np.empty(npar)
    for l in range(st.mx.shape[1]):
        belief_update_lane(st.belief, l, scheme.belief, st.mx, st.mP, ns, True, bl, bh, bv, bw)
    select_four(pl, scheme, kn, st, work)
