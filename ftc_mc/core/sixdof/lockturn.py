"""Flying on with one elevon: the lock-turn law scheduled on the side monitor.

A design with ``controller: lock_turn`` flies the paper's reconfiguring loop
until the side monitor (:mod:`ftc_mc.core.sixdof.monitor`) names an elevon.
From that step on the lane flies the lock-turn controller of that side
(:mod:`ftc_mc.design.lock_turn`): a discounted LQR on the throttle and the
healthy elevon about the steady turn closest to the nominal glide that the
lock allows; the lateral autopilot (wings level, heading hold) is off, and the
paper's controllers keep running unheard.  The first elevon the monitor names
is kept: a later decision (the monitor's Jacobians about wings-level flight
describe a banked turn less well) does not switch sides.

**Schedule.**  The designs form a table over lock positions on a uniform grid
per side (``LockTurnTable.lo``, ``step``).  Each step, the law is interpolated
linearly between the two designs around the monitor's current estimate of the
lock position ``p = b0 + (1 - b1)(u + u0)`` (``LaneState.mpos``; clamped to
the grid's ends), entry by entry: the design state ``x*`` and commands ``u*``,
the gain ``K`` and the bias ``k`` of Theorem 4.1.

**No steady flight.**  Where neither grid point bracketing ``p`` (the last
two beyond the grid's end) has a steady flight of its own in the design box
(``LockTurnTable.steady``: their designs are about the nearest lock that has
one, with Theorem 4.1's bias), no linear law about a steady flight applies.
There the throttle and the healthy elevon either hold the 6-DOF trim commands
(``LockTurnTable.hold``; ``monitor.turn_beyond: hold``): the oracle study
(``scripts/studies/study_lock_turn.py``) found that holding them keeps such locks in
the envelope longer than the biased designs (+3 deg from trim: 12.7 s against
6.8 s); or they fly the **rocking law** (``turn_beyond: rollout``,
:func:`rocking_law`).

**Rocking law** (a receding-horizon choice among bang-bang histories).  Each
step, from the lane's state (the monitor's estimate on its rows, the law's
fed-back states from their sensors where ``meas`` says so, the rest of the
6-DOF trim), the airframe's equations (:func:`~ftc_mc.core.sixdof.plant.propagate`,
``ro_sub`` RK4 sub-steps per period, still air, the named elevon at ``p``)
fly each candidate command history for ``ro_steps`` periods; on the linear
plant its own model flies them (:func:`rollout_step`: ``x+ = A x + B u`` in
deviations, the air data from its output map, as the truth).  A candidate
holds one pair (throttle, healthy elevon) for its first ``ro_first`` periods
and a second pair after (``ro_u``; a pair from the throttle's two limits and
``monitor.rollout_elevon_levels`` positions of the healthy elevon from limit
to limit: with 5, 10 held pairs and, per switch time, the 90 ordered pairs of
two different ones).  The envelope's excess after each period is the
largest of ``Va_min - Va``, ``Va - Va_max`` [m/s], ``alpha_min - alpha``,
``alpha - alpha_max``, ``|phi| - phi_max`` [deg] (``ro_env``; one m/s counts
as one degree, as ``scripts/studies/study_recoverable.py`` counts it).  The
candidate that stays inside
longest wins; among those that stay equally long, the one whose largest
excess before leaving is least (the widest margin); the first in the table
on a tie.  Its first pair is sent, and the choice is made again at the next
step.  When every candidate leaves within the first period (or the state is
not finite), the trim commands are held, as without the law.  With no steady
flight the lock rolls the wing at about 2.8 deg/s per degree of offset; the
histories that last swing it: roll with the lock while pitching up, then
mirror the lock with the healthy elevon and dive back to wings level, trading
height for time (``docs/findings/sixdof-rocking-guard.md``).

**Rollout guard** (``turn_beyond: guarded``, :func:`guarded_law`).  The
table is then designed with a wide box as well
(:func:`ftc_mc.design.lock_turn.envelope_box`: the validity envelope less
0.5 of each bound, and ``monitor.rollout_guard_bank_margin_deg`` below the
bank bound), so that a lock whose steady flights all lie outside the design
box (on ``x8-pyfly``, with the default 10 deg: locks from -15 to -11 deg of
trim, turns at 50 deg of bank and 12.5-14.7 m/s) has a design about its
own.  Flown directly from the nominal glide, such a design overshoots the
bank bound (oracle, designs at 59.5 deg: within 1.1-2.4 s; true lock and
state from 0.1 s after the lock).  So every step, before the LQR's command
is sent, the airframe's equations (the linear plant's model on the linear
plant) fly the LQR ``ro_steps`` periods from the lane's state (as the
rocking law does, the LQR applied to the flown state); if it leaves, candidates that first hold a pair (throttle, healthy elevon)
for ``gd_holds`` periods and then hand over to the LQR are flown too, and
the first pair of the one that stays inside longest (then with the widest
margin) is sent.  On the oracle's flights (designs at 59.5 deg) this kept
left and right locks from -14.5 to -10 deg in for 60 s, where the LQR alone
left.  Where no steady flight exists even in the wide box, the rocking law
flies.

**Law** (:func:`lock_turn_law`), on ``x_hat``: the ten fed-back states (bank,
pitch, body velocities and rates, the throttle and the healthy elevon), each
read from its sensor where one measures it and ``monitor.turn_feedback`` is
``measured`` (``LockTurnTable.meas``), else from the monitor's estimate (its
rows ``LockTurnTable.rows``; the actuators always).  The monitor's model is
linear about wings-level flight, and in the steep turns of locks far from
trim its estimate drifts from the truth (``docs/findings/sixdof-lock-turn.md``)::

    [throttle, healthy] = u* - K (x_hat - x*) - k,   clipped to the command limits

and the locked elevon is commanded to its trim position (``hold``): a locked
elevon does not move whatever its command, and an elevon the monitor named
wrongly (an engine change misread) stays where the nominal glide needs it,
instead of following the estimate of a lock it does not have (commanding it
to ``p`` let that estimate run away in the 6-DOF paper scenario).  Commands
and ``u*`` are deviations from the longitudinal trim ``u0``, ``x*`` from the
6-DOF trim, as the kernels hold them.

**Probe and hand-back** (:func:`turn_probe`, :func:`hands_back`; off when
``LockTurnTable.probe`` is 0).  The monitor names an elevon from the offset
it sees, and a partial loss of effectiveness offsets the elevon as a lock does
(by ``b1 (u + u0)``): with a steady command the two are the same to the
monitor, which then puts the offset into ``b0`` and estimates ``b1`` near 0
for both.  So while the law flies, the named elevon's command also carries a
3211 of amplitude ``probe`` (eq. 23's shape, ``probe_unit`` steps a unit)
from the step the law takes over (``LaneState.mturn``).  A locked elevon does
not move; one that still works follows it in proportion to ``1 - b1``, and the
monitor's ``b1`` of that side (its block was reset at the decision) learns
which.  The law is scheduled on the lock estimate without the probe
(``mpos - (1 - b1) probe``: a lock estimate that followed the probe would
move the law across the designs near the edge of the steady band).
``check`` steps after the law took over, a lane whose ``b1`` estimate
is below ``hand_back`` by at least ``hand_back_sd`` of its standard deviations
(the monitor's covariance) hands back: its ``mside`` turns negative, and from
that step it flies the paper's reconfiguring loop and lateral autopilot again,
for the rest of the flight (the monitor names no elevon after it).  In gusts
the probe hardly moves ``b1`` (``docs/findings/sixdof-selection.md``); its spread then keeps
the lane turning.

**Which block the paper's filter resets** (:func:`side_blocks`).  In a
``lock_turn`` design the monitor also decides which block of the paper's
longitudinal filter a reset opens: Table 1 still decides *when* (a residual
statistic reaches its threshold), and the actuator the design acts on decides
*which*: the elevon a lane flies the law about, else the actuator the monitor
named last (``LaneState.mlast``), each mapped to the longitudinal filter's
block (``conventions.LONGITUDINAL.actuator_block``: the throttle to the
thrust block, either elevon to the elevon block).  Until the monitor's first
decision Table 1 decides both.  The longitudinal filter sees a locked elevon
through pitch only, and once the law banks the wing its model (wings level)
reads the turn as a thrust change; the monitor reads roll and pitch together
(the side is decided by the direction's GLR).

**Resets from the monitor** (a design with ``resets: side_monitor``,
``Detection.source``; any controller).  The monitor then decides *when* as
well: at each step it names an actuator (``LaneState.mnow``) the
longitudinal filter resets that actuator's block, and Table 1's decisions
are dropped (``docs/findings/sixdof-monitor-resets.md``).  With ``resets:
either`` a step the monitor names no actuator keeps Table 1's decision (moved
as above in a ``lock_turn`` design).  The design's settle and start-up rules
still apply after it.

Plain-NumPy twins: ``tests/naive_sixdof.py::lock_turn_law_ref``,
``rocking_law_ref``, ``guarded_law_ref``, ``turn_probe_ref``, ``side_blocks_ref``.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ...conventions import LONGITUDINAL, NO_RESET, RESETS_SIDE_MONITOR, RESETS_TABLE1
from ..jit import kernel
from ..shared.excitation import signal_3211, signal_3211_length
from .kinds import LOCK_TURN, SELECTED_TURN  # noqa: F401 -- the kinds, by their module
from .layout import (N_COMMAND, N_STATE, N_WIND, SIXDOF_LINEAR, X_PHI, X_U, X_V, X_W,
                     Y_ALPHA, Y_VA)
from .monitor import on_trim
from .plant import N_WORK, linear_output, linear_step, propagate


DECISION_BLOCK = (NO_RESET,) + LONGITUDINAL.actuator_block
"""The longitudinal filter's block of each monitor decision code (0: none, then
the direction's index plus one; the directions are the commands, in the
longitudinal actuators' order: ``layout.MONITOR_DIRECTIONS``)."""

