"""The lock-turn controller (ftc_mc/design/lock_turn.py):
design point, reduced linear model about the steady turn, discounted LQR."""

import math

import numpy as np
import pytest
import scipy.linalg

from ftc_mc.core.sixdof.layout import COMMAND, OUTPUT, STATE
from ftc_mc.design.lock_turn import DesignBox, lock_turn_lqr, turn_states
from ftc_mc.model.linear import jacobian
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import derivatives, outputs, trim6

AF = PRESETS["x8-pyfly"].airframe
TRIM = trim6(AF)


def lock_at(side, offset_deg):
    return TRIM.u0[COMMAND[side]] + math.radians(offset_deg)


@pytest.fixture(scope="module", params=[("left", 1.0), ("right", -4.0)])
def steady(request):
    side, off = request.param
    return lock_turn_lqr(AF, side, lock_at(side, off))


def test_the_design_point_is_a_steady_turn_in_the_box(steady):
    pt = steady.point
    assert pt.steady and pt.design_lock == pt.lock
    assert pt.x[STATE[pt.side]] == pt.lock == pt.cmd[COMMAND[pt.side]]
    d = derivatives(pt.x, pt.cmd, TRIM.params)
    rows = [STATE[n] for n in ("u", "v", "w", "p", "q", "r", "phi", "theta")]
    assert np.abs(d[rows]).max() < 1e-10
    # actuators at their commands, and it turns
    assert np.abs(d[[STATE[n] for n in ("throttle", "left", "right")]]).max() == 0.0
    v = pt.values
    assert abs(v["turn_rate"]) > math.radians(1.0)
    box = DesignBox()
    tol = 1e-9
    assert box.airspeed[0] - tol <= v["airspeed"] <= box.airspeed[1] + tol
    assert abs(v["phi"]) <= box.bank + tol
    assert box.throttle[0] - tol <= v["throttle"] <= box.throttle[1] + tol
    y = outputs(pt.x, TRIM.params)
    assert abs(y[OUTPUT["gamma"]] - v["gamma"]) < 1e-15
    assert abs(y[OUTPUT["Va"]] - v["airspeed"]) < 1e-12


def test_the_turn_states_see_neither_position_nor_heading(steady):
    """The reduced model is exact: no row of the fed-back states depends on the
    positions or the heading, which a steady turn changes."""
    pt = steady.point
    Jx = jacobian(lambda x: derivatives(x, pt.cmd, TRIM.params), pt.x)
    idx = steady.idx
    away = [STATE[n] for n in ("x", "y", "z", "psi")]
    assert np.abs(Jx[np.ix_(idx, away)]).max() < 1e-20  # finite differences of 0
    np.testing.assert_array_equal(Jx[np.ix_(idx, idx)], steady.Ac)
    assert steady.states == turn_states(pt.side) and len(steady.states) == 10


def test_the_gain_is_the_riccati_solution_and_stabilises(steady):
    d = steady
    sa = math.sqrt(d.alpha)
    P = scipy.linalg.solve_discrete_are(sa * d.A, sa * d.B, d.Q, d.R)
    K = np.linalg.solve(d.R + d.alpha * d.B.T @ P @ d.B, d.alpha * d.B.T @ P @ d.A)
    np.testing.assert_allclose(d.P, P, rtol=1e-9, atol=1e-9 * np.abs(P).max())
    np.testing.assert_allclose(d.K, K, rtol=1e-8, atol=1e-10)
    assert not d.F.any() and not d.k.any()
    assert np.max(np.abs(d.closed_loop)) < 0.99
    # the open loop is not (the Dutch roll)
    assert np.max(np.abs(np.linalg.eigvals(d.A))) > 1.0


def test_the_gain_matches_python_control(steady):
    control = pytest.importorskip("control")
    d = steady
    sa = math.sqrt(d.alpha)
    K, _, _ = control.dlqr(sa * d.A, sa * d.B, d.Q, d.R)
    np.testing.assert_allclose(d.K, K, rtol=1e-7, atol=1e-9)


