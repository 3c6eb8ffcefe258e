"""Score a user's detector on a run's recorded signals, by the built-in designs' rules.

A *detector* is a plain NumPy function::

    def detector(signals, names, dt):
        # signals: float ndarray (trials, steps, len(names)), NaN after a trial stopped
        # names:   tuple of str, the signal columns (docs/reference/outputs.md)
        # dt:      the sampling period [s]
        return alarm_s                    # (trials,) first alarm time [s], NaN: none,
        #                                 # from dt to the trial's last sample
        # or: return alarm_s, block       # block: (trials,) "thrust" / "elevons"
        #                                 # (or 1 / 2), an actuator name, or ""
        #                                 # (None, NaN) where unnamed

A detector sees what the aircraft sees: by default the observable columns, every
signal column but the truth (:data:`ftc_mc.campaign.signals.TRUTH_COLUMNS`: the
true ``mode`` and each actuator's ``b0_*``, ``b1_*``).  A detector with an
attribute ``columns`` (a tuple of signal names) receives only those, in that
order: less to read.  It gets a truth column only when ``columns`` names it, and
then its rows are marked as having read the truth (``reads_truth``: an oracle,
not a detector an aircraft could fly).  Row ``j`` of ``signals`` holds the step that reached sample ``j + 1`` (time
``(j + 1) dt``, the ``step`` column of ``signals/``).  It is called once per
signals file (one chunk of trials) and design, with the signals of the loop
that design flew: the detector sees them *open loop*, it cannot act on them
(``docs/guides/your-detector.md``).

Its first alarm is scored as a built-in design's first reset
(:func:`ftc_mc.campaign.chunk.classify`, with ``k_f`` the switch step and the
window ``k_f < k <= k_f + window``): an alarm at ``k`` in the window is
*correct* when it names the transition's block (or names none), *inappropriate*
when it names the other block; no alarm in the window is *no alarm*
(``no_reset``); an alarm at or before ``k_f`` of a trial that starts nominal is a
false alarm (``false_resets = 1``), and then its window holds no alarm (only
the first alarm is known).  The other columns (``judged``, ``status``, the
costs) are the flown trial's, so the detector is judged on the same trials as
the design; ``correct_side`` (6-DOF runs) is whether the alarm in the window
named the faulty elevon (``left_elevon`` or ``right_elevon``).  Its rows take the variant name ``<detector>@<design>``; the summary
rows are :func:`ftc_mc.campaign.summary.summary_row`'s, Tables 2-3 and the ALFA
scores alike.

Fault-free flights of ``ftc-mc endurance --record signals``: every alarm is a
false alarm, summarised as the designs' false resets are
(:func:`ftc_mc.campaign.endurance.summarize_endurance`: per flight hour with
exact Poisson intervals; at most one per flight, its first alarm).

Scoring refuses, with one line (a :class:`~ftc_mc.errors.UserError`) and before
anything is written, every input it cannot score honestly: a name that is not a
plain name, an output folder inside the run's own files, a run folder, table,
metadata or signals file that is missing, damaged or inconsistent, and every
detector return that is not one alarm time per trial (numbers, NaN for none,
from the first sample ``dt`` to the trial's last recorded sample) with an
optional valid block per trial, or a detector that raises.
"""

from __future__ import annotations

import importlib
import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ..conventions import LONGITUDINAL as LAY
from ..conventions import MODE_NAMES, MODE_NOMINAL, NO_RESET
from ..errors import UserError
from ..io.lock import holder
from ..io.results import META_KEY
from .signals import KEYS, TRUTH_COLUMNS, signal_files
from .summary import summary_frame, summary_row
from .transitions import TRANSITION_TABLE, is_sensor

ENDURANCE_NAME = "endurance"
"""The chunk (and ``transition``) name of an endurance run's flights."""


NAME_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+-]{0,99}")
"""A detector's name: a plain name (the folder ``detectors/<name>/`` and the
prefix of its variants ``<name>@<design>``), never a path."""


def check_name(name) -> str:
    """``name`` when it is a plain name (:data:`NAME_PATTERN`), else a UserError.

    Raises
    ------
    UserError
        Not a string, empty, a path, longer than 100 characters, or holding a
        character other than letters, digits, ``_``, ``.``, ``+``, ``-`` (or
        starting with ``.``, ``+``, ``-``).
    """
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name):
        raise UserError(f"--name: {name!r} is not a plain name (letters, digits, '_', "
                        "'.', '+', '-', at most 100, starting with a letter, digit or '_'; "
                        "never a path)")
    return name


def load_detector(spec: str):
    """The function ``module:function`` names (the module imported as Python
    imports it; the current folder first).

    Raises
    ------
    UserError
        Not ``module:function``, a module that cannot be imported, or no such
        callable in it.
    """
    import sys
    mod, sep, fn = spec.partition(":")
    if not sep or not mod or not fn:
        raise UserError(f"--detector: expected module:function, got {spec!r}")
    if "" not in sys.path and "." not in sys.path:
        sys.path.insert(0, "")
    try:
        module = importlib.import_module(mod)
    except (Exception, SystemExit) as exc:  # noqa: BLE001 -- any import failure is the user's
        raise UserError(f"--detector: cannot import {mod!r}: {type(exc).__name__}: "
                        f"{_one_line(exc)}") from None
    func = getattr(module, fn, None)
    if not callable(func):
        raise UserError(f"--detector: {mod!r} has no function {fn!r}")
    return func


