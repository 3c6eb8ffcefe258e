"""Study: is the gust-aware side monitor consistent on the nonlinear 6-DOF plant?

Feeds ``docs/findings/sixdof.md`` (nonlinear 6-DOF, moderate turbulence).  In
a campaign on the nonlinear plant in moderate turbulence the side monitor
(``ftc_mc/core/sixdof/monitor.py``, ``design_turbulence: moderate``,
``prediction: nonlinear``) makes thousands of false decisions per fault-free
hour, and still about 1,800 per hour at a GLR threshold of 1000 (against 30
shipped).  Its direction projections should be standard normal under no fault
(mean square 1: ``tests/test_side_monitor.py`` checks it without gust states).
This script measures their mean square on fault-free data, written in NumPy:

Data (``--lanes`` lanes, open loop, commands ``0.02 N(0, 1)`` about the
longitudinal trim, the monitor's process and measurement noise, its gust
states driven by their own noise), flown one of two ways:

* ``own``: the monitor's own model: the airframe's equations (RK4, the
  monitor's sub-steps) in still air, the gusts' effect added linearly through
  the trim's ``B_w C_d`` and ``D_w C_d``;
* ``truth``: as the trials' truth flies them: the gust states' wind ``C_d g``
  through the equations and the outputs (RK4, 10 sub-steps).

Monitors (the filter of the module docstring; only the projections, no test):

* ``nonlinear``: the ``monitor.prediction: nonlinear`` filter: trim Jacobians
  ``A``, ``B``, ``C`` for the covariance, the gains and the directions, gusts
  linear (checked equal to the kernel ``sixdof_monitor`` on the first data set);
* ``relin``: the Jacobians re-linearised about each lane's estimate at every
  step (central differences of the equations and outputs), gusts linear;
* ``relin-wind``: re-linearised, and the gust states' wind flown through the
  equations and the outputs, as the truth does (what ``monitor.prediction:
  extended`` builds, there with forward differences);
* ``trim-wind``: trim Jacobians, wind through the equations.

Prints one line per combination: the mean square of each direction's
projection (throttle, left, right) over the steps after ``--skip``, and its
largest magnitude (``nan``: the filter diverged).

Usage::

    .venv/bin/python scripts/studies/study_monitor_consistency.py [--lanes 7] [--steps 50]
        [--seeds 2] [--skip 20] [--gust-scale 1] [--state-noise-scale 1]

The figures in docs/findings/sixdof-side-monitor.md: ``--steps 35 --skip 15 --seeds 4``, with
``--gust-scale 0.3`` and ``--state-noise-scale 10`` or ``100`` beside.
"""

from __future__ import annotations

import argparse
import time

import ftc_mc  # noqa: F401  (BLAS pinning before numpy's first use)
import numpy as np

from ftc_mc import api
from ftc_mc.sim.lanes import new_state
from ftc_mc.core.longitudinal.workspace import new_trial_work
from ftc_mc.core.sixdof.layout import LAYOUT, MONITOR_STATES
from ftc_mc.core.sixdof.monitor import sixdof_monitor
from ftc_mc.core.sixdof.truth import N_LAT
from ftc_mc.model.sixdof import derivatives, outputs
from ftc_mc.sim.lanes import new_record
from ftc_mc.sim.paths import path_of
from ftc_mc.sim.setup import build_setup

COMBINATIONS = (("own", "nonlinear"), ("own", "relin"), ("truth", "nonlinear"),
                ("truth", "trim-wind"), ("truth", "relin"), ("truth", "relin-wind"))


def build():
    """The setup: 6-DOF nonlinear plant, moderate turbulence, the monitor
    gust-aware with the nonlinear prediction; its monitor with no test."""
    cfg = {"campaign": {"transitions": ["elevon_lock"], "trials": 8, "seed": 5,
                        "signature": "paper", "chunk_size": 8},
           "plant": {"kind": "nonlinear", "dof": 6, "turbulence": "moderate"},
           "monitor": {"design_turbulence": "moderate", "prediction": "nonlinear"},
           "timing": {"fault_time_s": 2.0, "window_s": 2.0, "duration_s": 5.0}}
    setup = build_setup(api.campaign_config(cfg))
    mon = setup.truth.monitor._replace(startup=0)
    return setup, mon


