"""Steady flight of the flying wing with one elevon locked.

The X8 has no rudder: with one elevon locked, pitch and roll share the healthy
elevon, and the throttle is the only other control.  A lock offset is
*trimmable* when some steady flight exists with it -- straight or turning, at
any airspeed and flight path inside the validity envelope -- with the healthy
elevon and the throttle within their limits.

Steady flight (no wind) means constant body velocities and rates: a level or
climbing/descending turn at the turn rate ``Omega`` about the vertical, body
rates ``(p, q, r) = Omega (-sin theta, sin phi cos theta, cos phi cos theta)``,
and the six body accelerations of the authors' equations
(:func:`ftc_mc.model.sixdof.derivatives`) zero.  The unknowns are airspeed,
angle of attack, sideslip, bank, pitch, turn rate, throttle and the healthy
elevon: eight unknowns for six conditions, so a lock is trimmable when the
least-squares residual over the envelope's box reaches zero
(``scipy.optimize.least_squares`` with bounds, from the trim and from
``starts`` random points of the box).  With ``V0`` and ``gamma0`` given, the
airspeed is fixed and the air-path angle is a seventh condition.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.optimize

from ..core.sixdof.layout import COMMAND, LAYOUT, N_COMMAND, N_STATE, OUTPUT, STATE
from .airframe import Airframe
from .sixdof import derivatives, outputs, pack_parameters, trim6

UNKNOWNS = ("airspeed", "alpha", "beta", "phi", "theta", "turn_rate", "throttle",
            "free_elevon")
"""The unknowns of a steady flight, in order (SI units, rad, rad/s)."""

RESIDUAL_TOL = 1e-9
"""Largest scaled acceleration residual [m/s^2; rad/s^2 / 10] of a steady flight."""


@dataclasses.dataclass(frozen=True)
class Envelope:
    """The box the search stays in.

    Attributes
    ----------
    airspeed : (float, float)
        [m/s] (``validity.airspeed_*_mps``).
    alpha : (float, float)
        Angle of attack [rad] (``validity.alpha_*_deg``).
    bank : float
        Largest bank [rad] (``validity.bank_max_deg``).
    """

    airspeed: tuple = (12.0, 30.0)
    alpha: tuple = (math.radians(-8.0), math.radians(12.0))
    bank: float = math.radians(60.0)


@dataclasses.dataclass(frozen=True)
class SteadyFlight:
    """The best steady flight found with one elevon locked.

    Attributes
    ----------
    side : str
        ``"left"`` or ``"right"``: the locked elevon.
    lock : float
        Its absolute position [rad].
    offset : float
        ``lock`` less the trim's position of that elevon [rad].
    residual : float
        Largest scaled acceleration left (:data:`RESIDUAL_TOL` or less: steady).
    values : dict
        :data:`UNKNOWNS` -> value at the best point; ``gamma`` the air-path angle.
    """

    side: str
    lock: float
    offset: float
    residual: float
    values: dict

    @property
    def steady(self) -> bool:
        """Whether a steady flight exists (the residual reached zero)."""
        return self.residual <= RESIDUAL_TOL


def _state(w, side, pos):
    V, alpha, beta, phi, theta, om, thr, e = w
    x = np.zeros(N_STATE)
    x[STATE["phi"]], x[STATE["theta"]] = phi, theta
    x[STATE["u"]] = V * math.cos(alpha) * math.cos(beta)
    x[STATE["v"]] = V * math.sin(beta)
    x[STATE["w"]] = V * math.sin(alpha) * math.cos(beta)
    x[STATE["p"]] = -om * math.sin(theta)
    x[STATE["q"]] = om * math.sin(phi) * math.cos(theta)
    x[STATE["r"]] = om * math.cos(phi) * math.cos(theta)
    cmd = np.zeros(N_COMMAND)
    cmd[COMMAND["throttle"]] = thr
    cmd[COMMAND[side]] = pos
    cmd[COMMAND["right" if side == "left" else "left"]] = e
    for name in LAYOUT.actuators:
        x[STATE[name]] = cmd[COMMAND[name]]
    return x, cmd


def steady_flight(airframe: Airframe, side: str, lock: float, envelope: Envelope = Envelope(),
                  V0: float | None = None, gamma0_deg: float | None = None, starts: int = 12,
                  seed: int = 0) -> SteadyFlight:
    """The best steady flight with the ``side`` elevon locked at ``lock`` [rad].

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    side : {"left", "right"}
    lock : float
        Absolute position of the locked elevon [rad].
    envelope : Envelope
    V0, gamma0_deg : float, optional
        Fix the airspeed [m/s] and the air-path angle [deg]; free by default.
    starts : int
        Random starting points tried after the trim (the search stops at the
        first steady one).
    seed : int
        Their generator's seed.
    """
    tr = trim6(airframe)
    p = pack_parameters(airframe, tr.V0, tr.gamma0)
    rows = [STATE[n] for n in ("u", "v", "w", "p", "q", "r")]
    scale = np.array([1.0, 1.0, 1.0, 10.0, 10.0, 10.0])
    lo_e, hi_e = airframe.elevon_limits
    lo_t, hi_t = airframe.throttle_limits
    lo = np.array([envelope.airspeed[0], envelope.alpha[0], -0.5, -envelope.bank, -1.2,
                   -2.0, lo_t, lo_e])
    hi = np.array([envelope.airspeed[1], envelope.alpha[1], 0.5, envelope.bank, 1.2, 2.0,
                   hi_t, hi_e])
    free = slice(0 if V0 is None else 1, None)  # a fixed airspeed is no unknown
    lo, hi = lo[free], hi[free]

    def full(w):
        return w if V0 is None else np.concatenate(([V0], w))

    def residual(w):
        x, cmd = _state(full(w), side, lock)
        out = derivatives(x, cmd, p)[rows] / scale
        if gamma0_deg is not None:
            out = np.append(out, outputs(x, p)[OUTPUT["gamma"]] - math.radians(gamma0_deg))
        return out

    other = "right" if side == "left" else "left"
    first = np.array([tr.V0, tr.alpha, 0.0, 0.0, tr.x0[STATE["theta"]], 0.0,
                      tr.u0[COMMAND["throttle"]], tr.u0[COMMAND[other]]])
    first = first[free]
    rng = np.random.default_rng(seed)
    best = None
    for s in range(starts + 1):
        w0 = np.clip(first, lo, hi) if s == 0 else rng.uniform(lo, hi)
        sol = scipy.optimize.least_squares(residual, w0, bounds=(lo, hi), xtol=1e-15,
                                           ftol=1e-15, gtol=1e-15)
        if best is None or sol.cost < best.cost:
            best = sol
        if np.max(np.abs(best.fun)) <= RESIDUAL_TOL:
            break
    w = full(best.x)
    x, _ = _state(w, side, lock)
    values = dict(zip(UNKNOWNS, (float(v) for v in w)))
    values["gamma"] = float(outputs(x, p)[OUTPUT["gamma"]])
    return SteadyFlight(side=side, lock=float(lock),
                        offset=float(lock - tr.u0[COMMAND[side]]),
                        residual=float(np.max(np.abs(best.fun))), values=values)


def trimmable_set(airframe: Airframe, side: str, offsets_deg, **kw) -> list:
    """:func:`steady_flight` at each lock offset from trim [deg] of ``side``."""
    tr = trim6(airframe)
    return [steady_flight(airframe, side, tr.u0[COMMAND[side]] + math.radians(o), **kw)
            for o in offsets_deg]


def bisect_band(steady, start: float, limits, tol: float):
    """The band of locks around ``start`` for which ``steady`` holds, its ends
    found by bisection towards each limit.

    Parameters
    ----------
    steady : callable
        ``steady(lock) -> bool``.
    start : float
        A lock for which it holds [rad].
    limits : (float, float)
        The lowest and highest locks [rad]: an end that holds is the band's.
    tol : float
        Largest distance of each end from the nearest lock where it fails [rad].

    Returns
    -------
    (float, float) or None
        The lowest and highest locks found to hold; None when ``start`` does
        not.  Bisection assumes one interval: a lock beyond a failing one is
        not tried (``scripts/studies/study_trimmable.py`` checks a grid).
    """
    if not tol > 0.0:
        raise ValueError(f"bisect_band: tol must be > 0, got {tol!r}")
    if not steady(start):
        return None
    ends = []
    for limit in limits:
        inside, outside = start, limit
        if steady(limit):
            ends.append(float(limit))
            continue
        while abs(outside - inside) > tol:
            mid = 0.5 * (inside + outside)
            if mid in (inside, outside):  # adjacent floats: no finer lock exists
                break
            inside, outside = (mid, outside) if steady(mid) else (inside, mid)
        ends.append(float(inside))
    return tuple(ends)


def equations_trimmable_set(airframe: Airframe, side: str, envelope: Envelope = Envelope(),
                            tol: float = math.radians(0.05)):
    """The locks of the ``side`` elevon [rad, absolute] for which
    :func:`steady_flight` finds a steady flight of the airframe's equations
    inside ``envelope``: :func:`bisect_band` from the trim towards the elevon
    limits, to ``tol`` [rad] (about 20 searches per side, 0.1 s for a lock
    that has one and up to 13 s for one that has none).  From the 6-DOF trim:
    ``x8-pyfly`` -29.27 to +2.34 deg (left elevon) and -28.85 to +2.62 deg
    (right), where a 0.25 deg grid from -30 to +6 deg finds one interval each,
    -29.25 to +2.25 and -28.75 to +2.5 deg; ``x8-gryte2018`` -33.52 to +6.26
    deg on both sides, whose lower end is the elevon's limit (-30 deg)."""
    start = trim6(airframe).u0[COMMAND[side]]
    return bisect_band(lambda lock: steady_flight(airframe, side, lock, envelope).steady,
                       start, airframe.elevon_limits, tol)