def _one_line(exc) -> str:
    """An exception's message on one line."""
    return " ".join(str(exc).split())


def _read_schema(f: Path):
    """The Parquet schema of ``f``, or a one-line UserError."""
    if not f.is_file():
        raise UserError(f"{f}: not a file")
    try:
        return pq.read_schema(f)
    except (pa.ArrowException, OSError) as exc:
        raise UserError(f"{f}: not a readable Parquet file ({_one_line(exc)})") from None


def _read_table(f: Path, columns) -> pa.Table:
    """The columns ``columns`` of the Parquet file ``f``, or a one-line UserError."""
    try:
        return pq.read_table(f, columns=list(columns))
    except (pa.ArrowException, OSError) as exc:
        raise UserError(f"{f}: not a readable Parquet file ({_one_line(exc)})") from None


def run_meta(run_dir) -> dict:
    """The provenance of a run or endurance directory (its config included).

    Raises
    ------
    UserError
        No such folder, not a folder, no ``trials.parquet`` or
        ``flights.parquet``, a table that cannot be read, or metadata that is
        missing, damaged or not of a run or endurance run.
    """
    d = Path(run_dir)
    if not d.exists():
        raise UserError(f"{run_dir}: no such folder")
    if not d.is_dir():
        raise UserError(f"{run_dir}: not a folder")
    for name, kind in (("trials.parquet", "run"), ("flights.parquet", "endurance")):
        f = d / name
        if not f.exists() and not f.is_symlink():
            continue
        md = _read_schema(f).metadata or {}
        if META_KEY not in md:
            raise UserError(f"{f}: no ftc-mc metadata (not written by ftc-mc)")
        try:
            meta = json.loads(md[META_KEY])
        except (ValueError, UnicodeDecodeError):
            raise UserError(f"{f}: damaged ftc-mc metadata (not JSON)") from None
        if not isinstance(meta, dict) or not isinstance(meta.get("config"), dict):
            raise UserError(f"{f}: damaged ftc-mc metadata (no config)")
        if meta.get("kind") != kind:
            raise UserError(f"{f}: metadata of kind {meta.get('kind')!r}, expected {kind!r}")
        return meta
    raise UserError(f"{run_dir}: not a finished run or endurance directory "
                    "(no trials.parquet or flights.parquet)")


BATCH_VALUES = 1 << 22
"""Signal values (trials x steps x signals) of one call of a detector, at most:
consecutive chunk files of a transition are joined up to it (fewer, larger
calls; 16 MB of float32, whatever the run's size)."""


def batches(run_dir, columns=None, truth: bool = True):
    """The recorded signals of a run, in batches of one transition and design
    (consecutive chunk files joined up to :data:`BATCH_VALUES` values).

    Parameters
    ----------
    run_dir : str or Path
    columns : sequence of str, optional
        The signal columns to read, in this order (default: all of a file's).
    truth : bool
        With ``columns`` None, whether the truth columns
        (:data:`~ftc_mc.campaign.signals.TRUTH_COLUMNS`, the labels of a learned
        detector's training) are among them; the scoring passes False.

    Yields
    ------
    name : str
        Transition (or ``endurance``).
    design : str
    trial_ids : ndarray of int64, shape (n,)
    signals : ndarray of float32 (float64 when a column is), shape (n, steps, len(names))
        NaN after a trial's last recorded step.
    names : tuple of str
        The signal columns (all of the file's but the keys, or ``columns``).

    Raises
    ------
    UserError
        No signals, or a signals file that cannot be read or holds wrong
        columns, types or rows.
    """
    for name, design, ids, sig, names, _ in _batches(run_dir, columns, truth):
        yield name, design, ids, sig, names


def _batches(run_dir, columns=None, truth: bool = True, max_step: int | None = None):
    """:func:`batches`, each with the last recorded step of each trial; steps
    beyond ``max_step`` (the flight's samples) are refused."""
    files = signal_files(run_dir)
    if not files:
        raise UserError(f"{run_dir}: recorded without signals (run it with "
                        "--record signals)")
    group, group_name, values = [], None, 0
    names = None
    for f in files:
        schema = _read_schema(f)
        have = schema.names
        lost = [k for k in KEYS if k not in have]
        if lost:
            raise UserError(f"{f}: not a signals file (no key columns {lost})")
        if columns is None:
            names = tuple(c for c in have if c not in KEYS
                          and (truth or c not in TRUTH_COLUMNS))
        else:
            names = tuple(columns)
        missing = [c for c in names if c not in have]
        if missing:
            raise UserError(f"{f}: no signal columns {missing}")
        if not names:
            raise UserError(f"{f}: no signal columns")
        for c in names:
            t = schema.field(c).type
            text = _is_text(t)
            if (c == "mode") != text or not (text or pa.types.is_integer(t)
                                             or pa.types.is_floating(t)):
                raise UserError(f"{f}: signal column {c!r} is of type {t}, not "
                                + ("the mode's names" if c == "mode" else "numbers"))
        table = _read_table(f, [*KEYS, *names])
        _check_rows(f, table, max_step)
        name = table["transition"][0].as_py()
        size = table.num_rows * len(names)
        if group and (name != group_name or values + size > BATCH_VALUES):
            yield from _split(pa.concat_tables(group), group_name, names)
            group, values = [], 0
        group.append(table)
        group_name = name
        values += size
    if group:
        yield from _split(pa.concat_tables(group), group_name, names)


