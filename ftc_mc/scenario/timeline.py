"""The paper's scenario timeline (section 5.2) and ours beside it in Markdown."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .run import ScenarioResult




def summary_markdown(res: ScenarioResult) -> str:
    """Our timeline beside the paper's, event by event."""
    seg = res.segments.copy()
    ev = res.events
    design = res.config.scenario.design or res.config.scenario.signature
    lines = ["# ftc-mc scenario", "",
             f"Design: `{design}`; controller: "
             f"`{res.config.controller_of(design)}`; seed {res.config.scenario.seed}; "
             f"truth plant `{res.config.plant.kind}`, turbulence "
             f"`{res.config.plant.turbulence}`; run status: `{res.status}`.", "",
             "## Detection of each schedule entry", ""]
    tab = seg[["start_s", "truth_mode", "detection_s", "paper_detection_s",
               "max_cross_track_m", "max_along_track_m", "cross_track_recovery_s",
               "position_recovery_s"]]
    lines.append(tab.to_markdown(index=False, floatfmt=".2f"))
    lines += ["", "Paper: faults detected in less than 3 s, engine recoveries in 8 s "
              "and 6 s; `detection_s` is ours (first belief update where the true mode "
              f"is the most probable with at least {res.config.scenario.detection_probability}"
              "); `cross_track_recovery_s` and `position_recovery_s` are the times after "
              "the entry from which the distance to the glide path, and to the moving "
              "reference point, stay below 1 m (paper: tracking recovered 15 s after the "
              "engine recovers; with the paper's Q_lqr the along-track error is weighted by "
              "tan^2(gamma) only, so the UAV is 'late but almost on the desired slope').",
              "",
              "## Controller switches", ""]
    sw = ev[ev.kind == "controller_switch"]
    lines.append(sw[["time_s", "detail"]].to_markdown(index=False, floatfmt=".1f")
                 if len(sw) else "No switch: c0 throughout.")
    lines += ["", "Paper: c1 at 11 s (before the engine fault is detected at 13 s; the "
              "text also says the controller changes at 12 s once it is), "
              "c1 kept after the engine recovers (the penalty outweighs the gain), "
              "c2 at 91 s.", "", "## Excitations and resets", ""]
    ex = ev[ev.kind == "excitation"]
    lines.append(ex[["time_s", "detail"]].to_markdown(index=False, floatfmt=".1f")
                 if len(ex) else "No excitation.")
    rs = ev[ev.kind == "reset"]
    lines += ["", f"{len(rs)} covariance resets ({(rs.detail.str.startswith('thrust')).sum()} "
              f"thrust, {(rs.detail.str.startswith('elevons')).sum()} elevons).", "",
              "Paper: the doublet was sent six times (10 s, 12.6 s, 15.6 s, 30 s, 50 s, "
              "70 s), the 3211 once (90 s).", ""]
    return "\n".join(lines)
