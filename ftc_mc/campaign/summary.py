"""The Tables 2-3 summary: one row per transition and signature variant.

Rates carry 95 % Wilson score intervals (:func:`ftc_mc.stats.wilson`).  The
paper's own counts stand beside ours, with the verdict whether ours agree with
them (:func:`paper_agreement`: a two-sided Fisher exact test per quantity,
``docs/findings/paper-tables.md``, "How agreement is judged").

A sensor transition (``sensor_<kind>:<output>``) has no correct
actuator block, so its row has no Tables 2-3 columns (inappropriate, no reset,
correct, delay, detection, the paper's counts: NaN in a run that mixes both
kinds); it has the misattribution columns instead (:func:`sensor_row`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..conventions import STATUS_NAMES
from ..stats import agrees, median_p95, two_proportion_p, wilson
from .chunk import COST_COLUMNS
from .scoring import real_flight_scores
from .transitions import TRANSITION_TABLE, is_sensor, paper_counts, transition_of

SENSOR_RATES = ("actuator_reset", "wrong_mode", "controller_switch", "misattributed",
                "envelope_exit")
"""Rates of a sensor row: any actuator-block reset after the fault, the belief's
most probable mode an actuator fault (>= 0.5), a controller switch, any of the
three (``misattributed``), and a departure from the validity envelope."""


def _rate(prefix: str, k: int, n: int) -> dict:
    lo, hi = wilson(k, n) if n else (np.nan, np.nan)
    return {prefix: int(k), f"{prefix}_rate": k / n if n else np.nan,
            f"{prefix}_ci_low": lo, f"{prefix}_ci_high": hi}


def _quantiles(prefix: str, values: np.ndarray) -> dict:
    median, p95 = median_p95(values)
    return {f"{prefix}_median_s": median, f"{prefix}_p95_s": p95}


def _column(trials: pd.DataFrame, col: str) -> np.ndarray:
    """``trials[col]`` as floats, all NaN when the column is missing (tables
    written before it existed)."""
    if col not in trials:
        return np.full(len(trials), np.nan)
    return trials[col].to_numpy(dtype=float)


def summarize(trials: pd.DataFrame) -> pd.DataFrame:
    """Summary table of a campaign.

    Columns of an actuator row besides the counts: ``<x>``, ``<x>_rate``,
    ``<x>_ci_low``, ``<x>_ci_high`` (95 % Wilson) for ``inappropriate``,
    ``no_reset``, ``correct`` (the correct block was reset in the window) and
    ``correct_only`` (it was, and the other block was not: the correct-block
    rate of the operating characteristic); ``delay_median_s`` /
    ``delay_p95_s``: delay from the switch to the first reset of any block in
    the window [s], over the trials with one; ``correct_delay_median_s`` /
    ``correct_delay_p95_s``: delay from the switch to the first reset of the
    correct block in the window [s] (``correct_reset_s``), over the trials with
    one, whatever was reset before it (the detection delay of the operating
    characteristic; NaN for trials tables without that column);
    ``detection_median_s`` / ``detection_p95_s``: the belief's detection time [s];
    the real-flight metrics of :mod:`ftc_mc.campaign.scoring` (ALFA precision,
    recall and delays; average detection delay ``add_s`` and correct diagnosis
    rate ``cdr``); ``correct_side`` (with ``_rate``, ``_ci_low``, ``_ci_high``)
    and ``correct_side_trials``: of the judged trials of an elevon row whose
    final mode is an elevon mode (``correct_side_trials`` of them), those whose
    more probable elevon mode at the end of the judging window is the faulty
    side (the ``correct_side`` trial column; rate NaN where no trial applies:
    engine rows, recoveries, and tables written before the column existed).
    The paper's counts (``paper_*``) are NaN in the right elevon's rows, which
    the paper did not run; where they stand, :func:`paper_agreement` adds the
    verdict whether ours agree with them (``paper_p_*``, ``paper_agrees*``).

    Only judged trials (``judged`` column: no numerical failure, inside the
    validity envelope through the judging window, all resets stored) enter the
    rates; the others are counted in ``excluded``.  ``stopped_<reason>`` counts
    every trial that stopped early, judged or not.

    Parameters
    ----------
    trials : DataFrame
        The ``trials.parquet`` table.

    Returns
    -------
    DataFrame
        One row per (transition, variant), in the paper's row order.
    """
    rows = [summary_row(name, variant, g)
            for (name, variant), g in trials.groupby(["transition", "variant"], sort=False)]
    # designs in the order they were run (the signature variants, paper first, then
    # campaign.designs)
    return summary_frame(rows, trials["transition"].unique(),
                         dict.fromkeys(trials["variant"]))


SUMMARY_COLUMNS = ("transition", "variant", "judged", "no_reset", "small_b1",
                   "lock_near_trim", "mode_changed", "status", "resets_truncated",
                   "inappropriate", "correct", "first_reset_s", "correct_reset_s",
                   "false_resets", "detected", "detection_s", "actuator_reset",
                   "wrong_mode", "controller_switch", "envelope_exit", "actuator_reset_s",
                   "wrong_mode_s", "controller_switch_s", "first_action_s",
                   "sensor_bias_hat_end", "isolated", "first_reset_block", "correct_side",
                   "bank_rms_deg", "heading_rms_deg") + COST_COLUMNS
"""The ``trials.parquet`` columns :func:`summary_row` reads: a chunked scan reads
only these (``campaign/assemble.py``)."""


def summary_row(name: str, variant: str, g: pd.DataFrame) -> dict:
    """The summary row of the trials ``g`` of one transition and variant
    (:func:`summarize`; a sensor transition: :func:`sensor_row`).

    Depends only on the rows of ``g``, so a summary built one (transition,
    variant) at a time equals the summary of the whole table.
    """
    if is_sensor(name):
        return sensor_row(name, variant, g)
    ok = g[g["judged"]]
    n = len(ok)
    no_reset = ok["no_reset"].to_numpy()
    explained = no_reset & (ok["small_b1"].to_numpy() | ok["lock_near_trim"].to_numpy())
    changed = ok["mode_changed"].to_numpy()
    paper = paper_counts(name)
    row = {"transition": name, "label": TRANSITION_TABLE[name].label,
           "variant": variant, "trials": n, "excluded": len(g) - n}
    for reason in STATUS_NAMES[1:]:
        row[f"stopped_{reason}"] = int((g["status"] == reason).sum())
    row["resets_truncated"] = int(g["resets_truncated"].sum())
    row.update(_rate("inappropriate", int(ok["inappropriate"].sum()), n))
    row.update(_rate("no_reset", int(no_reset.sum()), n))
    row["no_reset_explained"] = int(explained.sum())
    row["no_reset_explained_share"] = (explained.sum() / no_reset.sum()
                                       if no_reset.sum() else np.nan)
    row.update(_rate("correct", int(ok["correct"].sum()), n))
    row.update(_rate("correct_only", int((ok["correct"] & ~ok["inappropriate"]).sum()), n))
    row.update(_quantiles("delay", ok["first_reset_s"].to_numpy()))
    row.update(_quantiles("correct_delay", _column(ok, "correct_reset_s")))
    row["false_alarm_trials"] = int((ok["false_resets"] > 0).sum())
    row["false_resets"] = int(ok["false_resets"].sum())
    row["mode_changes"] = int(changed.sum())
    row["detected"] = int(ok["detected"].sum())
    row.update(_quantiles("detection", ok["detection_s"].to_numpy()))
    row.update({"paper_trials": paper[0], "paper_inappropriate": paper[1],
                "paper_no_reset": paper[2]})
    row.update(paper_agreement(row))
    row.update(real_flight_scores(name, ok))  # ALFA and FDDBenchmark (scoring.py)
    side = _column(ok, "correct_side")
    applies = np.isfinite(side)
    row["correct_side_trials"] = int(applies.sum())
    row.update(_rate("correct_side", int((side[applies] == 1.0).sum()), int(applies.sum())))
    row.update(lateral_summary(g))
    row.update(cost_summary(ok))
    return row


AGREEMENT_QUANTITIES = ("inappropriate", "no_reset")
"""The two counts of Tables 2-3 that :func:`paper_agreement` judges."""
AGREEMENT_COLUMNS = ("paper_agrees_inappropriate", "paper_agrees_no_reset", "paper_agrees")
"""The verdict columns (nullable booleans: NA where there is no verdict)."""


def paper_agreement(row: dict) -> dict:
    """Whether the counts of a summary row agree with the paper's.

    Per quantity of :data:`AGREEMENT_QUANTITIES`, our count of the judged trials
    (``row[q]`` of ``row["trials"]``) against the paper's (``row["paper_" + q]``
    of ``row["paper_trials"]``): the p-value of the two-sided Fisher exact test
    (:func:`ftc_mc.stats.two_proportion_p`) and whether it finds agreement at
    5 % (:func:`ftc_mc.stats.agrees`).  The row agrees only if both quantities
    do.

    Parameters
    ----------
    row : dict
        A summary row with the counts, ``trials`` and the paper's counts
        (:func:`~ftc_mc.campaign.transitions.paper_counts`).

    Returns
    -------
    dict
        ``paper_p_inappropriate``, ``paper_p_no_reset`` (NaN where not
        compared), ``paper_agrees_inappropriate``, ``paper_agrees_no_reset`` and
        ``paper_agrees`` (None: no verdict, for a row the paper did not run or
        with no judged trial).
    """
    out = {}
    for q in AGREEMENT_QUANTITIES:
        paper_n, paper_k = row["paper_trials"], row[f"paper_{q}"]
        p = (two_proportion_p(row[q], row["trials"], paper_k, paper_n)
             if np.isfinite(paper_n) and np.isfinite(paper_k) else np.nan)
        out[f"paper_p_{q}"] = p
        out[f"paper_agrees_{q}"] = agrees(p)
    each = [out[f"paper_agrees_{q}"] for q in AGREEMENT_QUANTITIES]
    out["paper_agrees"] = None if None in each else all(each)
    return out


def p_text(p: float) -> str:
    """A p-value to two significant digits; ``<1e-300`` where it underflowed to 0."""
    return "<1e-300" if p == 0 else f"{p:.2g}"


def agreement_text(r) -> str:
    """The verdict of a summary row in words, with the p-values it rests on.

    ``agrees (p 0.61 / 0.28)``, ``differs: no reset (p 1 / 3.1e-09)`` (the
    p-values of inappropriate / no reset, the quantities that differ named);
    ``not in the paper`` for a row the paper did not run (the right elevon's:
    no verdict); ``-`` for a paper row without a judged trial; ``not
    recorded`` for a summary written before the verdict columns.
    """
    if "paper_agrees" not in r:
        return "not recorded"
    if not np.isfinite(float(r["paper_trials"])):
        return "not in the paper"
    verdict = r["paper_agrees"]
    if verdict is None or verdict is pd.NA or (isinstance(verdict, float)
                                              and not np.isfinite(verdict)):
        return "-"
    ps = " / ".join(p_text(r[f"paper_p_{q}"]) for q in AGREEMENT_QUANTITIES)
    if verdict:
        return f"agrees (p {ps})"
    differ = [q.replace("_", " ") for q in AGREEMENT_QUANTITIES
              if r[f"paper_agrees_{q}"] is not pd.NA and not r[f"paper_agrees_{q}"]]
    return f"differs: {', '.join(differ)} (p {ps})"


def cost_summary(ok: pd.DataFrame) -> dict:
    """What flying cost over the judged trials ``ok`` (the trial columns
    of :func:`ftc_mc.campaign.chunk.cost_columns`): ``track_rms_m``, the RMS of
    the glide path's cross-track error (``sqrt`` of the mean of the trials'
    squares, each trial weighted equally) [m]; ``track_max_m_mean`` and
    ``track_max_m``, the mean and the largest of the trials' largest
    cross-track errors [m]; ``control_energy_<command>``, the mean of the
    trials' control energies.  ``{}`` for a table written before those
    columns."""
    if "track_rms_m" not in ok:
        return {}
    n = len(ok)
    rms = ok["track_rms_m"].to_numpy(dtype=float)
    mx = ok["track_max_m"].to_numpy(dtype=float)
    out = {"track_rms_m": float(np.sqrt(np.mean(rms ** 2))) if n else np.nan,
           "track_max_m_mean": float(mx.mean()) if n else np.nan,
           "track_max_m": float(mx.max()) if n else np.nan}
    for col in COST_COLUMNS[2:]:
        out[col] = float(ok[col].to_numpy(dtype=float).mean()) if n else np.nan
    return out


def lateral_summary(g: pd.DataFrame) -> dict:
    """6-DOF runs: the bank and heading RMS [deg] over every trial of ``g``
    (``sqrt`` of the mean square, each trial weighted equally) and the largest
    trial's; ``{}`` for a longitudinal run (no such columns)."""
    if "bank_rms_deg" not in g:
        return {}
    out = {}
    for key in ("bank_rms_deg", "heading_rms_deg"):
        v = g[key].to_numpy(dtype=float)
        out[key] = float(np.sqrt(np.mean(v ** 2))) if len(v) else np.nan
        out[f"{key}_max"] = float(v.max()) if len(v) else np.nan
    return out


