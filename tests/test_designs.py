"""Detection designs: config validation, --design, settings, common random
numbers across designs."""

import numpy as np
import pytest
from click.testing import CliRunner

from ftc_mc import api
from ftc_mc.cli import cli
from ftc_mc.config import Config, ScenarioConfig
from ftc_mc.config.load import validate_model
from ftc_mc.conventions import TEST_GLR, TEST_ONE_STEP
from ftc_mc.errors import UserError
from ftc_mc.model.turbulence import dryden_model
from ftc_mc.model.wind import plant_wind_matrices
from ftc_mc.sim.estimator import EstimatorSettings, detection, filter_model, initial_covariance

GUST_GLR = {"estimator": "gust_aware", "test": "glr", "window_s": 1.0,
            "design_turbulence": "light"}
SHORT = {"timing": {"fault_time_s": 2.0, "window_s": 2.0, "duration_s": 5.0},
         "controller": {"kind": "nominal"}}


def config(**over):
    data = {"designs": {"gust_glr": GUST_GLR, "tight": {"t_q": 5.0, "t_nx": 5.0,
                                                         "sigma_qx": 0.05}},
            "campaign": {"designs": ["gust_glr", "tight"], "trials": 3},
            **SHORT}
    data.update(over)
    return validate_model(Config, data, "test.yaml")


# ------------------------------------------------------------------ validation

def test_designs_validate_and_run_in_order():
    cfg = config()
    assert cfg.campaign.runs() == ("paper", "swapped", "gust_glr", "tight")
    d = cfg.designs["gust_glr"]
    assert (d.estimator, d.test, d.window_s, d.signature) == ("gust_aware", "glr", 1.0,
                                                              "swapped")
    assert cfg.designs["tight"].sigma_qb is None
    assert Config().designs == {} and Config().campaign.runs() == ("paper", "swapped")
    only = config(campaign={"signature": "none", "designs": ["tight"]})
    assert only.campaign.runs() == ("tight",)


@pytest.mark.parametrize("data, needle", [
    ({"designs": {"paper": {}}}, "designs: 'paper': reserved"),
    ({"designs": {"both": {}}}, "reserved"),
    ({"designs": {"a b": {}}}, "letters, digits"),
    ({"designs": {"x": {"test": "cusum"}}}, "designs.x.test"),
    ({"designs": {"x": {"estimator": "ekf"}}}, "designs.x.estimator"),
    ({"designs": {"x": {"t_q": 0}}}, "designs.x.t_q"),
    ({"designs": {"x": {"sigma_qx": -1}}}, "designs.x.sigma_qx"),
    ({"designs": {"x": {"design_turbulence": "none"}}}, "designs.x.design_turbulence"),
    ({"designs": {"x": {"bogus": 1}}}, "designs.x.bogus"),
    ({"designs": {"x": {"test": "glr", "window_s": 0.15}}},
     "designs.x.window_s: must be a positive multiple of model.dt_s"),
    ({"designs": {"x": {"test": "glr", "window_s": 60.0}}},
     "designs.x.window_s: must not exceed timing.duration_s"),
    ({"designs": {"x": {"prediction": "nonlinear", "relinearise_s": 0.15}}},
     "designs.x.relinearise_s: must be a positive multiple of model.dt_s"),
    ({"designs": {"x": {"relinearise_s": 1.0}}},
     "designs.x.relinearise_s: only with prediction: nonlinear"),
    ({"designs": {"x": {"innovation_clip": 4.0}}},
     "designs.x.innovation_clip: only with test: glr"),
    ({"designs": {"x": {"test": "glr", "innovation_clip": 0}}}, "designs.x.innovation_clip"),
    ({"designs": {"x": {"sensor_biases": ["alpha"]}}}, "designs.x.sensor_biases.0"),
    ({"designs": {"x": {"sensor_biases": ["q", "q"]}}}, "sensor_biases: outputs must not repeat"),
    ({"designs": {"x": {"sensor_biases": ["q"], "sensor_bias_sd": {"q": -0.1}}}},
     "designs.x.sensor_bias_sd.q"),
    ({"designs": {"x": {"sensor_biases": ["q"], "sensor_bias_walk": {"q": float("nan")}}}},
     "designs.x.sensor_bias_walk.q"),
    ({"designs": {"x": {"sensor_biases": ["q"], "sensor_bias_sd": {"n_z": 0.1}}}},
     "sensor_bias_sd: n_z not in sensor_biases"),
    ({"campaign": {"designs": ["nope"]}, "designs": {"x": {}}},
     "campaign.designs: unknown design 'nope'; designs defined: x"),
    ({"campaign": {"designs": ["nope"]}}, "designs defined: none"),
    ({"campaign": {"designs": ["paper"]}}, "built-in design; choose it with campaign.signature"),
    ({"campaign": {"designs": ["x", "x"]}, "designs": {"x": {}}}, "must not repeat"),
    ({"campaign": {"signature": "none"}}, "campaign.signature: none runs nothing"),
])
def test_bad_designs_are_one_line(data, needle):
    with pytest.raises(UserError) as exc:
        validate_model(Config, data, "test.yaml")
    msg = str(exc.value)
    assert needle in msg and "\n" not in msg, msg


