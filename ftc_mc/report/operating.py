"""The operating characteristic of a sweep's detection designs.

A *design* (the sweep's ``variant`` column: estimator model x residual test x
thresholds, e.g. ``paper``, ``swapped``, ``gust_glr``) is judged by the flight
hours between false resets against its detection delay and its correct-block
rate, swept over its threshold points (Basseville & Nikiforov 1993).  The
paper's design (:data:`BASELINE_DESIGNS`, the two Table 1 signature variants)
is the baseline every other design is drawn against; all designs of a sweep
flew the same trials.

Per design and threshold point (:func:`operating_points`), averaged over the
sweep's transitions:

* ``hours_per_false_reset`` [h]: 1 / false resets per flight hour on the
  fault-free flights; when none was seen it is infinite and the report shows
  the hours flown as a lower bound (``hours_is_bound``);
* ``delay_median_s`` / ``delay_p95_s`` [s]: the mean over transitions of each
  transition's median / 95th percentile of the delay from the fault switch to
  the first reset of the correct block in the judging window (over the trials
  that had one; ``correct_delay_median_s`` / ``_p95_s`` of ``sweep.parquet``;
  a transition without such a trial is left out of the mean);
* ``correct_only_rate`` [-]: trials whose correct block was reset in the
  window and the other block was not, pooled over transitions (judged trials),
  with its 95 % Wilson interval;
* ``cost`` [-]: the mean over transitions of the inappropriate-reset rate plus
  the unexplained no-reset rate (the criterion of
  :func:`~ftc_mc.report.sweep.recommend_threshold`);
* ``false_resets_per_hour_upper95`` [1/h]: the one-sided 95 % upper bound of
  the false-reset rate (:func:`ftc_mc.stats.poisson_upper`): a point meets a
  false-alarm target only when this bound does, and otherwise
  ``hours_to_show`` [h] says how many flight hours would show it with no
  further false reset (3.0 / target with none seen).

Where an endurance run (``ftc-mc endurance``) flew the same design at the same
thresholds in the same condition, its hours and false resets replace the
sweep's fault-free flights at that point (``hours_source`` ``endurance``;
:func:`endurance_hours`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..stats import hours_to_show, poisson_upper, wilson

BASELINE_DESIGNS = ("paper", "swapped")
"""Design names of the paper's own scheme (its Table 1 signature variants)."""


def is_baseline(design: str) -> bool:
    """Whether ``design`` is the paper's design (:data:`BASELINE_DESIGNS`)."""
    return str(design) in BASELINE_DESIGNS


def _col(g: pd.DataFrame, name: str) -> pd.Series:
    """Column ``name`` of ``g`` as floats, NaN when a sweep written before it
    existed lacks it."""
    return g[name].astype(float) if name in g else pd.Series(np.nan, index=g.index)


def _point(g: pd.DataFrame, flights=None) -> dict:
    """Operating-characteristic row of one design's rows at one threshold point;
    ``flights``: an endurance run's ``(hours, false resets, ci_high)`` at this
    point, in place of the sweep's fault-free flights."""
    explained = _col(g, "no_reset_explained_share").fillna(0.0)
    cost = _col(g, "inappropriate_rate") + _col(g, "no_reset_rate") * (1.0 - explained)
    if flights is None:
        hours = float(g["flight_hours"].iloc[0])
        n_false = int(g["flight_false_resets"].iloc[0])
        ci_high = float(g["false_resets_per_hour_ci_high"].iloc[0])
        rate = float(g["false_resets_per_hour"].iloc[0])
    else:
        hours, n_false, ci_high = flights
        rate = n_false / hours if hours else np.nan
    k = int(_col(g, "correct_only").fillna(0).sum())
    n = int(g["trials"].sum())
    has_rate = "correct_only" in g and n > 0
    lo, hi = wilson(k, n) if has_rate else (np.nan, np.nan)
    between = np.inf if rate == 0 else 1.0 / rate
    return {
        "transitions": int(g["transition"].nunique()),
        "flight_hours": hours,
        "flight_false_resets": n_false,
        "hours_source": "sweep" if flights is None else "endurance",
        "false_resets_per_hour": rate,
        "false_resets_per_hour_ci_high": ci_high,
        "false_resets_per_hour_upper95": poisson_upper(n_false, hours),
        "hours_per_false_reset": between,
        "hours_is_bound": bool(rate == 0),
        "hours_shown": hours if rate == 0 else between,
        "delay_median_s": float(_col(g, "correct_delay_median_s").mean()),
        "delay_p95_s": float(_col(g, "correct_delay_p95_s").mean()),
        "correct_only": k, "judged": n,
        "correct_only_rate": k / n if has_rate else np.nan,
        "correct_only_ci_low": lo, "correct_only_ci_high": hi,
        "cost": float(cost.mean()),
    }