def summary_frame(rows, transitions, variants) -> pd.DataFrame:
    """The summary table of :func:`summary_row` rows: transitions in the paper's
    row order (others after them, in the order of ``transitions``), designs in
    the order of ``variants``.

    Parameters
    ----------
    rows : list of dict
    transitions : iterable of str
        The transitions in the order they appear in the trials table.
    variants : iterable of str
        The designs in the order they were run.
    """
    order = {name: i for i, name in enumerate(TRANSITION_TABLE)}
    for name in transitions:
        order.setdefault(name, len(order))
    out = pd.DataFrame(rows)
    if len(out):
        vorder = {v: i for i, v in enumerate(variants)}
        out = out.sort_values(["transition", "variant"],
                              key=lambda s: s.map(order if s.name == "transition" else vorder),
                              kind="stable").reset_index(drop=True)
        for col in AGREEMENT_COLUMNS:  # True / False / NA, also beside sensor rows
            if col in out:
                out[col] = out[col].astype("boolean")
    return out


def sensor_row(name: str, variant: str, g: pd.DataFrame) -> dict:
    """The summary row of the trials ``g`` of sensor transition ``name``.

    Over the judged trials (no numerical failure, every reset stored): the rates
    of :data:`SENSOR_RATES` with Wilson intervals, and the median / p95 time
    from the sensor fault to each first action and to the first of any; for a
    bias on an output the design estimates, the ``isolated`` rate
    (:func:`ftc_mc.campaign.chunk.classify_sensor`).
    """
    tr = transition_of(name)
    ok = g[g["judged"].astype(bool)]
    n = len(ok)
    row = {"transition": name, "label": tr.label, "variant": variant, "trials": n,
           "excluded": len(g) - n, "sensor_output": tr.output, "sensor_kind": tr.kind}
    for reason in STATUS_NAMES[1:]:
        row[f"stopped_{reason}"] = int((g["status"] == reason).sum())
    row["resets_truncated"] = int(g["resets_truncated"].astype(bool).sum())
    any_action = (ok["actuator_reset"].astype(bool) | ok["wrong_mode"].astype(bool)
                  | ok["controller_switch"].astype(bool))
    flags = {"actuator_reset": ok["actuator_reset"].astype(bool),
             "wrong_mode": ok["wrong_mode"].astype(bool),
             "controller_switch": ok["controller_switch"].astype(bool),
             "misattributed": any_action,
             "envelope_exit": ok["envelope_exit"].astype(bool)}
    for key in SENSOR_RATES:
        row.update(_rate(key, int(flags[key].sum()), n))
    for key in ("actuator_reset", "wrong_mode", "controller_switch"):
        row.update(_quantiles(key, ok[f"{key}_s"].to_numpy(dtype=float)))
    row.update(_quantiles("first_action", ok["first_action_s"].to_numpy(dtype=float)))
    row["false_resets"] = int(ok["false_resets"].sum())
    row.update(cost_summary(ok))
    if (tr.kind == "bias" and "sensor_bias_hat_end" in ok
            and ok["sensor_bias_hat_end"].notna().any()):  # the design estimates it
        row.update(_rate("isolated", int(ok["isolated"].astype(bool).sum()), n))
    return row


