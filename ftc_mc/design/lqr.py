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
