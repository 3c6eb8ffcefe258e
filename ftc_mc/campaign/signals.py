"""Recorded signals: every step of every trial, as a user's detector reads them.

``ftc-mc run --record signals`` (``campaign.record``) keeps each trial's per-step
history (the kernels' history mode, :func:`ftc_mc.sim.lanes.new_record` with
``history=True``, the one a scenario uses) and writes it, chunk by chunk, to
``signals/<transition>-<first trial id>.parquet`` beside ``trials.parquet``: one
row per trial, design and step, keyed by ``(transition, variant, trial_id)`` as
``trials.parquet`` is.  The columns (:func:`signal_columns`) are documented in
``docs/reference/outputs.md``.

A row ``step = k`` holds what the loop of its design saw and did on the step
that reached sample ``k`` (time ``k dt``): the measurements ``z_k``, the
commands applied during the step, the truth's fault parameters and mode during
it, the excitation, the filter's normalised innovations, the decision
statistics Table 1 (or the GLR) compared at ``k``, the block reset at ``k``, and
the belief after the last reconfiguration period ending at or before ``k``.
Rows stop at the last step after which the trial was still valid (its
``stop_s``, ``trials.parquet``): a trial that left the envelope has fewer rows.

Measured signals, commands, innovations, fault values and the belief are
``float32``: their noise (measurement noise at least 1e-3 of their scale, the
innovations unit-variance) is far above float32's 6e-8 relative rounding.  The
decision statistics ``r_q, r_nx, r_nz`` stay ``float64``, so that Table 1
re-run offline on them compares with the same thresholds bit for bit
(:func:`ftc_mc.campaign.detector.table1_detector`); on the 6-DOF plant the
side monitor's projections are float64 too, for its decisions re-run offline
(:func:`ftc_mc.campaign.detector.side_monitor_decisions`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..conventions import LONGITUDINAL as LAY
from ..conventions import MODE_NAMES
from ..core.longitudinal.workspace import EXC_3211, EXC_DOUBLET
from ..sim.inputs import Schedule, schedule_kinds

FOLDER = "signals"
"""The folder of a run's recorded signals, beside ``trials.parquet``."""

KEYS = ("transition", "variant", "trial_id", "step")
"""The key columns of a signals row."""


def innovation_names() -> tuple:
    """``innov_q, innov_nx, innov_nz``: one per Table 1 residual channel."""
    return tuple("innov_" + r.partition("_")[2] for r in LAY.residuals)


KIND_COLUMNS = tuple(f"kind_{a}" for a in LAY.actuators)
"""The truth's fault kind of each actuator during the step: its code in
:data:`~ftc_mc.conventions.ACTUATOR_FAULT_KINDS`, ``-1`` while the actuator
is healthy (an intermittent fault's off-spells included)."""

TRUTH_COLUMNS = (("mode",) + tuple(f"b0_{a}" for a in LAY.actuators)
                 + tuple(f"b1_{a}" for a in LAY.actuators) + KIND_COLUMNS)
"""The signal columns that hold the truth, not what the aircraft sees: the true
mode, each actuator's ``b0``, ``b1`` and fault kind.  A detector scored by ``ftc-mc score``
reads them only when it names them (:mod:`ftc_mc.campaign.detector`); every
other signal column is observable on board."""


def lateral_columns() -> tuple:
    """The 6-DOF plant's lateral sensors (bank, side velocity, roll and yaw
    rates, heading; deviations from the 6-DOF trim).  The 6-DOF layout is
    imported here, not with the module: a longitudinal run never imports the
    6-DOF family (``tests/test_sixdof.py``)."""
    from ..core.sixdof.layout import MONITOR_LATERAL
    return tuple(f"z_{o}" for o in MONITOR_LATERAL)


def monitor_columns() -> tuple:
    """The 6-DOF side monitor's projection of each fault direction (throttle,
    left, right elevon): standard normal under no fault, the input of its GLR
    (``ftc_mc/core/sixdof/monitor.py``)."""
    from ..core.sixdof.layout import MONITOR_DIRECTIONS
    return tuple(f"side_d_{d}" for d in MONITOR_DIRECTIONS)


def signal_columns(n_z: int = LAY.n_z, sixdof: bool = False) -> tuple:
    """Names of the signal columns of a signals row (after :data:`KEYS`), in file
    order (``docs/reference/outputs.md``); :data:`TRUTH_COLUMNS` among them.
    ``sixdof``: a recording on the 6-DOF plant with its side monitor, which
    adds :func:`lateral_columns` and :func:`monitor_columns`."""
    outs = LAY.outputs if n_z == LAY.n_z else tuple(str(i) for i in range(n_z))
    return (tuple(f"z_{o}" for o in outs) + (lateral_columns() if sixdof else ())
            + tuple(f"u_{i}" for i in LAY.inputs)
            + TRUTH_COLUMNS + ("exc_doublet", "exc_3211")
            + innovation_names() + tuple(LAY.residuals) + ("reset",)
            + tuple(f"belief_{m}" for m in MODE_NAMES)
            + (monitor_columns() if sixdof else ()))


def is_truth(column: str) -> bool:
    """Whether a signal column holds the truth (:data:`TRUTH_COLUMNS`)."""
    return column in TRUTH_COLUMNS


