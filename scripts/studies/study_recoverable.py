"""Which elevon locks can any controller fly on from? The recoverable set.

Feeds ``docs/findings/sixdof.md``.  A lock is *trimmable*
(``ftc_mc.model.trimmable``) when a steady flight exists with it inside the
validity envelope.  That does not
make it *recoverable*: the aircraft must also get from the nominal glide to
that steady flight without leaving the envelope, while the lock rolls and
pitches it.  This study asks the question with perfect knowledge (an oracle:
side and lock known from the lock's first instant, true state, still air),
for any command history of the throttle and the healthy elevon within their
limits, not only for one controller family.

The 6-DOF nonlinear equations (``ftc_mc.core.sixdof.plant.simulate``: RK4,
10 sub-steps per 0.1 s period, the actuators' first-order lags, the locked
elevon following its lock from the nominal trim at ``t = 0``) fly from the
nominal 6-DOF trim (20 m/s, -3 deg).  The commands are piecewise linear
between nodes every 0.2 s (throttle, healthy elevon; the locked elevon held at
its lock).  The envelope is the trials' (``validity`` defaults): airspeed
12-30 m/s, angle of attack -8 to 12 deg, |bank| <= 60 deg, checked every
0.1 s as the trials check it.  Its *excess* at a sample is the largest of
``12 - Va``, ``Va - 30`` [m/s], ``-8 - alpha``, ``alpha - 12``,
``|phi| - 60`` [deg]: one metre per second counts as one degree.

Per side and lock offset from trim, four questions:

1. **Lower bound: the least excess over the first ``--horizon`` seconds**
   (3 s by default).  ``min s`` subject to ``excess_k <= s`` at every sample,
   over the commands (``scipy.optimize.minimize``, SLSQP), from eight starts:
   the trim commands held, the design point's commands, full throttle with the
   healthy elevon at the lock, at either limit, and three random histories
   (seeded).  A positive least excess from every start means that no command
   history found keeps the aircraft inside even for that long.  SLSQP finds
   local minima, so this is evidence, not proof; the starts agreeing is
   reported (``agree``: starts within 0.05 of the best).
2. **Constructive: a flight of 60 s.**  The lock-turn LQR
   (``ftc_mc.design.lock_turn.lock_turn_lqr``) designed about the steady
   flight closest to the nominal glide inside the envelope less 0.5 of each
   bound (``WIDE``, not the controllers' ``DesignBox``), flown after an
   optimised transient: over the first ``--transient`` seconds (8 s) the
   commands minimise the LQR's cost-to-go ``dx' P dx`` at the hand-over,
   subject to ``excess_k <= -0.3`` (SLSQP, from the five structured starts
   of question 1 in turn, until one flies).  Then the 60 s are flown, the LQR after the transient, and
   the flight counts only if it stays inside the envelope at every sample
   (``scripts/studies/study_lock_turn.fly``, as the oracle study flies its runs).

3. **Later exits.**  For a lock question 2 did not fly and question 1 did
   not lose, question 1 again over ``--long-horizon`` seconds (20 s), with
   nodes every 0.2 s for the first 3 s and every 1 s after.

4. **The longest stay.**  For a lock not flown for the 60 s, the longest
   time any command history found keeps the aircraft inside: the longest
   horizon (bisected on the 0.1 s samples, up to ``--long-horizon``) whose
   least excess from the eight starts is not positive, nodes every 0.1 s up
   to 3 s and every 1 s beyond; beside it, the time the nominal 6-DOF LQR
   (the paper's longitudinal law and the wings-level lateral law,
   ``scripts/studies/study_lock_turn.py``) leaves.  Their ratio bounds what the
   target "the reconfiguring loop at least doubles the time to leave" can reach
   for that lock.

``--plant linear`` asks the same of the linear plant: the 6-DOF linear model
at the nominal glide (``x+ = A x + B u`` in deviations) flies every history,
the air data come from its output map, and its steady flights, designs and
trimmable set are the linear model's (``ftc_mc.model.trimmable.LinearSteady``).

``--delay`` holds the trim commands for that long before every history (the
detection's delay; the side monitor names the side a median 0.1 s after the
lock, ``docs/findings/sixdof-side-monitor.md``).

A lock is **recoverable** when question 2 flies the 60 s.  Otherwise the
longest stay any search found (question 4's, or the horizon of question 1
when its least excess is not positive) decides: **lost** when it is shorter
than the short horizon, **none found** when it is shorter than the long one
(whose coarse nodes after 3 s may miss a history that exists), undecided
otherwise.  Every search is local (SLSQP): on ``x8-gryte2018`` at -26 deg
question 1 found no 3 s history where question 4's bisection found one of
4.0 s, so a verdict is evidence, not proof.  Prints one line per lock as it
ends and, last, the bands per side.

    python scripts/studies/study_recoverable.py [--airframe x8-pyfly]
        [--offsets=-30:5:1,6,7,8,10,12,15,20,25] [--sides left,right]
        [--delay 0] [--plant nonlinear] [--jobs 2] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import math
import time

import ftc_mc  # noqa: F401 -- the package first (its numba settings)
import numpy as np
from joblib import Parallel, delayed
from scipy.optimize import minimize

from ftc_mc.core.sixdof import plant as kernels
from ftc_mc.core.sixdof.layout import COMMAND, N_STATE, N_WIND, OUTPUT, STATE
from ftc_mc.design.lock_turn import design_point, envelope_box, healthy, lock_turn_lqr
from ftc_mc.io.atomic import write_text
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import build_sixdof_plant
from ftc_mc.model.trimmable import linear_steady_flight, steady_flight
from study_lock_turn import fly, nominal_gain  # this script's folder

DT, N_SUB, NODE = 0.1, 10, 0.2
"""Control period [s], RK4 sub-steps per period, command node spacing [s]."""
T_END = 60.0
ENVELOPE = dict(va=(12.0, 30.0), alpha=(-8.0, 12.0), bank=60.0)
"""The trials' validity envelope (``validity`` defaults) [m/s, deg, deg]."""
WIDE = envelope_box(ENVELOPE["va"], ENVELOPE["alpha"], ENVELOPE["bank"])
"""Where the oracle's design point may lie: the envelope less 0.5 of each bound."""
LONG_NODE = 1.0
"""Command node spacing of the long horizons after their first :data:`FINE_S` [s]."""
FINE_S = 3.0
"""The long horizons keep the fine nodes (:data:`NODE`, 0.1 s in question 4) this long [s]."""
MARGIN = 0.3
"""Excess the constructive transient must stay below [m/s or deg]."""
VERDICTS = ("recoverable", "lost", "none found", "undecided")
"""What the study says of a lock (module docstring)."""
SEED = 26
"""Root seed of the random starts (:func:`seed_of`)."""
AGREE = 0.05
"""Starts whose least excess is within this of the best one agree with it."""


