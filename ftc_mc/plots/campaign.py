"""The report's figures of campaign results.

* :func:`delay_figure`: reset-delay and detection-time box plots of one run;
* :func:`sweep_figure`: rates against the threshold of one sweep;
* :func:`plant_figure`: rates of runs flown on different truth plants;
* :func:`survival_figure`: share staying in the envelope after an elevon lock,
  by lock offset.

They read the tables the report builds from Parquet files
(``ftc_mc/report/``); transition names are shown through the ``labels``
mapping the report passes (names missing from it are shown as they are).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .figure import plt, save


LINESTYLES = ("-", "--", ":", "-.")
MARKERS = (None, "o", "s", "^", "v", "x")


def design_styles(variants) -> dict:
    """``name -> plot keywords`` of each design: ``paper`` solid and ``swapped``
    dashed, as always; further designs in order of appearance, by line style and
    then marker."""
    names = ["paper", "swapped"]
    names += [v for v in dict.fromkeys(variants) if v not in names]
    return {v: {"linestyle": LINESTYLES[i % 4], "marker": MARKERS[(i // 4) % 6]}
            for i, v in enumerate(names)}


def _namer(labels):
    """``name -> label`` from a mapping (names missing from it are kept)."""
    labels = labels or {}
    return lambda name: labels.get(name, name)


# ------------------------------------------------------------------- delay figure


def _box_data(trials: pd.DataFrame, col: str, names: list, variants: list) -> list:
    judged = trials[trials["judged"]]
    out = []
    for name in names:
        for v in variants:
            x = judged.loc[(judged["transition"] == name) & (judged["variant"] == v), col]
            out.append(x[np.isfinite(x)].to_numpy())
    return out


def _horizontal() -> dict:
    """``boxplot`` keyword for horizontal boxes (``vert`` is deprecated in 3.11)."""
    import matplotlib

    major, minor = (int(x) for x in matplotlib.__version__.split(".")[:2])
    return {"orientation": "horizontal"} if (major, minor) >= (3, 10) else {"vert": False}


def _draw_boxes(ax, data: list, variants: list, colors: list) -> None:
    """Horizontal boxes, one group of ``len(variants)`` boxes per transition."""
    nv = len(variants)
    pos = [k + k // nv for k in range(len(data))]  # a gap between transitions
    for j, v in enumerate(variants):
        d = [(p, x) for k, (p, x) in enumerate(zip(pos, data)) if k % nv == j and len(x)]
        color = colors[j % len(colors)]
        if d:
            bp = ax.boxplot([x for _, x in d], positions=[p for p, _ in d], widths=0.7,
                            patch_artist=True, whis=(5, 95), medianprops={"color": "k"},
                            **_horizontal())
            for box in bp["boxes"]:
                box.set_facecolor(color)
                box.set_alpha(0.6)
        ax.plot([], [], "s", color=color, label=f"signature {v}")
    for p, x in zip(pos, data):
        if not len(x):
            ax.text(0.01, p, "no data", transform=ax.get_yaxis_transform(), va="center",
                    fontsize=7, color="0.4")


def delay_figure(trials: pd.DataFrame, path: Path, labels=None) -> Path:
    """Box plots of ``first_reset_s`` and ``detection_s`` per transition and variant.

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run (judged trials are plotted); times [s]
        after the fault switch.
    path : Path
        PNG file, written atomically.
    labels : mapping of str to str, optional
        Display label of each transition name.

    Returns
    -------
    Path
    """
    label = _namer(labels)
    names = list(dict.fromkeys(trials["transition"]))
    variants = list(dict.fromkeys(trials["variant"]))
    nv = len(variants)
    fig, axs = plt.subplots(1, 2, figsize=(11, 1.0 + 0.45 * nv * len(names)), sharey=True,
                            layout="constrained")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, (col, title) in zip(axs, (("first_reset_s", "first reset after the switch [s]"),
                                      ("detection_s", "detection of the new mode [s]"))):
        _draw_boxes(ax, _box_data(trials, col, names, variants), variants, colors)
        ax.set_xlabel(title)
        ax.grid(alpha=0.3, axis="x")
    axs[0].set_yticks([i * (nv + 1) + (nv - 1) / 2 for i in range(len(names))],
                      [label(n) for n in names], fontsize=8)
    axs[0].invert_yaxis()
    axs[1].legend(loc="best", fontsize=8)
    fig.suptitle("Reset delay and detection time (judged trials; whiskers 5-95 %)")
    return save(fig, path)


def survival_figure(table: pd.DataFrame, path: Path, labels=None,
                    trimmable: pd.DataFrame | None = None) -> Path:
    """Share of trials staying inside the envelope after an elevon lock, against
    the lock offset from trim, one panel per elevon-lock row and one line per
    design (95 % Wilson intervals as bars); the trimmable set shaded where it
    is known.

    Parameters
    ----------
    table : DataFrame
        :func:`ftc_mc.campaign.survival.survival_table` of a run.
    path : Path
        PNG file, written atomically.
    labels : mapping of str to str, optional
        Display label of each transition name.
    trimmable : DataFrame, optional
        :func:`ftc_mc.campaign.survival.trimmable_table` of the run: each row's
        set is shaded, its ends placed in their bins in proportion.

    Returns
    -------
    Path
    """
    label = _namer(labels)
    names = list(dict.fromkeys(table["transition"]))
    bins = (table[["offset_lo_deg", "offset_hi_deg", "bin"]].drop_duplicates()
            .sort_values("offset_lo_deg"))
    pos = {b: i for i, b in enumerate(bins["bin"])}

    def x_of(offset):
        """Position of a lock offset [deg] on the binned axis: in proportion
        inside a bin shown (the middle of an open-ended one), else at the edge
        of the next bin shown."""
        for i, (lo, hi) in enumerate(zip(bins["offset_lo_deg"], bins["offset_hi_deg"])):
            if offset < lo:
                return i - 0.5
            if offset < hi:
                frac = (offset - lo) / (hi - lo) if np.isfinite(lo) and np.isfinite(hi) else 0.5
                return i - 0.5 + frac
        return len(pos) - 0.5
    styles = design_styles(list(dict.fromkeys(table["variant"])))
    fig, axs = plt.subplots(1, len(names), figsize=(5.5 * len(names), 3.8), sharey=True,
                            layout="constrained", squeeze=False)
    for ax, name in zip(axs[0], names):
        sets = (trimmable[trimmable["transition"] == name] if trimmable is not None
                and len(trimmable) else ())
        if len(sets):
            ax.axvspan(x_of(sets["set_lo_deg"].iloc[0]), x_of(sets["set_hi_deg"].iloc[0]),
                       color="0.9", zorder=0, label="trimmable set")
        for variant, g in table[table["transition"] == name].groupby("variant", sort=False):
            g = g[g["flying"] > 0]
            x = np.array([pos[b] for b in g["bin"]])
            y = g["survived_rate"].to_numpy()
            err = np.vstack([y - g["survived_ci_low"].to_numpy(),
                             g["survived_ci_high"].to_numpy() - y])
            ax.errorbar(x, 100 * y, yerr=100 * err, capsize=2, label=variant,
                        **styles[variant])
        ax.set_xticks(range(len(pos)), list(pos), rotation=45, ha="right", fontsize=7)
        ax.set_xlabel("lock offset from trim [deg]")
        ax.set_title(label(name), fontsize=9)
        ax.set_ylim(-3, 103)
        ax.grid(alpha=0.3)
    horizon = table["horizon_s"].iloc[0]
    axs[0][0].set_ylabel(f"stay in the envelope {horizon:g} s [%]")
    axs[0][-1].legend(loc="best", fontsize=8)
    fig.suptitle("Survival after an elevon lock")
    return save(fig, path)


# ------------------------------------------------------------------- sweep figure


def sweep_figure(table: pd.DataFrame, path: Path, target_per_h: float, labels=None) -> Path:
    """Rates per transition and false resets per flight hour against the threshold.

    The x axis is the threshold when ``t_q = t_nx`` at every point, else the
    point index.

    Parameters
    ----------
    table : DataFrame
        ``sweep.parquet``: rates [-] per point, transition and variant, and
        ``false_resets_per_hour`` [1/h].
    path : Path
        PNG file, written atomically.
    target_per_h : float
        Largest acceptable false-reset rate [1/h], drawn as a line.
    labels : mapping of str to str, optional
        Display label of each transition name.

    Returns
    -------
    Path
    """
    label = _namer(labels)
    same = bool((table["t_q"] == table["t_nx"]).all())
    names = list(dict.fromkeys(table["transition"]))
    ncols = 3
    nrows = (len(names) + 1 + ncols - 1) // ncols
    fig, axs = plt.subplots(nrows, ncols, figsize=(12, 3.2 * nrows), squeeze=False)
    pts = table[["t_q", "t_nx"]].drop_duplicates().reset_index(drop=True)
    xkey = {(a, b): (a if same else i) for i, (a, b) in enumerate(zip(pts["t_q"], pts["t_nx"]))}
    styles = design_styles(table["variant"])
    for ax, name in zip(axs.flat, names):
        for variant, g in table[table["transition"] == name].groupby("variant"):
            x = [xkey[(a, b)] for a, b in zip(g["t_q"], g["t_nx"])]
            st = styles[variant]
            ax.plot(x, 100 * g["inappropriate_rate"], color="r", **st,
                    label=f"inappropriate {variant}")
            ax.plot(x, 100 * g["no_reset_rate"], color="b", **st, label=f"no reset {variant}")
        ax.set_title(label(name), fontsize=9)
        ax.set_ylabel("% of trials")
        ax.grid(alpha=0.3)
    ax = axs.flat[len(names)]
    for variant, g in table.groupby("variant"):
        g = g.drop_duplicates(["t_q", "t_nx"])
        x = [xkey[(a, b)] for a, b in zip(g["t_q"], g["t_nx"])]
        ax.semilogy(x, g["false_resets_per_hour"].clip(lower=1e-3), color="k",
                    **styles[variant], label=variant)
    ax.axhline(target_per_h, color="g", lw=0.8, label=f"1 per {1 / target_per_h:g} h")
    ax.set_title("false resets per flight hour", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    for extra in list(axs.flat)[len(names) + 1:]:
        extra.axis("off")
    axs.flat[0].legend(fontsize=7)
    for a in axs.flat:
        a.set_xlabel("threshold t_q = t_nx" if same else "threshold point")
    fig.tight_layout()
    return save(fig, path)


# ------------------------------------------------------------------- plant figure


def plant_figure(rates: pd.DataFrame, variant: str, path: Path, labels=None) -> Path:
    """Grouped bars: inappropriate and no-reset rates per transition and condition.

    Parameters
    ----------
    rates : DataFrame
        ``plant_rates`` of ``ftc_mc/report/plants.py``: rates [%] per
        transition, variant and condition, ``_cond`` the condition's rank.
    variant : str
        The signature variant drawn.
    path : Path
        PNG file, written atomically.
    labels : mapping of str to str, optional
        Display label of each transition name.

    Returns
    -------
    Path
    """
    label = _namer(labels)
    g = rates[rates["variant"] == variant]
    names = list(dict.fromkeys(g["transition"]))
    conds = list(g.sort_values("_cond", kind="stable")["condition"].drop_duplicates())
    width = 0.8 / len(conds)
    fig, axs = plt.subplots(1, 2, figsize=(max(7.0, 1.6 * len(names) + 4), 3.8),
                            sharey=True, layout="constrained")
    for ax, (col, title) in zip(axs, (("inappropriate_pct", "inappropriate resets"),
                                      ("no_reset_pct", "no reset in the window"))):
        for j, cond in enumerate(conds):
            c = g[g["condition"] == cond].set_index("transition")[col]
            ax.bar(np.arange(len(names)) + (j - (len(conds) - 1) / 2) * width,
                   [c.get(n, np.nan) for n in names], width, label=cond)
        ax.set_xticks(range(len(names)),
                      [label(n).replace(" → ", "\n→ ") for n in names], fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3, axis="y")
    axs[0].set_ylabel("% of judged trials")
    axs[1].legend(fontsize=7, title="plant / turbulence", title_fontsize=7)
    fig.suptitle(f"Truth plant and turbulence (signature {variant})")
    return save(fig, path)
