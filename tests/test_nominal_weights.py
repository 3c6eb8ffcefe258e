"""The opt-in turbulence weights of the nominal LQR (``controller.weights: airspeed``).

The gain is the discounted LQR of Bryson's diagonal weights (checked against
scipy's and python-control's Riccati solvers on the scaled pair), the config
field is validated (a result folder recorded before it existed still resumes),
a design may set its own, c1's tables and the terminal costs are built from
the same weights, and the nonlinear X8 flies moderate turbulence with them.
"""

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import scipy.linalg
import yaml

from ftc_mc.config import Config, load_any, parse_config
from ftc_mc.conventions import LONGITUDINAL
from ftc_mc.design.lqr import (bryson_q_lqr, bryson_r_lqr, controller_weights, discounted_lqr,
                               paper_q_lqr)
from ftc_mc.errors import UserError
from ftc_mc.model.source import load_plant

ALPHA = 0.999


@pytest.fixture(scope="module")
def plant():
    return load_plant("x8-pyfly", 20.0, -3.0, 0.1, (math.radians(-8), math.radians(12)))


def test_bryson_weights_are_one_over_the_squared_scales():
    Q = bryson_q_lqr(2.0, 1.0, 10.0, 30.0)
    q = np.diag(Q)
    s = LONGITUDINAL.state
    assert q[s("u")] == 0.25 and q[s("z")] == 1.0
    assert q[s("theta")] == pytest.approx(1 / math.radians(10) ** 2)
    assert q[s("q")] == pytest.approx(1 / math.radians(30) ** 2)
    assert q[s("x")] == 0 and q[s("w")] == 0 and np.count_nonzero(q) == 4
    assert np.array_equal(Q, np.diag(q))
    assert np.allclose(np.diag(bryson_r_lqr(0.3, 0.1)), [1 / 0.09, 100.0, 100.0])


def test_gain_solves_the_discounted_riccati_equation(plant):
    Q, R = bryson_q_lqr(), bryson_r_lqr()
    K, P = discounted_lqr(plant.A, plant.B, Q, R, ALPHA)
    sa = math.sqrt(ALPHA)
    A, B = sa * plant.A, sa * plant.B
    X = scipy.linalg.solve_discrete_are(A, B, Q, R)
    assert np.allclose(P, X, rtol=1e-9, atol=1e-9)
    assert np.allclose(K, np.linalg.solve(R + B.T @ X @ B, B.T @ X @ A), rtol=1e-9, atol=1e-12)
    # the discounted cost's Bellman equation: P = Q + K'RK + alpha (A-BK)' P (A-BK)
    Acl = plant.A - plant.B @ K
    assert np.allclose(P, Q + K.T @ R @ K + ALPHA * Acl.T @ P @ Acl, rtol=1e-8, atol=1e-8)
    # the scaled closed loop is stable
    assert np.max(np.abs(np.linalg.eigvals(sa * Acl))) < 1


def test_gain_matches_python_control(plant):
    control = pytest.importorskip("control")
    Q, R = bryson_q_lqr(2.0, 1.0), bryson_r_lqr()
    K, _ = discounted_lqr(plant.A, plant.B, Q, R, ALPHA)
    sa = math.sqrt(ALPHA)
    Kc, _, _ = control.dlqr(sa * plant.A, sa * plant.B, Q, R)
    assert np.allclose(K, np.asarray(Kc), rtol=1e-7, atol=1e-10)


def test_config_selects_the_weights(plant):
    paper = Config().controller
    Q, R = controller_weights(paper, plant.trim.gamma0)
    assert np.array_equal(Q, paper_q_lqr(plant.trim.gamma0)) and np.array_equal(R, 0.1 * np.eye(3))
    air = Config.model_validate({"controller": {"weights": "airspeed", "height_scale_m": 3.0,
                                                "throttle_scale": 0.5}}).controller
    Q, R = controller_weights(air, plant.trim.gamma0)
    assert np.array_equal(Q, bryson_q_lqr(2.0, 3.0, 10.0, 30.0))
    assert np.array_equal(R, bryson_r_lqr(0.5, 0.1))
    default = Config.model_validate({"controller": {"weights": "airspeed"}}).controller
    assert np.array_equal(controller_weights(default, 0.0)[1], bryson_r_lqr(3.0, 0.1))


@pytest.mark.parametrize("text, field", [
    ("controller:\n  weights: bryson\n", "controller.weights"),
    ("controller:\n  weights: airspeed\n  airspeed_scale_mps: 0\n",
     "controller.airspeed_scale_mps"),
    ("controller:\n  height_scale_m: -1\n", "controller.height_scale_m"),
    ("controller:\n  elevon_scale_rad: .nan\n", "controller.elevon_scale_rad"),
    ("controller:\n  throttle_scale: yes\n", "controller.throttle_scale"),
    ("controller:\n  weights: airspeed\n  coupling: coupled\n", "coupling: separate only"),
    ("designs:\n  a: {weights: bryson}\n", "designs.a.weights"),
    ("plant: {dof: 6}\ncontroller: {coupling: coupled}\ncampaign: {designs: [a]}\n"
     "designs:\n  a: {weights: airspeed}\n", "designs.a.weights: airspeed flies with"),
    ("plant: {dof: 6}\ncampaign: {designs: [a]}\n"
     "designs:\n  a: {weights: airspeed, controller: lock_turn_selected}\n",
     "designs.a.weights: a lock_turn_selected design"),
])
def test_bad_weights_name_the_field(text, field):
    with pytest.raises(UserError) as exc:
        parse_config(yaml.safe_load(text))
    assert field in str(exc.value)