class Problem:
    """One side and lock: the shooting problem of the module docstring."""

    def __init__(self, plant, side, lock, horizon, delay, node=NODE, coarse=None,
                 linear=False):
        self.tp, self.side, self.lock = plant.trim, side, lock
        self.plant, self.linear = plant, linear
        self.lo, self.hi = plant.u_lower, plant.u_upper
        self.thr, self.free = COMMAND["throttle"], COMMAND[healthy(side)]
        self.n_hold = int(round(delay / DT))
        self.n = self.n_hold + int(round(horizon / DT))
        self.tn = node_times(horizon, node, coarse)
        self.nn = len(self.tn)
        self.tk = np.arange(self.n - self.n_hold) * DT
        self.winds = np.zeros((self.n, N_WIND))

    def commands(self, z):
        """Commands (n, 3) of the node values ``z`` (throttle nodes, then
        healthy-elevon nodes); the trim commands during the delay."""
        c = np.tile(self.tp.u0, (self.n, 1))
        c[self.n_hold:, self.thr] = np.interp(self.tk, self.tn, z[:self.nn])
        c[self.n_hold:, self.free] = np.interp(self.tk, self.tn, z[self.nn:])
        c[:, COMMAND[self.side]] = self.lock
        return c

    def flight(self, z):
        """States (n + 1, 15) from the nominal trim (on the linear plant's
        model with ``linear``: ``x+ = A x + B u`` in deviations)."""
        x = self.tp.x0.copy()
        out = np.empty((self.n + 1, N_STATE))
        if self.linear:
            pl, out[0] = self.plant, x
            for k, c in enumerate(self.commands(z)):
                out[k + 1] = x = self.tp.x0 + pl.A @ (x - self.tp.x0) + pl.B @ (c - pl.u0)
            return out
        kernels.simulate(x, self.commands(z), self.tp.params, self.winds, DT, N_SUB, out)
        return out

    def excess(self, z):
        """The envelope's excess at every sample after the start (module
        docstring), all bounds stacked [m/s or deg]; large where the flight
        diverged."""
        return excess(self.flight(z)[1:], self.plant if self.linear else None)

    def bounds(self):
        return ([(self.lo[self.thr], self.hi[self.thr])] * self.nn
                + [(self.lo[self.free], self.hi[self.free])] * self.nn)

    def starts(self, design_cmd, rng):
        """The eight starting histories of question 1 (module docstring)."""
        nn, thr, free = self.nn, self.thr, self.free
        held = [(self.tp.u0[thr], self.tp.u0[free]), (design_cmd[thr], design_cmd[free]),
                (self.hi[thr], self.lock), (self.hi[thr], self.hi[free]),
                (self.hi[thr], self.lo[free])]
        out = [np.r_[np.full(nn, a), np.full(nn, b)] for a, b in held]
        out += [np.r_[rng.uniform(self.lo[thr], self.hi[thr], nn),
                      rng.uniform(self.lo[free], self.hi[free], nn)] for _ in range(3)]
        return out