class Model:
    """The equations about the trim on the monitor's rows, and the wind of its gust states."""

    def __init__(self, setup, mon):
        self.pl, self.mon = setup.truth, mon
        self.nx = len(MONITOR_STATES)
        pl = self.pl
        self.Cw = np.zeros((len(LAYOUT.wind), mon.A.shape[0] - self.nx))
        for j, name in enumerate(("u_g", "w_g", "q_g")):
            self.Cw[LAYOUT.wind.index(name), :4] = pl.Cd[j]
        for j, name in enumerate(("v_g", "p_g", "r_g")):
            self.Cw[LAYOUT.wind.index(name), 4:] = pl.Cdl[j]

    def fly(self, xr, cmd, wind, n_sub):
        pl, mon = self.pl, self.mon
        x = pl.x0.copy()
        x[mon.states] += xr
        h = pl.dt / n_sub
        for _ in range(n_sub):
            k1 = derivatives(x, cmd, pl.p, wind)
            k2 = derivatives(x + h / 2 * k1, cmd, pl.p, wind)
            k3 = derivatives(x + h / 2 * k2, cmd, pl.p, wind)
            k4 = derivatives(x + h * k3, cmd, pl.p, wind)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return x[mon.states] - pl.x0[mon.states]

    def out(self, xr, wind):
        pl, mon = self.pl, self.mon
        x = pl.x0.copy()
        x[mon.states] += xr
        return outputs(x, pl.p, wind)[mon.outs] - pl.y0[mon.outs]


def psd_sqrt(Q):
    lam, V = np.linalg.eigh(Q)
    return V * np.sqrt(np.clip(lam, 0.0, None))


def fly_data(model, rng, lanes, steps, how, gust_scale=1.0):
    """Commands (steps, 3, lanes) and measurements (steps, m, lanes), fault-free;
    the gust states' noise scaled by ``gust_scale``."""
    mon, nx = model.mon, model.nx
    ns, nu = mon.B.shape
    x = np.zeros((ns, lanes))
    u = 0.02 * rng.standard_normal((steps, nu, lanes))
    z = np.zeros((steps, mon.C.shape[0], lanes))
    S = psd_sqrt(mon.Q[:ns, :ns])
    still = np.zeros(len(LAYOUT.wind))
    for k in range(steps):
        w = S @ rng.standard_normal((ns, lanes))
        w[nx:] *= gust_scale
        xn = mon.A @ x
        for l in range(lanes):
            cmd = mon.u0 + u[k, :, l]
            if how == "own":
                xn[:nx, l] = (model.fly(x[:nx, l], cmd, still, mon.n_sub)
                              + mon.A[:nx, nx:] @ x[nx:, l])
            else:
                xn[:nx, l] = model.fly(x[:nx, l], cmd, model.Cw @ x[nx:, l], 10)
        x = xn + w
        for l in range(lanes):
            if how == "own":
                y = mon.C[:, nx:] @ x[nx:, l] + model.out(x[:nx, l], still)
            else:
                y = model.out(x[:nx, l], model.Cw @ x[nx:, l])
            z[k, :, l] = y + np.sqrt(mon.r) * rng.standard_normal(mon.C.shape[0])
    return u, z


def jacobian(f, x0, eps=1e-6):
    f0 = f(x0)
    J = np.zeros((f0.size, x0.size))
    for i in range(x0.size):
        d = np.zeros_like(x0)
        d[i] = eps
        J[:, i] = (f(x0 + d) - f(x0 - d)) / (2 * eps)
    return J


def monitor_projections(model, u, z, variant, state_noise_scale=1.0):
    """One lane's direction projections (steps, 3) under ``variant``, the
    monitor's process noise on the 6-DOF states times ``state_noise_scale``."""
    mon, nx = model.mon, model.nx
    ns, nu = mon.B.shape
    n = ns + 2 * nu
    relin = variant.startswith("relin")
    wind_through = variant.endswith("wind")
    still = np.zeros(len(LAYOUT.wind))
    X, P = np.zeros(n), mon.P0.copy()
    Q = mon.Q.copy()
    Q[:nx, :nx] *= state_noise_scale
    proj = np.zeros((u.shape[0], nu))
    for k in range(u.shape[0]):
        xr, g = X[:nx], X[nx:ns]
        cmd = X[ns:ns + nu] + (1 - X[ns + nu:]) * (u[k] + mon.u0)
        wind = model.Cw @ g if wind_through else still
        A, B, C = mon.A.copy(), mon.B.copy(), mon.C.copy()
        if relin:
            A[:nx, :nx] = jacobian(lambda v: model.fly(v, cmd, wind, mon.n_sub), xr)
            B[:nx] = jacobian(lambda c: model.fly(xr, c, wind, mon.n_sub), cmd)
            if wind_through:
                A[:nx, nx:] = jacobian(lambda w: model.fly(xr, cmd, w, mon.n_sub), wind) @ model.Cw
        F = np.eye(n)
        F[:ns, :ns] = A
        F[:ns, ns:ns + nu] = B
        F[:ns, ns + nu:] = B @ np.diag(-(u[k] + mon.u0))
        Xp = F @ X
        Xp[:nx] = model.fly(xr, cmd, wind, mon.n_sub) + (0.0 if wind_through
                                                          else mon.A[:nx, nx:] @ g)
        Xp[nx:ns] = mon.A[nx:, nx:] @ g
        wind_p = model.Cw @ Xp[nx:ns] if wind_through else still
        if relin:
            C[:, :nx] = jacobian(lambda v: model.out(v, wind_p), Xp[:nx])
            if wind_through:
                C[:, nx:] = jacobian(lambda w: model.out(Xp[:nx], w), wind_p) @ model.Cw
        h = model.out(Xp[:nx], wind_p) + (0.0 if wind_through else mon.C[:, nx:] @ Xp[nx:ns])
        P = F @ P @ F.T + Q
        S = np.zeros((n, nu))
        S[:ns] = B
        num, den = np.zeros(nu), np.zeros(nu)
        X = Xp.copy()
        for r in range(C.shape[0]):
            c = np.zeros(n)
            c[:ns] = C[r]
            s = c @ P @ c + mon.r[r]
            innov = z[k, r] - h[r] - c @ (X - Xp)
            mu = (c @ S) / np.sqrt(s)
            num += mu * innov / np.sqrt(s)
            den += mu ** 2
            K = P @ c / s
            S = S - np.outer(K, c @ S)
            X = X + K * innov
            P = P - np.outer(P @ c, P @ c) / s
            P = np.triu(P) + np.triu(P, 1).T
        X[ns:ns + nu] = np.clip(X[ns:ns + nu], mon.lo, mon.hi)
        X[ns + nu:] = np.clip(X[ns + nu:], 0.0, 1.0)
        proj[k] = num / np.sqrt(den)
    return proj


