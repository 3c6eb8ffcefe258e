"""The paper's Figs. 6-12 for one scenario (``ftc-mc scenario``)."""

from __future__ import annotations

from pathlib import Path

from .figure import plt, save


def _switch_lines(ax, res):
    for e in res.config.scenario.schedule[1:]:
        ax.axvline(e.time_s, color="0.6", lw=0.8, ls=":")


def scenario_figures(res, out: Path) -> list:
    """Figures like the paper's Figs. 6-12 for a :class:`ScenarioResult`.

    Parameters
    ----------
    res : ftc_mc.scenario.ScenarioResult
        One flight: its time series (time [s], errors [m], fault parameters,
        residuals, beliefs, controller, commands), its config (schedule) and
        the names of the controllers it flew (``controller_names``, as recorded:
        Fig. 11 labels its codes with them, nothing is rebuilt from the config).
    out : Path
        Folder of the PNG files (``fig06_trajectory.png`` ... ``fig12_commands.png``).

    Returns
    -------
    list of Path
    """
    ts = res.timeseries
    t = ts.time_s
    paths = []

    fig, axs = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    axs[0].plot(t, ts.x_true, label="x error (along the path) [m]")
    axs[0].plot(t, -ts.z_true, label="-z error (height) [m]")
    axs[0].set_ylabel("tracking error [m]")
    axs[1].plot(t, ts.x_true, label="x tracking error")
    axs[1].plot(t, ts.x_est_error_m, "--", label="x estimation error")
    axs[1].set_ylabel("x [m]")
    axs[2].plot(t, ts.z_true, label="z tracking error")
    axs[2].plot(t, ts.z_est_error_m, "--", label="z estimation error")
    axs[2].set_ylabel("z (down) [m]")
    axs[2].set_xlabel("time [s]")
    for ax in axs:
        _switch_lines(ax, res)
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle("Fig. 6: trajectory, tracking and estimation errors")
    paths.append(save(fig, out / "fig06_trajectory.png"))

    for name, params, title, fname in (
            ("thrust", ("b0_thrust", "b1_thrust"), "Fig. 7: thrust fault parameters",
             "fig07_thrust_b.png"),
            ("elevons", ("b0_elevons", "b1_left", "b1_right"),
             "Fig. 8: elevon fault parameters", "fig08_elevon_b.png")):
        fig, axs = plt.subplots(len(params), 1, figsize=(8, 2.6 * len(params)), sharex=True)
        for ax, p in zip(axs, params):
            ax.plot(t, ts[f"{p}_true"], "k", lw=1.2, label="truth")
            ax.plot(t, ts[f"{p}_est"], label="estimate")
            ax.fill_between(t, ts[f"{p}_est"] - 2 * ts[f"{p}_sd"],
                            ts[f"{p}_est"] + 2 * ts[f"{p}_sd"], alpha=0.2, label="±2 sd")
            ax.set_ylabel(p)
            _switch_lines(ax, res)
            ax.grid(alpha=0.3)
            ax.legend(loc="best", fontsize=8)
        axs[-1].set_xlabel("time [s]")
        fig.suptitle(title)
        paths.append(save(fig, out / fname))

    fig, axs = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for ax, (r, thr) in zip(axs, (("r_q", "t_q"), ("r_nx", "t_nx"), ("r_nz", None))):
        ax.semilogy(t, ts[r].clip(lower=1e-6), lw=0.8, label=r)
        if thr:
            ax.semilogy(t, ts[thr], "r--", label=thr)
        ax.set_ylabel(r)
        _switch_lines(ax, res)
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axs[-1].set_xlabel("time [s]")
    fig.suptitle("Fig. 9: residuals and thresholds")
    paths.append(save(fig, out / "fig09_residuals.png"))

    fig, ax = plt.subplots(figsize=(8, 3.5))
    for m in ("nominal", "engine", "left_elevon", "right_elevon"):
        ax.plot(t, ts[f"belief_{m}"], label=m)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("probability")
    ax.set_xlabel("time [s]")
    _switch_lines(ax, res)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title("Fig. 10: mode probabilities")
    paths.append(save(fig, out / "fig10_belief.png"))

    fig, ax = plt.subplots(figsize=(8, 2.8))
    ax.step(t, ts.controller + 1, where="post")
    names = res.controller_names
    ax.set_yticks(range(1, len(names) + 1), [f"{i + 1} {n.split(' ', 1)[-1]}"
                                               for i, n in enumerate(names)])
    ax.set_xlabel("time [s]")
    _switch_lines(ax, res)
    ax.grid(alpha=0.3)
    ax.set_title("Fig. 11: selected controller")
    paths.append(save(fig, out / "fig11_controller.png"))

    fig, axs = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for ax, c in zip(axs, ("throttle", "elevon_left", "elevon_right")):
        ax.plot(t, ts[f"cmd_{c}_dev"], lw=0.9)
        ax.set_ylabel(f"{c} - trim")
        _switch_lines(ax, res)
        ax.grid(alpha=0.3)
    axs[-1].set_xlabel("time [s]")
    fig.suptitle("Fig. 12: commands (difference from trim)")
    paths.append(save(fig, out / "fig12_commands.png"))
    if "phi_true" in ts:  # the 6-DOF plant: its lateral motion
        paths.append(lateral_figure(res, out / "fig13_lateral.png"))
    return paths


LATERAL_PANELS = (("phi_true", "bank [deg]", True), ("p_true", "roll rate [deg/s]", True),
                  ("psi_true", "heading [deg]", True), ("y_true", "cross-track y [m]", False))
"""Panels of :func:`lateral_figure`: column, label, shown in degrees."""


def lateral_figure(res, path: Path) -> Path:
    """Bank, roll rate, heading and lateral position of a 6-DOF scenario
    (deviations from trim; the columns of
    :data:`ftc_mc.scenario.run.LATERAL_COLUMNS`), with the validity's bank
    bound."""
    import numpy as np

    ts = res.timeseries
    t = ts.time_s
    fig, axs = plt.subplots(len(LATERAL_PANELS), 1, figsize=(8, 8.5), sharex=True)
    for ax, (col, ylabel, deg) in zip(axs, LATERAL_PANELS):
        ax.plot(t, np.degrees(ts[col]) if deg else ts[col], lw=0.9)
        ax.set_ylabel(ylabel)
        _switch_lines(ax, res)
        ax.grid(alpha=0.3)
    bound = res.config.validity.bank_max_deg
    for b in (-bound, bound):
        axs[0].axhline(b, color="r", ls="--", lw=0.8)
    axs[-1].set_xlabel("time [s]")
    fig.suptitle("Fig. 13 (6-DOF): bank, roll rate, heading and lateral position")
    return save(fig, path)