def _check_rows(f: Path, table: pa.Table, max_step: int | None) -> None:
    """One signals file's rows: some, of one transition, keys without nulls, the
    steps of the flight (``1 .. max_step``), modes known."""
    if table.num_rows == 0:
        raise UserError(f"{f}: no rows")
    for k in KEYS:
        if table[k].null_count:
            raise UserError(f"{f}: {k} has empty values")
    for k in ("trial_id", "step"):
        if not pa.types.is_integer(table.schema.field(k).type):
            raise UserError(f"{f}: {k} is of type {table.schema.field(k).type}, not integers")
    for k in ("transition", "variant"):
        if not _is_text(table.schema.field(k).type):
            raise UserError(f"{f}: {k} is of type {table.schema.field(k).type}, not names")
    if len(pc.unique(_text(table["transition"]))) != 1:
        raise UserError(f"{f}: rows of more than one transition")
    lo, hi = pc.min_max(table["step"]).values()
    if lo.as_py() < 1 or (max_step is not None and hi.as_py() > max_step):
        raise UserError(f"{f}: steps {lo.as_py()}..{hi.as_py()} outside the flight's "
                        f"1..{max_step if max_step is not None else ''}")
    if "mode" in table.column_names:
        seen = pc.unique(_text(table["mode"])).to_pylist()
        bad = [m for m in seen if m not in MODE_NAMES]
        if bad:
            raise UserError(f"{f}: mode {bad[0]!r} is none of {list(MODE_NAMES)}")


def _is_text(t) -> bool:
    """Whether an Arrow type holds names (strings, or a dictionary of them)."""
    if pa.types.is_dictionary(t):
        t = t.value_type
    return pa.types.is_string(t) or pa.types.is_large_string(t)


def _text(col) -> pa.Array:
    """A column of names as plain strings."""
    col = col.combine_chunks()
    return col.cast(pa.string()) if isinstance(col, pa.DictionaryArray) else col


def _split(table, name: str, names):
    """The batches of one joined table, one per design (:func:`_batches`)."""
    # float64 when a column is (the decision statistics: thresholds compare exactly)
    wide = any(pa.types.is_float64(table.schema.field(c).type) for c in names)
    variant = table["variant"].combine_chunks()
    if isinstance(variant, pa.DictionaryArray):
        variant = variant.cast(pa.string())
    for design in pc.unique(variant).to_pylist():
        t = table.filter(pc.equal(variant, design))
        ids = t["trial_id"].to_numpy()
        step = t["step"].to_numpy().astype(np.int64)
        uid, lane = np.unique(ids, return_inverse=True)
        n_steps = int(step.max())
        if len(np.unique(lane * (n_steps + 1) + step)) != len(step):
            raise UserError(f"signals of {name}, {design}: a trial's step recorded twice")
        last = np.zeros(len(uid), dtype=np.int64)
        np.maximum.at(last, lane, step)
        out = np.full((len(uid), n_steps, len(names)), np.nan,
                      dtype=np.float64 if wide else np.float32)
        for j, c in enumerate(names):
            col = t[c]
            if c == "mode":  # the mode's code (conventions.MODE_NAMES)
                d = col.combine_chunks()
                if isinstance(d, pa.DictionaryArray):
                    codes = np.array([MODE_NAMES.index(m) for m in d.dictionary.to_pylist()])
                    v = codes[d.indices.to_numpy()].astype(np.float32)
                else:
                    v = np.array([MODE_NAMES.index(m) for m in d.to_pylist()],
                                 dtype=np.float32)
            else:
                v = col.to_numpy(zero_copy_only=False)
            out[lane, step - 1, j] = v
        yield name, design, uid, out, names, last