def node_times(horizon, node, coarse=None):
    """Command node times [s] over ``horizon``: every ``node`` seconds, or,
    with ``coarse``, every ``node`` up to :data:`FINE_S` and every ``coarse``
    seconds after (the horizon itself always a node)."""
    if coarse is None or horizon <= FINE_S:
        return np.linspace(0.0, horizon, int(round(horizon / node)) + 1)
    fine = np.linspace(0.0, FINE_S, int(round(FINE_S / node)) + 1)
    late = np.arange(FINE_S + coarse, horizon, coarse)
    return np.r_[fine, late[late < horizon - 1e-9], horizon]


def excess(states, linear=None):
    """Envelope excess (module docstring) of states (n, 15) in still air; with
    ``linear`` (a ``SixDofPlant``), the air data of its output map, as the
    linear plant's truth reads them."""
    if linear is None:
        u, v, w = (states[:, STATE[k]] for k in ("u", "v", "w"))
        va = np.sqrt(u * u + v * v + w * w)
        alpha = np.degrees(np.arctan2(w, u))
    else:
        y = linear.trim.y0 + (states - linear.trim.x0) @ linear.C.T
        va, alpha = y[:, OUTPUT["Va"]], np.degrees(y[:, OUTPUT["alpha"]])
    bank = np.degrees(np.abs(states[:, STATE["phi"]]))
    g = np.concatenate([ENVELOPE["va"][0] - va, va - ENVELOPE["va"][1],
                        ENVELOPE["alpha"][0] - alpha, alpha - ENVELOPE["alpha"][1],
                        bank - ENVELOPE["bank"]])
    return np.where(np.isfinite(g), g, 1e3)


def least_excess(prob, z0):
    """Question 1 from one start: ``(s, z)``."""
    s0 = float(prob.excess(z0).max())
    r = minimize(lambda zs: zs[-1], np.r_[z0, s0], method="SLSQP",
                 bounds=prob.bounds() + [(None, None)],
                 constraints=[{"type": "ineq", "fun": lambda zs: zs[-1] - prob.excess(zs[:-1])}],
                 options=dict(maxiter=200))
    z = np.clip(r.x[:-1], *np.array(prob.bounds()).T)
    return float(prob.excess(z).max()), z


def transient(prob, design, z0):
    """Question 2's transient from one start: node values ``z``, or ``None``."""
    pt, idx = design.point, design.idx

    def cost_to_go(z):
        dev = prob.flight(z)[-1, idx] - pt.x[idx]
        return float(dev @ design.P @ dev)

    r = minimize(cost_to_go, z0, method="SLSQP", bounds=prob.bounds(),
                 constraints=[{"type": "ineq", "fun": lambda z: -MARGIN - prob.excess(z)}],
                 options=dict(maxiter=300))
    z = np.clip(r.x, *np.array(prob.bounds()).T)
    return z if prob.excess(z).max() <= 0.0 else None


