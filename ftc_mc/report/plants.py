"""The report's comparison of runs flown on different airframes, plants or turbulence.

When at least two runs differ in ``(model.airframe, plant.kind,
plant.turbulence)`` (:func:`plant_conditions_differ`), :func:`plant_section`
sets their rates side by side per transition: inappropriate and no-reset rates, false resets per
flight hour with the exact Poisson interval (:func:`ftc_mc.stats.poisson_rate`),
median delays, and the changes against the reference condition
(:data:`ftc_mc.report.markdown.DEFAULT_PLANT` if present).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..conventions import (AIRFRAME_PRESETS, DEFAULT_AIRFRAME, MODE_NAMES, MODE_NOMINAL,
                           PLANT_KINDS, TRANSITIONS, TURBULENCE_LEVELS)
from ..config.schema import TimingConfig
from ..stats import finite_median, poisson_rate
from .markdown import (DEFAULT_PLANT, LABELS, airframe_of, label, num, plant_condition,
                       rel_link)
from .runs import exclusion_reason, why, window_end_s

IGNORED_CAMPAIGN_KEYS = ("trials", "seed", "chunk_size", "reset_log")
"""``campaign`` fields that may differ between compared runs without a warning
(results do not depend on ``chunk_size``; the trials table and the summary not
on ``reset_log``)."""
PLANT_FIGURE = "plant_turbulence.png"
"""File name of the plant-comparison figure in the figure folder."""


# ------------------------------------------------------------------ conditions


def _rank(seq: tuple, value: str) -> int:
    """Position of ``value`` in ``seq``; unknown values after the known ones."""
    return seq.index(value) if value in seq else len(seq)


def run_conditions(configs: list) -> list:
    """The condition of each run: ``(kind, turbulence)``, with the airframe in
    front, ``(airframe, kind, turbulence)``, when the runs fly several.

    Parameters
    ----------
    configs : list of dict
        The configs stored in the runs' metadata.

    Returns
    -------
    list of tuple of str
    """
    plants = [plant_condition(c) for c in configs]
    frames = [airframe_of(c) for c in configs]
    if len(set(frames)) > 1:
        return [(f, *p) for f, p in zip(frames, plants)]
    return plants


def _is_reference(cond: tuple) -> bool:
    """The default airframe (if named) on the linear plant in still air."""
    *frame, kind, turbulence = cond
    return (kind, turbulence) == DEFAULT_PLANT and frame in ([], [DEFAULT_AIRFRAME])


def condition_order(conditions: list) -> list:
    """Indices of ``conditions`` in report order.

    The reference condition (the default airframe, when named, on
    :data:`DEFAULT_PLANT`) first, then by airframe
    (:data:`AIRFRAME_PRESETS`, then files), plant kind (:data:`PLANT_KINDS`) and
    turbulence (:data:`TURBULENCE_LEVELS`); ties keep the input order.

    Parameters
    ----------
    conditions : list of tuple of str
        ``(kind, turbulence)`` or ``(airframe, kind, turbulence)`` of each run
        (:func:`run_conditions`).

    Returns
    -------
    list of int
    """
    def key(i):
        *frame, kind, turbulence = conditions[i]
        name = frame[0] if frame else ""
        return (not _is_reference(conditions[i]), _rank(AIRFRAME_PRESETS, name), name, _rank(PLANT_KINDS, kind), kind,
                _rank(TURBULENCE_LEVELS, turbulence), turbulence, i)
    return sorted(range(len(conditions)), key=key)


def condition_labels(conditions: list, slugs: list) -> list:
    """``kind / turbulence`` of each run, with its slug when the condition repeats.

    Parameters
    ----------
    conditions : list of (str, str)
    slugs : list of str

    Returns
    -------
    list of str
    """
    out = []
    for cond, slug in zip(conditions, slugs):
        text = " / ".join(cond)
        out.append(f"{text} ({slug})" if conditions.count(cond) > 1 else text)
    return out


def reference_index(conditions: list) -> int:
    """The reference run: the first of the default airframe (when airframes
    differ) on the linear plant in still air (:data:`DEFAULT_PLANT`); else the
    first on that plant; else the first."""
    for test in (_is_reference, lambda c: tuple(c[-2:]) == DEFAULT_PLANT):
        for i, cond in enumerate(conditions):
            if test(cond):
                return i
    return 0


def plant_conditions_differ(runs: list) -> bool:
    """True if at least two runs differ in (airframe, plant kind, turbulence)."""
    return len(set(run_conditions([r.meta.get("config", {}) for r in runs]))) >= 2


# ------------------------------------------------------------------ rates


def _fault_time_s(cfg: dict) -> float:
    """``timing.fault_time_s`` of a config (the default if absent) [s]."""
    return float(cfg.get("timing", {}).get(
        "fault_time_s", TimingConfig.model_fields["fault_time_s"].default))


def condition_rates(trials: pd.DataFrame, fault_time_s: float) -> pd.DataFrame:
    """Rates of one run per transition and signature variant, over judged trials.

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run.
    fault_time_s : float
        Flight before the switch in every trial [s]: the exposure of
        ``false_resets``, counted only in trials whose truth is nominal before
        the switch (``mode_pre``; unlock and recover rows start faulted and
        have no false resets).

    Returns
    -------
    DataFrame
        ``transition, variant, judged, excluded, inappropriate_pct,
        no_reset_pct, false_resets, flight_hours, false_per_h, false_per_h_low,
        false_per_h_high, delay_median_s, detection_median_s``; the
        false-reset interval is the exact (Garwood) Poisson 95 % interval
        [1/h].
    """
    rows = []
    for (name, variant), g in trials.groupby(["transition", "variant"], sort=False):
        ok = g[g["judged"].astype(bool)]
        n, k = len(ok), int(ok["false_resets"].sum())
        nominal = (ok["mode_pre"] == MODE_NAMES[MODE_NOMINAL]) if "mode_pre" in ok else ok["judged"]
        hours = int(nominal.sum()) * fault_time_s / 3600.0
        rate, lo, hi = poisson_rate(k, hours)
        rows.append({
            "transition": name, "variant": variant, "judged": n, "excluded": len(g) - n,
            "inappropriate_pct": 100 * ok["inappropriate"].mean() if n else np.nan,
            "no_reset_pct": 100 * ok["no_reset"].mean() if n else np.nan,
            "false_resets": k, "flight_hours": hours,
            "false_per_h": rate, "false_per_h_low": lo, "false_per_h_high": hi,
            "delay_median_s": finite_median(ok["first_reset_s"]),
            "detection_median_s": finite_median(ok["detection_s"])})
    return pd.DataFrame(rows)


def _with_deltas(rates: pd.DataFrame, ref: str) -> pd.DataFrame:
    """``rates`` plus the rate changes [pp] against condition ``ref``."""
    base = rates[rates["condition"] == ref][["transition", "variant", "inappropriate_pct",
                                             "no_reset_pct"]]
    out = rates.merge(base, on=["transition", "variant"], how="left", suffixes=("", "_ref"))
    for col in ("inappropriate", "no_reset"):
        out[f"d_{col}_pp"] = out[f"{col}_pct"] - out[f"{col}_pct_ref"]
    out["reference"] = out["condition"] == ref
    return out.drop(columns=["inappropriate_pct_ref", "no_reset_pct_ref"])


def plant_rates(runs: list, conds: list, labels: list) -> pd.DataFrame:
    """Rates of every run, one condition per run, in report order.

    Parameters
    ----------
    runs : list of ResultDir
        Run directories.
    conds : list of tuple of str
        Their conditions (:func:`run_conditions`).
    labels : list of str
        Their labels (:func:`condition_labels`).

    Returns
    -------
    DataFrame
        The :func:`condition_rates` columns plus ``condition`` (label),
        ``reference`` (bool), ``d_inappropriate_pp``, ``d_no_reset_pp``
        (change against the reference run, NaN where it lacks the row) and
        ``_cond`` (rank of the condition, :func:`condition_order`); rows by
        transition (paper order), variant, then condition.
    """
    rank = {i: pos for pos, i in enumerate(condition_order(conds))}
    parts = []
    for i, r in enumerate(runs):
        part = condition_rates(r.tables["trials"], _fault_time_s(r.meta.get("config", {})))
        parts.append(part.assign(condition=labels[i], _cond=rank[i]))
    rates = _with_deltas(pd.concat(parts, ignore_index=True),
                         labels[reference_index(conds)])
    t_order = {n: i for i, n in enumerate(TRANSITIONS)}
    v_order = {v: i for i, v in enumerate(dict.fromkeys(rates["variant"]))}
    rates["_t"] = rates["transition"].map(t_order).fillna(len(t_order))
    rates["_v"] = rates["variant"].map(v_order)
    return (rates.sort_values(["_t", "_v", "_cond"], kind="stable")
            .drop(columns=["_t", "_v"]).reset_index(drop=True))


# ------------------------------------------------------------------ table


def _per_hour(x: float) -> str:
    """A rate per flight hour: three significant digits, whole numbers from 1000."""
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"


def _delta(r: pd.Series, col: str) -> str:
    return "ref" if r["reference"] else num(r[f"d_{col}_pp"], "{:+.1f}")


def _plant_row(r: pd.Series) -> dict:
    """One row of the plant-comparison table."""
    return {
        "transition": label(r["transition"]), "signature": r["variant"],
        "condition": r["condition"], "judged": int(r["judged"]),
        "inappropriate [%]": num(r["inappropriate_pct"]),
        "no reset [%]": num(r["no_reset_pct"]),
        "false resets / flight h (95 % CI)":
            f"{_per_hour(r['false_per_h'])} ({_per_hour(r['false_per_h_low'])}-"
            f"{_per_hour(r['false_per_h_high'])})" if r["judged"] else "-",
        "first reset median [s]": num(r["delay_median_s"]),
        "detection median [s]": num(r["detection_median_s"]),
        "Δ inappropriate [pp]": _delta(r, "inappropriate"),
        "Δ no reset [pp]": _delta(r, "no_reset"),
    }


def _excluded_note(runs: list, labels: list, order: list) -> str:
    """One sentence: how many trials of each condition were not judged, and why."""
    parts = []
    for i in order:
        trials = runs[i].tables["trials"]
        end = window_end_s(runs[i].meta.get("config", {}))
        out = trials[~trials["judged"].astype(bool)]
        reasons = f" ({why(exclusion_reason(out, end))})" if len(out) else ""
        parts.append(f"`{labels[i]}` {len(out)} of {len(trials)}{reasons}")
    return ("Trials excluded from the rates (not judged), by condition: "
            + "; ".join(parts) + ". In turbulence many trials can leave the validity "
            "envelope before the end of the judging window; they enter no column above, "
            "so compare the judged counts too.")


# ------------------------------------------------------------------ config check


def _comparable(cfg: dict) -> dict:
    """``cfg`` without the ``plant`` section, ``model.airframe`` and
    :data:`IGNORED_CAMPAIGN_KEYS`."""
    out = {k: v for k, v in cfg.items() if k != "plant"}
    if isinstance(out.get("model"), dict):
        out["model"] = {k: v for k, v in out["model"].items() if k != "airframe"}
    if isinstance(out.get("campaign"), dict):
        out["campaign"] = {k: v for k, v in out["campaign"].items()
                           if k not in IGNORED_CAMPAIGN_KEYS}
    return out


def config_differences(configs: list) -> list:
    """Top-level config sections in which the compared runs differ.

    The ``plant`` section and ``campaign`` fields :data:`IGNORED_CAMPAIGN_KEYS`
    are left out.

    Parameters
    ----------
    configs : list of dict

    Returns
    -------
    list of str
        In the order of the first config.
    """
    first = _comparable(configs[0]) if configs else {}
    found = {}
    for cfg in configs[1:]:
        other = _comparable(cfg)
        for key in list(first) + list(other):
            if first.get(key) != other.get(key):
                found[key] = None
    return list(found)


def _difference_warning(configs: list) -> list:
    """Markdown lines: a warning if the runs differ beyond the plant, else nothing."""
    diff = config_differences(configs)
    if not diff:
        return []
    return [f"> **Warning: the compared runs also differ in "
            f"{', '.join(f'`{d}`' for d in diff)}** (besides `plant`, `model.airframe` and "
            f"`campaign.{'`/`campaign.'.join(IGNORED_CAMPAIGN_KEYS)}`): the changes "
            "below need not come from the plant alone.", ""]


# ------------------------------------------------------------------ section


def _figure_variant(rates: pd.DataFrame) -> str:
    variants = list(dict.fromkeys(rates["variant"]))
    return "swapped" if "swapped" in variants else variants[0]


def plant_section(runs: list, slugs: list, fig_dir: Path, report: Path) -> list:
    """Markdown lines: the runs' rates side by side, one condition per run.

    Parameters
    ----------
    runs : list of ResultDir
        The run inputs (at least two conditions, :func:`plant_conditions_differ`).
    slugs : list of str
        Their slugs.
    fig_dir : Path
        Folder of the figure.
    report : Path
        The report file (for the relative link).

    Returns
    -------
    list of str
    """
    from ..plots.campaign import plant_figure  # matplotlib only when drawing

    configs = [r.meta.get("config", {}) for r in runs]
    conds = run_conditions(configs)
    labels = condition_labels(conds, slugs)
    ref = reference_index(conds)
    rates = plant_rates(runs, conds, labels)
    variant = _figure_variant(rates)
    fig = plant_figure(rates, variant, fig_dir / PLANT_FIGURE, LABELS)
    airframes = len(conds[0]) == 3
    what = "airframe / plant / turbulence" if airframes else "plant / turbulence"
    heading = ("## Airframe, truth plant and turbulence" if airframes
               else "## Truth plant and turbulence")
    return ([heading, "",
             f"{len(runs)} runs, one condition each ({what}); reference "
             f"`{labels[ref]}` (`{runs[ref].path}`).", ""]
            + _difference_warning(configs)
            + [pd.DataFrame([_plant_row(r) for _, r in rates.iterrows()])
               .to_markdown(index=False, floatfmt=".1f"), "",
               "Rates in % of judged trials. False resets: resets at or before the fault "
               "switch, per hour of the fault-free flight before it (judged trials × "
               "`timing.fault_time_s`), with the exact Poisson 95 % interval. First reset: "
               "median delay after the switch, of trials with a reset in the window. "
               "Δ: change in percentage points against the reference condition.", "",
               _excluded_note(runs, labels, condition_order(conds)), "",
               f"![truth plant and turbulence]({rel_link(fig, report)})", ""])