LockTurnTable = namedtuple("LockTurnTable", [
    "lo",    # (2,) absolute lock position [rad] of each side's first grid point (left, right)
    "step",  # grid step [rad]
    "x",     # (2, n, n_f) design state on the fed-back rows, less the 6-DOF trim
    "u",     # (2, n, 3) design commands less the longitudinal trim u0
    "K",     # (2, n, 2, n_f) gains on (throttle, healthy elevon)
    "k",     # (2, n, 2) Theorem 4.1's constant term
    "rows",  # (2, n_f) int64: the monitor's row of each fed-back state
    "meas",  # (2, n_f) int64: its measured output (the monitor's order), or -1: estimated
    "cmd",   # (2, 2) int64: command index of the throttle and the healthy elevon
    "locked",  # (2,) int64: command index of the locked elevon
    "steady",  # (2, n) 1.0: the lock has its own steady flight in the design box; 0.0: not
    "hold",    # (3,) the 6-DOF trim commands less u0: the locked elevon's command, and
               # the others' where neither lock bracketing the estimate is steady (unless
               # the rocking law flies there and a history stays in for a period)
    "probe",   # amplitude of the 3211 on the named elevon [rad]; 0.0: no probe, no hand-back
    "probe_unit",  # steps of one unit of that 3211
    "check",   # steps after the law took over at which the hand-back is judged
    "hand_back",  # the lane hands back when the monitor's b1 of the named elevon is below,
    "hand_back_sd",  # by at least this many of its standard deviations
    "ro_on",   # 1: the rocking law flies where no steady flight exists; 0: the trim is held
    "ro_steps",  # periods each candidate history is flown
    "ro_sub",  # RK4 sub-steps per period of those flights
    "ro_first",  # (n_c,) int64: periods of each candidate's first pair
    "ro_u",    # (2, n_c, 2, 2) per side and candidate, the first and the second pair
               # (throttle, healthy elevon) less the longitudinal trim u0
    "ro_env",  # (5,) envelope: Va min, max [m/s], alpha min, max [deg], |bank| max [deg]
    "gd_on",   # 1: the LQR flies under the rollout guard (turn_beyond: guarded); 0: not
    "gd_pairs",  # the guard's pairs: the first gd_pairs candidates of ro_u (the held ones)
    "gd_holds",  # (n_h,) int64: periods each of the guard's candidates holds its pair
])
"""The lock-turn designs of both sides over a grid of lock positions (module
docstring); ``x`` of shape ``(2, 0, n_f)`` when no design flies it.  Built by
:func:`ftc_mc.sim.monitor.lock_turn_table`."""


