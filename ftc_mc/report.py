"""One Markdown report from finished run and scenario directories.

:func:`build_report` reads only the Parquet files of each input directory (so a
report can be rebuilt at any time without rerunning anything) and writes a
Markdown file with:

* for each run (``ftc-mc run``): Tables 2-3 beside the paper's counts, per
  signature variant, with 95 % Wilson intervals; the excluded trials and why;
  a paired comparison of the signature variants; a figure of the reset-delay
  and detection-time distributions;
* for each scenario (``ftc-mc scenario``): the event timeline beside the
  paper's (section 5.2) and links to the scenario's own figures;
* when at least two runs flew different truth plants or turbulence levels
  (config section ``plant``): their rates side by side per transition, with
  false resets per flight hour and the changes against the reference plant;
* the provenance of every input (kind, version, git revision, seed, config).

Every section names the truth plant and turbulence of its input (results
written before the ``plant`` section existed flew the linear plant without
turbulence).  Inputs whose metadata show different package versions or git
revisions are refused unless ``allow_mixed`` is set.  Figures go to
``<out stem>_figures/`` beside the report and are linked by relative paths.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from urllib.parse import quote

import numpy as np
import pandas as pd
import scipy.stats
import yaml

from .campaign.summary import wilson
from .campaign.sweep import poisson_ci
from .campaign.transitions import TRANSITION_TABLE
from .errors import UserError
from .io.atomic import write_text
from .io.chunks import FOLDER as CHUNKS_FOLDER
from .config.schema import TimingConfig
from .conventions import PLANT_KINDS, TRANSITIONS, TURBULENCE_LEVELS
from .io.lock import holder
from .io.results import read_metadata
from .scenario import PAPER_TIMELINE

RUN_TABLES = ("trials.parquet", "summary.parquet")
"""Parquet files a run directory must hold (``resets.parquet`` is optional)."""
SCENARIO_TABLES = ("segments.parquet", "events.parquet")
"""Parquet files a scenario directory must hold (``timeseries.parquet`` optional)."""
SWEEP_TABLES = ("sweep.parquet",)
"""Parquet file of a sweep directory."""
FALSE_RESET_TARGET_PER_H = 0.01
"""Largest acceptable false-reset rate when recommending a threshold: one per
100 flight hours."""
PAPER_EXCITATIONS = {"doublet": (10.0, 12.6, 15.6, 30.0, 50.0, 70.0), "3211": (90.0,)}
"""Excitations the paper reports in section 5.2 (same text as
:func:`ftc_mc.scenario.summary_markdown`)."""
SIGNIFICANCE = 0.05
"""Level of the paired (McNemar) test between signature variants."""
DEFAULT_PLANT = ("linear", "none")
"""Truth plant of results written before the ``plant`` section existed; the
reference condition of the plant comparison."""
IGNORED_CAMPAIGN_KEYS = ("trials", "seed", "chunk_size")
"""``campaign`` fields that may differ between compared runs without a warning
(results do not depend on ``chunk_size``)."""
PLANT_FIGURE = "plant_turbulence.png"
"""File name of the plant-comparison figure in the figure folder."""


@dataclasses.dataclass
class ResultDir:
    """One input directory, as read from its Parquet files.

    Attributes
    ----------
    path : Path
        The directory as given.
    kind : str
        ``"run"`` or ``"scenario"``.
    meta : dict
        ``ftc_mc`` metadata of the main table (summary or segments).
    file_meta : dict of str to dict
        Metadata of every Parquet file in the directory, by file name.
    tables : dict of str to DataFrame
        The tables the report uses, by file stem.
    """

    path: Path
    kind: str
    meta: dict
    file_meta: dict
    tables: dict


# ----------------------------------------------------------------------------- input


def _kind_from_files(path: Path) -> str | None:
    """``"run"``, ``"scenario"`` or None, from the Parquet files present."""
    found = [k for k, files in (("run", RUN_TABLES), ("scenario", SCENARIO_TABLES),
                                ("sweep", SWEEP_TABLES))
             if any((path / f).is_file() for f in files)]
    if len(found) > 1:
        raise UserError(f"{path}: holds {' and '.join(found)} files; give one "
                        "directory per result")
    return found[0] if found else None


def _file_metadata(path: Path) -> dict:
    """Metadata of every Parquet file of ``path``, by file name."""
    metas = {}
    for f in sorted(path.glob("*.parquet")):
        try:
            metas[f.name] = read_metadata(f)
        except Exception as exc:  # pyarrow raises several types for a bad file
            raise UserError(f"{f}: not a readable Parquet file ({exc})") from None
        if not metas[f.name]:
            raise UserError(f"{f}: has no ftc_mc metadata; not an ftc-mc result file")
    return metas


def _check_not_busy(path: Path) -> None:
    """Refuse a directory that a live ``ftc-mc run``/``scenario`` is writing."""
    owner = holder(path)
    if owner is not None:
        raise UserError(f"{path}: being written by `{owner.get('command')}` (pid "
                        f"{owner.get('pid')}); build the report when it has finished")


def load_result_dir(path) -> ResultDir:
    """Read one run or scenario directory.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    ResultDir

    Raises
    ------
    UserError
        If ``path`` is not a directory, is being written by a live ``ftc-mc``
        process, holds no results, misses a table, or its files disagree on
        their kind.
    """
    path = Path(path)
    if not path.is_dir():
        raise UserError(f"{path}: not a directory")
    _check_not_busy(path)
    kind = _kind_from_files(path)
    if kind is None:
        unfinished = (" (only the chunks of an unfinished run: finish it with "
                      "`ftc-mc run CONFIG --resume --out DIR`)"
                      if (path / CHUNKS_FOLDER).is_dir() else "")
        raise UserError(f"{path}: no ftc-mc results{unfinished} (expected trials.parquet "
                        "and summary.parquet of a run, or segments.parquet and "
                        "events.parquet of a scenario)")
    needed = {"run": RUN_TABLES, "scenario": SCENARIO_TABLES, "sweep": SWEEP_TABLES}[kind]
    missing = [f for f in needed if not (path / f).is_file()]
    if missing:
        raise UserError(f"{path}: incomplete {kind} results, missing {', '.join(missing)}")
    file_meta = _file_metadata(path)
    kinds = {m.get("kind") for m in file_meta.values()}
    if kinds != {kind}:
        raise UserError(f"{path}: metadata kind {sorted(map(str, kinds))} does not match "
                        f"the {kind} files it holds")
    tables = {f[:-len(".parquet")]: pd.read_parquet(path / f) for f in needed}
    return ResultDir(path=path, kind=kind, meta=file_meta[needed[-1]],
                     file_meta=file_meta, tables=tables)


def _unique_dirs(dirs) -> list:
    """``dirs`` as Paths, duplicates (same resolved directory) dropped."""
    seen, out = set(), []
    for d in dirs:
        key = Path(d).resolve()
        if key not in seen:
            seen.add(key)
            out.append(Path(d))
    return out


# ------------------------------------------------------------------------ provenance


def _stamp(meta: dict) -> tuple:
    return (str(meta.get("version")), str(meta.get("git_revision")))


def provenance_groups(inputs: list) -> dict:
    """Inputs grouped by (version, git revision).

    Returns
    -------
    dict of (str, str) to list of str
        Each distinct stamp and where it occurs: a directory when all its files
        carry the stamp, ``dir/file`` otherwise.
    """
    groups = {}
    for r in inputs:
        stamps = {name: _stamp(m) for name, m in r.file_meta.items()}
        for s in dict.fromkeys(stamps.values()):
            names = [n for n, v in stamps.items() if v == s]
            where = ([str(r.path)] if len(set(stamps.values())) == 1
                     else [str(r.path / n) for n in names])
            groups.setdefault(s, []).extend(where)
    return groups


def mixed_message(groups: dict) -> str:
    """One line saying which inputs differ in version or git revision."""
    parts = [f"version {v}, git revision {g}: {', '.join(w)}"
             for (v, g), w in groups.items()]
    return "inputs come from different versions or git revisions (" + "; ".join(parts) + ")"


def check_provenance(inputs: list, allow_mixed: bool) -> str | None:
    """Refuse inputs of different versions or git revisions.

    Parameters
    ----------
    inputs : list of ResultDir
    allow_mixed : bool
        Return a warning instead of raising.

    Returns
    -------
    str or None
        The warning (mixed inputs allowed), or None if all inputs agree.

    Raises
    ------
    UserError
        If the inputs differ and ``allow_mixed`` is false.
    """
    groups = provenance_groups(inputs)
    if len(groups) <= 1:
        return None
    msg = mixed_message(groups)
    if not allow_mixed:
        raise UserError(f"{msg}; pass --allow-mixed (allow_mixed=True) to build the "
                        "report anyway")
    return msg


# --------------------------------------------------------------------------- helpers


def _rel_link(target: Path, report: Path) -> str:
    """URL-quoted POSIX path of ``target`` relative to the report's folder."""
    rel = os.path.relpath(Path(target).resolve(), Path(report).resolve().parent)
    return quote(Path(rel).as_posix())