def _rows(a: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """``a`` laid out (steps, [channels,] lanes) as rows (lane-major, then step) of
    the kept (lane, step) pairs: shape (rows,) or (rows, channels)."""
    if a.ndim == 2:
        return a.T[keep]
    return np.moveaxis(a, 2, 0)[keep]


def signals_frame(tr_name: str, variant: str, trial_ids, inp, rec, k_fault: int,
                  every: int, kind=None) -> pd.DataFrame:
    """The signals rows of one design's record of a chunk.

    Parameters
    ----------
    tr_name, variant : str
        Transition (or chunk name) and design.
    trial_ids : ndarray of int, shape (L,)
    inp : TrialInputs
        The chunk's inputs (``k_switch``, ``b0``, ``b1``, ``mode_pre``, ``mode_post``).
    rec : TrialRecord
        Recorded with its history (``history=True``).
    k_fault : int
        Step of the switch to the final mode.
    every : int
        Steps per reconfiguration period.
    kind : ndarray of int, shape (E, 3, L), optional
        The schedule's fault kind per entry and actuator (``Schedule.kind``);
        omitted: lock or loss as ``b1`` says (:func:`ftc_mc.sim.inputs.schedule_kinds`).

    Returns
    -------
    DataFrame
        :data:`KEYS` then :func:`signal_columns`, rows by trial then step.
    """
    n, L = rec.hist_block.shape
    kn = np.arange(1, n + 1)
    stop = np.asarray(rec.stop_k)
    keep = (stop[:, None] < 0) | (kn[None, :] < stop[:, None])  # (L, n)
    lane, k = np.nonzero(keep)
    f4 = np.float32
    same = np.zeros(len(lane), dtype=np.int8)
    cols = {"transition": pd.Categorical.from_codes(same, [tr_name]),
            "variant": pd.Categorical.from_codes(same, [variant]),
            "trial_id": np.asarray(trial_ids, dtype=np.int64)[lane],
            "step": (k + 1).astype(np.int32)}
    sixdof = rec.hist_mon.shape[1] > 0
    names = signal_columns(rec.hist_z.shape[1], sixdof)
    z = _rows(rec.hist_z, keep).astype(f4)
    if sixdof:
        z = np.hstack([z, _rows(rec.hist_lat, keep).astype(f4)])
    u = _rows(rec.hist_u, keep).astype(f4)
    i = 0
    for j in range(z.shape[1]):
        cols[names[i]] = z[:, j]
        i += 1
    for j in range(u.shape[1]):
        cols[names[i]] = u[:, j]
        i += 1
    # the truth during the step k -> k+1 (row step = k+1)
    mode = np.where(k >= k_fault, np.asarray(inp.mode_post)[lane], np.asarray(inp.mode_pre)[lane])
    cols["mode"] = pd.Categorical.from_codes(mode, categories=list(MODE_NAMES))
    e = np.searchsorted(np.asarray(inp.k_switch), k, side="right") - 1
    for name, arr in (("b0", inp.b0), ("b1", inp.b1)):
        for a, act in enumerate(LAY.actuators):
            cols[f"{name}_{act}"] = np.asarray(arr)[e, a, lane].astype(f4)
    kinds = (schedule_kinds(Schedule(inp.k_switch, inp.b0, inp.b1)) if kind is None
             else np.asarray(kind))
    for a, nm in enumerate(KIND_COLUMNS):
        cols[nm] = kinds[e, a, lane].astype(np.int8)
    exc = _rows(rec.hist_exc, keep)
    cols["exc_doublet"] = exc[:, EXC_DOUBLET].astype(f4)
    cols["exc_3211"] = exc[:, EXC_3211].astype(f4)
    innov = _rows(rec.hist_innov, keep).astype(f4)
    for j, nm in enumerate(innovation_names()):
        cols[nm] = innov[:, j]
    res = _rows(rec.hist_res, keep)
    for j, nm in enumerate(LAY.residuals):
        cols[nm] = np.ascontiguousarray(res[:, j], dtype=np.float64)
    cols["reset"] = _rows(rec.hist_block, keep).astype(np.int8)
    # the belief after the last period ending at or before the row's step
    p = (k + 1) // every - 1
    init = np.zeros((len(MODE_NAMES), L))
    init[np.asarray(inp.mode_pre), np.arange(L)] = 1.0
    bel = np.concatenate([init[None], rec.belief], axis=0)  # row 0: before any update
    for m, nm in enumerate(MODE_NAMES):
        cols[f"belief_{nm}"] = bel[p + 1, m, lane].astype(f4)
    if sixdof:  # float64: the monitor's GLR re-run offline decides as it did
        mon = _rows(rec.hist_mon, keep)
        for j, nm in enumerate(monitor_columns()):
            cols[nm] = np.ascontiguousarray(mon[:, j], dtype=np.float64)
    return pd.DataFrame(cols)


def chunk_file(out_dir, name: str, start: int) -> Path:
    """The signals file of the chunk ``(name, start)`` in a run directory."""
    return Path(out_dir) / FOLDER / f"{name}-{start:09d}.parquet"


def move_signals(store, units, out_dir) -> None:
    """Move every chunk's signals from the chunk store to ``out_dir/signals/``
    (a rename each: nothing is read or copied; idempotent, so a run resumed
    after a partial move finishes it)."""
    folder = Path(out_dir) / FOLDER
    folder.mkdir(exist_ok=True)
    for name, ids in units:
        start = int(ids[0])
        src = store._path(name, start, "signals")
        if src.exists():
            os.replace(src, chunk_file(out_dir, name, start))


def signal_files(run_dir) -> list:
    """The signals files of a run directory, in name order (empty when the run
    was recorded without signals)."""
    folder = Path(run_dir) / FOLDER
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir()
                  if p.suffix == ".parquet" and not p.name.startswith("."))
