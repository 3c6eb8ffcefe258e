"""Benchmark of a threshold sweep against running its points one by one.

A 20-point sweep (``--thresholds 5:100:5``) over the eight transitions of
configs/paper_tables.yaml, both signature variants, with ``--jobs 2``; then the
same 20 points as separate campaigns (``run_campaign`` per point) in the same
process.  Prints both wall times, their ratio and the trial steps the sharing
saved.  The nominal controller is used by default (``--controller``).

Usage: ``python scripts/benchmarks/bench_sweep.py [--trials N] [--points SPEC]``.
Last line: ``sweep_wall_s=<x> separate_wall_s=<y> ratio=<y/x> steps_saved=<f>``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--points", default="5:100:5")
    ap.add_argument("--controller", default="nominal", choices=["nominal", "reconfiguring"])
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()

    import ftc_mc
    from ftc_mc.campaign.sweep import run_sweep, threshold_points
    from ftc_mc.config import load_config, with_overrides

    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    cfg = with_overrides(cfg, campaign={"trials": args.trials},
                         controller={"kind": args.controller})
    points = threshold_points(args.points)
    ftc_mc.run_campaign(with_overrides(cfg, campaign={"trials": 2}), jobs=1,
                        progress=False)  # compile / load kernels first
    t = time.perf_counter()
    res = run_sweep(cfg, points, jobs=args.jobs, progress=False)
    sweep_wall = time.perf_counter() - t
    t = time.perf_counter()
    for tq, tnx in points:
        ftc_mc.run_campaign(with_overrides(cfg, estimator={"t_q": tq, "t_nx": tnx}),
                            jobs=args.jobs, progress=False)
    separate_wall = time.perf_counter() - t
    print(f"{len(points)} points x {len(cfg.campaign.transitions)} transitions x "
          f"{args.trials} trials x 2 variants, controller {args.controller}, "
          f"--jobs {args.jobs}")
    print(f"sweep (shared trials, plus {args.trials} fault-free flights per point): "
          f"{sweep_wall:8.1f} s")
    print(f"the points as separate runs (no fault-free flights):         "
          f"{separate_wall:8.1f} s")
    print(f"trial steps simulated {res.simulated_steps:,} of {res.alone_steps:,} "
          f"unshared ({100 * res.saving:.1f} % saved)")
    print(f"sweep_wall_s={sweep_wall:.2f} separate_wall_s={separate_wall:.2f} "
          f"ratio={separate_wall / sweep_wall:.2f} steps_saved={res.saving:.3f}")


if __name__ == "__main__":
    main()