@kernel(inline="always")
def lock_turn_law(tab, pl, s, p, mx, z, lat, l, lo_dev, hi_dev, u):
    """Commands of lane ``l`` under the lock-turn law of side ``s`` (0 left,
    1 right) at the estimated lock position ``p`` [rad] (module docstring).

    Parameters
    ----------
    tab : LockTurnTable
    pl : SixDofTruth
        The plant's model (``kind``; the airframe's equations ``p``, ``dt``;
        the linear model ``A``, ``B``, ``Bw``, ``C``, ``Dw``, ``y0``, ``u0``), its trim
        ``x0`` and the monitor (``monitor.states``, ``monitor.u0``), for the
        rocking law and the guard.
    s : int
        Side: 0 left, 1 right.
    p : float
        Estimated absolute lock position [rad].
    mx : ndarray, shape (n_m, L)
        The side monitor's estimate.
    z, lat : ndarray, shapes (12, L), (>= 5, L)
        The measurements at this step, less the 6-DOF trim outputs: the 12
        longitudinal ones and the lateral loop's (the monitor's outputs, in order).
    l : int
        Lane.
    lo_dev, hi_dev : ndarray, shape (3,)
        Command limits less ``u0``.
    u : ndarray, shape (3, L)
        Commands less ``u0``; column ``l`` is written.
    """
    i, j1, w = bracket(tab, s, p)
    if tab.steady[s, i] == 0.0 and tab.steady[s, j1] == 0.0:  # no steady flight
        if tab.ro_on == 0 or not rocking_law(tab, pl, s, p, mx, z, lat, l, lo_dev, hi_dev,
                                             u):
            for c in range(2):  # hold the trim commands
                a = tab.cmd[s, c]
                u[a, l] = held(tab, a, lo_dev, hi_dev)
    elif tab.gd_on == 0 or not guarded_law(tab, pl, s, i, j1, w, p, mx, z, lat, l, lo_dev,
                                           hi_dev, u):
        turn_law(tab, s, i, j1, w, mx, z, lat, l, lo_dev, hi_dev, u)
    a = tab.locked[s]
    u[a, l] = held(tab, a, lo_dev, hi_dev)