def _num(x, fmt="{:.1f}") -> str:
    return "-" if x is None or not np.isfinite(x) else fmt.format(x)


def _count(k: int, n: int, ci: bool = True) -> str:
    """``k/n (rate %, CI low-high)``."""
    if not n:
        return f"{k}/0"
    text = f"{k}/{n} ({100 * k / n:.1f} %"
    if ci:
        lo, hi = wilson(k, n)
        text += f", {100 * lo:.1f}-{100 * hi:.1f}"
    return text + ")"


def _slugs(inputs: list) -> list:
    """A distinct file-name stem per input (its directory name, made unique)."""
    out, used = [], set()
    for r in inputs:
        base = "".join(c if c.isalnum() or c in "-_." else "_"
                       for c in r.path.resolve().name) or "input"
        slug, n = base, 1
        while slug in used:
            n += 1
            slug = f"{base}-{n}"
        used.add(slug)
        out.append(slug)
    return out


# ------------------------------------------------------------------------ run tables


def _vs_paper(r: pd.Series) -> str:
    """Where our 95 % interval lies wholly above or below the paper's."""
    notes = []
    for col in ("inappropriate", "no_reset"):
        lo, hi = wilson(r[f"paper_{col}"], r["paper_trials"])
        if r["trials"] and r[f"{col}_ci_low"] > hi:
            notes.append(f"{col.replace('_', ' ')} higher")
        elif r["trials"] and r[f"{col}_ci_high"] < lo:
            notes.append(f"{col.replace('_', ' ')} lower")
    return ", ".join(notes) or "consistent"


