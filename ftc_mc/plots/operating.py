"""The operating-characteristic figure of a sweep's detection designs.

:func:`operating_figure` draws, for each design, its threshold points as one
curve: flight hours between false resets (log x) against the detection delay
and the correct-block rate.  It reads the rows of
:func:`ftc_mc.report.operating.operating_points`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .figure import plt, save

BASELINE_STYLE = {"paper": ("k", "-"), "swapped": ("0.45", "--")}
"""Colour and line style of the paper's design, the baseline."""


def _style(design: str, others: list) -> tuple:
    """``(colour, line style, line width)`` of a design's curve."""
    if design in BASELINE_STYLE:
        return (*BASELINE_STYLE[design], 2.2)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    return colors[others.index(design) % len(colors)], "-", 1.4


def operating_figure(points: pd.DataFrame, path: Path, target_per_h: float,
                     title: str = "") -> Path:
    """Detection delay and correct-block rate against flight hours between false resets.

    Three panels over one log x axis (flight hours between false resets [h]):
    the median and the 95th percentile of the detection delay [s] and the
    correct-block rate [%] with its 95 % Wilson interval.  One curve per
    design through its threshold points, ordered by x; the paper's design
    (``paper``, ``swapped``) is drawn thick in black and grey as the
    baseline.  A point without any false reset sits at the hours flown, drawn
    as an open triangle pointing right: a lower bound.  The target is a
    vertical line at ``1 / target_per_h`` hours.

    Parameters
    ----------
    points : DataFrame
        :func:`~ftc_mc.report.operating.operating_points` rows: ``design``,
        ``hours_shown`` [h], ``hours_is_bound``, ``delay_median_s``,
        ``delay_p95_s`` [s], ``correct_only_rate`` and its ``_ci_low`` /
        ``_ci_high`` [-].
    path : Path
        PNG file, written atomically.
    target_per_h : float
        Largest acceptable false-reset rate [1/h].
    title : str
        Figure title (e.g. the condition).

    Returns
    -------
    Path
    """
    designs = list(dict.fromkeys(points["design"]))
    others = [d for d in designs if d not in BASELINE_STYLE]
    fig, axs = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True, layout="constrained")
    panels = (("delay_median_s", "median detection delay [s]"),
              ("delay_p95_s", "95th-percentile detection delay [s]"),
              ("correct_only_rate", "correct block only [% of trials]"))
    for design in designs:
        g = points[(points["design"] == design) & np.isfinite(points["hours_shown"])]
        g = g.sort_values(["hours_shown", "t_q", "t_nx"], kind="stable")
        color, ls, lw = _style(design, others)
        x = g["hours_shown"].to_numpy()
        bound = g["hours_is_bound"].to_numpy(dtype=bool)
        for ax, (col, _) in zip(axs, panels):
            scale = 100.0 if col == "correct_only_rate" else 1.0
            y = scale * g[col].to_numpy(dtype=float)
            ax.plot(x, y, color=color, ls=ls, lw=lw,
                    label=f"{design} (paper's design)" if design in BASELINE_STYLE else design)
            ax.plot(x[~bound], y[~bound], "o", color=color, ms=4)
            ax.plot(x[bound], y[bound], ">", mfc="none", color=color, ms=7)
            if col == "correct_only_rate":
                lo = scale * g["correct_only_ci_low"].to_numpy(dtype=float)
                hi = scale * g["correct_only_ci_high"].to_numpy(dtype=float)
                ax.fill_between(x, lo, hi, color=color, alpha=0.12, lw=0)
    for ax, (_, label) in zip(axs, panels):
        ax.axvline(1.0 / target_per_h, color="g", lw=0.8)
        ax.set_xscale("log")
        ax.set_ylabel(label, fontsize=8)
        ax.grid(alpha=0.3, which="both")
    axs[2].plot([], [], ">", mfc="none", color="0.3", label="no false reset: hours flown")
    axs[2].plot([], [], color="g", lw=0.8, label=f"target: 1 per {1 / target_per_h:g} h")
    axs[2].set_ylim(-2, 102)
    axs[2].set_xlabel("flight hours between false resets [h] (log)")
    axs[2].legend(fontsize=7, loc="best")
    fig.suptitle(title or "Operating characteristic", fontsize=10)
    return save(fig, path)