@kernel(inline="always")
def bracket(tab, s, p):
    """``(i, j1, w)``: the designs of side ``s`` around the lock position ``p``
    [rad] (clamped to the grid's ends) and the weight on ``j1``."""
    n = tab.x.shape[1]
    f = (p - tab.lo[s]) / tab.step
    f = min(float(n - 1), max(0.0, f))
    i = min(int(f), max(n - 2, 0))
    w = f - i
    j1 = min(i + 1, n - 1)
    return i, j1, w


@kernel(inline="always")
def base_law(tab, pl, s, p, xs, lo_dev, hi_dev, u, l):
    """Column ``l`` of ``u`` (commands less ``u0``): the lock-turn law of side
    ``s`` at the lock position ``p`` on the flown absolute 6-DOF state ``xs``,
    without the rocking law and the guard (their own rollouts): the scheduled
    LQR (:func:`turn_deviation`) where a design bracketing ``p`` has a steady
    flight, else the trim commands held; the locked elevon at its trim
    command (:func:`lock_turn_law`)."""
    i, j1, w = bracket(tab, s, p)
    steady = tab.steady[s, i] != 0.0 or tab.steady[s, j1] != 0.0
    for c in range(2):
        a = tab.cmd[s, c]
        if steady:
            u[a, l] = turn_deviation(tab, pl, s, i, j1, w, xs, lo_dev, hi_dev, c)
        else:
            u[a, l] = held(tab, a, lo_dev, hi_dev)
    a = tab.locked[s]
    u[a, l] = held(tab, a, lo_dev, hi_dev)


