"""Figures of the paper scenario's engine recoveries (feeds ``docs/findings/recoveries.md``).

Runs ``configs/paper_scenario.yaml`` (or the config given) and draws, from 25 s
to the end: the thrust's b1 and b0, true and estimated (with the estimate's
standard deviation), the throttle command, and the belief of the nominal and
engine modes, with the nominal box of the engine (b1 < beta_engine,
|b0| < b0_nominal_engine).  Prints the times the belief returns to nominal.

``--reset-scale S`` also flies the scenario's design with its covariance reset
``S`` times wider (the design field ``reset_scale``) and draws it dashed.

``--seeds N`` draws a second figure (``-o`` with ``_seeds`` before the
suffix) over the seeds 0..N-1: the distribution of the two recovery times
under the paper's reset (and ``S``), and the engine's b1 estimate 2 s after the
recovery at 70 s (the end of its one doublet) against the reset's scale, with
the shrinkage a Gaussian prior of the reset's variance gives (text).

Usage: ``python scripts/studies/figure_recoveries.py [CONFIG] [--plant P] [--turbulence T]
[--reset-scale S] [--seeds N] [-o docs/figures/recoveries.png]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]

SCALES = (1.0, 2.0, 4.0, 9.0, 25.0, 52.08)
"""Reset scales of the seeds figure's last panel (52.08 = 25^2/12: a uniform
distribution over each parameter's range at t = 25)."""


def with_scale(sc, scale):
    """``sc`` flying its design with ``reset_scale`` = ``scale`` (1: ``sc``)."""
    from ftc_mc.config import ScenarioConfig

    if scale == 1.0:
        return sc
    d = sc.model_dump()
    base = (d["designs"].get(d["scenario"]["design"], {}) if d["scenario"]["design"]
            else {"signature": d["scenario"]["signature"]})
    d["designs"]["wide_reset"] = {**base, "reset_scale": scale}
    d["scenario"]["design"] = "wide_reset"
    return ScenarioConfig.model_validate(d)


def back_to_nominal(ts, start, end=None):
    """Seconds from ``start`` to the first sample with the nominal mode the most
    probable at >= 0.5 before ``end``; NaN if none."""
    t = ts.time_s.to_numpy()
    sel = (t > start + 1e-9) & (t <= (end if end is not None else t[-1]) + 1e-9)
    hit = sel & (ts.belief_nominal.to_numpy() >= 0.5)
    return float(t[np.argmax(hit)] - start) if hit.any() else np.nan


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="?", default=str(ROOT / "configs" / "paper_scenario.yaml"))
    ap.add_argument("--plant")
    ap.add_argument("--turbulence")
    ap.add_argument("--reset-scale", type=float, default=None)
    ap.add_argument("--seeds", type=int, default=0)
    ap.add_argument("-o", "--output", default=str(ROOT / "docs" / "figures" / "recoveries.png"))
    args = ap.parse_args()

    import ftc_mc
    from ftc_mc.api import scenario_config
    from ftc_mc.plots.figure import plt, save

    sc = scenario_config(args.config, plant=args.plant, turbulence=args.turbulence)
    runs = [("paper's reset", sc)]
    if args.reset_scale is not None:
        runs.append((f"reset x {args.reset_scale:g}", with_scale(sc, args.reset_scale)))
    beta, b0box = sc.estimator.beta_engine, sc.estimator.b0_nominal_engine
    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for i, (label, s) in enumerate(runs):
        ts = ftc_mc.run_scenario(s).timeseries
        t = ts[ts.time_s >= 25.0]
        ls, col = ("-", "C0") if i == 0 else ("--", "C3")
        for a, key, box in ((ax[0], "b1_thrust", (0.0, beta)), (ax[1], "b0_thrust", (-b0box, b0box))):
            if i == 0:
                a.plot(t.time_s, t[f"{key}_true"], "k", lw=1.5, label="true")
                a.axhspan(*box, color="g", alpha=0.12, label="nominal box")
            a.plot(t.time_s, t[f"{key}_est"], col, ls=ls, label=f"estimate, {label}")
            a.fill_between(t.time_s, t[f"{key}_est"] - 2 * t[f"{key}_sd"],
                           t[f"{key}_est"] + 2 * t[f"{key}_sd"], color=col, alpha=0.15)
            a.set_ylabel(key.replace("_", " "))
            a.legend(loc="upper right", fontsize=7)
        ax[2].plot(t.time_s, t.cmd_throttle, col, ls=ls, label=f"throttle command, {label}")
        if i == 0:
            ax[2].plot(t.time_s, t.excitation_doublet, "C1", lw=0.8, label="doublet")
        ax[3].plot(t.time_s, t.belief_nominal, col, ls=ls, label=f"nominal, {label}")
        ax[3].plot(t.time_s, t.belief_engine, "C1", ls=ls, label=f"engine, {label}")
        for start, end in ((30.0, 50.0), (70.0, 90.0)):
            back = back_to_nominal(ts, start, end)
            print(f"{label}: recovery at {start:g} s: belief back to nominal after "
                  + (f"{back:.1f} s" if np.isfinite(back) else f"not before {end:g} s"))
    ax[2].set_ylabel("throttle [-]")
    ax[2].legend(loc="upper right", fontsize=7)
    ax[3].set_ylabel("belief")
    ax[3].set_xlabel("time [s]")
    ax[3].legend(loc="center right", fontsize=7)
    for a in ax:
        for x in (30, 50, 70, 90):
            a.axvline(x, color="grey", lw=0.6, ls=":")
    fig.suptitle(f"Engine recoveries at 30 s and 70 s: plant {sc.plant.kind}, "
                 f"turbulence {sc.plant.turbulence}, seed {sc.scenario.seed}")
    out = Path(args.output)
    save(fig, out)
    print(f"wrote {out}")
    if args.seeds:
        seeds_figure(sc, args.seeds, args.reset_scale, out.with_name(f"{out.stem}_seeds{out.suffix}"))


