"""The 6-DOF X8: parameters, trim, numerical linearisation, named modes.

The equations are the Numba kernels of :mod:`ftc_mc.core.sixdof.plant` (the
authors' simulator, krisgry/x8 ``forces.m`` and ``dynamics.m``); names and
indices come from :mod:`ftc_mc.core.sixdof.layout`.  This module is imported
only on the 6-DOF path (``ftc-mc model --dof 6``), never by a longitudinal run,
so the 6-DOF kernels are never compiled or loaded there.

Trim (:func:`trim6`): a steady straight glide at airspeed ``V0`` and air-path
angle ``gamma0`` along the reference track (north), still air, the
longitudinal trim's approach (``ftc_mc.model.linear.trim``) extended to the
lateral unknowns: solve ``d(u, v, w, p, q, r)/dt = 0``, air-path angle
``gamma0`` and no east velocity for ``alpha, beta, phi, theta, psi``, throttle,
elevator and aileron (``scipy.optimize.root``).  With no propeller torque the
solution is wings level (``beta = phi = psi = aileron = 0``) and equals the
longitudinal trim; PyFly's file has a propeller torque (``k_T_P``), which the
trim balances with a small aileron, sideslip and bank (``docs/reference/airframes.md``).

Linearisation (:func:`build_sixdof_plant`): scipy's adaptive finite differences
of the kernels at the trim (``ftc_mc.model.linear.jacobian``), then the
zero-order hold of ``ftc_mc.model.linear.zoh``: 12 rigid-body states plus the
throttle and each elevon (15), 3 commands, 19 outputs, and the gust input
matrices of the six wind components (:func:`gust_jacobians`).  The wind of
either plant comes from the longitudinal and lateral Dryden models
(``ftc_mc.model.turbulence``), placed by :func:`sixdof_wind`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.optimize

from ..core.sixdof import plant as kernels
from ..core.sixdof.layout import (COMMAND, LAYOUT, N_COMMAND, N_OUTPUT, N_RIGID,
                                  N_STATE, N_WIND, PARAM, STATE)
from ..errors import UserError
from .airframe import Airframe
from .linear import _fmt, jacobian, zoh
from .summary import mode_table

_STILL_AIR = np.zeros(N_WIND)


def require_lateral(airframe: Airframe, where: str = "airframe") -> None:
    """Refuse an airframe without lateral-directional data, naming the fields.

    Parameters
    ----------
    airframe : Airframe
    where : str
        The airframe's name or file, for the error line.

    Raises
    ------
    UserError
        One line: the 6-DOF model needs the missing fields, each named.
    """
    missing = airframe.missing_lateral
    if missing:
        raise UserError(f"{where}: the 6-DOF model needs the lateral-directional "
                        f"field{'s' if len(missing) > 1 else ''} {', '.join(missing)}, "
                        "missing in this airframe (docs/reference/airframes.md lists them; "
                        "`ftc-mc model --airframe x8-pyfly --export FILE.yaml` writes "
                        "a complete file)")


def pack_parameters(airframe: Airframe, V0: float, gamma0: float) -> np.ndarray:
    """Pack an airframe and the reference glide path for the 6-DOF kernels.

    Parameters
    ----------
    airframe : Airframe
        With every lateral-directional field (:func:`require_lateral`).
    V0 : float
        Reference airspeed of the glide path [m/s].
    gamma0 : float
        Reference flight-path angle [rad] (negative when descending).

    Returns
    -------
    numpy.ndarray
        Shape ``(N_PARAM,)`` in the order of ``layout.PARAM_NAMES``.
    """
    require_lateral(airframe)
    values = dict(dataclasses.asdict(airframe), V0=V0, gamma0=gamma0)
    return np.array([float(values[n]) for n in LAYOUT.params], dtype=np.float64)


def derivatives(x, cmd, p, wind=None) -> np.ndarray:
    """``dx/dt`` of the 6-DOF model (:func:`ftc_mc.core.sixdof.plant.derivatives`).

    Parameters
    ----------
    x : array_like, shape (15,)
        State (:mod:`ftc_mc.core.sixdof.layout`).
    cmd : array_like, shape (3,)
        Absolute commands: throttle [-], left, right elevon [rad].
    p : ndarray
        Packed parameters (:func:`pack_parameters`).
    wind : array_like, shape (6,), optional
        Body-axis gusts [m/s, rad/s]; still air when omitted.

    Returns
    -------
    ndarray, shape (15,)
    """
    dx = np.empty(N_STATE)
    w = _STILL_AIR if wind is None else np.ascontiguousarray(wind, dtype=np.float64)
    kernels.derivatives(np.ascontiguousarray(x, dtype=np.float64),
                        np.ascontiguousarray(cmd, dtype=np.float64), p, w, dx)
    return dx


def outputs(x, p, wind=None) -> np.ndarray:
    """The 19 outputs of the 6-DOF model (:func:`ftc_mc.core.sixdof.plant.outputs`)."""
    y = np.empty(N_OUTPUT)
    w = _STILL_AIR if wind is None else np.ascontiguousarray(wind, dtype=np.float64)
    kernels.outputs(np.ascontiguousarray(x, dtype=np.float64), p, w, y)
    return y


def elevons(elevator: float, aileron: float) -> tuple:
    """Left and right elevon from elevator and aileron (PyFly's mixing).

    ``left = elevator + aileron``, ``right = elevator - aileron`` [rad].
    """
    return elevator + aileron, elevator - aileron


@dataclasses.dataclass(frozen=True)
class SixDofTrim:
    """A steady straight glide of the 6-DOF model.

    Attributes
    ----------
    x0 : ndarray, shape (15,)
        Trim state (positions zero).
    u0 : ndarray, shape (3,)
        Trim commands: throttle [-], left, right elevon [rad].
    y0 : ndarray, shape (19,)
        Trim outputs.
    alpha, beta, phi : float
        Angle of attack, sideslip, bank [rad].
    elevator, aileron : float
        ``(left + right)/2``, ``(left - right)/2`` [rad].
    V0, gamma0 : float
        Airspeed [m/s] and air-path angle [rad].
    params : ndarray
        Packed parameters.
    """

    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    alpha: float
    beta: float
    phi: float
    elevator: float
    aileron: float
    V0: float
    gamma0: float
    params: np.ndarray


def _trim_state(v, V0):
    """State and commands of the trim unknowns ``v`` (see :func:`trim6`)."""
    alpha, beta, phi, theta, psi, thr, de, da = v
    x = np.zeros(N_STATE)
    x[STATE["phi"]] = phi
    x[STATE["theta"]] = theta
    x[STATE["psi"]] = psi
    x[STATE["u"]] = V0 * math.cos(alpha) * math.cos(beta)
    x[STATE["v"]] = V0 * math.sin(beta)
    x[STATE["w"]] = V0 * math.sin(alpha) * math.cos(beta)
    left, right = elevons(de, da)
    cmd = np.zeros(N_COMMAND)
    cmd[COMMAND["throttle"]] = thr
    cmd[COMMAND["left"]] = left
    cmd[COMMAND["right"]] = right
    for name in LAYOUT.actuators:
        x[STATE[name]] = cmd[COMMAND[name]]
    return x, cmd


def trim6(airframe: Airframe, V0: float = 20.0, gamma0_deg: float = -3.0,
          where: str = "airframe", locked: tuple | None = None) -> SixDofTrim:
    """Trim the 6-DOF airframe in a steady straight glide (module docstring).

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    V0 : float
        Airspeed [m/s], > 0.
    gamma0_deg : float
        Air-path angle [deg], within (-30, 30).
    where : str
        The airframe's name, for error lines.
    locked : (str, float), optional
        ``("left" | "right", position [rad])``: that elevon held at an absolute
        position, the other one free.  Eight conditions then meet seven
        unknowns, solved in the least-squares sense (``scipy.optimize.
        least_squares``); with no rudder a straight glide exists only where
        the locked elevon leaves no aileron to balance (the project's design
        notes, section 11: locks away from trim are not trimmable).

    Returns
    -------
    SixDofTrim

    Raises
    ------
    UserError
        Missing lateral data (:func:`require_lateral`), a bad condition, no
        equilibrium (with ``locked``: no straight glide with that lock), or a
        trim throttle or elevon outside its range.
    """
    require_lateral(airframe, where)
    if not (isinstance(V0, (int, float)) and math.isfinite(V0) and V0 > 0):
        raise UserError(f"model.airspeed_mps: must be a finite number > 0, got {V0!r}")
    if not (isinstance(gamma0_deg, (int, float)) and math.isfinite(gamma0_deg)
            and abs(gamma0_deg) < 30):
        raise UserError("model.gamma_deg: must be finite and within (-30, 30) deg, "
                        f"got {gamma0_deg!r}")
    gamma0 = math.radians(gamma0_deg)
    p = pack_parameters(airframe, V0, gamma0)
    rows = [STATE[n] for n in ("u", "v", "w", "p", "q", "r")]
    i_gamma = LAYOUT.outputs.index("gamma")
    i_east = STATE["y"]

    def residual(v):
        x, cmd = _trim_state(v, V0)
        dx = derivatives(x, cmd, p)
        y = outputs(x, p)
        return np.concatenate((dx[rows], [y[i_gamma] - gamma0, dx[i_east]]))

    guess = np.array([0.02, 0.0, 0.0, 0.02 + gamma0, 0.0, 0.1, 0.05, 0.0])
    where_c = (f"model.airspeed_mps: the airframe cannot fly this condition ({V0:g} m/s, "
               f"model.gamma_deg {gamma0_deg:g}, 6-DOF):")
    if locked is None:
        sol = scipy.optimize.root(residual, guess, tol=1e-14)
        v = sol.x
        how = f"solver: {' '.join(sol.message.split())}"
    else:
        side, pos = locked
        if side not in ("left", "right") or not math.isfinite(pos):
            raise ValueError(f"trim parameter 'locked' must be ('left' or 'right', a "
                             f"finite position [rad]), got {locked!r}")
        sign = 1.0 if side == "left" else -1.0

        def full(w):
            # w: alpha, beta, phi, theta, psi, throttle, the free elevon
            de = 0.5 * (pos + w[6])
            da = 0.5 * sign * (pos - w[6])
            return np.concatenate((w[:6], [de, da]))

        sol = scipy.optimize.least_squares(lambda w: residual(full(w)),
                                           np.concatenate((guess[:6], [pos])),
                                           xtol=1e-15, ftol=1e-15, gtol=1e-15)
        v = full(sol.x)
        how = f"no straight glide with the {side} elevon locked at {pos:.4g} rad"
    res = np.max(np.abs(residual(v))) if np.all(np.isfinite(v)) else math.inf
    if not (math.isfinite(res) and res <= 1e-9):
        raise UserError(f"{where_c} no equilibrium found (residual {res:.2g}; {how})")
    alpha, beta, phi, theta, psi, thr, de, da = v
    x0, u0 = _trim_state(v, V0)
    problems = []
    lo_t, hi_t = airframe.throttle_limits
    if not lo_t <= thr <= hi_t:
        problems.append(f"trim throttle {_fmt(thr)} outside [{_fmt(lo_t)}, "
                        f"{_fmt(hi_t)}]")
    lo_e, hi_e = airframe.elevon_limits
    for name in ("left", "right"):
        e = u0[COMMAND[name]]
        if not lo_e <= e <= hi_e:
            problems.append(f"trim {name} elevon {_fmt(e)} rad outside "
                            f"[{_fmt(lo_e)}, {_fmt(hi_e)}] rad")
    if problems:
        raise UserError(f"{where_c} {'; '.join(problems)}")
    return SixDofTrim(x0=x0, u0=u0, y0=outputs(x0, p), alpha=float(alpha),
                      beta=float(beta), phi=float(phi), elevator=float(de),
                      aileron=float(da), V0=float(V0), gamma0=gamma0, params=p)


@dataclasses.dataclass(frozen=True)
class SixDofPlant:
    """Discrete linear 6-DOF model about a trim (deviations from it).

    Attributes
    ----------
    A, B, C : ndarray
        Discrete matrices, shapes (15, 15), (15, 3), (19, 15).
    Ac, Bc, Cc : ndarray or None
        Continuous matrices before the zero-order hold (``None`` for a model
        read from a file).
    dt : float
        Sampling period [s].
    trim : SixDofTrim
    u_lower, u_upper : ndarray, shape (3,)
        Absolute command limits.
    airframe : Airframe
    Bw, Dw : ndarray, shapes (15, 6) and (19, 6)
        Gust input matrices: the wind ``[u_g, v_g, w_g, p_g, q_g, r_g]`` held
        over ``dt`` (zero-order hold of the continuous Jacobian) and its
        feed-through into the outputs (:func:`gust_jacobians`).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    dt: float
    trim: SixDofTrim
    u_lower: np.ndarray
    u_upper: np.ndarray
    airframe: Airframe
    Bw: np.ndarray | None = None
    Dw: np.ndarray | None = None

    @property
    def u0(self) -> np.ndarray:
        """Trim commands (absolute)."""
        return self.trim.u0


def linearise6(tp: SixDofTrim):
    """Continuous Jacobians ``Ac`` (15, 15), ``Bc`` (15, 3), ``Cc`` (19, 15) at a trim.

    The first 12 rows of ``Cc`` (the rigid-body states) are set exactly.
    """
    p = tp.params
    Ac = jacobian(lambda x: derivatives(x, tp.u0, p), tp.x0)
    Bc = jacobian(lambda u: derivatives(tp.x0, u, p), tp.u0)
    Cc = jacobian(lambda x: outputs(x, p), tp.x0)
    Cc[:N_RIGID] = np.eye(N_OUTPUT, N_STATE)[:N_RIGID]
    return Ac, Bc, Cc


def gust_jacobians(tp: SixDofTrim):
    """Continuous gust Jacobians at a trim: ``Bwc = df/dwind`` (15, 6) and
    ``Dw = dh/dwind`` (19, 6), the wind ``[u_g, v_g, w_g, p_g, q_g, r_g]``
    (body axes) entering air-relative (:mod:`ftc_mc.core.sixdof.plant`)."""
    p = tp.params
    w0 = np.zeros(N_WIND)
    Bwc = jacobian(lambda w: derivatives(tp.x0, tp.u0, p, w), w0)
    Dw = jacobian(lambda w: outputs(tp.x0, p, w), w0)
    return Bwc, Dw


def sixdof_wind(longitudinal, lateral) -> np.ndarray:
    """The 6-DOF wind from the two Dryden records, placed by name.

    Parameters
    ----------
    longitudinal : ndarray, shape (n, 3)
        ``u_g, w_g, q_g`` (:func:`ftc_mc.model.turbulence.dryden_model` run by
        :func:`ftc_mc.core.shared.dryden.gust_record`).
    lateral : ndarray, shape (n, 3)
        ``v_g, p_g, r_g`` (:func:`ftc_mc.model.turbulence.dryden_lateral_model`,
        the same kernel).

    Returns
    -------
    ndarray, shape (n, 6)
        In the order of ``layout.LAYOUT.wind``.
    """
    lon = np.asarray(longitudinal, dtype=float)
    lat = np.asarray(lateral, dtype=float)
    out = np.zeros((lon.shape[0], N_WIND))
    for j, name in enumerate(("u_g", "w_g", "q_g")):
        out[:, LAYOUT.wind.index(name)] = lon[:, j]
    for j, name in enumerate(("v_g", "p_g", "r_g")):
        out[:, LAYOUT.wind.index(name)] = lat[:, j]
    return out


def build_sixdof_plant(airframe: Airframe, V0: float = 20.0, gamma0_deg: float = -3.0,
                       dt: float = 0.1, where: str = "airframe") -> SixDofPlant:
    """Trim, linearise and discretise (zero-order hold) the 6-DOF airframe.

    Parameters
    ----------
    airframe : Airframe
        With lateral-directional data.
    V0 : float
        Trim airspeed [m/s].
    gamma0_deg : float
        Trim air-path angle [deg].
    dt : float
        Sampling period [s], > 0.
    where : str
        The airframe's name, for error lines.

    Returns
    -------
    SixDofPlant

    Raises
    ------
    UserError
        A bad ``dt`` or any refusal of :func:`trim6`.
    """
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise UserError(f"model.dt_s: must be a finite number > 0, got {dt!r}")
    tp = trim6(airframe, V0, gamma0_deg, where)
    Ac, Bc, Cc = linearise6(tp)
    A, B = zoh(Ac, Bc, dt)
    Bwc, Dw = gust_jacobians(tp)
    _, Bw = zoh(Ac, Bwc, dt)
    return SixDofPlant(A=np.array(A), B=np.array(B), C=Cc.copy(), Ac=Ac, Bc=Bc, Cc=Cc,
                       dt=float(dt), trim=tp,
                       u_lower=np.array(airframe.command_lower, dtype=float),
                       u_upper=np.array(airframe.command_upper, dtype=float),
                       airframe=airframe, Bw=np.array(Bw), Dw=Dw)


MODE_NAMES = ("short_period", "phugoid", "roll", "dutch_roll", "spiral")
"""The named rigid-body modes of :func:`named_modes` (JSON keys of ``modes``)."""


def named_modes(plant: SixDofPlant) -> list:
    """Continuous eigenvalues of the 6-DOF model with the mode each belongs to.

    Naming by structure: eigenvalues at zero are the integrators (the three
    positions and the heading), those equal to ``-1/tau`` of an actuator are
    that actuator; each of the other eight is longitudinal or lateral by where
    its eigenvector lies (``theta, u/V0, w/V0, q`` against ``phi, v/V0, p, r``).
    Longitudinal: the faster complex pair is the short period, the slower the
    phugoid.  Lateral: the complex pair is the Dutch roll, the faster real
    root the roll subsidence and the slower the spiral.  An eigenvalue that
    fits none of these (a lateral pair become complex, say) is ``other``.

    Parameters
    ----------
    plant : SixDofPlant

    Returns
    -------
    list of dict
        ``mode`` (a :data:`MODE_NAMES` entry, ``integrator``, ``engine
        actuator``, ``elevon actuator`` or ``other``), ``continuous`` and
        ``discrete`` (complex), ordered as :data:`MODE_NAMES` first.
    """
    lam, vec = np.linalg.eig(plant.Ac)
    af = plant.airframe
    V0 = plant.trim.V0
    scale = np.ones(N_STATE)
    for n in ("u", "v", "w"):
        scale[STATE[n]] = 1.0 / V0
    names = [None] * len(lam)
    for i, l in enumerate(lam):
        if abs(l) < 1e-8:
            names[i] = "integrator"
        elif abs(l + 1 / af.tau_thrust) < 1e-6 * abs(l):
            names[i] = "engine actuator"
        elif abs(l + 1 / af.tau_elevon) < 1e-6 * abs(l):
            names[i] = "elevon actuator"
    lon_idx = [STATE[n] for n in LAYOUT.longitudinal]
    lat_idx = [STATE[n] for n in LAYOUT.lateral]
    lon, lat = [], []
    for i in range(len(lam)):
        if names[i] is not None:
            continue
        v = np.abs(vec[:, i] * scale)
        (lat if np.sum(v[lat_idx] ** 2) > np.sum(v[lon_idx] ** 2) else lon).append(i)
    lon_c = sorted((i for i in lon if abs(lam[i].imag) > 0), key=lambda i: -abs(lam[i]))
    if len(lon_c) == 4 and len(lon) == 4:
        for i in lon_c[:2]:
            names[i] = "short_period"
        for i in lon_c[2:]:
            names[i] = "phugoid"
    lat_c = [i for i in lat if abs(lam[i].imag) > 0]
    lat_r = sorted((i for i in lat if lam[i].imag == 0), key=lambda i: -abs(lam[i]))
    if len(lat_c) == 2 and len(lat_r) == 2:
        for i in lat_c:
            names[i] = "dutch_roll"
        names[lat_r[0]] = "roll"
        names[lat_r[1]] = "spiral"
    names = [n or "other" for n in names]
    order = list(MODE_NAMES) + ["engine actuator", "elevon actuator", "integrator",
                                "other"]
    idx = sorted(range(len(lam)), key=lambda i: (order.index(names[i]), -lam[i].imag))
    return [{"mode": names[i], "continuous": complex(lam[i]),
             "discrete": complex(np.exp(lam[i] * plant.dt))} for i in idx]


def sixdof_summary(plant: SixDofPlant) -> dict:
    """JSON-ready description of the 6-DOF linear model (``ftc-mc model --dof 6``).

    Returns
    -------
    dict
        ``dof`` (6); ``trim`` (``alpha_deg``, ``beta_deg``, ``phi_deg``,
        ``theta_deg``, ``throttle``, ``left_elevon_rad``, ``right_elevon_rad``,
        ``elevator_rad``, ``aileron_rad``, ``airspeed_mps``, ``gamma_deg``,
        ``dt_s``); ``modes``: for each of :data:`MODE_NAMES` found, ``real``
        and ``imag`` [1/s] (the root with ``imag >= 0``), ``wn_rad_s`` and
        ``zeta``; ``eigenvalues``: every eigenvalue as in
        :func:`ftc_mc.model.summary.model_summary`.
    """
    tp = plant.trim
    eig = named_modes(plant)
    modes = {}
    for e in eig:
        name = e["mode"]
        lc = e["continuous"]
        if name in MODE_NAMES and name not in modes and lc.imag >= 0:
            wn = abs(lc)
            modes[name] = {"real": lc.real, "imag": lc.imag, "wn_rad_s": wn,
                           "zeta": -lc.real / wn if wn > 0 else float("nan")}
    return {
        "dof": 6,
        "trim": {"alpha_deg": math.degrees(tp.alpha), "beta_deg": math.degrees(tp.beta),
                 "phi_deg": math.degrees(tp.phi),
                 "theta_deg": math.degrees(tp.x0[STATE["theta"]]),
                 "throttle": float(tp.u0[COMMAND["throttle"]]),
                 "left_elevon_rad": float(tp.u0[COMMAND["left"]]),
                 "right_elevon_rad": float(tp.u0[COMMAND["right"]]),
                 "elevator_rad": tp.elevator, "aileron_rad": tp.aileron,
                 "airspeed_mps": tp.V0, "gamma_deg": math.degrees(tp.gamma0),
                 "dt_s": plant.dt},
        "modes": {name: modes[name] for name in MODE_NAMES if name in modes},
        "eigenvalues": [{"mode": e["mode"],
                         "continuous": [e["continuous"].real, e["continuous"].imag],
                         "discrete": [e["discrete"].real, e["discrete"].imag]}
                        for e in eig],
    }


def format_sixdof_summary(s: dict, name: str = "") -> str:
    """Human-readable text of :func:`sixdof_summary` (the trimmable sets:
    :func:`ftc_mc.model.trimmable.format_trimmable_summary`)."""
    t = s["trim"]
    lines = [
        f"{name + ': ' if name else ''}6-DOF trim at Va = {t['airspeed_mps']:g} m/s, "
        f"gamma = {t['gamma_deg']:g} deg, dt = {t['dt_s']:g} s",
        f"  angle of attack  {t['alpha_deg']:9.4f} deg     sideslip {t['beta_deg']:9.4f} deg",
        f"  bank             {t['phi_deg']:9.4f} deg     pitch    {t['theta_deg']:9.4f} deg",
        f"  throttle         {t['throttle']:9.4f}",
        f"  elevons          left {t['left_elevon_rad']:.4f} rad, right "
        f"{t['right_elevon_rad']:.4f} rad (elevator {t['elevator_rad']:.4f}, aileron "
        f"{t['aileron_rad']:.5f})",
        "",
    ] + mode_table(s["eigenvalues"])
    return "\n".join(lines)


# ----------------------------------------------------------------------------
# the 6-DOF linear-model file (``ftc-mc model --dof 6 --save FILE.npz``)

SIXDOF_MODEL_VARIABLES: dict[str, tuple[tuple[int, ...], str]] = {
    "dof": ((), "degrees of freedom of the model: 6"),
    "A": ((N_STATE, N_STATE), "discrete state matrix, x[k+1] = A x[k] + B u[k] "
                              "(deviations from trim; states: state_names)"),
    "B": ((N_STATE, N_COMMAND), "discrete input matrix (throttle [-], left, right "
                                "elevon [rad])"),
    "C": ((N_OUTPUT, N_STATE), "output matrix, z[k] = C x[k] (outputs: output_names)"),
    "x0": ((N_STATE,), "trim state, absolute: x, y, z [m], phi, theta, psi [rad], "
                       "u, v, w [m/s], p, q, r [rad/s], throttle [-], left, right "
                       "elevon [rad]"),
    "u0": ((N_COMMAND,), "trim commands, absolute: throttle [-], left, right "
                         "elevon [rad]"),
    "y0": ((N_OUTPUT,), "trim outputs, absolute: the 12 rigid-body states, n_x, "
                        "n_y, n_z [g], alpha, beta, gamma [rad], Va [m/s]"),
    "u_lower": ((N_COMMAND,), "absolute lower command limits"),
    "u_upper": ((N_COMMAND,), "absolute upper command limits"),
    "dt": ((), "sampling period [s] of the zero-order hold"),
    "V0": ((), "trim airspeed [m/s]"),
    "gamma0": ((), "trim air-path angle [rad]"),
    "alpha": ((), "trim angle of attack [rad]"),
    "beta": ((), "trim sideslip [rad]"),
    "phi": ((), "trim bank angle [rad]"),
    "Bw": ((N_STATE, N_WIND), "discrete gust input matrix; gust [u_g, v_g, w_g "
                              "[m/s], p_g, q_g, r_g [rad/s]] held over dt"),
    "Dw": ((N_OUTPUT, N_WIND), "gust feed-through into the 19 outputs"),
    "state_names": ((N_STATE,), "names of the states (text)"),
    "command_names": ((N_COMMAND,), "names of the commands (text)"),
    "output_names": ((N_OUTPUT,), "names of the outputs (text)"),
    "source": ((), "where the airframe's numbers come from (text)"),
}
"""Variable -> (shape, meaning with unit) of a 6-DOF linear-model file; besides
these, ``airframe_<field>`` holds every field of the airframe
(:data:`ftc_mc.model.airframe_files.AIRFRAME_FIELDS` gives each one's unit and
meaning; the command ranges as two numbers), lateral-directional data included."""


def save_sixdof_npz(plant: SixDofPlant, f, source: str = "", suffix: str = ".npz") -> None:
    """Write the 6-DOF linear model and its airframe to a ``.npz`` file (or,
    with ``suffix=".mat"``, a MATLAB ``.mat`` with the same variables; only the
    ``.npz`` is read back by :func:`load_sixdof_model`).

    Variables: :data:`SIXDOF_MODEL_VARIABLES` and ``airframe_<field>`` for every
    airframe field (``docs/reference/airframes.md``); :func:`load_sixdof_model` reads it
    back to an equal model.

    Parameters
    ----------
    plant : SixDofPlant
    f : str, Path or binary file
        Destination, as for :func:`numpy.savez`.
    source : str
        Where the airframe's numbers come from (a preset's source or a path).
    """
    tp = plant.trim
    data = dict(dof=np.int64(6), A=plant.A, B=plant.B, C=plant.C, Bw=plant.Bw,
                Dw=plant.Dw, x0=tp.x0, u0=tp.u0,
                y0=tp.y0, u_lower=plant.u_lower, u_upper=plant.u_upper,
                dt=np.float64(plant.dt), V0=np.float64(tp.V0),
                gamma0=np.float64(tp.gamma0), alpha=np.float64(tp.alpha),
                beta=np.float64(tp.beta), phi=np.float64(tp.phi),
                state_names=np.array(LAYOUT.states), command_names=np.array(LAYOUT.commands),
                output_names=np.array(LAYOUT.outputs), source=np.array(str(source)))
    for field in dataclasses.fields(Airframe):
        data[f"airframe_{field.name}"] = np.array(getattr(plant.airframe, field.name),
                                                  dtype=np.float64)
    from .summary import save_model_file

    save_model_file(data, f, suffix)


def load_sixdof_model(path) -> tuple:
    """Read a 6-DOF linear-model file written by :func:`save_sixdof_npz`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    (SixDofPlant, str)
        The model (its trim rebuilt from the file: ``x0``, ``u0``, ``y0``, the
        packed parameters of its airframe) and the ``source`` text.

    Raises
    ------
    UserError
        One line: not a readable ``.npz``, a missing variable, a wrong shape
        or names that are not this layout's, naming the variable.
    """
    import zipfile
    from pathlib import Path

    from .airframe_files import AIRFRAME_FIELDS

    path = Path(path)
    tail = f" ({path})"
    try:
        if not zipfile.is_zipfile(path):
            raise ValueError("not a zip archive")
        with np.load(path, allow_pickle=False) as z:
            raw = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile) as exc:
        raise UserError(f"6-DOF model: not a readable NumPy .npz file ({exc}){tail}") \
            from None
    needed = list(SIXDOF_MODEL_VARIABLES) + [f"airframe_{n}" for n in AIRFRAME_FIELDS]
    missing = [k for k in needed if k not in raw]
    if missing:
        raise UserError(f"6-DOF model: missing variable{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing[:6])}{' ...' if len(missing) > 6 else ''}"
                        f"{tail}")
    for name, (shape, _) in SIXDOF_MODEL_VARIABLES.items():
        if raw[name].shape != shape:
            raise UserError(f"6-DOF model: {name}: must have shape {shape}, got "
                            f"{raw[name].shape}{tail}")
    for name, names in (("state_names", LAYOUT.states), ("command_names", LAYOUT.commands),
                        ("output_names", LAYOUT.outputs)):
        if tuple(str(v) for v in raw[name]) != tuple(names):
            raise UserError(f"6-DOF model: {name}: must be {', '.join(names)}{tail}")
    if int(raw["dof"]) != 6:
        raise UserError(f"6-DOF model: dof: must be 6, got {raw['dof']!r}{tail}")
    fields = {}
    for name in AIRFRAME_FIELDS:
        v = raw[f"airframe_{name}"]
        fields[name] = tuple(float(e) for e in v) if v.shape == (2,) else float(v)
    airframe = Airframe(**fields)
    V0, gamma0 = float(raw["V0"]), float(raw["gamma0"])
    u0 = np.array(raw["u0"], dtype=float)
    tp = SixDofTrim(x0=np.array(raw["x0"], dtype=float), u0=u0,
                    y0=np.array(raw["y0"], dtype=float), alpha=float(raw["alpha"]),
                    beta=float(raw["beta"]), phi=float(raw["phi"]),
                    elevator=0.5 * (u0[COMMAND["left"]] + u0[COMMAND["right"]]),
                    aileron=0.5 * (u0[COMMAND["left"]] - u0[COMMAND["right"]]),
                    V0=V0, gamma0=gamma0, params=pack_parameters(airframe, V0, gamma0))
    plant = SixDofPlant(A=np.array(raw["A"], dtype=float), B=np.array(raw["B"], dtype=float),
                        C=np.array(raw["C"], dtype=float), Ac=None, Bc=None, Cc=None,
                        dt=float(raw["dt"]), trim=tp,
                        u_lower=np.array(raw["u_lower"], dtype=float),
                        u_upper=np.array(raw["u_upper"], dtype=float), airframe=airframe,
                        Bw=np.array(raw["Bw"], dtype=float),
                        Dw=np.array(raw["Dw"], dtype=float))
    return plant, str(raw["source"])


__all__ = ["require_lateral", "pack_parameters", "derivatives", "outputs", "elevons",
           "SixDofTrim", "trim6", "SixDofPlant", "linearise6", "build_sixdof_plant",
           "MODE_NAMES", "named_modes", "sixdof_summary", "format_sixdof_summary",
           "PARAM", "SIXDOF_MODEL_VARIABLES", "save_sixdof_npz", "load_sixdof_model",
           "gust_jacobians", "sixdof_wind"]
