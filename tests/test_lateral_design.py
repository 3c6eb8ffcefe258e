"""The lateral loop of the 6-DOF X8 (offline design): wings
level and heading hold by the discounted LQR on the 6-DOF linear model."""

import math

import numpy as np
import pytest

from ftc_mc.core.sixdof import plant as kernels
from ftc_mc.core.sixdof.layout import COMMAND, N_STATE, N_WIND, OUTPUT, STATE
from ftc_mc.design.lateral import (LATERAL_STATES, aileron_column, lateral_lqr,
                                   longitudinal_gain_on_sixdof)
from ftc_mc.design.lqr import discounted_lqr, paper_q_lqr
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import build_sixdof_plant, outputs
from ftc_mc.model.source import load_plant


@pytest.fixture(scope="module", params=list(PRESETS))
def loops(request):
    name = request.param
    plant = build_sixdof_plant(PRESETS[name].airframe)
    lat = lateral_lqr(plant)
    lon = load_plant(name, 20.0, -3.0, 0.1)
    K_lon, _ = discounted_lqr(lon.A, lon.B, paper_q_lqr(lon.trim.gamma0),
                              0.1 * np.eye(3), 0.999)
    return plant, lat, longitudinal_gain_on_sixdof(K_lon) + lat.K_full


def test_lateral_loop_stabilises_the_dutch_roll(loops):
    plant, lat, _ = loops
    # open loop: the Dutch roll is outside the unit circle (+0.30 1/s)
    assert np.max(np.abs(lat.open_loop)) > 1.02
    assert np.max(np.abs(lat.closed_loop)) < 0.99
    # the law is differential: equal and opposite on the two elevons
    np.testing.assert_array_equal(lat.K_full[COMMAND["left"]], -lat.K_full[COMMAND["right"]])
    assert not lat.K_full[COMMAND["throttle"]].any()


def test_both_loops_together_on_the_full_model(loops):
    # with the paper's longitudinal LQR: every eigenvalue strictly inside the
    # unit circle but one, the cross-track integrator (heading hold, not track
    # hold); the Dutch roll pair is stable
    plant, _, K = loops
    ev, vec = np.linalg.eig(plant.A - plant.B @ K)
    outside = np.abs(ev) >= 1 - 1e-9
    assert outside.sum() == 1
    v = np.abs(vec[:, np.argmax(np.abs(ev))])
    assert np.argmax(v) == STATE["y"]
    lam = np.log(ev[~outside].astype(complex)) / plant.dt
    osc = lam[np.abs(lam.imag) > 2.5]  # the Dutch roll is near 3.3-3.5 rad/s
    assert len(osc) >= 2 and np.all(osc.real < -0.5)


def fly(plant, K, x0, seconds, wind=None):
    """The nonlinear 6-DOF plant under ``u = u0 - K (x - x0_trim)``, commands
    clipped to the limits; returns the states at each period."""
    tp = plant.trim
    x = x0.copy()
    work = np.zeros((kernels.N_WORK, N_STATE))
    w = np.zeros(N_WIND) if wind is None else wind
    out = [x.copy()]
    for _ in range(int(round(seconds / plant.dt))):
        u = np.clip(tp.u0 - K @ (x - tp.x0), plant.u_lower, plant.u_upper)
        kernels.propagate(x, u, tp.params, w, plant.dt, 10, work)
        out.append(x.copy())
    return np.array(out)


def test_nonlinear_plant_levels_its_wings_and_holds_heading(loops):
    plant, lat, K = loops
    tp = plant.trim
    x0 = tp.x0.copy()
    x0[STATE["phi"]] += math.radians(15.0)
    x0[STATE["psi"]] += math.radians(10.0)
    traj = fly(plant, K, x0, 30.0)
    phi = traj[:, STATE["phi"]] - tp.x0[STATE["phi"]]
    psi = traj[:, STATE["psi"]] - tp.x0[STATE["psi"]]
    assert np.all(np.isfinite(traj))
    assert np.max(np.abs(phi[-50:])) < math.radians(0.2)
    assert np.max(np.abs(psi[-50:])) < math.radians(0.5)
    # without the lateral loop the same start departs (unstable Dutch roll)
    lon_only = K - lat.K_full
    free = fly(plant, lon_only, x0, 30.0)
    assert np.all(np.isfinite(free))
    beta = [outputs(s, tp.params)[OUTPUT["beta"]] for s in free]
    assert max(abs(b) for b in beta) > math.radians(5.0)


def test_lateral_model_is_the_named_states():
    plant = build_sixdof_plant(PRESETS["x8-gryte2018"].airframe)
    lat = lateral_lqr(plant)
    idx = [STATE[n] for n in LATERAL_STATES]
    np.testing.assert_array_equal(lat.A_lat, plant.A[np.ix_(idx, idx)])
    np.testing.assert_array_equal(lat.B_lat[:, 0], aileron_column(plant.B)[idx])
    # at the symmetric trim the lateral rows do not see the longitudinal states
    lon = [STATE[n] for n in ("u", "w", "q", "theta")]
    assert np.max(np.abs(plant.A[np.ix_(idx[:5], lon)])) < 1e-9