def sensor_markdown_table(summary: pd.DataFrame, intervals: bool = True) -> str:
    """The misattribution table of the sensor rows of a summary.

    Per sensor transition and variant: judged trials, the share with an
    actuator-block reset, a wrong mode (an actuator fault most probable with
    >= 0.5), a controller switch, any of them, and an envelope exit (95 % Wilson
    intervals when ``intervals``), and the median time from the fault to the first
    action; with a design estimating sensor biases, the share of bias faults it
    isolates (``-`` where it does not estimate that bias).  Empty string without
    sensor rows.
    """
    if "transition" not in summary or not summary["transition"].map(is_sensor).any():
        return ""
    rows = []
    for _, r in summary[summary["transition"].map(is_sensor)].iterrows():
        def pct(p):
            if not np.isfinite(r[p + "_rate"]):
                return "-"
            if not intervals:
                return f"{100 * r[p + '_rate']:.1f}"
            return (f"{100 * r[p + '_rate']:.1f} ({100 * r[p + '_ci_low']:.1f}-"
                    f"{100 * r[p + '_ci_high']:.1f})")
        med = r["first_action_median_s"]
        rows.append({
            "sensor fault": r["transition"], "signature": r["variant"],
            "judged": int(r["trials"]),
            "actuator reset %": pct("actuator_reset"),
            "wrong mode %": pct("wrong_mode"),
            "ctrl switch %": pct("controller_switch"),
            "any %": pct("misattributed"),
            "envelope exit %": pct("envelope_exit"),
            "1st action med [s]": "-" if not np.isfinite(med) else f"{med:.1f}",
        })
        if "isolated_rate" in summary:
            rows[-1]["isolated %"] = pct("isolated")
    return pd.DataFrame(rows).to_markdown(index=False)