def test_scenario_design_validation():
    sc = validate_model(ScenarioConfig, {"designs": {"g": GUST_GLR},
                                         "scenario": {"design": "g"}}, "s.yaml")
    assert sc.scenario.design == "g"
    with pytest.raises(UserError, match="scenario.design: unknown design 'h'; designs "
                                        "defined: g"):
        validate_model(ScenarioConfig, {"designs": {"g": {}}, "scenario": {"design": "h"}},
                       "s.yaml")


# ------------------------------------------------------------------ --design

def test_design_override_replaces_signature_and_designs():
    cfg = config()
    c = api.campaign_config(cfg, design=["gust_glr"]).campaign
    assert (c.signature, c.designs, c.runs()) == ("none", ["gust_glr"], ("gust_glr",))
    c = api.campaign_config(cfg, design=["tight", "paper"]).campaign
    assert c.runs() == ("paper", "tight")
    c = api.campaign_config(cfg, design="swapped,paper").campaign
    assert (c.signature, c.designs) == ("both", [])
    with pytest.raises(UserError, match="--design: unknown design 'zz'; known designs: "
                                        "paper, swapped, gust_glr, tight"):
        api.campaign_config(cfg, design=["zz"])
    with pytest.raises(UserError, match="--design: give either"):
        api.campaign_config(cfg, design=["paper"], signature="swapped")
    with pytest.raises(UserError, match="named twice"):
        api.campaign_config(cfg, design=["paper", "paper"])


def test_scenario_design_override():
    sc = ScenarioConfig.model_validate({"designs": {"g": GUST_GLR},
                                        "scenario": {"design": "g"}})
    assert api.scenario_config(sc, design="paper").scenario.design is None
    assert api.scenario_config(sc, design="paper").scenario.signature == "paper"
    assert api.scenario_config(ScenarioConfig.model_validate(
        {"designs": {"g": GUST_GLR}}), design="g").scenario.design == "g"
    with pytest.raises(UserError, match="one design"):
        api.scenario_config(sc, design=["g", "paper"])


@pytest.mark.parametrize("command", ["run", "sweep", "scenario"])
def test_cli_unknown_design_is_one_line_and_writes_nothing(tmp_path, command):
    path = tmp_path / "c.yaml"
    path.write_text("scenario: {}\n" if command == "scenario" else "{}\n")
    out = tmp_path / "out"
    args = [command, str(path), "--design", "zz", "--out", str(out)]
    if command == "sweep":
        args += ["--thresholds", "10"]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "--design: unknown design 'zz'; known designs: paper, " \
        "swapped" in lines[0], res.output
    assert not out.exists()


