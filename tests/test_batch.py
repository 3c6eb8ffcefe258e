"""The lane-interleaved kernels of :mod:`ftc_mc.core.longitudinal.batch` against the
single-trajectory kernels, lane by lane.

The batch kernels perform each lane's floating-point operations in the single
kernels' order, so the expected agreement is exact; the assertions allow the
1e-10 relative (Frobenius / Euclidean) tolerance of the specification, and
require the reset blocks to agree exactly and every ``P`` to be exactly
symmetric.  Lane counts are not multiples of the vector width (8), so the
vector loops' remainders are exercised too.
"""

from __future__ import annotations

import numpy as np
import pytest

from lane_workspace import LaneWorkspace, new_lane_workspace
from ftc_mc.core.longitudinal import batch as kb
import single_trajectory as kk
import naive
from ftc_mc.conventions import TABLE1
from ftc_mc.core.longitudinal import signature as ks
from single_trajectory import Workspace, filter_step
from ftc_mc.sim.estimator import (EstimatorSettings, detection, filter_model,
                                  initial_covariance, unit_rows)
from ftc_mc.model.linear import build_plant

TOL = 1e-10


@pytest.fixture(scope="module")
def plant():
    return build_plant()


def rel_err(a, b):
    scale = np.linalg.norm(b)
    return np.linalg.norm(np.asarray(a) - np.asarray(b)) / (scale if scale > 0 else 1.0)


def random_spd(rng, n=14):
    """SPD covariance with standard deviations over two decades, random correlations."""
    G = rng.standard_normal((n, n))
    C = G @ G.T + n * np.eye(n)
    d = 1.0 / np.sqrt(np.diag(C))
    sd = 10.0 ** rng.uniform(-3.0, -1.0, n)
    return (C * d[:, None] * d[None, :]) * sd[:, None] * sd[None, :]


def lanes_of(mats):
    """Stack per-lane arrays along a new last axis (C-contiguous)."""
    return np.ascontiguousarray(np.stack(mats, axis=-1))


def simulate(plant, fm, rng, n_steps, L, noise_scale):
    """Commands and measurements of ``L`` nominal-plant trajectories.

    Returns ``U`` (n_steps, 3, L) and ``Z`` (n_steps, 12, L); lane ``l``'s
    measurement noise is ``noise_scale[l]`` times the filter's R.
    """
    sq = np.sqrt(fm.q_diag[:9])[:, None]
    sr = np.sqrt(fm.r_diag)[:, None] * noise_scale[None, :]
    x = np.zeros((9, L))
    U = np.empty((n_steps, 3, L))
    Z = np.empty((n_steps, 12, L))
    for k in range(n_steps):
        U[k] = rng.normal(0.0, 0.08, (3, L))
        x = plant.A @ x + plant.B @ U[k] + sq * rng.standard_normal((9, L))
        Z[k] = plant.C @ x + sr * rng.standard_normal((12, L))
    return U, Z


# ------------------------------------------------------------------ full step
@pytest.mark.parametrize("variant", ["paper", "swapped"])
def test_filter_step_lanes_matches_single(plant, variant):
    """Chained steps of 21 lanes: some lanes' measurements are noisy enough to
    fire Table 1 often (with low thresholds), fault parameters start out of
    bounds (projection active), and each lane follows ``filter_step`` exactly:
    same blocks, same residuals, states and covariances to 1e-10."""
    s = EstimatorSettings(t_q=4.0, t_nx=4.0, signature=variant)
    fm, det = filter_model(plant, s), detection(plant, s)
    assert det.swapped == (1 if variant == "swapped" else 0)
    L, n_steps = 21, 120
    rng = np.random.default_rng(11)
    scale = np.where(np.arange(L) % 3 == 0, 4.0, 1.0)
    U, Z = simulate(plant, fm, rng, n_steps, L, scale)
    P0 = initial_covariance(fm, det)
    X0 = np.zeros((14, L))
    X0[9:] = rng.uniform(-2.0, 2.0, (5, L))  # mostly outside [lo, hi]
    xa, P = X0.copy(), lanes_of([P0] * L)
    ws = new_lane_workspace(L)

    singles = [(X0[:, l].copy(), P0.copy(), Workspace()) for l in range(L)]
    n_fired = []
    projected = 0
    for k in range(n_steps):
        kb.filter_step_lanes(xa, P, U[k], Z[k], fm, det, *ws)
        n_fired.append(int(np.count_nonzero(ws.block)))
        for l, (x1, P1, w) in enumerate(singles):
            blk = filter_step(x1, P1, np.ascontiguousarray(U[k, :, l]),
                              np.ascontiguousarray(Z[k, :, l]), fm, det, w.phi, w.T,
                              w.h, w.res, w.x_prev, w.P_prev)
            assert ws.block[l] == blk, (k, l)
            assert rel_err(ws.res[:, l], w.res) <= TOL, (k, l)
            assert rel_err(xa[:, l], x1) <= TOL, (k, l)
            assert rel_err(P[:, :, l], P1) <= TOL, (k, l)
            projected += int(np.any(x1[9:] == fm.lo) or np.any(x1[9:] == fm.hi))
        assert all(np.array_equal(P[:, :, l], P[:, :, l].T) for l in range(L)), k
    n_fired = np.array(n_fired)
    # both re-prediction paths ran: a few resets (run by run) and many (all lanes)
    assert np.any((n_fired > 0) & (n_fired <= kb.SERIAL_REPREDICT))
    assert np.any(n_fired > kb.SERIAL_REPREDICT)
    assert set(np.unique(ws.block)) <= {0, 1, 2}
    assert projected > 0


