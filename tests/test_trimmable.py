"""Steady flight with one elevon locked (ftc_mc/model/trimmable.py).

Reference: the project's held-out trim analysis of the authors' equations
(DESIGN.md section 11): at 20 m/s and -3 deg a lock 5 deg above
trim admits no steady flight, straight or turning, and steady no-rudder turns
keep the locked elevon within about +0.4 to +0.6 deg of trim."""

import math

import numpy as np
import pytest

from ftc_mc.core.sixdof.layout import OUTPUT, STATE
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import derivatives, pack_parameters, trim6
from ftc_mc.model.trimmable import _state, steady_flight, trimmable_set

AF = PRESETS["x8-pyfly"].airframe


def test_the_trim_is_steady_and_a_far_lock_is_not():
    at_trim, far = trimmable_set(AF, "left", [0.0, 10.0], starts=4)
    assert at_trim.steady and abs(at_trim.offset) < 1e-12
    assert not far.steady and far.residual > 1e-3


def test_a_steady_turn_is_an_equilibrium_of_the_equations():
    """The solution found 1 deg above trim, put back into the 6-DOF equations:
    every body acceleration vanishes, it turns, and it stays in the envelope."""
    f = steady_flight(AF, "left", trim6(AF).u0[1] + math.radians(1.0), starts=8)
    assert f.steady
    v = f.values
    x, cmd = _state([v[k] for k in ("airspeed", "alpha", "beta", "phi", "theta",
                                    "turn_rate", "throttle", "free_elevon")], "left", f.lock)
    p = pack_parameters(AF, 20.0, math.radians(-3.0))
    d = derivatives(x, cmd, p)
    rows = [STATE[n] for n in ("u", "v", "w", "p", "q", "r")]
    assert np.abs(d[rows]).max() < 1e-8
    assert abs(v["turn_rate"]) > math.radians(1.0) and abs(v["phi"]) <= math.radians(60)
    assert 12.0 <= v["airspeed"] <= 30.0


@pytest.mark.parametrize("offset_deg, steady", [(0.5, True), (5.0, False)])
def test_at_20_mps_and_minus_3_deg_as_the_held_out_analysis(offset_deg, steady):
    f = steady_flight(AF, "left", trim6(AF).u0[1] + math.radians(offset_deg), V0=20.0,
                      gamma0_deg=-3.0, starts=8)
    assert f.steady == steady, f
    if steady:
        assert abs(f.values["airspeed"] - 20.0) < 1e-12
        assert abs(f.values["gamma"] - math.radians(-3.0)) < 1e-8


# --- the 6-DOF linear model's steady flights (the linear plant's own) ---

PLANT = None


def linear_plant():
    global PLANT
    if PLANT is None:
        from ftc_mc.model.sixdof import build_sixdof_plant

        PLANT = build_sixdof_plant(AF)
    return PLANT


def test_a_linear_steady_flight_is_an_equilibrium_of_the_continuous_model():
    """The lock-turn design point on the linear model with the left elevon
    4 deg above trim (:func:`ftc_mc.design.lock_turn.design_point`), put back
    into the linear model before its zero-order hold (``Ac``, ``Bc``, which
    :func:`linear_steady` does not read): the rigid-body states and the
    actuators do not move, the dead elevon sits at its lock, and it turns,
    banked, inside the design box."""
    from ftc_mc.core.sixdof.layout import COMMAND
    from ftc_mc.design.lock_turn import DesignBox, design_point

    pl = linear_plant()
    lock = pl.u0[COMMAND["left"]] + math.radians(4.0)
    pt = design_point(AF, "left", lock, plant=pl)
    assert pt.steady
    dx, du = pt.x - pl.trim.x0, pt.cmd - pl.u0
    assert pt.cmd[COMMAND["left"]] == lock
    rows = [STATE[n] for n in ("phi", "theta", "u", "v", "w", "p", "q", "r",
                               "throttle", "left", "right")]
    assert np.abs((pl.Ac @ dx + pl.Bc @ du)[rows]).max() < 1e-9
    box, v = DesignBox(), pt.values
    assert math.radians(20.0) < abs(v["phi"]) <= box.bank + 1e-9
    assert box.airspeed[0] - 1e-9 <= v["airspeed"] <= box.airspeed[1] + 1e-9
    assert abs(v["turn_rate"]) > 0.01
    assert abs(v["airspeed"] - (pl.trim.y0[OUTPUT["Va"]] + pl.C[OUTPUT["Va"]] @ dx)) < 1e-12