def test_default_out_names_the_designs(tmp_path, monkeypatch):
    from ftc_mc.cli import _default_out

    monkeypatch.chdir(tmp_path)
    assert _default_out("x/c.yaml", config()).name == "c-gust_glr-tight"
    assert _default_out("x/c.yaml", Config()).name == "c"


# ------------------------------------------------------------------ settings

def test_builtin_designs_are_todays_settings():
    from ftc_mc.sim.setup import build_setup

    cfg = config()
    setup = build_setup(cfg)
    plant = setup.plant
    est = EstimatorSettings.from_config(cfg.estimator, "paper")
    fm = filter_model(plant, est)
    for name in ("paper", "swapped"):
        d = setup.designs[name]
        for a, b in zip(d.fm, fm):
            np.testing.assert_array_equal(a, b)
        want = detection(plant, EstimatorSettings.from_config(cfg.estimator, name))
        # every field Table 1's settings give; the side monitor's thresholds are
        # the run's monitor section's (a design may set its own)
        want = want._replace(side_thresholds=np.full(3, cfg.monitor.threshold))
        for a, b in zip(d.det, want):
            np.testing.assert_array_equal(a, b)
        assert d.det.test == TEST_ONE_STEP and d.det.window == 1
        np.testing.assert_array_equal(d.P0, initial_covariance(fm, detection(
            plant, EstimatorSettings())))
        np.testing.assert_array_equal(d.P0, setup.P0)
    assert setup.designs["paper"].key == setup.designs["swapped"].key


def test_gust_aware_glr_design():
    from ftc_mc.sim.setup import build_setup

    cfg = config()
    setup = build_setup(cfg)
    d, p = setup.designs["gust_glr"], setup.designs["paper"]
    plant = setup.plant
    Bw, Dw = plant_wind_matrices(plant)
    dm = dryden_model("light", V=plant.trim.V0, altitude_m=100.0, dt=plant.dt)
    np.testing.assert_allclose(d.fm.G, Bw @ dm.Cd)
    np.testing.assert_allclose(d.fm.Dg, Dw @ dm.Cd)
    np.testing.assert_allclose(d.fm.Ad, dm.Ad)
    np.testing.assert_allclose(d.fm.Qg, dm.Bd @ dm.Bd.T)
    np.testing.assert_array_equal(d.fm.Bw, Bw)
    np.testing.assert_array_equal(d.fm.Dw, Dw)
    assert d.fm.relin == 0 and p.fm.relin == 0 and not p.fm.Bw.any() and not p.fm.Dw.any()
    for f in ("A", "B", "Bb0", "C", "q_diag", "r_diag", "lo", "hi"):
        np.testing.assert_array_equal(getattr(d.fm, f), getattr(p.fm, f))
    assert d.P0.shape == (18, 18) and d.n_aug == 18
    np.testing.assert_array_equal(d.P0[:14, :14], p.P0)
    np.testing.assert_allclose(d.P0[14:, 14:], dm.P0)
    assert not d.P0[:14, 14:].any()
    assert d.det.test == TEST_GLR and d.det.window == 10 and d.det.swapped == 1
    for a in (*d.fm, d.P0):
        if isinstance(a, np.ndarray):
            assert a.flags.c_contiguous and a.dtype.kind in "fi"
    # a sweep point keeps the design's test; infinite thresholds disable resets
    det = setup.detection("gust_glr", 10.0, 12.0)
    assert (det.t_q, det.t_nx, det.test, det.window) == (10.0, 12.0, TEST_GLR, 10)
    assert np.isinf(setup.detection("gust_glr", np.inf, np.inf).t_q)
    assert d.key != p.key
    assert np.isinf(d.det.clip) and np.isinf(det.clip)


