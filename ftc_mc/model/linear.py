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
import scipy.optimize
import scipy.signal

from ..errors import UserError
from .airframe import X8, Airframe
from .dynamics import (N_INPUT, N_OUTPUT, N_STATE, derivatives, outputs,
                       pack_parameters)


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
    params : ndarray, shape (25,)
        Packed parameters used (airframe and glide path).
    """

    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    alpha: float
    V0: float
    gamma0: float
    params: np.ndarray


def trim(airframe: Airframe = X8, V0: float = 20.0, gamma0_deg: float = -3.0
         ) -> TrimPoint:
    """Trim the X8 in a steady straight glide.

    Solves ``du/dt = dw/dt = dq/dt = 0`` for angle of attack, throttle and
    (symmetric) elevon deflection with ``theta = alpha + gamma0`` and ``q = 0``.

    Parameters
    ----------
    airframe : Airframe
        Airframe parameters.
    V0 : float
        Airspeed [m/s], > 0.
    gamma0_deg : float
        Flight-path angle [deg], negative when descending.

    Returns
    -------
    TrimPoint

    Raises
    ------
    ValueError
        If ``V0`` is not positive or no trim exists within the command limits.
    """
    if not (math.isfinite(V0) and V0 > 0):
        raise UserError(f"trim parameter 'V0' must be a finite number > 0, got {V0!r}")
    if not (math.isfinite(gamma0_deg) and abs(gamma0_deg) < 30):
        raise UserError("trim parameter 'gamma0_deg' must be finite and within "
                        f"(-30, 30) deg, got {gamma0_deg!r}")
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
    lo_t, hi_t = airframe.throttle_limits
    lo_e, hi_e = airframe.elevon_limits
    if (not sol.success or np.max(np.abs(residual(sol.x))) > 1e-9
            or not lo_t <= thr <= hi_t or not lo_e <= de <= hi_e):
        raise UserError(f"no trim within the command limits at V0={V0} m/s, "
                        f"gamma0={gamma0_deg} deg (solver: {sol.message})")
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

    Attributes
    ----------
    A, B, C : ndarray
        Discrete matrices, shapes (9, 9), (9, 3), (12, 9).
    Ac, Bc, Cc : ndarray
        Continuous-time matrices before discretisation.
    dt : float
        Sampling period [s].
    trim : TrimPoint
        The trim point; deviations are taken from it.
    u_lower, u_upper : ndarray, shape (3,)
        Absolute command limits (throttle [-], elevons [rad]).
    airframe : Airframe
        The airframe it was built from.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    dt: float
    trim: TrimPoint
    u_lower: np.ndarray
    u_upper: np.ndarray
    airframe: Airframe

    @property
    def u0(self) -> np.ndarray:
        """Trim commands (absolute)."""
        return self.trim.u0


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
                dt: float = 0.1) -> LinearPlant:
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

    Returns
    -------
    LinearPlant

    Raises
    ------
    ValueError
        If ``dt`` is not a positive finite number, or trim fails.
    """
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise UserError(f"model parameter 'dt' must be a finite number > 0, got {dt!r}")
    tp = trim(airframe, V0, gamma0_deg)
    Ac, Bc, Cc = linearise(tp)
    A, B, C, _, _ = scipy.signal.cont2discrete(
        (Ac, Bc, Cc, np.zeros((N_OUTPUT, N_INPUT))), dt, method="zoh")
    return LinearPlant(A=A, B=B, C=C, Ac=Ac, Bc=Bc, Cc=Cc, dt=float(dt), trim=tp,
                       u_lower=np.array(airframe.command_lower, dtype=float),
                       u_upper=np.array(airframe.command_upper, dtype=float),
                       airframe=airframe)


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
