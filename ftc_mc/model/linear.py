"""Trim, numerical linearisation and zero-order-hold discretisation (paper eq. 1).

The linear model is the one every estimator and controller of the paper uses:
``x_{k+1} = A x_k + B u_k``, ``z_k = C x_k`` (eq. 1, noise omitted), with ``x``,
``u`` and ``z`` deviations from the trim point at airspeed ``V0`` and flight-path
angle ``gamma0`` (paper section 5.1: 20 m/s and -3 deg, dt = 0.1 s).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.differentiate
import scipy.linalg
import scipy.optimize

from ..conventions import N_X as N_STATE
from ..conventions import N_Z as N_OUTPUT
from ..errors import UserError
from .airframe import X8, Airframe
from .dynamics import derivatives, outputs, pack_parameters


@dataclasses.dataclass(frozen=True)
class TrimPoint:
    """Steady glide at constant airspeed and flight-path angle.

    Attributes
    ----------
    x0 : ndarray, shape (9,)
        Trim state (positions zero) [SI].
    u0 : ndarray, shape (3,)
        Trim commands: throttle [-], left and right elevon [rad].
    y0 : ndarray, shape (12,)
        Trim outputs.
    alpha : float
        Trim angle of attack [rad].
    V0, gamma0 : float
        Airspeed [m/s] and flight-path angle [rad] of the trim.
    params : ndarray, shape (25,) or None
        Packed parameters used (airframe and glide path); ``None`` for the trim
        of a linear model read from a file.
    """

    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    alpha: float
    V0: float
    gamma0: float
    params: np.ndarray


def _fmt(value: float) -> str:
    """Short decimal text of a number for error lines (4 significant digits)."""
    return f"{value:.4g}"


def trim(airframe: Airframe = X8, V0: float = 20.0, gamma0_deg: float = -3.0,
         alpha_range: tuple | None = None) -> TrimPoint:
    """Trim the airframe in a steady straight glide (or climb).

    Solves ``du/dt = dw/dt = dq/dt = 0`` for angle of attack, throttle and
    (symmetric) elevon deflection with ``theta = alpha + gamma0`` and ``q = 0``,
    then refuses a condition the airframe cannot fly: throttle or elevon outside
    its range, angle of attack outside ``alpha_range``, or no equilibrium found.

    Parameters
    ----------
    airframe : Airframe
        Airframe parameters.
    V0 : float
        Airspeed [m/s], > 0.
    gamma0_deg : float
        Flight-path angle [deg], within (-30, 30), negative when descending.
    alpha_range : tuple of float, optional
        ``(alpha_min, alpha_max)`` [rad]: the angles of attack where the
        aerodynamic model is trusted.  ``None`` (default): no check.

    Returns
    -------
    TrimPoint

    Raises
    ------
    UserError
        One line naming ``model.airspeed_mps`` and/or ``model.gamma_deg`` and
        what is wrong: a non-finite or non-positive airspeed, a flight-path angle
        outside (-30, 30) deg, no equilibrium found, or a trim throttle, elevon or
        angle of attack outside its range.
    ValueError
        If ``alpha_range`` is not two finite numbers with ``lo < hi``.
    """
    if not (isinstance(V0, (int, float)) and math.isfinite(V0) and V0 > 0):
        raise UserError(f"model.airspeed_mps: must be a finite number > 0, got {V0!r}")
    if not (isinstance(gamma0_deg, (int, float)) and math.isfinite(gamma0_deg)
            and abs(gamma0_deg) < 30):
        raise UserError("model.gamma_deg: must be finite and within (-30, 30) deg, "
                        f"got {gamma0_deg!r}")
    if alpha_range is not None:
        a_lo, a_hi = (float(v) for v in alpha_range)
        if not (math.isfinite(a_lo) and math.isfinite(a_hi) and a_lo < a_hi):
            raise ValueError("trim parameter 'alpha_range' must be two finite numbers "
                             f"lo < hi [rad], got {alpha_range!r}")
    gamma0 = math.radians(gamma0_deg)
    p = pack_parameters(airframe, V0, gamma0)

    def state(v):
        alpha, thr, de = v
        return np.array([V0 * math.cos(alpha), V0 * math.sin(alpha), 0.0, 0.0, 0.0,
                         alpha + gamma0, thr, de, de])

    def residual(v):
        x = state(v)
        dx = np.empty(N_STATE)
        derivatives(x, x[6:9], p, dx)
        return dx[:3]

    sol = scipy.optimize.root(residual, np.array([0.02, 0.1, 0.05]), tol=1e-14)
    alpha, thr, de = sol.x
    # Converged means an equilibrium to 1e-9 (m/s^2, rad/s^2): the solver's own
    # flag is not used, since with tol=1e-14 it reports "not making good
    # progress" at residuals of 1e-15 for some airframes.
    res = np.max(np.abs(residual(sol.x))) if np.all(np.isfinite(sol.x)) else math.inf
    where = (f"model.airspeed_mps: the airframe cannot fly this condition ({V0:g} m/s, "
             f"model.gamma_deg {gamma0_deg:g}):")
    if not (math.isfinite(res) and res <= 1e-9):
        raise UserError(f"{where} no equilibrium found (residual {res:.2g}; "
                        f"solver: {' '.join(sol.message.split())})")
    problems = []
    lo_t, hi_t = airframe.throttle_limits
    if thr > hi_t:
        problems.append(f"trim throttle {_fmt(thr)} above its maximum {_fmt(hi_t)}")
    elif thr < lo_t:
        problems.append(f"trim throttle {_fmt(thr)} below its minimum {_fmt(lo_t)}")
    lo_e, hi_e = airframe.elevon_limits
    if not lo_e <= de <= hi_e:
        problems.append(f"trim elevon {_fmt(de)} rad outside its range "
                        f"[{_fmt(lo_e)}, {_fmt(hi_e)}] rad")
    if alpha_range is not None and not a_lo <= alpha <= a_hi:
        problems.append(f"trim angle of attack {_fmt(math.degrees(alpha))} deg outside "
                        f"the validity range [{_fmt(math.degrees(a_lo))}, "
                        f"{_fmt(math.degrees(a_hi))}] deg")
    if problems:
        raise UserError(f"{where} {'; '.join(problems)}")
    x0 = state(sol.x)
    y0 = np.empty(N_OUTPUT)
    outputs(x0, p, y0)
    return TrimPoint(x0=x0, u0=x0[6:9].copy(), y0=y0, alpha=float(alpha), V0=V0,
                     gamma0=gamma0, params=p)


def jacobian(fun, at):
    """Jacobian of a scalar-loop function by scipy's adaptive finite differences."""
    def vectorised(v):
        flat = v.reshape(v.shape[0], -1)
        out = np.stack([fun(flat[:, j]) for j in range(flat.shape[1])], axis=-1)
        return out.reshape((out.shape[0],) + v.shape[1:])

    res = scipy.differentiate.jacobian(vectorised, at, initial_step=1e-2,
                                       tolerances=dict(atol=1e-11, rtol=1e-10))
    return res.df