# ------------------------------------------------------------------ coupled c0
def paper_c0(name):
    """The paper's c0 on ``name``'s longitudinal model: ``(K0, Q, R)``, and the model."""
    lon = load_plant(name, 20.0, -3.0, 0.1)
    Q, R = paper_q_lqr(lon.trim.gamma0), 0.1 * np.eye(3)
    K0, _ = discounted_lqr(lon.A, lon.B, Q, R, 0.999)
    return (K0, Q, R), lon


def decoupled_model(plant, lon):
    """A 6-DOF model whose two motions do not act on each other: the
    longitudinal model (by name) on its 9 states, the 6-DOF model's lateral
    rows reading only the lateral states and the elevons' half difference."""
    from types import SimpleNamespace

    from ftc_mc.conventions import STATE_NAMES
    from ftc_mc.core.sixdof.layout import sixdof_name

    six = [STATE[sixdof_name(n)] for n in STATE_NAMES]
    rows = [STATE[n] for n in ("phi", "v", "p", "r", "psi", "y")]
    L, Rt = STATE["left"], STATE["right"]
    A = np.zeros_like(plant.A)
    B = np.zeros_like(plant.B)
    A[np.ix_(six, six)] = lon.A
    B[six] = lon.B
    A[np.ix_(rows, rows)] = plant.A[np.ix_(rows, rows)]
    half = (plant.A[rows, L] - plant.A[rows, Rt]) / 2
    A[rows, L], A[rows, Rt] = half, -half
    half = (plant.B[rows, COMMAND["left"]] - plant.B[rows, COMMAND["right"]]) / 2
    B[rows, COMMAND["left"]], B[rows, COMMAND["right"]] = half, -half
    return SimpleNamespace(A=A, B=B, u0=lon.u0)


@pytest.mark.parametrize("name", list(PRESETS))
def test_coupled_c0_is_the_separate_pair_on_a_decoupled_model(name):
    """The coupled LQR's cost is the sum of the two loops' costs, so on a
    model where the motions do not act on each other its gain is the pair of
    separate gains (the paper's c0 by name plus the lateral LQR designed on
    the same model), and so is its cost-to-go."""
    from ftc_mc.design.lateral import coupled_lqr

    (K0, Q, R), lon = paper_c0(name)
    model = decoupled_model(build_sixdof_plant(PRESETS[name].airframe), lon)
    lat = lateral_lqr(model)
    d = coupled_lqr(model, K0, Q, R, 0.999, lat)
    np.testing.assert_allclose(d.K, d.K_separate, rtol=0, atol=1e-7 * np.abs(d.K).max())
    np.testing.assert_allclose(d.P, d.P_separate, rtol=0, atol=1e-7 * np.abs(d.P).max())


def test_coupled_c0_against_python_control():
    """The discounted LQR of the summed weights on the 6-DOF model against
    python-control's ``dlqr`` of ``(sqrt(alpha) A, sqrt(alpha) B)`` (eq. 43)."""
    control = pytest.importorskip("control")
    from ftc_mc.design.lateral import coupled_lqr

    (K0, Q, R), _ = paper_c0("x8-pyfly")
    plant = build_sixdof_plant(PRESETS["x8-pyfly"].airframe)
    d = coupled_lqr(plant, K0, Q, R, 0.999, lateral_lqr(plant))
    sa = math.sqrt(0.999)
    K, P, _ = control.dlqr(sa * plant.A, sa * plant.B, d.Q, d.R)
    np.testing.assert_allclose(d.K, K, rtol=0, atol=1e-6 * np.abs(K).max())
    np.testing.assert_allclose(d.P, P, rtol=0, atol=1e-6 * np.abs(P).max())


@pytest.mark.parametrize("name", list(PRESETS))
def test_coupled_c0_costs_no_more_than_the_separate_loops(name):
    """Optimality: from every initial state the coupled law's discounted cost
    on the 6-DOF model is at most the separate loops' (``P_separate - P``
    positive semi-definite). On ``x8-pyfly`` the propeller's torque couples
    the motions and the throttle joins the roll control, so it is strictly
    lower there; the cross-track position is in no cost and gets no gain."""
    from ftc_mc.design.lateral import coupled_lqr

    (K0, Q, R), _ = paper_c0(name)
    plant = build_sixdof_plant(PRESETS[name].airframe)
    d = coupled_lqr(plant, K0, Q, R, 0.999, lateral_lqr(plant))
    gap = np.linalg.eigvalsh((d.P_separate - d.P + (d.P_separate - d.P).T) / 2)
    scale = np.abs(d.P).max()
    assert gap.min() > -1e-9 * scale, gap.min()
    assert np.abs(d.K[:, STATE["y"]]).max() < 1e-9 * np.abs(d.K).max()
    if name == "x8-pyfly":
        assert gap.max() > 1e-3 * scale, gap.max()
        assert abs(d.K[COMMAND["throttle"], STATE["phi"]]) > 0.5  # throttle on bank [1/rad]


