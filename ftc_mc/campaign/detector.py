"""Score a user's detector on a run's recorded signals, by the built-in designs' rules.

A *detector* is a plain NumPy function::

    def detector(signals, names, dt):
        # signals: float ndarray (trials, steps, len(names)), NaN after a trial stopped
        # names:   tuple of str, the signal columns (docs/reference/outputs.md)
        # dt:      the sampling period [s]
        return alarm_s                    # (trials,) first alarm time [s], NaN: none
        # or: return alarm_s, block       # block: (trials,) "thrust" / "elevons",
        #                                 # an actuator name, or "" where unnamed

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
"""

from __future__ import annotations

import importlib
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from ..conventions import LONGITUDINAL as LAY
from ..conventions import MODE_NAMES, MODE_NOMINAL, NO_RESET
from ..errors import UserError
from ..io.results import META_KEY
from .signals import KEYS, TRUTH_COLUMNS, signal_files
from .summary import summary_frame, summary_row
from .transitions import TRANSITION_TABLE, is_sensor

ENDURANCE_NAME = "endurance"
"""The chunk (and ``transition``) name of an endurance run's flights."""


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
    except Exception as exc:  # noqa: BLE001 -- any import failure is the user's
        raise UserError(f"--detector: cannot import {mod!r}: {type(exc).__name__}: "
                        f"{exc}") from None
    func = getattr(module, fn, None)
    if not callable(func):
        raise UserError(f"--detector: {mod!r} has no function {fn!r}")
    return func


def run_meta(run_dir) -> dict:
    """The provenance of a run or endurance directory (its config included)."""
    d = Path(run_dir)
    for name in ("trials.parquet", "flights.parquet"):
        if (d / name).exists():
            md = pq.read_schema(d / name).metadata or {}
            if META_KEY in md:
                return json.loads(md[META_KEY])
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
    """
    files = signal_files(run_dir)
    if not files:
        raise UserError(f"{run_dir}: recorded without signals (run it with "
                        "--record signals)")
    group, group_name, values = [], None, 0
    for f in files:
        have = pq.read_schema(f).names
        names = tuple(c for c in have if c not in KEYS
                      and (truth or c not in TRUTH_COLUMNS)) if columns is None \
            else tuple(columns)
        missing = [c for c in names if c not in have]
        if missing:
            raise UserError(f"{f}: no signal columns {missing}")
        table = pq.read_table(f, columns=[*KEYS, *names])
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


def _split(table, name: str, names):
    """The batches of one joined table, one per design (:func:`batches`)."""
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
                v = col.to_numpy()
            out[lane, step - 1, j] = v
        yield name, design, uid, out, names


def _check_output(res, n: int, where: str):
    """The alarm times, and the block codes and actuator names of a detector's
    return, or a UserError."""
    block = None
    if isinstance(res, tuple):
        if len(res) != 2:
            raise UserError(f"detector: {where}: expected alarm_s or (alarm_s, block), "
                            f"got a tuple of {len(res)}")
        res, block = res
    try:
        alarm = np.asarray(res, dtype=float)
    except (TypeError, ValueError):
        raise UserError(f"detector: {where}: alarm times are not numbers") from None
    if alarm.shape != (n,):
        raise UserError(f"detector: {where}: expected {n} alarm times (one per trial), "
                        f"got shape {alarm.shape}")
    if np.isinf(alarm).any():
        raise UserError(f"detector: {where}: alarm times must be finite or NaN (none)")
    codes = np.full(n, -1, dtype=np.int64)  # -1: no block named
    sides = np.full(n, "", dtype=object)  # the actuator named, if one was
    if block is not None:
        block = np.asarray(block, dtype=object)
        if block.shape != (n,):
            raise UserError(f"detector: {where}: expected {n} blocks, got shape "
                            f"{block.shape}")
        for i, b in enumerate(block):
            codes[i] = _block_code(b, where)
            if isinstance(b, str) and b in LAY.actuators:
                sides[i] = b
    return alarm, (codes, sides)


def _block_code(b, where: str) -> int:
    if b is None or b == "" or (isinstance(b, float) and math.isnan(b)):
        return -1
    if isinstance(b, (int, np.integer)):
        if 0 <= b < len(LAY.blocks):
            return int(b)
    elif b in LAY.blocks:
        return LAY.blocks.index(b)
    elif b in LAY.actuators:
        return LAY.actuator_block[LAY.actuators.index(b)]
    raise UserError(f"detector: {where}: block {b!r} is none of {LAY.blocks[1:]} "
                    f"or {LAY.actuators}")


def call_detector(detector, signals, names, dt: float, where: str):
    """Call ``detector`` on one batch; its failure or bad output is a UserError."""
    try:
        res = detector(signals, names, dt)
    except Exception as exc:  # noqa: BLE001 -- the user's code
        raise UserError(f"detector raised {type(exc).__name__} on {where}: {exc}") from None
    return _check_output(res, signals.shape[0], where)


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
        ``endurance.parquet`` (an endurance run) of the detector, and
        ``summary.md``; default ``run_dir/detectors/<name>/``.  The run's own
        files are never written.
    name : str, optional
        The detector's name in the tables (default: its function name).

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
        A module that cannot be imported, a run without signals, a detector
        that raises or returns the wrong shape or infinite alarm times.
        Nothing is written then.
    """
    if isinstance(detector, str):
        spec = detector
        detector = load_detector(spec)
        name = name or spec.partition(":")[2]
    name = name or getattr(detector, "__name__", "detector")
    run_dir = Path(run_dir)
    meta = run_meta(run_dir)
    cfg = meta["config"]
    dt = float(cfg["model"]["dt_s"])
    endurance = meta.get("kind") == "endurance"
    table = run_dir / ("flights.parquet" if endurance else "trials.parquet")
    key = "flight_id" if endurance else "trial_id"
    flown_all = pd.read_parquet(table)
    by = ["variant"] if endurance else ["transition", "variant"]
    flown_of = {k if isinstance(k, tuple) else (k,): g.set_index(key)
                for k, g in flown_all.groupby(by if len(by) > 1 else by[0], sort=False)}
    parts, names = [], ()
    for tr, design, ids, sig, names in batches(run_dir, getattr(detector, "columns", None),
                                               truth=False):
        if not endurance and is_sensor(tr):
            continue
        where = f"{tr} trials {ids[0]}-{ids[-1]} of {design}"
        alarm, codes = call_detector(detector, sig, names, dt, where)
        flown = flown_of[(design,) if endurance else (tr, design)].loc[ids].reset_index()
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
        summary = _endurance_summary(rows, cfg)
    else:
        variants = list(dict.fromkeys(rows["variant"])) if len(rows) else []
        transitions = list(dict.fromkeys(rows["transition"])) if len(rows) else []
        summary = summary_frame([summary_row(t, v, rows[(rows["transition"] == t)
                                                        & (rows["variant"] == v)])
                                 for t in transitions for v in variants
                                 if ((rows["transition"] == t) & (rows["variant"] == v)).any()],
                                transitions, variants)
    summary["reads_truth"] = reads_truth
    folder = Path(out) if out is not None else run_dir / "detectors" / name
    _write(folder, rows, summary, endurance,
           {**meta, "detector": name, "detector_columns": list(names),
            "reads_truth": reads_truth})
    return {"summary": summary, ("flights" if endurance else "trials"): rows,
            "out": folder, "columns": names}