@kernel(inline="always")
def held(tab, a, lo_dev, hi_dev):
    """Command ``a``'s 6-DOF trim command less ``u0`` (``tab.hold``), clipped
    to the limits: what the law holds where it holds the trim."""
    return min(hi_dev[a], max(lo_dev[a], tab.hold[a]))


@kernel(internal=True)
def rocking_law(tab, pl, s, p, mx, z, lat, l, lo_dev, hi_dev, u):
    """The throttle and healthy elevon commands of lane ``l`` under the rocking
    law (module docstring): the first pair of the candidate history that
    the plant's model (:func:`rollout_step`) keeps inside the envelope
    longest.  Arguments as
    :func:`lock_turn_law`'s.  Returns False, writing nothing, when every
    candidate leaves within the first period (or the state is not finite)."""
    x6, xs, cmd, wd, rk = rollout_start(tab, pl, s, mx, z, lat, l)
    best = 0
    best_k = -1
    best_e = np.inf
    for c in range(tab.ro_first.shape[0]):
        k_out, worst = fly_history(tab, pl, s, p, x6, c, tab.ro_first[c], tab.ro_steps, 0, 0,
                                   0.0, lo_dev, hi_dev, xs, cmd, wd, rk)
        if k_out > best_k or (k_out == best_k and worst < best_e):
            best = c
            best_k = k_out
            best_e = worst
    if best_k == 0:  # every history leaves within a period (or the state is not finite)
        return False
    send_pair(tab, s, best, l, lo_dev, hi_dev, u)
    return True


@kernel(inline="always")
def send_pair(tab, s, c, l, lo_dev, hi_dev, u):
    """Write the first pair (throttle, healthy elevon) of candidate ``c`` of
    side ``s`` (``tab.ro_u``, clipped to the limits) into lane ``l`` of ``u``."""
    for j in range(2):
        a = tab.cmd[s, j]
        u[a, l] = min(hi_dev[a], max(lo_dev[a], tab.ro_u[s, c, 0, j]))


@kernel(inline="always")
def rollout_start(tab, pl, s, mx, z, lat, l):
    """What the rocking law and the guard fly from: ``(x6, xs, cmd, wd, rk)``,
    lane ``l``'s 6-DOF state (absolute, 15): the monitor's estimate on its
    rows (:func:`~ftc_mc.core.sixdof.monitor.on_trim`), the fed-back states
    of side ``s`` from their sensors where ``tab.meas`` says so, the rest of
    the 6-DOF trim; then :func:`fly_history`'s work arrays (the flown state,
    the commands, still air, the RK4 stages)."""
    mon = pl.monitor
    x6 = np.empty(N_STATE)
    on_trim(mon, pl, mx[:, l], x6)
    nz = z.shape[0]
    for r in range(tab.meas.shape[1]):
        o = tab.meas[s, r]
        if o >= 0:
            j = mon.states[tab.rows[s, r]]
            x6[j] = pl.x0[j] + (z[o, l] if o < nz else lat[o - nz, l])
    return (x6, np.empty(N_STATE), np.empty(N_COMMAND), np.zeros(N_WIND),
            np.empty((N_WORK, N_STATE)))


