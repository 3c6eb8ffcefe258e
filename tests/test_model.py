"""Plant model: trim, linearisation, discretisation, redundancy, bad input."""

import dataclasses
import json
import math

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
import scipy.signal
from click.testing import CliRunner

from ftc_mc.cli import cli
from ftc_mc.config import EstimatorConfig
from ftc_mc.model.airframe import X8
from ftc_mc.model.dynamics import derivatives, outputs
from ftc_mc.model.linear import build_plant, named_eigenvalues, redundancy, zoh
from ftc_mc.model.wind import wind_matrices


def test_trim_is_an_equilibrium(plant):
    dx = np.empty(9)
    tp = plant.trim
    derivatives(tp.x0, tp.u0, tp.params, dx)
    assert np.max(np.abs(dx)) < 1e-9
    assert tp.u0[1] == tp.u0[2]  # symmetric elevons


def test_trim_matches_hand_solution():
    # Hand solution with small-angle force balance (drag and thrust-line terms
    # neglected): Cm = 0 and L = m g cos(gamma) give two linear equations in
    # alpha and de (the design notes expected alpha about 1.1 deg, throttle 0.08).
    a = X8
    qS = 0.5 * a.rho * 20.0 ** 2 * a.S
    CL = a.mass * a.g * math.cos(math.radians(-3)) / qS
    M = np.array([[a.CLa, a.CLde], [a.Cma, a.Cmde]])
    alpha, de = np.linalg.solve(M, [CL - a.CL0, -a.Cm0])
    tp = build_plant().trim
    assert abs(tp.alpha - alpha) < math.radians(0.05)
    assert abs(tp.u0[1] - de) < 0.005
    assert 0.06 < tp.u0[0] < 0.10


def test_outputs_at_trim(plant):
    y = plant.trim.y0
    assert y[11] == pytest.approx(20.0, rel=1e-12)          # Va
    assert y[9] == pytest.approx(math.radians(-3), abs=1e-12)  # gamma
    # specific force: n_z = cos(theta) ... close to one, n_x = sin(theta)
    th = plant.trim.x0[5]
    assert y[7] == pytest.approx(math.cos(th), abs=1e-9)
    assert y[6] == pytest.approx(math.sin(th), abs=1e-9)


def test_discretisation_is_zoh(plant):
    n, m = plant.Bc.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = plant.Ac
    M[:n, n:] = plant.Bc
    E = scipy.linalg.expm(M * plant.dt)
    np.testing.assert_allclose(plant.A, E[:n, :n], atol=1e-12)
    np.testing.assert_allclose(plant.B, E[:n, n:], atol=1e-12)


def test_zoh_is_scipy_signal_to_the_bit(plant):
    # model.linear.zoh stands in for scipy.signal.cont2discrete(method="zoh") so
    # that runs need not import scipy.signal; results must not move
    zeros = np.zeros((plant.Cc.shape[0], plant.Bc.shape[1]))
    A, B, C, _, _ = scipy.signal.cont2discrete((plant.Ac, plant.Bc, plant.Cc, zeros),
                                               plant.dt, method="zoh")
    assert np.array_equal(plant.A, A) and np.array_equal(plant.B, B)
    assert np.array_equal(plant.C, C) and plant.C is not plant.Cc
    Bw, _, Ewc = wind_matrices(plant)
    _, Bw_ref, _, _, _ = scipy.signal.cont2discrete(
        (plant.Ac, Ewc, plant.Cc, np.zeros((plant.Cc.shape[0], 3))), plant.dt, method="zoh")
    assert np.array_equal(Bw, Bw_ref)
    assert np.array_equal(zoh(plant.Ac, Ewc, 0.0)[1], np.zeros_like(Ewc))