def test_filter_step_lanes_one_lane(plant):
    """``L = 1`` (no vector loop at all) runs and matches the single step."""
    s = EstimatorSettings(t_q=2.0, t_nx=2.0)
    fm, det = filter_model(plant, s), detection(plant, s)
    rng = np.random.default_rng(3)
    U, Z = simulate(plant, fm, rng, 40, 1, np.array([3.0]))
    P0 = initial_covariance(fm, det)
    xa, P = np.zeros((14, 1)), lanes_of([P0])
    x1, P1, w = np.zeros(14), P0.copy(), Workspace()
    ws = new_lane_workspace(1)
    fired = 0
    for k in range(40):
        kb.filter_step_lanes(xa, P, U[k], Z[k], fm, det, *ws)
        blk = filter_step(x1, P1, U[k, :, 0].copy(), Z[k, :, 0].copy(), fm, det, w.phi,
                          w.T, w.h, w.res, w.x_prev, w.P_prev)
        assert ws.block[0] == blk
        fired += blk != 0
        assert rel_err(xa[:, 0], x1) <= TOL
        assert rel_err(P[:, :, 0], P1) <= TOL
    assert fired > 0


# ------------------------------------------------------------------ kernels
def test_predict_lanes(plant):
    fm = filter_model(plant, EstimatorSettings())
    rng = np.random.default_rng(5)
    L = 13
    X = rng.normal(0.0, 0.3, (14, L))
    Ps = [random_spd(rng) for _ in range(L)]
    u = rng.normal(0.0, 0.3, (3, L))
    xa, P = X.copy(), lanes_of(Ps)
    phi, T = np.zeros((9, 5, L)), np.zeros((9, 14, L))
    kb.predict_lanes(xa, P, u, fm, phi, T)
    for l in range(L):
        x1, P1 = X[:, l].copy(), Ps[l].copy()
        phi1 = np.zeros((9, 5))
        kk.predict(x1, P1, u[:, l].copy(), fm, phi1, np.zeros((9, 14)))
        assert rel_err(xa[:, l], x1) <= TOL
        assert rel_err(P[:, :, l], P1) <= TOL
        assert rel_err(phi[:, :, l], phi1) <= TOL
        assert np.array_equal(P[:, :, l], P[:, :, l].T)


def test_residuals_lanes(plant):
    fm = filter_model(plant, EstimatorSettings())
    rng = np.random.default_rng(6)
    L = 10
    X = rng.normal(0.0, 0.3, (14, L))
    Ps = [random_spd(rng) for _ in range(L)]
    z = rng.normal(0.0, 0.3, (12, L))
    res = np.zeros((3, L))
    innov = np.zeros((3, L))
    kb.residuals_lanes(X, lanes_of(Ps), z, fm, res)
    kb.innovations_lanes(X, lanes_of(Ps), z, fm, innov)
    for l in range(L):
        out = np.zeros(3)
        kk.residuals(X[:, l].copy(), Ps[l], z[:, l].copy(), fm, out)
        assert rel_err(res[:, l], out) <= TOL
        # the signed innovation squares to the residual (eqs. 9-11)
        assert rel_err(innov[:, l] ** 2, out) <= 1e-13


