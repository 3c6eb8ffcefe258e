"""The misattribution table of runs with sensor transitions (issue 14).

A sensor fault leaves the actuators healthy, so every action of the actuator
FDI after it is a misattribution: a covariance-block reset, the belief's most
probable mode an actuator fault (with at least 0.5), a controller switch.  The
table gives each as ``k/n (rate %, 95 % Wilson CI)`` over the judged trials
(:func:`ftc_mc.campaign.summary.sensor_row`), with the median time from the
fault to the first action and the share of trials that left the envelope.
"""

from __future__ import annotations

import pandas as pd

from ..campaign.transitions import is_sensor
from .markdown import count, num

COLUMNS = (("actuator_reset", "actuator-block reset"), ("wrong_mode", "wrong mode (>= 0.5)"),
           ("controller_switch", "controller switch"), ("misattributed", "any of them"),
           ("envelope_exit", "left the envelope"))
"""Summary counts shown, and their headings."""


def sensor_rows(summary: pd.DataFrame) -> pd.DataFrame:
    """The summary rows of sensor transitions (none: an empty frame)."""
    if "transition" not in summary or not len(summary):
        return summary.iloc[0:0]
    return summary[summary["transition"].map(is_sensor)]


def misattribution_table(summary: pd.DataFrame) -> list:
    """Markdown lines of the misattribution table; empty without sensor rows.

    Parameters
    ----------
    summary : DataFrame
        ``summary.parquet`` of a run.

    Returns
    -------
    list of str
    """
    rows = sensor_rows(summary)
    if not len(rows):
        return []
    out = []
    for _, r in rows.iterrows():
        n = int(r["trials"])
        row = {"sensor fault": f"`{r['transition']}`", "signature": r["variant"],
               "judged": n}
        for key, head in COLUMNS:
            row[head] = count(int(r[key]), n)
        row["first action median / p95 [s]"] = (f"{num(r['first_action_median_s'])} / "
                                                f"{num(r['first_action_p95_s'])}")
        out.append(row)
    return ["### Sensor faults: what the actuator FDI does with them", "",
            pd.DataFrame(out).to_markdown(index=False), "",
            "The actuators stay healthy, so the correct block is `none`: any reset after "
            "the sensor fault, an actuator mode most probable (>= 0.5) or a controller "
            "switch is a misattribution. Counts are `k/n (rate %, 95 % Wilson CI)` over "
            "judged trials (no numerical failure); leaving the envelope is an outcome "
            "here, not an exclusion. Times are from the sensor fault to the first action "
            "of any kind, over the trials with one.", ""]


def has_sensor_rows(summary: pd.DataFrame) -> bool:
    return bool(len(sensor_rows(summary)))


def actuator_part(summary: pd.DataFrame, trials: pd.DataFrame):
    """``(summary, trials)`` of the actuator transitions only, sensor columns dropped."""
    from ..campaign.summary import actuator_rows
    if "transition" not in trials:
        return summary, trials
    t = trials[~trials["transition"].map(is_sensor)]
    sensor_cols = [c for c in ("sensor_output", "sensor_kind", "sensor_size", "actuator_reset",
                               "actuator_reset_s", "wrong_mode", "wrong_mode_s",
                               "controller_switch", "controller_switch_s", "first_action_s",
                               "envelope_exit") if c in t]
    t = t.drop(columns=sensor_cols)
    for c in ("correct", "inappropriate", "no_reset", "mode_changed", "detected", "small_b1",
              "lock_near_trim", "resets_truncated", "judged"):
        if c in t and t[c].dtype == object:
            t = t.astype({c: bool})
    return actuator_rows(summary), t

