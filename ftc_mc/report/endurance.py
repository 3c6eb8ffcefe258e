"""The report section of an endurance run (``ftc-mc endurance``), and the
endurance rows a sweep's operating characteristic uses.

Per design: the fault-free flight hours, the false resets, their rate per hour
with the exact two-sided 95 % interval, the one-sided 95 % upper bound a
false-alarm target is checked against, and whether the target is shown (else
the hours that would show it); the false resets in the first seconds of a flight
(the filters' start-up) and a histogram of the false resets' times from the
flight's start.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd

from ..config.load import as_current
from ..config.schema import WEIGHT_SCALES, ControllerConfig, DesignConfig, EstimatorConfig
from .load import ResultDir
from .markdown import controller_of, plant_text, weights_of

THRESHOLDS = ("t_q", "t_nx")


def _definition(cfg: dict, design: str) -> str:
    """The design ``design`` of a stored config as JSON, without its thresholds: a
    key of ``designs``, or a built-in one (the ``estimator`` section), resolved by
    the current schema, with the controller it flies (its own, else the
    ``controller`` section's kind) and its LQR weights (with their scales)."""
    own = cfg.get("designs", {}).get(design)
    d = dict(as_current(DesignConfig, own) if own
             else as_current(EstimatorConfig, cfg.get("estimator", {})))
    for t in THRESHOLDS:
        d.pop(t, None)
    d["controller"] = controller_of(cfg, design)
    d["weights"] = weights_of(cfg, design)
    if d["weights"] != "paper":
        c = as_current(ControllerConfig, cfg.get("controller", {}))
        d["weight_scales"] = {f: c.get(f) for f in WEIGHT_SCALES}
    return json.dumps(d, sort_keys=True)


def _condition(cfg: dict) -> tuple:
    plant = cfg.get("plant", {})
    return (plant.get("kind"), plant.get("turbulence"), cfg.get("model", {}).get("airframe"))


def matching_endurance(endurance_dirs, sweep_cfg: dict) -> pd.DataFrame | None:
    """The rows of ``endurance.parquet`` of ``endurance_dirs`` flown in the sweep's
    condition (truth plant, turbulence, airframe) by a design defined as in the
    sweep (every field but the thresholds, which must then equal a sweep point:
    :func:`ftc_mc.report.operating.endurance_hours`); None when there are none."""
    rows = []
    for r in endurance_dirs:
        cfg = r.meta.get("config", {})
        if _condition(cfg) != _condition(sweep_cfg):
            continue
        t = r.tables["endurance"]
        keep = [_definition(cfg, v) == _definition(sweep_cfg, v) for v in t["variant"]]
        rows.append(t[np.asarray(keep, dtype=bool)])
    rows = [t for t in rows if len(t)]
    return pd.concat(rows, ignore_index=True) if rows else None


def _fmt(x, f="{:.3g}") -> str:
    return "-" if not np.isfinite(x) else f.format(x)


def endurance_table(summary: pd.DataFrame) -> str:
    """The per-design table of an endurance run, in Markdown: a detector's rows
    (``ftc-mc score``) have no thresholds (``-``), and one that read the truth is
    marked an oracle."""
    from .runs import reads_truth
    oracle = reads_truth(summary).to_numpy()
    view = pd.DataFrame({
        "design": [f"{v} (oracle: read the truth)" if o else v
                   for v, o in zip(summary["variant"], oracle)],
        "t_q / t_nx": [f"{_fmt(a, '{:g}')} / {_fmt(b, '{:g}')}"
                       if np.isfinite(a) or np.isfinite(b) else "-"
                       for a, b in zip(summary["t_q"], summary["t_nx"])],
        "flights (judged)": [f"{a} ({b})" for a, b in zip(summary["flights"],
                                                         summary["judged"])],
        "flight hours": summary["flight_hours"].map("{:.4g}".format),
        "false resets": summary["false_resets"],
        "per flight h (95 % CI)": [
            f"{_fmt(r)} ({_fmt(lo)}-{_fmt(hi)})" for r, lo, hi in
            zip(summary["false_resets_per_hour"], summary["false_resets_per_hour_ci_low"],
                summary["false_resets_per_hour_ci_high"])],
        "one-sided 95 % bound / h": summary["false_resets_per_hour_upper95"].map(_fmt),
        "in the first 5 s": summary["early_false_resets"],
        "target": [f"shown (<= {t:g} / h)" if s else
                   f"**not shown** (<= {t:g} / h): {h:.0f} h would show it"
                   + (" (none seen: 3.0 / target)" if k == 0 else " if no further one came")
                   for s, h, t, k in zip(summary["target_shown"], summary["hours_to_show"],
                                         summary["target_per_h"], summary["false_resets"])],
    })
    return view.to_markdown(index=False)


def endurance_section(r: ResultDir, fig_dir, slug: str, report) -> list:
    """Report section of one endurance directory: the table and the histogram of
    the false resets' times from the flight's start."""
    from ..plots.endurance import endurance_figure  # matplotlib only when drawing
    from .markdown import rel_link

    s = r.tables["endurance"]
    cfg = r.meta.get("config", {})
    flight_s = float(s["flight_s"].iloc[0]) if len(s) else np.nan
    lines = [f"## Endurance `{r.path}`", "",
             f"Fault-free flights of {flight_s:g} s, every design on the same flights, "
             f"{plant_text(cfg)}. Every reset of a fault-free flight is a false reset. A "
             "false-alarm target counts as shown only when the one-sided 95 % upper bound "
             "of the rate meets it; with no false reset seen that bound is 3.0 / hours "
             "(-ln 0.05), so 300 h show 0.01 per hour.", "",
             endurance_table(s), ""]
    resets = r.tables.get("false_resets")
    if resets is not None and len(resets):
        path = endurance_figure(resets, flight_s, fig_dir / f"{slug}_endurance.png")
        lines += [f"![false resets by time from the flight's start]({rel_link(path, report)})",
                  ""]
    return lines
