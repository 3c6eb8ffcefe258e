"""Which actuator failed, by the 6-DOF side monitor.

On the 6-DOF plant a side monitor flies beside every design
(:mod:`ftc_mc.core.sixdof.monitor`): an augmented filter of the 6-DOF model
and a windowed GLR per actuator, reading roll as well as pitch.  Its trial
columns (:func:`side_columns`), with ``k_f`` the switch step and the window the
steps ``k_f <= k <= k_f + window`` (the monitor's decision at step ``k``
follows the measurement of ``k``):

* ``side_block``: the actuator of its first decision at or after the switch
  (``throttle``, ``left``, ``right``), ``none`` without one;
* ``side_s``: that decision's delay from the switch [s] (NaN: none);
* ``side_correct``: for a trial of a fault row (the transition's actuator
  changes) still flying at the switch and with no numerical failure, 1.0 when
  that first decision came within the window and names the faulty actuator,
  0.0 otherwise (another actuator, or none in the window: a trial that leaves
  the envelope before a decision is a miss); NaN for other trials.  Unlike the
  scheme's rates it keeps the trials that leave the envelope within the
  window, most of the 6-DOF elevon locks;
* ``side_false``: its decisions before the switch in a row whose truth is
  fault-free before it (an onset from nominal, a sensor fault): false alarms;
  0 in unlock and recover rows, which start faulted (a loss too small for the
  belief's nominal box is still a fault the monitor may name);
* ``side_b0``, ``side_b1``, ``side_position``: its estimate of the transition
  actuator's ``b0``, ``b1`` and position ``b0 + (1 - b1)(u + u0)`` [throttle
  fraction, rad; absolute] ``monitor.estimate_after_s`` after that decision
  (or at the last step flown, if earlier or without a decision).

Per row and design (:func:`side_table`): ``side_correct_rate`` with its 95 %
Wilson interval over those trials, the median delay of the
correct decisions, ``side_wrong_rate`` (the first decision in the window named
another actuator), the correct rate over the losses of at least
:data:`LARGE_LOSS` (``side_correct_rate_large``), the false decisions and the
hours of fault-free flight before the switch, and for lock rows the median
error of ``side_position`` against the lock position.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..conventions import ACTUATOR_NAMES, STATUS_NONFINITE, STATUS_NOT_PSD
from ..stats import finite_median, wilson
from .transitions import TRANSITION_TABLE

DIRECTIONS = ("none", "throttle", "left", "right")
"""``TrialRecord.side_block`` codes by name (``core/sixdof/layout.MONITOR_DIRECTIONS``
after ``none``), in the order of the longitudinal actuators
(:data:`~ftc_mc.conventions.ACTUATOR_NAMES`)."""

assert len(DIRECTIONS) == len(ACTUATOR_NAMES) + 1

LARGE_LOSS = 0.5
"""``b1`` from which a loss counts as large (``b1 >= 0.5``): the losses the side
monitor is asked to name (``side_correct_rate_large``)."""

SIDE_COLUMNS = ("side_block", "side_s", "side_correct", "side_false", "side_b0", "side_b1",
                "side_position")
"""The trial columns of :func:`side_columns`."""


def side_columns(rec, actuator: int | None, starts_nominal, kf: int, window: int,
                 dt: float) -> dict:
    """The side monitor's trial columns (module docstring) of one kernel call.

    Parameters
    ----------
    rec : TrialRecord
        The monitor's ``side_k``, ``side_block``, ``side_pre``, ``mon_b``, and
        ``status``, ``stop_k`` (which trials are flying at the switch).
    actuator : int or None
        The transition's actuator (index into ``ACTUATOR_NAMES``); None for a
        sensor fault (``side_correct`` and the estimates NaN).
    starts_nominal : bool
        The row's truth is fault-free before the switch (its decisions there
        are false alarms).
    kf, window : int
        Switch step and window [steps].
    dt : float
        Step [s].
    """
    k = rec.side_k
    numeric = (rec.status == STATUS_NONFINITE) | (rec.status == STATUS_NOT_PSD)
    judged = ~numeric & ((rec.stop_k < 0) | (rec.stop_k > kf))
    blk = rec.side_block
    decided = k >= 0
    in_win = decided & (k <= kf + window)
    nu = len(ACTUATOR_NAMES)
    L = len(k)
    if actuator is None:
        correct = b0 = b1 = pos = np.full(L, np.nan)
    else:
        correct = np.where(judged, (in_win & (blk == actuator + 1)).astype(float), np.nan)
        b0, b1, pos = (rec.mon_b[i * nu + actuator].copy() for i in range(3))
    return {
        "side_block": np.array([DIRECTIONS[b] for b in blk], dtype=object),
        "side_s": np.where(decided, (k - kf) * dt, np.nan),
        "side_correct": correct,
        "side_false": np.where(starts_nominal, rec.side_pre, 0).astype(np.int64),
        "side_b0": b0,
        "side_b1": b1,
        "side_position": pos,
    }


def side_table(trials: pd.DataFrame, fault_time_s: float, window_s: float) -> pd.DataFrame:
    """Per transition and design, how well the side monitor named the actuator
    (module docstring); empty when the trials have no monitor columns.

    Parameters
    ----------
    trials : DataFrame
        A run's trials (``transition``, ``variant``, the
        :data:`SIDE_COLUMNS`, ``lock_position``, ``loss_b1``, ``stop_s``).
    fault_time_s, window_s : float
        The switch time and the judging window [s].
    """
    if "side_correct" not in trials:
        return pd.DataFrame()
    rows = []
    for (tr_name, variant), g in trials.groupby(["transition", "variant"], sort=False):
        tr = TRANSITION_TABLE.get(tr_name)
        if tr is None:  # a sensor fault: no actuator to name
            continue
        judged = g[np.isfinite(g["side_correct"].to_numpy(float))]
        n = len(judged)
        k = int(judged["side_correct"].sum())
        lo, hi = wilson(k, n) if n else (np.nan, np.nan)
        ok = judged["side_correct"] == 1.0
        first_in = judged["side_s"].to_numpy(float) <= window_s
        wrong = (~ok) & first_in & (judged["side_block"] != "none")
        stop = g["stop_s"].to_numpy(float)
        flown_pre = np.where(np.isfinite(stop), np.minimum(stop, fault_time_s), fault_time_s)
        hours = float(flown_pre.sum()) / 3600.0 if tr.onset else 0.0
        row = {"transition": tr_name, "variant": variant, "side_trials": n,
               "side_correct": k, "side_correct_rate": k / n if n else np.nan,
               "side_ci_low": lo, "side_ci_high": hi,
               "side_s_median": finite_median(judged.loc[ok, "side_s"]),
               "side_wrong_rate": float(wrong.sum()) / n if n else np.nan,
               "side_false": int(g["side_false"].sum()), "side_false_hours": hours,
               "side_correct_rate_large": np.nan, "side_b0_err_median": np.nan}
        if tr.kind == "loss":
            big = judged["loss_b1"].to_numpy(float) >= LARGE_LOSS
            if big.any():
                row["side_correct_rate_large"] = float(ok[big].mean())
        if tr.kind == "lock" and tr.onset:
            err = (judged["side_position"] - judged["lock_position"]).abs()
            row["side_b0_err_median"] = finite_median(err)
        rows.append(row)
    return pd.DataFrame(rows)


def side_markdown(table: pd.DataFrame, level: int = 2) -> str:
    """:func:`side_table` as a Markdown section with a heading of ``level``
    (``""`` for an empty table)."""
    if table.empty:
        return ""
    head = "#" * level
    lines = [f"{head} Which actuator failed: the 6-DOF side monitor", "",
             "First decision of the side monitor (augmented 6-DOF filter, one windowed "
             "GLR per actuator, roll and pitch) in the window after the switch, over "
             "the trials flying at the switch; false decisions before it in the rows "
             "that start fault-free (docs/findings/sixdof-side-monitor.md, \"Which elevon failed: the side "
             "monitor\").", "",
             "| transition | design | correct actuator | b1 >= 0.5 | median delay | "
             "wrong actuator | false decisions (fault-free hours) | median lock error |",
             "|---|---|---|---|---|---|---|---|"]
    for r in table.itertuples():
        if r.side_trials:
            rate = (f"{r.side_correct}/{r.side_trials} ({100 * r.side_correct_rate:.1f} %, "
                    f"{100 * r.side_ci_low:.1f}-{100 * r.side_ci_high:.1f})")
            wrong = f"{100 * r.side_wrong_rate:.1f} %"
        else:
            rate = wrong = "-"
        delay = "-" if not np.isfinite(r.side_s_median) else f"{r.side_s_median:.1f} s"
        err = ("-" if not np.isfinite(r.side_b0_err_median)
               else f"{np.degrees(r.side_b0_err_median):.2f} deg")
        large = ("-" if not np.isfinite(r.side_correct_rate_large)
                 else f"{100 * r.side_correct_rate_large:.1f} %")
        lines.append(f"| {r.transition} | {r.variant} | {rate} | {large} | {delay} | {wrong} | "
                     f"{r.side_false} ({r.side_false_hours:.2f} h) | {err} |")
    return "\n".join(lines)
