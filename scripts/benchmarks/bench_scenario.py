"""Benchmark of `ftc-mc scenario configs/paper_scenario.yaml`.

Prints:

* offline design (``build_setup`` of the scenario config: trim,
  linearisation, LQR, the Theorem 4.1 engine tables and the terminal costs
  J^N), cold and cached.  Cold runs in a fresh interpreter whose design cache
  (``FTC_MC_CACHE_DIR``) is an empty temporary folder, so the engine tables are
  solved; cached is the second call in that interpreter (tables read from
  disk, J^N recomputed: it is not cached).  The Numba cache is warm in both, so
  neither includes compilation; the split tables / J^N is printed too;
* the 100 s paper scenario after compilation, median of ``--repeat`` runs:
  the kernel alone (``run_trials`` with the inputs built once, exactly as
  ``run_scenario`` builds them), ``run_scenario`` with a prebuilt setup
  (kernel plus inputs and the time series, events and segments tables), and
  ``run_scenario`` building its setup (design cached); the writing of the
  files and figures is timed once;
* the ratio to the paper's 7 s in Matlab R2014b (section 5.2).

Targets: kernel under 0.05 s; offline design under 30 s cold, 1 s cached.
The last line is
``scenario_kernel_s=<x> scenario_total_s=<y> design_cold_s=<z> design_cached_s=<w>``
with ``scenario_total_s`` the median of ``run_scenario(sc, setup=prebuilt)``.
Usage: ``python scripts/benchmarks/bench_scenario.py [--repeat N] [--config PATH]``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PAPER_MATLAB_S = 7.0

DESIGN = """
import json, sys, time
t0 = time.perf_counter()
import numpy as np
from ftc_mc.config import load_scenario
from ftc_mc.design.lqr import paper_q_lqr
from ftc_mc.design.terminal import terminal_costs
from ftc_mc.cache.engine_tables import cached_engine_tables
from ftc_mc.sim.setup import build_setup
import_s = time.perf_counter() - t0
cfg = load_scenario(sys.argv[1])
out = {"import_s": import_s}
for name in ("cold", "cached"):
    t = time.perf_counter()
    s = build_setup(cfg)
    out[name] = time.perf_counter() - t
# the parts, with the tables cached (J^N is recomputed on every build_setup)
c = cfg.controller
Q = paper_q_lqr(s.plant.trim.gamma0)
R = c.r_lqr * np.eye(3)
t = time.perf_counter()
eng = cached_engine_tables(s.plant, Q=Q, R=R, alpha=c.discount)
out["tables_cached"] = time.perf_counter() - t
t = time.perf_counter()
terminal_costs(s.fm, s.ctl.K, eng, s.ctl.lo_dev, s.ctl.hi_dev, c.discount,
               np.ascontiguousarray(np.diag(Q)), np.ascontiguousarray(np.diag(R)),
               cfg.steps(c.terminal_horizon_s))
out["jn"] = time.perf_counter() - t
print(json.dumps(out))
"""


def design_times(config: Path) -> dict:
    """Cold and cached ``build_setup`` in a fresh interpreter with an empty design cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, FTC_MC_CACHE_DIR=cache)
        res = subprocess.run([sys.executable, "-c", DESIGN, str(config)], cwd=ROOT,
                             env=env, check=True, capture_output=True, text=True)
        files = list(Path(cache).rglob("*.npz"))
    out = json.loads(res.stdout.strip().splitlines()[-1])
    out["cache_files"] = len(files)
    return out


def kernel_inputs(sc, setup):
    """The kernel inputs of ``run_scenario`` (same code path, built once)."""
    from ftc_mc.sim.inputs import scenario_inputs

    return scenario_inputs(setup, sc.scenario)


