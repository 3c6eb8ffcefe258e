"""Theorem 4.1 (eqs. 26-44), the engine-fault tables, their interpolation kernel,
the redundant-elevon allocation (eqs. 20-25) and the design cache.

Paper: ``../shared/seeds/000_6d7db61963b544ed.txt``, sections 4.1.4-4.1.5.
"""

from __future__ import annotations

import math
import time

import control
import numpy as np
import pytest
import scipy.linalg
from scipy.interpolate import RegularGridInterpolator

from ftc_mc.core.longitudinal.control import elevon_allocation
from ftc_mc.core.shared.interp import bilinear, engine_controller
from ftc_mc.cache import engine_tables as et
from ftc_mc.cache import store
from ftc_mc.design import theorem41 as t41
from ftc_mc.design.lqr import discounted_lqr, paper_q_lqr

ALPHA = 0.999
R = 0.1 * np.eye(3)


@pytest.fixture(scope="module")
def Q(plant):
    return paper_q_lqr(plant.trim.gamma0)


def _random_system(rng, n=5, m=2):
    A = rng.normal(size=(n, n)) * 0.5
    E = rng.normal(size=(n, m))
    F = rng.normal(size=n)
    G = rng.normal(size=(n, n))
    Qr = G @ G.T / n
    H = rng.normal(size=(m, m))
    Rr = H @ H.T + m * np.eye(m)
    return A, E, F, Qr, Rr