def test_kernel_gain_is_the_coupled_law_on_the_kernel_s_inputs():
    """``sim.truth.kernel_gain``: the paper's ``-K0 xhat`` plus the kernel's
    ``-G [xhat, lat]`` is ``-K x`` on the 6-DOF state assembled by name from
    the estimate (longitudinal states, the elevons' mean) and the lateral
    loop's state (bank, side velocity, rates, heading, the elevons' half
    difference)."""
    from ftc_mc.conventions import STATE_NAMES
    from ftc_mc.core.sixdof.layout import sixdof_name
    from ftc_mc.core.sixdof.truth import LATERAL_LOOP
    from ftc_mc.design.lateral import coupled_lqr
    from ftc_mc.sim.truth import kernel_gain

    (K0, Q, R), _ = paper_c0("x8-pyfly")
    plant = build_sixdof_plant(PRESETS["x8-pyfly"].airframe)
    d = coupled_lqr(plant, K0, Q, R, 0.999, lateral_lqr(plant))
    G = kernel_gain(d.K, K0)
    rng = np.random.default_rng(5)
    for _ in range(5):
        xhat, lat = rng.standard_normal(len(STATE_NAMES)), rng.standard_normal(len(LATERAL_LOOP))
        x = np.zeros(N_STATE)
        for j, n in enumerate(STATE_NAMES):
            x[STATE[sixdof_name(n)]] = xhat[j]
        for j, n in enumerate(LATERAL_LOOP[:5]):
            x[STATE[n]] = lat[j]
        left, right = STATE_NAMES.index("elevon_left"), STATE_NAMES.index("elevon_right")
        mean = (xhat[left] + xhat[right]) / 2
        diff = (lat[LATERAL_LOOP.index("left")] - lat[LATERAL_LOOP.index("right")]) / 2
        x[STATE["left"]], x[STATE["right"]] = mean + diff, mean - diff
        np.testing.assert_allclose(-K0 @ xhat - G @ np.concatenate([xhat, lat]), -d.K @ x,
                                   rtol=0, atol=1e-12 * np.abs(d.K).max() * np.abs(x).max() * 30)


@pytest.mark.parametrize("name", list(PRESETS))
def test_coupled_c1_is_the_paper_s_c1_and_the_lateral_loop_on_a_decoupled_model(name):
    """c1's Theorem 4.1 tables on the 6-DOF model (``coupled_engine_tables``):
    on a model whose motions do not act on each other, every node's gain is
    the paper's c1 gain (``engine_fault_tables`` of the longitudinal model) by
    name plus the lateral LQR, and its affine term is the paper's (a stuck
    throttle then moves nothing lateral)."""
    from ftc_mc.design.lateral import coupled_engine_tables, coupled_lqr
    from ftc_mc.design.theorem41 import engine_fault_tables

    (K0, Q, R), lon = paper_c0(name)
    model = decoupled_model(build_sixdof_plant(PRESETS[name].airframe), lon)
    lat = lateral_lqr(model)
    d = coupled_lqr(model, K0, Q, R, 0.999, lat)
    grid0, grid1 = np.linspace(0.0, 1.0, 3), np.array([0.0, 0.5, 1.0])
    t6 = coupled_engine_tables(model, d, grid0, grid1)
    t3 = engine_fault_tables(lon, grid0, grid1, Q, R, 0.999)
    for i in range(grid0.size):
        for j in range(grid1.size):
            want = longitudinal_gain_on_sixdof(t3.K[i, j]) + lat.K_full
            np.testing.assert_allclose(t6.K[i, j], want, rtol=0,
                                       atol=1e-6 * np.abs(want).max(), err_msg=(i, j))
            np.testing.assert_allclose(t6.k[i, j], t3.k[i, j], rtol=0,
                                       atol=1e-6 * np.abs(t3.k).max() + 1e-12, err_msg=(i, j))


def test_coupled_c1_holds_the_stuck_throttle_s_torque():
    """On ``x8-pyfly`` the propeller's torque rolls the wing: a throttle stuck
    at full power needs a steady aileron, which the 6-DOF c1's affine term
    holds and the paper's (longitudinal) c1 cannot; a throttle stuck at its
    6-DOF trim needs none (the locked-engine column, ``b1 = 1``)."""
    from ftc_mc.design.lateral import coupled_engine_tables, coupled_lqr

    (K0, Q, R), _ = paper_c0("x8-pyfly")
    plant = build_sixdof_plant(PRESETS["x8-pyfly"].airframe)
    d = coupled_lqr(plant, K0, Q, R, 0.999, lateral_lqr(plant))
    grid0 = np.array([plant.u0[COMMAND["throttle"]], 1.0])
    t6 = coupled_engine_tables(plant, d, grid0, np.array([1.0]))
    aileron = lambda k: (k[COMMAND["left"]] - k[COMMAND["right"]]) / 2  # noqa: E731
    assert abs(aileron(t6.k[0, 0])) < 1e-9
    assert abs(aileron(t6.k[1, 0])) > math.radians(0.01), math.degrees(aileron(t6.k[1, 0]))