def _check_output(res, n: int, where: str, dt: float | None = None, last_s=None):
    """The alarm times, and the block codes and actuator names of a detector's
    return, or a UserError: one alarm time per trial (numbers, not booleans;
    NaN for none; none infinite, none before the first sample ``dt``, none after
    the trial's last recorded sample ``last_s``), and optionally one block per
    trial."""
    block = None
    if isinstance(res, tuple):
        if len(res) != 2:
            raise UserError(f"detector: {where}: expected alarm_s or (alarm_s, block), "
                            f"got a tuple of {len(res)}")
        res, block = res
    if res is None:
        raise UserError(f"detector: {where}: returned None, not alarm times")
    try:
        raw = np.asarray(res)
    except Exception:  # noqa: BLE001 -- whatever the user returned
        raise UserError(f"detector: {where}: alarm times are not numbers") from None
    if raw.dtype.kind not in "iuf":
        what = {"b": "booleans", "c": "complex numbers"}.get(raw.dtype.kind, "not numbers")
        raise UserError(f"detector: {where}: alarm times are {what} (dtype {raw.dtype}), "
                        "expected times [s]")
    alarm = raw.astype(float)
    if alarm.shape != (n,):
        raise UserError(f"detector: {where}: expected {n} alarm times (one per trial), "
                        f"got shape {alarm.shape}")
    if np.isinf(alarm).any():
        raise UserError(f"detector: {where}: alarm times must be finite or NaN (none)")
    if dt is not None:
        early = alarm < dt * (1 - 1e-9)
        if early.any():
            i = int(np.argmax(early))
            raise UserError(f"detector: {where}: alarm at {alarm[i]:g} s, before the "
                            f"flight's first sample ({dt:g} s; trial index {i})")
    if last_s is not None:
        late = alarm > np.asarray(last_s, dtype=float) + 1e-9 * max(dt or 1.0, 1.0)
        if late.any():
            i = int(np.argmax(late))
            raise UserError(f"detector: {where}: alarm at {alarm[i]:g} s, after the "
                            f"trial's last recorded sample ({last_s[i]:g} s; trial index {i})")
    codes = np.full(n, -1, dtype=np.int64)  # -1: no block named
    sides = np.full(n, "", dtype=object)  # the actuator named, if one was
    if block is not None:
        try:
            block = np.asarray(block, dtype=object)
        except Exception:  # noqa: BLE001 -- whatever the user returned
            raise UserError(f"detector: {where}: blocks are not an array") from None
        if block.shape != (n,):
            raise UserError(f"detector: {where}: expected {n} blocks, got shape "
                            f"{block.shape}")
        for i, b in enumerate(block):
            codes[i] = _block_code(b, where)
            if isinstance(b, str) and b in LAY.actuators:
                sides[i] = b
    return alarm, (codes, sides)


def _block_code(b, where: str) -> int:
    """The block code of a named block: ``"thrust"`` / ``"elevons"`` (or their
    codes 1, 2), an actuator's name; -1 for none named (``""``, None, NaN)."""
    if b is None or (isinstance(b, str) and b == "") \
            or (isinstance(b, (float, np.floating)) and math.isnan(b)):
        return -1
    if isinstance(b, (int, np.integer)) and not isinstance(b, (bool, np.bool_)):
        if 0 < b < len(LAY.blocks):
            return int(b)
    elif isinstance(b, str) and b in LAY.blocks[1:]:
        return LAY.blocks.index(b)
    elif isinstance(b, str) and b in LAY.actuators:
        return LAY.actuator_block[LAY.actuators.index(b)]
    raise UserError(f"detector: {where}: block {b!r} is none of {LAY.blocks[1:]} "
                    f"or {LAY.actuators}")


def call_detector(detector, signals, names, dt: float, where: str, last_s=None):
    """Call ``detector`` on one batch; its failure or bad output is a UserError
    (:func:`_check_output`; ``last_s``: each trial's last recorded sample [s])."""
    try:
        res = detector(signals, names, dt)
    except (Exception, SystemExit) as exc:  # noqa: BLE001 -- the user's code
        raise UserError(f"detector raised {type(exc).__name__} on {where}: "
                        f"{_one_line(exc)}") from None
    return _check_output(res, signals.shape[0], where, dt, last_s)


def _wanted_columns(detector):
    """The detector's ``columns`` as a tuple of names (None: it has none), or a
    UserError."""
    cols = getattr(detector, "columns", None)
    if cols is None:
        return None
    bad = isinstance(cols, (str, bytes)) or not hasattr(cols, "__iter__")
    cols = () if bad else tuple(cols)
    if bad or not cols or not all(isinstance(c, str) for c in cols):
        raise UserError(f"detector.columns: expected a tuple of signal names, got "
                        f"{getattr(detector, 'columns')!r}")
    keys = [c for c in cols if c in KEYS]
    if keys:
        raise UserError(f"detector.columns: {keys[0]!r} is a key, not a signal column")
    if len(set(cols)) != len(cols):
        raise UserError(f"detector.columns: a name given twice in {cols}")
    return cols


def _check_out(run_dir: Path, folder: Path, default: bool) -> None:
    """The detector's output folder: inside the run folder only below
    ``detectors/``, no file on its path."""
    run = run_dir.resolve()
    f = folder.resolve()
    allowed = run / "detectors"
    if default and allowed not in f.parents:
        raise UserError(f"{folder}: leads out of {run_dir}/detectors/ (a link?)")
    if (f == run or run in f.parents) and allowed not in f.parents:
        raise UserError(f"-o {folder}: inside the run folder only as "
                        f"{run_dir}/detectors/<folder> (the run's own files are never "
                        "written)")
    for q in (f, *f.parents):
        if q.exists():
            if not q.is_dir():
                raise UserError(f"-o {folder}: {q} is a file, not a folder")
            break