def _paper_row(r: pd.Series) -> dict:
    """One row of the ours-beside-the-paper table."""
    n = int(r["trials"])
    return {
        "transition": r["label"], "judged": n,
        "inappropriate: ours": _count(int(r["inappropriate"]), n),
        "inappropriate: paper": _count(int(r["paper_inappropriate"]),
                                       int(r["paper_trials"])),
        "no reset: ours": _count(int(r["no_reset"]), n),
        "no reset: paper": _count(int(r["paper_no_reset"]), int(r["paper_trials"])),
        "no reset explained": _num(100 * r["no_reset_explained_share"], "{:.0f} %"),
        "correct block": _count(int(r["correct"]), n, ci=False),
        "reset delay median / p95 [s]":
            f"{_num(r['delay_median_s'])} / {_num(r['delay_p95_s'])}",
        "detection median / p95 [s]":
            f"{_num(r['detection_median_s'])} / {_num(r['detection_p95_s'])}",
        "false-alarm trials": int(r["false_alarm_trials"]),
        "95 % CIs vs paper": _vs_paper(r),
    }


def paper_tables(summary: pd.DataFrame) -> list:
    """Markdown lines: Tables 2-3 beside the paper's, one table per variant."""
    lines = []
    for variant, g in summary.groupby("variant", sort=False):
        lines += [f"#### Signature `{variant}`", "",
                  pd.DataFrame([_paper_row(r) for _, r in g.iterrows()])
                  .to_markdown(index=False), ""]
    lines += ["Counts are `k/n (rate %, 95 % Wilson CI)`, over judged trials only; the "
              "paper's counts are from its Tables 2-3 (one set for both variants). "
              "*95 % CIs vs paper* says where our interval lies wholly above or below "
              "the paper's.", ""]
    return lines


def _exclusion_reason(t: pd.DataFrame, window_end_s: float | None) -> pd.Series:
    """Why each trial of ``t`` (not judged) was excluded."""
    numeric = t["status"].isin(["nonfinite", "covariance_not_psd"])
    early = t["status"].ne("ok") & (t["stop_s"] <= window_end_s + 1e-9
                                    if window_end_s is not None else True)
    stopped = t["status"].where(numeric | early)
    reason = stopped.fillna(pd.Series("resets_truncated", index=t.index)
                            .where(t["resets_truncated"]))
    return reason.fillna("unknown")


def _why(reasons: pd.Series) -> str:
    counts = reasons.value_counts()
    return ", ".join(f"{k} {v}" for k, v in counts.items()) or "-"


def _stopped(r: pd.Series) -> str:
    cols = [c for c in r.index if c.startswith("stopped_")]
    parts = [f"{c[len('stopped_'):]} {int(r[c])}" for c in cols if r[c]]
    return ", ".join(parts) or "-"


def exclusion_table(summary: pd.DataFrame, trials: pd.DataFrame, config: dict) -> list:
    """Markdown lines: excluded trials per transition and variant, and why."""
    timing = config.get("timing", {})
    end = (timing["fault_time_s"] + timing["window_s"]
           if {"fault_time_s", "window_s"} <= timing.keys() else None)
    out = trials[~trials["judged"]]
    reasons = _exclusion_reason(out, end) if len(out) else pd.Series(dtype=object)
    rows = []
    for _, r in summary.iterrows():
        sel = (out["transition"] == r["transition"]) & (out["variant"] == r["variant"])
        if not r["excluded"] and _stopped(r) == "-":
            continue
        rows.append({"transition": r["label"], "signature": r["variant"],
                     "run": int(r["trials"] + r["excluded"]), "excluded": int(r["excluded"]),
                     "why excluded": _why(reasons[sel]),
                     "stopped at any time (stopped_*)": _stopped(r)})
    if not rows:
        return ["No trial was excluded or stopped early.", ""]
    return [pd.DataFrame(rows).to_markdown(index=False), "",
            "A trial is excluded from the rates when it failed numerically, left the "
            "validity envelope before the end of the judging window"
            + (f" ({end:g} s)" if end is not None else "")
            + ", or had more resets than it could store (`resets_truncated`); a trial stopped "
            "after the window still counts.", ""]


# -------------------------------------------------------------------- variant choice


