"""The 6-DOF model layer and kernels: kernels against their NumPy
twins, trim, linearisation, named modes against an independent implementation,
the 6-DOF model file, ``ftc-mc model --dof 6``, and that no longitudinal path
imports the 6-DOF kernels."""

import dataclasses
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from ftc_mc.cli import cli
from ftc_mc.core.sixdof import plant as kernels
from ftc_mc.core.sixdof.layout import (COMMAND, LAYOUT, N_COMMAND, N_OUTPUT, N_STATE,
                                       N_WIND, OUTPUT, STATE)
from ftc_mc.errors import UserError
from ftc_mc.model.airframe import X8
from ftc_mc.model.airframe_files import export_airframe
from ftc_mc.model.linear import trim
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import (build_sixdof_plant, derivatives, load_sixdof_model,
                                 named_modes, outputs, pack_parameters,
                                 require_lateral, save_sixdof_npz, sixdof_summary,
                                 trim6)

from naive_sixdof import derivatives_ref, outputs_ref, rk4_ref

PRESET_NAMES = list(PRESETS)

# Spread of random states around the trim: positions [m], angles [rad],
# velocities [m/s], rates [rad/s], actuators.
SPREAD = {"x": 50.0, "y": 50.0, "z": 20.0, "phi": 0.6, "theta": 0.3, "psi": 1.0,
          "u": 3.0, "v": 2.0, "w": 2.0, "p": 0.5, "q": 0.5, "r": 0.3,
          "throttle": 0.2, "left": 0.15, "right": 0.15}
WIND_SPREAD = {"u_g": 2.0, "v_g": 2.0, "w_g": 2.0, "p_g": 0.1, "q_g": 0.1, "r_g": 0.1}


def random_points(tp, n, seed):
    """``n`` (state, command, wind) draws around the trim ``tp``."""
    rng = np.random.default_rng(seed)
    spread = np.array([SPREAD[s] for s in LAYOUT.states])
    wspread = np.array([WIND_SPREAD[w] for w in LAYOUT.wind])
    for _ in range(n):
        x = tp.x0 + spread * rng.uniform(-1, 1, N_STATE)
        x[STATE["throttle"]] = rng.uniform(0.0, 1.0)
        cmd = tp.u0 + rng.uniform(-0.2, 0.2, N_COMMAND)
        cmd[COMMAND["throttle"]] = rng.uniform(0.0, 1.0)
        yield x, cmd, wspread * rng.uniform(-1, 1, N_WIND)


@pytest.fixture(scope="module", params=PRESET_NAMES)
def plant(request):
    return build_sixdof_plant(PRESETS[request.param].airframe, where=request.param)


# ------------------------------------------------------------ kernels vs twins

@pytest.mark.parametrize("name", PRESET_NAMES)
def test_derivatives_and_outputs_equal_the_numpy_twin(name):
    tp = trim6(PRESETS[name].airframe)
    for x, cmd, wind in random_points(tp, 200, seed=1):
        got = derivatives(x, cmd, tp.params, wind)
        want = derivatives_ref(x, cmd, tp.params, wind)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-11)
        np.testing.assert_allclose(outputs(x, tp.params, wind),
                                   outputs_ref(x, tp.params, wind),
                                   rtol=1e-12, atol=1e-13)


