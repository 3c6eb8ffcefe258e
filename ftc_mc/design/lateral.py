"""Lateral-directional loop of the 6-DOF X8: wings level and heading hold.

An offline design on the 6-DOF linear model (:mod:`ftc_mc.model.sixdof`), by
the discounted LQR of :mod:`ftc_mc.design.lqr` (the paper's approach, eq. 43,
its discount 0.999).  The loop flies beside the paper's longitudinal loop, as
autopilots do: its only command is differential, an aileron ``da`` added to the
left elevon and subtracted from the right one (PyFly's mixing: aileron =
(left - right)/2), so the elevator ``(left + right)/2`` stays the longitudinal
loop's.

Lateral model: the states ``phi, v, p, r, psi`` and both elevon actuator states
(the aileron is their half difference) of the discrete 6-DOF model, with the
aileron input column ``B[:, left] - B[:, right]``; at a symmetric trim these
rows do not depend on the longitudinal states (with ``x8-pyfly``'s propeller
torque, the trim's 0.0019 rad of aileron couples them weakly; the closed loop
is checked on the full model).  Weights by Bryson's rule: bank
``phi_max``, heading ``psi_max``, aileron ``da_max``; the rates and sideslip
unweighted.  The cross-track position ``y`` is not held (heading hold, not
track hold), so it stays an integrator of the closed loop.

:func:`coupled_lqr` is the alternative c0 (``controller.coupling:
coupled``): one discounted LQR on the whole 6-DOF model whose
cost is the sum of the two loops' costs, so that it is the pair of separate
gains exactly when the model does not couple them; :func:`coupled_engine_tables`
is c1's Theorem 4.1 tables on the same model and weights.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg

from ..core.sixdof.layout import COMMAND, LAYOUT, N_STATE, STATE, sixdof_name
from .lqr import discounted_lqr

LATERAL_STATES = ("phi", "v", "p", "r", "psi", "left", "right")
"""States of the lateral design model, by name (:mod:`ftc_mc.core.sixdof.layout`)."""


@dataclasses.dataclass(frozen=True)
class LateralDesign:
    """A lateral LQR gain and its closed loop.

    Attributes
    ----------
    K : ndarray, shape (1, 7)
        ``da = -K x_lat`` [rad], ``x_lat`` the deviations of
        :data:`LATERAL_STATES` from trim.
    K_full : ndarray, shape (3, 15)
        The same law on the full 6-DOF state, as commands: ``+da`` on the left
        elevon, ``-da`` on the right, none on the throttle.
    A_lat, B_lat : ndarray
        The lateral design model, shapes (7, 7), (7, 1).
    open_loop, closed_loop : ndarray
        Eigenvalues (discrete) of ``A_lat`` and ``A_lat - B_lat K``.
    Q, R : ndarray
        Weights; ``alpha`` the discount.
    """

    K: np.ndarray
    K_full: np.ndarray
    A_lat: np.ndarray
    B_lat: np.ndarray
    open_loop: np.ndarray
    closed_loop: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    alpha: float


def aileron_column(B: np.ndarray) -> np.ndarray:
    """Input column of a unit aileron (left +1, right -1) of a 6-DOF ``B``."""
    return B[:, COMMAND["left"]] - B[:, COMMAND["right"]]


def lateral_lqr(plant, phi_max_deg: float = 5.0, psi_max_deg: float = 10.0,
                da_max_deg: float = 5.0, alpha: float = 0.999) -> LateralDesign:
    """Discounted LQR for wings level and heading hold on the 6-DOF linear model.

    Parameters
    ----------
    plant : ftc_mc.model.sixdof.SixDofPlant
        The discrete 6-DOF model.
    phi_max_deg, psi_max_deg, da_max_deg : float
        Bryson's rule: the bank, heading and aileron deviations [deg] that
        cost one unit each.
    alpha : float
        Discount factor in (0, 1] (the paper's 0.999).

    Returns
    -------
    LateralDesign
    """
    idx = [STATE[n] for n in LATERAL_STATES]
    A_lat = plant.A[np.ix_(idx, idx)]
    B_lat = aileron_column(plant.B)[idx][:, None]
    q = np.zeros(len(idx))
    q[LATERAL_STATES.index("phi")] = 1.0 / math.radians(phi_max_deg) ** 2
    q[LATERAL_STATES.index("psi")] = 1.0 / math.radians(psi_max_deg) ** 2
    Q = np.diag(q)
    R = np.array([[1.0 / math.radians(da_max_deg) ** 2]])
    K, _ = discounted_lqr(A_lat, B_lat, Q, R, alpha)
    K_full = np.zeros((len(LAYOUT.commands), N_STATE))
    K_full[COMMAND["left"], idx] = K[0]
    K_full[COMMAND["right"], idx] = -K[0]
    return LateralDesign(K=K, K_full=K_full, A_lat=A_lat, B_lat=B_lat,
                         open_loop=np.linalg.eigvals(A_lat),
                         closed_loop=np.linalg.eigvals(A_lat - B_lat @ K),
                         Q=Q, R=R, alpha=float(alpha))


@dataclasses.dataclass(frozen=True)
class CoupledDesign:
    """The nominal controller c0 as one LQR on the 6-DOF model.

    Attributes
    ----------
    K : ndarray, shape (3, 15)
        ``u = -K x`` on the 6-DOF state (deviations from its trim).
    K_separate : ndarray, shape (3, 15)
        The separate loops' gains on the same state: the paper's longitudinal
        LQR by name (:func:`longitudinal_gain_on_sixdof`) plus the lateral one.
    P, P_separate : ndarray, shape (15, 15)
        Discounted cost-to-go matrices of the two laws on the 6-DOF model
        (``x^T P x``): ``P`` solves eq. (43), ``P_separate`` the discounted
        Lyapunov equation of the separate loops.
    Q, R : ndarray
        The summed weights, shapes (15, 15) and (3, 3); ``alpha`` the discount.
    """

    K: np.ndarray
    K_separate: np.ndarray
    P: np.ndarray
    P_separate: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    alpha: float


def coupled_lqr(plant, K_lon: np.ndarray, Q_lon: np.ndarray, R_lon: np.ndarray,
                alpha: float, lat: LateralDesign) -> CoupledDesign:
    """c0 as one discounted LQR on the 6-DOF linear model.

    The cost is the sum of the two loops' costs: the paper's ``Q_lqr``
    (section 5.1) on the longitudinal states by name, the lateral design's
    Bryson weights on :data:`LATERAL_STATES`, and on the commands the paper's
    ``R_lqr`` plus, along the aileron ``da = (left - right)/2``, what brings
    the aileron's weight to the lateral design's (``R_lon`` already charges
    ``a^T R_lon a`` per unit ``da``, ``a = [0, 1, -1]``)::

        R = R_lon + (R_lat - a^T R_lon a) a a^T / 4

    With a model whose longitudinal and lateral motions do not act on each
    other, the minimiser of this sum is the pair of separate gains; on
    ``x8-pyfly`` the propeller's torque couples them and the throttle joins
    the roll control (``docs/findings/sixdof.md``).

    Parameters
    ----------
    plant : ftc_mc.model.sixdof.SixDofPlant
        The discrete 6-DOF model.
    K_lon, Q_lon, R_lon : ndarray
        The paper's c0 gain (3 x 9) and its weights (9 x 9, 3 x 3), on the
        longitudinal model's states (:data:`ftc_mc.conventions.STATE_NAMES`).
    alpha : float
        Discount of the coupled design (the paper's c0's, eq. 43).  The lateral
        loop is designed at 0.999, so with another discount the coupled law on
        an uncoupled model is close to, but not exactly, the separate pair.
    lat : LateralDesign
        The lateral loop (its weights are used).

    Returns
    -------
    CoupledDesign

    Raises
    ------
    ValueError
        If the lateral design's aileron weight is below what ``R_lon`` already
        charges (the sum would not be the lateral design's).
    """
    from ..conventions import STATE_NAMES

    n = N_STATE
    six = [STATE[sixdof_name(name)] for name in STATE_NAMES]
    Q = np.zeros((n, n))
    Q[np.ix_(six, six)] += Q_lon
    idx = [STATE[name] for name in LATERAL_STATES]
    Q[np.ix_(idx, idx)] += lat.Q
    a = np.zeros(len(LAYOUT.commands))
    a[COMMAND["left"]], a[COMMAND["right"]] = 1.0, -1.0
    extra = float(lat.R[0, 0] - a @ R_lon @ a)
    if extra < 0.0:
        raise ValueError(f"the lateral aileron weight {lat.R[0, 0]:g} is below the "
                         f"longitudinal R's {a @ R_lon @ a:g} along the aileron")
    R = R_lon + extra * np.outer(a, a) / 4.0
    K, P = discounted_lqr(plant.A, plant.B, Q, R, alpha)
    K_sep = longitudinal_gain_on_sixdof(K_lon) + lat.K_full
    sa = math.sqrt(alpha)
    P_sep = scipy.linalg.solve_discrete_lyapunov(sa * (plant.A - plant.B @ K_sep).T,
                                                 Q + K_sep.T @ R @ K_sep)
    return CoupledDesign(K=K, K_separate=K_sep, P=P, P_separate=P_sep, Q=Q, R=R,
                         alpha=float(alpha))


def coupled_engine_tables(plant, design: CoupledDesign, b0_grid: np.ndarray,
                          b1_grid: np.ndarray):
    """c1 on the 6-DOF model: Theorem 4.1's tables (section 4.1.5, eqs.
    26-44) with the coupled design's weights.

    The paper's engine-fault tables (:func:`ftc_mc.design.theorem41.engine_fault_tables`)
    on the 6-DOF linear model, its throttle faulty and its own trim throttle
    in ``F``: the gain of each ``(b0, b1)`` node flies both elevons and what
    is left of the throttle on the whole 6-DOF state, and its affine term
    holds the constant moments of the stuck throttle, the propeller's torque
    about the roll axis among them.

    Parameters
    ----------
    plant : ftc_mc.model.sixdof.SixDofPlant
    design : CoupledDesign
        Its ``Q``, ``R`` and ``alpha``.
    b0_grid, b1_grid : ndarray
        The nodes of the paper's tables (absolute throttle lock, loss).

    Returns
    -------
    EngineTables
        ``K`` (nb0, nb1, 3, 15), ``k`` (nb0, nb1, 3): ``u = -K x - k``, ``x``
        the 6-DOF state and ``u`` the commands, deviations from the 6-DOF trim.
    """
    from types import SimpleNamespace

    from .theorem41 import engine_fault_tables

    model = SimpleNamespace(A=plant.A, B=plant.B, u0=plant.u0)
    return engine_fault_tables(model, b0_grid, b1_grid, design.Q, design.R, design.alpha)


def longitudinal_gain_on_sixdof(K_lon: np.ndarray) -> np.ndarray:
    """The paper's longitudinal gain (3 x 9, on ``u, w, q, x, z, theta,
    throttle, left, right``) acting on the 6-DOF state (3 x 15).

    The longitudinal model's states are the 6-DOF states of the same names
    (its ``x``, ``z`` the along-track and down position errors), so the gain
    maps column by name.
    """
    from ..conventions import INPUT_NAMES, STATE_NAMES

    K = np.zeros((len(LAYOUT.commands), N_STATE))
    for i, cmd in enumerate(INPUT_NAMES):
        for j, name in enumerate(STATE_NAMES):
            K[COMMAND[sixdof_name(cmd)], STATE[sixdof_name(name)]] = K_lon[i, j]
    return K
