"""Filter steps per second of the estimation core, one process, one thread.

The problem is the paper's: the augmented filter of the X8 plant (14 states,
12 outputs, ``A_aug`` changing with every command, Q and R of section 5.1,
thresholds 25), fed with commands and measurements of the nominal linear plant
with Q- and R-sized noise (so resets are as rare as in a nominal flight).
One *filter step* is predict, residuals, Table 1, reset and re-prediction when
it fires, update and projection.  Measured:

a. ``tests/single_trajectory.py::filter_step`` called from a ``@njit`` loop;
b. the plain-NumPy twin ``tests/naive.py::filter_step_ref`` (textbook: explicit
   ``A_aug`` and ``C_aug``, ``S = C P C^T + R``, ``K = P C^T S^-1``, Joseph form);
c. filterpy's ``KalmanFilter`` (``kf.F = A_aug(u)`` every step, ``predict`` /
   ``update``), with the same residuals, Table 1, reset and projection in NumPy;
d. ``ftc_mc.core.longitudinal.batch.filter_step_lanes`` at several lane counts
   (steps = lanes x time steps).

Compile (or cache-load) time of the first call is reported apart.  Usage::

    .venv/bin/python scripts/benchmarks/bench_core.py

The last line is ``numba_vs_numpy=<x> numba_vs_filterpy=<y> batch_steps_per_s=<z>``
(``x``, ``y``: single-trajectory Numba steps/s over NumPy's and filterpy's;
``z``: the best lane count's steps/s).
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import naive  # noqa: E402
from filterpy.kalman import KalmanFilter  # noqa: E402

from lane_workspace import lane_zeros, new_lane_workspace  # noqa: E402
from ftc_mc.core.longitudinal.batch import filter_step_lanes  # noqa: E402
from single_trajectory import Workspace, filter_step  # noqa: E402
from ftc_mc.sim.estimator import (EstimatorSettings, detection,  # noqa: E402
                                  filter_model, initial_covariance)
from ftc_mc.model.faults import augmented  # noqa: E402
from ftc_mc.model.linear import build_plant  # noqa: E402

LANES = (64, 96, 128, 192)


def simulate(plant, fm, n_steps, L, seed=0):
    """Commands (n_steps, 3, L) and measurements (n_steps, 12, L) of the nominal
    linear plant with Q- and R-sized noise and smooth random commands."""
    rng = np.random.default_rng(seed)
    sq = np.sqrt(fm.q_diag[:9])[:, None]
    sr = np.sqrt(fm.r_diag)[:, None]
    x = np.zeros((9, L))
    u = np.zeros((3, L))
    U = np.empty((n_steps, 3, L))
    Z = np.empty((n_steps, 12, L))
    for k in range(n_steps):
        u = 0.9 * u + 0.02 * rng.standard_normal((3, L))
        x = plant.A @ x + plant.B @ u + sq * rng.standard_normal((9, L))
        U[k] = u
        Z[k] = plant.C @ x + sr * rng.standard_normal((12, L))
    return U, Z


@numba.njit
def run_single(xa, P, U, Z, fm, det, phi, T, h, res, x_prev, P_prev):
    """``filter_step`` over the rows of ``U``, ``Z``; returns the number of resets."""
    n = 0
    for k in range(U.shape[0]):
        n += filter_step(xa, P, U[k], Z[k], fm, det, phi, T, h, res, x_prev, P_prev) != 0
    return n


@numba.njit
def run_lanes(xa, P, U, Z, fm, det, phi, T, work, res, block):
    """``filter_step_lanes`` over the first axis of ``U``, ``Z``; returns resets."""
    n = 0
    for k in range(U.shape[0]):
        filter_step_lanes(xa, P, U[k], Z[k], fm, det, phi, T, work, res, block)
        for l in range(block.shape[0]):
            n += block[l] != 0
    return n


def best_rate(fn, steps, repeats=3):
    """Best steps/s of ``repeats`` calls of ``fn`` (each doing ``steps`` steps)."""
    best = 0.0
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = max(best, steps / (time.perf_counter() - t))
    return best


def bench_numba_single(fm, det, P0, U, Z):
    ws = Workspace()

    def go(n):
        return run_single(np.zeros(14), P0.copy(), U[:n], Z[:n], fm, det, ws.phi, ws.T,
                          ws.h, ws.res, ws.x_prev, ws.P_prev)

    t = time.perf_counter()
    go(2)
    first = time.perf_counter() - t
    n = U.shape[0]
    return best_rate(lambda: go(n), n), first, go(n)


def bench_numpy(ref, P0, U, Z):
    def go():
        X, P = np.zeros(14), P0.copy()
        for k in range(U.shape[0]):
            X, P, *_ = naive.filter_step_ref(X, P, U[k], Z[k], ref)
    return best_rate(go, U.shape[0], repeats=2)


def bench_filterpy(ref, P0, U, Z):
    """filterpy predict/update with the same matrices, plus the kernel's logic."""
    _, B_aug, C_aug = naive.aug(ref, np.zeros(3))

    def go():
        kf = KalmanFilter(dim_x=14, dim_z=12, dim_u=3)
        kf.x = np.zeros((14, 1))
        kf.P = P0.copy()
        kf.Q = np.diag(ref.q)
        kf.R = np.diag(ref.r)
        kf.H = C_aug
        kf.B = B_aug
        out = (naive.OUT_Q, naive.OUT_NX, naive.OUT_NZ)
        for k in range(U.shape[0]):
            u = U[k]
            kf.F = augmented(ref.A, ref.B, ref.C, u, ref.u0)[0]
            x0, P_prev = kf.x.copy(), kf.P.copy()
            kf.predict(u=u[:, None])
            mu = Z[k] - (C_aug @ kf.x)[:, 0]
            S = C_aug @ kf.P @ C_aug.T + kf.R
            r = np.array([mu[i] * mu[i] / S[i, i] for i in out])
            block = naive.signature_ref(r[0], r[1], r[2], ref.t_q, ref.t_nx, ref.variant)
            if block:
                kf.x, kf.P = x0, naive.reset_ref(P_prev, block, ref.reset_var)
                kf.predict(u=u[:, None])
            kf.update(Z[k][:, None])
            kf.x[9:, 0] = np.clip(kf.x[9:, 0], ref.lo, ref.hi)
    return best_rate(go, U.shape[0], repeats=2)