_COUNTS = ("inappropriate", "no_reset", "no_reset_explained", "correct", "correct_only",
           "false_alarm_trials", "mode_changes", "detected", "paper_trials",
           "paper_inappropriate", "paper_no_reset", "alfa_tp", "alfa_fp", "alfa_fn",
           "correct_side", "correct_side_trials")


def actuator_rows(summary: pd.DataFrame) -> pd.DataFrame:
    """The rows of actuator transitions (Tables 2-3), without the sensor columns and
    with their counts as integers again (a run mixing both kinds has NaN there;
    the paper's counts stay NaN in the right elevon's rows)."""
    if "transition" not in summary or not summary["transition"].map(is_sensor).any():
        return summary
    sensor = summary["transition"].map(is_sensor)
    act = summary[~sensor]
    only = [c for c in summary if act[c].isna().all() and summary.loc[sensor, c].notna().any()]
    sub = act.drop(columns=only)
    return sub.astype({c: "int64" for c in _COUNTS if c in sub and sub[c].notna().all()})


def paper_text(r) -> str:
    """``inappropriate / no reset of trials`` of the paper's row ``r``; ``-`` for a
    row the paper did not run (NaN counts)."""
    counts = [r[f"paper_{c}"] for c in ("inappropriate", "no_reset", "trials")]
    if not all(np.isfinite(float(x)) for x in counts):
        return "-"
    i, nr, n = (int(x) for x in counts)
    return f"{i} / {nr} of {n}"


