"""Lateral-directional loop of the 6-DOF X8: wings level and heading hold (issue 24).

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
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..core.sixdof.layout import COMMAND, LAYOUT, N_STATE, STATE
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


def longitudinal_gain_on_sixdof(K_lon: np.ndarray) -> np.ndarray:
    """The paper's longitudinal gain (3 x 9, on ``u, w, q, x, z, theta,
    throttle, left, right``) acting on the 6-DOF state (3 x 15).

    The longitudinal model's states are the 6-DOF states of the same names
    (its ``x``, ``z`` the along-track and down position errors), so the gain
    maps column by name.
    """
    from ..conventions import INPUT_NAMES, STATE_NAMES

    rename = {"thrust": "throttle", "elevon_left": "left", "elevon_right": "right"}
    K = np.zeros((len(LAYOUT.commands), N_STATE))
    for i, cmd in enumerate(INPUT_NAMES):
        for j, name in enumerate(STATE_NAMES):
            K[COMMAND[rename.get(cmd, cmd)], STATE[rename.get(name, name)]] = K_lon[i, j]
    return K
