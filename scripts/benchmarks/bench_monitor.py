"""Speed of the 6-DOF side monitor's filter beside the paper's 14-state filter.

One process, one thread.  Both filters run on lanes of data from their own
model, nominal, so that no reset or decision fires:

a. the paper's filter, ``ftc_mc.core.longitudinal.batch.filter_step_lanes``
   (14 states, 12 outputs, Table 1), as ``scripts/benchmarks/bench_core.py`` measures it;
b. the side monitor, ``ftc_mc.core.sixdof.monitor.sixdof_monitor`` (20 states,
   17 outputs: predict, 17 sequential updates carrying three direction
   signatures, projection, three windowed GLR statistics), called from Python
   once per step on all lanes (the call's own cost is included).

One *filter step* is one lane advanced by one 0.1 s period.  The best of
three repeats after a warm-up call (which compiles or loads the kernels).
Usage::

    .venv/bin/python scripts/benchmarks/bench_monitor.py [--lanes 128] [--steps 400]
        [--prediction linear|nonlinear|extended]

``--prediction nonlinear`` times the monitor that predicts with the airframe's
equations (``monitor.prediction``; 5 RK4 sub-steps), on the same data;
``extended`` the extended filter (those equations and, per lane and step,
their Jacobians by forward differences: 17 more propagations and 14 more
output evaluations without gust states, as here).

The last line is ``paper_filter_steps_per_s=<a> monitor_steps_per_s=<b>
ratio=<b/a>``.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import bench_core  # noqa: E402
from ftc_mc import api  # noqa: E402
from ftc_mc.sim.lanes import new_state  # noqa: E402
from ftc_mc.core.longitudinal.workspace import new_trial_work  # noqa: E402
from ftc_mc.core.sixdof.monitor import (EXTENDED, sixdof_monitor,  # noqa: E402
                                        sixdof_monitor_extended)
from ftc_mc.core.sixdof.truth import N_LAT  # noqa: E402
from ftc_mc.sim.lanes import new_record  # noqa: E402
from ftc_mc.sim.paths import path_of  # noqa: E402
from ftc_mc.sim.setup import build_setup  # noqa: E402


def monitor_data(mon, n_steps, L, seed=0):
    """Commands and measurements of ``L`` lanes flying the monitor's model, no fault."""
    rng = np.random.default_rng(seed)
    ns, nu = mon.B.shape
    x = np.zeros((ns, L))
    U = 0.02 * rng.standard_normal((n_steps, nu, L))
    Z = np.zeros((n_steps, mon.C.shape[0], L))
    for k in range(n_steps):
        w = np.sqrt(np.diag(mon.Q)[:ns])[:, None] * rng.standard_normal((ns, L))
        x = mon.A @ x + mon.B @ (U[k] - mon.u_ff[:, None]) + w
        Z[k] = mon.C @ x + np.sqrt(mon.r)[:, None] * rng.standard_normal((mon.C.shape[0], L))
    return U, Z


def bench_monitor(L, n_steps, prediction="linear"):
    """Best monitor filter steps per second, and the first call's time."""
    cfg = api.campaign_config({"campaign": {"transitions": ["elevon_lock"]},
                               "plant": {"kind": "linear", "dof": 6},
                               "monitor": {"prediction": prediction}})
    setup = build_setup(cfg)
    mon = setup.truth.monitor
    scheme = setup.scheme("paper")
    flight = setup.flight
    U, Z = monitor_data(mon, n_steps, L)
    work = new_trial_work(L, 14)
    nz = work.z.shape[0]
    plant = path_of(scheme, flight).plant
    kernel = sixdof_monitor_extended if mon.nonlinear == EXTENDED else sixdof_monitor

    def go(n):
        st = new_state(L, 14, 1, setup.truth.x0.shape[0], N_LAT, 0, mon.P0.shape[0],
                       mon.window)
        st.alive[:] = True
        rec = new_record(setup, L, 4)
        for k in range(n):
            work.u[:] = U[k]
            work.z[:] = Z[k, :nz]
            st.lat[:Z.shape[1] - nz] = Z[k, nz:]
            kernel(plant, scheme, flight, k, st, work, rec)
        return rec

    t = time.perf_counter()
    go(1)
    first = time.perf_counter() - t
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        go(n_steps)
        best = min(best, time.perf_counter() - t)
    return L * n_steps / best, first


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lanes", type=int, default=128)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--prediction", choices=("linear", "nonlinear", "extended"),
                    default="linear")
    args = ap.parse_args()
    plant = bench_core.build_plant()
    es = bench_core.EstimatorSettings()
    fm, det = bench_core.filter_model(plant, es), bench_core.detection(plant, es)
    P0 = bench_core.initial_covariance(fm, det)
    paper, first_p, _ = bench_core.bench_batch(fm, det, P0, plant, args.lanes, args.steps)
    mon, first_m = bench_monitor(args.lanes, args.steps, args.prediction)
    print(f"a  paper filter (filter_step_lanes), L={args.lanes}: {paper:.3e} steps/s "
          f"(first call {first_p:.1f} s)")
    print(f"b  side monitor (sixdof_monitor, {args.prediction} prediction), L={args.lanes}: "
          f"{mon:.3e} steps/s "
          f"(first call {first_m:.1f} s)")
    print(f"paper_filter_steps_per_s={paper:.3e} monitor_steps_per_s={mon:.3e} "
          f"ratio={mon / paper:.3f}")


if __name__ == "__main__":
    main()
