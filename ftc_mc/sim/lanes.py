"""Run lanes of trial inputs through the kernels: alone, or sharing their start.

:func:`simulate` runs the same inputs under several designs and Table 1
detections (the designs run, and in a sweep each at every threshold point).  Alone, each
detection runs every lane from the start (:func:`run_trials`).
Shared, the runs are grouped by design key (designs differing at most in Table
1's signature and thresholds: :class:`ftc_mc.sim.designs.Design`); per
group, the lanes are first advanced once to a step ``k_share`` with resets
disabled, recording the largest ``r_q`` and ``r_nx`` of each lane; then, for
each detection of the group:

* a lane whose residuals stayed below its thresholds until ``k_share`` had no
  reset there either, so it continues from that shared state;
* any other lane runs again from the start.

Until its first reset a lane does not depend on the thresholds (the residuals
are the same, and the initial covariance uses the paper's thresholds whatever
is run, see ``ftc_mc/sim/setup.py``), so both ways give bit-identical records
(``tests/test_sweep.py``).  A design whose resets come from the side monitor
(``resets: side_monitor`` or ``either``) runs alone at every point: a
monitor reset in the shared start would open its block with the reset
variances of the design's own thresholds, not the point's
(``tests/test_sixdof_signals.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ..conventions import LONGITUDINAL as LAY
from ..conventions import N_COST, N_MODES, RESETS_TABLE1
from ..core.longitudinal.gustfilter import N_WIND
from ..core.longitudinal.settings import TrialInputs, TrialRecord
from ..core.longitudinal.workspace import N_EXC
from ..core.longitudinal.trial import (N_DIRECTIONS, advance, init_jacobians, init_state,
                                        new_state)
from .inputs import design_inputs
from .paths import path_of

N_SQ_LAT = 2
"""``TrialRecord.sq_lat``: the squared bank and heading deviations' sums."""

HISTORY_RESETS = 100_000
"""Resets stored per lane when every step is kept (a scenario)."""


def start_lanes(scheme, flight, inp: TrialInputs, rec: TrialRecord):
    """The lane state of every trial of ``inp`` at step 0, and ``rec``'s per-lane
    fields initialised (:func:`ftc_mc.core.longitudinal.trial.init_state`; the extended
    filter's Jacobians at trim, :func:`~ftc_mc.core.longitudinal.trial.init_jacobians`).
    The truth's sizes are the flight's plant's (the 6-DOF one has 15 states, its
    lateral loop's and its side monitor's)."""
    pl = flight.plant
    n_lat = pl.K_lat.shape[0] if hasattr(pl, "K_lat") else 0
    mon = getattr(pl, "monitor", None)
    n_m, window_m = (mon.P0.shape[0], mon.window) if mon is not None else (0, 1)
    st = new_state(inp.w.shape[2], inp.xa0.shape[0], scheme.detection.window,
                   pl.x0.shape[0], n_lat, inp.g0_lat.shape[0], n_m, window_m)
    init_state(inp, st, rec)
    init_jacobians(scheme.filter, st)
    return st


def run_trials(scheme, flight, inp: TrialInputs, rec: TrialRecord) -> None:
    """Simulate the ``L`` trials of ``inp`` from the start to the end, writing
    ``rec`` (overwritten): :func:`start_lanes`, then
    :func:`ftc_mc.core.longitudinal.trial.advance` over every step.

    Parameters are those of :func:`~ftc_mc.core.longitudinal.trial.advance` without the
    state and step range.  The step kernel is called from Python, not from a
    compiled wrapper: Numba re-optimises and re-emits all the code a compiled
    caller links in, so a wrapper kernel cost the cold compile about 20 s
    (``docs/findings/performance.md``, lesson 6).
    """
    st = start_lanes(scheme, flight, inp, rec)
    advance(path_of(scheme, flight), scheme, flight, inp, rec, st, 0, flight.timing.n_steps)


def new_record(setup, L: int, max_resets: int, history: bool = False,
               n_est: int = LAY.n_aug) -> TrialRecord:
    """Preallocated outputs of :func:`run_trials`.

    ``history=True`` keeps every step's state, estimate, commands, residuals
    and excitation (for scenarios); campaigns keep only the per-period arrays.
    ``n_est``: states of the final estimate kept (the design's ``n_aug``: its
    extra states too; the history keeps the first 14).
    """
    n_per = setup.tim.n_steps // setup.tim.reconf_every
    n_hist = setup.tim.n_steps if history else 0
    n_res, n_par = len(LAY.residuals), len(LAY.params)
    mon = getattr(setup.truth, "monitor", None)
    n_mon = 3 * mon.u0.shape[0] if mon is not None and mon.on else 0
    return TrialRecord(
        reset_k=np.zeros((max_resets, L), dtype=np.int64),
        reset_block=np.zeros((max_resets, L), dtype=np.int64),
        reset_res=np.zeros((max_resets, n_res, L)),
        n_resets=np.zeros(L, dtype=np.int64),
        belief=np.zeros((n_per, N_MODES, L)), bhat=np.zeros((n_per, n_par, L)),
        detect_k=np.zeros(L, dtype=np.int64), status=np.zeros(L, dtype=np.int64),
        stop_k=np.zeros(L, dtype=np.int64),
        controller=np.zeros((n_per, L), dtype=np.int64),
        hist_x=np.zeros((n_hist, setup.truth.x0.shape[0], L)),
        hist_xa=np.zeros((n_hist, LAY.n_aug, L)),
        hist_pdiag=np.zeros((n_hist, n_par, L)), hist_u=np.zeros((n_hist, LAY.n_u, L)),
        hist_res=np.zeros((n_hist, n_res, L)), hist_exc=np.zeros((n_hist, N_EXC, L)),
        hist_block=np.zeros((n_hist, L), dtype=np.int64),
        hist_wind=np.zeros((n_hist, N_WIND, L)),
        hist_z=np.zeros((n_hist, LAY.n_z, L)), hist_innov=np.zeros((n_hist, n_res, L)),
        hist_lat=np.zeros((n_hist, 0 if setup.lat_std is None else len(setup.lat_std), L)),
        hist_mon=np.zeros((n_hist, N_DIRECTIONS if n_mon else 0, L)),
        xa_end=np.zeros((n_est, L)), sq_lat=np.zeros((N_SQ_LAT, L)),
        cost=np.zeros((N_COST, L)), z_switch_last=np.zeros((2, L)),
        side_k=np.zeros(L, dtype=np.int64), side_block=np.zeros(L, dtype=np.int64),
        side_pre=np.zeros(L, dtype=np.int64), side_n=np.zeros(L, dtype=np.int64),
        mon_b=np.zeros((n_mon, L)))