def paired_counts(trials: pd.DataFrame, a: str, b: str, col: str) -> pd.DataFrame:
    """Per transition, ``col`` of variants ``a`` and ``b`` on the same trials.

    Only trials judged in both variants enter.  The p-value is the exact
    McNemar test (binomial test on the discordant pairs).

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
        p = (scipy.stats.binomtest(only_a, only_a + only_b).pvalue
             if only_a + only_b else 1.0)
        rows.append({"transition": name, "n": int(both.sum()), "a": int(x[a].sum()),
                     "b": int(x[b].sum()), "only_a": only_a, "only_b": only_b, "p": p})
    return pd.DataFrame(rows)


def _label(name: str) -> str:
    return TRANSITION_TABLE[name].label if name in TRANSITION_TABLE else name


def _verdict(inap: pd.DataFrame, a: str, b: str) -> str:
    """The sentence naming the better variant, with its numbers."""
    sig = inap[inap["p"] < SIGNIFICANCE]
    a_better = sig[sig["a"] < sig["b"]]
    b_better = sig[sig["b"] < sig["a"]]

    def cite(df):
        return "; ".join(f"{_label(r.transition)}: {r.a}/{r.n} vs {r.b}/{r.n}, "
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
        f"{_label(r.transition)} ({a} {r.a}/{r.n}, {b} {r.b}/{r.n}, p = {r.p:.2g})"
        for r in diff.itertuples()) + "; weigh these against the inappropriate resets.")


def variant_comparison(trials: pd.DataFrame) -> list:
    """Markdown lines: which signature variant is better, from paired trials."""
    variants = list(dict.fromkeys(trials["variant"]))
    if len(variants) != 2:
        return [f"Only the `{'`, `'.join(variants)}` variant was run; nothing to compare.",
                ""]
    a, b = variants
    inap = paired_counts(trials, a, b, "inappropriate")
    nr = paired_counts(trials, a, b, "no_reset")
    table = pd.DataFrame({
        "transition": inap["transition"].map(_label), "paired trials": inap["n"],
        f"inappropriate `{a}`": inap["a"], f"inappropriate `{b}`": inap["b"],
        f"only `{a}`": inap["only_a"], f"only `{b}`": inap["only_b"],
        "McNemar p": inap["p"].map(lambda p: f"{p:.2g}"),
        f"no reset `{a}`": nr["a"], f"no reset `{b}`": nr["b"]})
    return [_verdict(inap, a, b) + " " + _no_reset_note(nr, a, b), "",
            table.to_markdown(index=False), "",
            "Both variants run on the same draws and noise, so the comparison is "
            "paired: trial by trial on the trials judged in both variants, with an exact "
            f"McNemar test (difference called significant at p < {SIGNIFICANCE}).", ""]


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


def delay_figure(trials: pd.DataFrame, path: Path) -> Path:
    """Box plots of ``first_reset_s`` and ``detection_s`` per transition and variant.

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run (judged trials are plotted).
    path : Path
        PNG file, written atomically.

    Returns
    -------
    Path
    """
    from .plots import plt, save

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
                      [_label(n) for n in names], fontsize=8)
    axs[0].invert_yaxis()
    axs[1].legend(loc="best", fontsize=8)
    fig.suptitle("Reset delay and detection time (judged trials; whiskers 5-95 %)")
    return save(fig, path)


# --------------------------------------------------------------------- run section


def plant_condition(cfg: dict) -> tuple:
    """The truth plant of a config: ``(plant.kind, plant.turbulence)``.

    Parameters
    ----------
    cfg : dict
        The config stored in a result's metadata.

    Returns
    -------
    (str, str)
        :data:`DEFAULT_PLANT` for results written before the ``plant`` section
        existed (or a field missing from it).
    """
    plant = cfg.get("plant") or {}
    return (str(plant.get("kind", DEFAULT_PLANT[0])),
            str(plant.get("turbulence", DEFAULT_PLANT[1])))


def _plant_text(cfg: dict) -> str:
    """``truth plant `kind`, turbulence `level``` of a config."""
    kind, turbulence = plant_condition(cfg)
    return f"truth plant `{kind}`, turbulence `{turbulence}`"


def _run_header(cfg: dict) -> str:
    c = cfg.get("campaign", {})
    return (f"{len(c.get('transitions', []))} transition(s), {c.get('trials', '?')} trials "
            f"each, seed {c.get('seed', '?')}, signature `{c.get('signature', '?')}`, "
            f"controller `{cfg.get('controller', {}).get('kind', '?')}`, "
            f"{_plant_text(cfg)}.")


def run_section(r: ResultDir, fig_dir: Path, slug: str, report: Path) -> list:
    """Markdown lines of one run."""
    summary, trials = r.tables["summary"], r.tables["trials"]
    cfg = r.meta.get("config", {})
    fig = delay_figure(trials, fig_dir / f"{slug}_delays.png")
    return ([f"## Run `{r.path}`", "", _run_header(cfg), "",
             "### Tables 2-3: ours beside the paper", ""] + paper_tables(summary)
            + ["### Excluded trials", ""] + exclusion_table(summary, trials, cfg)
            + ["### Which signature variant is better", ""] + variant_comparison(trials)
            + ["### Delay distributions", "", f"![delays of {slug}]({_rel_link(fig, report)})",
               ""])


# ---------------------------------------------------------------- scenario section


def _in_segment(ev: pd.DataFrame, kind: str, t0: float, t1: float) -> pd.DataFrame:
    e = ev[ev["kind"] == kind]
    return e[(e["time_s"] >= t0 - 1e-9) & (e["time_s"] < t1 - 1e-9)]


def _segment_row(s, prev_mode, ev: pd.DataFrame) -> dict:
    """One row of the timeline: what happened after one schedule entry."""
    fault = _in_segment(ev, "fault_switch", s.start_s, s.start_s + 1e-6)
    resets = _in_segment(ev, "reset", s.start_s, s.end_s)["detail"]
    exc = _in_segment(ev, "excitation", s.start_s, s.end_s)
    sw = _in_segment(ev, "controller_switch", s.start_s, s.end_s)
    recovery = (PAPER_TIMELINE["tracking_recovery_s"]
                if prev_mode == "engine" and s.truth_mode == "nominal" else np.nan)
    return {
        "from [s]": f"{s.start_s:g}", "fault": fault["detail"].iloc[0] if len(fault) else "",
        "detection: ours [s]": _num(s.detection_s),
        "detection: paper [s]": _num(s.paper_detection_s),
        "resets thrust / elevons": f"{resets.str.startswith('thrust').sum()} / "
                                   f"{resets.str.startswith('elevons').sum()}",
        "excitations": ", ".join(f"{d} {t:.1f}" for t, d in zip(exc.time_s, exc.detail))
                       or "-",
        "controller switches": ", ".join(f"{t:.0f} s: {d}" for t, d in
                                         zip(sw.time_s, sw.detail)) or "-",
        "max cross-track [m]": _num(s.max_cross_track_m, "{:.2f}"),
        "position recovery: ours [s]": _num(s.position_recovery_s),
        "tracking recovery: paper [s]": _num(recovery),
    }


def timeline_table(segments: pd.DataFrame, events: pd.DataFrame) -> list:
    """Markdown lines: one row per schedule entry, ours beside the paper."""
    prev = [None] + list(segments["truth_mode"][:-1])
    rows = [_segment_row(s, p, events) for s, p in zip(segments.itertuples(), prev)]
    return [pd.DataFrame(rows).to_markdown(index=False), "",
            "Detection: first belief update where the true mode is the most probable "
            "(paper: faults 'in less than 3 s', engine recoveries 8 s and 6 s). Position "
            "recovery: time after the entry from which the distance to the moving "
            "reference point stays below 1 m (paper: tracking recovered 15 s after the "
            "engine recovers). Paper values refer to the schedule of its Table 4.", ""]


def _side_by_side(ours: list, paper: list, what: str) -> str:
    n = max(len(ours), len(paper))
    pad = lambda x: x + ["-"] * (n - len(x))  # noqa: E731
    return pd.DataFrame({"#": range(1, n + 1), f"{what}: ours": pad(ours),
                         f"{what}: paper": pad(paper)}).to_markdown(index=False)


def switches_and_excitations(events: pd.DataFrame) -> list:
    """Markdown lines: controller switches and excitations beside the paper's."""
    sw = events[events["kind"] == "controller_switch"]
    ours = [f"{t:.1f} s ({d})" for t, d in zip(sw.time_s, sw.detail)]
    lines = [_side_by_side(ours, [f"{t:g} s" for t in
                                  PAPER_TIMELINE["controller_switches_s"]],
                           "controller switch"), ""]
    for name, paper in PAPER_EXCITATIONS.items():
        ex = events[(events["kind"] == "excitation") & (events["detail"] == name)]
        lines += [f"`{name}`: ours {len(ex)} at "
                  + (", ".join(f"{t:.1f}" for t in ex.time_s) or "-")
                  + f" s; paper {len(paper)} at {', '.join(f'{t:g}' for t in paper)} s.", ""]
    return lines