LINEAR_FREE = ("phi", "theta", "u", "v", "w", "p", "q", "r")
"""The rigid-body states of a steady flight of the 6-DOF linear model (its
unknowns, with the throttle and the healthy elevon)."""


@dataclasses.dataclass(frozen=True)
class LinearSteady:
    """The steady flights of the 6-DOF linear model with one elevon locked.

    The linear plant (``plant.kind: linear``) flies ``x+ = A x + B u`` in
    deviations from its trim, and has no steady turn in the sense of the
    authors' equations: its pitch rate, for one, stays ``q`` where a banked
    turn has ``Omega sin(phi) cos(theta)``.  A flight of it is steady when the
    rigid-body states of :data:`LINEAR_FREE` repeat, ``x = A x + B u`` on their
    rows, with each actuator at its command.  With ``z`` their deviations
    and the throttle's and healthy elevon's command deviations (10), the
    state deviation is ``x + X z`` and the command deviation ``u + U z``
    (positions and heading zero, the locked elevon at its lock), and the
    flight is steady when ``M z + c = 0`` (8 conditions): a plane of
    steady flights per lock.

    Attributes
    ----------
    side : str
        The locked elevon.
    lock : float
        Its absolute position [rad].
    x, X : ndarray, shapes (15,), (15, 10)
    u, U : ndarray, shapes (3,), (3, 10)
    M, c : ndarray, shapes (8, 10), (8,)
    """

    side: str
    lock: float
    x: np.ndarray
    X: np.ndarray
    u: np.ndarray
    U: np.ndarray
    M: np.ndarray
    c: np.ndarray


