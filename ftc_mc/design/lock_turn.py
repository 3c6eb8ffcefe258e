"""The reconfigured controller of a locked elevon: fly the steady turn.

The X8 has no rudder.  With one elevon locked away from trim, the healthy
elevon and the throttle must fly pitch and roll together, and a straight glide
no longer exists (:func:`ftc_mc.model.sixdof.trim6` with ``locked``); a steady
*turn* often does (:mod:`ftc_mc.model.trimmable`).  This module designs, for a
known side and lock position (an oracle: perfect and instant knowledge), the
controller that flies such a turn:

1. **Design point** (:func:`design_point`).  The steady flights with one lock
   form a two-parameter family (eight unknowns -- airspeed, angle of attack,
   sideslip, bank, pitch, turn rate, throttle, healthy elevon -- for six body
   accelerations).  The one picked is the closest to the nominal wings-level
   glide (``V0`` = 20 m/s, ``gamma0`` = -3 deg, bank 0), measured in units of
   the room the validity envelope leaves::

       J = ((V - V0) / s_V)^2 + ((gamma - gamma0) / s_gamma)^2 + (phi / s_phi)^2

   (:class:`DesignWeights`: ``s_V`` 2.5 m/s, ``s_gamma`` 2 deg, ``s_phi`` 20
   deg), minimised by SLSQP with the six accelerations as equality
   constraints, inside a *design box* smaller than the validity envelope
   (:class:`DesignBox`: airspeed 14-28 m/s, angle of attack -6 to 10 deg,
   bank 45 deg, throttle 0.05-0.95, healthy elevon within 25 deg, air-path
   angle -15 to +10 deg), so that the controller has room around its design
   point.  Starts: the solution of
   :func:`ftc_mc.model.trimmable.steady_flight`, the nominal trim, and any
   points given.
2. **A lock with no steady flight in the design box** (beyond about -24/+2
   deg from trim on ``x8-pyfly``): the design point is that of the nearest
   lock that has one (bisection between the lock and the trim position, to
   :data:`LOCK_TOLERANCE`), and the difference of the two lock positions
   enters the linear model as a constant input ``F`` (Theorem 4.1,
   :func:`ftc_mc.design.theorem41.biased_discounted_lqr`): the law then holds
   what it can (pitch, bank) and lets the rest (height, heading) go.
   With a *wide box* (:func:`envelope_box`, the validity envelope less 0.5
   of each bound and a margin of bank; ``monitor.turn_beyond: guarded``),
   such a lock is first designed about its own steady flight in that box, if
   it has one.
3. **Linear model**: scipy's adaptive finite differences of the authors'
   equations (:func:`ftc_mc.model.linear.jacobian` of
   :func:`ftc_mc.model.sixdof.derivatives`) at the design point, reduced to
   the states that a steady turn holds constant, :data:`TURN_STATES` (``phi,
   theta, u, v, w, p, q, r``, the throttle and the healthy elevon): the
   positions and the heading change steadily in a turn and no row of these
   states depends on them, so they are left out exactly; the locked elevon is
   a constant.  Zero-order hold at ``dt`` (:func:`ftc_mc.model.linear.zoh`).
4. **Gain**: discounted LQR (the paper's discount 0.999) on the two healthy
   commands, throttle and healthy elevon, by Theorem 4.1 (``F = 0`` for a
   steady design point; then the ordinary discounted LQR of
   :func:`ftc_mc.design.lqr.discounted_lqr`).  Bryson's rule
   (:class:`TurnWeights`).

The law (:meth:`LockTurnDesign.command`), on the true state (the oracle)::

    [throttle, healthy] = u* - K (x_turn - x_turn*) - k,   clipped to the limits

with the locked elevon's command its lock position.

5. **Table** (:func:`lock_turn_designs`): the designs of both sides
   over a uniform grid of lock offsets, computed once per airframe and cached
   on disk (:func:`ftc_mc.cache.lock_turn.cached_lock_turn_designs`); the
   ``lock_turn`` controller of the trial loop flies them,
   interpolated on the side monitor's lock estimate, with measurements in
   place of the oracle's true state (:mod:`ftc_mc.core.sixdof.lockturn`).
6. **On the linear plant** (``monitor.turn_model: linear``, or ``auto``
   there): the plant flies the 6-DOF linear model, whose steady flights are
   not the equations' (:class:`ftc_mc.model.trimmable.LinearSteady`: a plane
   per lock, found by the same cost in the same boxes on a convex problem;
   the side monitor gives such a table the wide box too), and steps 3-4 use
   its own discrete matrices,
   the held offset entering through the locked elevon's actuator and command
   columns.  On ``x8-pyfly`` its trimmable set is -4.87 to +5.68 deg (left),
   against -29 to +2.25 deg for the equations (``docs/findings/sixdof-lock-turn.md``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.optimize
from threadpoolctl import threadpool_limits

from ..core.sixdof.layout import COMMAND, OUTPUT, STATE
from ..model.airframe import Airframe
from ..model.linear import jacobian, zoh
from ..model.sixdof import build_sixdof_plant, derivatives, outputs, trim6
from ..model.trimmable import (UNKNOWNS, _state, linear_closest, linear_quantities,
                               linear_steady, steady_flight)
from .theorem41 import ALPHA, biased_discounted_lqr

TURN_RIGID = ("phi", "theta", "u", "v", "w", "p", "q", "r")
"""Rigid-body states a steady turn holds constant (fed back)."""

LOCK_TOLERANCE = math.radians(0.05)
"""Bisection tolerance [rad] of the nearest lock with a design point."""

_ROWS = [STATE[n] for n in ("u", "v", "w", "p", "q", "r")]
_SCALE = np.array([1.0, 1.0, 1.0, 10.0, 10.0, 10.0])  # as model/trimmable.py


def healthy(side: str) -> str:
    """The other elevon: ``"right"`` for ``"left"`` and back."""
    if side not in ("left", "right"):
        raise ValueError(f"side must be 'left' or 'right', got {side!r}")
    return "right" if side == "left" else "left"


def turn_states(side: str) -> tuple:
    """Names of the fed-back states with ``side`` locked: :data:`TURN_RIGID`,
    ``throttle`` and the healthy elevon (10)."""
    return TURN_RIGID + ("throttle", healthy(side))


@dataclasses.dataclass(frozen=True)
class DesignBox:
    """Where a design point may lie (inside the validity envelope, with room).

    Attributes
    ----------
    airspeed : (float, float)
        [m/s].
    alpha : (float, float)
        Angle of attack [rad].
    bank : float
        Largest bank [rad].
    throttle : (float, float)
        Throttle [-].
    elevon : float
        Largest healthy elevon deflection [rad].
    sideslip : float
        Largest sideslip [rad] (the bound of :mod:`ftc_mc.model.trimmable`).
    gamma : (float, float)
        Air-path angle [rad]: the validity envelope has no bound, but the
        family holds steep steady climbs (``x8-gryte2018``, 5 deg above trim:
        +60 deg at full throttle) that a glide cannot reach.
    """

    airspeed: tuple = (14.0, 28.0)
    alpha: tuple = (math.radians(-6.0), math.radians(10.0))
    bank: float = math.radians(45.0)
    throttle: tuple = (0.05, 0.95)
    elevon: float = math.radians(25.0)
    sideslip: float = 0.5
    gamma: tuple = (math.radians(-15.0), math.radians(10.0))

    def bounds(self):
        """Lower and upper bounds of the :data:`~ftc_mc.model.trimmable.UNKNOWNS`."""
        lo = np.array([self.airspeed[0], self.alpha[0], -self.sideslip, -self.bank, -1.2,
                       -2.0, self.throttle[0], -self.elevon])
        hi = np.array([self.airspeed[1], self.alpha[1], self.sideslip, self.bank, 1.2,
                       2.0, self.throttle[1], self.elevon])
        return lo, hi


def envelope_box(airspeed, alpha_deg, bank_deg, margin: float = 0.5,
                 bank_margin: float | None = None) -> DesignBox:
    """The validity envelope less ``margin`` of each bound, as a design box.

    Where the design box (:class:`DesignBox`) holds no steady flight of a lock,
    the envelope may still hold one: on ``x8-pyfly`` the steady turns closest
    to the nominal glide of locks from about -29 to -10 deg of trim lie at
    12.5-16.5 m/s and 58-60 deg of bank (``scripts/studies/study_recoverable.py``,
    docs/findings/sixdof-rocking-guard.md); with 10 deg of room below the bank bound, those of
    -15 to -11 deg at 12.5-14.7 m/s and 50 deg.  The air-path
    angle may then lie from -45 to +30 deg; the throttle, elevon and
    sideslip bounds are the design box's.

    Parameters
    ----------
    airspeed : (float, float)
        The envelope's airspeed bounds [m/s].
    alpha_deg : (float, float)
        Its angle-of-attack bounds [deg].
    bank_deg : float
        Its largest bank [deg].
    margin : float
        Room left inside each bound [m/s or deg].
    bank_margin : float, optional
        Room left below the largest bank [deg]; default ``margin``.
    """
    return DesignBox(airspeed=(airspeed[0] + margin, airspeed[1] - margin),
                     alpha=(math.radians(alpha_deg[0] + margin),
                            math.radians(alpha_deg[1] - margin)),
                     bank=math.radians(bank_deg - (margin if bank_margin is None
                                                   else bank_margin)),
                     gamma=(math.radians(-45.0), math.radians(30.0)))


@dataclasses.dataclass(frozen=True)
class DesignWeights:
    """Scales of the distance from the nominal glide (module docstring).

    Attributes
    ----------
    airspeed : float
        [m/s].
    gamma : float
        Air-path angle [rad].
    bank : float
        [rad].
    """

    airspeed: float = 2.5
    gamma: float = math.radians(2.0)
    bank: float = math.radians(20.0)


@dataclasses.dataclass(frozen=True)
class TurnWeights:
    """Bryson's rule for the turn LQR: deviations that cost one unit each.

    Attributes
    ----------
    phi, theta : float
        Bank and pitch [rad].
    u, v, w : float
        Body velocities [m/s].
    throttle : float
        Throttle command [-].
    elevon : float
        Healthy elevon command [rad].
    """

    phi: float = math.radians(5.0)
    theta: float = math.radians(5.0)
    u: float = 1.0
    v: float = 1.0
    w: float = 1.0
    throttle: float = 0.2
    elevon: float = math.radians(5.0)

    def matrices(self, side: str):
        """``Q`` (10 x 10) on :func:`turn_states` and ``R`` (2 x 2) on throttle
        and healthy elevon; the rates and actuator states unweighted."""
        names = turn_states(side)
        q = np.zeros(len(names))
        for n in ("phi", "theta", "u", "v", "w"):
            q[names.index(n)] = 1.0 / getattr(self, n) ** 2
        return np.diag(q), np.diag([1.0 / self.throttle ** 2, 1.0 / self.elevon ** 2])


@dataclasses.dataclass(frozen=True)
class DesignPoint:
    """The steady flight a lock-turn controller is designed about.

    Attributes
    ----------
    side : str
        Locked elevon, ``"left"`` or ``"right"``.
    lock : float
        Its absolute position [rad] (the fault).
    design_lock : float
        The lock position of the design point [rad]: ``lock`` when a steady
        flight exists in the box, else the nearest one that has one.
    offset_deg, design_offset_deg : float
        ``lock`` and ``design_lock`` less the trim position of that elevon [deg].
    values : dict
        :data:`~ftc_mc.model.trimmable.UNKNOWNS` (SI units, rad, rad/s) and
        ``gamma``, the air-path angle [rad].
    x : ndarray, shape (15,)
        The design state (positions and heading zero).
    cmd : ndarray, shape (3,)
        Its commands: throttle [-], left, right elevon [rad].
    residual : float
        Largest scaled body acceleration at the point (as
        :data:`ftc_mc.model.trimmable.RESIDUAL_TOL`).
    cost : float
        ``J`` of the module docstring.
    """

    side: str
    lock: float
    design_lock: float
    offset_deg: float
    design_offset_deg: float
    values: dict
    x: np.ndarray
    cmd: np.ndarray
    residual: float
    cost: float

    @property
    def steady(self) -> bool:
        """Whether the actual lock has the design point (no constant term)."""
        return self.design_lock == self.lock


def _closest(p, side, lock, box, weights, V0, gamma0, starts):
    """Best steady flight of one lock in the box: ``(J, w, residual)`` or ``None``."""
    lo, hi = box.bounds()

    def acc(w):
        x, cmd = _state(w, side, lock)
        return derivatives(x, cmd, p)[_ROWS] / _SCALE

    def gamma(w):
        x, _ = _state(w, side, lock)
        return outputs(x, p)[OUTPUT["gamma"]]

    def room(w):
        g = gamma(w)
        return np.array([g - box.gamma[0], box.gamma[1] - g])

    def cost(w):
        return (((w[0] - V0) / weights.airspeed) ** 2
                + ((gamma(w) - gamma0) / weights.gamma) ** 2
                + (w[3] / weights.bank) ** 2)

    best = None
    for w0 in starts:
        sol = scipy.optimize.minimize(cost, np.clip(w0, lo, hi), method="SLSQP",
                                      bounds=list(zip(lo, hi)),
                                      constraints=[{"type": "eq", "fun": acc},
                                                   {"type": "ineq", "fun": room}],
                                      options={"maxiter": 500, "ftol": 1e-14})
        w = np.clip(sol.x, lo, hi)
        res = float(np.max(np.abs(acc(w))))
        if res <= 1e-8 and np.min(room(w)) >= -1e-9 and (best is None or cost(w) < best[0]):
            best = (float(cost(w)), w, res)
    return best


def _polish(p, side, lock, w):
    """Polish a steady flight to round-off: the six accelerations solved for
    angle of attack, sideslip, bank, pitch, turn rate and healthy elevon
    (``scipy.optimize.least_squares`` from SLSQP's point, which is steady to
    1e-8), airspeed and throttle kept."""
    keep = w.copy()

    def res(z):
        ww = keep.copy()
        ww[[1, 2, 3, 4, 5, 7]] = z
        x, cmd = _state(ww, side, lock)
        return derivatives(x, cmd, p)[_ROWS] / _SCALE

    sol = scipy.optimize.least_squares(res, keep[[1, 2, 3, 4, 5, 7]], xtol=1e-15,
                                       ftol=1e-15, gtol=1e-15)
    ww = keep.copy()
    ww[[1, 2, 3, 4, 5, 7]] = sol.x
    return ww, float(np.max(np.abs(sol.fun)))


def _closest_linear(plant, side, lock, box, weights):
    """:func:`_closest` on the 6-DOF linear model ``plant``: ``(J, (s, z))`` or
    ``None`` (:func:`~ftc_mc.model.trimmable.linear_closest` in the box, the
    cost of the module docstring about the plant's trim)."""
    lo, hi = box.bounds()
    bounds = {"Va": box.airspeed, "alpha": box.alpha, "beta": (lo[2], hi[2]),
              "phi": (lo[3], hi[3]), "theta": (lo[4], hi[4]), "r": (lo[5], hi[5]),
              "throttle": box.throttle, "free_elevon": (lo[7], hi[7]), "gamma": box.gamma}
    tr = plant.trim
    cost = {"Va": (tr.V0, weights.airspeed), "gamma": (tr.gamma0, weights.gamma),
            "phi": (0.0, weights.bank)}
    s = linear_steady(plant, side, lock)
    z = linear_closest(plant, s, bounds, cost)
    if z is None:
        return None
    q = linear_quantities(plant, s)
    return (float(sum(((q[n][0] + q[n][1] @ z - t) / sc) ** 2 for n, (t, sc) in cost.items())),
            (s, z))


def _linear_point(plant, found):
    """State, commands (absolute), :data:`UNKNOWNS` with ``gamma``, and the
    steady residual of a steady flight of the linear model
    (:func:`_closest_linear`'s ``(s, z)``); its turn rate is the heading's
    rate of change [rad/s]."""
    s, z = found
    tr = plant.trim
    dx, du = s.x + s.X @ z, s.u + s.U @ z
    q = linear_quantities(plant, s)
    values = {"airspeed": "Va", "alpha": "alpha", "beta": "beta", "phi": "phi",
              "theta": "theta", "throttle": "throttle", "free_elevon": "free_elevon",
              "gamma": "gamma"}
    values = {k: float(q[n][0] + q[n][1] @ z) for k, n in values.items()}
    psi = STATE["psi"]
    values["turn_rate"] = float((plant.A[psi] @ dx + plant.B[psi] @ du - dx[psi]) / plant.dt)
    residual = float(np.max(np.abs(s.M @ z + s.c)))
    return tr.x0 + dx, tr.u0 + du, values, residual


def design_point(airframe: Airframe, side: str, lock: float, box: DesignBox = DesignBox(),
                 weights: DesignWeights = DesignWeights(), V0: float = 20.0,
                 gamma0_deg: float = -3.0, extra_starts=(),
                 nearest: bool = True, plant=None) -> DesignPoint | None:
    """The design point of the lock-turn controller (module docstring, steps 1-2).

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    side : {"left", "right"}
        The locked elevon.
    lock : float
        Its absolute position [rad].
    box : DesignBox
        Where the design point may lie.
    weights : DesignWeights
        Scales of the distance from the nominal glide.
    V0 : float
        Nominal airspeed [m/s].
    gamma0_deg : float
        Nominal air-path angle [deg].
    extra_starts : sequence of array_like
        More starting points (:data:`~ftc_mc.model.trimmable.UNKNOWNS`).
    nearest : bool
        Where the lock has no steady flight in the box, design about the
        nearest lock that has one (a bisection towards the trim position);
        False: return None instead.
    plant : SixDofPlant, optional
        Find the steady flight of this 6-DOF linear model
        (:class:`~ftc_mc.model.trimmable.LinearSteady`: the linear plant's own,
        ``monitor.turn_model: linear``) instead of the airframe's equations';
        its trim must be the one of ``V0`` and ``gamma0_deg``.

    Returns
    -------
    DesignPoint or None
        None only with ``nearest=False``.

    Raises
    ------
    ValueError
        When not even the trim position of the locked elevon has a steady
        flight in the box (``nearest`` only).
    """
    other = healthy(side)
    tr = trim6(airframe, V0, gamma0_deg)
    p = tr.params
    gamma0 = math.radians(gamma0_deg)
    trim_pos = float(tr.u0[COMMAND[side]])
    nominal = np.array([tr.V0, tr.alpha, 0.0, 0.0, tr.x0[STATE["theta"]], 0.0,
                        tr.u0[COMMAND["throttle"]], tr.u0[COMMAND[other]]])

    def attempt(pos, more=()):
        if plant is not None:
            return _closest_linear(plant, side, pos, box, weights)
        f = steady_flight(airframe, side, pos, starts=4)
        starts = [np.array([f.values[k] for k in UNKNOWNS]), nominal, *more]
        return _closest(p, side, pos, box, weights, tr.V0, gamma0, starts)

    best = attempt(lock, [np.asarray(s, dtype=float) for s in extra_starts])
    design_lock = float(lock)
    if best is None and not nearest:
        return None
    if best is None:
        inside = attempt(trim_pos)
        if inside is None:
            raise ValueError(f"no steady flight in the design box even with the {side} "
                             "elevon at its trim position")
        a, b = trim_pos, float(lock)  # a has a design point, b has none
        while abs(b - a) > LOCK_TOLERANCE:
            mid = 0.5 * (a + b)
            found = attempt(mid, [inside[1]])
            if found is None:
                b = mid
            else:
                a, inside = mid, found
        design_lock, best = a, inside
    if plant is not None:
        x, cmd, values, residual = _linear_point(plant, best[1])
    else:
        w, residual = _polish(p, side, design_lock, best[1])
        x, cmd = _state(w, side, design_lock)
        values = dict(zip(UNKNOWNS, (float(v) for v in w)))
        values["gamma"] = float(outputs(x, p)[OUTPUT["gamma"]])
    return DesignPoint(side=side, lock=float(lock), design_lock=design_lock,
                       offset_deg=math.degrees(lock - trim_pos),
                       design_offset_deg=math.degrees(design_lock - trim_pos),
                       values=values, x=x, cmd=cmd, residual=residual, cost=best[0])


@dataclasses.dataclass(frozen=True)
class LockTurnDesign:
    """The lock-turn controller: design point, reduced linear model and gain.

    Attributes
    ----------
    point : DesignPoint
    states : tuple of str
        The fed-back states (:func:`turn_states`), in the order of ``K``.
    idx : ndarray of int
        Their indices in the 15-state layout.
    inputs : tuple of int
        Command indices of the throttle and the healthy elevon.
    Ac, Bc : ndarray, shapes (10, 10), (10, 2), or None
        Continuous Jacobians at the design point [1/s] (of a linear model:
        its own, None when it has none).
    A, B : ndarray
        Their zero-order hold at ``dt`` (of a linear model: its discrete
        matrices' rows and columns).
    F : ndarray, shape (10,)
        Constant input per step from ``lock - design_lock`` (zero when steady).
    K : ndarray, shape (2, 10)
    k : ndarray, shape (2,)
        The law ``u = u* - K (x - x*) - k`` on throttle [-] and healthy elevon [rad].
    P : ndarray, shape (10, 10)
        Riccati solution of the discounted pair.
    Q, R : ndarray
        Weights.
    alpha : float
        Discount.
    dt : float
        Sampling period [s].
    u_lower, u_upper : ndarray, shape (3,)
        Absolute command limits.
    """

    point: DesignPoint
    states: tuple
    idx: np.ndarray
    inputs: tuple
    Ac: np.ndarray
    Bc: np.ndarray
    A: np.ndarray
    B: np.ndarray
    F: np.ndarray
    K: np.ndarray
    k: np.ndarray
    P: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    alpha: float
    dt: float
    u_lower: np.ndarray
    u_upper: np.ndarray

    @property
    def closed_loop(self) -> np.ndarray:
        """Discrete closed-loop eigenvalues of ``A - B K``."""
        return np.linalg.eigvals(self.A - self.B @ self.K)

    def command(self, x: np.ndarray) -> np.ndarray:
        """Absolute commands (3,) at the 15-state ``x``: the law on throttle and
        healthy elevon, clipped to the limits; the locked elevon at its lock."""
        pt = self.point
        dev = x[self.idx] - pt.x[self.idx]
        u = pt.cmd.copy()
        u[list(self.inputs)] += -self.K @ dev - self.k
        u[COMMAND[pt.side]] = pt.lock
        return np.clip(u, self.u_lower, self.u_upper)


def lock_turn_lqr(airframe: Airframe, side: str, lock: float, dt: float = 0.1,
                  weights: TurnWeights = TurnWeights(), alpha: float = ALPHA,
                  point: DesignPoint | None = None, plant=None,
                  **point_kw) -> LockTurnDesign:
    """Design the lock-turn controller of one side and lock (module docstring).

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    side : {"left", "right"}
        The locked elevon.
    lock : float
        Its absolute position [rad].
    dt : float
        Sampling period [s] of the zero-order hold and the law.
    weights : TurnWeights
        Bryson's rule.
    alpha : float
        Discount in (0, 1] (the paper's 0.999).
    point : DesignPoint, optional
        A design point already found for this side and lock.
    plant : SixDofPlant, optional
        Design on this 6-DOF linear model (``monitor.turn_model: linear``):
        its design point (:func:`design_point`'s ``plant``), and its own
        discrete matrices in place of the airframe's equations' Jacobians at
        the point; ``dt`` must be its period.
    **point_kw
        Passed to :func:`design_point`.

    Returns
    -------
    LockTurnDesign
    """
    if point is None:
        point = design_point(airframe, side, lock, plant=plant, **point_kw)
    names = turn_states(side)
    idx = np.array([STATE[n] for n in names])
    inputs = (COMMAND["throttle"], COMMAND[healthy(side)])
    locked = STATE[side]
    if plant is not None:
        if not math.isclose(plant.dt, dt):
            raise ValueError(f"the linear model's period is {plant.dt} s, not dt = {dt} s")
        Ac = None if plant.Ac is None else plant.Ac[np.ix_(idx, idx)]
        Bc = None if plant.Bc is None else plant.Bc[np.ix_(idx, list(inputs))]
        A = plant.A[np.ix_(idx, idx)]
        B = plant.B[np.ix_(idx, list(inputs))]
        # the held lock offset: its actuator state and its command
        F = (plant.A[idx, locked] + plant.B[idx, COMMAND[side]]) * (point.lock
                                                                    - point.design_lock)
    else:
        p = trim6(airframe).params
        x0, u0 = point.x, point.cmd
        Jx = jacobian(lambda x: derivatives(x, u0, p), x0)
        Ju = jacobian(lambda u: derivatives(x0, u, p), u0)
        Ac = Jx[np.ix_(idx, idx)]
        Bc = Ju[np.ix_(idx, list(inputs))]
        # the locked elevon's offset from the design lock as a third (held) input
        Ad, Bd = zoh(Ac, np.column_stack((Bc, Jx[idx, locked])), dt)
        A, B = np.array(Ad), np.array(Bd[:, :2])
        F = Bd[:, 2] * (point.lock - point.design_lock)
    Q, R = weights.matrices(side)
    sol = biased_discounted_lqr(A, B, F, Q, R, alpha)
    return LockTurnDesign(point=point, states=names, idx=idx, inputs=inputs, Ac=Ac, Bc=Bc,
                          A=A, B=B, F=F, K=sol.K, k=sol.k, P=sol.P, Q=Q, R=R,
                          alpha=float(alpha), dt=float(dt),
                          u_lower=np.array(airframe.command_lower, dtype=float),
                          u_upper=np.array(airframe.command_upper, dtype=float))


LOCK_TURN_TABLE_VERSION = "2"
"""Bumped when :func:`lock_turn_designs` changes what it computes (cache key)."""


@dataclasses.dataclass(frozen=True)
class LockTurnDesigns:
    """Lock-turn designs of both sides over a grid of lock offsets from trim.

    Attributes
    ----------
    offsets : ndarray, shape (n,)
        Lock offsets from each side's trim position [rad], uniform, ascending.
    lock : ndarray, shape (2, n)
        Absolute lock positions [rad] (left, right).
    x : ndarray, shape (2, n, 15)
        Design states, absolute (the 15-state layout).
    cmd : ndarray, shape (2, n, 3)
        Design commands, absolute.
    K : ndarray, shape (2, n, 2, 10)
        Gains on the fed-back states (:func:`turn_states` of the side).
    k : ndarray, shape (2, n, 2)
        Theorem 4.1's constant term.
    steady : ndarray of bool, shape (2, n)
        The lock has its own steady flight in the design box, or in the wide
        box where one was given (else the design is about the nearest lock
        that has one in the design box).
    """

    offsets: np.ndarray
    lock: np.ndarray
    x: np.ndarray
    cmd: np.ndarray
    K: np.ndarray
    k: np.ndarray
    steady: np.ndarray


SIDES = ("left", "right")
"""The elevons a lock-turn table holds, in its order (block codes 2 and 3)."""


def lock_turn_designs(airframe: Airframe, offsets, V0: float = 20.0,
                      gamma0_deg: float = -3.0, dt: float = 0.1,
                      wide: DesignBox | None = None, linear: bool = False) -> LockTurnDesigns:
    """:func:`lock_turn_lqr` of both sides at each lock offset from trim.

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    offsets : array_like, shape (n,)
        Lock offsets from the side's position in the 6-DOF trim [rad].
    V0, gamma0_deg : float
        The nominal glide [m/s], [deg]: the trim and the design point's target.
    dt : float
        Sampling period [s].
    wide : DesignBox, optional
        Where a lock has no steady flight in the design box, its design is
        about its own steady flight in this box if it has one
        (:func:`envelope_box`; ``monitor.turn_beyond: guarded``); else, and
        without it, about the nearest lock that has one in the design box.
    linear : bool
        Design on the 6-DOF linear model at the trim of ``V0``, ``gamma0_deg``
        and ``dt`` (:func:`~ftc_mc.model.sixdof.build_sixdof_plant`: the linear
        plant's own; ``monitor.turn_model: linear``) instead of the airframe's
        equations.

    Returns
    -------
    LockTurnDesigns

    Notes
    -----
    The designs are computed on one BLAS thread (``threadpoolctl``): the
    design points' SLSQP solutions move by up to 1.6e-7 (the gains by 5e-8)
    between one and two OpenBLAS threads, and the table must be the same to
    the bit on every machine, as the trials flown on it are.
    """
    offsets = np.asarray(offsets, dtype=float)
    with threadpool_limits(limits=1, user_api="blas"):
        return _designs(airframe, offsets, V0, gamma0_deg, dt, wide, linear)


def _designs(airframe, offsets, V0, gamma0_deg, dt, wide=None, linear=False) -> LockTurnDesigns:
    """:func:`lock_turn_designs` on the threads in force."""
    n = offsets.size
    plant = build_sixdof_plant(airframe, V0, gamma0_deg, dt) if linear else None
    trim_cmd = trim6(airframe, V0, gamma0_deg).u0
    lock = np.empty((2, n))
    x = np.empty((2, n, len(STATE)))
    cmd = np.empty((2, n, len(COMMAND)))
    K = np.empty((2, n, 2, len(turn_states("left"))))
    k = np.empty((2, n, 2))
    steady = np.empty((2, n), dtype=bool)
    for s, side in enumerate(SIDES):
        for i, off in enumerate(offsets):
            lock[s, i] = trim_cmd[COMMAND[side]] + off
            point = None  # the design box's, with its nearest steady lock if need be
            if wide is not None:  # the lock's own steady flight in either box first
                for box in (DesignBox(), wide):
                    if point is None:
                        point = design_point(airframe, side, float(lock[s, i]), box=box,
                                             V0=V0, gamma0_deg=gamma0_deg, nearest=False,
                                             plant=plant)
            d = lock_turn_lqr(airframe, side, float(lock[s, i]), dt, point=point, V0=V0,
                              gamma0_deg=gamma0_deg, plant=plant)
            x[s, i], cmd[s, i] = d.point.x, d.point.cmd
            K[s, i], k[s, i] = d.K, d.k
            steady[s, i] = d.point.lock == d.point.design_lock
    return LockTurnDesigns(offsets=offsets, lock=lock, x=x, cmd=cmd, K=K, k=k,
                           steady=steady)


__all__ = ["TURN_RIGID", "LOCK_TOLERANCE", "healthy", "turn_states", "DesignBox", "envelope_box",
           "DesignWeights", "TurnWeights", "DesignPoint", "design_point",
           "LockTurnDesign", "lock_turn_lqr", "LOCK_TURN_TABLE_VERSION", "LockTurnDesigns",
           "SIDES", "lock_turn_designs"]
