"""Monte Carlo trials of the semi-closed estimation loop, many at once (lanes).

One lane is one trial: the truth plant (the linear model of eq. 4, or the
nonlinear X8, each with or without Dryden gusts) with the injected fault and
process/measurement noise, the controllers with the saturation of eqs. (15-16),
the doublet / 3211 excitation on reset requests and the re-sent doublet
(section 4.1.1), the estimator (eqs. 5-11, Table 1), the belief (eqs. 12-14)
and the controller selection (eqs. 45-47) every reconfiguration period.

Lane-last storage (``a[..., L]``) lets the inner loops vectorise across trials
(see :mod:`ftc_mc.core.longitudinal.batch`).  Random numbers come in from outside
(:class:`~ftc_mc.core.longitudinal.settings.TrialInputs`) so each trial's stream depends only
on its own seed.

A step ``k -> k+1`` (time ``t = k dt``) is a sequence of stage kernels, each
described where it is defined; stages 1-6 of the steps between two
reconfigurations make one kernel, :func:`trial_steps`, and :func:`advance`
calls it and stage 7 by address (``core/linking.py``):

1. :func:`ftc_mc.core.longitudinal.stages.commands` -- ``u_k = f(U(x_hat_k), s_k, A_k)``;
2. :func:`ftc_mc.core.longitudinal.plant.truth` -- effect, gusts, plant, ``z_{k+1}``
   (the longitudinal :func:`~ftc_mc.core.longitudinal.plant.truth_step`, or the
   6-DOF family's :func:`ftc_mc.core.sixdof.truth.sixdof_truth`), then
   :func:`ftc_mc.core.longitudinal.stages.record_cost` -- tracking and command costs,
   then :func:`side_monitor` -- on the 6-DOF plant its side monitor
   (:func:`ftc_mc.core.sixdof.monitor.sixdof_monitor`), which records, and which a
   ``lock_turn`` design's truth stage and its choice of the block to reset
   read (``core/sixdof/lockturn.py``);
3. :func:`ftc_mc.core.longitudinal.stages.filter_update` -- the filter with ``u_k``, ``z_{k+1}``;
4. :func:`ftc_mc.core.longitudinal.stages.check_validity`;
5. :func:`ftc_mc.core.longitudinal.stages.handle_resets` -- resets, excitation requests
   and the design's excitation policy;
6. :func:`ftc_mc.core.longitudinal.stages.record_step` -- history;
7. :func:`ftc_mc.core.longitudinal.stages.reconfigure` -- belief and controller, every
   ``reconf_every`` steps (on the path of a ``lock_turn_selected`` design,
   after :func:`six_dof_selection`: its belief and its choice among the
   four 6-DOF controllers).
"""

from __future__ import annotations

from ...conventions import N_U
from ..jit import kernel
from .plant import truth
from ..shared.paths import SELECT_FOUR, SIXDOF_EXTENDED_PLANT, SIXDOF_PLANT, on_path
from .stages import (check_validity, commands, filter_update, handle_resets,  # noqa: F401
                     is_psd, reconfigure, record_cost, record_end, record_step)
from .workspace import new_trial_work

NO_SIGNAL = -(1 << 40)
"""Start step of a signal that is not running (far in the past)."""

N_RMAX = 2
"""Residuals whose running maximum a lane keeps (``r_q``, ``r_nx``;
``LaneState.rmax``)."""

N_DIRECTIONS = N_U
"""Fault directions of the 6-DOF side monitor: one per actuator
(``core/sixdof/layout.MONITOR_DIRECTIONS``)."""


@on_path("plant", {SIXDOF_PLANT: "ftc_mc.core.sixdof.monitor:sixdof_monitor",
                   SIXDOF_EXTENDED_PLANT: "ftc_mc.core.sixdof.monitor:sixdof_monitor_extended"},
         passes="marker")
def side_monitor(path, scheme, flight, k, st, work, rec):
    """Stage 2b: the 6-DOF side monitor over step ``k -> k+1``
    (:func:`ftc_mc.core.sixdof.monitor.sixdof_monitor`, imported only by a
    path that flies the 6-DOF plant); nothing on the longitudinal plants."""


