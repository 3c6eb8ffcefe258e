"""Oracle study: can the lock-turn LQR keep a one-elevon-locked X8 in the envelope?

Feeds ``docs/findings/sixdof.md``.  For each side and lock offset from trim,
the nonlinear 6-DOF equations (the repo's RK4 kernel, ``ftc_mc.core.sixdof.plant.propagate``,
10 sub-steps of 0.01 s per 0.1 s control period) fly 60 s from the nominal
6-DOF trim (20 m/s, -3 deg, wings level) with the elevon locked at ``t = 0``
(the locked actuator follows its lock with its 0.05 s lag, as eq. (2) does in
the trials).  Controllers, full state, true values (oracle, no noise):

* **nominal**: the paper's longitudinal LQR (discount 0.999, ``R = 0.1 I``,
  on the longitudinal model at 20 m/s, -3 deg) plus the wings-level, heading
  hold lateral LQR (``ftc_mc.design.lateral``), on the 6-DOF state about the
  6-DOF trim, both elevons commanded; the locked one ignores its command.
  "No reconfiguration" flies it for the whole 60 s.
* **hold**: the trim commands, unchanged (open loop); the other baseline.
* **lock-turn**: ``ftc_mc.design.lock_turn.lock_turn_lqr`` for the true side
  and lock, switched on after a detection delay of 0, 1 or 3 s; before the
  switch the nominal controller flies (``d3h``: the trim commands are held
  for the 3 s instead).

Envelope (``validity`` defaults): airspeed 12-30 m/s, angle of attack -8 to 12
deg, |bank| <= 60 deg; a run stops when it leaves.  Measured: whether it
survived 60 s, the time it left and by which bound, the height lost [m]
(absolute; the nominal glide loses 62.8 m in 60 s) and the largest |bank|.

Usage::

    PYTHONPATH=. python scripts/studies/study_lock_turn.py [--airframe x8-pyfly]
        [--offsets -30,-20,...] [--turbulence [--seeds N]]  # moderate turbulence,
                                            # N records: nominal and lock-turn (1 s)
        [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from ftc_mc.core.sixdof import plant as kernels
from ftc_mc.core.sixdof.layout import COMMAND, N_STATE, N_WIND, OUTPUT, STATE
from ftc_mc.design.lateral import lateral_lqr, longitudinal_gain_on_sixdof
from ftc_mc.design.lock_turn import design_point, lock_turn_lqr
from ftc_mc.design.lqr import discounted_lqr, paper_q_lqr
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import build_sixdof_plant
from ftc_mc.model.source import load_plant

OFFSETS = (-30, -20, -15, -12, -10, -6, -4, -2, -1, -0.5, 0.5, 1, 2, 2.5, 3, 4, 5, 10)
DELAYS = (0.0, 1.0, 3.0)
T_END = 60.0
DT = 0.1
N_SUB = 10
ENVELOPE = dict(va=(12.0, 30.0), alpha=(math.radians(-8.0), math.radians(12.0)),
                bank=math.radians(60.0))


def nominal_gain(name, plant):
    """The nominal 6-DOF law's gain (3 x 15): paper's longitudinal + lateral."""
    lon = load_plant(name, 20.0, -3.0, DT)
    K_lon, _ = discounted_lqr(lon.A, lon.B, paper_q_lqr(lon.trim.gamma0), 0.1 * np.eye(3),
                              0.999)
    return longitudinal_gain_on_sixdof(K_lon) + lateral_lqr(plant).K_full


def turbulence_record(n, seed, V0=20.0, h=100.0):
    """Moderate Dryden turbulence at ``h`` m, the six body components held over
    each period (n, 6): the longitudinal and lateral models of
    ``ftc_mc.model.turbulence`` started at rest, one generator."""
    from ftc_mc.core.shared.dryden import gust_record
    from ftc_mc.model.sixdof import sixdof_wind
    from ftc_mc.model.turbulence import dryden_lateral_model, dryden_model

    rng = np.random.default_rng(seed)
    recs = []
    for m in (dryden_model("moderate", V0, h, DT), dryden_lateral_model("moderate", V0, h, DT)):
        rec = np.zeros((n, 3))
        gust_record(np.zeros(4), rng.standard_normal((n, 4)), m.Ad, m.Bd, m.Cd, rec)
        recs.append(rec)
    return sixdof_wind(recs[0], recs[1])


def fly(tp, K_nom, lower, upper, side, lock, turn=None, delay=math.inf, winds=None,
        pre="nominal", linear=None):
    """One run (module docstring); returns a dict of results.

    ``pre``: what flies before the switch to ``turn`` (or throughout without
    one): ``"nominal"`` the nominal 6-DOF LQR, ``"hold"`` the trim commands.
    ``linear``: a ``SixDofPlant`` whose linear model flies in place of the
    equations (the linear plant: ``x+ = A x + B u`` in deviations from its
    trim, the outputs ``y0 + C dx``; still air only).
    """
    assert linear is None or winds is None, "the linear flights are in still air"
    p = tp.params
    x = tp.x0.copy()
    work = np.zeros((kernels.N_WORK, N_STATE))
    y = np.zeros(len(OUTPUT))
    still = np.zeros(N_WIND)
    n = int(round(T_END / DT))
    alt0 = 0.0
    down_ref = -tp.V0 * math.sin(tp.gamma0)  # the reference's down speed [m/s]
    left_at, why, bank_max = None, "", 0.0
    for k in range(n):
        t = k * DT
        if turn is not None and t >= delay - 1e-9:
            u = turn.command(x)
        elif pre == "hold":
            u = tp.u0.copy()
        else:
            u = np.clip(tp.u0 - K_nom @ (x - tp.x0), lower, upper)
        u[COMMAND[side]] = lock
        w = still if winds is None else winds[k]
        if linear is None:
            kernels.propagate(x, u, p, w, DT, N_SUB, work)
        else:
            x = tp.x0 + linear.A @ (x - tp.x0) + linear.B @ (u - linear.u0)
        if not np.all(np.isfinite(x)):
            left_at, why = t + DT, "diverged"
            break
        if linear is None:
            kernels.outputs(x, p, w, y)
        else:
            y = tp.y0 + linear.C @ (x - tp.x0)
        va, alpha, phi = y[OUTPUT["Va"]], y[OUTPUT["alpha"]], x[STATE["phi"]]
        bank_max = max(bank_max, abs(phi))
        if not ENVELOPE["va"][0] <= va <= ENVELOPE["va"][1]:
            why = "airspeed low" if va < ENVELOPE["va"][0] else "airspeed high"
        elif not ENVELOPE["alpha"][0] <= alpha <= ENVELOPE["alpha"][1]:
            why = "alpha low" if alpha < ENVELOPE["alpha"][0] else "alpha high"
        elif abs(phi) > ENVELOPE["bank"]:
            why = "bank"
        if why:
            left_at = t + DT
            break
    t_flown = left_at if left_at is not None else T_END
    height_lost = x[STATE["z"]] + down_ref * t_flown - alt0
    return dict(survived=left_at is None, t_leave=left_at, why=why,
                height_lost=float(height_lost),
                below_glide=float(x[STATE["z"]]), bank_max_deg=math.degrees(bank_max),
                va_end=float(y[OUTPUT["Va"]]), phi_end_deg=math.degrees(x[STATE["phi"]]))


def mirror(values):
    """A design point's unknowns mirrored to the other side (start for SLSQP)."""
    w = [values[k] for k in ("airspeed", "alpha", "beta", "phi", "theta", "turn_rate",
                             "throttle", "free_elevon")]
    w[2], w[3], w[5] = -w[2], -w[3], -w[5]
    return np.array(w)