def test_rk4_propagate_and_simulate_equal_the_numpy_twin():
    tp = trim6(PRESETS["x8-pyfly"].airframe)
    work = np.zeros((kernels.N_WORK, N_STATE))
    for x, cmd, wind in random_points(tp, 20, seed=2):
        want = rk4_ref(x, cmd, tp.params, wind, 0.1, 10)
        got = x.copy()
        kernels.propagate(got, cmd, tp.params, wind, 0.1, 10, work)
        np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-11)
    rng = np.random.default_rng(3)
    cmds = tp.u0 + rng.uniform(-0.05, 0.05, (30, N_COMMAND))
    winds = rng.uniform(-0.5, 0.5, (30, N_WIND))
    out = np.empty((31, N_STATE))
    x = tp.x0.copy()
    kernels.simulate(x, cmds, tp.params, winds, 0.1, 10, out)
    ref = tp.x0.copy()
    for k in range(30):
        ref = rk4_ref(ref, cmds[k], tp.params, winds[k], 0.1, 10)
        np.testing.assert_allclose(out[k + 1], ref, rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(x, out[-1])


def test_wind_enters_air_relative():
    # a uniform gust equal to the aircraft's velocity leaves no airspeed
    tp = trim6(PRESETS["x8-pyfly"].airframe)
    wind = np.zeros(N_WIND)
    for n in ("u", "v", "w"):
        wind[LAYOUT.wind.index(f"{n}_g")] = tp.x0[STATE[n]] * 0.5
    y = outputs(tp.x0, tp.params, wind)
    assert y[OUTPUT["Va"]] == pytest.approx(0.5 * tp.V0, rel=1e-12)
    # a side gust gives sideslip of the opposite sign to a lateral velocity
    side = np.zeros(N_WIND)
    side[LAYOUT.wind.index("v_g")] = 1.0
    assert outputs(tp.x0, tp.params, side)[OUTPUT["beta"]] < tp.beta - 0.04


# ------------------------------------------------------------ trim

@pytest.mark.parametrize("name", PRESET_NAMES)
def test_trim_is_an_equilibrium_on_the_glide_path(name):
    tp = trim6(PRESETS[name].airframe)
    dx = derivatives(tp.x0, tp.u0, tp.params)
    assert np.max(np.abs(dx)) < 1e-9
    assert tp.y0[OUTPUT["gamma"]] == pytest.approx(math.radians(-3.0), abs=1e-12)
    assert tp.y0[OUTPUT["Va"]] == pytest.approx(20.0, rel=1e-14)


def test_trim_without_propeller_torque_is_wings_level_and_the_longitudinal_one():
    # x8-gryte2018 has no propeller torque (k_T_P 0): the 6-DOF trim is symmetric
    # and equals the longitudinal trim of model/linear.py
    af = PRESETS["x8-gryte2018"].airframe
    tp = trim6(af)
    assert abs(tp.beta) < 1e-12 and abs(tp.phi) < 1e-12 and abs(tp.aileron) < 1e-12
    lon = trim(af, 20.0, -3.0)
    assert tp.alpha == pytest.approx(lon.alpha, abs=1e-10)
    assert tp.u0[COMMAND["throttle"]] == pytest.approx(lon.u0[0], abs=1e-10)
    assert tp.elevator == pytest.approx(lon.u0[1], abs=1e-10)


def test_propeller_torque_is_balanced_by_aileron():
    # PyFly's file: k_T_P 1.1871e-6, k_Omega 797.13: -0.0816 N m of roll torque at
    # the trim throttle 0.329, balanced by aileron (and a little sideslip, bank)
    af = PRESETS["x8-pyfly"].airframe
    tp = trim6(af)
    torque = af.k_T_P * (af.k_Omega * tp.u0[COMMAND["throttle"]]) ** 2
    assert torque == pytest.approx(0.0816, abs=5e-4)
    assert 0.0015 < tp.aileron < 0.0025
    assert abs(math.degrees(tp.phi)) < 0.05 and abs(math.degrees(tp.beta)) < 0.05
    flat = dataclasses.replace(af, k_T_P=0.0)
    assert abs(trim6(flat).aileron) < 1e-12


def test_mirror_symmetry_of_the_elevons():
    # swapping left and right mirrors the lateral motion (y, v, p, r, phi, psi flip)
    # exactly once the two asymmetric terms are off: the propeller torque and the
    # drag linear in sideslip (C_D_beta1 beta: the files' sideslip drag is not
    # even in beta; with it the mirror holds to 3e-4 rad after 1 s)
    af = dataclasses.replace(PRESETS["x8-pyfly"].airframe, k_T_P=0.0, C_D_beta1=0.0)
    tp = trim6(af)
    x = tp.x0.copy()
    cmd = tp.u0.copy()
    cmd[COMMAND["left"]] += 0.05
    mirror = tp.u0.copy()
    mirror[COMMAND["right"]] += 0.05
    work = np.zeros((kernels.N_WORK, N_STATE))
    a, b = x.copy(), x.copy()
    for _ in range(10):
        kernels.propagate(a, cmd, tp.params, np.zeros(N_WIND), 0.1, 10, work)
        kernels.propagate(b, mirror, tp.params, np.zeros(N_WIND), 0.1, 10, work)
    flip = [STATE[n] for n in ("y", "phi", "psi", "v", "p", "r")]
    keep = [STATE[n] for n in ("x", "z", "theta", "u", "w", "q")]
    np.testing.assert_allclose(a[flip], -b[flip], atol=1e-12)
    np.testing.assert_allclose(a[keep], b[keep], atol=1e-12)
    assert a[STATE["p"]] > 0.01  # a left elevon down rolls right (aileron > 0)


def test_trim_refusals_are_one_line():
    af = PRESETS["x8-pyfly"].airframe
    with pytest.raises(UserError, match="throttle .* outside"):
        trim6(af, 20.0, 20.0)
    with pytest.raises(UserError, match="^model.airspeed_mps"):
        trim6(af, -1.0)


def test_missing_lateral_data_is_named():
    with pytest.raises(UserError) as exc:
        require_lateral(X8, "airframe X8")
    text = str(exc.value)
    assert text.startswith("airframe X8: the 6-DOF model needs the lateral-directional "
                           "fields b, Jx, Jz, Jxz,") and "\n" not in text
    with pytest.raises(UserError, match="C_n_r"):
        pack_parameters(dataclasses.replace(PRESETS["x8-pyfly"].airframe, C_n_r=None),
                        20.0, 0.0)


# ------------------------------------------------------------ linear model, modes

# Reference modes at 20 m/s, -3 deg (continuous, rigid body) from an independent
# implementation of the authors' equations: ../shared/DESIGN.md section 11, the
# table "Modes at 20 m/s, -3 deg, wings level", quoted to the digits below
# (checked to half a unit of the last quoted digit).
DESIGN_MODES = {
    "x8-pyfly": {"short_period": (-7.767, 8.793), "phugoid": (-0.0625, 0.5808),
                 "roll": (-38.53, 0.0), "dutch_roll": (0.304, 3.528),
                 "spiral": (-0.1858, 0.0)},
    "x8-gryte2018": {"short_period": (-7.762, 12.275), "phugoid": (-0.0597, 0.6361),
                     "roll": (-38.53, 0.0), "dutch_roll": (0.304, 3.528),
                     "spiral": (-0.1860, 0.0)},
}
DIGITS = {"short_period": (0.0005, 0.0005), "phugoid": (0.00005, 0.00005),
          "roll": (0.005, 0.0), "dutch_roll": (0.0005, 0.0005),
          "spiral": (0.00005, 0.0)}


def test_modes_match_the_independent_implementation(plant):
    name = next(n for n, p in PRESETS.items() if p.airframe == plant.airframe)
    modes = sixdof_summary(plant)["modes"]
    assert list(modes) == list(DESIGN_MODES[name])
    for mode, (re, im) in DESIGN_MODES[name].items():
        tol_re, tol_im = DIGITS[mode]
        assert abs(modes[mode]["real"] - re) <= tol_re + 1e-12, mode
        assert abs(modes[mode]["imag"] - im) <= tol_im + 1e-12, mode
    # the Dutch roll is unstable at this trim: the lateral loop is not optional
    assert modes["dutch_roll"]["real"] > 0


def test_linear_model_shapes_and_structure(plant):
    assert plant.A.shape == (N_STATE, N_STATE) and plant.B.shape == (N_STATE, N_COMMAND)
    assert plant.C.shape == (N_OUTPUT, N_STATE)
    names = [e["mode"] for e in named_modes(plant)]
    assert names.count("integrator") == 4  # x, y, z, psi
    assert names.count("elevon actuator") == 2 and names.count("engine actuator") == 1
    # zero-order hold: A = expm(Ac dt)
    import scipy.linalg
    np.testing.assert_allclose(plant.A, scipy.linalg.expm(plant.Ac * plant.dt),
                               atol=1e-12)
    # the commands drive only their actuator states; the throttle state moves no
    # lateral state at a symmetric trim, a differential elevon does
    act = [STATE[n] for n in LAYOUT.actuators]
    assert np.max(np.abs(np.delete(plant.Bc, act, axis=0))) < 1e-12
    if plant.airframe.k_T_P == 0:
        lat = [STATE[n] for n in LAYOUT.lateral]
        assert np.max(np.abs(plant.Ac[lat, STATE["throttle"]])) < 1e-9
        diff = plant.Ac[:, STATE["left"]] - plant.Ac[:, STATE["right"]]
        assert np.max(np.abs(diff[lat])) > 1.0


def test_linear_model_follows_the_nonlinear_plant_for_small_inputs(plant):
    # a 0.005 rad left-elevon step over 1 s: linear and nonlinear agree to 3 %
    # of the response (the rest is the nonlinearity, second order in the step)
    tp = plant.trim
    du = np.zeros(N_COMMAND)
    du[COMMAND["left"]] = 0.005
    x = tp.x0.copy()
    dxl = np.zeros(N_STATE)
    work = np.zeros((kernels.N_WORK, N_STATE))
    for _ in range(10):
        kernels.propagate(x, tp.u0 + du, tp.params, np.zeros(N_WIND), 0.1, 10, work)
        dxl = plant.A @ dxl + plant.B @ du
    for n in ("p", "phi", "r", "q"):
        i = STATE[n]
        assert abs((x[i] - tp.x0[i]) - dxl[i]) <= 0.03 * abs(dxl[i]) + 1e-9, n


def test_sixdof_model_file_round_trip(tmp_path):
    af = PRESETS["x8-pyfly"].airframe
    plant = build_sixdof_plant(af)
    path = tmp_path / "m6.npz"
    save_sixdof_npz(plant, path, source="x8-pyfly test")
    back, source = load_sixdof_model(path)
    assert source == "x8-pyfly test" and back.airframe == af
    for name in ("A", "B", "C", "u_lower", "u_upper"):
        np.testing.assert_array_equal(getattr(back, name), getattr(plant, name))
    np.testing.assert_array_equal(back.trim.x0, plant.trim.x0)
    np.testing.assert_array_equal(back.trim.params, plant.trim.params)
    with np.load(path) as z:  # lateral data with it, under the airframe's names
        assert float(z["airframe_C_l_p"]) == af.C_l_p and float(z["airframe_Jxz"]) == af.Jxz
        data = {k: z[k] for k in z.files if k != "A"}
    np.savez(tmp_path / "bad.npz", **data)
    with pytest.raises(UserError, match=r"^6-DOF model: missing variable A \("):
        load_sixdof_model(tmp_path / "bad.npz")


# ------------------------------------------------------------ command line

def test_cli_model_dof6_json_names_the_modes():
    res = CliRunner().invoke(cli, ["model", "--dof", "6", "--json"])
    assert res.exit_code == 0, res.output
    s = json.loads(res.output)
    assert s["dof"] == 6
    assert set(s["modes"]) == {"short_period", "phugoid", "roll", "dutch_roll", "spiral"}
    assert s["modes"]["dutch_roll"]["real"] > 0 and s["modes"]["roll"]["imag"] == 0
    assert s["trim"]["throttle"] == pytest.approx(0.329, abs=5e-4)
    text = CliRunner().invoke(cli, ["model", "--dof", "6"]).output
    for mode in ("short period", "phugoid", "roll", "dutch roll", "spiral"):
        assert mode in text


def test_cli_model_dof6_prints_the_trimmable_sets():
    """``ftc-mc model --dof 6 --trimmable``: each elevon's trimmable set, of the
    linear model (:func:`linear_trimmable_set`, as offsets from the trim) and
    of the equations (its search replaced by the linear model's here,
    tests/conftest.py), as JSON and as text; without ``--dof 6``, one line
    and exit 2."""
    from ftc_mc.model.trimmable import linear_trimmable_set

    res = CliRunner().invoke(cli, ["model", "--dof", "6", "--trimmable", "--json"])
    assert res.exit_code == 0, res.output
    sets = json.loads(res.output)["trimmable_set"]
    plant = build_sixdof_plant(PRESETS["x8-pyfly"].airframe)
    for side in ("left", "right"):
        lo, hi = linear_trimmable_set(plant, side)
        got = sets["linear"][side]
        assert (got["lo_rad"], got["hi_rad"]) == (lo, hi)
        assert got["lo_deg"] == pytest.approx(math.degrees(lo - plant.u0[COMMAND[side]]))
        assert sets["equations"][side] is not None
    text = CliRunner().invoke(cli, ["model", "--dof", "6", "--trimmable"]).output
    left = sets["linear"]["left"]
    assert f"left {left['lo_deg']:+.2f} to {left['hi_deg']:+.2f} deg" in text
    assert "linear model (exact)" in text and "equations (bisection" in text
    res = CliRunner().invoke(cli, ["model", "--trimmable"])
    assert res.exit_code == 2 and len(res.output.strip().splitlines()) == 1
    assert "--trimmable: needs --dof 6" in res.output


def test_cli_model_dof6_refuses_a_longitudinal_only_file(tmp_path):
    path = tmp_path / "lon.yaml"
    export_airframe(X8, path)
    out = tmp_path / "m.npz"
    res = CliRunner().invoke(cli, ["model", "--dof", "6", "--airframe", str(path),
                                   "--save", str(out)])
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "lateral-directional fields b, Jx" in lines[0]
    assert not out.exists()
    # the same file still flies the longitudinal model
    assert CliRunner().invoke(cli, ["model", "--airframe", str(path)]).exit_code == 0


def test_cli_model_dof6_save(tmp_path):
    out = tmp_path / "m6.npz"
    res = CliRunner().invoke(cli, ["model", "--dof", "6", "--airframe", "x8-gryte2018",
                                   "--save", str(out)])
    assert res.exit_code == 0 and out.exists(), res.output
    plant, source = load_sixdof_model(out)
    assert "krisgry/x8" in source and plant.airframe.k_T_P == 0.0


def test_longitudinal_path_does_not_import_the_sixdof_kernels():
    # Numba compile time matters to every user: a longitudinal model or run
    # must not import (so never compiles or loads) ftc_mc.core.sixdof
    code = (
        "import sys\n"
        "from click.testing import CliRunner\n"
        "from ftc_mc.cli import cli\n"
        "import ftc_mc.api, ftc_mc.sim.setup, ftc_mc.campaign.runner\n"
        "import ftc_mc.scenario.run, ftc_mc.campaign.sweep\n"
        "r = CliRunner().invoke(cli, ['model', '--json'])\n"
        "assert r.exit_code == 0, r.output\n"
        "bad = [m for m in sys.modules if m.startswith(('ftc_mc.core.sixdof', "
        "'ftc_mc.model.sixdof'))]\n"
        "print(bad)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


# ------------------------------------------------------------ lateral gusts

def test_lateral_dryden_variances_are_the_spectra_integrals():
    import scipy.integrate

    from ftc_mc.model.turbulence import (dryden_lateral_model, dryden_model, psd_p,
                                         psd_r, psd_v)

    m = dryden_lateral_model("moderate", V=20.0, altitude_m=100.0, dt=0.1, span=2.1)
    lon = dryden_model("moderate", V=20.0, altitude_m=100.0, dt=0.1, span=2.1)
    # MIL-F-8785C at low altitude: sigma_v = sigma_u, L_v = L_u
    assert m.sigma_v == lon.sigma_u and m.L_v == lon.L_u
    var = np.diag(m.Cc @ m.P0 @ m.Cc.T)
    for i, psd in enumerate((psd_v, psd_p, psd_r)):
        integral = scipy.integrate.quad(lambda w: psd(w, m), 0, np.inf, limit=500)[0]
        assert var[i] == pytest.approx(integral, rel=1e-6), i
    assert var[0] == pytest.approx(m.sigma_v ** 2, rel=1e-9)
    assert not dryden_lateral_model("none").Bd.any()


def test_lateral_gusts_run_through_the_dryden_kernel():
    # the lateral model has the longitudinal one's shape, so gust_step runs it;
    # a long record has the model's variances, and r_g lags dv_g/dt / V
    from ftc_mc.core.shared.dryden import gust_record
    from ftc_mc.model.turbulence import dryden_lateral_model

    m = dryden_lateral_model("moderate", dt=0.1)
    rng = np.random.default_rng(7)
    n = 200_000
    state = m.P0_chol @ rng.standard_normal(4)
    rec = np.empty((n, 3))
    gust_record(state, rng.standard_normal((n, 4)), m.Ad, m.Bd, m.Cd, rec)
    np.testing.assert_allclose(rec.var(axis=0), [m.sigma_v ** 2, m.sigma_p ** 2,
                                                 m.sigma_r ** 2], rtol=0.06)
    dv = np.diff(rec[:, 0]) / m.dt / m.V
    assert np.corrcoef(dv, rec[1:, 2])[0, 1] > 0.5  # r_g = +dv_g/dx, lagged


def test_sixdof_wind_places_components_by_name():
    from ftc_mc.model.sixdof import sixdof_wind

    w = sixdof_wind(np.array([[1.0, 2.0, 3.0]]), np.array([[4.0, 5.0, 6.0]]))
    named = dict(zip(LAYOUT.wind, w[0]))
    assert named == {"u_g": 1.0, "w_g": 2.0, "q_g": 3.0, "v_g": 4.0, "p_g": 5.0,
                     "r_g": 6.0}


def test_linear_and_nonlinear_agree_for_small_gusts(plant):
    # the discrete gust matrices Bw, Dw against the nonlinear plant in a small,
    # constant gust of every component over 1 s
    tp = plant.trim
    wind = 1e-3 * np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1])
    x = tp.x0.copy()
    work = np.zeros((kernels.N_WORK, N_STATE))
    dxl = np.zeros(N_STATE)
    for _ in range(10):
        kernels.propagate(x, tp.u0, tp.params, wind, 0.1, 10, work)
        dxl = plant.A @ dxl + plant.Bw @ wind
    # (the rest is second order in the gust: 1e-4 of the response here)
    np.testing.assert_allclose(x - tp.x0, dxl, atol=1e-3 * np.max(np.abs(dxl)))
    y = outputs(tp.x0, tp.params, wind)
    np.testing.assert_allclose(y - tp.y0, plant.Dw @ wind, atol=1e-7)
    assert plant.Bw.shape == (N_STATE, N_WIND) and plant.Dw.shape == (N_OUTPUT, N_WIND)