def median_time(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), min(times), max(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--config", type=Path, default=ROOT / "configs" / "paper_scenario.yaml")
    args = ap.parse_args()

    import numpy as np

    from ftc_mc.config import load_scenario
    from ftc_mc.io.results import provenance
    from ftc_mc.scenario import run_scenario, write_scenario
    from ftc_mc.sim.lanes import HISTORY_RESETS, new_record, run_trials
    from ftc_mc.sim.setup import build_setup

    sc = load_scenario(args.config)
    t = time.perf_counter()
    setup = build_setup(sc)  # warms the Numba cache of the design
    first_setup_s = time.perf_counter() - t
    t = time.perf_counter()
    ref = run_scenario(sc, setup=setup)  # compiles (or loads) the kernel
    first_run_s = time.perf_counter() - t

    design = design_times(args.config)

    inp = kernel_inputs(sc, setup)
    det = setup.det[sc.scenario.signature]
    recs = [new_record(setup, 1, HISTORY_RESETS, history=True) for _ in range(args.repeat)]
    it = iter(recs)

    def kernel():
        run_trials(setup.scheme(sc.scenario.signature, det), setup.flight, inp, next(it))

    kernel_s, kernel_min, kernel_max = median_time(kernel, args.repeat)
    # the timed kernel is the one run_scenario runs
    assert np.array_equal(recs[-1].hist_x[:, 0, 0], ref.timeseries.u_true.to_numpy())
    total_s, total_min, total_max = median_time(lambda: run_scenario(sc, setup=setup),
                                                args.repeat)
    with_design_s, _, _ = median_time(lambda: run_scenario(sc), max(3, args.repeat // 4))
    with tempfile.TemporaryDirectory() as out:
        meta = provenance(ref.config.model_dump(mode="json"), ref.config.scenario.seed,
                          "scenario")
        t = time.perf_counter()
        write_scenario(ref, Path(out) / "s", meta)
        write_s = time.perf_counter() - t

    n = setup.tim.n_steps
    print(f"scenario {args.config.name}: {sc.scenario.duration_s:g} s, {n} steps, "
          f"{len(sc.scenario.schedule)} schedule entries, status {ref.status}")
    print(f"first build_setup in this process (warm caches): {first_setup_s:8.3f} s")
    print(f"first run_scenario (kernel compile or cache load): {first_run_s:8.3f} s")
    print(f"offline design cold  (empty FTC_MC_CACHE_DIR, {design['cache_files']} table file "
          f"written): {design['cold']:8.3f} s   [target < 30 s]")
    print(f"offline design cached (second build_setup):          {design['cached']:8.3f} s"
          f"   [target < 1 s]")
    print(f"  of which engine tables read from cache {design['tables_cached']:.3f} s, "
          f"J^N terminal costs {design['jn']:.3f} s; import {design['import_s']:.2f} s")
    print(f"kernel run_trials, median of {args.repeat}: {kernel_s * 1e3:8.2f} ms "
          f"(min {kernel_min * 1e3:.2f}, max {kernel_max * 1e3:.2f}; "
          f"{n / kernel_s / 1e3:.0f} k steps/s)   [target < 50 ms]")
    print(f"run_scenario(setup=prebuilt), median of {args.repeat}: {total_s * 1e3:8.2f} ms "
          f"(min {total_min * 1e3:.2f}, max {total_max * 1e3:.2f})")
    print(f"run_scenario incl. build_setup (cached tables):  {with_design_s * 1e3:8.2f} ms")
    print(f"write_scenario (3 Parquet files, 7 figures, summary.md): {write_s:8.3f} s")
    print(f"paper (Matlab R2014b, 100 s scenario): {PAPER_MATLAB_S:g} s -> kernel "
          f"{PAPER_MATLAB_S / kernel_s:.0f}x faster, run_scenario "
          f"{PAPER_MATLAB_S / total_s:.0f}x faster, with design cached "
          f"{PAPER_MATLAB_S / with_design_s:.0f}x faster")
    print(f"scenario_kernel_s={kernel_s:.4g} scenario_total_s={total_s:.4g} "
          f"design_cold_s={design['cold']:.4g} design_cached_s={design['cached']:.4g}")


if __name__ == "__main__":
    main()