def test_innovation_clip_reaches_every_detection():
    """``innovation_clip`` is the design's ``Detection.clip``, at its own thresholds
    and at a sweep point (a sweep once rebuilt the detection without it); a
    design without it does not clip."""
    from ftc_mc.sim.setup import build_setup

    clipped = {**GUST_GLR, "innovation_clip": 4.0}
    setup = build_setup(config(designs={"c": clipped, "g": GUST_GLR},
                               campaign={"designs": ["c", "g"]}))
    assert setup.det["c"].clip == 4.0 and np.isinf(setup.det["g"].clip)
    assert setup.detection("c", 10.0, 12.0).clip == 4.0
    assert np.isinf(setup.detection("g", 10.0, 12.0).clip)
    assert setup.designs["c"].key != setup.designs["g"].key


def test_relinearise_design():
    """``relinearise_s`` of an extended design: ``FilterModel.relin`` in steps and a
    key of its own; the same design without it re-linearises never."""
    from ftc_mc.sim.setup import build_setup

    ext = {**GUST_GLR, "prediction": "nonlinear"}
    cfg = config(designs={"ext": ext, "relin": {**ext, "relinearise_s": 1.0}},
                 campaign={"designs": ["ext", "relin"], "trials": 3})
    setup = build_setup(cfg)
    e, r = setup.designs["ext"], setup.designs["relin"]
    assert e.fm.relin == 0 and e.fm.nl == 1
    assert r.fm.relin == round(1.0 / setup.plant.dt) and r.key != e.key


def test_sigma_overrides_change_the_filter_only():
    from ftc_mc.sim.setup import build_setup

    cfg = config()
    setup = build_setup(cfg)
    t, p = setup.designs["tight"], setup.designs["paper"]
    assert t.fm.q_diag[0] == pytest.approx(0.05 ** 2 * setup.plant.dt)
    np.testing.assert_array_equal(t.fm.q_diag[9:], p.fm.q_diag[9:])
    assert t.det.t_q == 5.0 and t.key != p.key
    # the truth noise stays the config's
    np.testing.assert_allclose(setup.q_std, np.sqrt(p.fm.q_diag[:9]))


# ------------------------------------------------------------------ common random numbers

def test_every_design_flies_the_same_trials():
    from ftc_mc.campaign.chunk import chunk_spec, trial_inputs
    from ftc_mc.sim.inputs import design_inputs

    cfg = config(plant={"turbulence": "light"})
    spec = chunk_spec(cfg)
    inp, _ = trial_inputs(spec, "elevon_lock", np.arange(3))
    per = {n: design_inputs(inp, d) for n, d in spec.setup.designs.items()}
    base = per["paper"]
    for name, di in per.items():
        for f in ("b0", "b1", "w", "v", "eta", "g0", "k_switch", "sensor_out"):
            np.testing.assert_array_equal(getattr(di, f), getattr(base, f), err_msg=name)
        np.testing.assert_array_equal(di.xa0[:14], base.xa0)
        assert not di.xa0[14:].any()
        assert di.P0.shape == (di.xa0.shape[0],) * 2
    assert per["gust_glr"].xa0.shape == (18, 3)


# ------------------------------------------------------------------ report

def test_report_compares_each_design_with_the_paper():
    import pandas as pd

    from ftc_mc.plots.campaign import design_styles
    from ftc_mc.report import variant_comparison

    rows = [{"transition": "elevon_lock", "variant": v, "trial_id": i,
             "inappropriate": i < k, "no_reset": False, "judged": True}
            for v, k in (("swapped", 5), ("gust_glr", 0), ("paper", 15)) for i in range(20)]
    text = "\n".join(variant_comparison(pd.DataFrame(rows)))
    assert "baseline `paper`" in text
    assert "#### `swapped` against `paper`" in text
    assert "#### `gust_glr` against `paper`" in text and "**`gust_glr` is better**" in text
    st = design_styles(["gust_glr", "swapped", "paper", "x"])
    assert st["paper"]["linestyle"] == "-" and st["swapped"]["linestyle"] == "--"
    assert len({(s["linestyle"], s["marker"]) for s in st.values()}) == 4


