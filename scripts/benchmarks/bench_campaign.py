"""Benchmark of `ftc-mc run configs/paper_tables.yaml`.

Prints, for the full reproduction (1000 trials per transition, 8 transitions,
both signature variants, 500 steps each):

* cold compile: a fresh interpreter with an empty Numba cache compiling every
  campaign kernel (``NUMBA_CACHE_DIR`` pointed at an empty folder);
* cached start: ``ftc-mc run configs/elevon_lock.yaml`` end to end in a new
  process with the cache warm;
* wall time and trial steps per second with ``--jobs 1`` and ``--jobs 2``
  (one trial step = plant, controller, filter and logic for one 0.1 s period),
  for the nominal controller c0 and for the reconfiguring loop (the default,
  which adds the rolling-horizon controller selection every second).

* the cold compile that ``configs/robust_moderate.yaml``'s paths add once the
  default path is cached (its ``robust`` design: nonlinear plant, extended
  filter, GLR test; and the paper's ``swapped`` on the nonlinear plant), in the
  same empty cache;
The last line is ``trial_steps_per_s=<x> reconf_trial_steps_per_s=<r> wall_s=<y>
compile_s=<z> compile_robust_s=<c>``: trial steps per second with --jobs 2 for
the nominal controller (the estimation campaign of Tables 2-3, ``x``, with its
wall time ``y``) and for the reconfiguring loop (``r``), the cold compile time
of the default path (``z``) and the compile the robust config adds (``c``).
Usage: ``python scripts/benchmarks/bench_campaign.py [--trials N] [--skip-cold]``;
``--skip-cold`` measures only the trial speeds (the kernels cached by an
earlier run), and the last line then reports ``compile_s=nan
compile_robust_s=nan``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
WARM = ("from ftc_mc.config import load_config; "
        "from ftc_mc.campaign.chunk import chunk_spec, warm_up; "
        "c = load_config('configs/{}'); "
        "warm_up(chunk_spec(c), c.campaign.transitions[0])")


def timed(cmd, env=None):
    t = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def cold_parts(py):
    """The cold compiles (empty cache) and the cached starts: ``import_s,
    compile_s, compile_robust_s, cached_robust_s, cached_start_s,
    cached_start_nominal_s`` [s]."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        import_s = timed([py, "-c", "import ftc_mc.campaign.runner"], env)
        cold_s = timed([py, "-c", WARM.format("paper_tables.yaml")], env)
        robust_s = timed([py, "-c", WARM.format("robust_moderate.yaml")], env)
        cached_robust_s = timed([py, "-c", WARM.format("robust_moderate.yaml")], env)
    compile_s = cold_s - import_s
    compile_robust_s = robust_s - cached_robust_s  # minus the setup and the trials
    timed([py, "-c", WARM.format("paper_tables.yaml")])  # the normal cache warm
    with tempfile.TemporaryDirectory() as out:
        cached_start_s = timed([py, "-m", "ftc_mc", "run", "configs/elevon_lock.yaml",
                                "--out", str(Path(out) / "r"), "--quiet"])
        cached_start_nominal_s = timed([py, "-m", "ftc_mc", "run", "configs/elevon_lock.yaml",
                                        "--out", str(Path(out) / "n"), "--quiet",
                                        "--controller", "nominal"])
    return (import_s, compile_s, compile_robust_s, cached_robust_s, cached_start_s,
            cached_start_nominal_s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--skip-cold", action="store_true",
                    help="skip the cold compiles and the cached starts: trial speeds only")
    args = ap.parse_args()
    py = sys.executable
    if args.skip_cold:
        import_s = compile_s = compile_robust_s = cached_robust_s = float("nan")
        cached_start_s = cached_start_nominal_s = float("nan")
        timed([py, "-c", WARM.format("paper_tables.yaml")])  # the normal cache warm
        with tempfile.TemporaryDirectory() as out:  # and the nominal controller's path
            timed([py, "-m", "ftc_mc", "run", "configs/elevon_lock.yaml", "--out",
                   str(Path(out) / "n"), "--quiet", "--controller", "nominal"])
    else:
        import_s, compile_s, compile_robust_s, cached_robust_s, cached_start_s, \
            cached_start_nominal_s = cold_parts(py)

    import ftc_mc
    from ftc_mc.config import load_config, with_overrides

    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    n_steps = cfg.steps(cfg.timing.duration_s)
    variants = 2 if cfg.campaign.signature == "both" else 1
    steps = args.trials * len(cfg.campaign.transitions) * variants * n_steps
    rows = {}
    for kind in ("nominal", "reconfiguring"):
        ck = with_overrides(cfg, controller={"kind": kind})
        for jobs in (1, 2):
            t = time.perf_counter()
            ftc_mc.run_campaign(ck, trials=args.trials, jobs=jobs, progress=False)
            wall = time.perf_counter() - t
            rows[kind, jobs] = (wall, steps / wall)
    print(f"paper_tables.yaml: {args.trials} trials x {len(cfg.campaign.transitions)} "
          f"transitions x {variants} variants x {n_steps} steps = {steps:,} trial steps")
    print(f"cold compile (empty cache, minus {import_s:.2f} s import): {compile_s:8.2f} s")
    print(f"robust_moderate.yaml's paths added to it (minus its cached start "
          f"{cached_robust_s:.2f} s):   {compile_robust_s:8.2f} s")
    print(f"cached start, ftc-mc run configs/elevon_lock.yaml:   {cached_start_s:8.2f} s "
          f"(--controller nominal: {cached_start_nominal_s:.2f} s)")
    for (kind, jobs), (wall, rate) in rows.items():
        print(f"{kind:>14} --jobs {jobs}: wall {wall:7.2f} s   {rate / 1e6:6.3f} M trial steps/s")
    for kind in ("nominal", "reconfiguring"):
        print(f"{kind}: jobs 2 / jobs 1 speed-up {rows[kind, 1][0] / rows[kind, 2][0]:.2f}x")
    wall, rate = rows["nominal", 2]
    reconf_rate = rows["reconfiguring", 2][1]
    print(f"trial_steps_per_s={rate:.4g} reconf_trial_steps_per_s={reconf_rate:.4g} "
          f"wall_s={wall:.3f} compile_s={compile_s:.2f} compile_robust_s={compile_robust_s:.2f}")


if __name__ == "__main__":
    main()
