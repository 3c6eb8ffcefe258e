"""The misattribution table of runs with sensor transitions.

A sensor fault leaves the actuators healthy, so every action of the actuator
FDI after it is a misattribution: a covariance-block reset, the belief's most
probable mode an actuator fault (with at least 0.5), a controller switch.  The
table gives each as ``k/n (rate %, 95 % Wilson CI)`` over the judged trials
(:func:`ftc_mc.campaign.summary.sensor_row`), with the median time from the
fault to the first action and the share of trials that left the envelope.
"""

from __future__ import annotations

import numpy as np
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


def misattribution_table(summary: pd.DataFrame, trials: pd.DataFrame | None = None) -> list:
    """Markdown lines of the misattribution table; empty without sensor rows.
    With a design that estimates sensor biases, its isolation rates follow
    (:func:`isolation_table`, by fault size when ``trials`` is given).

    Parameters
    ----------
    summary : DataFrame
        ``summary.parquet`` of a run.
    trials : DataFrame, optional
        ``trials.parquet`` of the run.

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
    return _section(
        "Sensor faults: what the actuator FDI does with them", out,
        "The actuators stay healthy, so the correct block is `none`: any reset after "
        "the sensor fault, an actuator mode most probable (>= 0.5) or a controller "
        "switch is a misattribution. Counts are `k/n (rate %, 95 % Wilson CI)` over "
        "judged trials (no numerical failure); leaving the envelope is an outcome "
        "here, not an exclusion. Times are from the sensor fault to the first action "
        "of any kind, over the trials with one.") + isolation_table(rows, trials)


def _section(title: str, rows: list, note: str) -> list:
    """Markdown lines of a report section: heading, the table of ``rows`` (dicts),
    the note under it."""
    return [f"### {title}", "", pd.DataFrame(rows).to_markdown(index=False), "", note, ""]


SIZE_BINS = 4
"""Bins of equal width over the drawn |bias| of the isolation table."""


def isolation_table(rows: pd.DataFrame, trials: pd.DataFrame | None) -> list:
    """Markdown lines of the isolation rates of the sensor-aware designs.

    A bias fault is isolated when the trial flew to the end, the design's
    estimate of the bias is within 25 % of the true one, and the belief's most
    probable mode at the end is nominal
    (:func:`ftc_mc.campaign.chunk.classify_sensor`).  One row per bias
    transition and design that estimates it: all judged trials, then the drawn
    |bias| in :data:`SIZE_BINS` bins of equal width.  Empty without such rows.
    """
    if "isolated_rate" not in rows:
        return []
    rows = rows[rows["isolated_rate"].notna()]
    if not len(rows):
        return []
    out = []
    for _, r in rows.iterrows():
        row = {"sensor fault": f"`{r['transition']}`", "design": r["variant"],
               "isolated (all sizes)": count(int(r["isolated"]), int(r["trials"]))}
        if trials is not None and "isolated" in trials and r["trials"] > 0:
            g = trials[(trials["transition"] == r["transition"])
                       & (trials["variant"] == r["variant"]) & trials["judged"].astype(bool)]
            size = g["sensor_size"].abs().to_numpy(dtype=float)
            iso = g["isolated"].astype(bool).to_numpy()
            edges = np.linspace(size.min(), size.max(), SIZE_BINS + 1)
            idx = np.clip(np.searchsorted(edges, size, side="right") - 1, 0, SIZE_BINS - 1)
            for b in range(SIZE_BINS):
                m = idx == b
                row[f"bin {b + 1}"] = (f"{edges[b]:.3g}-{edges[b + 1]:.3g}: "
                                       f"{count(int(iso[m].sum()), int(m.sum()))}")
        out.append(row)
    return _section(
        "Sensor-bias isolation of the sensor-aware designs", out,
        "Isolated: the trial flew to the end, the design's estimate of the bias is "
        "within 25 % of the true bias, and the belief's most probable mode at the end "
        "is nominal. Bins split the drawn |bias| (in the output's unit: rad/s, g) into "
        f"{SIZE_BINS} of equal width. A reset of the block sharing the bias's "
        "residual opens the bias hypothesis, so these designs' actuator-block resets "
        "above are hypotheses opened, not misattributions; a wrong mode or a "
        "controller switch still is.")


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
                               "envelope_exit", "sensor_bias_hat_end", "isolated") if c in t]
    t = t.drop(columns=sensor_cols)
    for c in ("correct", "inappropriate", "no_reset", "mode_changed", "detected", "small_b1",
              "lock_near_trim", "resets_truncated", "judged"):
        if c in t and t[c].dtype == object:
            t = t.astype({c: bool})
    return actuator_rows(summary), t