def endurance_hours(endurance, design: str, t_q: float, t_nx: float):
    """``(hours, false resets, two-sided 95 % upper bound)`` of ``design`` at
    ``(t_q, t_nx)`` in the endurance rows ``endurance`` (already of the sweep's
    condition, :func:`ftc_mc.report.endurance.matching_endurance`), the run with
    the most hours; None when none flew it."""
    if endurance is None or not len(endurance):
        return None
    e = endurance[(endurance["variant"] == design) & np.isclose(endurance["t_q"], t_q)
                  & np.isclose(endurance["t_nx"], t_nx)]
    if not len(e):
        return None
    r = e.sort_values("flight_hours", ascending=False, kind="stable").iloc[0]
    return (float(r["flight_hours"]), int(r["false_resets"]),
            float(r["false_resets_per_hour_ci_high"]))


def operating_points(table: pd.DataFrame, endurance=None) -> pd.DataFrame:
    """One row per design and threshold point of a sweep, transitions averaged.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet`` (one row per threshold point, transition and variant).
    endurance : DataFrame, optional
        ``endurance.parquet`` rows of the sweep's condition: where one flew a
        design at a point, its hours replace the sweep's fault-free flights
        (:func:`endurance_hours`).

    Returns
    -------
    DataFrame
        Columns ``design``, ``baseline``, ``t_q``, ``t_nx`` and those of the
        module docstring; ``hours_shown`` [h] is ``hours_per_false_reset`` or,
        when no false reset was seen (``hours_is_bound``), the flight hours
        flown.  Designs in their order in ``table``, points by ``(t_q, t_nx)``.
    """
    rows = []
    order = list(dict.fromkeys(table["variant"]))
    for design in order:
        d = table[table["variant"] == design]
        for (tq, tnx), g in d.groupby(["t_q", "t_nx"], sort=True):
            rows.append({"design": design, "baseline": is_baseline(design),
                         "t_q": float(tq), "t_nx": float(tnx),
                         **_point(g, endurance_hours(endurance, design, tq, tnx))})
    return pd.DataFrame(rows)


def _pick(points: pd.DataFrame, target: float):
    """``(row, met)``: the lowest-cost point whose one-sided 95 % upper bound of
    false resets per flight hour is at most ``target`` (``met``), else the point
    with the lowest such bound."""
    ok = points[points["false_resets_per_hour_upper95"] <= target]
    if len(ok):
        keys, met, pool = ["cost", "false_resets_per_hour_upper95"], True, ok
    else:
        keys, met, pool = ["false_resets_per_hour_upper95", "cost"], False, points
    return pool.sort_values(keys, kind="stable").iloc[0], met


def recommend_design(table: pd.DataFrame, target: float, endurance=None):
    """The design and threshold point a sweep recommends, and the paper's best.

    Among all points of all designs whose false-reset rate per flight hour is
    shown to be at most ``target`` (its one-sided 95 % upper bound, from the
    sweep's fault-free flights or an endurance run's, ``endurance``), the one with the smallest mean over transitions of the
    inappropriate-reset rate plus the unexplained no-reset rate (ties: fewer
    false resets, then the design's order in the table); if no point meets the
    target, the point with the lowest bound.  The same choice among the
    points of the paper's design (:data:`BASELINE_DESIGNS`) is returned beside
    it.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet``.
    target : float
        Largest acceptable false-reset rate [1/h].

    Returns
    -------
    dict
        ``best``: the chosen :func:`operating_points` row (Series); ``met``:
        whether it meets ``target``; ``baseline`` and ``baseline_met``: the same
        among the paper's design (None when the sweep has no such design).
    """
    points = operating_points(table, endurance)
    best, met = _pick(points, target)
    base = points[points["baseline"]]
    out = {"best": best, "met": met, "baseline": None, "baseline_met": False}
    if len(base):
        out["baseline"], out["baseline_met"] = _pick(base, target)
    return out


def hours_text(row) -> str:
    """Flight hours between false resets as the report prints them [h]: the
    value, or ``>= hours flown (none seen)`` when no false reset was seen."""
    if not np.isfinite(row["hours_shown"]):
        return "-"
    if row["hours_is_bound"]:
        return f">= {row['hours_shown']:.3g} (none seen)"
    return f"{row['hours_shown']:.3g}"