FLOWN_COLUMNS = {"run": ("transition", "variant", "trial_id", "judged", "status",
                         "mode_pre", "mode_post", "correct_side", "mode_changed",
                         "small_b1", "lock_near_trim"),
                 "endurance": ("variant", "flight_id", "judged", "status", "flown_s")}
"""The columns of the run's ``trials.parquet`` (``flights.parquet``) the scoring
reads beside the keys."""


def _flown(table: Path, endurance: bool) -> pd.DataFrame:
    """The run's trials (flights), checked: readable, its columns there, each
    trial once."""
    need = FLOWN_COLUMNS["endurance" if endurance else "run"]
    have = _read_schema(table).names
    lost = [c for c in need if c not in have]
    if lost:
        raise UserError(f"{table}: no columns {lost}")
    try:
        flown = pd.read_parquet(table)
    except (pa.ArrowException, OSError, ValueError) as exc:
        raise UserError(f"{table}: not a readable Parquet file ({_one_line(exc)})") from None
    key = ["variant", "flight_id"] if endurance else ["transition", "variant", "trial_id"]
    if not pd.api.types.is_integer_dtype(flown[key[-1]]) \
            or not pd.api.types.is_bool_dtype(flown["judged"]):
        raise UserError(f"{table}: {key[-1]} is not integers or judged not booleans")
    if flown[key].isna().any().any():
        raise UserError(f"{table}: {'/'.join(key)} has empty values")
    if flown.duplicated(key).any():
        raise UserError(f"{table}: a {'flight' if endurance else 'trial'} listed twice")
    return flown


def _trial_rows(flown: pd.DataFrame, alarm, named_by, cfg: dict, name: str) -> pd.DataFrame:
    """The design's trial rows ``flown`` with its detection columns replaced by
    the detector's (module docstring).  ``correct_side``: where the design's
    applies (a judged elevon trial whose final mode is an elevon's), 1.0 when
    the detector's alarm in the window named the faulty elevon, else 0.0; NaN
    throughout when the detector names no actuator in any trial."""
    codes, sides = named_by
    dt = cfg["model"]["dt_s"]
    kf = round(cfg["timing"]["fault_time_s"] / dt)
    win = round(cfg["timing"]["window_s"] / dt)
    tr = TRANSITION_TABLE[name]
    k = np.where(np.isfinite(alarm), np.round(alarm / dt), -1).astype(np.int64)
    has = np.isfinite(alarm)
    in_win = has & (k > kf) & (k <= kf + win)
    before = has & (k <= kf)
    named = codes >= 0
    correct = in_win & (~named | (codes == tr.correct_block))
    other = in_win & named & (codes == tr.other_block)
    delay = np.where(in_win, (k - kf) * dt, np.nan)
    g = flown.copy()
    nominal = g["mode_pre"].to_numpy() == MODE_NAMES[MODE_NOMINAL]
    g["correct"] = correct
    g["inappropriate"] = other
    g["no_reset"] = ~in_win
    g["first_reset_s"] = delay
    g["first_reset_block"] = np.where(in_win, np.array(
        [LAY.blocks[c] if c >= 0 else "unnamed" for c in codes], dtype=object), "none")
    g["correct_reset_s"] = np.where(correct, delay, np.nan)
    g["resets_in_window"] = in_win.astype(np.int64)
    g["false_resets"] = (before & nominal).astype(np.int64)
    g["resets_total"] = has.astype(np.int64)
    g["resets_truncated"] = False
    g["detected"] = False  # the belief's detection is the design's, not the detector's
    g["detection_s"] = np.nan
    applies = np.isfinite(g["correct_side"].to_numpy(dtype=float))
    if (sides != "").any():
        g["correct_side"] = np.where(applies, (in_win & (sides == g["mode_post"].to_numpy()))
                                     .astype(float), np.nan)
    else:
        g["correct_side"] = np.nan
    g["alarm_s"] = alarm
    g["alarm_block"] = np.array([LAY.blocks[c] if c >= 0 else "" for c in codes], dtype=object)
    g["alarm_actuator"] = sides
    return g