def _rel(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


# ------------------------------------------------------------ Theorem 4.1
@pytest.mark.parametrize("b1", [0.0, 0.5])
def test_reduces_to_discounted_lqr_when_F_is_zero(plant, Q, b1):
    E, _ = t41.engine_fault_model(plant.B, plant.u0, 0.0, b1)
    sol = t41.biased_discounted_lqr(plant.A, E, np.zeros(9), Q, R, ALPHA)
    K_ref, P_ref = discounted_lqr(plant.A, E, Q, R, ALPHA)
    sa = math.sqrt(ALPHA)
    K_ctrl, _, _ = control.dlqr(sa * plant.A, sa * E, Q, R)
    assert _rel(sol.K, K_ref) < 1e-10
    assert _rel(sol.K, np.asarray(K_ctrl)) < 1e-10
    assert _rel(sol.P, P_ref) < 1e-10
    assert np.all(sol.v == 0.0) and np.all(sol.k == 0.0)


def test_reduces_to_dlqr_random_systems():
    rng = np.random.default_rng(7)
    for _ in range(5):
        A, E, _, Qr, Rr = _random_system(rng)
        sol = t41.biased_discounted_lqr(A, E, np.zeros(A.shape[0]), Qr, Rr, 0.9)
        K_ctrl, _, _ = control.dlqr(math.sqrt(0.9) * A, math.sqrt(0.9) * E, Qr, Rr)
        assert _rel(sol.K, np.asarray(K_ctrl)) < 1e-10
        assert np.all(sol.v == 0.0)


def _eq41_residual(A, E, F, R_, alpha, P, v):
    """Residual of eq. 41 *as printed* and of eq. 40 (explicit inverses)."""
    n = A.shape[0]
    Ri = np.linalg.inv(R_)
    N41 = np.linalg.inv(np.eye(n) + alpha * P @ E @ Ri @ E.T)
    r41 = v - alpha * A.T @ N41 @ (v - P @ F)
    N40 = np.linalg.inv(np.eye(n) + alpha * E @ Ri @ E.T @ P)
    r40 = v - (alpha * A.T @ v - alpha * A.T @ P @ N40 @ (alpha * E @ Ri @ E.T @ v + F))
    scale = max(np.max(np.abs(v)), 1.0)
    return np.max(np.abs(r41)) / scale, np.max(np.abs(r40)) / scale


@pytest.mark.parametrize("b1", [0.0, 0.5, 1.0])
def test_v_satisfies_eq41_and_eq40(plant, Q, b1):
    E, F = t41.engine_fault_model(plant.B, plant.u0, 0.3, b1)
    sol = t41.biased_discounted_lqr(plant.A, E, F, Q, R, ALPHA)
    r41, r40 = _eq41_residual(plant.A, E, F, R, ALPHA, sol.P, sol.v)
    assert r41 < 1e-10 and r40 < 1e-10
    assert np.any(sol.v != 0.0)
    # eq. 42 == eq. 28 with this v
    S = R + ALPHA * E.T @ sol.P @ E
    k42 = ALPHA * np.linalg.solve(S, E.T @ (sol.P @ F - sol.v))
    assert _rel(sol.k, k42) < 1e-12


def test_v_fixed_point_random_systems():
    rng = np.random.default_rng(11)
    for _ in range(5):
        A, E, F, Qr, Rr = _random_system(rng)
        sol = t41.biased_discounted_lqr(A, E, F, Qr, Rr, 0.95)
        r41, r40 = _eq41_residual(A, E, F, Rr, 0.95, sol.P, sol.v)
        assert r41 < 1e-10 and r40 < 1e-10


def test_locked_engine_needs_discount(plant, Q):
    E, F = t41.engine_fault_model(plant.B, plant.u0, 0.3, 1.0)
    assert not np.any(E[:, 0])
    # (A, E) is not stabilisable (integrator at 1), the discounted pair is
    assert t41.unstabilizable_eigenvalues(plant.A, E).size == 1
    sa = math.sqrt(ALPHA)
    assert t41.unstabilizable_eigenvalues(sa * plant.A, sa * E).size == 0
    with pytest.raises(ValueError, match="not stabilisable"):
        t41.biased_discounted_lqr(plant.A, E, F, Q, R, 1.0)
    sol = t41.biased_discounted_lqr(plant.A, E, F, Q, R, ALPHA)
    assert np.all(np.isfinite(sol.K)) and np.all(np.isfinite(sol.k))
    assert np.all(sol.K[0] == 0.0) and sol.k[0] == 0.0   # the dead throttle gets no command


def _simulate_costs(A, E, F, Q_, R_, alpha, Ks, ks, X0, n_steps):
    """Discounted costs of policies u = -K x - k; states of policy 0 returned too."""
    X = np.broadcast_to(X0[None], (Ks.shape[0],) + X0.shape).copy()  # (p, s, n)
    J = np.zeros(X.shape[:2])
    disc = 1.0
    traj = np.empty((n_steps + 1,) + X0.shape)
    traj[0] = X[0]
    for step in range(n_steps):
        U = -np.einsum("pmn,psn->psm", Ks, X) - ks[:, None, :]
        J += disc * (np.einsum("psn,nj,psj->ps", X, Q_, X)
                     + np.einsum("psm,mj,psj->ps", U, R_, U))
        X = X @ A.T + U @ E.T + F
        traj[step + 1] = X[0]
        disc *= alpha
    return J, traj


@pytest.mark.parametrize("b1", [1.0, 0.5])
def test_optimal_by_simulation(plant, Q, b1):
    b0 = 0.3
    A = plant.A
    E, F = t41.engine_fault_model(plant.B, plant.u0, b0, b1)
    sol = t41.biased_discounted_lqr(A, E, F, Q, R, ALPHA)
    rng = np.random.default_rng(2024)
    n_pert = 24
    Ks = [sol.K]
    ks = [sol.k]
    for i in range(n_pert):
        # relative per entry (the entries span four decades) plus a small floor on k
        dK = sol.K * rng.normal(size=sol.K.shape) * 0.02
        dk = (sol.k * rng.normal(size=3) * 0.02
              + rng.normal(size=3) * 1e-3 * np.abs(sol.k).max())
        if i % 3 == 0:          # gain only
            dk[:] = 0.0
        elif i % 3 == 1:        # affine term only
            dK[:] = 0.0
        Ks.append(sol.K + dK)
        ks.append(sol.k + dk)
    Ks, ks = np.array(Ks), np.array(ks)
    X0 = np.zeros((4, 9))
    X0[1, [0, 3, 4]] = [1.0, 5.0, -3.0]      # speed, along-track, height error
    X0[2, [1, 2, 5]] = [0.5, 0.05, 0.03]
    X0[3] = rng.normal(size=9) * 0.5
    n_steps = 20_000
    J, traj = _simulate_costs(A, E, F, Q, R, ALPHA, Ks, ks, X0, n_steps)
    J_opt = J[0]
    # every perturbation is worse, from every initial state (the smallest margin,
    # ~1e-10, is a gain-only perturbation from x0 = 0 where x stays near its fixed
    # point; the round-off of the 20 000-term sums is ~1e-13)
    assert np.all(J[1:] > J_opt[None, :] * (1 + 1e-11)), (J[1:] / J_opt - 1).min()
    # same verdict from the exact infinite-horizon costs
    J_inf = np.array([t41.policy_cost(A, E, F, Q, R, ALPHA, Kp, kp, X0.T)
                      for Kp, kp in zip(Ks, ks)])
    assert np.all(J_inf[1:] > J_inf[0][None, :]), (J_inf[1:] / J_inf[0] - 1).min()
    # the simulated optimum is the value function x'Px - 2 v'x + c (exact, Lyapunov)
    J_exact = t41.policy_cost(A, E, F, Q, R, ALPHA, sol.K, sol.k, X0.T)
    yc = F - E @ sol.k
    c = (sol.k @ R @ sol.k + ALPHA * (yc @ sol.P @ yc - 2 * sol.v @ yc)) / (1 - ALPHA)
    V = np.einsum("si,ij,sj->s", X0, sol.P, X0) - 2 * X0 @ sol.v + c
    assert np.allclose(J_exact, V, rtol=1e-9)
    # finite horizon: sum_{k<N} = V(x_0) - alpha^N V(x_N) (the locked engine's drift
    # makes the tail alpha^N V(x_N) about 5e-7 of the total at N = 20 000)
    xN = traj[-1]
    VN = np.einsum("si,ij,sj->s", xN, sol.P, xN) - 2 * xN @ sol.v + c
    assert np.allclose(J_opt, V - ALPHA ** n_steps * VN, rtol=1e-9)
    assert np.allclose(J_opt, J_exact, rtol=2e-6)
    # closed loop: bounded (b1 < 1), or only the unavoidable drift (locked engine)
    Acl = A - E @ sol.K
    rho = np.abs(np.linalg.eigvals(Acl))
    dx = np.diff(traj, axis=0)
    if b1 < 1.0:
        assert rho.max() < 1.0
        x_ss = np.linalg.solve(np.eye(9) - Acl, F - E @ sol.k)
        assert np.max(np.abs(traj[-1] - x_ss)) < 1e-8 * max(1.0, np.abs(x_ss).max())
        assert np.all(np.isfinite(traj)) and np.abs(traj).max() < 1e3
    else:
        # one eigenvalue at 1 stays (uncontrollable integrator), all others inside
        assert np.sum(rho > 1 - 1e-9) == 1 and np.sort(rho)[-2] < 1.0
        # left null vector of [A - I, E]: w'A = w', w'E = 0 (the uncontrollable mode)
        wl = scipy.linalg.null_space(np.hstack([A - np.eye(9), E]).T, rcond=1e-10)
        assert wl.shape[1] == 1
        wl = wl[:, 0]
        drift = wl @ F
        # no controller changes w'x: it grows by w'F every step
        assert np.allclose(traj[:, 0] @ wl, X0[0] @ wl + drift * np.arange(n_steps + 1),
                           rtol=1e-8, atol=1e-8)
        # increments converge to a constant: the state is a bounded part plus k d
        assert np.max(np.abs(dx[-1] - dx[-1000])) < 1e-9
        resid = traj - np.arange(n_steps + 1)[:, None, None] * dx[-1]
        assert np.abs(resid).max() < 1e3


# ------------------------------------------------------------ engine tables
def test_engine_tables_match_theorem(plant, Q):
    tab = t41.engine_fault_tables(plant)
    assert tab.K.shape == (11, 11, 3, 9) and tab.k.shape == (11, 11, 3)
    assert np.all(np.isfinite(tab.K)) and np.all(np.isfinite(tab.k))
    for i, j in [(0, 0), (3, 5), (3, 10), (10, 10)]:
        E, F = t41.engine_fault_model(plant.B, plant.u0, tab.b0_grid[i], tab.b1_grid[j])
        sol = t41.biased_discounted_lqr(plant.A, E, F, Q, R, ALPHA)
        assert np.allclose(tab.K[i, j], sol.K, rtol=1e-12, atol=1e-14)
        assert np.allclose(tab.k[i, j], sol.k, rtol=1e-10, atol=1e-14)
    # nominal node: the nominal discounted LQR, no affine term
    K0, _ = discounted_lqr(plant.A, plant.B, Q, R, ALPHA)
    assert _rel(tab.K[0, 0], K0) < 1e-10 and np.all(tab.k[0, 0] == 0.0)
    # locked column: no throttle command
    assert np.all(tab.K[:, -1, 0] == 0.0) and np.all(tab.k[:, -1, 0] == 0.0)


# ------------------------------------------------------------ interpolation
def _bilinear_twin(table, xg, yg, x, y):
    """Plain-NumPy bilinear interpolation with clamping (reference)."""
    x = min(max(x, xg[0]), xg[-1])
    y = min(max(y, yg[0]), yg[-1])
    i = min(max(np.searchsorted(xg, x, side="right") - 1, 0), len(xg) - 2)
    j = min(max(np.searchsorted(yg, y, side="right") - 1, 0), len(yg) - 2)
    tx = (x - xg[i]) / (xg[i + 1] - xg[i])
    ty = (y - yg[j]) / (yg[j + 1] - yg[j])
    return ((1 - tx) * (1 - ty) * table[i, j] + (1 - tx) * ty * table[i, j + 1]
            + tx * (1 - ty) * table[i + 1, j] + tx * ty * table[i + 1, j + 1])


def test_bilinear_nodes_between_and_outside():
    rng = np.random.default_rng(3)
    xg = np.sort(rng.uniform(-1, 2, 7))
    yg = np.concatenate([[0.0], np.sort(rng.uniform(0.05, 0.95, 4)), [1.0]])
    table = rng.normal(size=(7, 6, 5))
    out = np.empty(5)
    for i in range(7):
        for j in range(6):
            bilinear(table, xg, yg, xg[i], yg[j], out)
            assert np.array_equal(out, table[i, j])          # exact at nodes
    rgi = RegularGridInterpolator((xg, yg), table, method="linear")
    for _ in range(300):
        x, y = rng.uniform(xg[0], xg[-1]), rng.uniform(0, 1)
        bilinear(table, xg, yg, x, y, out)
        assert np.max(np.abs(out - rgi([x, y])[0])) < 1e-12
        assert np.max(np.abs(out - _bilinear_twin(table, xg, yg, x, y))) < 1e-12
    for x, y in [(-5.0, 0.3), (7.0, 0.3), (0.5, -1.0), (0.5, 3.0), (-9.0, 9.0)]:
        bilinear(table, xg, yg, x, y, out)
        xc, yc = np.clip(x, xg[0], xg[-1]), np.clip(y, 0.0, 1.0)
        assert np.max(np.abs(out - rgi([xc, yc])[0])) < 1e-12
    bilinear(table, xg, yg, np.nan, 0.5, out)
    assert np.all(np.isnan(out))


def test_engine_controller_matches_twin(plant):
    tab = t41.engine_fault_tables(plant)
    rng = np.random.default_rng(5)
    u = np.empty(3)
    x = rng.normal(size=9)
    for i, j in [(0, 0), (4, 7), (10, 10)]:           # nodes: the table's own gains
        engine_controller(tab, tab.b0_grid[i], tab.b1_grid[j], x, u)
        ref = -tab.K[i, j] @ x - tab.k[i, j]
        assert np.max(np.abs(u - ref)) < 1e-13 * max(1.0, np.abs(ref).max())
    for _ in range(200):
        b0, b1 = rng.uniform(-0.1, 1.1), rng.uniform(-0.1, 1.1)
        x = rng.normal(size=9)
        engine_controller(tab, b0, b1, x, u)
        K = _bilinear_twin(tab.K, tab.b0_grid, tab.b1_grid, b0, b1)
        k = _bilinear_twin(tab.k, tab.b0_grid, tab.b1_grid, b0, b1)
        ref = -K @ x - k
        assert np.max(np.abs(u - ref)) < 1e-12 * max(1.0, np.abs(ref).max())
    # bilinear on the flattened K table agrees with the controller's interpolation
    out = np.empty(27)
    bilinear(tab.K.reshape(11, 11, 27), tab.b0_grid, tab.b1_grid, 0.37, 0.81, out)
    assert np.allclose(out.reshape(3, 9), _bilinear_twin(tab.K, tab.b0_grid, tab.b1_grid,
                                                         0.37, 0.81), rtol=0, atol=1e-14)


# ---------------------------------------------------------- elevon allocation
def test_elevon_allocation_constraint_and_min_norm():
    rng = np.random.default_rng(9)
    for trial in range(500):
        K2x = rng.normal() * 0.2
        b0e = rng.uniform(-1.0, 1.0)
        b1L, b1R = rng.uniform(0, 1, 2)
        if trial % 4 == 0:
            b1L = 1.0                                   # left elevon locked
        u0L, u0R = rng.uniform(-0.2, 0.2, 2)
        U2, U3 = elevon_allocation(K2x, b0e, b1L, b1R, u0L, u0R)
        phi = 2 * K2x + b0e + (1 - b1L) * U2 - b1L * u0L + (1 - b1R) * U3 - b1R * u0R
        assert abs(phi) < 1e-12                         # eq. 22: Phi = 0
        a = np.array([[1 - b1L, 1 - b1R]])
        c = 2 * K2x + b0e - b1L * u0L - b1R * u0R
        U_ls = np.linalg.lstsq(a, [-c], rcond=None)[0]   # minimum-norm solution
        assert np.allclose([U2, U3], U_ls, rtol=1e-12, atol=1e-12)
    # nominal: U2 = U3 = -K2 x
    assert elevon_allocation(0.123, 0.0, 0.0, 0.0, 0.06, 0.06) == (-0.123, -0.123)
    # both elevons dead: constraint infeasible, minimum-norm least squares is zero
    assert elevon_allocation(0.1, 0.2, 1.0, 1.0, 0.06, 0.06) == (0.0, 0.0)


def test_paper_eq25_as_printed_violates_constraint():
    """Eq. 25 prints U3 = -lambda (1 - b1^2): it breaks Phi = 0 for b1^2 != b1^3."""
    K2x, b0e, b1L, b1R, u0 = 0.1, 0.3, 1.0, 0.0, 0.06   # left elevon locked
    lam = (b0e - b1L * u0 - b1R * u0 + 2 * K2x) / ((1 - b1L) ** 2 + (1 - b1R) ** 2)
    U2p, U3p = -lam * (1 - b1L), -lam * (1 - b1L)
    phi = lambda U2, U3: (2 * K2x + b0e + (1 - b1L) * U2 - b1L * u0
                          + (1 - b1R) * U3 - b1R * u0)
    assert abs(phi(U2p, U3p)) > 0.1
    assert abs(phi(*elevon_allocation(K2x, b0e, b1L, b1R, u0, u0))) < 1e-15


# --------------------------------------------------------------------- cache
def test_cache_hit_and_key(plant, tmp_path, monkeypatch):
    grid_b0 = np.linspace(0.0, 1.0, 41)
    grid_b1 = np.linspace(0.0, 1.0, 41)
    t = time.perf_counter()
    cold = et.cached_engine_tables(plant, grid_b0, grid_b1, cache_dir=tmp_path)
    t_cold = time.perf_counter() - t
    files = list((tmp_path / "engine_tables").glob("*.npz"))
    assert len(files) == 1 and not list((tmp_path / "engine_tables").glob(".*tmp"))

    def boom(*a, **k):
        raise AssertionError("cache miss")

    monkeypatch.setattr(et, "engine_fault_tables", boom)
    t = time.perf_counter()
    hot = et.cached_engine_tables(plant, grid_b0, grid_b1, cache_dir=tmp_path)
    t_hot = time.perf_counter() - t
    for a, b in zip(cold, hot):
        assert np.array_equal(a, b)
    assert t_hot < t_cold / 3, (t_cold, t_hot)
    # the cached tables drive the kernel directly
    u = np.empty(3)
    engine_controller(hot, 0.5, 0.5, np.ones(9), u)
    assert np.all(np.isfinite(u))

    key = et.engine_tables_key(plant, grid_b0, grid_b1)
    assert files[0].stem == key
    Q0 = paper_q_lqr(plant.trim.gamma0)
    assert et.engine_tables_key(plant, grid_b0, grid_b1, Q0, 0.1 * np.eye(3), 0.999) == key
    changed = [
        et.engine_tables_key(plant, grid_b0[:-1], grid_b1),
        et.engine_tables_key(plant, grid_b0, grid_b1 * 0.99),
        et.engine_tables_key(plant, grid_b0, grid_b1, Q=2 * Q0),
        et.engine_tables_key(plant, grid_b0, grid_b1, R=0.2 * np.eye(3)),
        et.engine_tables_key(plant, grid_b0, grid_b1, alpha=0.99),
    ]
    for field in ("A", "B"):
        M = getattr(plant, field).copy()
        M[0, 0] += 1e-12
        changed.append(et.engine_tables_key(_Fake(plant, **{field: M}), grid_b0, grid_b1))
    changed.append(et.engine_tables_key(_Fake(plant, u0=plant.u0 + [1e-9, 0, 0]),
                                         grid_b0, grid_b1))
    assert len(set(changed + [key])) == len(changed) + 1


class _Fake:
    """A plant stand-in with one attribute replaced."""

    def __init__(self, plant, **over):
        self.A, self.B, self.u0, self.trim = plant.A, plant.B, plant.u0, plant.trim
        self.__dict__.update(over)


def test_cache_env_dir_and_corrupt_file(plant, tmp_path, monkeypatch):
    monkeypatch.setenv("FTC_MC_CACHE_DIR", str(tmp_path))
    assert store.default_cache_dir() == tmp_path / "design"
    tab = et.cached_engine_tables(plant)
    path = tmp_path / "design" / "engine_tables" / f"{et.engine_tables_key(plant)}.npz"
    assert path.exists()
    path.write_bytes(b"not an npz")
    again = et.cached_engine_tables(plant)          # recomputed and rewritten
    assert np.array_equal(again.k, tab.k)
    with np.load(path) as z:
        assert np.array_equal(z["K"], tab.K)


def test_bad_inputs(plant):
    with pytest.raises(ValueError, match="b1_grid"):
        t41.engine_fault_tables(plant, b1_grid=[0.0, 1.5])
    with pytest.raises(ValueError, match="b0_grid"):
        t41.engine_fault_tables(plant, b0_grid=[0.5, 0.2])
    with pytest.raises(ValueError, match="b1 = 1.0"):
        t41.engine_fault_tables(plant, alpha=1.0)
    with pytest.raises(ValueError, match="discount"):
        t41.biased_discounted_lqr(plant.A, plant.B, np.zeros(9), np.eye(9), R, 1.5)