def fmt_run(r):
    if r["survived"]:
        return f"ok {r['height_lost']:5.0f}m b{r['bank_max_deg']:3.0f}"
    return f"{r['t_leave']:4.1f}s {r['why'][:8]:8s}"


def fmt_turb(runs):
    """Survivors out of the turbulence seeds, and the shortest exit time."""
    ok = sum(r["survived"] for r in runs)
    t = [r["t_leave"] for r in runs if not r["survived"]]
    return f"{ok}/{len(runs)}" + (f" (first {min(t):.1f}s)" if t else "")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--airframe", default="x8-pyfly")
    ap.add_argument("--offsets", default=",".join(str(o) for o in OFFSETS))
    ap.add_argument("--turbulence", action="store_true")
    ap.add_argument("--seeds", type=int, default=1,
                    help="turbulence records (seeds 26, 27, ...) per lock")
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    t_start = time.time()
    af = PRESETS[a.airframe].airframe
    plant = build_sixdof_plant(af)
    tp = plant.trim
    K_nom = nominal_gain(a.airframe, plant)
    offsets = [float(o) for o in a.offsets.split(",")]
    rows = []
    designs = {}
    for side in ("left", "right"):
        for off in offsets:
            lock = tp.u0[COMMAND[side]] + math.radians(off)
            starts = ()
            if side == "right" and ("left", off) in designs:
                starts = (mirror(designs[("left", off)].point.values),)
            pt = design_point(af, side, lock, extra_starts=starts)
            d = lock_turn_lqr(af, side, lock, point=pt)
            designs[(side, off)] = d
            row = dict(side=side, offset_deg=off, design_offset_deg=pt.design_offset_deg,
                       design={k: (v if k in ("airspeed", "throttle") else math.degrees(v))
                               for k, v in pt.values.items()},
                       rho=float(np.max(np.abs(d.closed_loop))))
            row["none"] = fly(tp, K_nom, plant.u_lower, plant.u_upper, side, lock)
            row["hold"] = fly(tp, K_nom, plant.u_lower, plant.u_upper, side, lock, pre="hold")
            row["turn3_hold"] = fly(tp, K_nom, plant.u_lower, plant.u_upper, side, lock, d,
                                    3.0, pre="hold")
            for delay in DELAYS:
                row[f"turn{delay:g}"] = fly(tp, K_nom, plant.u_lower, plant.u_upper, side,
                                            lock, d, delay)
            if a.turbulence:
                row["none_turb"], row["turn1_turb"] = [], []
                for seed in range(26, 26 + a.seeds):
                    winds = turbulence_record(round(T_END / DT), seed=seed)
                    row["none_turb"].append(fly(tp, K_nom, plant.u_lower, plant.u_upper,
                                                side, lock, winds=winds))
                    row["turn1_turb"].append(fly(tp, K_nom, plant.u_lower, plant.u_upper,
                                                 side, lock, d, 1.0, winds=winds))
            rows.append(row)
            v = row["design"]
            print(f"{side:5s} {off:+6.1f} | design {row['design_offset_deg']:+6.2f} "
                  f"V {v['airspeed']:4.1f} phi {v['phi']:+5.1f} gam {v['gamma']:+5.1f} "
                  f"thr {v['throttle']:.2f} | none {fmt_run(row['none'])} | "
                  f"hold {fmt_run(row['hold'])} | "
                  + " | ".join(f"d{dl:g} {fmt_run(row[f'turn{dl:g}'])}" for dl in DELAYS)
                  + f" | d3h {fmt_run(row['turn3_hold'])}"
                  + ("" if not a.turbulence else
                     f" || turb none {fmt_turb(row['none_turb'])} d1 "
                     f"{fmt_turb(row['turn1_turb'])}"), flush=True)
    print(f"wall {time.time() - t_start:.0f} s")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
