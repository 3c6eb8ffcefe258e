"""The report's "metrics comparable with real-flight studies" of a run.

Per design and transition row, from ``trials.parquet`` (so older runs are scored
too): ALFA precision, recall and detection delays, and FDDBenchmark's average
detection delay and correct diagnosis rate (:mod:`ftc_mc.campaign.scoring`),
with Keipour et al. 2019's real-flight figures as context.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..campaign.scoring import ALFA_TIMEOUT_S, KEIPOUR_2019, real_flight_scores
from ..campaign.transitions import TRANSITION_TABLE


def real_flight_table(trials: pd.DataFrame) -> pd.DataFrame:
    """One row per design and actuator transition: the :mod:`~ftc_mc.campaign.scoring`
    metrics over the judged trials."""
    rows = []
    for (name, variant), g in trials.groupby(["transition", "variant"], sort=False):
        if name not in TRANSITION_TABLE:
            continue
        ok = g[g["judged"].astype(bool)]
        rows.append({"variant": variant, "transition": name, "judged": len(ok),
                     **real_flight_scores(name, ok)})
    return pd.DataFrame(rows)


def real_flight_lines(trials: pd.DataFrame) -> list:
    """Markdown lines: the metrics per design and row, and Keipour et al. 2019."""
    t = real_flight_table(trials)
    if not len(t):
        return []

    def pct(x):
        return "-" if not np.isfinite(x) else f"{100 * x:.1f}"

    def sec(x):
        return "-" if not np.isfinite(x) else f"{x:.2f}"

    k = KEIPOUR_2019
    lines = ["### Metrics comparable with real-flight studies", "",
             "An alarm is a covariance-block reset. ALFA scoring (Keipour et al., the "
             "evaluator of `castacks/alfa-dataset-tools`): a reset before the fault while "
             "the truth is nominal is a false positive (FP); a reset of the correct block "
             f"within {ALFA_TIMEOUT_S:g} s after the fault is a detection (TP) with its "
             "delay; otherwise a miss (FN); precision TP / (TP + FP), recall TP / (TP + FN). "
             "FDDBenchmark's names: average detection delay (ADD, to the first reset of any "
             "block in the judging window, missed trials excluded) and correct diagnosis "
             "rate (CDR, the first reset after the fault names the correct block). "
             "Definitions: docs/guides/compare-designs.md, *Metrics comparable with "
             "real-flight studies*.", "",
             f"For context only: on {k['flights']} real flights of a {k['aircraft']} "
             f"({k['faults']}) Keipour, Mousaei and Scherer (ICRA 2019) report precision "
             f"and recall {100 * k['precision']:.2f} %, mean detection delay "
             f"{k['delay_mean_s']:.2f} s and maximum {k['delay_max_s']:.1f} s. **The aircraft, "
             "the faults, the sensors and the detector differ from ours** (a simulated X8 "
             "flying wing, single locks and effectiveness losses of the engine or one "
             "elevon), so these figures are not a target and the comparison is not like "
             "for like.", ""]
    for variant, g in t.groupby("variant", sort=False):
        view = pd.DataFrame({
            "transition": g["transition"], "judged": g["judged"],
            "TP / FP / FN": [f"{a} / {b} / {c}" for a, b, c in
                             zip(g["alfa_tp"], g["alfa_fp"], g["alfa_fn"])],
            "precision %": g["alfa_precision"].map(pct),
            "recall %": g["alfa_recall"].map(pct),
            "delay mean / max [s]": [f"{sec(a)} / {sec(b)}" for a, b in
                                     zip(g["alfa_delay_mean_s"], g["alfa_delay_max_s"])],
            "ADD [s]": g["add_s"].map(sec), "CDR %": g["cdr"].map(pct)})
        lines += [f"Design `{variant}`:", "", view.to_markdown(index=False), ""]
    return lines