def test_linear_model_matches_nonlinear_for_small_inputs(plant):
    """A small elevon doublet: the linear and nonlinear responses agree to 2 %."""
    tp = plant.trim
    steps = 30
    du = np.zeros((steps, 3))
    du[:5, 1:] = 0.01
    du[5:10, 1:] = -0.01
    x_lin = np.zeros(9)
    x_nl = tp.x0.copy()
    err, peak = 0.0, 0.0
    for k in range(steps):
        def f(t, x, u=tp.u0 + du[k]):
            dx = np.empty(9)
            derivatives(x, u, tp.params, dx)
            return dx
        x_nl = scipy.integrate.solve_ivp(f, (0, plant.dt), x_nl, rtol=1e-10,
                                         atol=1e-12).y[:, -1]
        x_lin = plant.A @ x_lin + plant.B @ du[k]
        dev = x_nl - tp.x0
        err = max(err, abs(dev[2] - x_lin[2]))
        peak = max(peak, abs(dev[2]))
    assert peak > 0.01
    assert err < 0.02 * peak


def test_output_jacobian_matches_finite_difference(plant):
    tp = plant.trim
    h = 1e-6
    for j in range(9):
        xp, xm = tp.x0.copy(), tp.x0.copy()
        xp[j] += h
        xm[j] -= h
        yp, ym = np.empty(12), np.empty(12)
        outputs(xp, tp.params, yp)
        outputs(xm, tp.params, ym)
        np.testing.assert_allclose(plant.C[:, j], (yp - ym) / (2 * h), atol=1e-6)


def test_redundancy_definition(plant):
    r = redundancy(plant)
    assert r["elevons_redundant"] is True
    assert r["thrust_redundant"] is False
    assert r["thrust_sv_ratio_min"] > 1e-3


def test_eigenvalues_are_named(plant):
    modes = [e["mode"] for e in named_eigenvalues(plant)]
    for name, count in [("short period", 2), ("phugoid", 2), ("engine actuator", 1),
                        ("elevon actuator", 2), ("position integrator", 2)]:
        assert modes.count(name) == count
    sp = [e["continuous"] for e in named_eigenvalues(plant) if e["mode"] == "short period"]
    ph = [e["continuous"] for e in named_eigenvalues(plant) if e["mode"] == "phugoid"]
    assert abs(sp[0]) > 5 * abs(ph[0])
    assert all(e.real < 0 for e in sp + ph)


@pytest.mark.parametrize("field,value", [("mass", -1.0), ("Jy", 0.0),
                                         ("tau_thrust", -0.1), ("tau_elevon", 0.0),
                                         ("S", float("nan"))])
def test_nonphysical_airframe_is_refused(field, value):
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(X8, **{field: value})


def test_zero_dt_is_refused():
    with pytest.raises(ValueError, match="dt"):
        build_plant(dt=0.0)


@pytest.mark.parametrize("field", ["t_q", "t_nx"])
@pytest.mark.parametrize("value", [0.0, -5.0])
def test_nonpositive_threshold_is_refused(field, value):
    # the schema is the only validator of the thresholds (sim/estimator.py trusts it)
    with pytest.raises(ValueError, match=field):
        EstimatorConfig(**{field: value})


def test_cli_model_json(tmp_path):
    out = tmp_path / "plant.npz"
    res = CliRunner().invoke(cli, ["model", "--json", "--save", str(out)])
    assert res.exit_code == 0, res.output
    data = json.loads(res.output)
    assert set(data["trim"]) >= {"alpha_deg", "throttle", "elevon_rad"}
    assert data["redundancy"]["elevons_redundant"] is True
    assert data["redundancy"]["thrust_redundant"] is False
    assert len(data["eigenvalues"]) == 9
    saved = np.load(out)
    assert saved["A"].shape == (9, 9) and saved["C"].shape == (12, 9)
    assert float(saved["dt"]) == 0.1
    # everything a linear trial uses (ftc_mc/model/summary.py: save_npz)
    assert saved.files == ["A", "B", "C", "u0", "u_lower", "u_upper", "dt", "x0",
                           "y0", "alpha", "V0", "gamma0", "Bw", "Dw"]
    assert saved["Bw"].shape == (9, 3) and saved["Dw"].shape == (12, 3)


def test_cli_model_bad_input_is_one_line(tmp_path):
    res = CliRunner().invoke(cli, ["model", "--dt", "0", "--save", str(tmp_path / "a.npz")])
    assert res.exit_code == 2
    assert "dt" in res.output and "Traceback" not in res.output
    assert not list(tmp_path.iterdir())
