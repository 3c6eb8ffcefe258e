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
from ..conventions import (C_NOMINAL, N_CMD_HIST, N_COST, N_MODES, N_U, N_X, N_Z,
                           RESETS_TABLE1, RESIDUAL_OUTPUTS, STATUS_OK)
from ..core.longitudinal.gustfilter import N_WIND
from ..core.longitudinal.settings import LaneState, TrialInputs, TrialRecord
from ..core.longitudinal.workspace import N_EXC
from ..core.longitudinal.trial import N_DIRECTIONS, N_RMAX, NO_SIGNAL, advance
from ..core.shared.dryden import N_GUST_STATE
from .inputs import design_inputs
from .paths import path_of

N_SQ_LAT = 2
"""``TrialRecord.sq_lat``: the squared bank and heading deviations' sums."""

HISTORY_RESETS = 100_000
"""Resets stored per lane when every step is kept (a scenario)."""


ALIGN = 64
"""Byte alignment of the lane state's arrays: one cache line, one AVX-512 vector.
The kernels load and store 64-byte vectors along the lane axis, and a lane row
that does not start on a 64-byte boundary splits every vector access over two
cache lines (``docs/findings/performance.md`` lesson 2)."""


def lane_zeros(shape, dtype=np.float64) -> np.ndarray:
    """A zeroed C-contiguous array whose data start on a 64-byte boundary
    (:data:`ALIGN`).

    Parameters
    ----------
    shape : int or tuple of int
        Array shape, lane axis last.
    dtype : data-type, optional
        Element type (default float64).

    Returns
    -------
    ndarray
        A view into a slightly larger buffer, writeable, C-contiguous.
    """
    dtype = np.dtype(dtype)
    n = int(np.prod(shape, dtype=np.int64))
    buf = np.zeros(n * dtype.itemsize + ALIGN, dtype=np.uint8)
    start = (-buf.ctypes.data) % ALIGN
    return buf[start:start + n * dtype.itemsize].view(dtype).reshape(shape)


def new_state(L: int, n: int, window: int, n_x: int, n_lat: int, n_glat: int, n_m: int,
              window_m: int) -> LaneState:
    """A :class:`~ftc_mc.core.longitudinal.settings.LaneState` of ``L`` lanes,
    every array zeroed and 64-byte aligned (:func:`lane_zeros`); contents set by
    :func:`init_state` (the side monitor's estimate by the monitor at step 0).

    Parameters
    ----------
    L : int
        Lanes (trials).
    n : int
        States of the estimate (14: the paper's filter; more with a design's
        extra states).
    window : int
        Steps of the GLR window (1 for the one-step test).
    n_x : int
        States of the truth (9 longitudinal, 15 on the 6-DOF plant).
    n_lat, n_glat : int
        The 6-DOF lateral loop's states and lateral gust states (0 otherwise).
    n_m, window_m : int
        The 6-DOF side monitor's states and window in steps (0 and 1 without it).

    Built in NumPy, not a kernel: a kernel called from Python compiles the
    unboxing of every field with it, and this runs once per chunk.
    """
    z, i8 = lane_zeros, np.int64
    st = LaneState(x=z((n_x, L)), xa=z((n, L)), P=z((n, n, L)),
                   d_start=z(L, i8), s_start=z(L, i8), d_amp=z(L), s_amp=z(L),
                   recheck=z(L, i8), belief=z((N_MODES, L)), alive=z(L, np.bool_),
                   cur=z(L, i8), rmax=z((N_RMAX, L)), gust=z((N_GUST_STATE, L)),
                   zhold=z(L), ebuf=z((window, len(RESIDUAL_OUTPUTS), L)),
                   ecount=z(L, i8), last_k=z(L, i8), last_block=z(L, i8),
                   lat=z((n_lat, L)), glat=z((n_glat, L)), mx=z((n_m, L)),
                   mP=z((n_m, n_m, L)), mbuf=z((window_m, N_DIRECTIONS, L)),
                   mcount=z(L, i8), mside=z(L, i8), mpos=z(L), mturn=z(L, i8),
                   mlast=z(L, i8), mnow=z(L, i8),
                   JA=z((N_X, N_X, L)), JB=z((N_X, N_U, L)), JW=z((N_X, N_WIND, L)),
                   JC=z((N_Z, N_X, L)), JHW=z((N_Z, N_WIND, L)),
                   uhist=z((N_CMD_HIST, N_U, L)), uprev=z((N_U, L)))
    st.mturn[:] = -1
    return st