class Replay:
    """Question 2's flight as ``scripts/studies/study_lock_turn.fly`` flies a
    controller: the transient's commands ``cmds`` (n, 3), then ``design``'s
    law."""

    def __init__(self, cmds, design):
        self.cmds, self.design, self.k = cmds, design, 0

    def command(self, x):
        k, self.k = self.k, self.k + 1
        return self.cmds[k].copy() if k < len(self.cmds) else self.design.command(x)


def study_lock(airframe_name, side, offset_deg, horizon, delay, transient_s, long_horizon,
               seed, linear=False):
    """The four questions for one side and lock offset [deg]; a dict of results.
    ``linear``: on the linear plant's model (its steady flights, designs,
    flights and air data) instead of the airframe's equations."""
    af = PRESETS[airframe_name].airframe
    plant = build_sixdof_plant(af)
    tp = plant.trim
    lin = plant if linear else None
    lock = float(tp.u0[COMMAND[side]] + math.radians(offset_deg))
    row = dict(side=side, offset_deg=offset_deg)
    row["trimmable"] = bool(linear_steady_flight(plant, side, lock) if linear
                            else steady_flight(af, side, lock).steady)
    try:
        pt = design_point(af, side, lock, box=WIDE, plant=lin)
        design = lock_turn_lqr(af, side, lock, point=pt, plant=lin)
        design_cmd = pt.cmd
        row["design_offset_deg"] = pt.design_offset_deg
    except ValueError:
        design, design_cmd = None, tp.u0
    rng = np.random.default_rng(seed)
    short = Problem(plant, side, lock, horizon, delay, linear=linear)
    found = sorted((least_excess(short, z0) for z0 in short.starts(design_cmd, rng)),
                   key=lambda r: r[0])
    row["least_excess"] = found[0][0]
    row["agree"] = sum(s <= found[0][0] + AGREE for s, _ in found)
    row["survived_s"], row["left_by"] = None, ""
    if design is not None and found[0][0] < -MARGIN:
        long = Problem(plant, side, lock, transient_s, delay, linear=linear)
        for z0 in long.starts(design_cmd, np.random.default_rng(seed))[:5]:
            z = transient(long, design, z0)
            if z is None:
                continue
            flown = fly(tp, None, plant.u_lower, plant.u_upper, side, lock,
                        Replay(long.commands(z), design), delay=0.0, linear=lin)
            if flown["survived"]:
                row["survived_s"] = T_END
                break
            if row["survived_s"] is None or flown["t_leave"] > row["survived_s"]:
                row["survived_s"], row["left_by"] = flown["t_leave"], flown["why"]
    row["least_excess_long"] = None
    if row["survived_s"] != T_END and row["least_excess"] <= 0.0:
        long = Problem(plant, side, lock, long_horizon, delay, coarse=LONG_NODE, linear=linear)
        row["least_excess_long"] = min(least_excess(long, z0)[0] for z0 in
                                       long.starts(design_cmd, np.random.default_rng(seed)))
    row["longest_stay_s"] = row["nominal_exit_s"] = None
    if row["survived_s"] != T_END:
        row["longest_stay_s"] = longest_stay(plant, side, lock, delay, long_horizon,
                                             design_cmd, seed, linear)
        gain = nominal_gain(airframe_name, plant)
        flown = fly(tp, gain, plant.u_lower, plant.u_upper, side, lock, linear=lin)
        row["nominal_exit_s"] = flown["t_leave"]
    row["verdict"] = verdict(row, horizon, long_horizon)
    return row


def verdict(row, horizon, long_horizon):
    """What the study says of one lock (module docstring), from every search
    that ran: a stay found by one search counts against another's failure."""
    if row["survived_s"] == T_END:
        return "recoverable"
    stay = row["longest_stay_s"]
    if row["least_excess"] <= 0.0:
        stay = max(stay, horizon)
    if row["least_excess_long"] is not None and row["least_excess_long"] <= 0.0:
        stay = max(stay, long_horizon)
    if stay < horizon:
        return "lost"
    return "none found" if stay < long_horizon else "undecided"