@pytest.mark.parametrize("swapped", [0, 1])
def test_signature_lanes(plant, swapped):
    """Every clause of Table 1, including residuals exactly at the thresholds
    and ``r_nz == r_nx``."""
    det = detection(plant, EstimatorSettings())._replace(t_q=25.0, t_nx=9.0,
                                                         swapped=swapped)
    grid = np.array([0.0, 5.0, 9.0, 10.0, 25.0, 30.0])
    rq, rnx, rnz = np.meshgrid(grid, grid, grid, indexing="ij")
    res = np.ascontiguousarray(np.stack([rq.ravel(), rnx.ravel(), rnz.ravel()]))
    block = np.full(res.shape[1], -7, dtype=np.int64)
    ks.signature_lanes(res, det, block)
    # Table 1 written clause by clause (tests/naive.py), not the decision table
    variant = "swapped" if swapped else "paper"
    expect = [naive.signature_ref(res[0, l], res[1, l], res[2, l], det.t_q, det.t_nx,
                                  variant) for l in range(res.shape[1])]
    assert np.array_equal(block, expect)
    assert set(np.unique(block)) == {0, 1, 2}
    # the decision table is the family's data: the variant's rows, nothing else
    assert np.array_equal(det.table, np.array(TABLE1[variant])) and det.swapped == swapped


def test_reset_lanes(plant):
    det = detection(plant, EstimatorSettings())
    rng = np.random.default_rng(8)
    blocks = np.array([0, 1, 2, 2, 1, 0, 3, 2, 1], dtype=np.int64)
    Ps = [random_spd(rng) for _ in blocks]
    P = lanes_of(Ps)
    kb.reset_lanes(P, blocks, det.reset_var)
    for l, b in enumerate(blocks):
        P1 = Ps[l].copy()
        kk.reset_covariance(P1, int(b), det.reset_var)
        assert np.array_equal(P[:, :, l], P1)


def update_against_single(fm, rng, L=11):
    X = rng.normal(0.0, 0.3, (14, L))
    Ps = [random_spd(rng) for _ in range(L)]
    z = rng.normal(0.0, 0.3, (12, L))
    xa, P = X.copy(), lanes_of(Ps)
    kb.update_lanes(xa, P, z, fm, np.zeros((kb.UPDATE_ROWS, 14, L)))
    for l in range(L):
        x1, P1 = X[:, l].copy(), Ps[l].copy()
        kk.update(x1, P1, z[:, l].copy(), fm, np.zeros(14))
        assert rel_err(xa[:, l], x1) <= TOL
        assert rel_err(P[:, :, l], P1) <= TOL
        assert np.array_equal(P[:, :, l], P[:, :, l].T)


def test_update_lanes(plant):
    fm = filter_model(plant, EstimatorSettings())
    assert list(fm.c_ident[:6]) == list(range(6)) and np.all(fm.c_ident[6:] < 0)
    update_against_single(fm, np.random.default_rng(9))


@pytest.mark.parametrize("pattern", ["interleaved", "seven_unit", "no_unit"])
def test_update_lanes_other_unit_rows(plant, pattern):
    """Unit rows of ``C`` anywhere, more than a group of them, or none."""
    C = np.array(plant.C, dtype=float)
    eye = np.eye(9)
    if pattern == "interleaved":  # unit rows 1, 3, 4, 5, 7, 9, 10 (two runs of 3)
        C = C[[6, 1, 7, 8, 4, 0, 10, 2, 11, 5, 3, 9]]
        C[3] = eye[8]
        C[9] = eye[2]
    elif pattern == "seven_unit":  # rows 0..6 unit, the seventh repeats state 2
        C[6] = eye[2]
    else:
        C[:6] += 0.01
    fm = filter_model(plant, EstimatorSettings())._replace(
        C=np.ascontiguousarray(C), c_ident=unit_rows(C))
    n_unit = int(np.sum(fm.c_ident >= 0))
    assert n_unit == {"interleaved": 7, "seven_unit": 7, "no_unit": 0}[pattern]
    update_against_single(fm, np.random.default_rng(10))


def test_project_lanes(plant):
    fm = filter_model(plant, EstimatorSettings())
    rng = np.random.default_rng(12)
    L = 19
    X = rng.normal(0.0, 1.5, (14, L))
    X[9:, 0] = fm.lo  # exactly on the bounds
    X[9:, 1] = fm.hi
    xa = X.copy()
    kb.project_lanes(xa, fm)
    for l in range(L):
        x1 = X[:, l].copy()
        kk.project(x1, fm)
        assert np.array_equal(xa[:, l], x1)
    assert np.any(xa[9:] != X[9:])


# ------------------------------------------------------------------ workspace
def test_new_lane_workspace():
    ws = new_lane_workspace(5)
    assert isinstance(ws, LaneWorkspace)
    assert ws.phi.shape == (9, 5, 5) and ws.T.shape == (9, 14, 5)
    assert ws.work.shape == (kb.STEP_ROWS, 14, 5)
    assert ws.res.shape == (3, 5) and ws.block.shape == (5,)
    assert ws.block.dtype == np.int64
    assert all(a.flags.c_contiguous for a in ws)
    for bad in (0, -3, 2.0, True, "8"):
        with pytest.raises(ValueError, match="lane count"):
            new_lane_workspace(bad)