def seeds_figure(sc, n, scale, path):
    """Recovery times over the seeds ``0..n-1`` and the b1 estimate 2 s after the
    recovery at 70 s against the reset's scale."""
    from ftc_mc.plots.figure import plt, save
    from ftc_mc.scenario.run import run_scenario
    from ftc_mc.sim.setup import build_setup

    scales = sorted(set(SCALES) | ({scale} if scale else set()))
    res = {}
    for s in scales:
        cfg = with_scale(sc, s)
        setup = build_setup(cfg)
        rows = []
        for seed in range(n):
            ts = run_scenario(cfg, seed=seed, setup=setup).timeseries
            k72 = int(np.searchsorted(ts.time_s.to_numpy(), 72.0))
            rows.append((back_to_nominal(ts, 30.0, 50.0), back_to_nominal(ts, 70.0, 90.0),
                         ts.b1_thrust_est[k72], ts.b1_thrust_est[int(np.searchsorted(
                             ts.time_s.to_numpy(), 69.95))]))
        res[s] = np.array(rows)
        r = res[s]
        print(f"reset x {s:g}: back to nominal after 30 s: median {np.nanmedian(r[:, 0]):.1f} s, "
              f"p90 {np.nanpercentile(r[:, 0], 90):.1f} s, none {np.isnan(r[:, 0]).sum()}/{n}; "
              f"after 70 s: median {np.nanmedian(r[:, 1]):.1f} s, "
              f"p90 {np.nanpercentile(r[:, 1], 90):.1f} s, none by 90 s {np.isnan(r[:, 1]).sum()}/{n}; "
              f"b1 at 72 s median {np.median(r[:, 2]):.3f}")
    fig, ax = plt.subplots(1, 3, figsize=(14, 4.2))
    fig.subplots_adjust(wspace=0.3)
    shown = [1.0] + ([scale] if scale and scale != 1.0 else [])
    for a, j, start, paper in ((ax[0], 0, 30, 8.0), (ax[1], 1, 70, 6.0)):
        for s, col in zip(shown, ("C0", "C3")):
            v = res[s][:, j]
            x = np.sort(np.where(np.isfinite(v), v, 21.0))
            a.step(x, np.arange(1, n + 1) / n, where="post", color=col,
                   label=f"reset x {s:g} ({np.isnan(v).sum()} of {n} not within 20 s)")
        a.axvline(paper, color="k", ls=":", label=f"paper: {paper:g} s")
        a.set_xlim(0, 21)
        a.set_xlabel(f"back to nominal after the {start} s recovery [s]")
        a.set_ylabel("fraction of seeds")
        a.legend(fontsize=7, loc="lower right")
    # b1 2 s after the 70 s recovery (the doublet's end) against the reset's scale
    b1 = np.array([np.median(res[s][:, 2]) for s in scales])
    pre = np.median(res[1.0][:, 3])
    p1 = 1.0 / (1.0 / sc.estimator.t_nx ** 2)  # the paper's b1 prior precision at scale 1
    data = p1 * (pre / b1[0] - 1.0)  # the doublet's precision that fits scale 1
    grid = np.geomspace(scales[0], scales[-1], 50)
    ax[2].semilogx(scales, b1, "o", color="C0", label="median over seeds")
    ax[2].semilogx(grid, pre * (p1 / grid) / (p1 / grid + data), "k--", lw=1,
                   label=f"prior N({pre:.2f}, var x scale / {sc.estimator.t_nx:g}^2) + "
                         f"data of precision {data:.0f}")
    ax[2].axhline(sc.estimator.beta_engine, color="g", ls=":", label="beta_engine")
    ax[2].set_xlabel("reset_scale")
    ax[2].set_ylabel("engine b1 estimate at 72 s (truth 0)")
    ax[2].set_ylim(0.0, 0.3)
    ax[2].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Paper scenario, seeds 0-{n - 1}: engine recoveries")
    save(fig, path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
