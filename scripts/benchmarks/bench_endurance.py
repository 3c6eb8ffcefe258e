"""Benchmark of an endurance run: fault-free flight hours flown per minute.

Design ``robust`` of configs/robust_moderate.yaml (nonlinear X8, moderate
turbulence, reconfiguring controller, 50 s flights) flies ``--hours`` fault-free
flight hours with ``--jobs`` workers (threads), after one warm-up flight that
compiles or loads the kernels.  Prints the wall time, the flights, and the
flight hours per minute of wall time, and per minute of CPU time (on a
machine shared with other work the wall time says less).  Target: at least 100 flight
hours per minute on 2 cores.

Usage: ``python scripts/benchmarks/bench_endurance.py [--hours H] [--jobs N] [--design NAME]``.
Last line: ``endurance_hours_per_min=<x>``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=50.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--design", default="robust")
    args = ap.parse_args()

    from ftc_mc.api import campaign_config
    from ftc_mc.campaign.endurance import run_endurance

    cfg = campaign_config(ROOT / "configs" / "robust_moderate.yaml", design=[args.design])
    run_endurance(cfg, cfg.timing.duration_s / 3600, jobs=1, progress=False)  # warm up
    t, cpu = time.perf_counter(), time.process_time()
    res = run_endurance(cfg, args.hours, jobs=args.jobs, progress=False)
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    s = res.summary.iloc[0]
    print(f"design {args.design}: {int(s['flights'])} flights of {s['flight_s']:g} s, "
          f"{s['flight_hours']:.1f} flight hours judged, {int(s['false_resets'])} false "
          f"resets; {wall:.1f} s wall on {args.jobs} jobs ({os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}); {cpu:.1f} s of CPU, i.e. "
          f"{args.hours / (cpu / 60):.1f} flight hours per CPU minute (a shared machine: "
          "times the cores for an idle one)")
    print(f"endurance_hours_per_min={args.hours / (wall / 60):.1f}")


if __name__ == "__main__":
    main()