def test_the_law_holds_the_design_point(steady):
    pt = steady.point
    np.testing.assert_allclose(steady.command(pt.x), pt.cmd, rtol=0, atol=1e-15)


def test_a_lock_with_no_steady_flight_designs_about_the_nearest_one():
    d = lock_turn_lqr(AF, "left", lock_at("left", 5.0))
    pt = d.point
    assert not pt.steady
    # x8-pyfly's edge is about +2.25 deg from trim in the whole envelope;
    # the design box leaves a little less
    assert 1.5 < pt.design_offset_deg < 2.3
    assert abs(pt.offset_deg - 5.0) < 1e-12
    assert np.abs(d.F).max() > 0 and np.abs(d.k).max() > 0
    assert np.max(np.abs(d.closed_loop)) < 1.0
    # the design point is steady with its own lock
    dd = derivatives(pt.x, pt.cmd, TRIM.params)
    assert np.abs(dd[[STATE[n] for n in ("u", "v", "w", "p", "q", "r")]]).max() < 1e-10
    assert pt.x[STATE["left"]] == pt.design_lock
    # the command holds the true lock on the dead elevon
    assert d.command(pt.x)[COMMAND["left"]] == pt.lock


# --- designs on the 6-DOF linear model (monitor.turn_model: linear) ---

@pytest.fixture(scope="module")
def linear_plant():
    from ftc_mc.model.sixdof import build_sixdof_plant

    return build_sixdof_plant(AF)


def test_on_the_linear_model_the_gain_is_its_own_lqr(linear_plant):
    """A design on the linear model flies its discrete matrices' rows and
    columns of the fed-back states, with python-control's discounted LQR on
    them (as the paper's controllers are designed on eq. 1's model); a steady
    lock has no constant term, and the law holds the design point."""
    control = pytest.importorskip("control")
    pl = linear_plant
    d = lock_turn_lqr(AF, "right", lock_at("right", 3.0), plant=pl)
    assert d.point.steady
    idx, inputs = d.idx, list(d.inputs)
    np.testing.assert_array_equal(d.A, pl.A[np.ix_(idx, idx)])
    np.testing.assert_array_equal(d.B, pl.B[np.ix_(idx, inputs)])
    sa = math.sqrt(d.alpha)
    K, _, _ = control.dlqr(sa * d.A, sa * d.B, d.Q, d.R)
    np.testing.assert_allclose(d.K, K, rtol=1e-7, atol=1e-9)
    assert not d.F.any() and not d.k.any()
    assert np.max(np.abs(d.closed_loop)) < 0.99
    np.testing.assert_allclose(d.command(d.point.x), d.point.cmd, rtol=0, atol=1e-15)
    # one step of the linear plant from the design point leaves it there
    dx, du = d.point.x - pl.trim.x0, d.point.cmd - pl.u0
    step = pl.A @ dx + pl.B @ du - dx
    assert np.abs(step[idx]).max() < 1e-12


def test_on_the_linear_model_a_far_lock_designs_about_its_nearest(linear_plant):
    """-6 deg has no steady flight of the linear model in the design box (its
    steady flights end near -3.5 deg on the left, docs/findings/sixdof-lock-turn.md): the
    design is about the nearest lock that has one, and the held offset
    enters as the plant's own constant input, its actuator's column and its
    command's."""
    pl = linear_plant
    d = lock_turn_lqr(AF, "left", lock_at("left", -6.0), plant=pl)
    pt = d.point
    assert not pt.steady and -4.0 < pt.design_offset_deg < -3.0
    locked = STATE["left"]
    F = (pl.A[d.idx, locked] + pl.B[d.idx, COMMAND["left"]]) * (pt.lock - pt.design_lock)
    np.testing.assert_array_equal(d.F, F)
    assert np.abs(d.k).max() > 0
    assert d.command(pt.x)[COMMAND["left"]] == pt.lock
