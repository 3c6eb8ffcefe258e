"""PyFly as an external oracle of the 6-DOF equations.

PyFly (``pyfly-fixed-wing`` 0.1.2 on PyPI, MIT, E. Bøhn; the ``test`` extra) is a
6-DOF X8 simulator nobody here wrote: quaternion attitude, Beard & McLain's
``gamma`` inertia terms, its own force function.  Its ``PyFly._dynamics(t, y)``
is the right-hand side of its ODE; it is compared with
:func:`ftc_mc.core.sixdof.plant.derivatives` where the force models are matched:

* PyFly's differing terms are switched to ours in the test, on PyFly's side:
  ``C_m_q`` is scaled by ``b/(2 Va)`` there and ``c/(2 Va)`` in the authors'
  ``forces.m`` (PyFly's ``C_m_q`` is set to ``C_m_q c / b``); its stall blend
  ``sigma`` is pushed out of reach (``a_0`` 3.3 rad, ``M`` 100: sigma below
  1e-17 for |alpha| < 2.9 rad, and no overflow of its exponentials at any
  alpha); its elevons are made first order with our
  time constant (its own are second order, omega 100 rad/s, zeta 1.71) and its
  throttle lag is set to ours (0.3 s; its own 0.2 s);
* on our side, the drag polar is PyFly's: its drag without stall,
  ``C_D_p + (C_L_0 + C_L_alpha alpha)^2 / (pi e AR)``, is a quadratic in alpha,
  so our ``CD0``, ``CDa``, ``CDa2`` are set to its coefficients;
* the propeller torque ``-k_T_P (k_Omega throttle)^2`` is in both (the authors'
  ``forces.m`` has it too; their file sets it to zero, PyFly's does not), so it
  needs no switch.

What each difference does when not switched is measured and documented in
``docs/reference/airframes.md`` ("PyFly's own simulator").  Attitude: PyFly's quaternion
derivative is mapped to Euler-angle rates through the exact Jacobian of the
Euler-to-quaternion map (complex step), and both derivative functions are
integrated by one fixed-step RK4 in our coordinates.
"""

import dataclasses
import json
import math

import numpy as np
import pytest

from ftc_mc.core.sixdof.layout import COMMAND, LAYOUT, N_COMMAND, N_STATE, STATE
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.sixdof import derivatives, trim6

pyfly_module = pytest.importorskip("pyfly.pyfly")

AF = PRESETS["x8-pyfly"].airframe
PYFLY_DYNAMICS = ("elevon_right", "elevon_left", "throttle")  # its config's order
STALL_OFF = {"a_0": 3.3, "M": 100.0}


def make_pyfly():
    """PyFly with the matched force model (module docstring), still air."""
    import importlib.resources

    cfg_path = importlib.resources.files("pyfly") / "pyfly_config.json"
    cfg = json.loads(cfg_path.read_text())
    assert tuple(cfg["actuation"]["dynamics"]) == PYFLY_DYNAMICS
    assert cfg["turbulence"] is False and cfg["wind_magnitude_max"] == 0
    assert (cfg["rho"], cfg["g"]) == (AF.rho, AF.g)
    for v in cfg["variables"]:
        if v["name"] in ("elevon_left", "elevon_right"):
            for key in ("omega_0", "zeta", "dot_max"):
                v.pop(key)
            v.update(order=1, tau=AF.tau_elevon)
        elif v["name"] == "throttle":
            v["tau"] = AF.tau_thrust
        elif v["name"] in ("omega_p", "omega_q", "omega_r"):
            v.pop("constraint_min")
            v.pop("constraint_max")
    pf = pyfly_module.PyFly(config_kw={"variables": cfg["variables"]})
    pf.params["C_m_q"] = pf.params["C_m_q"] * pf.params["c"] / pf.params["b"]
    pf.params.update(STALL_OFF)
    pf.seed(0)
    pf.reset()
    return pf


def matched_airframe(pf):
    """Our x8-pyfly with PyFly's drag polar (module docstring)."""
    k = math.pi * pf.params["e"] * pf.params["ar"]
    CL0, CLa = pf.params["C_L_0"], pf.params["C_L_alpha"]
    return dataclasses.replace(AF, CD0=pf.params["C_D_p"] + CL0 ** 2 / k,
                               CDa=2 * CL0 * CLa / k, CDa2=CLa ** 2 / k)


