"""Actuator fault model (paper eqs. 2-4) and the augmented system (eq. 5).

Conventions (docs/reference/paper-map.md):

* ``u`` is the command deviation from trim ``u0``.  The effect of actuator ``i``
  (eq. 2) is ``e_i = b0_i + (1 - b1_i) u_i - b1_i u0_i``, so the *absolute* effect
  is ``(1 - b1_i)(u0_i + u_i) + b0_i``.
* nominal: ``b0 = 0``, ``b1 = 0``; locked at absolute position ``p``:
  ``b1 = 1``, ``b0 = p``; loss of effectiveness: ``b0 = 0``, ``b1`` in (0, 1].
* The truth plant carries one ``b0`` per actuator (3 entries).  The estimator
  carries two (paper section 2.4): the thrust's and the *sum* of the two elevons'
  (biases of redundant actuators cannot be told apart).  The elevon sum enters the
  augmented model through the mean of the two elevon columns of ``B``,
  ``(B[:, 1] + B[:, 2]) / 2``: the pitch effect of the elevons is their mean, so a
  bias ``b`` on one elevon and ``b/2`` on each give the same outputs, and the
  symmetric split keeps the estimator neutral between left and right until ``b1``
  tells them apart.
* Bounds: ``b1`` in [0, 1]; ``b0`` of the thrust within the absolute throttle range
  [0, 1]; ``b0`` of the elevon sum within twice the elevon range (a sum of two
  absolute deflections).

Augmented state (14): ``X = [x (9), b0 (2), b1 (3)]`` (eq. 5).
"""

from __future__ import annotations

import numpy as np

from ..conventions import (MODE_ENGINE, MODE_LEFT_ELEVON, MODE_NOMINAL,
                           MODE_RIGHT_ELEVON, N_B0, N_FAULT)


def effect(u, u0, b0, b1):
    """Effect of the actuators on the plant (eq. 2), deviation from trim.

    Parameters
    ----------
    u : array_like, shape (3,)
        Command deviations from trim.
    u0 : array_like, shape (3,)
        Trim commands (absolute).
    b0 : array_like, shape (3,)
        Per-actuator bias fault parameter (absolute lock position when locked).
    b1 : array_like, shape (3,)
        Per-actuator effectiveness loss in [0, 1].

    Returns
    -------
    ndarray, shape (3,)
        ``e = b0 + (1 - b1) u - b1 u0``.
    """
    u = np.asarray(u, dtype=float)
    b1 = np.asarray(b1, dtype=float)
    return np.asarray(b0, dtype=float) + (1.0 - b1) * u - b1 * np.asarray(u0, dtype=float)


def bias_matrix(B):
    """Input matrix of the estimator's two biases (thrust, elevon sum).

    Parameters
    ----------
    B : ndarray, shape (n, 3)

    Returns
    -------
    ndarray, shape (n, 2)
        ``[B[:, 0], (B[:, 1] + B[:, 2]) / 2]``.
    """
    return np.column_stack([B[:, 0], 0.5 * (B[:, 1] + B[:, 2])])


def fault_input_matrix(B, u, u0):
    """``D(u) = B diag(-u - u0)`` of eq. (4).

    Parameters
    ----------
    B : ndarray, shape (n, 3)
    u, u0 : array_like, shape (3,)
        Command deviation and trim commands.

    Returns
    -------
    ndarray, shape (n, 3)
    """
    return B * (-(np.asarray(u, dtype=float) + np.asarray(u0, dtype=float)))[None, :]


def augmented(A, B, C, u, u0):
    """Augmented matrices of eq. (5) for the command ``u`` applied this step.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, 3)
    C : ndarray, shape (m, n)
    u, u0 : array_like, shape (3,)

    Returns
    -------
    A_aug : ndarray, shape (n+5, n+5)
        ``[[A, B_b0, D(u)], [0, I_2, 0], [0, 0, I_3]]``.
    B_aug : ndarray, shape (n+5, 3)
        ``[B; 0]``.
    C_aug : ndarray, shape (m, n+5)
        ``[C, 0]``.
    """
    n = A.shape[0]
    na = n + N_FAULT
    A_aug = np.eye(na)
    A_aug[:n, :n] = A
    A_aug[:n, n:n + N_B0] = bias_matrix(B)
    A_aug[:n, n + N_B0:] = fault_input_matrix(B, u, u0)
    B_aug = np.zeros((na, B.shape[1]))
    B_aug[:n] = B
    C_aug = np.zeros((C.shape[0], na))
    C_aug[:, :n] = C
    return A_aug, B_aug, C_aug


def fault_bounds(u_lower, u_upper):
    """Box bounds of the fault parameters (eq. 6 with unit rows).

    Parameters
    ----------
    u_lower, u_upper : array_like, shape (3,)
        Absolute command limits.

    Returns
    -------
    lo, hi : ndarray, shape (5,)
        Bounds of ``[b0_thrust, b0_elevon_sum, b1_thrust, b1_left, b1_right]``.
    """
    lo = np.array([u_lower[0], 2 * u_lower[1], 0.0, 0.0, 0.0])
    hi = np.array([u_upper[0], 2 * u_upper[1], 1.0, 1.0, 1.0])
    return lo, hi


def estimator_params(b0, b1):
    """The estimator's parameters ``[b0_T, b0_L + b0_R, b1_T, b1_L, b1_R]`` of a truth.

    Parameters
    ----------
    b0, b1 : ndarray, shape (3,) or (3, L)
        Per-actuator truth (one column per lane).

    Returns
    -------
    ndarray, shape (5,) or (5, L)
    """
    return np.stack([b0[0], b0[1] + b0[2], b1[0], b1[1], b1[2]])


def mode_of(b1, beta_engine: float, beta_elevon: float):
    """The belief mode whose box holds the truth ``b1`` (one fault at a time).

    The engine is faulty when its ``b1`` exceeds ``beta_engine``, else an elevon
    when its ``b1`` exceeds ``beta_elevon`` (the left one first); otherwise the
    mode is nominal (docs/reference/paper-map.md).

    Parameters
    ----------
    b1 : ndarray, shape (3,) or (3, L)
    beta_engine, beta_elevon : float

    Returns
    -------
    ndarray of int64, shape () or (L,)
        Mode codes (:data:`ftc_mc.conventions.MODE_NAMES`).
    """
    b1 = np.asarray(b1, dtype=float)
    mode = np.full(b1.shape[1:], MODE_NOMINAL, dtype=np.int64)
    mode = np.where(b1[2] > beta_elevon, MODE_RIGHT_ELEVON, mode)
    mode = np.where(b1[1] > beta_elevon, MODE_LEFT_ELEVON, mode)
    return np.where(b1[0] > beta_engine, MODE_ENGINE, mode).astype(np.int64)