def score_detector(run_dir, detector, out=None, name: str | None = None) -> dict:
    """Score ``detector`` on the recorded signals of ``run_dir``.

    Parameters
    ----------
    run_dir : str or Path
        A run (``ftc-mc run --record signals``) or endurance run
        (``ftc-mc endurance --record signals``) directory.
    detector : callable or str
        The detector (module docstring), or ``"module:function"``.  It is
        passed the observable signal columns, or those its ``columns``
        attribute names (a truth column only then: ``reads_truth``).
    out : str or Path, optional
        Where to write ``trials.parquet`` and ``summary.parquet`` (a run) or
        ``flights.parquet`` and ``endurance.parquet`` (an endurance run) of the
        detector, and ``summary.md``; default ``run_dir/detectors/<name>/``.
        Inside ``run_dir`` only below ``detectors/``: the run's own files are
        never written.
    name : str, optional
        The detector's name in the tables (default: its function name), a plain
        name (:func:`check_name`), never a path.

    Returns
    -------
    dict
        ``summary`` (DataFrame, one row per transition and design the signals
        came from, variant ``<name>@<design>``, ``reads_truth`` whether the
        detector read a truth column), ``trials`` (a run) or ``flights`` (an
        endurance run), ``out`` (the folder written) and ``columns`` (the
        signal columns the detector was passed).

    Raises
    ------
    UserError
        A bad name or output folder, a module that cannot be imported, a run
        folder, table, metadata or signals file that is missing, damaged or
        inconsistent, a run without signals, a detector that raises or
        returns anything but one valid alarm time (and block) per trial
        (module docstring).  Nothing is written then.
    """
    from ..config import parse_config
    if isinstance(detector, str):
        spec = detector
        if name is not None:
            check_name(name)
        detector = load_detector(spec)
        name = name or spec.partition(":")[2]
    if not callable(detector):
        raise UserError(f"detector: expected a function (signals, names, dt), got "
                        f"{type(detector).__name__}")
    name = check_name(name if name is not None else getattr(detector, "__name__", "detector"))
    wanted = _wanted_columns(detector)
    run_dir = Path(run_dir)
    meta = run_meta(run_dir)
    owner = holder(run_dir)
    if owner is not None:
        raise UserError(f"{run_dir}: being written by `{owner.get('command')}` (pid "
                        f"{owner.get('pid')}); score it when it has finished")
    endurance = meta.get("kind") == "endurance"
    table = run_dir / ("flights.parquet" if endurance else "trials.parquet")
    config = parse_config(meta["config"], f"{table} metadata")
    cfg = config.model_dump(mode="json")
    dt = float(config.model.dt_s)
    max_step = round(config.timing.duration_s / dt)
    folder = Path(out) if out is not None else run_dir / "detectors" / name
    _check_out(run_dir, folder, out is None)
    key = "flight_id" if endurance else "trial_id"
    flown_all = _flown(table, endurance)
    by = ["variant"] if endurance else ["transition", "variant"]
    flown_of = {k if isinstance(k, tuple) else (k,): g.set_index(key)
                for k, g in flown_all.groupby(by if len(by) > 1 else by[0], sort=False)}
    parts, names = [], ()
    for tr, design, ids, sig, names, last in _batches(run_dir, wanted, truth=False,
                                                      max_step=max_step):
        if endurance and tr != ENDURANCE_NAME or not endurance and tr not in TRANSITION_TABLE:
            raise UserError(f"{run_dir}: signals of {tr!r}, not "
                            + ("an endurance run's flights" if endurance
                               else "a transition (ftc-mc run --help)"))
        if not endurance and is_sensor(tr):
            continue
        where = f"{tr} trials {ids[0]}-{ids[-1]} of {design}"
        flown = flown_of.get((design,) if endurance else (tr, design))
        unknown = ids if flown is None else ids[~np.isin(ids, flown.index.to_numpy())]
        if len(unknown):
            raise UserError(f"{run_dir}: signals of {where} hold {key} {unknown[0]}, "
                            f"which {table.name} does not list")
        alarm, codes = call_detector(detector, sig, names, dt, where, last * dt)
        flown = flown.loc[ids].reset_index()
        if endurance:
            g = flown.copy()
            ok = np.isfinite(alarm) & (alarm <= g["flown_s"].to_numpy() + 1e-9)
            g["false_resets"] = ok.astype(np.int64)
            g["first_false_reset_s"] = np.where(ok, alarm, np.nan)
            g["alarm_s"] = alarm
        else:
            g = _trial_rows(flown, alarm, codes, cfg, tr)
        g["variant"] = f"{name}@{design}"
        g["design"] = design
        parts.append(g)
    reads_truth = any(c in TRUTH_COLUMNS for c in names)
    rows = pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()
    if endurance:
        summary = _endurance_summary(rows, config)
    else:
        variants = list(dict.fromkeys(rows["variant"])) if len(rows) else []
        transitions = list(dict.fromkeys(rows["transition"])) if len(rows) else []
        summary = summary_frame([summary_row(t, v, rows[(rows["transition"] == t)
                                                        & (rows["variant"] == v)])
                                 for t in transitions for v in variants
                                 if ((rows["transition"] == t) & (rows["variant"] == v)).any()],
                                transitions, variants)
    summary["reads_truth"] = reads_truth
    _write(folder, rows, summary, endurance,
           {**meta, "detector": name, "detector_columns": list(names),
            "reads_truth": reads_truth})
    return {"summary": summary, ("flights" if endurance else "trials"): rows,
            "out": folder, "columns": names}


TRUTH_NOTE = ("**Reads the truth** ({columns}): an oracle, not a detector an aircraft "
              "could fly.")
"""The line of ``summary.md`` above the table of a detector that read a truth
column (the report heads its rows *Oracle*: :func:`ftc_mc.report.runs.paper_tables`)."""


