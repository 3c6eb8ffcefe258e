"""The report section of one run (``ftc-mc run``).

Tables 2-3 beside the paper's counts, per signature variant, with 95 % Wilson
intervals and the verdict whether ours agree with the paper's, as the summary
recorded it (:func:`paper_tables`; the report does not judge again); the excluded trials and why
(:func:`exclusion_table`); a paired comparison of the signature variants with
an exact McNemar test (:func:`variant_comparison`); a link to the delay figure
(``ftc_mc/plots/campaign.py``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..conventions import VARIANTS
from ..campaign.summary import AGREEMENT_NOTE, agreement_text
from ..stats import mcnemar_exact
from .load import ResultDir
from .markdown import LABELS, count, label, num, plant_text, rel_link

SIGNIFICANCE = 0.05
"""Level of the paired (McNemar) test between signature variants."""


# ------------------------------------------------------------------ Tables 2-3


def _has_paper(r: pd.Series) -> bool:
    """Whether the paper ran row ``r`` (the right elevon's rows it did not: NaN)."""
    return bool(np.isfinite(float(r["paper_trials"])))


def _paper_count(r: pd.Series, col: str) -> str:
    if not _has_paper(r):
        return "-"
    return count(int(r[f"paper_{col}"]), int(r["paper_trials"]))


def _side(r: pd.Series) -> str:
    """``correct_side`` as ``k/n (rate %, CI)``; ``-`` where no trial applies
    (engine rows, recoveries) or the summary predates the column."""
    if "correct_side_rate" not in r or not np.isfinite(r["correct_side_rate"]):
        return "-"
    return count(int(r["correct_side"]), int(r["correct_side_trials"]))


def _paper_row(r: pd.Series) -> dict:
    """One row of the ours-beside-the-paper table."""
    n = int(r["trials"])
    return {
        "transition": r["label"], "judged": n,
        "inappropriate: ours": count(int(r["inappropriate"]), n),
        "inappropriate: paper": _paper_count(r, "inappropriate"),
        "no reset: ours": count(int(r["no_reset"]), n),
        "no reset: paper": _paper_count(r, "no_reset"),
        "no reset explained": num(100 * r["no_reset_explained_share"], "{:.0f} %"),
        "correct block": count(int(r["correct"]), n, ci=False),
        "reset delay median / p95 [s]":
            f"{num(r['delay_median_s'])} / {num(r['delay_p95_s'])}",
        "detection median / p95 [s]":
            f"{num(r['detection_median_s'])} / {num(r['detection_p95_s'])}",
        "false-alarm trials": int(r["false_alarm_trials"]),
        "correct side": _side(r),
        "agrees with the paper? (p inappr. / no reset)": agreement_text(r),
    }


def reads_truth(rows: pd.DataFrame) -> pd.Series:
    """Per row, whether it is a detector's that read the truth (``reads_truth``
    of ``ftc-mc score``'s tables; False for the designs' rows).

    Parameters
    ----------
    rows : DataFrame
        Summary or endurance rows.

    Returns
    -------
    Series of bool
    """
    if "reads_truth" not in rows:
        return pd.Series(False, index=rows.index)
    return rows["reads_truth"].eq(True)


def paper_tables(summary: pd.DataFrame) -> list:
    """Markdown lines: Tables 2-3 beside the paper's, one table per variant.

    Parameters
    ----------
    summary : DataFrame
        ``summary.parquet`` of a run.

    Returns
    -------
    list of str
    """
    lines = []
    for variant, g in summary.groupby("variant", sort=False):
        kind = "Signature" if variant in VARIANTS else "Design"
        if reads_truth(g).any():  # a detector scored on the truth (ftc-mc score)
            kind = "Oracle (a detector that read the truth: mode, b0, b1)"
        lines += [f"#### {kind} `{variant}`", "",
                  pd.DataFrame([_paper_row(r) for _, r in g.iterrows()])
                  .to_markdown(index=False), ""]
    lines += ["Counts are `k/n (rate %, 95 % Wilson CI)`, over judged trials only; the "
              "paper's counts are from its Tables 2-3 (one set for both variants; its "
              "faulty elevon is the left one, and it ran no right-elevon row). "
              "*Correct side*: of the judged trials whose final mode is an elevon fault, "
              "those whose belief at the end of the judging window holds the faulty "
              "elevon more probable than the other (`correct_side_rate`; `-` in other "
              "rows). " + AGREEMENT_NOTE + " The verdict is the one `summary.parquet` "
              "recorded (`paper_agrees*`, `paper_p_*`); *not recorded*: a summary written "
              "before those columns.", ""]
    return lines


def cost_lines(summary: pd.DataFrame) -> list:
    """Markdown lines: what flying cost, per row and design, from the
    summary's cost columns (:func:`ftc_mc.campaign.summary.cost_summary`);
    nothing for a run written before them."""
    if "track_rms_m" not in summary:
        return []
    rows = [{"transition": r["label"], "design": r["variant"],
             "track RMS [m]": num(r["track_rms_m"], "{:.3g}"),
             "largest track error, mean / max [m]":
                 f"{num(r['track_max_m_mean'], '{:.3g}')} / {num(r['track_max_m'], '{:.3g}')}",
             "energy throttle [s]": num(r["control_energy_throttle"], "{:.3g}"),
             "energy left / right elevon [rad^2 s]":
                 f"{num(r['control_energy_elevon_left'], '{:.3g}')} / "
                 f"{num(r['control_energy_elevon_right'], '{:.3g}')}"}
            for _, r in summary.iterrows()]
    return ["### Cost of flying", "",
            pd.DataFrame(rows).to_markdown(index=False), "",
            "Over the judged trials: the RMS of the glide path's cross-track error "
            "`x sin(gamma0) + z cos(gamma0)` (each trial weighted equally), the mean and "
            "the largest of each trial's largest error, and the mean control energy of "
            "each command (its squared deviation from trim times dt, excitation "
            "included), over the steps each trial flew.", ""]


# ------------------------------------------------------------------ exclusions


def window_end_s(cfg: dict) -> float | None:
    """End of the judging window, ``timing.fault_time_s + timing.window_s`` [s].

    Parameters
    ----------
    cfg : dict
        The config stored in a run's metadata.

    Returns
    -------
    float or None
        None if the config lacks either field.
    """
    timing = cfg.get("timing", {})
    return (timing["fault_time_s"] + timing["window_s"]
            if {"fault_time_s", "window_s"} <= timing.keys() else None)


def exclusion_reason(t: pd.DataFrame, window_end: float | None) -> pd.Series:
    """Why each trial of ``t`` (not judged) was excluded.

    Parameters
    ----------
    t : DataFrame
        Trials that were not judged (rows of ``trials.parquet``).
    window_end : float or None
        :func:`window_end_s` [s]; None: every early stop counts.

    Returns
    -------
    Series of str
        The stop status, ``resets_truncated`` or ``unknown``.
    """
    numeric = t["status"].isin(["nonfinite", "covariance_not_psd"])
    early = t["status"].ne("ok") & (t["stop_s"] <= window_end + 1e-9
                                    if window_end is not None else True)
    stopped = t["status"].where(numeric | early)
    reason = stopped.fillna(pd.Series("resets_truncated", index=t.index)
                            .where(t["resets_truncated"]))
    return reason.fillna("unknown")


def why(reasons: pd.Series) -> str:
    """``reason count, ...`` of :func:`exclusion_reason`, ``-`` if empty."""
    counts = reasons.value_counts()
    return ", ".join(f"{k} {v}" for k, v in counts.items()) or "-"


def _stopped(r: pd.Series) -> str:
    cols = [c for c in r.index if c.startswith("stopped_")]
    parts = [f"{c[len('stopped_'):]} {int(r[c])}" for c in cols if r[c]]
    return ", ".join(parts) or "-"


def exclusion_table(summary: pd.DataFrame, trials: pd.DataFrame, config: dict) -> list:
    """Markdown lines: excluded trials per transition and variant, and why.

    Parameters
    ----------
    summary, trials : DataFrame
        ``summary.parquet`` and ``trials.parquet`` of a run.
    config : dict
        The config stored in the run's metadata.

    Returns
    -------
    list of str
    """
    end = window_end_s(config)
    out = trials[~trials["judged"]]
    reasons = exclusion_reason(out, end) if len(out) else pd.Series(dtype=object)
    rows = []
    for _, r in summary.iterrows():
        sel = (out["transition"] == r["transition"]) & (out["variant"] == r["variant"])
        if not r["excluded"] and _stopped(r) == "-":
            continue
        rows.append({"transition": r["label"], "signature": r["variant"],
                     "run": int(r["trials"] + r["excluded"]), "excluded": int(r["excluded"]),
                     "why excluded": why(reasons[sel]),
                     "stopped at any time (stopped_*)": _stopped(r)})
    if not rows:
        return ["No trial was excluded or stopped early.", ""]
    return [pd.DataFrame(rows).to_markdown(index=False), "",
            "A trial is excluded from the rates when it failed numerically, left the "
            "validity envelope before the end of the judging window"
            + (f" ({end:g} s)" if end is not None else "")
            + ", or had more resets than it could store (`resets_truncated`); a trial stopped "
            "after the window still counts.", ""]


# ------------------------------------------------------------------ variant choice


def paired_counts(trials: pd.DataFrame, a: str, b: str, col: str) -> pd.DataFrame:
    """Per transition, ``col`` of variants ``a`` and ``b`` on the same trials.

    Only trials judged in both variants enter.  The p-value is the exact
    McNemar test (:func:`ftc_mc.stats.mcnemar_exact`).

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run with both variants.
    a, b : str
        The two signature variants.
    col : str
        A boolean outcome column, e.g. ``inappropriate``.

    Returns
    -------
    DataFrame
        ``transition, n, a, b, only_a, only_b, p``.
    """
    rows = []
    for name, g in trials.groupby("transition", sort=False):
        wide = g.pivot_table(index="trial_id", columns="variant",
                             values=[col, "judged"], aggfunc="first")
        both = wide["judged"].reindex(columns=[a, b]).fillna(False).astype(bool).all(axis=1)
        x = wide[col].reindex(columns=[a, b])[both].astype(bool)
        only_a = int((x[a] & ~x[b]).sum())
        only_b = int((x[b] & ~x[a]).sum())
        rows.append({"transition": name, "n": int(both.sum()), "a": int(x[a].sum()),
                     "b": int(x[b].sum()), "only_a": only_a, "only_b": only_b,
                     "p": mcnemar_exact(only_a, only_b)})
    return pd.DataFrame(rows)


def _verdict(inap: pd.DataFrame, a: str, b: str) -> str:
    """The sentence naming the better variant, with its numbers."""
    sig = inap[inap["p"] < SIGNIFICANCE]
    a_better = sig[sig["a"] < sig["b"]]
    b_better = sig[sig["b"] < sig["a"]]

    def cite(df):
        return "; ".join(f"{label(r.transition)}: {r.a}/{r.n} vs {r.b}/{r.n}, "
                         f"p = {r.p:.2g}" for r in df.itertuples()) or "none"

    n_tr = len(inap)
    if len(a_better) and len(b_better):
        head = (f"**Neither variant is better everywhere**: `{a}` has fewer inappropriate "
                f"resets in {len(a_better)} transition(s) ({cite(a_better)}), `{b}` in "
                f"{len(b_better)} ({cite(b_better)}).")
    elif len(a_better) or len(b_better):
        win, lose, df = (a, b, a_better) if len(a_better) else (b, a, b_better)
        head = (f"**`{win}` is better**: fewer inappropriate resets than `{lose}` in "
                f"{len(df)} of {n_tr} transitions ({cite(df)}) and more in none.")
    else:
        head = (f"**Neither variant is better on this data**: no transition shows a "
                f"significant difference in inappropriate resets (of {n_tr}).")
    tot = (f" Over all transitions: `{a}` {inap['a'].sum()}/{inap['n'].sum()}, "
           f"`{b}` {inap['b'].sum()}/{inap['n'].sum()} inappropriate.")
    return head + tot


def _no_reset_note(nr: pd.DataFrame, a: str, b: str) -> str:
    diff = nr[nr["a"] != nr["b"]]
    if not len(diff):
        return "The no-reset counts are identical for both variants in every transition."
    return ("No-reset counts differ in " + "; ".join(
        f"{label(r.transition)} ({a} {r.a}/{r.n}, {b} {r.b}/{r.n}, p = {r.p:.2g})"
        for r in diff.itertuples()) + "; weigh these against the inappropriate resets.")


def baseline_of(variants) -> str:
    """The reference design of a comparison: the paper's (``paper``, Table 1 as
    printed) when it was run, else the first run."""
    variants = list(variants)
    return "paper" if "paper" in variants else variants[0]


def variant_comparison(trials: pd.DataFrame) -> list:
    """Markdown lines: which design (signature variant) is better, from paired trials.

    Two designs are compared with each other; with more, each is compared with
    the baseline (:func:`baseline_of`).

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run.

    Returns
    -------
    list of str
    """
    variants = list(dict.fromkeys(trials["variant"]))
    if len(variants) < 2:
        return [f"Only the `{'`, `'.join(variants)}` variant was run; nothing to compare.",
                ""]
    if len(variants) == 2:
        return _pair_comparison(trials, *variants)
    base = baseline_of(variants)
    lines = [f"Each design against the baseline `{base}`, on the same trials.", ""]
    for other in variants:
        if other != base:
            lines += [f"#### `{other}` against `{base}`", ""]
            lines += _pair_comparison(trials, base, other)
    return lines


def _pair_comparison(trials: pd.DataFrame, a: str, b: str) -> list:
    """Markdown lines: the paired comparison of the designs ``a`` and ``b``."""
    inap = paired_counts(trials, a, b, "inappropriate")
    nr = paired_counts(trials, a, b, "no_reset")
    table = pd.DataFrame({
        "transition": inap["transition"].map(label), "paired trials": inap["n"],
        f"inappropriate `{a}`": inap["a"], f"inappropriate `{b}`": inap["b"],
        f"only `{a}`": inap["only_a"], f"only `{b}`": inap["only_b"],
        "McNemar p": inap["p"].map(lambda p: f"{p:.2g}"),
        f"no reset `{a}`": nr["a"], f"no reset `{b}`": nr["b"]})
    return [_verdict(inap, a, b) + " " + _no_reset_note(nr, a, b), "",
            table.to_markdown(index=False), "",
            "Both variants run on the same draws and noise, so the comparison is "
            "paired: trial by trial on the trials judged in both variants, with an exact "
            f"McNemar test (difference called significant at p < {SIGNIFICANCE}).", ""]


# ------------------------------------------------------------------ section


def _comparison_heading(trials: pd.DataFrame) -> str:
    if set(trials["variant"]) <= set(VARIANTS):
        return "### Which signature variant is better"
    return "### Which design is better"


def _design_text(cfg: dict) -> str:
    """``designs `a` (estimator, test, t_q/t_nx), ...`` of a run's extra designs."""
    names = cfg.get("campaign", {}).get("designs", [])
    defs = cfg.get("designs", {})

    def one(n):
        d = defs.get(n, {})
        test = d.get("test", "?") + (f" {d.get('window_s', '?'):g} s"
                                     if d.get("test") == "glr" else "")
        own = f", controller `{d['controller']}`" if d.get("controller") else ""
        own += f", `{d['weights']}` weights" if d.get("weights") else ""
        return (f"`{n}` ({d.get('estimator', '?')} estimator, {test}, "
                f"t_q {d.get('t_q', '?')}, t_nx {d.get('t_nx', '?')}{own})")

    return (", designs " + ", ".join(one(n) for n in names)) if names else ""


def _run_header(cfg: dict) -> str:
    c = cfg.get("campaign", {})
    own = any((cfg.get("designs", {}).get(n) or {}).get("controller")
              for n in c.get("designs", []))
    return (f"{len(c.get('transitions', []))} transition(s), {c.get('trials', '?')} trials "
            f"each, seed {c.get('seed', '?')}, signature `{c.get('signature', '?')}`"
            f"{_design_text(cfg)}, "
            f"controller `{cfg.get('controller', {}).get('kind', '?')}`"
            f"{' where a design names none' if own else ''}, "
            f"{plant_text(cfg)}.")


def run_section(r: ResultDir, fig_dir: Path, slug: str, report: Path) -> list:
    """Markdown lines of one run.

    Parameters
    ----------
    r : ResultDir
        A run directory.
    fig_dir : Path
        Folder of the report's figures (``<slug>_delays.png`` is written there).
    slug : str
        The run's file-name stem (:func:`ftc_mc.report.markdown.slugs`).
    report : Path
        The report file (for the relative link).

    Returns
    -------
    list of str
    """
    from ..plots.campaign import delay_figure  # matplotlib only when drawing

    from .realflight import real_flight_lines
    from .sensors import actuator_part, misattribution_table

    full_summary = r.tables["summary"]
    summary, trials = actuator_part(full_summary, r.tables["trials"])
    cfg = r.meta.get("config", {})
    head = [f"## Run `{r.path}`", "", _run_header(cfg), ""]
    sensor = misattribution_table(full_summary, r.tables["trials"])
    if not len(summary):
        return head + sensor
    fig = delay_figure(trials, fig_dir / f"{slug}_delays.png", LABELS)
    return (head + ["### Tables 2-3: ours beside the paper", ""] + paper_tables(summary)
            + cost_lines(summary)
            + ["### Excluded trials", ""] + exclusion_table(summary, trials, cfg)
            + [_comparison_heading(trials), ""] + variant_comparison(trials)
            + ["### Delay distributions", "", f"![delays of {slug}]({rel_link(fig, report)})",
               ""] + real_flight_lines(trials)
            + survival_lines(trials, cfg, fig_dir / f"{slug}_survival.png", report,
                             r.meta.get("trimmable_sets"))
            + side_lines(r.tables["trials"], cfg) + sensor)


def survival_lines(trials: pd.DataFrame, cfg: dict, fig_path: Path, report: Path,
                   stored_sets: dict | None = None) -> list:
    """The survival after an elevon lock (:mod:`ftc_mc.campaign.survival`) with its
    figure; nothing for a run without elevon-lock rows.  ``stored_sets``: the
    trimmable sets the run split its survival at (``summary.parquet``'s
    metadata); a run written before them has them found again."""
    from ..campaign.survival import (survival_markdown, survival_table, trimmable_markdown,
                                     trimmable_table)
    from ..plots.campaign import survival_figure

    timing = cfg.get("timing", {})
    if "fault_time_s" not in timing:
        return []
    table = survival_table(trials, timing["fault_time_s"], timing["duration_s"])
    if not len(table):
        return []
    sets = ({name: tuple(ends) for name, ends in stored_sets.items()}
            if isinstance(stored_sets, dict) else _trimmable_sets(cfg))
    inside = trimmable_table(trials, timing["fault_time_s"], timing["duration_s"], sets)
    fig = survival_figure(table, fig_path, LABELS, inside)
    return ([survival_markdown(table, level=3), ""]
            + ([trimmable_markdown(inside, level=3,
                                                kind=cfg.get("plant", {}).get("kind", "linear")), ""]
               if len(inside) else [])
            + [f"![survival of {fig_path.stem}]({rel_link(fig, report)})", ""])


def _trimmable_sets(cfg: dict) -> dict:
    """:func:`ftc_mc.campaign.survival.trimmable_sets` of a run's stored
    configuration, found again by today's code (on the nonlinear plant from
    its cache); ``{}`` when it no longer parses (a run of an older version)
    or its airframe file is gone."""
    from ..campaign.survival import trimmable_sets
    from ..config.load import parse_config
    from ..errors import UserError

    try:
        return trimmable_sets(parse_config(cfg))
    except UserError:
        return {}


def side_lines(trials: pd.DataFrame, cfg: dict) -> list:
    """Which actuator the 6-DOF side monitor named (:mod:`ftc_mc.campaign.side`);
    nothing for a run without it."""
    from ..campaign.side import side_markdown, side_table

    timing = cfg.get("timing", {})
    if "fault_time_s" not in timing or "side_correct" not in trials:
        return []
    md = side_markdown(side_table(trials, timing["fault_time_s"], timing["window_s"]), level=3)
    return [md, ""] if md else []