def test_other_design_set_is_never_resumed_or_overwritten(tmp_path):
    cfg = config(campaign={"trials": 2, "chunk_size": 1})
    out = tmp_path / "run"
    res = api.run_campaign(cfg, design=["paper"], out=out, progress=False)
    assert list(res.summary["variant"].unique()) == ["paper"]
    with pytest.raises(UserError, match="another configuration"):
        api.run_campaign(cfg, design=["swapped"], out=out, resume=True, progress=False)
    with pytest.raises(UserError, match="already holds"):
        api.run_campaign(cfg, design=["swapped"], out=out, progress=False)
    assert api.run_campaign(cfg, design=["paper"], out=out, resume=True,
                            progress=False) is None


def test_shared_start_per_design_equals_running_alone():
    """Sweep sharing groups runs by design key; each gives the records it gives alone."""
    from ftc_mc.campaign.chunk import chunk_spec, trial_inputs

    cfg = config(plant={"turbulence": "light"}, campaign={"trials": 4, "designs": [
        "gust_glr", "tight"], "transitions": ["elevon_lock"]})
    spec = chunk_spec(cfg)
    setup = spec.setup
    inp, _ = trial_inputs(spec, "elevon_lock", np.arange(4))
    runs = [(n, setup.detection(n, t, t)) for t in (10.0, 40.0) for n in setup.designs]
    sim, (alone, sim_alone) = assert_shared_start_exact(setup, inp, runs)
    assert sim_alone == 4 * setup.tim.n_steps * len(runs)


def assert_shared_start_exact(setup, inp, runs):
    """Every run's records with a shared start up to the switch equal its
    records alone (``sim.lanes.simulate``); returns the shared run's lane
    steps and the alone ``(records, lane steps)``."""
    from ftc_mc.sim.lanes import simulate

    shared, sim = simulate(setup, inp, runs, 64, setup.tim.k_fault)
    alone, sim_alone = simulate(setup, inp, runs, 64)
    for (name, det), a, b in zip(runs, shared, alone):
        for f in a._fields:
            np.testing.assert_array_equal(getattr(a, f), getattr(b, f),
                                          err_msg=f"{name} {det.t_q} {f}")
    return sim, (alone, sim_alone)


def test_a_design_flies_its_own_controller_on_the_same_trials():
    """``controller`` of a design: a nominal-controller design run beside the
    reconfiguring paper flies c0 throughout and equals the paper's own run with
    ``controller.kind: nominal``, trial by trial; null keeps the section's kind."""
    data = {"designs": {"paper_c0": {"signature": "paper", "controller": "nominal"}},
            "campaign": {"designs": ["paper_c0"], "trials": 4, "signature": "paper",
                         "transitions": ["engine_lock"]},
            "timing": {"fault_time_s": 2.0, "window_s": 3.0, "duration_s": 6.0},
            "controller": {"kind": "reconfiguring"}}
    cfg = validate_model(Config, data, "test.yaml")
    assert cfg.controller_of("paper_c0") == "nominal"
    assert cfg.controller_of("paper") == "reconfiguring"
    both = api.run_campaign(cfg, progress=False, jobs=1).trials
    nominal = validate_model(Config, {**data, "controller": {"kind": "nominal"},
                                      "campaign": {**data["campaign"], "designs": []}},
                             "test.yaml")
    alone = api.run_campaign(nominal, progress=False, jobs=1).trials
    c0 = both[both.variant == "paper_c0"].reset_index(drop=True)
    ref = alone.reset_index(drop=True)
    for col in ref.columns.drop("variant"):
        np.testing.assert_array_equal(c0[col].to_numpy(), ref[col].to_numpy(), err_msg=col)
    rc = both[both.variant == "paper"].reset_index(drop=True)
    # the reconfiguring paper flies otherwise after the switch (c1 chosen in some trial)
    assert not np.array_equal(rc["b1_hat_end"].to_numpy(), c0["b1_hat_end"].to_numpy())