def bench_batch(fm, det, P0, plant, L, n_steps):
    U0, Z0 = simulate(plant, fm, n_steps, L, seed=L)
    U, Z = lane_zeros(U0.shape), lane_zeros(Z0.shape)  # 64-byte aligned lane rows
    U[:], Z[:] = U0, Z0
    ws = new_lane_workspace(L)
    xa, P = lane_zeros((14, L)), lane_zeros((14, 14, L))

    def go(n):
        xa[:] = 0.0
        P[:] = P0[:, :, None]
        return run_lanes(xa, P, U[:n], Z[:n], fm, det, *ws)

    t = time.perf_counter()
    go(2)
    first = time.perf_counter() - t
    return best_rate(lambda: go(n_steps), n_steps * L), first, go(n_steps)


def threads_note():
    try:
        from threadpoolctl import threadpool_info
    except ImportError:
        return "threadpoolctl not installed; BLAS/OpenMP threads set to 1 by env"
    info = threadpool_info()
    return "threadpools: " + (", ".join(f"{p['internal_api']}={p['num_threads']}"
                                         for p in info) or "none")


def main():
    plant = build_plant()
    s = EstimatorSettings()
    fm, det, ref = filter_model(plant, s), detection(plant, s), naive.ref_model(plant, s)
    P0 = initial_covariance(fm, det)
    U3, Z3 = simulate(plant, fm, 60_000, 1)
    U, Z = np.ascontiguousarray(U3[:, :, 0]), np.ascontiguousarray(Z3[:, :, 0])

    print(f"bench_core: 14 states, 12 outputs, X8 plant, paper settings; numba "
          f"{numba.__version__}, numpy {np.__version__}, NUMBA_NUM_THREADS="
          f"{numba.config.NUMBA_NUM_THREADS}; {threads_note()}")
    t0 = time.perf_counter()
    numba_rate, numba_first, numba_resets = bench_numba_single(fm, det, P0, U, Z)
    numpy_rate = bench_numpy(ref, P0, U[:3000], Z[:3000])
    fp_rate = bench_filterpy(ref, P0, U[:3000], Z[:3000])
    rows = [("a  Numba filter_step (njit loop)", numba_rate, 1,
             f"first call {numba_first:.2f} s, {numba_resets} resets / {len(U)}"),
            ("b  NumPy twin (tests/naive.py)", numpy_rate, 1, ""),
            ("c  filterpy KalmanFilter", fp_rate, 1, "")]
    batch = []
    for L in LANES:
        rate, first, resets = bench_batch(fm, det, P0, plant, L, 400)
        batch.append((L, rate))
        rows.append((f"d  Numba filter_step_lanes, L={L}", rate, L,
                     f"first call {first:.2f} s, {resets} resets / {400 * L}"))
    best_L, best = max(batch, key=lambda t: t[1])

    print(f"{'variant':38s} {'steps/s':>12s} {'vs NumPy':>9s} {'vs filterpy':>11s}  notes")
    for name, rate, _, note in rows:
        print(f"{name:38s} {rate:12,.0f} {rate / numpy_rate:9.1f} {rate / fp_rate:11.1f}  "
              f"{note}")
    print(f"(first call = compile, or load from Numba's cache when warm; excluded "
          f"from the rates; total {time.perf_counter() - t0:.1f} s)")
    print(f"best lane count {best_L}: {best / numba_rate:.2f}x the single-trajectory "
          f"kernel")
    print(f"numba_vs_numpy={numba_rate / numpy_rate:.3g} "
          f"numba_vs_filterpy={numba_rate / fp_rate:.3g} batch_steps_per_s={best:.3g}")


if __name__ == "__main__":
    main()