def linear_steady(plant, side: str, lock: float) -> LinearSteady:
    """:class:`LinearSteady` of ``plant`` (a
    :class:`~ftc_mc.model.sixdof.SixDofPlant`) with the ``side`` elevon locked
    at ``lock`` [rad, absolute]."""
    other = "right" if side == "left" else "left"
    free = [STATE[n] for n in LINEAR_FREE]
    inputs = [COMMAND["throttle"], COMMAND[other]]
    n = len(free) + len(inputs)
    X = np.zeros((N_STATE, n))
    U = np.zeros((N_COMMAND, n))
    X[free, np.arange(len(free))] = 1.0
    U[inputs, len(free) + np.arange(len(inputs))] = 1.0
    u = np.zeros(N_COMMAND)
    u[COMMAND[side]] = lock - plant.u0[COMMAND[side]]
    x = np.zeros(N_STATE)
    for name in LAYOUT.actuators:  # each actuator at its command
        x[STATE[name]] = u[COMMAND[name]]
        X[STATE[name]] = U[COMMAND[name]]
    A, B = np.asarray(plant.A), np.asarray(plant.B)
    G = A[free] - np.eye(N_STATE)[free]
    return LinearSteady(side=side, lock=float(lock), x=x, X=X, u=u, U=U,
                        M=G @ X + B[free] @ U, c=G @ x + B[free] @ u)