def scenario_figures(r: ResultDir, report: Path) -> list:
    """Markdown lines linking the scenario's own PNG figures, if present."""
    figs = sorted(r.path.glob("fig*.png"))
    if not figs:
        return [f"No figures in `{r.path}` (the report does not redraw them).", ""]
    return [line for f in figs for line in (f"![{f.stem}]({_rel_link(f, report)})", "")]


def scenario_section(r: ResultDir, report: Path) -> list:
    """Markdown lines of one scenario."""
    seg, ev = r.tables["segments"], r.tables["events"]
    sc = r.meta.get("config", {}).get("scenario", {})
    details = ev.to_markdown(index=False, floatfmt=".1f")
    return ([f"## Scenario `{r.path}`", "",
             f"Signature `{sc.get('signature', '?')}`, controller "
             f"`{r.meta.get('config', {}).get('controller', {}).get('kind', '?')}`, seed "
             f"{sc.get('seed', '?')}, {sc.get('duration_s', '?')} s, "
             f"{len(sc.get('schedule', []))} schedule entries, "
             f"{_plant_text(r.meta.get('config', {}))}.", "",
             "### Event timeline beside the paper", ""] + timeline_table(seg, ev)
            + ["### Controller switches and excitations", ""] + switches_and_excitations(ev)
            + ["<details><summary>All events</summary>", "", details, "", "</details>", "",
               "### Figures", ""] + scenario_figures(r, report))


# ---------------------------------------------------------------- provenance section


