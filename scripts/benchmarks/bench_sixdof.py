"""Steps per second of the 6-DOF nonlinear plant against the longitudinal one.

Times the nonlinear truth plants alone, one thread: ``--lanes`` trajectories of
``--steps`` control periods (dt = 0.1 s, 10 RK4 sub-steps each, commands and
wind held), from the trim of ``x8-pyfly`` with small random commands and wind,
each plant's own ``propagate`` kernel called from one compiled loop (the way the
trial kernel calls the longitudinal one per lane).  Median of ``--repeat``
after a warm-up call.  With ``--trial`` it also times the longitudinal
nonlinear plant's full trial (``scripts/benchmarks/bench_truth.py``'s measure: filter,
controllers and classification included), the reference of the 6-DOF plant's speed target
(6-DOF plant at least 0.5x the longitudinal nonlinear plant's trial steps/s);
that compiles the trial kernel when it is not cached (1.5-3 min).

With ``--campaign N`` it also times the reconfiguring 6-DOF campaign's speed: the reconfiguring
6-DOF campaign, ``configs/sixdof_tables.yaml``'s twelve rows with the design
``sixdof`` alone (the paper's filter and loop, the side monitor, the lock-turn
law; ``--design sixdof_selected``: the selection among the four 6-DOF
controllers instead), ``N`` trials per row, ``--jobs 2``, on the linear 6-DOF plant (the
setting of its target) and on the nonlinear one, each after a small warm-up run of
the same path (its compile and the lock-turn designs are not timed): trial
steps per second of the whole ``api.run_campaign`` call (setup, trials, summary).

Usage::

    .venv/bin/python scripts/benchmarks/bench_sixdof.py [--lanes 128] [--steps 500] [--repeat 5] [--trial]
        [--campaign 500] [--design sixdof_selected]

The last line is ``longitudinal_plant_steps_per_s=<a> sixdof_plant_steps_per_s=<b>
ratio=<b/a>`` (and ``longitudinal_trial_steps_per_s=<c> sixdof_vs_trial=<b/c>``
with ``--trial``, ``campaign_linear_trial_steps_per_s=<d>
campaign_nonlinear_trial_steps_per_s=<e>`` with ``--campaign``).
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from ftc_mc.core.longitudinal import nonlinear as lon  # noqa: E402
from ftc_mc.core.sixdof import plant as six  # noqa: E402
from ftc_mc.model.dynamics import pack_parameters as pack_lon  # noqa: E402
from ftc_mc.model.linear import trim  # noqa: E402
from ftc_mc.model.presets import PRESETS  # noqa: E402
from ftc_mc.model.sixdof import trim6  # noqa: E402

DT = 0.1
N_SUB = 10


@numba.njit(cache=False, nogil=True)
def run_longitudinal(x0, cmds, p, winds, dt, n_sub):
    """Every lane through every step with the longitudinal ``propagate``."""
    work = lon.make_work()
    acc = 0.0
    for lane in range(cmds.shape[0]):
        x = x0.copy()
        for k in range(cmds.shape[1]):
            lon.propagate(x, cmds[lane, k], p, winds[lane, k], dt, n_sub, work)
        acc += x[0]
    return acc


@numba.njit(cache=False, nogil=True)
def run_sixdof(x0, cmds, p, winds, dt, n_sub):
    """Every lane through every step with the 6-DOF ``propagate``."""
    work = np.zeros((six.N_WORK, x0.shape[0]))
    acc = 0.0
    for lane in range(cmds.shape[0]):
        x = x0.copy()
        for k in range(cmds.shape[1]):
            six.propagate(x, cmds[lane, k], p, winds[lane, k], dt, n_sub, work)
        acc += x[0]
    return acc


def steps_per_s(fn, args, n_steps, repeat):
    fn(*args)  # compile
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - t)
    return n_steps / statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lanes", type=int, default=128)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--trial", action="store_true",
                    help="also time the longitudinal nonlinear plant's full trial")
    ap.add_argument("--campaign", type=int, default=0, metavar="N",
                    help="also time the reconfiguring 6-DOF campaign, N trials per row")
    ap.add_argument("--design", default="sixdof",
                    help="the campaign's design (sixdof_tables.yaml's designs section; "
                         "sixdof_selected: the selection among four controllers)")
    args = ap.parse_args()
    af = PRESETS["x8-pyfly"].airframe
    rng = np.random.default_rng(24)
    n = args.lanes * args.steps

    tp = trim(af, 20.0, -3.0)
    p = pack_lon(af, 20.0, math.radians(-3.0))
    cmds = tp.u0 + rng.uniform(-0.01, 0.01, (args.lanes, args.steps, 3))
    winds = rng.uniform(-0.2, 0.2, (args.lanes, args.steps, 3)) * [1.0, 1.0, 0.01]
    r_lon = steps_per_s(run_longitudinal, (tp.x0, cmds, p, winds, DT, N_SUB), n,
                        args.repeat)

    tp6 = trim6(af)
    cmds6 = tp6.u0 + rng.uniform(-0.001, 0.001, (args.lanes, args.steps, 3))
    winds6 = rng.uniform(-0.05, 0.05, (args.lanes, args.steps, 6)) * \
        [1.0, 1.0, 1.0, 0.01, 0.01, 0.01]
    r_six = steps_per_s(run_sixdof, (tp6.x0, cmds6, tp6.params, winds6, DT, N_SUB), n,
                        args.repeat)

    print(f"one thread, {args.lanes} lanes x {args.steps} steps of {DT} s, {N_SUB} RK4 "
          f"sub-steps, x8-pyfly, plant alone")
    print(f"{'plant':>14} {'states':>6} {'plant steps/s':>14} {'vs longitudinal':>16}")
    print(f"{'longitudinal':>14} {lon.N_STATE:>6} {r_lon:14.4g} {1.0:16.3f}")
    print(f"{'6-DOF':>14} {six.N_STATE:>6} {r_six:14.4g} {r_six / r_lon:16.3f}")
    line = (f"longitudinal_plant_steps_per_s={r_lon:.4g} sixdof_plant_steps_per_s="
            f"{r_six:.4g} ratio={r_six / r_lon:.3f}")
    if args.trial:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from bench_truth import trials_per_s

        trials, n_steps = trials_per_s("nonlinear", "none", "nominal", args.lanes,
                                       max(1, args.repeat // 2))
        r_trial = trials * n_steps
        print(f"longitudinal nonlinear plant, full trial (bench_truth, nominal "
              f"controller, both variants): {r_trial:.4g} trial steps/s")
        line += (f" longitudinal_trial_steps_per_s={r_trial:.4g} "
                 f"sixdof_vs_trial={r_six / r_trial:.3f}")
    if args.campaign:
        for kind in ("linear", "nonlinear"):
            rate, wall = campaign_steps_per_s(kind, args.campaign, args.design)
            print(f"reconfiguring 6-DOF campaign (sixdof_tables.yaml, design {args.design}, "
                  f"{kind} plant, {args.campaign} trials x 12 rows, --jobs 2): "
                  f"{wall:.1f} s, {rate:.4g} trial steps/s")
            line += f" campaign_{kind}_trial_steps_per_s={rate:.4g}"
    print(line)


def campaign_steps_per_s(kind, trials, design="sixdof"):
    """Trial steps per second of ``configs/sixdof_tables.yaml`` with the design
    ``design`` on the ``kind`` 6-DOF plant, ``trials`` per row, two workers,
    after a warm-up run of 2 trials per row; and the wall time [s]."""
    from ftc_mc import api

    config = str(Path(__file__).resolve().parents[2] / "configs" / "sixdof_tables.yaml")
    common = dict(design=[design], plant=kind, jobs=2, progress=False)
    api.run_campaign(config, trials=2, **common)
    t = time.perf_counter()
    res = api.run_campaign(config, trials=trials, **common)
    wall = time.perf_counter() - t
    cfg = api.campaign_config(config, trials=trials, design=[design], plant=kind)
    steps = len(res.trials) * int(round(cfg.timing.duration_s / cfg.model.dt_s))
    return steps / wall, wall


if __name__ == "__main__":
    main()