def test_a_folder_recorded_before_a_field_existed_still_resumes(tmp_path):
    """Resuming compares what the recorded configuration means under the current
    schema: fields added since then (here the weights, a design's weights and the
    campaign's record) take their defaults; a changed value still refuses."""
    from ftc_mc.api import _open_chunks

    cfg = load_any("configs/robust_moderate.yaml")
    ours = cfg.model_dump(mode="json")
    old = json.loads(json.dumps(ours))
    for name in ("weights", "airspeed_scale_mps", "height_scale_m", "throttle_scale"):
        del old["controller"][name]
    for d in old["designs"].values():
        for name in ("weights", "excitation_pause_belief", "policy_doublet_amplitude"):
            if d[name] is None:  # at its default: as a folder of before the field
                del d[name]
    del old["campaign"]["record"]
    store = tmp_path / ".chunks"
    store.mkdir()
    (store / "manifest.json").write_text(json.dumps({"config": old}))
    _open_chunks(tmp_path, json.dumps(ours, sort_keys=True), False, True)  # resumes
    old["controller"]["height_scale_m"] = 3.0
    (store / "manifest.json").write_text(json.dumps({"config": old}))
    with pytest.raises(UserError, match="another configuration"):
        _open_chunks(tmp_path, json.dumps(ours, sort_keys=True), False, True)


def test_c1_and_terminal_costs_use_the_same_weights():
    from ftc_mc.cache.engine_tables import engine_tables_key
    from ftc_mc.design.terminal import terminal_costs
    from ftc_mc.sim.setup import build_setup

    paper = build_setup(Config())
    cfg = Config.model_validate({"controller": {"weights": "airspeed"}})
    air = build_setup(cfg)
    c = cfg.controller
    Q, R = controller_weights(c, air.plant.trim.gamma0)
    K, _ = discounted_lqr(air.plant.A, air.plant.B, Q, R, c.discount)
    assert np.array_equal(air.ctl.K, K)
    assert np.array_equal(air.rc.q_lqr, np.diag(Q)) and np.array_equal(air.rc.r_lqr, np.diag(R))
    assert engine_tables_key(air.plant, Q=Q, R=R, alpha=c.discount) != engine_tables_key(
        paper.plant, Q=paper_q_lqr(paper.plant.trim.gamma0), R=0.1 * np.eye(3),
        alpha=c.discount)
    assert not np.allclose(air.eng.K, paper.eng.K)
    JN = terminal_costs(air.fm, K, air.eng, air.ctl.lo_dev, air.ctl.hi_dev, c.discount,
                        np.diag(Q), np.diag(R), cfg.steps(c.terminal_horizon_s))
    assert np.array_equal(air.rc.JN, JN)


def test_shipped_robust_moderate_flies_the_paper_design_on_c0_beside_the_airspeed_weights():
    """The paper's design stays the baseline on c0's weights; the config's
    default design flies the airspeed weights; the designs it was chosen over
    (robust and its variants) keep c0's."""
    cfg = load_any(Path(__file__).resolve().parents[1] / "configs" / "robust_moderate.yaml")
    assert cfg.controller.weights == "paper" and cfg.campaign.signature == "swapped"
    assert cfg.campaign.designs == ["excited_airspeed"]
    assert cfg.designs["excited_airspeed"].weights == "airspeed"
    assert all(cfg.designs[n].weights is None
               for n in ("robust", "robust_ekf", "robust_clip", "robust_excited"))


def test_the_airspeed_weights_fly_moderate_turbulence():
    """Flights 0-23 of the endurance seed 777 with the shipped robust design:
    the paper's c0 leaves the envelope below 12 m/s on flight 20, the airspeed
    weights keep all 24 inside (docs/findings/turbulence-envelope.md). A
    design's own weights fly as the controller section's would, beside a
    design on c0 in the same run."""
    from ftc_mc import run_endurance

    base = load_any(Path(__file__).resolve().parents[1] / "configs" / "robust_moderate.yaml")
    data = base.model_dump()
    data["controller"]["weights"] = "airspeed"
    air = Config.model_validate(data)
    data = base.model_dump()
    data["designs"]["robust_air"] = {**data["designs"]["robust"], "weights": "airspeed"}
    both = Config.model_validate(data)
    hours = 24 * 50.0 / 3600
    kw = dict(seed=777, jobs=1, progress=False)
    f_air = run_endurance(air, hours, design=("robust",), **kw).flights
    f_both = run_endurance(both, hours, design=("robust", "robust_air"), **kw).flights
    f_paper = f_both[f_both.variant == "robust"].set_index("flight_id")
    f_own = f_both[f_both.variant == "robust_air"].set_index("flight_id")
    assert len(f_own) == len(f_paper) == 24
    assert f_paper.loc[20, "status"] == "airspeed_out_of_bounds"
    assert (f_own.status == "ok").all() and (f_own.flown_s == 50.0).all()
    pd.testing.assert_frame_equal(f_own.drop(columns="variant"),
                                  f_air.set_index("flight_id").drop(columns="variant"),
                                  check_exact=True)
