r"""Fault controllers of sections 4.1.4-4.1.5: Theorem 4.1 and the elevon allocation.

Paper: "Reconfiguration control method for non-redundant actuator faults on UAV"
(``../shared/seeds/000_6d7db61963b544ed.txt``), eqs. 20-44.

Theorem 4.1 (discounted LQR with a constant input term)
-------------------------------------------------------
Plant ``x+ = A x + E u + F`` (eq. 26), cost ``sum_k alpha^k (x'Qx + u'Ru)``
(eq. 27).  The value function is ``V(x) = x'Px - 2 v'x + c`` (the paper's costate
``mu_k = alpha^k (P x_k - v)``, eq. 34, is the gradient of *half* the cost-to-go
because its Hamiltonian (29) carries a factor 1/2 that (27) does not; this only
scales ``mu`` and changes nothing else).  Bellman's equation gives

* ``P = Q + alpha A'[P - alpha P E (alpha E'PE + R)^-1 E'P] A`` (eqs. 39, 43):
  the ordinary DARE of ``(sqrt(alpha) A, sqrt(alpha) E)``;
* ``u = -K x - k`` with ``K = alpha S^-1 E'PA``, ``k = alpha S^-1 E'(PF - v)``,
  ``S = R + alpha E'PE`` (eqs. 28 = 42);
* ``v = alpha A'v - alpha A'P (I + alpha E R^-1 E'P)^-1 (alpha E R^-1 E' v + F)``
  (eq. 40), equivalently (eq. 41) ``v = alpha A'(I + alpha P E R^-1 E')^-1 (v - PF)``.

Check of the printed equations (done analytically here and numerically in
``tests/test_theorem41.py``):

* eq. 41 is **consistent** with eq. 40 and with the proof (eqs. 34-38).  With
  ``N = (I + alpha P E R^-1 E')^-1`` the push-through identity
  ``P (I + alpha E R^-1 E'P)^-1 = N P`` turns (40) into
  ``v = alpha A'(v - alpha N P E R^-1 E' v - N P F)`` and
  ``v - alpha N P E R^-1 E' v = N (N^-1 - alpha P E R^-1 E') v = N v`` gives (41).
  Eq. 42 repeats eq. 28, and the sign of ``v`` in (28)/(42) matches (34): from
  (32), ``u_k = -alpha R^-1 E'(P x_{k+1} - v)`` with ``x_{k+1} = A x + E u + F``.
  No sign or factor error was found in eqs. 26-43.
* Woodbury gives ``N' A = (I + alpha E R^-1 E'P)^-1 A = A - E K = A_cl`` (the
  closed-loop matrix, also visible in eq. 35), so eq. 41 is the linear system
  ``(I - alpha A_cl') v = -alpha A_cl' P F``.  It is solved in this form with one
  ``numpy.linalg.solve`` (no iteration, no ``R^-1``).  It is uniquely solvable
  because the stabilising DARE solution makes ``sqrt(alpha) A_cl`` Schur stable,
  so the spectral radius of ``alpha A_cl`` is below ``sqrt(alpha) < 1``.
* Notation clash in eq. 44: there ``v^i`` is the whole affine term added to
  ``-K x`` (i.e. ``-alpha S^-1 E'(PF - v)``), not the ``v`` of the theorem.  Here
  the affine term is called ``k`` with ``u = -K x - k``, so eq. 44's ``v^i`` is
  ``-k_i``.

Engine fault (section 4.1.5)
----------------------------
Project convention (:mod:`ftc_mc.model.faults`): ``u`` is the command deviation
from trim, the thrust effect is ``e1 = b0 + (1 - b1) u1 - b1 u0_1`` and the plant
is ``x+ = A x + B e``.  Splitting ``e1`` into its ``u``-dependent and constant
parts gives eq. 26 with

    E = [(1 - b1) B[:, 0], B[:, 1], B[:, 2]],   F = B[:, 0] (b0 - b1 u0_1).

``b0`` is the absolute lock position when locked (``b1 = 1``), so then
``F = B[:, 0] (p - u0_1)``: the stuck throttle's offset from trim.  Nominal
(``b0 = b1 = 0``) gives ``F = 0`` and the nominal discounted LQR.

For ``b1 = 1`` the thrust column of ``E`` vanishes.  With the X8 model the pair
``(A, E)`` then has two uncontrollable eigenvalues: the engine actuator pole
(stable) and one of the two position integrators (at 1, an energy-like
combination of u, x, z, theta and the throttle state).  The undiscounted Riccati
equation has no stabilising solution, but ``(sqrt(alpha) A, sqrt(alpha) E)`` is
stabilisable for ``alpha < 1`` (section 4.1.2): the integrator moves to
``sqrt(alpha)``.  The resulting closed loop still has that eigenvalue at 1, and
when the lock is away from trim ``F`` drives it, so the state drifts linearly
(``w'x_{k+1} = w'x_k + w'F`` for the left eigenvector ``w`` with ``w'E = 0``):
no controller can prevent that drift, the discount keeps the cost finite.

Redundant elevons (section 4.1.4)
---------------------------------
See :func:`ftc_mc.core.longitudinal.control.elevon_allocation`: eq. 25 as printed has a typo (``U^3`` uses
``1 - b1^2``); the minimum-norm solution of (24) uses ``1 - b1^3``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.linalg

from ..core.shared.interp import EngineTables
from .lqr import paper_q_lqr

#: Bumped whenever the table computation changes, so old cache entries are ignored.
TABLES_VERSION = "theorem41-engine-tables-v1"

#: Default grid of the thrust ``b0`` (absolute lock position) [-].
B0_GRID = np.linspace(0.0, 1.0, 11)
#: Default grid of the thrust ``b1`` [-].
B1_GRID = np.linspace(0.0, 1.0, 11)
#: Paper's ``R_lqr = 0.1 Id_3`` (section 5.1).
R_LQR = 0.1 * np.eye(3)
#: Paper's discount ``alpha`` (section 5.1).
ALPHA = 0.999


class BiasedLQR(NamedTuple):
    """Solution of Theorem 4.1: ``u = -K x - k`` (eq. 42)."""

    K: np.ndarray
    """(m, n) gain ``alpha (R + alpha E'PE)^-1 E'PA``."""
    k: np.ndarray
    """(m,) affine term ``alpha (R + alpha E'PE)^-1 E'(PF - v)``."""
    P: np.ndarray
    """(n, n) stabilising solution of the discounted Riccati equation (eq. 43)."""
    v: np.ndarray
    """(n,) solution of eq. 41."""


# --------------------------------------------------------------- Theorem 4.1
def _check_alpha(alpha):
    if not (isinstance(alpha, (int, float, np.floating)) and 0.0 < alpha <= 1.0):
        raise ValueError(f"controller parameter 'discount' must lie in (0, 1], got {alpha!r}")


def unstabilizable_eigenvalues(A, E, tol=1e-9):
    """Eigenvalues of ``A`` with ``|lambda| >= 1`` that ``E`` cannot move (PBH test).

    Parameters
    ----------
    A : ndarray, shape (n, n)
    E : ndarray, shape (n, m)
    tol : float
        Relative rank tolerance on the singular values of ``[A - lambda I, E]``.

    Returns
    -------
    ndarray, complex
        Distinct such eigenvalues (repeated ones listed once); empty when
        ``(A, E)`` is stabilisable.
    """
    A = np.asarray(A, dtype=float)
    E = np.asarray(E, dtype=float)
    n = A.shape[0]
    bad = []
    for lam in np.linalg.eigvals(A):
        if abs(lam) < 1.0 - 1e-12 or any(abs(lam - b) < 1e-9 for b in bad):
            continue
        s = np.linalg.svd(np.hstack([A - lam * np.eye(n), E]), compute_uv=False)
        if s[-1] <= tol * max(s[0], 1.0):
            bad.append(lam)
    return np.array(bad, dtype=complex)


def biased_discounted_lqr(A, E, F, Q, R, alpha):
    """Discounted LQR for ``x+ = A x + E u + F`` (Theorem 4.1, eqs. 26-43).

    Parameters
    ----------
    A : ndarray, shape (n, n)
        State matrix.
    E : ndarray, shape (n, m)
        Input matrix (may have zero columns, e.g. a locked actuator).
    F : ndarray, shape (n,)
        Constant input term.
    Q : ndarray, shape (n, n)
        State weight, symmetric PSD.
    R : ndarray, shape (m, m)
        Input weight, symmetric PD.
    alpha : float
        Discount factor in (0, 1] (paper: 0.999).

    Returns
    -------
    BiasedLQR
        ``(K, k, P, v)`` with the optimal command ``u = -K x - k``.

    Raises
    ------
    ValueError
        On a bad ``alpha`` or shapes, when ``(sqrt(alpha) A, sqrt(alpha) E)`` is
        not stabilisable, or when the Riccati equation has no stabilising solution.
    """
    _check_alpha(alpha)
    A = np.asarray(A, dtype=float)
    E = np.asarray(E, dtype=float)
    F = np.asarray(F, dtype=float)
    Q = np.asarray(Q, dtype=float)
    R = np.asarray(R, dtype=float)
    n, m = E.shape
    if A.shape != (n, n) or F.shape != (n,) or Q.shape != (n, n) or R.shape != (m, m):
        raise ValueError(f"inconsistent shapes: A {A.shape}, E {E.shape}, F {F.shape}, "
                         f"Q {Q.shape}, R {R.shape}")
    sa = math.sqrt(alpha)
    Ab, Eb = sa * A, sa * E
    bad = unstabilizable_eigenvalues(Ab, Eb)
    if bad.size:
        raise ValueError("(sqrt(alpha) A, sqrt(alpha) E) is not stabilisable: "
                         f"uncontrollable eigenvalues {bad} of modulus >= 1 "
                         f"(alpha = {alpha}); use a discount alpha < 1 (section 4.1.2)")
    try:
        P = scipy.linalg.solve_discrete_are(Ab, Eb, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"discounted Riccati equation (eq. 43) not solvable: {exc}") from exc
    P = 0.5 * (P + P.T)
    S = R + Eb.T @ P @ Eb                       # R + alpha E'PE
    K = np.linalg.solve(S, Eb.T @ P @ Ab)       # alpha S^-1 E'PA (eq. 42)
    Acl = A - E @ K
    # eq. 41 as a linear system: (I - alpha Acl') v = -alpha Acl' P F
    G = alpha * Acl.T
    v = np.linalg.solve(np.eye(n) - G, -G @ (P @ F))
    k = alpha * np.linalg.solve(S, E.T @ (P @ F - v))
    return BiasedLQR(K=K, k=k, P=P, v=v)


def policy_cost(A, E, F, Q, R, alpha, K, k, x0):
    """Exact discounted cost of the affine policy ``u = -K x - k`` (eq. 27).

    ``J = sum_k alpha^k (x'Qx + u'Ru)`` from ``x0`` along ``x+ = A x + E u + F``,
    from the discounted Lyapunov equation of the augmented state ``[x; 1]``.

    Parameters
    ----------
    A, E, F, Q, R, alpha
        As in :func:`biased_discounted_lqr`.
    K : ndarray, shape (m, n)
    k : ndarray, shape (m,)
    x0 : ndarray, shape (n,) or (n, p)
        Initial state(s).

    Returns
    -------
    float or ndarray, shape (p,)
        ``inf`` when ``sqrt(alpha)`` times the closed-loop spectral radius is >= 1.
    """
    A, E, F, Q, R, K, k = (np.asarray(a, dtype=float) for a in (A, E, F, Q, R, K, k))
    n = A.shape[0]
    Phi = np.zeros((n + 1, n + 1))
    Phi[:n, :n] = A - E @ K
    Phi[:n, n] = F - E @ k
    Phi[n, n] = 1.0
    x0 = np.asarray(x0, dtype=float)
    z0 = np.vstack([x0.reshape(n, -1), np.ones((1, x0.reshape(n, -1).shape[1]))])
    if math.sqrt(alpha) * max(abs(np.linalg.eigvals(Phi))) >= 1.0:
        out = np.full(z0.shape[1], np.inf)
        return out if x0.ndim == 2 else float(out[0])
    W = np.zeros((n + 1, n + 1))
    W[:n, :n] = Q + K.T @ R @ K
    W[:n, n] = K.T @ R @ k
    W[n, :n] = W[:n, n]
    W[n, n] = k @ R @ k
    X = scipy.linalg.solve_discrete_lyapunov(math.sqrt(alpha) * Phi.T, W)
    out = np.einsum("ip,ij,jp->p", z0, X, z0)
    return out if x0.ndim == 2 else float(out[0])


# -------------------------------------------------------------- engine fault
def engine_fault_model(B, u0, b0, b1):
    """``E`` and ``F`` of eq. 26 for a thrust fault ``(b0, b1)`` (section 4.1.5).

    Parameters
    ----------
    B : ndarray, shape (n, 3)
        Input matrix of eq. 1.
    u0 : array_like, shape (3,)
        Trim commands (absolute).
    b0 : float
        Thrust bias (absolute lock position when ``b1 = 1``) [-].
    b1 : float
        Thrust effectiveness loss in [0, 1] [-].

    Returns
    -------
    E : ndarray, shape (n, 3)
        ``[(1 - b1) B[:, 0], B[:, 1], B[:, 2]]``.
    F : ndarray, shape (n,)
        ``B[:, 0] (b0 - b1 u0_1)``: the constant part of the thrust effect
        ``e1 = b0 + (1 - b1) u1 - b1 u0_1``.
    """
    B = np.asarray(B, dtype=float)
    E = B.copy()
    E[:, 0] *= 1.0 - b1
    F = B[:, 0] * (b0 - b1 * float(u0[0]))
    return E, F


def _defaults(plant, b0_grid, b1_grid, Q, R, alpha):
    b0_grid = B0_GRID if b0_grid is None else b0_grid
    b1_grid = B1_GRID if b1_grid is None else b1_grid
    Q = paper_q_lqr(plant.trim.gamma0, plant.A.shape[0]) if Q is None else Q
    R = R_LQR if R is None else R
    alpha = ALPHA if alpha is None else alpha
    b0_grid = np.ascontiguousarray(b0_grid, dtype=float)
    b1_grid = np.ascontiguousarray(b1_grid, dtype=float)
    for name, g in (("b0_grid", b0_grid), ("b1_grid", b1_grid)):
        if g.ndim != 1 or g.size < 1 or not np.all(np.isfinite(g)) or np.any(np.diff(g) <= 0):
            raise ValueError(f"engine table parameter '{name}' must be a non-empty, finite, "
                             f"strictly increasing 1-D grid, got {g!r}")
    if b1_grid[0] < 0 or b1_grid[-1] > 1:
        raise ValueError(f"engine table parameter 'b1_grid' must lie in [0, 1], got {b1_grid!r}")
    _check_alpha(alpha)
    return (b0_grid, b1_grid, np.ascontiguousarray(Q, dtype=float),
            np.ascontiguousarray(R, dtype=float), float(alpha))


def engine_fault_tables(plant, b0_grid=None, b1_grid=None, Q=None, R=None, alpha=None):
    """Theorem 4.1 gain and affine term over a ``(b0, b1)`` grid of the thrust fault.

    Engine-fault controller c1 of section 4.1.5 (eqs. 26-44), computed offline.

    Parameters
    ----------
    plant : LinearPlant
        Uses ``A``, ``B`` and ``u0``.
    b0_grid : array_like, shape (nb0,), optional
        Strictly increasing thrust ``b0`` nodes (absolute lock position) [-];
        default 11 points on [0, 1].
    b1_grid : array_like, shape (nb1,), optional
        Strictly increasing thrust ``b1`` nodes in [0, 1]; default 11 points.
        ``b1 = 1`` (engine locked) is solvable thanks to the discount.
    Q : ndarray, shape (9, 9), optional
        State weight; default ``Q_lqr`` of section 5.1.
    R : ndarray, shape (3, 3), optional
        Input weight; default ``0.1 Id_3`` (section 5.1).
    alpha : float, optional
        Discount in (0, 1); default 0.999.

    Returns
    -------
    EngineTables
        ``K`` (nb0, nb1, 3, 9), ``k`` (nb0, nb1, 3) with ``u = -K x - k``, and the
        grids (C-contiguous float64, ready for :func:`ftc_mc.core.shared.interp.engine_controller`).

    Raises
    ------
    ValueError
        On invalid grids or weights, or when a grid point is not solvable (e.g.
        ``alpha = 1`` with ``b1 = 1``).
    """
    b0_grid, b1_grid, Q, R, alpha = _defaults(plant, b0_grid, b1_grid, Q, R, alpha)
    A = np.asarray(plant.A, dtype=float)
    B = np.asarray(plant.B, dtype=float)
    u0 = np.asarray(plant.u0, dtype=float)
    n, m = B.shape
    K_tab = np.empty((b0_grid.size, b1_grid.size, m, n))
    k_tab = np.empty((b0_grid.size, b1_grid.size, m))
    for j, b1 in enumerate(b1_grid):
        # P and K depend on b1 only; v and k are linear in F (eq. 41), so one
        # Riccati solve serves the whole b0 column
        E, _ = engine_fault_model(B, u0, 0.0, b1)
        try:
            sol = biased_discounted_lqr(A, E, np.zeros(n), Q, R, alpha)
        except ValueError as exc:
            raise ValueError(f"engine fault table: b1 = {b1}: {exc}") from exc
        S = R + alpha * E.T @ sol.P @ E
        G = alpha * (A - E @ sol.K).T
        lhs = np.eye(n) - G
        for i, b0 in enumerate(b0_grid):
            _, F = engine_fault_model(B, u0, b0, b1)
            v = np.linalg.solve(lhs, -G @ (sol.P @ F))
            K_tab[i, j] = sol.K
            k_tab[i, j] = alpha * np.linalg.solve(S, E.T @ (sol.P @ F - v))
    return EngineTables(K=K_tab, k=k_tab, b0_grid=b0_grid, b1_grid=b1_grid)
