"""The report section of one threshold sweep (``ftc-mc sweep``).

The trade-off figure (``ftc_mc/plots/campaign.py``), the threshold point
recommended for each variant (:func:`recommend_threshold`), and the operating
characteristic of the sweep's designs with the design recommended for its
condition (``operating.py``, ``ftc_mc/plots/operating.py``).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from .load import ResultDir
from .markdown import LABELS, plant_text, rel_link
from ..stats import hours_to_show, poisson_upper
from .operating import operating_section

FALSE_RESET_TARGET_PER_H = 0.01
"""Largest acceptable false-reset rate when recommending a threshold: one per
100 flight hours [1/h]."""


def recommend_threshold(table: pd.DataFrame, variant: str,
                        target: float = FALSE_RESET_TARGET_PER_H):
    """The threshold point a sweep recommends for one signature variant.

    Among the points whose false-reset rate per flight hour is shown to be at
    most ``target`` (its one-sided 95 % upper bound, :func:`ftc_mc.stats.poisson_upper`),
    the one with the smallest mean over transitions of the inappropriate-reset rate
    plus the *unexplained* no-reset rate (no-reset trials not explained by a small
    ``b1`` or a lock near trim).  If no point
    meets the target, the point with the lowest bound.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet``.
    variant : str
        Signature variant.
    target : float
        Largest acceptable false-reset rate [1/h].

    Returns
    -------
    (float, float, str)
        ``t_q``, ``t_nx`` and the reasoning in one sentence.
    """
    g = table[table["variant"] == variant].copy()
    explained = g["no_reset_explained_share"].fillna(0.0)
    g["cost"] = g["inappropriate_rate"] + g["no_reset_rate"] * (1.0 - explained)
    per = g.groupby(["t_q", "t_nx"]).agg(cost=("cost", "mean"),
                                         false=("false_resets_per_hour", "first"),
                                         k=("flight_false_resets", "first"),
                                         hours=("flight_hours", "first"))
    per["upper"] = [poisson_upper(int(k), h) for k, h in zip(per["k"], per["hours"])]
    ok = per[per["upper"] <= target]
    if len(ok):
        (tq, tnx), row = ok["cost"].idxmin(), ok.loc[ok["cost"].idxmin()]
        why = (f"lowest mean inappropriate + unexplained no-reset rate "
               f"({100 * row['cost']:.2f} %) among the {len(ok)} points shown to have at "
               f"most {target:g} false resets per flight hour (here {row['false']:.3g}; "
               f"one-sided 95 % upper bound {row['upper']:.3g} from the flights flown)")
    else:
        (tq, tnx) = per["upper"].idxmin()
        row = per.loc[(tq, tnx)]
        need = hours_to_show(int(row["k"]), target)
        why = (f"not shown that any point reaches {target:g} false resets per flight hour "
               f"(one-sided 95 % upper bound); this one has the lowest bound "
               f"({row['upper']:.3g}, {int(row['k'])} in {row['hours']:.3g} h): {need:.0f} "
               "fault-free flight hours would show it if no further false reset came "
               "(`ftc-mc endurance`), or higher thresholds are needed")
    return float(tq), float(tnx), why


def sweep_section(r: ResultDir, fig_dir: Path, slug: str, report: Path,
                  endurance=None) -> list:
    """Report section of one sweep: trade-off plots, the recommended threshold per
    variant, and the operating characteristic with the recommended design.

    Parameters
    ----------
    r : ResultDir
        A sweep directory.
    fig_dir : Path
        Folder of the report's figures (``<slug>_sweep.png`` and
        ``<slug>_operating.png`` are written there).
    slug : str
        The sweep's file-name stem.
    report : Path
        The report file (for the relative link).
    endurance : DataFrame, optional
        Endurance rows of the sweep's condition (``ftc_mc/report/endurance.py``):
        their hours replace the sweep's fault-free flights where they match.

    Returns
    -------
    list of str
    """
    from ..plots.campaign import sweep_figure  # matplotlib only when drawing

    t = r.tables["sweep"]
    fig = sweep_figure(t, fig_dir / f"{slug}_sweep.png", FALSE_RESET_TARGET_PER_H, LABELS)
    lines = [f"## Sweep `{r.path}`", "",
             f"{t[['t_q', 't_nx']].drop_duplicates().shape[0]} threshold points, "
             f"{t['transition'].nunique()} transition(s), variants "
             f"{', '.join(sorted(t['variant'].unique()))}, "
             f"{plant_text(r.meta.get('config', {}))}.", "",
             f"![threshold trade-off]({rel_link(fig, report)})", "",
             "### Recommended threshold", ""]
    for variant in sorted(t["variant"].unique()):
        tq, tnx, why = recommend_threshold(t, variant)
        lines.append(f"- `{variant}`: **t_q = {tq:g}, t_nx = {tnx:g}**: {why}.")
    lines.append("")
    lines += operating_section(t, r.meta.get("config", {}), fig_dir / f"{slug}_operating.png",
                               report, FALSE_RESET_TARGET_PER_H, endurance)
    return lines