@on_path("control", {SELECT_FOUR: "ftc_mc.core.sixdof.selection:sixdof_select"})
def six_dof_selection(path, plant, scheme, kn, st, work):
    """At a reconfiguration period's end, before :func:`reconfigure`: on the
    path of a ``lock_turn_selected`` design (6-DOF plant), its belief and its
    selection among the four 6-DOF controllers
    (:func:`ftc_mc.core.sixdof.selection.sixdof_select`, imported only by
    that path); nothing on the others."""


@kernel
def advance(path, scheme, flight, inp, rec, st, k0, k1):
    """Advance ``L`` trials from step ``k0`` to ``k1``, writing their records.

    Each compile path is its own signature, compiled on its first call
    (``core/shared/paths.py``).

    Parameters
    ----------
    path : Path
        The compile path: the truth plant, filter, residual test and
        controller kinds of ``scheme`` and ``flight``
        (:func:`ftc_mc.sim.paths.path_of`).
    scheme : Scheme
        The FTC scheme: ``filter`` (FilterModel), ``detection`` (Detection),
        ``belief`` (Belief), ``controller`` (Controller), ``excitation``
        (Excitation), ``reconfig`` (Reconfig: ``kind == 0`` the nominal
        controller c0 throughout, ``1`` re-selected every period among c0, c1,
        c2) and ``engine`` (EngineTables of c1).
    flight : Flight
        ``timing`` (Timing), ``validity`` (Validity: where a lane stops being
        recorded, :func:`ftc_mc.core.longitudinal.stages.check_validity`), ``plant``
        (TruthPlant: linear or nonlinear, still air or Dryden gusts) and
        ``track`` (Track: the glide path's cross-track error).
    inp : TrialInputs
        Per-lane fault schedule, initial estimates and noise.
    rec : TrialRecord
        Outputs, continued from step ``k0`` (initialised by
        :func:`ftc_mc.sim.lanes.init_state`).
    st : LaneState
        The trials' state at step ``k0``, advanced in place to ``k1``.  It holds
        everything a trial carries from one step to the next, so a state saved
        at some step and advanced later gives bit-identical results.
    k0, k1 : int
        First step and end step (``0 <= k0 <= k1 <= timing.n_steps``).
    """
    work = new_trial_work(st.xa.shape[1], st.xa.shape[0])
    every = flight.timing.reconf_every
    if every <= 0:
        raise ValueError("timing.reconf_every must be at least one step")
    period = k0 // every
    k = k0
    while k < k1:
        k_end = min(k1, (k // every + 1) * every)  # the next reconfiguration
        trial_steps(path, scheme, flight, inp, k, k_end, st, work, rec)
        k = k_end
        if k % every == 0:
            six_dof_selection(path, flight.plant, scheme, k, st, work)
            reconfigure(path, scheme, flight.timing, inp, st, k, period, work, rec)
            period += 1
    record_end(st, rec)


@kernel(by_address=True)
def trial_steps(path, scheme, flight, inp, k0, k1, st, work, rec):
    """Stages 1-6 of the steps ``k0 -> k0+1`` to ``k1-1 -> k1`` (module
    docstring), every lane; no reconfiguration falls inside them.

    One kernel that ``advance`` calls by address once per reconfiguration
    period: the stages are IR-inlined into its loop, and the large kernels
    they reach (the truth plant, the filter's prediction and correction, the
    side monitor) are called by address (``core/linking.py``), so each is
    compiled once, and a period costs one call of ``advance``'s, not one per
    stage or per step (``docs/findings/performance.md`` lesson 17).  Parameters as
    :func:`advance`'s.
    """
    for k in range(k0, k1):
        kn = k + 1
        commands(path, scheme, st, k, work)
        truth(path, scheme, flight, inp, k, st, work, rec)
        record_cost(flight.track, flight.timing.k_fault, st, kn, work, rec)
        side_monitor(path, scheme, flight, k, st, work, rec)
        filter_update(path, scheme, st, k, work, rec.hist_innov.shape[0] > 0)
        check_validity(flight.validity, st, kn, work, rec)
        handle_resets(scheme.excitation, st, kn, work, rec)
        record_step(k, st, work, rec)
