"""Plant steps per second: nonlinear truth plant (RK4, n_sub 10) vs linear ``A x + B u``.

One process, one thread.  Both plants are stepped from a ``@njit`` loop (how a
trial kernel would call them), one control period (dt = 0.1 s) per step, with a
small deterministic elevon excitation about trim and moderate Dryden gusts for
the nonlinear plant (gust state advanced by ``gust_step`` every step, draws
precomputed outside the timing):

a. nonlinear: ``gust_step`` + ``ftc_mc.core.longitudinal.nonlinear.propagate`` (10 RK4 sub-steps,
   40 derivative evaluations per control period);
b. linear: ``x <- A x + B u`` on the 9-state discrete model (explicit loops).

Compile (or cache-load) time is excluded (warm-up call).  Usage::

    .venv/bin/python scripts/benchmarks/bench_nonlinear.py

The last line is ``nonlinear_steps_per_s=<x> linear_steps_per_s=<y> ratio=<y/x>``.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from ftc_mc.core.shared.dryden import gust_step  # noqa: E402
from ftc_mc.core.jit import kernel  # noqa: E402
from ftc_mc.core.longitudinal.nonlinear import make_work, propagate  # noqa: E402
from ftc_mc.model.linear import build_plant  # noqa: E402
from ftc_mc.model.turbulence import dryden_model  # noqa: E402

N_SUB = 10


@kernel
def run_nonlinear(x, u0, p, dt, n_sub, work, gs, etas, Ad, Bd, Cd, n_steps):
    cmd = u0.copy()
    wind = np.zeros(3)
    for k in range(n_steps):
        d = 0.01 if (k // 10) % 2 == 0 else -0.01
        cmd[1] = u0[1] + d
        cmd[2] = u0[2] + d
        gust_step(gs, etas[k % etas.shape[0]], Ad, Bd, Cd, wind)
        propagate(x, cmd, p, wind, dt, n_sub, work)
    return x[0]


@kernel
def run_linear(x, A, B, n_steps):
    n = x.shape[0]
    xn = np.empty(n)
    u = np.zeros(3)
    for k in range(n_steps):
        d = 0.01 if (k // 10) % 2 == 0 else -0.01
        u[1] = d
        u[2] = d
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += A[i, j] * x[j]
            for j in range(3):
                acc += B[i, j] * u[j]
            xn[i] = acc
        for i in range(n):
            x[i] = xn[i]
    return x[0]


def best_rate(fn, n_steps, repeats=5):
    """Best steps/s over ``repeats`` timed calls of ``fn(n_steps)``."""
    best = 0.0
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(n_steps)
        best = max(best, n_steps / (time.perf_counter() - t0))
    return best


def main():
    plant = build_plant()
    tp = plant.trim
    dm = dryden_model("moderate", V=tp.V0, altitude_m=100.0, dt=plant.dt)
    rng = np.random.default_rng(0)
    etas = rng.standard_normal((4096, 4))
    work = make_work()

    def nl(n):
        x = tp.x0.copy()
        gs = dm.P0_chol @ np.ones(4) * 0.5
        return run_nonlinear(x, tp.u0, tp.params, plant.dt, N_SUB, work, gs, etas,
                             dm.Ad, dm.Bd, dm.Cd, n)

    def lin(n):
        return run_linear(np.zeros(9), plant.A, plant.B, n)

    t0 = time.perf_counter()
    nl(10)
    lin(10)
    print(f"compile/cache-load: {time.perf_counter() - t0:.2f} s")
    r_nl = best_rate(nl, 200_000)
    r_lin = best_rate(lin, 5_000_000)
    print(f"nonlinear (RK4, n_sub={N_SUB}, + Dryden gust_step): {r_nl:,.0f} steps/s"
          f" ({1e9 / r_nl:.0f} ns/step)")
    print(f"linear A x + B u:                                {r_lin:,.0f} steps/s"
          f" ({1e9 / r_lin:.1f} ns/step)")
    print(f"nonlinear_steps_per_s={r_nl:.0f} linear_steps_per_s={r_lin:.0f} "
          f"ratio={r_lin / r_nl:.1f}")


if __name__ == "__main__":
    main()
