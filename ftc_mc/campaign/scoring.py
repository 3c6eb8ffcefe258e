"""Metrics comparable with published real-flight fault-detection results.

Beside Tables 2-3, each (transition, design) row of a campaign is scored the way
real-flight studies score a detector, so a reader can set our figures beside
theirs.  An *alarm* is a covariance-block reset (the scheme's detection output,
Table 1); the *fault* is the row's switch at ``timing.fault_time_s`` (for unlock
and recover rows the switch is the recovery).

**ALFA scoring** (Keipour, Mousaei and Scherer, "ALFA: A dataset for UAV fault and
anomaly detection", IJRR 2021, and "Automatic real-time anomaly detection for
autonomous aerial vehicles", ICRA 2019; the evaluator of
``castacks/alfa-dataset-tools``, ``alfa-evaluate``, with its 5 s timeout), per
judged trial:

* a **false positive**: an alarm before the fault while the truth is nominal
  (``false_resets > 0``: the unlock and recover rows, which fly faulted before
  the switch, have none);
* a **detection** (true positive): an alarm of the correct block within
  :data:`ALFA_TIMEOUT_S` after the fault, with its delay ``correct_reset_s``
  (at most the judging window);
* otherwise a **miss** (false negative).

A trial can be both a false positive and a detection, as the ALFA evaluator
scores every alarm.  ``alfa_precision`` = TP / (TP + FP), ``alfa_recall`` =
TP / (TP + FN) = TP / judged trials; ``alfa_delay_mean_s`` / ``_max_s`` over the
detections.

**FDDBenchmark's names** (the metrics of fault-detection-and-diagnosis
benchmarks; our definitions): ``add_s``, the *average detection delay*: the mean
delay from the fault to the first alarm of any block in the judging window
over the trials with one (missed trials excluded); ``cdr``, the *correct
diagnosis rate*: the share of judged trials whose first alarm after the fault,
in the judging window, names the correct block.

Keipour et al. 2019 report, on 22 real flights of a Carbon Z T-28 with engine,
aileron, rudder and elevator failures: precision and recall 88.23 %, mean
detection delay 2.02 s, maximum 5.6 s (:data:`KEIPOUR_2019`).  The aircraft,
the faults and the detector differ from ours: these are context, not a target.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..conventions import BLOCK_NAMES
from .transitions import TRANSITION_TABLE

ALFA_TIMEOUT_S = 5.0
"""A correct alarm at most this long after the fault is a detection (ALFA evaluator) [s]."""

KEIPOUR_2019 = {"flights": 22, "aircraft": "Carbon Z T-28",
                "faults": "engine, aileron, rudder and elevator failures",
                "precision": 0.8823, "recall": 0.8823, "delay_mean_s": 2.02,
                "delay_max_s": 5.6}
"""Real-flight figures of Keipour, Mousaei and Scherer, ICRA 2019 (ALFA dataset)."""

COLUMNS = ("alfa_tp", "alfa_fp", "alfa_fn", "alfa_precision", "alfa_recall",
           "alfa_delay_mean_s", "alfa_delay_max_s", "add_s", "cdr")
"""Columns :func:`real_flight_scores` adds to a summary row."""


def real_flight_scores(name: str, ok: pd.DataFrame) -> dict:
    """ALFA and FDDBenchmark metrics of the judged trials ``ok`` of transition ``name``.

    Parameters
    ----------
    name : str
        An actuator transition.
    ok : DataFrame
        Its judged trials of one design (``trials.parquet`` columns
        ``false_resets``, ``correct_reset_s``, ``first_reset_s``,
        ``first_reset_block``).

    Returns
    -------
    dict
        :data:`COLUMNS` (rates in [0, 1], delays [s]; NaN without trials or
        without detections, and ``cdr`` NaN for a table without
        ``first_reset_block``).
    """
    n = len(ok)
    correct = BLOCK_NAMES[TRANSITION_TABLE[name].correct_block]
    fp = int((ok["false_resets"].to_numpy() > 0).sum())
    delay = (ok["correct_reset_s"].to_numpy(dtype=float) if "correct_reset_s" in ok
             else np.full(n, np.nan))
    hit = np.isfinite(delay) & (delay <= ALFA_TIMEOUT_S + 1e-9)
    tp = int(hit.sum())
    first = ok["first_reset_s"].to_numpy(dtype=float)
    detected = np.isfinite(first)
    return {
        "alfa_tp": tp, "alfa_fp": fp, "alfa_fn": n - tp,
        "alfa_precision": tp / (tp + fp) if tp + fp else np.nan,
        "alfa_recall": tp / n if n else np.nan,
        "alfa_delay_mean_s": float(delay[hit].mean()) if tp else np.nan,
        "alfa_delay_max_s": float(delay[hit].max()) if tp else np.nan,
        "add_s": float(first[detected].mean()) if detected.any() else np.nan,
        "cdr": (float((ok["first_reset_block"].to_numpy() == correct).mean())
                if n and "first_reset_block" in ok else np.nan),
    }