def quaternion(euler):
    """Euler angles (phi, theta, psi) -> PyFly's attitude quaternion
    (``AttitudeQuaternion._from_euler_angles``; works on complex numbers)."""
    phi, theta, psi = euler
    cph, sph = np.cos(phi / 2), np.sin(phi / 2)
    cth, sth = np.cos(theta / 2), np.sin(theta / 2)
    cps, sps = np.cos(psi / 2), np.sin(psi / 2)
    return np.array([cps * cth * cph + sps * sth * sph, cps * cth * sph - sps * sth * cph,
                     cps * sth * cph + sps * cth * sph, sps * cth * cph - cps * sth * sph])


def quaternion_jacobian(euler):
    """d quaternion / d (phi, theta, psi), exact by complex step."""
    h = 1e-30
    J = np.empty((4, 3))
    for j in range(3):
        e = np.array(euler, dtype=complex)
        e[j] += 1j * h
        J[:, j] = quaternion(e).imag / h
    return J


ANGLES = [STATE[n] for n in ("phi", "theta", "psi")]
RATES = [STATE[n] for n in ("p", "q", "r")]
POS = [STATE[n] for n in ("x", "y", "z")]
VEL = [STATE[n] for n in ("u", "v", "w")]


def pyfly_derivatives(pf, x, cmd, V0, gamma0):
    """PyFly's ``_dynamics`` at our state ``x`` and commands ``cmd``, in our
    coordinates (Euler rates; position rates of the deviation from the
    reference point flying north at ``V0``, ``gamma0``)."""
    left, right = cmd[COMMAND["left"]], cmd[COMMAND["right"]]
    # PyFly's inputs are elevator, aileron, throttle; it mixes them to elevons
    pf.actuation.set_and_constrain_commands(
        [0.5 * (left + right), 0.5 * (left - right), cmd[COMMAND["throttle"]]])
    act = {"elevon_right": x[STATE["right"]], "elevon_left": x[STATE["left"]],
           "throttle": x[STATE["throttle"]]}
    y = np.concatenate([quaternion(x[ANGLES]), x[RATES], x[POS], x[VEL],
                        [act[n] for n in PYFLY_DYNAMICS], np.zeros(len(PYFLY_DYNAMICS))])
    d = pf._dynamics(1.0, y)  # t > 0: PyFly reads its state from y
    dq, domega, dpos, dvel = d[0:4], d[4:7], d[7:10], d[10:13]
    dact = dict(zip(PYFLY_DYNAMICS, d[13:16]))
    out = np.empty(N_STATE)
    out[ANGLES] = np.linalg.lstsq(quaternion_jacobian(x[ANGLES]), dq, rcond=None)[0]
    out[RATES] = domega
    out[POS] = dpos - V0 * np.array([math.cos(gamma0), 0.0, -math.sin(gamma0)])
    out[VEL] = dvel
    out[STATE["left"]] = dact["elevon_left"]
    out[STATE["right"]] = dact["elevon_right"]
    out[STATE["throttle"]] = dact["throttle"]
    return out


@pytest.fixture(scope="module")
def matched():
    pf = make_pyfly()
    af = matched_airframe(pf)
    tp = trim6(af)
    return pf, af, tp


def test_quaternion_map_is_pyflys():
    q = pyfly_module.AttitudeQuaternion()
    rng = np.random.default_rng(0)
    for _ in range(20):
        euler = rng.uniform([-1.5, -1.4, -3.1], [1.5, 1.4, 3.1])
        q.reset(euler)
        np.testing.assert_allclose(quaternion(euler), q.value, rtol=0, atol=1e-15)


def test_matched_parameters_are_pyflys_file(matched):
    pf, af, _ = matched
    for ours, theirs in (("mass", "mass"), ("Jx", "Jx"), ("Jy", "Jy"), ("Jz", "Jz"),
                         ("Jxz", "Jxz"), ("S", "S_wing"), ("b", "b"), ("c", "c"),
                         ("C_l_p", "C_l_p"), ("C_n_r", "C_n_r"), ("k_T_P", "k_T_P"),
                         ("k_Omega", "k_Omega"), ("k_motor", "k_motor"),
                         ("C_prop", "C_prop"), ("Cm0", "C_m_0"), ("CLa", "C_L_alpha")):
        assert getattr(af, ours) == float(pf.params[theirs]), ours