@kernel(internal=True)
def guarded_law(tab, pl, s, i, j1, w, p, mx, z, lat, l, lo_dev, hi_dev, u):
    """The rollout guard on the lock-turn LQR (``monitor.turn_beyond:
    guarded``; module docstring).  From the lane's state (:func:`rollout_start`),
    the plant's model (:func:`rollout_step`) flies ``tab.ro_steps`` periods
    under the LQR of the designs ``i`` and ``j1`` (weight ``w`` on ``j1``;
    :func:`turn_command`).
    If that flight stays inside the envelope, returns False and writes
    nothing: :func:`turn_law` flies.  Else each of the guard's candidates
    holds one of the first ``tab.gd_pairs`` pairs of ``tab.ro_u`` (the held
    ones: the throttle's limits by the healthy elevon's positions) for
    ``tab.gd_holds`` periods, then flies the LQR for the rest of the horizon;
    the candidate that stays inside longest, then with the widest margin,
    wins (the LQR's own flight first, then the candidates pair-major, on a
    tie).  When the LQR's own flight wins, returns False; else writes the
    winning pair and returns True.  Arguments as :func:`lock_turn_law`'s and
    :func:`turn_law`'s."""
    x6, xs, cmd, wd, rk = rollout_start(tab, pl, s, mx, z, lat, l)
    best = -1
    best_h = 0
    best_k = -1
    best_e = np.inf
    nh = tab.gd_holds.shape[0]
    for c in range(-1, tab.gd_pairs):
        for hh in range(nh if c >= 0 else 1):
            h = tab.gd_holds[hh] if c >= 0 else 0
            k_out, worst = fly_history(tab, pl, s, p, x6, max(c, 0), h, h, i, j1, w, lo_dev,
                                       hi_dev, xs, cmd, wd, rk)
            if k_out > best_k or (k_out == best_k and worst < best_e):
                best = c
                best_h = h
                best_k = k_out
                best_e = worst
            if c < 0 and k_out == tab.ro_steps:  # the LQR stays in: no guard needed
                return False
    if best < 0 or best_h == 0:
        return False
    send_pair(tab, s, best, l, lo_dev, hi_dev, u)
    return True


@kernel(inline="always")
def fly_history(tab, pl, s, p, x6, c, first, lqr_from, i, j1, w, lo_dev, hi_dev, xs, cmd, wd,
                rk):
    """Fly one command history ``tab.ro_steps`` periods (:func:`rollout_step`:
    the airframe's equations, or the linear plant's own model) from the
    absolute 6-DOF state ``x6`` (into ``xs``; still air, the named elevon of
    side ``s`` at ``p``):
    the first pair of candidate ``c`` (``tab.ro_u``) for ``first`` periods,
    its second after, and from period ``lqr_from`` on the LQR of the designs
    ``i`` and ``j1`` (weight ``w`` on ``j1``; :func:`turn_command`).  Returns
    the period in which the flight leaves the envelope (``tab.ro_steps`` if it
    stays in) and its largest excess before (:func:`excess_of`;
    ``-inf`` if it leaves in the first).  ``cmd``, ``wd``, ``rk``: work
    arrays."""
    for q in range(N_STATE):
        xs[q] = x6[q]
    cmd[tab.locked[s]] = p
    a_thr = tab.cmd[s, 0]
    a_free = tab.cmd[s, 1]
    worst = -np.inf
    for k in range(tab.ro_steps):
        if k >= lqr_from:
            turn_command(tab, pl, s, i, j1, w, xs, lo_dev, hi_dev, cmd)
        else:
            ph = 0 if k < first else 1
            cmd[a_thr] = pl.monitor.u0[a_thr] + tab.ro_u[s, c, ph, 0]
            cmd[a_free] = pl.monitor.u0[a_free] + tab.ro_u[s, c, ph, 1]
        e = rollout_step(tab, pl, xs, cmd, wd, rk)
        if e > 0.0:
            return k, worst
        worst = max(worst, e)
    return tab.ro_steps, worst


@kernel(inline="always")
def turn_command(tab, pl, s, i, j1, w, xs, lo_dev, hi_dev, cmd):
    """The throttle and healthy elevon commands (absolute) of the lock-turn LQR
    of designs ``i`` and ``j1`` of side ``s`` (weight ``w`` on ``j1``) at the
    6-DOF state ``xs`` (absolute), each fed-back state read from ``xs``;
    written into ``cmd`` (:func:`turn_law`'s law on a flown state)."""
    for c in range(2):
        a = tab.cmd[s, c]
        cmd[a] = pl.monitor.u0[a] + turn_deviation(tab, pl, s, i, j1, w, xs, lo_dev, hi_dev, c)