@dataclasses.dataclass(frozen=True)
class LinearPlant:
    """Discrete linear longitudinal model about a trim point (paper eq. 1).

    Built from an airframe by :func:`build_plant`, or read from a file by
    :func:`ftc_mc.model.airframe_files.load_linear_model`; a model read from a
    file has no airframe (``airframe is None``), so it has no nonlinear model
    and flies only the linear truth plant.

    Attributes
    ----------
    A, B, C : ndarray
        Discrete matrices, shapes (9, 9), (9, 3), (12, 9).
    Ac, Bc, Cc : ndarray or None
        Continuous-time matrices before discretisation; ``None`` for a model
        read from a file.
    dt : float
        Sampling period [s].
    trim : TrimPoint
        The trim point; deviations are taken from it (``trim.params`` is ``None``
        for a model read from a file).
    u_lower, u_upper : ndarray, shape (3,)
        Absolute command limits (throttle [-], elevons [rad]).
    airframe : Airframe or None
        The airframe it was built from; ``None``: no nonlinear model.
    Bw, Dw : ndarray or None
        Gust input matrices, shapes (9, 3) and (12, 3), of a model read from a
        file; ``None`` for a model built from an airframe, whose gust matrices
        :func:`ftc_mc.model.wind.wind_matrices` computes.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Ac: np.ndarray | None
    Bc: np.ndarray | None
    Cc: np.ndarray | None
    dt: float
    trim: TrimPoint
    u_lower: np.ndarray
    u_upper: np.ndarray
    airframe: Airframe | None = None
    Bw: np.ndarray | None = None
    Dw: np.ndarray | None = None

    @property
    def u0(self) -> np.ndarray:
        """Trim commands (absolute)."""
        return self.trim.u0

    @property
    def has_nonlinear_model(self) -> bool:
        """True when built from an airframe (the nonlinear truth plant can fly it)."""
        return self.airframe is not None


def linearise(tp: TrimPoint):
    """Continuous Jacobians of the dynamics and outputs at a trim point.

    Parameters
    ----------
    tp : TrimPoint

    Returns
    -------
    Ac, Bc, Cc : ndarray
        Shapes (9, 9), (9, 3), (12, 9); the outputs have no direct feed-through
        because the actuators are states.
    """
    p = tp.params

    def f_x(x):
        dx = np.empty(N_STATE)
        derivatives(x, tp.u0, p, dx)
        return dx

    def f_u(u):
        dx = np.empty(N_STATE)
        derivatives(tp.x0, u, p, dx)
        return dx

    def h_x(x):
        y = np.empty(N_OUTPUT)
        outputs(x, p, y)
        return y

    Cc = jacobian(h_x, tp.x0)
    # the first six outputs are the first six states: make those rows exact
    Cc[:6] = np.eye(N_OUTPUT, N_STATE)[:6]
    return jacobian(f_x, tp.x0), jacobian(f_u, tp.u0), Cc


def build_plant(airframe: Airframe = X8, V0: float = 20.0, gamma0_deg: float = -3.0,
                dt: float = 0.1, alpha_range: tuple | None = None) -> LinearPlant:
    """Trim, linearise and discretise (zero-order hold) the X8.

    Parameters
    ----------
    airframe : Airframe
        Airframe parameters.
    V0 : float
        Trim airspeed [m/s].
    gamma0_deg : float
        Trim flight-path angle [deg].
    dt : float
        Sampling period [s], > 0 (paper: 0.1 s).
    alpha_range : tuple of float, optional
        Validity range of the angle of attack [rad] the trim must lie in
        (:func:`trim`); ``None``: no check.

    Returns
    -------
    LinearPlant

    Raises
    ------
    UserError
        If ``dt`` is not a positive finite number, or the airframe cannot fly
        the condition (:func:`trim`).
    """
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise UserError(f"model.dt_s: must be a finite number > 0, got {dt!r}")
    tp = trim(airframe, V0, gamma0_deg, alpha_range)
    Ac, Bc, Cc = linearise(tp)
    A, B = zoh(Ac, Bc, dt)
    return LinearPlant(A=A, B=B, C=Cc.copy(), Ac=Ac, Bc=Bc, Cc=Cc, dt=float(dt), trim=tp,
                       u_lower=np.array(airframe.command_lower, dtype=float),
                       u_upper=np.array(airframe.command_upper, dtype=float),
                       airframe=airframe)


def zoh(Ac: np.ndarray, Bc: np.ndarray, dt: float):
    """Zero-order-hold discretisation ``A = e^{Ac dt}``, ``B = int_0^dt e^{Ac s} ds Bc``.

    Both come from one matrix exponential of the block matrix
    ``[[Ac, Bc], [0, 0]] dt`` (Van Loan 1978), computed exactly as
    ``scipy.signal.cont2discrete(..., method="zoh")`` does (scipy 1.17), so the
    results are the same to the bit (``tests/test_model.py``); calling
    ``scipy.linalg.expm`` directly spares every run the import of
    ``scipy.signal``, about 0.5 s.

    Parameters
    ----------
    Ac : ndarray, shape (n, n)
        Continuous state matrix [1/s].
    Bc : ndarray, shape (n, m)
        Continuous input matrix.
    dt : float
        Hold period [s].

    Returns
    -------
    (ndarray, ndarray)
        ``A`` (n, n) and ``B`` (n, m), views into one array.

    References
    ----------
    C. F. Van Loan, "Computing integrals involving the matrix exponential",
    IEEE Trans. Autom. Control 23 (1978) 395-404.
    """
    n, m = Bc.shape
    em = np.vstack((np.hstack((Ac, Bc)),
                    np.hstack((np.zeros((m, n)), np.zeros((m, m))))))
    ms = scipy.linalg.expm(dt * em)[:n, :]
    return ms[:, 0:n], ms[:, n:]


def transfer_matrix(plant: LinearPlant, z: complex) -> np.ndarray:
    """Discrete transfer matrix ``G(z) = C (z I - A)^-1 B`` at one point.

    Parameters
    ----------
    plant : LinearPlant
    z : complex
        Evaluation point (not an eigenvalue of A).

    Returns
    -------
    ndarray, shape (12, 3), complex
    """
    n = plant.A.shape[0]
    return plant.C @ np.linalg.solve(z * np.eye(n) - plant.A, plant.B)


def redundancy(plant: LinearPlant, n_freq: int = 64) -> dict:
    """Check the paper's redundancy definition (section 2.3) numerically.

    Two inputs are redundant when their columns of ``G(z)`` are linearly dependent
    (rank 1).  The rank of each column pair is judged from its singular values at
    ``n_freq`` points on the unit circle: the pair is rank 1 when the smaller
    singular value is below ``1e-9`` times the larger at every point.

    Parameters
    ----------
    plant : LinearPlant
    n_freq : int
        Number of evaluation points ``exp(j w dt)`` with w from 0.01 rad/s to
        the Nyquist frequency.

    Returns
    -------
    dict
        ``elevons_redundant``, ``thrust_redundant`` (bool) and the worst singular
        value ratios ``elevon_sv_ratio_max`` and ``thrust_sv_ratio_min``.
    """
    w = np.geomspace(1e-2, math.pi / plant.dt * 0.999, n_freq)

    def ratios(i, j):
        out = []
        for wk in w:
            G = transfer_matrix(plant, np.exp(1j * wk * plant.dt))
            s = np.linalg.svd(G[:, [i, j]], compute_uv=False)
            out.append(s[1] / s[0])
        return np.array(out)

    elev = ratios(1, 2)
    thr = np.minimum(ratios(0, 1), ratios(0, 2))
    return {"elevons_redundant": bool(np.all(elev < 1e-9)),
            "thrust_redundant": bool(np.all(thr < 1e-9)),
            "elevon_sv_ratio_max": float(elev.max()),
            "thrust_sv_ratio_min": float(thr.min())}


def named_eigenvalues(plant: LinearPlant) -> list:
    """Continuous and discrete eigenvalues with the mode each belongs to.

    Modes are named by structure: eigenvalues at zero are the position
    integrators, those equal to ``-1/tau`` of an actuator are that actuator (the
    actuator rows are decoupled from the airframe), and of the four airframe
    eigenvalues the faster pair is the short period and the slower the phugoid.

    Parameters
    ----------
    plant : LinearPlant

    Returns
    -------
    list of dict
        ``mode``, ``continuous`` (complex) and ``discrete`` (complex,
        ``exp(lambda dt)``), sorted by mode.
    """
    lam = np.linalg.eigvals(plant.Ac)
    af = plant.airframe
    names = [None] * len(lam)
    for i, l in enumerate(lam):
        if abs(l) < 1e-8:
            names[i] = "position integrator"
        elif abs(l + 1 / af.tau_thrust) < 1e-6 * abs(l):
            names[i] = "engine actuator"
        elif abs(l + 1 / af.tau_elevon) < 1e-6 * abs(l):
            names[i] = "elevon actuator"
    rest = [i for i in range(len(lam)) if names[i] is None]
    rest.sort(key=lambda i: abs(lam[i]))
    half = len(rest) // 2
    for k, i in enumerate(rest):
        names[i] = "phugoid" if k < half else "short period"
    order = ["short period", "phugoid", "engine actuator", "elevon actuator",
             "position integrator"]
    idx = sorted(range(len(lam)), key=lambda i: (order.index(names[i]), lam[i].imag))
    return [{"mode": names[i], "continuous": complex(lam[i]),
             "discrete": complex(np.exp(lam[i] * plant.dt))} for i in idx]