def test_state_derivatives_equal_pyflys_where_the_force_model_is_matched(matched):
    # 500 random states and inputs around the envelope: |alpha| and |beta| up to
    # about 0.35 rad, rates up to 1 rad/s, bank up to 60 deg, pitch up to 45 deg
    pf, af, tp = matched
    rng = np.random.default_rng(24)
    ours, theirs = [], []
    for _ in range(500):
        x = tp.x0.copy()
        x[ANGLES] = rng.uniform([-1.05, -0.8, -math.pi], [1.05, 0.8, math.pi])
        x[VEL] = rng.uniform([12.0, -5.0, -3.0], [30.0, 5.0, 6.0])
        x[RATES] = rng.uniform(-1.0, 1.0, 3)
        x[POS] = rng.uniform(-100.0, 100.0, 3)
        x[STATE["throttle"]] = rng.uniform(0.0, 1.0)
        x[STATE["left"]], x[STATE["right"]] = rng.uniform(-0.45, 0.45, 2)
        cmd = np.empty(N_COMMAND)
        cmd[COMMAND["throttle"]] = rng.uniform(0.0, 1.0)
        cmd[[COMMAND["left"], COMMAND["right"]]] = rng.uniform(-0.45, 0.45, 2)
        ours.append(derivatives(x, cmd, tp.params))
        theirs.append(pyfly_derivatives(pf, x, cmd, tp.V0, tp.gamma0))
    ours, theirs = np.array(ours), np.array(theirs)
    scale = np.max(np.abs(theirs), axis=0)
    err = np.max(np.abs(ours - theirs) / np.maximum(np.abs(theirs), scale), axis=0)
    assert np.all(err <= 1e-9), dict(zip(LAYOUT.states, err))


def rk4(f, x, h):
    k1 = f(x)
    k2 = f(x + h / 2 * k1)
    k3 = f(x + h / 2 * k2)
    k4 = f(x + h * k3)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


DOUBLET = 0.0005  # [rad]


def open_loop_commands(u0, t):
    """Elevon doublets on each side (left at 2 s, right at 6 s, 1 s each way) and
    a throttle step (+0.05 at 10 s) around the trim commands.

    The doublets are small (0.0005 rad) because the Dutch roll is unstable:
    open loop, the X8 departs anyway (sideslip beyond 40 deg by 30 s), and with
    0.002 rad it tumbles before 30 s (u through zero at 29.5 s)."""
    cmd = u0.copy()
    for side, start in (("left", 2.0), ("right", 6.0)):
        if start <= t < start + 1.0:
            cmd[COMMAND[side]] += DOUBLET
        elif start + 1.0 <= t < start + 2.0:
            cmd[COMMAND[side]] -= DOUBLET
    if t >= 10.0:
        cmd[COMMAND["throttle"]] += 0.05
    return cmd


def test_common_integrator_trajectories_agree_over_30_s(matched):
    # one fixed-step RK4 (h = 0.01 s) integrates both derivative functions over
    # 30 s of open-loop inputs; the Dutch roll is unstable (+0.30 1/s), so the
    # flight departs from the trim: the comparison covers that departure too
    pf, af, tp = matched
    h, n = 0.01, 3000
    xa = tp.x0.copy()
    xb = tp.x0.copy()
    traj_a, traj_b = [xa], [xb]
    for k in range(n):
        t = k * h
        cmd = open_loop_commands(tp.u0, t)
        xa = rk4(lambda s: derivatives(s, cmd, tp.params), xa, h)
        xb = rk4(lambda s: pyfly_derivatives(pf, s, cmd, tp.V0, tp.gamma0), xb, h)
        traj_a.append(xa)
        traj_b.append(xb)
    a, b = np.array(traj_a), np.array(traj_b)
    # the flight left the trim (the lateral motion grew) but stayed where both
    # models are defined
    beta = np.arcsin(b[:, STATE["v"]] / np.linalg.norm(b[:, VEL], axis=1))
    assert np.max(np.abs(beta)) > math.radians(20.0)
    assert np.max(np.abs(b[:, STATE["theta"]])) < 1.3
    # relative to each state's largest magnitude along the flight
    rel = np.max(np.abs(a - b), axis=0) / np.max(np.abs(b), axis=0)
    assert np.all(rel <= 1e-6), dict(zip(LAYOUT.states, rel))
