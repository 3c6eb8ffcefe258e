"""Discounted LQR (paper sections 4.1.2-4.1.3 and eq. 43).

The gain minimising ``sum_k alpha^k (x^T Q x + u^T R u)`` is the ordinary LQR gain
of the pair ``(sqrt(alpha) A, sqrt(alpha) B)`` (eq. 43); the Riccati equation is
solved by :func:`scipy.linalg.solve_discrete_are`.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from ..conventions import LONGITUDINAL


def paper_q_lqr(gamma0: float, n: int = LONGITUDINAL.n_x) -> np.ndarray:
    """``Q_lqr = diag(0, 0, 0, tan^2(gamma), 1, 0, 0, 0, 0)`` (section 5.1): the
    weights on the along-track ``x`` and the vertical ``z`` deviations.

    Parameters
    ----------
    gamma0 : float
        Glide-path angle [rad].
    n : int
        State dimension (9).
    """
    q = np.zeros(n)
    q[LONGITUDINAL.state("x")] = math.tan(gamma0) ** 2
    q[LONGITUDINAL.state("z")] = 1.0
    return np.diag(q)


def bryson_q_lqr(airspeed_mps: float = 2.0, height_m: float = 1.0, pitch_deg: float = 10.0,
                 pitch_rate_dps: float = 30.0, n: int = LONGITUDINAL.n_x) -> np.ndarray:
    """Diagonal ``Q_lqr`` by Bryson's rule, for flight in turbulence.

    Each weight is one over the square of the largest deviation accepted: on
    the body velocity ``u`` (the airspeed's proxy in the linear model; ``u`` is
    inertial, so the loop holds the ground-referenced speed, not the airspeed),
    the height ``z``, the pitch ``theta`` and the pitch rate ``q``; no weight on
    the along-track position ``x``.  The paper's :func:`paper_q_lqr` holds a
    point moving at the trim ground speed and pays a tailwind back in airspeed
    (docs/findings/turbulence-envelope.md).

    Parameters
    ----------
    airspeed_mps, height_m : float
        Largest accepted deviations of ``u`` [m/s] and ``z`` [m].
    pitch_deg, pitch_rate_dps : float
        Largest accepted pitch [deg] and pitch rate [deg/s] deviations.
    n : int
        State dimension (9).
    """
    q = np.zeros(n)
    q[LONGITUDINAL.state("u")] = 1.0 / airspeed_mps ** 2
    q[LONGITUDINAL.state("z")] = 1.0 / height_m ** 2
    q[LONGITUDINAL.state("theta")] = 1.0 / math.radians(pitch_deg) ** 2
    q[LONGITUDINAL.state("q")] = 1.0 / math.radians(pitch_rate_dps) ** 2
    return np.diag(q)


def bryson_r_lqr(throttle: float = 3.0, elevon_rad: float = 0.1) -> np.ndarray:
    """Diagonal ``R_lqr`` by Bryson's rule: ``diag(1/throttle^2, 1/elevon^2, 1/elevon^2)``
    (commands throttle, left and right elevon)."""
    return np.diag([1.0 / throttle ** 2, 1.0 / elevon_rad ** 2, 1.0 / elevon_rad ** 2])


def controller_weights(c, gamma0: float, weights: str | None = None):
    """``(Q_lqr, R_lqr)`` of a validated ``controller`` config section.

    ``weights`` (``paper`` or ``airspeed``; None: the section's ``weights``)
    chooses the rule. ``paper``: :func:`paper_q_lqr` and ``r_lqr I_3`` (section 5.1);
    ``weights: airspeed``: :func:`bryson_q_lqr` and :func:`bryson_r_lqr` on the
    section's scales.  c0's gain, Theorem 4.1's tables (c1), the terminal costs
    and the selection's prediction all use these weights.
    """
    if (c.weights if weights is None else weights) == "airspeed":
        return (bryson_q_lqr(c.airspeed_scale_mps, c.height_scale_m, c.pitch_scale_deg,
                             c.pitch_rate_scale_dps),
                bryson_r_lqr(c.throttle_scale, c.elevon_scale_rad))
    return paper_q_lqr(gamma0), c.r_lqr * np.eye(3)


def discounted_lqr(A, B, Q, R, alpha):
    """Gain and cost matrix of the discounted LQR.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, m)
    Q : ndarray, shape (n, n)
        State weight, symmetric PSD.
    R : ndarray, shape (m, m)
        Input weight, symmetric PD.
    alpha : float
        Discount factor in (0, 1] (paper: 0.999).

    Returns
    -------
    K : ndarray, shape (m, n)
        ``u = -K x``; ``K = alpha (R + alpha B^T P B)^-1 B^T P A`` (eq. 28, F = 0).
    P : ndarray, shape (n, n)
        Solution of eq. (43).

    Raises
    ------
    ValueError
        If ``alpha`` is outside (0, 1].
    """
    if not (0.0 < alpha <= 1.0):
        raise ValueError(f"controller parameter 'discount' must lie in (0, 1], got {alpha!r}")
    sa = math.sqrt(alpha)
    Ab, Bb = sa * A, sa * B
    P = scipy.linalg.solve_discrete_are(Ab, Bb, Q, R)
    K = np.linalg.solve(R + Bb.T @ P @ Bb, Bb.T @ P @ Ab)
    return K, P