def kernel_projections(setup, mon, u, z):
    """The kernel's projections (steps, 3, lanes), read from its GLR window."""
    steps, _, lanes = u.shape
    st = new_state(lanes, 14, 1, setup.truth.x0.shape[0], N_LAT, 0, mon.P0.shape[0],
                   mon.window)
    st.alive[:] = True
    rec = new_record(setup, lanes, 4)
    rec.side_k[:] = -1
    scheme = setup.scheme("paper")  # its monitor with no test
    scheme = scheme._replace(
        detection=scheme.detection._replace(side_thresholds=np.full(3, np.inf)))
    flight = setup.flight._replace(plant=setup.truth._replace(monitor=mon))
    work = new_trial_work(lanes, 14)
    nz = work.z.shape[0]
    out = np.zeros((steps, 3, lanes))
    for k in range(steps):
        work.u[:] = u[k]
        work.z[:] = z[k, :nz]
        st.lat[:z.shape[1] - nz] = z[k, nz:]
        sixdof_monitor(path_of(scheme, flight).plant, scheme, flight, k, st, work, rec)
        out[k] = st.mbuf[k % mon.window]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lanes", type=int, default=7)
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--skip", type=int, default=20, help="steps of the filter's transient")
    ap.add_argument("--gust-scale", type=float, default=1.0,
                    help="the data's gust noise against the monitor's (moderate) model")
    ap.add_argument("--state-noise-scale", type=float, default=1.0,
                    help="the monitors' process noise variance on the 6-DOF states, "
                         "times (not the data's)")
    a = ap.parse_args()
    setup, mon = build()
    model = Model(setup, mon)
    data = {how: [fly_data(model, np.random.default_rng(100 + s), a.lanes, a.steps, how,
                           a.gust_scale) for s in range(a.seeds)] for how in ("own", "truth")}
    rows = [list(mon.outs).index(LAYOUT.outputs.index(n)) for n in ("phi", "v")]
    for how, sets in data.items():
        z = np.concatenate([z for _, z in sets], axis=-1)[a.skip:, rows]
        print(f"data={how:5s}: steps {a.skip}-{a.steps - 1}, bank RMS "
              f"{np.degrees(np.sqrt((z[:, 0] ** 2).mean())):.1f} deg, side velocity RMS "
              f"{np.sqrt((z[:, 1] ** 2).mean()):.2f} m/s (deviations from trim)")
    u, z = data["own"][0]
    ref = kernel_projections(setup, mon, u, z)
    mine = np.stack([monitor_projections(model, u[:, :, l], z[:, :, l], "nonlinear")
                     for l in range(a.lanes)], axis=-1)
    print(f"nonlinear variant against the kernel: max |difference| "
          f"{np.abs(mine - ref).max():.2e}")
    print(f"{a.seeds} seeds x {a.lanes} lanes x steps {a.skip}-{a.steps - 1}, "
          "mean square of each direction's projection (throttle, left, right; 1 if consistent)")
    for how, variant in COMBINATIONS:
        t = time.perf_counter()
        d = []
        with np.errstate(all="ignore"):
            for u, z in data[how]:
                for l in range(a.lanes):
                    d.append(monitor_projections(model, u[:, :, l], z[:, :, l], variant,
                                                 a.state_noise_scale)[a.skip:])
        d = np.concatenate(d)
        ms = (d ** 2).mean(axis=0)
        print(f"data={how:5s} monitor={variant:10s} mean_square="
              f"{np.array2string(ms, precision=2)} max_abs={np.abs(d).max():.1f} "
              f"({time.perf_counter() - t:.0f} s)", flush=True)


if __name__ == "__main__":
    main()