def linear_quantities(plant, s: LinearSteady) -> dict:
    """The quantities a box bounds, each affine in ``z``: name -> ``(a, b)``
    with the absolute value ``a + b @ z``: ``Va`` [m/s], ``alpha``, ``beta``,
    ``gamma``, ``phi``, ``theta`` [rad], ``r`` [rad/s] (the linear plant's
    outputs and states) and the ``throttle`` [-] and ``free_elevon`` [rad]
    commands."""
    tr = plant.trim
    C = np.asarray(plant.C)
    y0 = tr.y0
    out = {n: (y0[OUTPUT[n]] + C[OUTPUT[n]] @ s.x, C[OUTPUT[n]] @ s.X)
           for n in ("Va", "alpha", "beta", "gamma")}
    for n in ("phi", "theta", "r"):
        out[n] = (tr.x0[STATE[n]] + s.x[STATE[n]], s.X[STATE[n]])
    other = "right" if s.side == "left" else "left"
    for n, k in (("throttle", COMMAND["throttle"]), ("free_elevon", COMMAND[other])):
        out[n] = (plant.u0[k] + s.u[k], s.U[k])
    return out


def _bound_rows(q: dict, bounds: dict, slopes: dict | None = None):
    """``G v <= h`` for the bounds on the quantities ``q``
    (:func:`linear_quantities`): ``v`` is ``z``, or ``z`` and the lock when
    ``slopes`` gives each quantity's change per radian of lock."""
    rows, rhs = [], []
    for name, (lo, hi) in bounds.items():
        a, b = q[name]
        if slopes is not None:
            b = np.append(b, slopes[name])
        for bound, sign in ((lo, -1.0), (hi, 1.0)):
            if bound is not None:  # sign (a + b v) <= sign bound
                rows.append(sign * b)
                rhs.append(sign * (bound - a))
    return np.array(rows), np.array(rhs)


def linear_closest(plant, s: LinearSteady, bounds: dict, cost=None):
    """A steady flight of ``s`` inside ``bounds``, or None.

    Parameters
    ----------
    plant : SixDofPlant
    s : LinearSteady
    bounds : dict
        Name of :func:`linear_quantities` -> ``(lo, hi)`` (absolute; either
        may be None).
    cost : dict, optional
        Name -> ``(target, scale)``: the flight minimising the sum of
        ``((value - target) / scale)^2`` (SLSQP; the problem is convex);
        default: any flight inside (``scipy.optimize.linprog``).

    Returns
    -------
    ndarray, shape (10,), or None
        ``z`` (:class:`LinearSteady`).
    """
    q = linear_quantities(plant, s)
    G, h = _bound_rows(q, bounds)
    if cost is None:
        sol = scipy.optimize.linprog(np.zeros(s.M.shape[1]), A_ub=G, b_ub=h, A_eq=s.M,
                                     b_eq=-s.c, bounds=(None, None), method="highs")
        return sol.x if sol.status == 0 else None
    terms = [(q[n][0] - t, q[n][1], sc) for n, (t, sc) in cost.items()]

    def f(z):
        return sum(((a + b @ z) / sc) ** 2 for a, b, sc in terms)

    def grad(z):
        return sum(2.0 * (a + b @ z) / sc ** 2 * b for a, b, sc in terms)

    sol = scipy.optimize.minimize(
        f, np.zeros(s.M.shape[1]), jac=grad, method="SLSQP",
        constraints=[{"type": "eq", "fun": lambda z: s.M @ z + s.c, "jac": lambda z: s.M},
                     {"type": "ineq", "fun": lambda z: h - G @ z, "jac": lambda z: -G}],
        options={"maxiter": 500, "ftol": 1e-14})
    z = sol.x
    if np.max(np.abs(s.M @ z + s.c)) > RESIDUAL_TOL or np.min(h - G @ z) < -1e-9:
        return None
    return z


def _linear_bounds(plant, envelope: Envelope) -> dict:
    """The bounds of :func:`linear_steady_flight` (:func:`linear_closest`'s form)."""
    af = plant.airframe
    return {"Va": envelope.airspeed, "alpha": envelope.alpha,
            "phi": (-envelope.bank, envelope.bank), "beta": (-0.5, 0.5),
            "theta": (-1.2, 1.2), "r": (-2.0, 2.0), "throttle": af.throttle_limits,
            "free_elevon": af.elevon_limits}