def run_alone(setup, name: str, det, inp: TrialInputs, max_resets: int,
              history: bool = False) -> TrialRecord:
    """Every lane of ``inp`` from the start to the end under the design ``name``
    with the detection ``det`` (``inp`` as :func:`~ftc_mc.sim.inputs.build_inputs`
    lays it out, for any design)."""
    rec = new_record(setup, inp.w.shape[2], max_resets, history, setup.designs[name].n_aug)
    run_trials(setup.scheme(name, det), setup.flight,
               design_inputs(inp, setup.designs[name]), rec)
    return rec


def take_lanes(nt, idx, shared=("k_switch", "P0")):
    """A namedtuple of lane-last arrays restricted to the lanes ``idx``."""
    return type(nt)(**{f: (v if f in shared else v[..., idx]) for f, v in nt._asdict().items()})


def _copy(nt):
    return type(nt)(**{f: v.copy() for f, v in nt._asdict().items()})


def simulate(setup, inp: TrialInputs, runs, max_resets: int, k_share: int | None = None,
             history: bool = False):
    """Records of the lanes of ``inp`` under each run of ``runs``.

    Parameters
    ----------
    setup : SimSetup
    inp : TrialInputs
        As :func:`~ftc_mc.sim.inputs.build_inputs` lays it out (any design).
    runs : list of (str, Detection)
        Design name and Table 1 settings of each run.
    max_resets : int
        Resets stored per lane.
    k_share : int, optional
        ``None``: every run from the start, alone.  Else the step up to which the
        runs of one design key share the lanes' start (module docstring),
        ``0 < k_share <= n_steps``.
    history : bool
        Keep every step (:func:`new_record`; recorded signals); only with
        ``k_share`` None.

    Returns
    -------
    recs : list of TrialRecord
        One per run, in order.
    simulated : int
        Lane steps simulated (``L n_steps len(runs)`` when alone).
    """
    L, n = inp.w.shape[2], setup.tim.n_steps
    if k_share is None:
        return ([run_alone(setup, v, det, inp, max_resets, history) for v, det in runs],
                L * n * len(runs))
    assert 0 < k_share <= n and not history
    groups = {}
    recs = [None] * len(runs)
    simulated = 0
    for i, (name, det) in enumerate(runs):
        if det.source == RESETS_TABLE1:
            groups.setdefault(setup.designs[name].key, []).append(i)
        else:  # the monitor resets before k_share too (lanes.py docstring)
            recs[i] = run_alone(setup, name, det, inp, max_resets)
            simulated += L * n
    for members in groups.values():
        lead = runs[members[0]][0]
        rec0, st0 = _shared_start(setup, lead, inp, max_resets, k_share)
        simulated += L * k_share
        for i in members:
            recs[i], sim = _continue(setup, runs[i], inp, rec0, st0, max_resets, k_share)
            simulated += sim
    return recs, simulated


def _shared_start(setup, name: str, inp: TrialInputs, max_resets: int, k_share: int):
    """Record and state of every lane after ``k_share`` steps of the design ``name``
    with resets disabled."""
    L = inp.w.shape[2]
    dinp = design_inputs(inp, setup.designs[name])
    rec0 = new_record(setup, L, max_resets, n_est=setup.designs[name].n_aug)
    scheme = setup.scheme(name, setup.detection(name, math.inf, math.inf))
    st0 = start_lanes(scheme, setup.flight, dinp, rec0)
    advance(path_of(scheme, setup.flight), scheme, setup.flight, dinp, rec0, st0, 0, k_share)
    return rec0, st0


def _continue(setup, run, inp: TrialInputs, rec0, st0, max_resets: int, k_share: int):
    """One run from the shared start: the record, and the lane steps simulated."""
    name, det = run
    L, n = inp.w.shape[2], setup.tim.n_steps
    rec, st = _copy(rec0), _copy(st0)
    simulated = 0
    if k_share < n:
        scheme = setup.scheme(name, det)
        advance(path_of(scheme, setup.flight), scheme, setup.flight,
                design_inputs(inp, setup.designs[name]), rec, st, k_share, n)
        simulated += L * (n - k_share)
    dirty = np.flatnonzero((st0.rmax[0] >= det.t_q) | (st0.rmax[1] >= det.t_nx))
    if len(dirty):
        sub = run_alone(setup, name, det, take_lanes(inp, dirty), max_resets)
        for f, v in sub._asdict().items():
            getattr(rec, f)[..., dirty] = v
        simulated += len(dirty) * n
    return rec, simulated
