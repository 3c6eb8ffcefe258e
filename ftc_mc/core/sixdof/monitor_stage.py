"""Stage 2b on the 6-DOF plant: the side monitor, and the 6-DOF selection.

Each step the side monitor (:mod:`ftc_mc.core.sixdof.monitor`) advances every
lane and keeps the first elevon it names (``LaneState.mside``), which in a
``controller: lock_turn`` design switches the lock-turn law in
(:mod:`ftc_mc.core.sixdof.lockturn`).  In a ``controller:
lock_turn_selected`` design it does not: at the end of each reconfiguration
period the belief is updated from the monitor's estimate and the selection
among the four controllers runs instead (:mod:`ftc_mc.core.sixdof.selection`),
so that the commands of the next step already come from the controller chosen.
"""

from __future__ import annotations

from ..jit import kernel
from .lockturn import SELECTED_TURN
from .monitor import EXTENDED, extended_filter, monitor_decide, monitor_start, trim_filter
from .selection import sixdof_select


@kernel(inline="always")
def after_update(scheme, flight, k, st, work, rec, num, den):
    """The monitor's decisions (:func:`~ftc_mc.core.sixdof.monitor.monitor_decide`),
    then, in a ``lock_turn_selected`` design at a period's end, the belief and
    the selection (:func:`~ftc_mc.core.sixdof.selection.sixdof_select`)."""
    mon = flight.plant.monitor
    kind = scheme.reconfig.kind
    monitor_decide(mon, flight, k, st, work, rec, num, den, kind != SELECTED_TURN)
    if kind == SELECTED_TURN and (k + 1) % flight.timing.reconf_every == 0:
        sixdof_select(flight.plant, scheme, k + 1, st, work)


@kernel(internal=True)
def sixdof_monitor(plant, scheme, flight, k, st, work, rec):
    """Advance the side monitor of every lane over step ``k -> k+1``.

    Parameters
    ----------
    plant : SixdofPlant
        The path's plant marker (the dispatcher's calling convention).
    scheme : Scheme
        ``reconfig.kind`` (a ``lock_turn`` or ``lock_turn_selected`` design);
        for the selection, ``belief``, ``reconfig``, ``controller``, ``engine``.
    flight : Flight
        ``plant.monitor`` (:class:`SideMonitor`), ``timing.k_fault``.
    k : int
        Step.
    st : LaneState
        ``mx`` (n, L), ``mP`` (n, n, L) (set at step 0: zero and ``P0``),
        the GLR window ``mbuf`` and ``mcount``, the first elevon named
        ``mside`` and its position estimate ``mpos``, the latest decision
        ``mlast``, updated in place; ``lat``
        the lateral loop's measurements of ``k + 1``.
    work : TrialWork
        ``u`` the commands sent over the step, ``z`` the 12 longitudinal
        measurements of ``k + 1``.
    rec : TrialRecord
        ``side_k``, ``side_block``, ``side_pre``, ``side_n`` (on live lanes), ``mon_b``
        (module docstring).
    """
    mon = flight.plant.monitor
    if mon.on == 0:
        return
    if mon.nonlinear == EXTENDED:
        raise ValueError("an extended side monitor flies sixdof_monitor_extended")
    num, den = monitor_start(mon, k, st)
    trim_filter(mon, flight.plant, st.mx, st.mP, work.u, work.z, st.lat, num, den)
    after_update(scheme, flight, k, st, work, rec, num, den)


@kernel(internal=True)
def sixdof_monitor_extended(plant, scheme, flight, k, st, work, rec):
    """:func:`sixdof_monitor` with the extended filter (:func:`extended_filter`),
    on the ``SIXDOF_EXTENDED_PLANT`` path (``core/shared/paths.py``): the
    other 6-DOF path never compiles it."""
    mon = flight.plant.monitor
    if mon.on == 0:
        return
    num, den = monitor_start(mon, k, st)
    extended_filter(mon, flight.plant, st.mx, st.mP, work.u, work.z, st.lat, num, den)
    after_update(scheme, flight, k, st, work, rec, num, den)