def side_text(r, intervals: bool = True) -> str:
    """``correct_side`` of a summary row as ``k/n (rate %, CI)``; ``-`` where it
    does not apply (or the summary predates it)."""
    if "correct_side_rate" not in r or not np.isfinite(r["correct_side_rate"]):
        return "-"
    k, n = int(r["correct_side"]), int(r["correct_side_trials"])
    if not intervals:
        return f"{k}/{n} ({100 * r['correct_side_rate']:.1f} %)"
    return (f"{k}/{n} ({100 * r['correct_side_rate']:.1f} %, "
            f"{100 * r['correct_side_ci_low']:.1f}-{100 * r['correct_side_ci_high']:.1f})")


def extra_columns(r) -> dict:
    """The columns of a summary row that only some runs have: the 6-DOF plant's
    bank and heading RMS [deg], and the glide-path tracking RMS [m] with the
    control energy of the commands."""
    out = {}
    if "bank_rms_deg" in r and np.isfinite(r["bank_rms_deg"]):
        out["bank / heading RMS [deg]"] = (f"{r['bank_rms_deg']:.2f} / "
                                           f"{r['heading_rms_deg']:.2f}")
    if "track_rms_m" in r and np.isfinite(r["track_rms_m"]):
        out["track RMS [m]"] = f"{r['track_rms_m']:.3g}"
    return out


