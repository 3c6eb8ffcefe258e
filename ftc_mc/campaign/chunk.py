"""One chunk of trials or fault-free flights: inputs -> kernels -> classified rows.

The one chunk executor of ``ftc-mc run`` and ``ftc-mc sweep`` (worker side).  A
chunk is a fixed range of trial ids of one transition, or of fault-free flights
(:data:`FLIGHT`); its results depend only on those ids and the root seed, never
on which worker runs it or how many chunks there are.  :func:`run_chunk` lays
out the inputs (``ftc_mc/sim/inputs.py``), runs them under every design (the
signature variants and ``campaign.designs``; in a sweep, each at every
threshold point) with
:func:`ftc_mc.sim.lanes.simulate`, and classifies the records.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ..config.schema import Config
from ..conventions import (BLOCK_NAMES, C_NOMINAL, COST_TRACK_MAX, COST_TRACK_SQ, COST_U2,
                           KIND_NONE, LONGITUDINAL, MODE_NAMES, MODE_NOMINAL, STATUS_AIRSPEED,
                           STATUS_ALPHA, STATUS_NAMES, STATUS_NONFINITE, STATUS_NOT_PSD)
from ..core.longitudinal.settings import TrialInputs, TrialRecord
from ..core.longitudinal.trial import advance
from ..sim.compiling import compiled_once
from ..sim.paths import path_of
from ..sim.inputs import (FLIGHT_FAULT_RANGE, build_inputs, draw_lanes, flight_inputs,
                          neutral_params, sensor_faults)
from ..sim.lanes import simulate
from ..sim.setup import SimSetup, build_setup, runs_of
from .kinds import KindRanges, KindTransition, kind_draws, kind_ranges, kind_schedule
from .side import side_columns
from .transitions import (ELEVON_MODES, ENGINE, TRANSITION_TABLE, FaultRanges,
                          SensorTransition, fault_ranges, is_sensor, transition_of)

FLIGHT = "fault_free"
"""Chunk name of the fault-free flights of a sweep (false resets per flight hour)."""
ENDURANCE = "endurance"
"""Chunk name of the fault-free flights of ``ftc-mc endurance``: the same flights
as :data:`FLIGHT`, every reset kept with its time (``ftc_mc/campaign/endurance.py``)."""


@dataclasses.dataclass(frozen=True)
class ChunkSpec:
    """What every chunk of one run or sweep shares (built once, sent to workers).

    Attributes
    ----------
    setup : SimSetup
    seed : int
        Root seed of the trial streams.
    variants : tuple of str
        Names of the designs run on the same inputs (the signature variants,
        then ``campaign.designs``): the ``variant`` column of the results.
    ranges : FaultRanges
        Ranges of the trials' fault values.
    near_trim : tuple
        ``(engine, elevon)`` half-widths of a lock 'near trim' (``explain``).
    window : int
        Judging window after the switch [steps].
    max_resets : int
        Resets stored per trial.
    points : tuple of (float, float) or None
        A sweep's ``(t_q, t_nx)`` threshold points, run sharing each trial's
        start (``ftc_mc/sim/lanes.py``); ``None``: the config's thresholds.
    sensor_ranges : dict of str to (float, float)
        Size magnitude range of each sensor transition of the config
        (``sensor_draws``).
    resets_kept : int or None
        Resets of each trial and design kept in the ``resets`` table
        (``campaign.reset_log``; the first ones in time); None: all.  Only the
        table is cut: the trials' columns are classified from every stored reset.
    record : bool
        Keep every step and return the ``signals`` table too
        (``campaign.record``, :mod:`ftc_mc.campaign.signals`).
    kind_ranges : KindRanges or None
        Ranges of the fault kinds' draws (``kind_draws``, :mod:`ftc_mc.campaign.kinds`).
    """

    setup: SimSetup
    seed: int
    variants: tuple
    ranges: FaultRanges
    near_trim: tuple
    window: int
    max_resets: int
    points: tuple | None = None
    sensor_ranges: dict = dataclasses.field(default_factory=dict)
    resets_kept: int | None = None
    record: bool = False
    kind_ranges: KindRanges | None = None

    @property
    def tables(self) -> tuple:
        """Names of the tables :func:`run_chunk` returns (``trials`` first)."""
        if self.points is not None:
            return ("trials", "steps")
        return ("trials", "resets", "signals") if self.record else ("trials", "resets")


def chunk_spec(cfg: Config, setup: SimSetup | None = None, points=None) -> ChunkSpec:
    """The :class:`ChunkSpec` of a validated campaign config.

    Parameters
    ----------
    cfg : Config
    setup : SimSetup, optional
        Built from ``cfg`` when omitted.
    points : list of (float, float), optional
        Threshold points of a sweep.
    """
    setup = build_setup(cfg) if setup is None else setup
    plant = setup.plant
    return ChunkSpec(setup=setup, seed=cfg.campaign.seed,
                     variants=runs_of(cfg),
                     ranges=fault_ranges(cfg.draws, plant.u_lower, plant.u_upper),
                     near_trim=(cfg.explain.engine_lock_near_trim,
                                cfg.explain.elevon_lock_near_trim_rad),
                     window=cfg.steps(cfg.timing.window_s), max_resets=cfg.resets_stored(),
                     points=None if points is None else tuple(map(tuple, points)),
                     sensor_ranges={name: cfg.sensor_draws.size_range(tr.kind, tr.output)
                                    for name in cfg.campaign.transitions if is_sensor(name)
                                    for tr in [transition_of(name)]},
                     resets_kept=cfg.campaign.resets_kept(),
                     kind_ranges=kind_ranges(cfg, setup, fault_ranges(
                         cfg.draws, plant.u_lower, plant.u_upper).lock),
                     record=cfg.campaign.record == "signals" and points is None)


def trial_inputs(spec: ChunkSpec, tr_name: str, trial_ids):
    """Draw every trial of a chunk of transition ``tr_name`` and lay out its inputs.

    Returns
    -------
    inp : TrialInputs
    values : ndarray, shape (L,) or (L, 2)
        The fault value of each trial (lock position or b1; for a sensor
        transition the sensor fault's size, NaN when stuck; for a fault kind
        its two parameters, ``ftc_mc/campaign/kinds.py``).
    """
    tr = transition_of(tr_name)
    setup = spec.setup
    if isinstance(tr, SensorTransition):
        draws = draw_lanes(setup, trial_ids, spec.seed, tr.DRAW_RANGE)
        sizes = tr.sizes(draws.fault, spec.sensor_ranges[tr_name])
        sensor = sensor_faults(tr.out_index, tr.kind_index, np.nan_to_num(sizes),
                               setup.tim.k_fault)
        return (build_inputs(setup, tr.schedule(draws.fault, setup.tim.k_fault), draws,
                             sensor), sizes)
    if isinstance(tr, KindTransition):
        # the main stream's first draw as a flight's (ignored): the same noise
        # and gusts as every other row; the kind's parameters from its own stream
        draws = draw_lanes(setup, trial_ids, spec.seed, FLIGHT_FAULT_RANGE)
        lanes = kind_draws(tr, trial_ids, spec.seed, spec.kind_ranges, setup.tim.k_fault,
                           setup.tim.n_steps)
        values = np.array([lane[3] for lane in lanes], dtype=float).reshape(-1, 2)
        return (build_inputs(setup, kind_schedule(tr, lanes, setup.tim.k_fault,
                                                  setup.plant.dt), draws), values)
    draws = draw_lanes(setup, trial_ids, spec.seed, spec.ranges.of(tr))
    return build_inputs(setup, tr.schedule(draws.fault, setup.tim.k_fault), draws), draws.fault


def classify(spec: ChunkSpec, tr_name: str, variant: str, trial_ids, values,
             inp: TrialInputs, rec: TrialRecord):
    """Per-trial and per-reset columns of one kernel call.

    Definitions (docs/reference/paper-map.md), with ``k_f`` the switch step and the
    window the steps ``k_f < k <= k_f + spec.window``:

    * ``correct``: the transition's block was reset in the window;
    * ``inappropriate``: the other block was reset in the window (whether or
      not the correct one was too);
    * ``no_reset``: nothing was reset in the window;
    * ``false_resets``: resets at or before ``k_f`` while the truth is nominal,
      i.e. in rows that start nominal (``mode_pre``); an unlock or recover row
      starts faulted, so its resets before the switch are no false alarms and
      count 0;
    * ``first_reset_s``: delay from the switch to the first reset in the window;
    * ``correct_reset_s``: delay from the switch to the first reset of the
      correct block in the window (NaN when it had none), whatever was reset
      before it; the detection delay of the operating characteristic;
    * ``detection_s``: delay from the switch to the first belief update where
      the final mode is the most probable with at least ``detect_prob``; NaN when
      the final mode equals the initial one (nothing to detect);
    * ``status``/``stop_s``: why and when a trial stopped (``ok`` if it ran to
      the end); ``judged``: the trial counts in the rates, i.e. it never failed
      numerically, left the validity envelope (if at all) only after the window,
      and stored all its resets;
    * ``correct_side``: for a judged trial of an elevon row (left or right)
      whose final mode is an elevon mode, 1.0 when the belief's more probable
      elevon mode at the end of the window is the faulty side, else 0.0; NaN
      for every other trial (:func:`correct_side`).

    Parameters
    ----------
    spec : ChunkSpec
    tr_name : str
    variant : str
    trial_ids : ndarray, shape (L,)
    values : ndarray, shape (L,) or (L, 2)
        The trials' fault values (lock position or ``b1``; a fault kind's two
        parameters, ``ftc_mc/campaign/kinds.py``'s ``PARAM_COLUMNS``).
    inp : TrialInputs
    rec : TrialRecord

    Returns
    -------
    trials : dict of str to ndarray
    resets : dict of str to ndarray
    """
    if is_sensor(tr_name):
        return classify_sensor(spec, tr_name, variant, trial_ids, values, inp, rec)
    setup = spec.setup
    window_steps = spec.window
    tr = TRANSITION_TABLE[tr_name]
    dt = setup.plant.dt
    kf = setup.tim.k_fault
    L = len(trial_ids)
    R = rec.reset_k.shape[0]
    k = rec.reset_k
    blk = rec.reset_block
    resets, valid, in_win, before = _reset_columns(tr_name, variant, trial_ids, rec, kf,
                                                   window_steps, dt)
    correct = np.any(in_win & (blk == tr.correct_block), axis=0)
    inappropriate = np.any(in_win & (blk == tr.other_block), axis=0)
    n_win = in_win.sum(axis=0)
    first = np.where(n_win > 0, np.argmax(in_win, axis=0), 0)
    first_k = k[first, np.arange(L)]
    first_block = blk[first, np.arange(L)]
    _, correct_reset_s = _first_after(in_win & (blk == tr.correct_block), k, kf, dt)
    changed = inp.mode_pre != inp.mode_post
    detected = changed & (rec.detect_k >= 0)
    a = tr.actuator
    u0 = setup.plant.u0[a]
    beta = setup.beta[0 if a == ENGINE else 1]  # (engine, elevon)
    near = spec.near_trim[0 if a == ENGINE else 1]
    is_lock = tr.kind == "lock"
    is_loss = tr.kind == "loss"
    kind_values = values if values.ndim == 2 else None  # a fault kind's two parameters
    values = values[:, 0] if kind_values is not None else values
    small_b1 = values < beta if is_loss else np.zeros(L, dtype=bool)
    near_trim = np.abs(values - u0) < near if is_lock else np.zeros(L, dtype=bool)
    truncated = rec.n_resets > R
    # A trial is judged when it stayed valid through the whole window: numerical
    # failures never count; an envelope exit after the window does not matter.
    numeric_fail = (rec.status == STATUS_NONFINITE) | (rec.status == STATUS_NOT_PSD)
    judged = (rec.status == 0) | (~numeric_fail & (rec.stop_k > kf + window_steps))
    xa = rec.xa_end
    b1_idx = LONGITUDINAL.b1_index[a]
    b0_idx = LONGITUDINAL.b0_index[a]
    trials = {
        "transition": np.full(L, tr_name, dtype=object),
        "variant": np.full(L, variant, dtype=object),
        "trial_id": np.asarray(trial_ids, dtype=np.int64),
        "lock_position": values if is_lock else np.full(L, np.nan),
        "lock_offset": values - u0 if is_lock else np.full(L, np.nan),
        "loss_b1": values if is_loss else np.full(L, np.nan),
        "mode_pre": np.array([MODE_NAMES[m] for m in inp.mode_pre], dtype=object),
        "mode_post": np.array([MODE_NAMES[m] for m in inp.mode_post], dtype=object),
        "correct": correct,
        "inappropriate": inappropriate,
        "no_reset": n_win == 0,
        "first_reset_s": np.where(n_win > 0, (first_k - kf) * dt, np.nan),
        "first_reset_block": np.array([BLOCK_NAMES[b] if n else "none"
                                       for b, n in zip(first_block, n_win)], dtype=object),
        "correct_reset_s": correct_reset_s,
        "resets_in_window": n_win.astype(np.int64),
        "false_resets": np.where(inp.mode_pre == MODE_NOMINAL, before.sum(axis=0),
                                 0).astype(np.int64),
        "resets_total": rec.n_resets.copy(),
        "detection_s": np.where(detected, (rec.detect_k - kf) * dt, np.nan),
        "mode_changed": changed,
        "detected": detected,
        "small_b1": small_b1,
        "lock_near_trim": near_trim,
        "b0_hat_end": xa[b0_idx].copy(),
        "b1_hat_end": xa[b1_idx].copy(),
        "resets_truncated": truncated,
        "judged": judged & ~truncated,
        "status": np.array([STATUS_NAMES[s] for s in rec.status], dtype=object),
        "stop_s": np.where(rec.stop_k >= 0, rec.stop_k * dt, np.nan),
        "correct_side": correct_side(tr, inp.mode_post, rec.belief, judged & ~truncated,
                                     kf + window_steps, setup.tim.reconf_every),
    }
    if kind_values is not None:  # a fault kind: its name and parameters (kinds.PARAM_COLUMNS)
        trials["fault_kind"] = np.full(L, tr.kind, dtype=object)
        trials["fault_param"] = kind_values[:, 0].copy()
        trials["fault_param2"] = kind_values[:, 1].copy()
    if rec.mon_b.shape[0]:  # the 6-DOF side monitor flew beside the design
        trials.update(side_columns(rec, a, tr.onset, kf, window_steps, dt))
    return trials, resets


def correct_side(tr, mode_post, belief, judged, k_end: int, every: int) -> np.ndarray:
    """Per lane: whether the belief names the faulty elevon at the window's end.

    The belief at the end of the judging window is the one of the last update
    at or before step ``k_end`` (period ``k_end // every - 1``; period ``p``
    ends at step ``(p + 1) every``).  The *most probable elevon mode* is the
    larger of its left- and right-elevon probabilities; a tie names neither
    side and counts as wrong.

    Parameters
    ----------
    tr : Transition
    mode_post : ndarray of int, shape (L,)
        Each lane's final mode.
    belief : ndarray, shape (n_periods, 4, L)
        The belief after each reconfiguration period (``TrialRecord.belief``).
    judged : ndarray of bool, shape (L,)
    k_end : int
        Last step of the judging window.
    every : int
        Steps per reconfiguration period.

    Returns
    -------
    ndarray of float, shape (L,)
        1.0 (the faulty side is the more probable) or 0.0 for the judged lanes
        of an elevon transition whose final mode is an elevon mode; NaN for the
        others (engine rows, recoveries, losses inside the nominal box,
        unjudged trials, and a window ending before the first update).
    """
    mode_post = np.asarray(mode_post)
    L = len(mode_post)
    out = np.full(L, np.nan)
    p = k_end // every - 1
    if not tr.is_elevon or not 0 <= p < belief.shape[0]:
        return out
    applies = np.isin(mode_post, ELEVON_MODES) & np.asarray(judged, dtype=bool)
    lanes = np.nonzero(applies)[0]
    faulty = mode_post[lanes]
    other = np.where(faulty == ELEVON_MODES[0], ELEVON_MODES[1], ELEVON_MODES[0])
    out[lanes] = belief[p, faulty, lanes] > belief[p, other, lanes]
    return out


def _reset_columns(tr_name, variant, trial_ids, rec, kf, window_steps, dt):
    """Resets of a chunk: the ``resets`` table, and the masks of stored resets in
    the window and before the switch."""
    R = rec.reset_k.shape[0]
    stored = np.minimum(rec.n_resets, R)
    valid = np.arange(R)[:, None] < stored[None, :]
    k, blk = rec.reset_k, rec.reset_block
    in_win = valid & (k > kf) & (k <= kf + window_steps)
    before = valid & (k <= kf)
    lane, slot = np.nonzero(valid.T)
    kk = k[slot, lane]
    resets = {
        "transition": np.full(len(lane), tr_name, dtype=object),
        "variant": np.full(len(lane), variant, dtype=object),
        "trial_id": np.asarray(trial_ids, dtype=np.int64)[lane],
        "time_s": kk * dt,
        "time_from_fault_s": (kk - kf) * dt,
        "block": np.array([BLOCK_NAMES[b] for b in blk[slot, lane]], dtype=object),
        "r_q": rec.reset_res[slot, 0, lane],
        "r_nx": rec.reset_res[slot, 1, lane],
        "r_nz": rec.reset_res[slot, 2, lane],
        "in_window": in_win[slot, lane],
        "before_fault": before[slot, lane],
    }
    return resets, valid, in_win, before


def _first_after(mask, steps, kf, dt):
    """Per lane: whether ``mask`` (rows x lanes) holds anywhere, and the time from
    the switch of its first row (``steps`` per row), NaN when never."""
    any_ = mask.any(axis=0)
    first = np.argmax(mask, axis=0)
    st = steps[first] if steps.ndim == 1 else steps[first, np.arange(mask.shape[1])]
    return any_, np.where(any_, (st - kf) * dt, np.nan)


def classify_sensor(spec: ChunkSpec, tr_name: str, variant: str, trial_ids, sizes,
                    inp: TrialInputs, rec: TrialRecord):
    """Per-trial and per-reset columns of a sensor transition.

    The actuators stay healthy, so the correct block is ``none`` and every
    action of the FTC scheme after the sensor fault (step ``k_f``) up to the end
    of the trial (or its stop) is a misattribution:

    * ``actuator_reset``: any covariance-block reset after ``k_f``
      (``actuator_reset_s``: time from the fault to the first);
    * ``wrong_mode``: at some belief update after ``k_f`` the most probable mode
      is an actuator fault with probability at least 0.5 (``wrong_mode_s``);
    * ``controller_switch``: the controller differs from the one in use at
      ``k_f`` after some update (``controller_switch_s``);
    * ``first_action_s``: the earliest of the three;
    * ``envelope_exit``: the aircraft left the airspeed or angle-of-attack
      envelope (the trial stopped there);
    * ``sensor_bias_hat_end``: the design's estimate of the faulty output's bias
      at the end (NaN when the design does not estimate it);
    * ``isolated``: a bias fault the design names: the trial flew to the end,
      the estimated bias is within :data:`ISOLATION_TOLERANCE` of the true one,
      and the belief's most probable mode at the last update is nominal.

    The actuator-row columns keep their definitions with the correct block
    ``none``: ``correct`` is True for no reset in the window, ``inappropriate``
    for any, and ``no_reset`` equals ``correct``; ``correct_reset_s`` is NaN
    (no block is correct); the summary does not report them for sensor rows.  ``judged``: no numerical failure and every reset
    stored (an envelope exit is an outcome here, not an exclusion).
    """
    setup = spec.setup
    tr = transition_of(tr_name)
    dt = setup.plant.dt
    kf = setup.tim.k_fault
    every = setup.tim.reconf_every
    L = len(trial_ids)
    resets, valid, in_win, before = _reset_columns(tr_name, variant, trial_ids, rec, kf,
                                                   spec.window, dt)
    after = valid & (rec.reset_k > kf)
    act_reset, act_reset_s = _first_after(after, rec.reset_k, kf, dt)
    n_per = rec.belief.shape[0]
    kn = (np.arange(n_per) + 1) * every
    alive = (rec.stop_k[None, :] < 0) | (kn[:, None] < rec.stop_k[None, :])
    watch = (kn[:, None] > kf) & alive
    best = np.argmax(rec.belief, axis=1)
    pbest = np.max(rec.belief, axis=1)
    wrong = watch & (best != MODE_NOMINAL) & (pbest >= 0.5)
    wrong_mode, wrong_mode_s = _first_after(wrong, kn, kf, dt)
    p_f = kf // every - 1
    cur0 = rec.controller[p_f] if p_f >= 0 else np.full(L, C_NOMINAL)
    switched = watch & (rec.controller != cur0[None, :])
    switch, switch_s = _first_after(switched, kn, kf, dt)
    first_action = np.fmin(np.fmin(act_reset_s, wrong_mode_s), switch_s)
    n_win = in_win.sum(axis=0)
    first = np.where(n_win > 0, np.argmax(in_win, axis=0), 0)
    first_k = rec.reset_k[first, np.arange(L)]
    first_block = rec.reset_block[first, np.arange(L)]
    truncated = rec.n_resets > rec.reset_k.shape[0]
    numeric_fail = (rec.status == STATUS_NONFINITE) | (rec.status == STATUS_NOT_PSD)
    trials = {
        "transition": np.full(L, tr_name, dtype=object),
        "variant": np.full(L, variant, dtype=object),
        "trial_id": np.asarray(trial_ids, dtype=np.int64),
        "lock_position": np.full(L, np.nan),
        "lock_offset": np.full(L, np.nan),
        "loss_b1": np.full(L, np.nan),
        "mode_pre": np.array([MODE_NAMES[m] for m in inp.mode_pre], dtype=object),
        "mode_post": np.array([MODE_NAMES[m] for m in inp.mode_post], dtype=object),
        "correct": n_win == 0,
        "inappropriate": n_win > 0,
        "no_reset": n_win == 0,
        "first_reset_s": np.where(n_win > 0, (first_k - kf) * dt, np.nan),
        "first_reset_block": np.array([BLOCK_NAMES[b] if n else "none"
                                       for b, n in zip(first_block, n_win)], dtype=object),
        "correct_reset_s": np.full(L, np.nan),
        "resets_in_window": n_win.astype(np.int64),
        "false_resets": before.sum(axis=0).astype(np.int64),
        "resets_total": rec.n_resets.copy(),
        "detection_s": np.full(L, np.nan),
        "mode_changed": np.zeros(L, dtype=bool),
        "detected": np.zeros(L, dtype=bool),
        "small_b1": np.zeros(L, dtype=bool),
        "lock_near_trim": np.zeros(L, dtype=bool),
        "b0_hat_end": np.full(L, np.nan),
        "b1_hat_end": np.full(L, np.nan),
        "resets_truncated": truncated,
        "judged": ~numeric_fail & ~truncated,
        "status": np.array([STATUS_NAMES[s] for s in rec.status], dtype=object),
        "stop_s": np.where(rec.stop_k >= 0, rec.stop_k * dt, np.nan),
        "correct_side": np.full(L, np.nan),  # no actuator is faulty
        "sensor_output": np.full(L, tr.output, dtype=object),
        "sensor_kind": np.full(L, tr.kind, dtype=object),
        "sensor_size": np.asarray(sizes, dtype=float),
        "actuator_reset": act_reset,
        "actuator_reset_s": act_reset_s,
        "wrong_mode": wrong_mode,
        "wrong_mode_s": wrong_mode_s,
        "controller_switch": switch,
        "controller_switch_s": switch_s,
        "first_action_s": first_action,
        "envelope_exit": (rec.status == STATUS_AIRSPEED) | (rec.status == STATUS_ALPHA),
    }
    trials.update(_isolation(setup.designs[variant], tr, sizes, rec))
    if rec.mon_b.shape[0]:  # the 6-DOF side monitor flew beside the design
        trials.update(side_columns(rec, None, True, kf, spec.window, dt))
    return trials, resets


ISOLATION_TOLERANCE = 0.25
"""Largest relative error of the estimated bias of an isolated sensor fault: the
filter then carries at most a quarter of the bias as a wrong state or fault
parameter."""


def _isolation(design, tr, sizes, rec: TrialRecord) -> dict:
    """``sensor_bias_hat_end`` and ``isolated`` of a sensor transition's lanes
    (:func:`classify_sensor`)."""
    L = rec.xa_end.shape[1]
    row = design.bias_row(tr.output)  # rec.xa_end holds the whole estimate
    if row is None:
        return {"sensor_bias_hat_end": np.full(L, np.nan), "isolated": np.zeros(L, dtype=bool)}
    hat = rec.xa_end[row].copy()
    size = np.asarray(sizes, dtype=float)
    nominal_end = np.argmax(rec.belief[-1], axis=0) == MODE_NOMINAL
    close = np.abs(hat - size) <= ISOLATION_TOLERANCE * np.abs(size)
    return {"sensor_bias_hat_end": hat,
            "isolated": (tr.kind == "bias") & (rec.status == 0) & close & nominal_end}


def count_flights(rec: TrialRecord) -> dict:
    """Flights, judged flights (valid to the end) and their resets."""
    ok = rec.status == 0
    return {"flights": len(ok), "judged": int(ok.sum()),
            "resets": int(rec.n_resets[ok].sum())}


def classify_flights(variant: str, flight_ids, rec: TrialRecord, dt: float, n_s: float):
    """Per-flight and per-reset columns of fault-free flights (``ftc-mc endurance``).

    Every reset of a fault-free flight is a false reset.  A flight is ``judged``
    when its numbers stayed finite and its covariance positive semi-definite;
    it then counts with the time it flew (``flown_s``: to its end, or to its
    exit from the validity envelope) and the resets it made meanwhile.  Its
    resets are counted whether or not stored; the first ``rec``-capacity of
    them keep their time and residuals.

    Returns
    -------
    flights : dict of str to ndarray
        ``variant, flight_id, status, stop_s, judged, flown_s, false_resets`` (all resets,
        stored or not), ``first_false_reset_s`` (from the flight's start, NaN
        without one); on the 6-DOF plant with its side monitor,
        ``side_decisions`` (its decisions, every one a false alarm).
    resets : dict of str to ndarray
        ``variant, flight_id, time_s`` (from the flight's start), ``block``,
        ``r_q, r_nx, r_nz`` of every stored reset.
    """
    L = len(flight_ids)
    R = rec.reset_k.shape[0]
    stored = np.minimum(rec.n_resets, R)
    valid = np.arange(R)[:, None] < stored[None, :]
    lane, slot = np.nonzero(valid.T)
    ids = np.asarray(flight_ids, dtype=np.int64)
    flights = {
        "variant": np.full(L, variant, dtype=object),
        "flight_id": ids,
        "status": np.array([STATUS_NAMES[s] for s in rec.status], dtype=object),
        "stop_s": np.where(rec.stop_k >= 0, rec.stop_k * dt, np.nan),
        "judged": (rec.status != STATUS_NONFINITE) & (rec.status != STATUS_NOT_PSD),
        "flown_s": np.where(rec.stop_k >= 0, rec.stop_k * dt, n_s),
        "false_resets": rec.n_resets.astype(np.int64),
        "first_false_reset_s": np.where(rec.n_resets > 0, rec.reset_k[0] * dt, np.nan),
    }
    if rec.mon_b.shape[0]:  # the 6-DOF side monitor: every decision of a fault-free flight
        flights["side_decisions"] = rec.side_n.astype(np.int64)
    resets = {
        "variant": np.full(len(lane), variant, dtype=object),
        "flight_id": ids[lane],
        "time_s": rec.reset_k[slot, lane] * dt,
        "block": np.array([BLOCK_NAMES[b] for b in rec.reset_block[slot, lane]], dtype=object),
        "r_q": rec.reset_res[slot, 0, lane],
        "r_nx": rec.reset_res[slot, 1, lane],
        "r_nz": rec.reset_res[slot, 2, lane],
    }
    return flights, resets


def steps_flown(rec: TrialRecord, n_steps: int) -> np.ndarray:
    """Per lane, the steps flown: to the stop (``stop_k``), or all ``n_steps``."""
    return np.where(rec.stop_k >= 0, rec.stop_k, n_steps)


def lateral_columns(rec: TrialRecord, n_steps: int) -> dict:
    """The 6-DOF plant's lateral columns of each trial: ``bank_rms_deg`` and
    ``heading_rms_deg``, the RMS of the bank and heading deviations from trim
    [deg] over the steps the trial flew (to its end, or to its exit from the
    validity envelope)."""
    flown = np.maximum(steps_flown(rec, n_steps), 1)
    return {"bank_rms_deg": np.degrees(np.sqrt(rec.sq_lat[0] / flown)),
            "heading_rms_deg": np.degrees(np.sqrt(rec.sq_lat[1] / flown))}


COST_COLUMNS = ("track_rms_m", "track_max_m") + tuple(
    f"control_energy_{n}" for n in LONGITUDINAL.inputs)
"""The trial columns of :func:`cost_columns`."""


def cost_columns(rec: TrialRecord, n_steps: int, dt: float) -> dict:
    """What flying a trial cost, over the steps it flew (to its end,
    or to its exit from the validity envelope; ``TrialRecord.cost``):
    ``track_rms_m`` and ``track_max_m``, the RMS and the largest magnitude of the
    glide path's cross-track error ``x sin(gamma0) + z cos(gamma0)`` [m] of the
    true state after each step; ``control_energy_<command>``, the sum of the
    command's squared deviation from trim times ``dt`` (throttle: [s], elevons:
    [rad^2 s]), excitation included."""
    flown = np.maximum(steps_flown(rec, n_steps), 1)
    out = {"track_rms_m": np.sqrt(rec.cost[COST_TRACK_SQ] / flown),
           "track_max_m": rec.cost[COST_TRACK_MAX].copy()}
    for i, name in enumerate(LONGITUDINAL.inputs):
        out[f"control_energy_{name}"] = rec.cost[COST_U2 + i] * dt
    return out


def height_columns(rec: TrialRecord, setup) -> dict:
    """``height_lost_m``: the height the aircraft lost from the switch to the last
    step it flew (its exit from the validity envelope, or the trial's end) [m],
    the glide path's own descent ``V0 |sin gamma0| t`` included; NaN for a trial
    that stopped before the switch (``TrialRecord.z_switch_last``; the height is
    ``V0 t sin(gamma0) - z`` above the start, ``z`` the vertical deviation, down,
    from the reference point flying the glide path)."""
    dt = setup.plant.dt
    last = steps_flown(rec, setup.tim.n_steps) * dt
    climb = setup.plant.trim.V0 * np.sin(setup.plant.trim.gamma0)
    z_switch, z_last = rec.z_switch_last
    return {"height_lost_m": climb * (setup.tim.k_fault * dt - last) + z_last - z_switch}


def _runs(spec: ChunkSpec):
    """``(t_q, t_nx, variant, Detection)`` of every run of a chunk, point-major."""
    setup = spec.setup
    if spec.points is None:
        return [(None, None, v, setup.det[v]) for v in spec.variants]
    return [(tq, tnx, v, setup.detection(v, tq, tnx))
            for tq, tnx in spec.points for v in spec.variants]


def first_resets(resets: dict, n: int | None) -> dict:
    """The rows of a chunk's ``resets`` columns (one design; rows by trial, then
    time) that are among the first ``n`` of their trial; all of them for None."""
    if n is None:
        return resets
    tid = np.asarray(resets["trial_id"])
    idx = np.arange(len(tid))
    new = np.ones(len(tid), dtype=bool)
    new[1:] = tid[1:] != tid[:-1]
    rank = idx - np.maximum.accumulate(np.where(new, idx, 0)) if len(tid) else idx
    keep = rank < n
    return {k: np.asarray(v)[keep] for k, v in resets.items()}


def _columns(parts) -> dict:
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def run_chunk(spec: ChunkSpec, name: str, trial_ids) -> dict:
    """Draw, simulate every run on the same inputs, and classify.

    Parameters
    ----------
    spec : ChunkSpec
    name : str
        A transition, :data:`FLIGHT` for fault-free flights (sweeps only), or
        :data:`ENDURANCE` for the fault-free flights of an endurance run
        (:func:`classify_flights` tables ``trials`` and ``resets``).
    trial_ids : ndarray of int

    Returns
    -------
    dict of str to DataFrame
        Without threshold points: ``trials`` and ``resets`` (:func:`classify`
        columns, variant-major).  With them: ``trials`` (plus ``t_q``, ``t_nx``;
        for :data:`FLIGHT`, one row of :func:`count_flights` per point and
        variant) and ``steps`` (trial steps ``simulated``, and ``alone``: what
        the points would cost run one by one).
    """
    setup = spec.setup
    runs = _runs(spec)
    L, n = len(trial_ids), setup.tim.n_steps
    if name == ENDURANCE:  # every design alone on the same flights (no threshold points)
        inp = flight_inputs(setup, trial_ids, spec.seed)
        recs, _ = simulate(setup, inp, [r[2:] for r in runs], spec.max_resets,
                           history=spec.record)
        parts = [classify_flights(v, trial_ids, rec, setup.plant.dt, n * setup.plant.dt)
                 for (_, _, v, _), rec in zip(runs, recs)]
        if setup.dof == 6:
            for (t, _), rec in zip(parts, recs):
                t.update(lateral_columns(rec, n))
        out = {"trials": pd.DataFrame(_columns([p[0] for p in parts])),
               "resets": pd.DataFrame(_columns([p[1] for p in parts]))}
        if spec.record:
            out["signals"] = _signals(spec, name, runs, trial_ids, inp, recs)
        return out
    if name == FLIGHT:
        assert spec.points is not None
        inp = flight_inputs(setup, trial_ids, spec.seed)
        recs, simulated = simulate(setup, inp, [r[2:] for r in runs], spec.max_resets, n)
        rows = [{"t_q": tq, "t_nx": tnx, "variant": v, **count_flights(rec)}
                for (tq, tnx, v, _), rec in zip(runs, recs)]
        return {"trials": pd.DataFrame(rows),
                "steps": pd.DataFrame({"simulated": [simulated], "alone": [L * n * len(runs)]})}
    inp, values = trial_inputs(spec, name, trial_ids)
    share = None if spec.points is None else setup.tim.k_fault
    recs, simulated = simulate(setup, inp, [r[2:] for r in runs], spec.max_resets, share,
                               history=spec.record)
    trials, resets = [], []
    for (tq, tnx, v, _), rec in zip(runs, recs):
        t, r = classify(spec, name, v, trial_ids, values, inp, rec)
        if setup.dof == 6:
            t.update(lateral_columns(rec, n))
        t.update(cost_columns(rec, n, setup.plant.dt))
        t.update(height_columns(rec, setup))
        if spec.points is not None:
            t["t_q"] = np.full(L, tq)
            t["t_nx"] = np.full(L, tnx)
        trials.append(t)
        resets.append(first_resets(r, spec.resets_kept))
    if spec.points is None:
        out = {"trials": pd.DataFrame(_columns(trials)),
               "resets": pd.DataFrame(_columns(resets))}
        if spec.record:
            out["signals"] = _signals(spec, name, runs, trial_ids, inp, recs)
        return out
    return {"trials": pd.DataFrame(_columns(trials)),
            "steps": pd.DataFrame({"simulated": [simulated], "alone": [L * n * len(runs)]})}


def _signals(spec: ChunkSpec, name: str, runs, trial_ids, inp, recs) -> pd.DataFrame:
    """The chunk's recorded signals, design by design
    (:func:`ftc_mc.campaign.signals.signals_frame`)."""
    from .signals import signals_frame
    tim = spec.setup.tim
    kind = None
    if isinstance(tr := TRANSITION_TABLE.get(name), KindTransition):
        neutral = neutral_params(1, 1)[0, :, :1]  # (N_FAULT_PARAM, 1, 1)
        acting = (np.asarray(inp.b1) != 0) | np.any(np.asarray(inp.fp) != neutral, axis=1)
        kind = np.where(acting, tr.kind_code, KIND_NONE)
    df = pd.concat([signals_frame(name, v, trial_ids, inp, rec, tim.k_fault,
                                  tim.reconf_every, kind)
                    for (_, _, v, _), rec in zip(runs, recs)], ignore_index=True)
    df["variant"] = pd.Categorical(df["variant"], categories=[r[2] for r in runs])
    return df


def warm_up(spec: ChunkSpec, tr_name: str) -> None:
    """Compile (or load from Numba's cache) the kernels before fanning out: one
    trial of ``tr_name`` under the first variant of each compile path the
    variants take (``core/shared/paths.py``).  When a path is not in the cache yet,
    one line on stderr says that it is being compiled, and another how long it
    took (:func:`ftc_mc.core.jit.announce_compile`); another process compiling
    it is waited for (:func:`ftc_mc.sim.compiling.compiled_once`)."""
    setup = spec.setup
    seen = set()
    for v in spec.variants:
        path = path_of(setup.scheme(v), setup.flight)
        if path in seen:
            continue
        seen.add(path)
        with compiled_once(advance, path):
            run_chunk(dataclasses.replace(spec, variants=(v,), max_resets=4, window=1,
                                          points=None, record=False), tr_name, np.arange(1))