def _endurance_summary(flights: pd.DataFrame, config) -> pd.DataFrame:
    """The endurance summary of the detector's alarms, with the built-in designs'
    columns and definitions (:func:`ftc_mc.campaign.endurance.summarize_endurance`:
    rates per flight hour with exact Poisson intervals, the one-sided bound, the
    hours that would show the target); each alarm is a false reset.  Its
    condition (``plant``, ``turbulence``, ``airframe``) is the run's."""
    from .endurance import summarize_endurance
    ok = flights["false_resets"].to_numpy() > 0
    resets = pd.DataFrame({"variant": flights["variant"][ok], "flight_id":
                           flights["flight_id"][ok], "time_s": flights["alarm_s"][ok]})
    return summarize_endurance(flights, resets, config,
                               list(dict.fromkeys(flights["variant"])))


def _write(folder: Path, rows, summary, endurance: bool, meta: dict) -> None:
    """The detector's tables, each written atomically; a folder that cannot be
    written is a UserError."""
    from ..io.atomic import write_text
    from ..io.results import write_parquet
    from .summary import markdown_table
    if endurance:
        from .endurance import endurance_markdown
        md = endurance_markdown(summary)
    else:
        md = markdown_table(summary)
    if meta["reads_truth"]:
        truth = [c for c in meta["detector_columns"] if c in TRUTH_COLUMNS]
        md = TRUTH_NOTE.format(columns=", ".join(f"`{c}`" for c in truth)) + "\n\n" + md
    try:
        folder.mkdir(parents=True, exist_ok=True)
        write_parquet(rows, folder / ("flights.parquet" if endurance else "trials.parquet"),
                      meta)
        write_parquet(summary, folder / ("endurance.parquet" if endurance
                                         else "summary.parquet"), meta)
        write_text(folder / "summary.md", f"# detector {meta['detector']}\n\n{md}\n")
    except OSError as exc:
        raise UserError(f"{folder}: cannot write the detector's tables "
                        f"({_one_line(exc)})") from None


def _plain(df: pd.DataFrame) -> str:
    """A small table in Markdown without optional dependencies."""
    cols = list(df.columns)
    fmt = (lambda v: f"{v:.4g}" if isinstance(v, float) else str(v))
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in df.itertuples(index=False)]
    return "\n".join(lines)


def table1_blocks(r: np.ndarray, thresholds, table) -> np.ndarray:
    """Table 1 on residuals, in NumPy: the block each row resets.

    The same rule as the kernel (:func:`ftc_mc.core.longitudinal.signature.signature_lanes`):
    a hit pattern (bit ``i`` when channel ``i`` reaches its threshold), then the
    pattern's row ``(block_if, block_else, cmp_a, cmp_b)`` of the decision table.

    Parameters
    ----------
    r : ndarray, shape (..., n_channels)
        ``r_q, r_nx, r_nz`` (``conventions.RESIDUAL_NAMES`` order); NaN reaches no
        threshold.
    thresholds : array_like, shape (n_channels,)
        ``inf`` for a channel that is only compared (``r_nz``).
    table : array_like of int, shape (2 ** n_channels, 4)
        ``conventions.TABLE1[variant]``.

    Returns
    -------
    ndarray of int64, shape (...)
        ``NO_RESET``, ``RESET_THRUST`` or ``RESET_ELEVONS``.
    """
    r = np.asarray(r, dtype=float)
    table = np.asarray(table, dtype=np.int64)
    pattern = np.zeros(r.shape[:-1], dtype=np.int64)
    for i, t in enumerate(np.asarray(thresholds, dtype=float)):
        pattern |= (r[..., i] >= t).astype(np.int64) << i
    row = table[pattern]
    a = row[..., 2]
    ra = np.take_along_axis(r, np.maximum(a, 0)[..., None], axis=-1)[..., 0]
    rb = np.take_along_axis(r, np.maximum(row[..., 3], 0)[..., None], axis=-1)[..., 0]
    return np.where((a < 0) | (ra >= rb), row[..., 0], row[..., 1])


def table1_detector(variant: str = "paper", t_q: float | None = None,
                    t_nx: float | None = None):
    """The paper's Table 1 as a detector of recorded signals (open loop): its first
    alarm is the first step whose ``r_q, r_nx, r_nz`` Table 1 sends to a block,
    and it names that block.  Exactly the closed loop's first reset when the
    signals were flown by the same design and thresholds (a design without a
    start-up hold or settling rule: the paper's), which is the recording's test
    (``tests/test_detector.py``).

    Parameters
    ----------
    variant : {"paper", "swapped"}
        Table 1 as printed, or with its third clause swapped.
    t_q, t_nx : float, optional
        Thresholds (default: the paper's, ``estimator`` section defaults).
    """
    from ..config.schema import EstimatorConfig
    from ..conventions import TABLE1
    est = EstimatorConfig()
    th = {"r_q": est.t_q if t_q is None else t_q, "r_nx": est.t_nx if t_nx is None else t_nx}
    thresholds = np.array([th.get(c, np.inf) for c in LAY.residuals])
    table = np.array(TABLE1[variant])

    def table1(signals, names, dt):
        r = signals[..., [names.index(c) for c in LAY.residuals]]
        blocks = table1_blocks(r, thresholds, table)
        fired = blocks != NO_RESET
        first = np.argmax(fired, axis=1)
        any_ = fired.any(axis=1)
        alarm = np.where(any_, (first + 1) * dt, np.nan)
        block = np.where(any_, np.array(LAY.blocks, dtype=object)[
            blocks[np.arange(len(first)), first]], "")
        return alarm, block

    table1.columns = tuple(LAY.residuals)
    table1.__name__ = f"table1_{variant}"
    return table1


