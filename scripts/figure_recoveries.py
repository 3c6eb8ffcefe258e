"""Figure of the paper scenario's engine recoveries (docs/recoveries.md, issue 25).

Runs ``configs/paper_scenario.yaml`` (or the config given) and draws, from 25 s
to the end: the thrust's b1 and b0, true and estimated (with the estimate's
standard deviation), the throttle command, and the belief of the nominal and
engine modes, with the nominal box of the engine (b1 < beta_engine,
|b0| < b0_nominal_engine).  Prints the times the belief returns to nominal.

Usage: ``python scripts/figure_recoveries.py [CONFIG] [--plant P] [--turbulence T]
[-o docs/figures/recoveries.png]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="?", default=str(ROOT / "configs" / "paper_scenario.yaml"))
    ap.add_argument("--plant")
    ap.add_argument("--turbulence")
    ap.add_argument("-o", "--output", default=str(ROOT / "docs" / "figures" / "recoveries.png"))
    args = ap.parse_args()

    import ftc_mc
    from ftc_mc.api import scenario_config
    from ftc_mc.plots.figure import plt, save

    sc = scenario_config(args.config, plant=args.plant, turbulence=args.turbulence)
    ts = ftc_mc.run_scenario(sc).timeseries
    t = ts[ts.time_s >= 25.0]
    beta, b0box = sc.estimator.beta_engine, sc.estimator.b0_nominal_engine
    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for a, key, box in ((ax[0], "b1_thrust", (0.0, beta)), (ax[1], "b0_thrust", (-b0box, b0box))):
        a.plot(t.time_s, t[f"{key}_true"], "k", lw=1.5, label="true")
        a.plot(t.time_s, t[f"{key}_est"], "C0", label="estimate")
        a.fill_between(t.time_s, t[f"{key}_est"] - 2 * t[f"{key}_sd"],
                       t[f"{key}_est"] + 2 * t[f"{key}_sd"], color="C0", alpha=0.2,
                       label="estimate +- 2 sd")
        a.axhspan(*box, color="g", alpha=0.12, label="nominal box")
        a.set_ylabel(key.replace("_", " "))
        a.legend(loc="upper right", fontsize=7)
    ax[2].plot(t.time_s, t.cmd_throttle, "C1", label="throttle command")
    ax[2].plot(t.time_s, t.excitation_doublet, "C3", lw=0.8, label="doublet")
    ax[2].set_ylabel("throttle [-]")
    ax[2].legend(loc="upper right", fontsize=7)
    ax[3].plot(t.time_s, t.belief_nominal, "g", label="nominal")
    ax[3].plot(t.time_s, t.belief_engine, "C1", label="engine")
    ax[3].plot(t.time_s, t.belief_left_elevon, "C4", label="left elevon")
    ax[3].set_ylabel("belief")
    ax[3].set_xlabel("time [s]")
    ax[3].legend(loc="center right", fontsize=7)
    for a in ax:
        for x in (30, 50, 70, 90):
            a.axvline(x, color="grey", lw=0.6, ls=":")
    fig.suptitle(f"Engine recoveries at 30 s and 70 s: plant {sc.plant.kind}, "
                 f"turbulence {sc.plant.turbulence}")
    save(fig, Path(args.output))
    for start in (30.0, 70.0):
        after = ts[(ts.time_s > start) & (ts.time_s < start + 20) & (ts.belief_nominal >= 0.5)]
        back = f"{after.time_s.iloc[0] - start:.1f} s" if len(after) else "not within 20 s"
        print(f"recovery at {start:g} s: belief back to nominal after {back}")
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