TRUTH_NOTE = ("**Reads the truth** ({columns}): an oracle, not a detector an aircraft "
              "could fly.")
"""The line of ``summary.md`` (and the report) above a detector that read a
truth column."""


def _endurance_summary(flights: pd.DataFrame, cfg: dict) -> pd.DataFrame:
    """The endurance summary of the detector's alarms, with the built-in designs'
    columns and definitions (:func:`ftc_mc.campaign.endurance.summarize_endurance`:
    rates per flight hour with exact Poisson intervals, the one-sided bound, the
    hours that would show the target); each alarm is a false reset."""
    from ..config import parse_config
    from .endurance import summarize_endurance
    ok = flights["false_resets"].to_numpy() > 0
    resets = pd.DataFrame({"variant": flights["variant"][ok], "flight_id":
                           flights["flight_id"][ok], "time_s": flights["alarm_s"][ok]})
    return summarize_endurance(flights, resets, parse_config(cfg),
                               list(dict.fromkeys(flights["variant"])))


def _write(folder: Path, rows, summary, endurance: bool, meta: dict) -> None:
    """The detector's tables, each written atomically."""
    from ..io.atomic import write_text
    from ..io.results import write_parquet
    from .summary import markdown_table
    folder.mkdir(parents=True, exist_ok=True)
    write_parquet(rows, folder / ("flights.parquet" if endurance else "trials.parquet"), meta)
    write_parquet(summary, folder / ("endurance.parquet" if endurance else "summary.parquet"),
                  meta)
    if endurance:
        from .endurance import endurance_markdown
        md = endurance_markdown(summary)
    else:
        md = markdown_table(summary)
    if meta["reads_truth"]:
        truth = [c for c in meta["detector_columns"] if c in TRUTH_COLUMNS]
        md = TRUTH_NOTE.format(columns=", ".join(f"`{c}`" for c in truth)) + "\n\n" + md
    write_text(folder / "summary.md", f"# detector {meta['detector']}\n\n{md}\n")


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