def linear_steady_flight(plant, side: str, lock: float,
                         envelope: Envelope = Envelope()) -> bool:
    """Whether the 6-DOF linear model has a steady flight (:class:`LinearSteady`)
    with the ``side`` elevon locked at ``lock`` [rad] inside ``envelope``, with
    the throttle and the healthy elevon within the airframe's limits and the
    sideslip, pitch and yaw rate within :func:`steady_flight`'s bounds."""
    return linear_closest(plant, linear_steady(plant, side, lock),
                          _linear_bounds(plant, envelope)) is not None


def linear_trimmable_set(plant, side: str, envelope: Envelope = Envelope()):
    """The locks of the ``side`` elevon [rad, absolute] for which
    :func:`linear_steady_flight` holds: an interval, ``(lo, hi)``, or None when
    no lock has a steady flight inside ``envelope``.

    Every term of :class:`LinearSteady` and :func:`linear_quantities` is affine
    in the lock, so the pairs (lock, ``z``) of steady flights inside the bounds
    form a polytope, and the trimmable locks its projection: an interval,
    whose ends two linear programmes (``scipy.optimize.linprog``) find.  The
    lock itself is bounded only by the airframe's elevon limits.
    """
    lo_lim, hi_lim = plant.airframe.elevon_limits
    base, unit = linear_steady(plant, side, 0.0), linear_steady(plant, side, 1.0)
    q0, q1 = linear_quantities(plant, base), linear_quantities(plant, unit)
    G, h = _bound_rows(q0, _linear_bounds(plant, envelope),
                       {n: q1[n][0] - q0[n][0] for n in q0})  # change per radian of lock
    A_eq = np.column_stack([base.M, unit.c - base.c])
    ends = []
    for direction in (1.0, -1.0):  # the lowest lock, then the highest
        cost = np.zeros(A_eq.shape[1])
        cost[-1] = direction
        sol = scipy.optimize.linprog(cost, A_ub=G, b_ub=h, A_eq=A_eq, b_eq=-base.c,
                                     bounds=[(None, None)] * base.M.shape[1]
                                     + [(lo_lim, hi_lim)], method="highs")
        if sol.status == 2:  # infeasible: no lock has a steady flight
            return None
        if sol.status != 0:
            raise RuntimeError(f"linear_trimmable_set ({side}): linprog failed: "
                               f"{sol.message}")
        ends.append(float(sol.x[-1]))
    return tuple(ends)


def trimmable_summary(plant, equations: dict) -> dict:
    """The trimmable set of each elevon: the locks with a steady flight inside
    the default validity envelope (:class:`Envelope`), of ``plant``'s linear
    model (exact, :func:`linear_trimmable_set`) and of the airframe's equations
    (``equations``: side -> ``(lo, hi)`` or None, as
    :func:`equations_trimmable_set` finds them; cached by
    :func:`ftc_mc.cache.trimmable.cached_trimmable_sets`).  Model -> side ->
    ``lo_deg``, ``hi_deg`` (offsets from ``plant``'s trim position of that
    elevon) and ``lo_rad``, ``hi_rad`` (absolute), or None where no lock has a
    steady flight."""
    sides = ("left", "right")
    found = {"linear": {side: linear_trimmable_set(plant, side) for side in sides},
             "equations": equations}
    out = {}
    for model_name, ends in found.items():
        out[model_name] = {}
        for side in sides:
            e = ends[side]
            trim = plant.u0[COMMAND[side]]
            out[model_name][side] = None if e is None else {
                "lo_deg": math.degrees(e[0] - trim), "hi_deg": math.degrees(e[1] - trim),
                "lo_rad": e[0], "hi_rad": e[1]}
    return out


def format_trimmable_summary(sets: dict) -> str:
    """Human-readable text of :func:`trimmable_summary`."""
    env = Envelope()
    lines = ["trimmable set: the elevon locks with a steady flight (straight or "
             "turning) inside the validity envelope ({:g}-{:g} m/s, alpha {:g} to "
             "{:g} deg, bank up to {:g} deg), offsets from trim".format(
                 *env.airspeed, *np.degrees(env.alpha), math.degrees(env.bank))]
    for model_name, label in (("linear", "linear model (exact)"),
                              ("equations", "equations (bisection, 0.05 deg)")):
        found = sets[model_name]
        lines.append(f"  {label:34s}" + ", ".join(
            f"{side} " + ("none" if found[side] is None else
                          f"{found[side]['lo_deg']:+.2f} to {found[side]['hi_deg']:+.2f} deg")
            for side in ("left", "right")))
    return "\n".join(lines)