def provenance_section(inputs: list, warning: str | None) -> list:
    """Markdown lines: kind, version, revision, seed and config of every input."""
    rows = [{"directory": str(r.path), "kind": r.kind, "version": r.meta.get("version"),
             "git revision": r.meta.get("git_revision") or "-", "seed": r.meta.get("seed"),
             "files": ", ".join(r.file_meta)} for r in inputs]
    lines = ["## Provenance", ""]
    if warning:
        lines += [f"> **Warning: mixed inputs.** {warning}.", ""]
    lines += [pd.DataFrame(rows).to_markdown(index=False), ""]
    for r in inputs:
        cfg = yaml.safe_dump(r.meta.get("config", {}), sort_keys=False,
                             default_flow_style=None, width=100).rstrip()
        lines += [f"<details><summary>config of <code>{r.path}</code></summary>", "",
                  "```yaml", cfg, "```", "", "</details>", ""]
    return lines


# ------------------------------------------------------------------------- report


def _check_out(out: Path) -> None:
    if out.is_dir():
        raise UserError(f"-o/--output: {out} is a directory; give a Markdown file name")


# ----------------------------------------------------------------------------- sweep


def recommend_threshold(table: pd.DataFrame, variant: str,
                        target: float = FALSE_RESET_TARGET_PER_H):
    """The threshold point a sweep recommends for one signature variant.

    Among the points whose false-reset rate per flight hour is at most
    ``target``, the one with the smallest mean over transitions of the
    inappropriate-reset rate plus the *unexplained* no-reset rate (no-reset
    trials not explained by a small ``b1`` or a lock near trim).  If no point
    meets the target, the point with the fewest false resets.

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
                                         upper=("false_resets_per_hour_ci_high", "first"))
    ok = per[per["false"] <= target]
    if len(ok):
        (tq, tnx), row = ok["cost"].idxmin(), ok.loc[ok["cost"].idxmin()]
        why = (f"lowest mean inappropriate + unexplained no-reset rate "
               f"({100 * row['cost']:.2f} %) among the {len(ok)} points with at most "
               f"{target:g} false resets per flight hour (here {row['false']:.3g}; "
               f"95 % upper bound {row['upper']:.3g} from the flights flown)")
    else:
        (tq, tnx) = per["false"].idxmin()
        row = per.loc[(tq, tnx)]
        why = (f"no point reaches {target:g} false resets per flight hour; this one has "
               f"the fewest ({row['false']:.3g}); more fault-free flights or higher "
               "thresholds are needed")
    return float(tq), float(tnx), why


def sweep_figure(table: pd.DataFrame, path: Path) -> Path:
    """Inappropriate and no-reset rates per transition, and false resets per hour,
    against the threshold (the point index when t_q and t_nx differ)."""
    import matplotlib.pyplot as plt

    from .plots import save

    same = bool((table["t_q"] == table["t_nx"]).all())
    names = list(dict.fromkeys(table["transition"]))
    ncols = 3
    nrows = (len(names) + 1 + ncols - 1) // ncols
    fig, axs = plt.subplots(nrows, ncols, figsize=(12, 3.2 * nrows), squeeze=False)
    pts = table[["t_q", "t_nx"]].drop_duplicates().reset_index(drop=True)
    xkey = {(a, b): (a if same else i) for i, (a, b) in enumerate(zip(pts["t_q"], pts["t_nx"]))}
    styles = {"paper": "-", "swapped": "--"}
    for ax, name in zip(axs.flat, names):
        for variant, g in table[table["transition"] == name].groupby("variant"):
            x = [xkey[(a, b)] for a, b in zip(g["t_q"], g["t_nx"])]
            ls = styles.get(variant, ":")
            ax.plot(x, 100 * g["inappropriate_rate"], "r" + ls, label=f"inappropriate {variant}")
            ax.plot(x, 100 * g["no_reset_rate"], "b" + ls, label=f"no reset {variant}")
        ax.set_title(_label(name), fontsize=9)
        ax.set_ylabel("% of trials")
        ax.grid(alpha=0.3)
    ax = axs.flat[len(names)]
    for variant, g in table.groupby("variant"):
        g = g.drop_duplicates(["t_q", "t_nx"])
        x = [xkey[(a, b)] for a, b in zip(g["t_q"], g["t_nx"])]
        ax.semilogy(x, g["false_resets_per_hour"].clip(lower=1e-3), "k" + styles.get(variant, ":"),
                    label=variant)
    ax.axhline(FALSE_RESET_TARGET_PER_H, color="g", lw=0.8, label="1 per 100 h")
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


def sweep_section(r: ResultDir, fig_dir: Path, slug: str, report: Path) -> list:
    """Report section of one sweep: trade-off plots and the recommended threshold."""
    t = r.tables["sweep"]
    fig = sweep_figure(t, fig_dir / f"{slug}_sweep.png")
    lines = [f"## Sweep `{r.path}`", "",
             f"{t[['t_q', 't_nx']].drop_duplicates().shape[0]} threshold points, "
             f"{t['transition'].nunique()} transition(s), variants "
             f"{', '.join(sorted(t['variant'].unique()))}, "
             f"{_plant_text(r.meta.get('config', {}))}.", "",
             f"![threshold trade-off]({_rel_link(fig, report)})", "",
             "### Recommended threshold", ""]
    for variant in sorted(t["variant"].unique()):
        tq, tnx, why = recommend_threshold(t, variant)
        lines.append(f"- `{variant}`: **t_q = {tq:g}, t_nx = {tnx:g}**: {why}.")
    lines.append("")
    return lines


# ------------------------------------------------------ truth plant and turbulence


def _rank(seq: tuple, value: str) -> int:
    """Position of ``value`` in ``seq``; unknown values after the known ones."""
    return seq.index(value) if value in seq else len(seq)


def condition_order(conditions: list) -> list:
    """Indices of ``conditions`` in report order.

    :data:`DEFAULT_PLANT` first, then by plant kind (:data:`PLANT_KINDS`), then
    by turbulence (:data:`TURBULENCE_LEVELS`); ties keep the input order.

    Parameters
    ----------
    conditions : list of (str, str)
        ``(kind, turbulence)`` of each run.

    Returns
    -------
    list of int
    """
    def key(i):
        kind, turbulence = conditions[i]
        return (conditions[i] != DEFAULT_PLANT, _rank(PLANT_KINDS, kind), kind,
                _rank(TURBULENCE_LEVELS, turbulence), turbulence, i)
    return sorted(range(len(conditions)), key=key)


def condition_labels(conditions: list, slugs: list) -> list:
    """``kind / turbulence`` of each run, with its slug when the condition repeats."""
    out = []
    for cond, slug in zip(conditions, slugs):
        label = " / ".join(cond)
        out.append(f"{label} ({slug})" if conditions.count(cond) > 1 else label)
    return out


def reference_index(conditions: list) -> int:
    """The reference run: the first with :data:`DEFAULT_PLANT`, else the first."""
    return conditions.index(DEFAULT_PLANT) if DEFAULT_PLANT in conditions else 0


def _fault_time_s(cfg: dict) -> float:
    """``timing.fault_time_s`` of a config (the default if absent)."""
    return float(cfg.get("timing", {}).get(
        "fault_time_s", TimingConfig.model_fields["fault_time_s"].default))


def _median(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.median(v)) if len(v) else np.nan


def condition_rates(trials: pd.DataFrame, fault_time_s: float) -> pd.DataFrame:
    """Rates of one run per transition and signature variant, over judged trials.

    Parameters
    ----------
    trials : DataFrame
        ``trials.parquet`` of a run.
    fault_time_s : float
        Fault-free flight before the switch in every trial [s]: the exposure
        of ``false_resets``.

    Returns
    -------
    DataFrame
        ``transition, variant, judged, excluded, inappropriate_pct,
        no_reset_pct, false_resets, flight_hours, false_per_h, false_per_h_low,
        false_per_h_high, delay_median_s, detection_median_s``; the
        false-reset interval is the exact (Garwood) Poisson 95 % interval.
    """
    rows = []
    for (name, variant), g in trials.groupby(["transition", "variant"], sort=False):
        ok = g[g["judged"].astype(bool)]
        n, k = len(ok), int(ok["false_resets"].sum())
        hours = n * fault_time_s / 3600.0
        lo, hi = poisson_ci(k, hours) if n else (np.nan, np.nan)
        rows.append({
            "transition": name, "variant": variant, "judged": n, "excluded": len(g) - n,
            "inappropriate_pct": 100 * ok["inappropriate"].mean() if n else np.nan,
            "no_reset_pct": 100 * ok["no_reset"].mean() if n else np.nan,
            "false_resets": k, "flight_hours": hours,
            "false_per_h": k / hours if n else np.nan,
            "false_per_h_low": lo, "false_per_h_high": hi,
            "delay_median_s": _median(ok["first_reset_s"]),
            "detection_median_s": _median(ok["detection_s"])})
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
    conds : list of (str, str)
        Their conditions (:func:`plant_condition`).
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


def _per_hour(x: float) -> str:
    """A rate per flight hour: three significant digits, whole numbers from 1000."""
    if x is None or not np.isfinite(x):
        return "-"
    return f"{x:,.0f}" if x >= 1000 else f"{x:.3g}"


def _delta(r: pd.Series, col: str) -> str:
    return "ref" if r["reference"] else _num(r[f"d_{col}_pp"], "{:+.1f}")


def _plant_row(r: pd.Series) -> dict:
    """One row of the plant-comparison table."""
    return {
        "transition": _label(r["transition"]), "signature": r["variant"],
        "condition": r["condition"], "judged": int(r["judged"]),
        "inappropriate [%]": _num(r["inappropriate_pct"]),
        "no reset [%]": _num(r["no_reset_pct"]),
        "false resets / flight h (95 % CI)":
            f"{_per_hour(r['false_per_h'])} ({_per_hour(r['false_per_h_low'])}-"
            f"{_per_hour(r['false_per_h_high'])})" if r["judged"] else "-",
        "first reset median [s]": _num(r["delay_median_s"]),
        "detection median [s]": _num(r["detection_median_s"]),
        "Δ inappropriate [pp]": _delta(r, "inappropriate"),
        "Δ no reset [pp]": _delta(r, "no_reset"),
    }


def _excluded_note(runs: list, labels: list, order: list) -> str:
    """One sentence: how many trials of each condition were not judged, and why."""
    parts = []
    for i in order:
        trials = runs[i].tables["trials"]
        timing = runs[i].meta.get("config", {}).get("timing", {})
        end = (timing["fault_time_s"] + timing["window_s"]
               if {"fault_time_s", "window_s"} <= timing.keys() else None)
        out = trials[~trials["judged"].astype(bool)]
        why = f" ({_why(_exclusion_reason(out, end))})" if len(out) else ""
        parts.append(f"`{labels[i]}` {len(out)} of {len(trials)}{why}")
    return ("Trials excluded from the rates (not judged), by condition: "
            + "; ".join(parts) + ". In turbulence many trials can leave the validity "
            "envelope before the end of the judging window; they enter no column above, "
            "so compare the judged counts too.")


def _comparable(cfg: dict) -> dict:
    """``cfg`` without the ``plant`` section and :data:`IGNORED_CAMPAIGN_KEYS`."""
    out = {k: v for k, v in cfg.items() if k != "plant"}
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
            f"{', '.join(f'`{d}`' for d in diff)}** (besides `plant` and "
            f"`campaign.{'`/`campaign.'.join(IGNORED_CAMPAIGN_KEYS)}`): the changes "
            "below need not come from the plant alone.", ""]


def _figure_variant(rates: pd.DataFrame) -> str:
    variants = list(dict.fromkeys(rates["variant"]))
    return "swapped" if "swapped" in variants else variants[0]


def plant_figure(rates: pd.DataFrame, variant: str, path: Path) -> Path:
    """Grouped bars: inappropriate and no-reset rates per transition and condition.

    Parameters
    ----------
    rates : DataFrame
        :func:`plant_rates`.
    variant : str
        The signature variant drawn.
    path : Path
        PNG file, written atomically.

    Returns
    -------
    Path
    """
    from .plots import plt, save

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
                      [_label(n).replace(" → ", "\n→ ") for n in names], fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3, axis="y")
    axs[0].set_ylabel("% of judged trials")
    axs[1].legend(fontsize=7, title="plant / turbulence", title_fontsize=7)
    fig.suptitle(f"Truth plant and turbulence (signature {variant})")
    return save(fig, path)


def plant_conditions_differ(runs: list) -> bool:
    """True if at least two runs differ in (plant kind, turbulence)."""
    return len({plant_condition(r.meta.get("config", {})) for r in runs}) >= 2


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
    configs = [r.meta.get("config", {}) for r in runs]
    conds = [plant_condition(c) for c in configs]
    labels = condition_labels(conds, slugs)
    ref = reference_index(conds)
    rates = plant_rates(runs, conds, labels)
    variant = _figure_variant(rates)
    fig = plant_figure(rates, variant, fig_dir / PLANT_FIGURE)
    return (["## Truth plant and turbulence", "",
             f"{len(runs)} runs, one condition each (plant / turbulence); reference "
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
               f"![truth plant and turbulence]({_rel_link(fig, report)})", ""])


def build_report(dirs: list, out: Path, allow_mixed: bool = False) -> Path:
    """Write one Markdown report of run and scenario directories.

    Parameters
    ----------
    dirs : list of Path
        Directories written by ``ftc-mc run`` or ``ftc-mc scenario``, in any mix;
        only their Parquet files are read.
    out : Path
        The Markdown file, written atomically.  Figures go to
        ``<out stem>_figures/`` beside it.  When at least two runs differ in truth
        plant or turbulence, a section compares them (:func:`plant_section`).
    allow_mixed : bool
        Build the report even if the inputs come from different package versions
        or git revisions (a warning is added to the report).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    UserError
        No input, an input without results, or mixed provenance without
        ``allow_mixed``.  Nothing is written then.
    """
    out = Path(out)
    _check_out(out)
    if not dirs:
        raise UserError("no input directories given")
    inputs = [load_result_dir(d) for d in _unique_dirs(dirs)]
    warning = check_provenance(inputs, allow_mixed)
    fig_dir = out.parent / f"{out.stem}_figures"
    lines = ["# ftc-mc report", "",
             f"Built from the Parquet files of {len(inputs)} result director"
             f"{'y' if len(inputs) == 1 else 'ies'}; rebuild it at any time with "
             "`ftc-mc report`.", ""]
    if warning:
        lines += [f"> **Warning: mixed inputs.** {warning}.", ""]
    slugs = _slugs(inputs)
    for r, slug in zip(inputs, slugs):
        if r.kind == "run":
            lines += run_section(r, fig_dir, slug, out)
        elif r.kind == "sweep":
            lines += sweep_section(r, fig_dir, slug, out)
        else:
            lines += scenario_section(r, out)
    runs = [(r, slug) for r, slug in zip(inputs, slugs) if r.kind == "run"]
    if plant_conditions_differ([r for r, _ in runs]):
        lines += plant_section([r for r, _ in runs], [s for _, s in runs], fig_dir, out)
    lines += provenance_section(inputs, warning)
    write_text(out, "\n".join(lines))
    return out