@kernel(inline="always")
def turn_deviation(tab, pl, s, i, j1, w, xs, lo_dev, hi_dev, c):
    """Command ``c`` (0 throttle, 1 healthy elevon) of :func:`turn_command`,
    less ``u0`` and clipped to the limits."""
    mon = pl.monitor
    nf = tab.x.shape[2]
    a = tab.cmd[s, c]
    v = law_base(tab, s, i, j1, w, c)
    for r in range(nf):
        q = mon.states[tab.rows[s, r]]
        v -= law_term(tab, s, i, j1, w, c, r, xs[q] - pl.x0[q])
    return min(hi_dev[a], max(lo_dev[a], v))


@kernel(inline="always")
def rollout_step(tab, pl, xs, cmd, wd, rk):
    """One period of a rollout, in place on the absolute 6-DOF state ``xs``
    under the absolute commands ``cmd`` (still air), and the envelope's excess
    after it (:func:`excess_of`), both on the model of the plant flown: on the
    linear plant (``pl.kind``) its own ``x+ = A x + B u`` in deviations from
    the trim and the air data of its output map, as the truth steps and
    checks them; else the airframe's equations (``tab.ro_sub`` RK4 sub-steps)
    and the air data of ``u, v, w``.  ``wd``, ``rk``: work arrays."""
    if pl.kind == SIXDOF_LINEAR:
        dev = rk[0]
        for q in range(N_STATE):
            dev[q] = xs[q] - pl.x0[q]
        linear_step(pl, dev, cmd, wd, rk[1])
        for q in range(N_STATE):
            xs[q] = pl.x0[q] + rk[1, q]
        return excess_of(tab.ro_env, linear_output(pl, rk[1], wd, Y_VA),
                         math.degrees(linear_output(pl, rk[1], wd, Y_ALPHA)),
                         math.degrees(abs(xs[X_PHI])))
    propagate(xs, cmd, pl.p, wd, pl.dt, tab.ro_sub, rk)
    uu = xs[X_U]
    vv = xs[X_V]
    ww = xs[X_W]
    return excess_of(tab.ro_env, math.sqrt(uu * uu + vv * vv + ww * ww),
                     math.degrees(math.atan2(ww, uu)), math.degrees(abs(xs[X_PHI])))


@kernel(inline="always")
def excess_of(env, va, alpha, bank):
    """The envelope's excess at airspeed ``va`` [m/s], angle of attack
    ``alpha`` and bank ``bank`` [deg]: the largest of ``env[0] - Va``,
    ``Va - env[1]`` [m/s], ``env[2] - alpha``, ``alpha - env[3]``,
    ``|phi| - env[4]`` [deg]; ``inf`` where one is not finite."""
    if not (math.isfinite(va) and math.isfinite(alpha) and math.isfinite(bank)):
        return np.inf
    return max(env[0] - va, va - env[1], env[2] - alpha, alpha - env[3], bank - env[4])


@kernel(inline="always")
def turn_probe(tab, t):
    """The probe's addition to the named elevon's command ``t`` steps after
    the law took over [rad]: the 3211 of ``tab.probe`` (0 outside it, or when
    ``tab.probe`` is 0; module docstring)."""
    if tab.probe == 0.0 or t < 0 or t >= signal_3211_length(tab.probe_unit):
        return 0.0
    return signal_3211(t, tab.probe_unit, tab.probe)


@kernel(inline="always")
def hands_back(tab, t, b1, var):
    """Whether a lane whose law took over ``t`` steps ago, and whose monitor
    estimates the named elevon's ``b1`` [-] with variance ``var``, hands back
    to the paper's loop (module docstring)."""
    return (tab.probe != 0.0 and t == tab.check
            and b1 + tab.hand_back_sd * np.sqrt(max(var, 0.0)) < tab.hand_back)