def side_monitor_decisions(d: np.ndarray, window: int, min_window: int, thresholds,
                           startup: int) -> np.ndarray:
    """The 6-DOF side monitor's decisions re-run on its recorded projections.

    The same test as the kernel (:func:`ftc_mc.core.sixdof.monitor.monitor_decide`
    with :func:`ftc_mc.core.shared.glr.glr_lanes`), in NumPy and in the kernel's
    order of sums, so that it decides bit for bit as the closed loop did: each
    step appends the projections to a window of the last ``window`` steps; each
    direction's statistic is ``max_m (sum of its newest m) ** 2 / m`` over
    ``min_window <= m <=`` the window's length; of the directions whose
    statistic passes its threshold, the one passing it by the largest factor
    is decided (the first of equal ones), and the window restarts.  Until the
    step ``startup`` the window stays empty.

    Parameters
    ----------
    d : ndarray, shape (trials, steps, 3)
        ``side_d_*`` of the signals (row ``j``: step ``j + 1``); NaN after a
        trial stopped (no decision there).
    window, min_window, startup : int
        The monitor's GLR window, shortest change and start-up [steps]
        (``monitor`` section).
    thresholds : float or array_like, shape (3,)
        The design's monitor threshold of each direction (one: all alike).

    Returns
    -------
    ndarray of int64, shape (trials, steps)
        0: no decision; else the direction's index plus one (throttle, left,
        right elevon: ``layout.MONITOR_DIRECTIONS``).
    """
    d = np.asarray(d, dtype=np.float64)
    n, steps, nd = d.shape
    thr = np.broadcast_to(np.asarray(thresholds, dtype=np.float64), (nd,))
    buf = np.zeros((n, window, nd))  # newest first
    count = np.zeros(n, dtype=np.int64)
    m = np.arange(1, window + 1, dtype=np.float64)
    out = np.zeros((n, steps), dtype=np.int64)
    for j in range(steps):
        if j + 1 <= startup:
            count[:] = 0
            continue
        buf = np.concatenate([d[:, j][:, None, :], buf[:, :-1]], axis=1)
        count = np.minimum(count + 1, window)
        acc = np.cumsum(buf, axis=1)  # sequential: the kernel's sums
        g = acc * acc / m[None, :, None]
        valid = (m[None, :] <= count[:, None]) & (m[None, :] >= min_window)
        stat = np.where(valid[..., None], g, 0.0).max(axis=1)  # (n, nd)
        passing = stat > thr
        factor = np.where(passing, stat / thr, 0.0)
        best = np.argmax(factor, axis=1)  # the first of equal ones, as the kernel
        hit = passing.any(axis=1)
        out[hit, j] = best[hit] + 1
        count[hit] = 0
    return out


def side_monitor_detector(threshold: float | None = None,
                          throttle_threshold: float | None = None):
    """The 6-DOF side monitor as a detector of recorded signals (open loop): its
    first decision, naming the actuator (``engine``, ``left_elevon``,
    ``right_elevon``), from the projections recorded on the 6-DOF plant
    (``side_d_*``) with the ``monitor`` section's defaults
    (:func:`side_monitor_decisions`).  On signals flown with those settings it
    decides at every step as the closed loop's monitor did, which is the
    6-DOF recording's test (``tests/test_detector.py``).

    Parameters
    ----------
    threshold : float, optional
        The GLR threshold (default: ``monitor.threshold``'s default).
    throttle_threshold : float, optional
        The throttle direction's (default: ``threshold``).
    """
    from ..config.schema import MonitorConfig
    from .signals import monitor_columns
    mc = MonitorConfig()
    one = mc.threshold if threshold is None else float(threshold)
    thr = np.array([one if throttle_threshold is None or c != "throttle"
                    else float(throttle_threshold) for c in LAY.inputs])

    def side_monitor(signals, names, dt):
        steps = lambda s: int(round(s / dt))  # noqa: E731
        dec = side_monitor_decisions(signals[..., [names.index(c) for c in columns]],
                                     steps(mc.window_s), steps(mc.min_window_s), thr,
                                     steps(mc.startup_s))
        fired = dec != 0
        first = np.argmax(fired, axis=1)
        any_ = fired.any(axis=1)
        alarm = np.where(any_, (first + 1) * dt, np.nan)
        named = dec[np.arange(len(first)), first]
        block = np.where(any_, np.array(("",) + LAY.actuators, dtype=object)[named], "")
        return alarm, block

    columns = monitor_columns()
    side_monitor.columns = columns
    side_monitor.__name__ = "side_monitor"
    return side_monitor