def markdown_table(summary: pd.DataFrame) -> str:
    """The summary as the paper's columns plus ours, in Markdown.

    Columns: transition, variant, trials, inappropriate (rate, 95 % CI), no reset
    (rate, CI, share explained), correct, median / p95 reset delay, false alarms,
    detection median, correct side (``k/n``, rate, 95 % CI; ``-`` outside the
    elevon-fault trials), the paper's counts (``-`` for the right elevon's
    rows) and whether ours agree with them (:func:`agreement_text`).
    """
    def pct(r, p):
        return (f"{r[p]} ({100 * r[p + '_rate']:.1f} %, "
                f"{100 * r[p + '_ci_low']:.1f}-{100 * r[p + '_ci_high']:.1f})")

    def num(x, fmt="{:.1f}"):
        return "-" if not np.isfinite(x) else fmt.format(x)

    sensor = sensor_markdown_table(summary)
    summary = actuator_rows(summary)
    if not len(summary):
        return sensor
    rows = []
    for _, r in summary.iterrows():
        rows.append({
            "transition": r["label"], "signature": r["variant"], "judged": r["trials"],
            "excluded": r["excluded"],
            "inappropriate (%, 95% CI)": pct(r, "inappropriate"),
            "no reset (%, 95% CI)": pct(r, "no_reset"),
            "no reset explained": num(100 * r["no_reset_explained_share"], "{:.0f} %"),
            "correct block": f"{100 * r['correct_rate']:.1f} %",
            "delay median / p95 [s]": f"{num(r['delay_median_s'])} / {num(r['delay_p95_s'])}",
            "false-alarm trials": r["false_alarm_trials"],
            "detection median [s]": num(r["detection_median_s"]),
            "correct side (%, 95% CI)": side_text(r),
            "paper: inappropriate / no reset": paper_text(r),
            "agrees with the paper? (p inappr. / no reset)": agreement_text(r),
            **extra_columns(r),
        })
    table = pd.DataFrame(rows).to_markdown(index=False)
    if (summary["paper_trials"].notna().any() if "paper_trials" in summary else False):
        table += ("\n\n" + AGREEMENT_NOTE)
    return table + ("\n\n" + sensor if sensor else "")


AGREEMENT_NOTE = ("*Agrees with the paper?*: per quantity, our count of the judged trials "
                  "against the paper's of 1000, two-sided Fisher exact test at 5 %; a row "
                  "agrees only if both quantities do (`-`: no trial judged). "
                  "Agreement means no difference this test can detect, not equality "
                  "(docs/findings/paper-tables.md, \"How agreement is judged\").")
"""The sentence under a table with the verdict column (``summary.md``, the report)."""