@kernel(inline="always")
def turn_law(tab, s, i, j1, w, mx, z, lat, l, lo_dev, hi_dev, u):
    """The throttle and healthy elevon commands of lane ``l``: the designs ``i``
    and ``j1`` of side ``s`` interpolated with weight ``w`` on ``j1``
    (:func:`lock_turn_law`)."""
    nf = tab.x.shape[2]
    nz = z.shape[0]
    for c in range(2):
        a = tab.cmd[s, c]
        v = law_base(tab, s, i, j1, w, c)
        for r in range(nf):
            o = tab.meas[s, r]
            if o < 0:
                xr = mx[tab.rows[s, r], l]
            elif o < nz:
                xr = z[o, l]
            else:
                xr = lat[o - nz, l]
            v -= law_term(tab, s, i, j1, w, c, r, xr)
        u[a, l] = min(hi_dev[a], max(lo_dev[a], v))


@kernel(inline="always")
def law_base(tab, s, i, j1, w, c):
    """Command ``c`` (0 throttle, 1 healthy elevon) of side ``s``'s law at its
    interpolated design point, less the longitudinal trim: ``u* - k`` of the
    designs ``i`` and ``j1`` (weight ``w`` on ``j1``)."""
    a = tab.cmd[s, c]
    return (1.0 - w) * (tab.u[s, i, a] - tab.k[s, i, c]) + w * (tab.u[s, j1, a]
                                                                 - tab.k[s, j1, c])


@kernel(inline="always")
def law_term(tab, s, i, j1, w, c, r, xr):
    """The feedback of fed-back state ``r`` (its deviation from the 6-DOF trim
    ``xr``) on command ``c``: ``K (xr - x*)`` of the interpolated designs."""
    dev = xr - ((1.0 - w) * tab.x[s, i, r] + w * tab.x[s, j1, r])
    return ((1.0 - w) * tab.K[s, i, c, r] + w * tab.K[s, j1, c, r]) * dev


@kernel(internal=True)
def side_blocks(plant, scheme, st, block):
    """Table 1's decisions of a ``lock_turn`` or ``lock_turn_selected``
    design, each moved to the block of the actuator the design acts on
    (module docstring, "Which block the paper's filter resets"); other
    designs' are left alone.  A design whose resets come from the monitor
    (``scheme.detection.source``) resets the block of this step's decision
    instead, whatever its controller; with ``either``, Table 1's where the
    monitor decides nothing ("Resets from the monitor").

    Parameters
    ----------
    plant : SixdofPlant or SixdofExtendedPlant
        The path's plant marker (the dispatcher's calling convention).
    scheme : Scheme
        ``detection.source`` (``RESETS_SIDE_MONITOR``: the monitor decides
        when and which; ``RESETS_EITHER``: it does where it decides) and
        ``reconfig.kind`` (:data:`LOCK_TURN` or :data:`SELECTED_TURN`: the
        monitor decides the block).
    st : LaneState
        ``mside`` (the elevon the lane flies the law about, if > 0),
        ``mlast`` (the monitor's latest decision, 0 none) and ``mnow``
        (its decision at this step, 0 none).
    block : ndarray of int64, shape (L,)
        Table 1's block per lane (``NO_RESET``, ``RESET_THRUST`` or
        ``RESET_ELEVONS``), rewritten in place.
    """
    source = scheme.detection.source
    turn = scheme.reconfig.kind >= LOCK_TURN
    if source == RESETS_TABLE1 and not turn:
        return
    for l in range(block.shape[0]):
        now = st.mnow[l] if source != RESETS_TABLE1 else 0
        if now != 0:
            block[l] = DECISION_BLOCK[now]
        elif source == RESETS_SIDE_MONITOR:
            block[l] = NO_RESET
        elif turn and block[l] != NO_RESET:
            named = st.mside[l] if st.mside[l] > 0 else st.mlast[l]
            if named != 0:
                block[l] = DECISION_BLOCK[named]
