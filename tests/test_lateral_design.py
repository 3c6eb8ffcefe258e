"""The lateral loop of the 6-DOF X8 (issue 24 item 4, offline design): wings
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