def test_single_elevon_step_matches_the_independent_implementation():
    # ../shared/DESIGN.md section 11: "Left locked at trim, right at trim + 0.05
    # rad (authors' equations, x8-pyfly): p, phi, q, theta, beta at 1 s: -0.037
    # rad/s, -0.160 rad, -0.132 rad/s, -0.192 rad, -0.044 rad (mirror case: p,
    # phi, beta flip sign, to 4e-4)" -- the surfaces stepped (the elevon states
    # set to their commands at t = 0), quoted to 3 decimals.  That implementation
    # had no propeller torque: with x8-pyfly's, p at 1 s is -0.0363 rad/s, the
    # rest unchanged to the quoted digits.
    tp = trim6(dataclasses.replace(PRESETS["x8-pyfly"].airframe, k_T_P=0.0))
    quoted = {"p": -0.037, "phi": -0.160, "q": -0.132, "theta": -0.192, "beta": -0.044}
    got = {}
    for side, sign in (("right", 1.0), ("left", -1.0)):
        x = tp.x0.copy()
        cmd = tp.u0.copy()
        cmd[COMMAND[side]] += 0.05
        x[STATE[side]] = cmd[COMMAND[side]]
        work = np.zeros((kernels.N_WORK, N_STATE))
        for _ in range(10):
            kernels.propagate(x, cmd, tp.params, np.zeros(N_WIND), 0.1, 10, work)
        y = outputs(x, tp.params)
        got[side] = {"p": x[STATE["p"]], "phi": x[STATE["phi"]], "q": x[STATE["q"]],
                     "theta": x[STATE["theta"]], "beta": y[OUTPUT["beta"]]}
        for name, value in quoted.items():
            mirrored = sign * value if name in ("p", "phi", "beta") else value
            assert abs(got[side][name] - mirrored) <= 0.0005 + (4e-4 if sign < 0 else 0), \
                (side, name, got[side][name])
    for name in ("p", "phi", "beta"):
        assert abs(got["left"][name] + got["right"][name]) <= 4e-4, name


@pytest.mark.parametrize("name", PRESET_NAMES)
def test_a_locked_elevon_away_from_trim_has_no_straight_glide(name):
    # no rudder: with one elevon locked, roll and yaw balance need the aileron
    # at its trim value (the design notes, section 11); a lock at the trim
    # position trims to the free trim, a lock 0.1 or 5 deg away is refused
    af = PRESETS[name].airframe
    tp = trim6(af)
    for side in ("left", "right"):
        at = trim6(af, locked=(side, tp.u0[COMMAND[side]]))
        np.testing.assert_allclose(at.u0, tp.u0, atol=1e-12)
        for deg in (0.1, 5.0, -5.0):
            pos = tp.u0[COMMAND[side]] + math.radians(deg)
            with pytest.raises(UserError, match=f"no straight glide with the {side} "
                                                "elevon locked"):
                trim6(af, locked=(side, pos))