def longest_stay(plant, side, lock, delay, limit, design_cmd, seed, linear=False):
    """Question 4: the longest horizon [s] (0.1 s samples, at most ``limit``)
    over which some start's least excess is not positive."""
    def inside(k):
        h = k * DT
        prob = Problem(plant, side, lock, h, delay, node=0.1, coarse=LONG_NODE, linear=linear)
        starts = prob.starts(design_cmd, np.random.default_rng(seed))
        return any(least_excess(prob, z0)[0] <= 0.0 for z0 in starts)

    lo, hi, cap = 0, 1, int(round(limit / DT))  # inside(lo) holds
    while inside(hi):  # doubling, then bisection
        if hi == cap:
            return cap * DT
        lo, hi = hi, min(2 * hi, cap)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if inside(mid) else (lo, mid)
    return lo * DT


def seed_of(side, offset_deg):
    """The random starts' seed of one lock: its side and offset only, so that
    a lock's result does not depend on the other locks of the run."""
    return [SEED, ("left", "right").index(side), int(round(1000 * offset_deg)) % 2**32]


def parse_offsets(text):
    """Comma-separated offsets [deg], each a value or ``a:b:step`` (inclusive)."""
    out = []
    for part in text.split(","):
        if ":" in part:
            a, b, step = (float(v) for v in part.split(":"))
            out += [round(float(v), 6) for v in np.arange(a, b + step / 2, step)]
        else:
            out.append(float(part))
    return out


def bands(rows, key):
    """The contiguous offset ranges [deg] whose ``key`` holds, as text."""
    out, start, prev = [], None, None
    for r in rows:
        if r[key] and start is None:
            start = r["offset_deg"]
        if not r[key] and start is not None:
            out.append(f"{start:+g} to {prev:+g}")
            start = None
        prev = r["offset_deg"]
    if start is not None:
        out.append(f"{start:+g} to {prev:+g}")
    return ", ".join(out) or "none"


def line_of(r, a):
    """One lock's results as a line of text."""
    flown = ("60 s" if r["survived_s"] == T_END else "-" if r["survived_s"] is None
             else f"left at {r['survived_s']:.1f} s ({r['left_by']})")
    return (f"{r['side']:5s} {r['offset_deg']:+6.1f} deg | trimmable {str(r['trimmable']):5s} | "
            f"least excess in {a.horizon:g} s {r['least_excess']:+7.2f} ({r['agree']}/8 agree)"
            + ("" if r["least_excess_long"] is None else
               f", in {a.long_horizon:g} s {r['least_excess_long']:+7.2f}")
            + f" | flown {flown:28s} | {r['verdict']}"
            + ("" if r["longest_stay_s"] is None else
               f" | longest stay {r['longest_stay_s']:.1f} s, nominal LQR "
               + ("60 s" if r["nominal_exit_s"] is None else f"{r['nominal_exit_s']:.1f} s")))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--airframe", default="x8-pyfly")
    ap.add_argument("--offsets", default="-30:5:1,6,7,8,10,12,15,20,25",
                    help="offsets from trim [deg], comma-separated, each a value or a:b:step")
    ap.add_argument("--sides", default="left,right")
    ap.add_argument("--horizon", type=float, default=3.0, help="question 1 [s]")
    ap.add_argument("--transient", type=float, default=8.0, help="question 2 [s]")
    ap.add_argument("--long-horizon", type=float, default=20.0,
                    help="question 1 again, for locks neither flown nor lost [s]")
    ap.add_argument("--delay", type=float, default=0.0, help="trim held first [s]")
    ap.add_argument("--plant", choices=("nonlinear", "linear"), default="nonlinear",
                    help="linear: the linear plant's model (steady flights, designs, flights)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", default=None)
    a = ap.parse_args(argv)
    t0 = time.time()
    offsets = parse_offsets(a.offsets)
    tasks = [(side, off) for side in a.sides.split(",") for off in offsets]
    rows = []
    for r in Parallel(n_jobs=a.jobs, return_as="generator")(
            delayed(study_lock)(a.airframe, side, off, a.horizon, a.delay, a.transient,
                                a.long_horizon, seed_of(side, off), a.plant == "linear")
            for side, off in tasks):
        rows.append(r)
        print(line_of(r, a), flush=True)
    for side in a.sides.split(","):
        mine = [r for r in rows if r["side"] == side]
        for r in mine:
            for v in VERDICTS:
                r[v] = r["verdict"] == v
        print(f"{side}: trimmable {bands(mine, 'trimmable')}; "
              + "; ".join(f"{v} {bands(mine, v)}" for v in VERDICTS))
    print(f"wall {time.time() - t0:.0f} s")
    if a.json:
        write_text(a.json, json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
