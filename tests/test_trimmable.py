"""Steady flight with one elevon locked (ftc_mc/model/trimmable.py, issue 26 item 5).

Reference: the project's held-out trim analysis of the authors' equations
(DESIGN.md section 11 and issue 26): at 20 m/s and -3 deg a lock 5 deg above
trim admits no steady flight, straight or turning, and steady no-rudder turns
keep the locked elevon within about +0.4 to +0.6 deg of trim."""

import math

import numpy as np
import pytest

from ftc_mc.core.sixdof.layout import STATE
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