@pytest.mark.parametrize("offset_deg", [-6.0, -3.0, 0.0, 4.0, 7.0, -8.0])
def test_the_linear_trimmable_set_agrees_with_a_search_of_its_plane(offset_deg):
    """:func:`linear_steady_flight` (a linear programme) against a plain
    search: the steady flights form a plane, on which airspeed and bank are
    coordinates; solving the steady conditions for each point of a grid of
    them (12-30 m/s by 0.05, +-60 deg by 0.25) finds one inside the envelope
    and the limits exactly where the programme does.  The linear model is
    narrower than the airframe's equations, which have steady turns from -29
    to +2.25 deg (docs/findings/sixdof-survival.md): at -6 and -8 deg neither finds one."""
    from ftc_mc.core.sixdof.layout import COMMAND
    from ftc_mc.model.trimmable import linear_quantities, linear_steady, linear_steady_flight

    pl = linear_plant()
    lock = pl.u0[COMMAND["left"]] + math.radians(offset_deg)
    s = linear_steady(pl, "left", lock)
    q = linear_quantities(pl, s)
    square = np.vstack([s.M, q["Va"][1], q["phi"][1]])
    va, bank = np.meshgrid(np.arange(12.0, 30.0 + 1e-9, 0.05),
                           np.radians(np.arange(-60.0, 60.0 + 1e-9, 0.25)))
    rhs = np.vstack([np.repeat(-s.c[:, None], va.size, axis=1),
                     va.ravel() - q["Va"][0], bank.ravel() - q["phi"][0]])
    z = np.linalg.solve(square, rhs)
    v = {n: q[n][0] + q[n][1] @ z for n in q}
    lo_t, hi_t = AF.throttle_limits
    lo_e, hi_e = AF.elevon_limits
    ok = ((np.radians(-8.0) <= v["alpha"]) & (v["alpha"] <= np.radians(12.0))
          & (np.abs(v["beta"]) <= 0.5) & (np.abs(v["theta"]) <= 1.2) & (np.abs(v["r"]) <= 2.0)
          & (lo_t <= v["throttle"]) & (v["throttle"] <= hi_t)
          & (lo_e <= v["free_elevon"]) & (v["free_elevon"] <= hi_e))
    assert linear_steady_flight(pl, "left", lock) == bool(ok.any())
    assert bool(ok.any()) == (offset_deg in (-3.0, 0.0, 4.0))


@pytest.mark.parametrize("side", ["left", "right"])
def test_the_linear_trimmable_set_is_the_interval_its_ends_bound(side):
    """:func:`linear_trimmable_set` (two linear programmes over lock and plane)
    against :func:`linear_steady_flight` lock by lock: every lock 0.01 deg
    inside its ends has a steady flight, none 0.01 deg outside them, and a
    grid of locks every 0.25 deg from -12 to +12 deg of trim has one exactly
    where the interval holds it.  The ends lie at or beyond the grid search's
    bands (x8-pyfly, linear model: -4.75 to +5.5 deg left, -5.25 to +5.5 deg
    right), within one step of 0.25 deg."""
    from ftc_mc.core.sixdof.layout import COMMAND
    from ftc_mc.model.trimmable import linear_steady_flight, linear_trimmable_set

    pl = linear_plant()
    lo, hi = linear_trimmable_set(pl, side)
    eps = math.radians(0.01)
    assert [linear_steady_flight(pl, side, v) for v in (lo + eps, hi - eps, lo - eps, hi + eps)] \
        == [True, True, False, False]
    trim = pl.u0[COMMAND[side]]
    grid = trim + np.radians(np.arange(-12.0, 12.0 + 1e-9, 0.25))
    assert [linear_steady_flight(pl, side, v) for v in grid] == list((grid >= lo) & (grid <= hi))
    band = {"left": (-4.75, 5.5), "right": (-5.25, 5.5)}[side]
    offsets = np.degrees([lo - trim, hi - trim])
    assert band[0] - 0.25 < offsets[0] <= band[0] and band[1] <= offsets[1] < band[1] + 0.25