def operating_table(points: pd.DataFrame) -> str:
    """The :func:`operating_points` rows as a Markdown table."""
    def num(x, fmt):
        return "-" if not np.isfinite(x) else fmt.format(x)

    view = pd.DataFrame({
        "design": [f"{d} (baseline)" if b else d
                   for d, b in zip(points["design"], points["baseline"])],
        "t_q": points["t_q"].map("{:g}".format),
        "t_nx": points["t_nx"].map("{:g}".format),
        "false resets / flight h": [
            f"{k} / {h:.3g}" + (" (endurance)" if s == "endurance" else "") for k, h, s in
            zip(points["flight_false_resets"], points["flight_hours"],
                points["hours_source"])],
        "one-sided 95 % bound / h": [num(u, "{:.3g}")
                                     for u in points["false_resets_per_hour_upper95"]],
        "h between false resets": [hours_text(r) for _, r in points.iterrows()],
        "delay median / p95 [s]": [f"{num(a, '{:.1f}')} / {num(b, '{:.1f}')}" for a, b in
                                   zip(points["delay_median_s"], points["delay_p95_s"])],
        "correct block only % (95% CI)": [
            "-" if not np.isfinite(r["correct_only_rate"]) else
            f"{100 * r['correct_only_rate']:.1f} ({100 * r['correct_only_ci_low']:.1f}-"
            f"{100 * r['correct_only_ci_high']:.1f})" for _, r in points.iterrows()],
        "inappropriate + unexplained no reset %": [num(100 * c, "{:.1f}")
                                                   for c in points["cost"]],
    })
    return view.to_markdown(index=False)


def _choice(row, met: bool, target: float) -> str:
    """One recommendation sentence for an :func:`operating_points` row."""
    source = " of an endurance run" if row["hours_source"] == "endurance" else ""
    point = (f"**`{row['design']}` at t_q = {row['t_q']:g}, t_nx = {row['t_nx']:g}**: "
             f"mean inappropriate + unexplained no-reset rate {100 * row['cost']:.2f} %, "
             f"{row['flight_false_resets']} false resets in {row['flight_hours']:.3g} "
             f"fault-free flight hours{source} (one-sided 95 % upper bound "
             f"{row['false_resets_per_hour_upper95']:.3g} per hour), median / p95 detection "
             f"delay {row['delay_median_s']:.2f} / {row['delay_p95_s']:.2f} s")
    if met:
        return point
    need = hours_to_show(int(row["flight_false_resets"]), target)
    more = ("with none seen, 3.0 / target" if row["flight_false_resets"] == 0 else
            "if no further false reset came")
    return (f"{point}; **not shown** that any point meets {target:g} false resets per flight "
            f"hour at 95 % confidence (this one has the lowest bound): {need:.0f} fault-free "
            f"flight hours would show it ({more}; `ftc-mc endurance`), or higher thresholds "
            "are needed")


def recommendation_lines(table: pd.DataFrame, condition: str, target: float,
                         endurance=None) -> list:
    """Markdown bullets: the recommended design for ``condition`` and the paper's best.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet``.
    condition : str
        The sweep's condition as text (truth plant and turbulence).
    target : float
        Largest acceptable false-reset rate [1/h].

    Returns
    -------
    list of str
    """
    rec = recommend_design(table, target, endurance)
    lines = [f"- For {condition}, at most {target:g} false resets per flight hour: "
             f"{_choice(rec['best'], rec['met'], target)}."]
    if rec["baseline"] is None:
        lines.append("- The paper's design (`paper` / `swapped`) is not in this sweep.")
    else:
        lines.append("- The paper's design at its best: "
                     f"{_choice(rec['baseline'], rec['baseline_met'], target)}.")
    return lines


def operating_section(table: pd.DataFrame, cfg: dict, fig_path, report,
                      target: float, endurance=None) -> list:
    """The "Operating characteristic" subsection of one sweep's report section.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet``.
    cfg : dict
        The sweep's stored config (its truth plant and turbulence name the
        condition).
    fig_path : Path
        PNG of the figure (:func:`~ftc_mc.plots.operating.operating_figure`).
    report : Path
        The report file (for the relative link).
    target : float
        Largest acceptable false-reset rate [1/h].
    endurance : DataFrame, optional
        Endurance rows of this condition (:func:`operating_points`).

    Returns
    -------
    list of str
    """
    from ..plots.operating import operating_figure  # matplotlib only when drawing
    from .markdown import plant_condition, rel_link

    kind, turbulence = plant_condition(cfg)
    condition = f"truth plant `{kind}`, turbulence `{turbulence}`"
    points = operating_points(table, endurance)
    fig = operating_figure(points, fig_path, target,
                           f"Operating characteristic: plant {kind}, turbulence {turbulence}")
    return ["### Operating characteristic", "",
            f"Condition: {condition}. Per design (the `variant` column; the paper's "
            "design `paper` / `swapped` is the baseline) and threshold point: the flight "
            "hours between false resets on the fault-free flights (when none was seen, "
            "the hours flown, a lower bound; an endurance run's hours where one flew the "
            "design at that point, marked `(endurance)`) and the one-sided 95 % upper "
            "bound of the false-reset rate, which a point must meet to count as meeting "
            "the target; the detection delay from the fault switch "
            "to the first reset of the correct block in the judging window (over the "
            "trials with one), median and 95th percentile, each the mean of the "
            "transitions' values; the share of trials whose correct block and only it "
            "was reset in the window, pooled over transitions, with its 95 % Wilson "
            "interval.", "",
            f"![operating characteristic]({rel_link(fig, report)})", "",
            operating_table(points), "",
            "#### Recommended design", "",
            *recommendation_lines(table, condition, target, endurance), ""]