def init_state(inp: TrialInputs, st: LaneState, rec: TrialRecord) -> None:
    """Initial state of every lane of ``st`` and the per-lane fields of ``rec``:
    the truth at trim, the initial estimate and covariance of ``inp``, the belief
    one-hot on the initial mode, no excitation, controller c0, the gust states
    of ``inp``, no reset, no side decision."""
    n = st.xa.shape[0]
    L = st.xa.shape[1]
    st.x[:] = 0.0
    st.xa[:] = inp.xa0[:n]
    st.P[:] = np.asarray(inp.P0)[:n, :n, None]
    st.d_start[:] = NO_SIGNAL
    st.s_start[:] = NO_SIGNAL
    st.d_amp[:] = 0.0
    st.s_amp[:] = 0.0
    st.recheck[:] = -1
    st.belief[:] = 0.0
    st.belief[np.asarray(inp.mode_pre), np.arange(L)] = 1.0
    st.alive[:] = True
    st.cur[:] = C_NOMINAL
    st.rmax[:] = 0.0
    st.gust[:] = inp.g0[:st.gust.shape[0]]
    st.zhold[:] = 0.0
    st.uprev[:] = 0.0
    st.uhist[:] = 0.0
    st.glat[:] = inp.g0_lat[:st.glat.shape[0]]
    st.lat[:] = 0.0
    for a in (st.ecount, st.last_block, st.mcount, st.mside, st.mlast, st.mnow):
        a[:] = 0
    st.last_k[:] = NO_SIGNAL
    st.mpos[:] = 0.0
    st.mturn[:] = -1
    rec.stop_k[:] = -1
    rec.n_resets[:] = 0
    rec.detect_k[:] = -1
    rec.status[:] = STATUS_OK
    rec.sq_lat[:] = 0.0
    rec.cost[:] = 0.0
    rec.z_switch_last[0] = np.nan
    rec.z_switch_last[1] = 0.0
    rec.side_k[:] = -1
    for a in (rec.side_block, rec.side_pre, rec.side_n):
        a[:] = 0
    rec.mon_b[:] = 0.0


def init_jacobians(fm, st: LaneState) -> None:
    """Every lane's Jacobians (``st.JA``, ``JB``, ``JW``, ``JC``, ``JHW``) at
    trim: ``fm.A``, ``fm.B``, ``fm.Bw``, ``fm.C``, ``fm.Dw``.  The extended
    filter with ``fm.relin > 0`` replaces them at its first step (``k = 0``);
    otherwise they are never read."""
    st.JA[:] = np.asarray(fm.A)[:N_X, :N_X, None]
    st.JB[:] = np.asarray(fm.B)[:N_X, :N_U, None]
    st.JW[:] = np.asarray(fm.Bw)[:N_X, :N_WIND, None]
    st.JC[:] = np.asarray(fm.C)[:N_Z, :N_X, None]
    st.JHW[:] = np.asarray(fm.Dw)[:N_Z, :N_WIND, None]


def start_lanes(scheme, flight, inp: TrialInputs, rec: TrialRecord):
    """The lane state of every trial of ``inp`` at step 0, and ``rec``'s per-lane
    fields initialised (:func:`init_state`; the extended filter's Jacobians at
    trim, :func:`init_jacobians`).
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
