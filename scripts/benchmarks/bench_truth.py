"""Trials per second on each truth plant, same process.

For every (plant, turbulence) pair of ``--plants`` the script times
``ftc_mc.campaign.chunk.run_chunk`` -- drawing the trials, running both
signature variants and classifying them, exactly what one campaign worker
does -- on one chunk of ``--lanes`` elevon-lock and engine-loss trials with the
default 50 s timing, in one thread, after a warm-up call, median of
``--repeat``.  The linear still-air plant (the paper's setting) is the
reference every ratio is taken against.  ``--controller`` picks the nominal
controller (the Tables 2-3 estimation campaign) or the reconfiguring loop.

Usage::

    .venv/bin/python scripts/benchmarks/bench_truth.py [--lanes 128] [--repeat 3]

Then the detection designs (``DESIGNS``) on the nonlinear plant in
moderate turbulence, each run alone on the same chunk: the paper's filter
(``swapped``), the gust-aware filter (18 states, linear prediction) and the
extended filter (the airframe predicts), with the one-step or the GLR test, and
the sensor-aware design (the paper's filter with three sensor biases:
17 states on the general filter); ratios against ``swapped``.

The last line is ``linear_trials_per_s=<a> nonlinear_trials_per_s=<b>
nonlinear_moderate_trials_per_s=<c> ratio=<a/b> sixdof_trials_per_s=<d>
sixdof_vs_nonlinear=<d/b>`` (nominal controller unless told otherwise; the last
ratio has a target: the 6-DOF nonlinear plant's full trial against the
longitudinal nonlinear one's, target at least 0.5).
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from ftc_mc.campaign.chunk import chunk_spec, run_chunk  # noqa: E402
from ftc_mc.config import Config  # noqa: E402

PLANTS = (("linear", "none", 3), ("nonlinear", "none", 3), ("linear", "moderate", 3),
          ("nonlinear", "moderate", 3), ("nonlinear", "none", 6), ("nonlinear", "moderate", 6))
"""(plant, turbulence, degrees of freedom) timed; the 6-DOF rows fly the 6-DOF
flying wing with its lateral loop."""
TRANSITIONS = ("elevon_lock", "engine_loss")

DESIGNS = {
    "swapped": None,
    "gust_one_step": {"estimator": "gust_aware", "test": "one_step"},
    "gust_glr": {"estimator": "gust_aware", "test": "glr", "window_s": 2.0},
    "extended_glr": {"estimator": "gust_aware", "prediction": "nonlinear", "test": "glr",
                     "window_s": 2.0},
    "sensor_aware": {"sensor_biases": ["q", "n_x", "n_z"], "settle_s": 3.0},
}
"""Designs timed on the nonlinear plant in moderate turbulence (``swapped``: the
paper's filter, the reference)."""


def trials_per_s(kind, turbulence, controller, lanes, repeat, design=None, dof=3):
    """Median trials/s of one chunk per transition (both variants count as trials;
    with ``design``, that design alone)."""
    campaign = {"transitions": list(TRANSITIONS), "signature": "both"}
    designs = {}
    if design is not None:
        name, dc = design
        if dc is None:
            campaign["signature"] = name
        else:
            campaign.update(signature="none", designs=[name])
            designs = {name: dc}
    cfg = Config.model_validate({
        "campaign": campaign, "designs": designs,
        "controller": {"kind": controller},
        "plant": {"kind": kind, "turbulence": turbulence, "dof": dof}})
    spec = chunk_spec(cfg)
    ids = np.arange(lanes)

    def once():
        for name in TRANSITIONS:
            run_chunk(spec, name, ids)

    once()  # compile or load from the cache
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        once()
        times.append(time.perf_counter() - t)
    n_trials = lanes * len(TRANSITIONS) * (2 if design is None else 1)
    return n_trials / statistics.median(times), cfg.steps(cfg.timing.duration_s)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lanes", type=int, default=128)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--controller", choices=("nominal", "reconfiguring"), default="nominal")
    args = ap.parse_args()
    rows = {}
    for kind, turb, dof in PLANTS:
        rows[kind, turb, dof], n_steps = trials_per_s(kind, turb, args.controller,
                                                      args.lanes, args.repeat, dof=dof)
    ref = rows["linear", "none", 3]
    print(f"one thread, chunks of {args.lanes} trials, {n_steps} steps per trial, "
          f"controller {args.controller}, transitions {', '.join(TRANSITIONS)}, "
          f"both variants")
    print(f"{'plant':>10} {'turbulence':>10} {'dof':>4} {'trials/s':>10} "
          f"{'trial steps/s':>14} {'vs linear':>10}")
    for (kind, turb, dof), r in rows.items():
        print(f"{kind:>10} {turb:>10} {dof:>4} {r:10.1f} {r * n_steps:14.3g} "
              f"{r / ref:10.3f}")
    drows = {name: trials_per_s("nonlinear", "moderate", args.controller, args.lanes,
                                args.repeat, (name, dc))[0]
             for name, dc in DESIGNS.items()}
    print("designs, nonlinear plant, moderate turbulence, one design per run:")
    print(f"{'design':>14} {'trials/s':>10} {'trial steps/s':>14} {'vs swapped':>10}")
    for name, r in drows.items():
        print(f"{name:>14} {r:10.1f} {r * n_steps:14.3g} {r / drows['swapped']:10.3f}")
    nl = rows["nonlinear", "none", 3]
    six = rows["nonlinear", "none", 6]
    print(f"linear_trials_per_s={ref:.1f} nonlinear_trials_per_s={nl:.1f} "
          f"nonlinear_moderate_trials_per_s={rows['nonlinear', 'moderate', 3]:.1f} "
          f"ratio={ref / nl:.2f} sixdof_trials_per_s={six:.1f} "
          f"sixdof_vs_nonlinear={six / nl:.3f}")


if __name__ == "__main__":
    main()
