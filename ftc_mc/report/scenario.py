"""The report section of one scenario (``ftc-mc scenario``).

The event timeline beside the paper's (section 5.2, :data:`ftc_mc.paper.PAPER_TIMELINE`),
the controller switches and excitations beside the paper's, every event, and
links to the scenario's own figures (the report does not redraw them).  The
names of the controllers flown are the ones ``ftc-mc scenario`` recorded in the
files' metadata (:func:`recorded_controller_names`), never rebuilt from the
config.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..paper import PAPER_EXCITATIONS, PAPER_TIMELINE
from .load import ResultDir
from .markdown import controller_of, num, plant_text, rel_link


GENERIC_CONTROLLER_NAMES = ("c0", "c1", "c2", "c3")
"""Names of the controller codes of a scenario written before the names were
recorded: the codes alone (the paper's three, or four with a
``lock_turn_selected`` design; which, the result does not say)."""


def recorded_controller_names(meta: dict) -> tuple:
    """The names of the controller codes a scenario flew, as recorded.

    Parameters
    ----------
    meta : dict
        The ``ftc_mc`` metadata of a scenario's Parquet file.

    Returns
    -------
    (tuple of str, bool)
        The names, indexed by controller code, and whether they were recorded;
        a result written before ``ftc-mc scenario`` recorded them gets
        :data:`GENERIC_CONTROLLER_NAMES` and False (the report does not
        rebuild them from the config: today's code may name them otherwise
        than the code that flew).
    """
    names = meta.get("controller_names")
    if names:
        return tuple(names), True
    return GENERIC_CONTROLLER_NAMES, False


def controller_line(meta: dict) -> str:
    """The sentence naming the controllers a scenario flew (:func:`recorded_controller_names`)."""
    names, recorded = recorded_controller_names(meta)
    listed = ", ".join(f"`{n}`" for n in names)
    if recorded:
        return f"Controllers flown (recorded with the result): {listed}."
    return (f"Controllers flown: {listed} (codes only: the result was written before "
            "`ftc-mc scenario` recorded their names).")


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
        "detection: ours [s]": num(s.detection_s),
        "detection: paper [s]": num(s.paper_detection_s),
        "resets thrust / elevons": f"{resets.str.startswith('thrust').sum()} / "
                                   f"{resets.str.startswith('elevons').sum()}",
        "excitations": ", ".join(f"{d} {t:.1f}" for t, d in zip(exc.time_s, exc.detail))
                       or "-",
        "controller switches": ", ".join(f"{t:.0f} s: {d}" for t, d in
                                         zip(sw.time_s, sw.detail)) or "-",
        "max cross-track [m]": num(s.max_cross_track_m, "{:.2f}"),
        "position recovery: ours [s]": num(s.position_recovery_s),
        "tracking recovery: paper [s]": num(recovery),
    }


def timeline_table(segments: pd.DataFrame, events: pd.DataFrame) -> list:
    """Markdown lines: one row per schedule entry, ours beside the paper.

    Parameters
    ----------
    segments, events : DataFrame
        ``segments.parquet`` and ``events.parquet`` of a scenario (times [s]).

    Returns
    -------
    list of str
    """
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
    """Markdown lines: controller switches and excitations beside the paper's.

    Parameters
    ----------
    events : DataFrame
        ``events.parquet`` of a scenario (``time_s`` [s], ``kind``, ``detail``).

    Returns
    -------
    list of str
    """
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
    return [line for f in figs for line in (f"![{f.stem}]({rel_link(f, report)})", "")]


def scenario_section(r: ResultDir, report: Path) -> list:
    """Markdown lines of one scenario.

    Parameters
    ----------
    r : ResultDir
        A scenario directory.
    report : Path
        The report file (for the relative links).

    Returns
    -------
    list of str
    """
    seg, ev = r.tables["segments"], r.tables["events"]
    sc = r.meta.get("config", {}).get("scenario", {})
    details = ev.to_markdown(index=False, floatfmt=".1f")
    return ([f"## Scenario `{r.path}`", "",
             (f"Design `{sc['design']}`, controller " if sc.get("design") else
              f"Signature `{sc.get('signature', '?')}`, controller ") +
             f"`{controller_of(r.meta.get('config', {}), sc.get('design'))}`, seed "
             f"{sc.get('seed', '?')}, {sc.get('duration_s', '?')} s, "
             f"{len(sc.get('schedule', []))} schedule entries, "
             f"{plant_text(r.meta.get('config', {}))}.", "", controller_line(r.meta), "",
             "### Event timeline beside the paper", ""] + timeline_table(seg, ev)
            + ["### Controller switches and excitations", ""] + switches_and_excitations(ev)
            + ["<details><summary>All events</summary>", "", details, "", "</details>", "",
               "### Figures", ""] + scenario_figures(r, report))
