"""Airframes in runs: model.airframe and --airframe on model, run, sweep and scenario.

Bad airframes are refused by the config schema or the trim before anything is
written; a linear model saved from a preset flies the same trials bit for bit;
an edited export flies; results of another airframe go to their own folder.
"""

import numpy as np
import pandas as pd
import pytest
import yaml
from click.testing import CliRunner

import ftc_mc
from ftc_mc.cli import cli
from ftc_mc.config import Config
from ftc_mc.model.presets import PRESETS
from ftc_mc.model.source import DEFAULT_AIRFRAME
from ftc_mc.sim.setup import build_setup

SHORT = {"timing": {"fault_time_s": 3.0, "window_s": 3.0, "duration_s": 8.0}}


def _cfg(tmp_path, **sections):
    data = {"campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 4,
                         "chunk_size": 4}, **SHORT, **sections}
    path = tmp_path / "cfg.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def _invoke(*args):
    return CliRunner().invoke(cli, [str(a) for a in args])


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """The default preset exported to YAML and saved as a linear model."""
    d = tmp_path_factory.mktemp("airframe")
    res = _invoke("model", "--airframe", DEFAULT_AIRFRAME, "--export", d / "af.yaml",
                  "--save", d / "lin.npz")
    assert res.exit_code == 0, res.output
    return d


def test_airframes_lists_both_presets_with_sources_and_trims():
    res = _invoke("airframes")
    assert res.exit_code == 0, res.output
    for name, p in PRESETS.items():
        assert name in res.output and p.source.commit[:12] in res.output
    # trims of the presets (docs/reference/airframes.md; tests/test_airframes.py checks them)
    assert "throttle 0.084" in res.output and "throttle 0.329" in res.output
    assert f"{DEFAULT_AIRFRAME} (default)" in res.output


def test_config_names_the_airframe_it_flies():
    cfg = Config.model_validate({"model": {"airframe": "x8-gryte2018"}})
    setup = build_setup(cfg)
    assert setup.plant.airframe == PRESETS["x8-gryte2018"].airframe
    assert build_setup(Config()).plant.airframe == PRESETS[DEFAULT_AIRFRAME].airframe


@pytest.mark.parametrize("turbulence", ["none", "moderate"])
def test_saved_linear_model_flies_the_presets_trials_bit_for_bit(exported, tmp_path,
                                                                  turbulence):
    base = {"campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 4,
                         "chunk_size": 4}, **SHORT, "plant": {"turbulence": turbulence}}
    a = ftc_mc.run_campaign(base, airframe=DEFAULT_AIRFRAME, progress=False)
    b = ftc_mc.run_campaign(base, airframe=exported / "lin.npz", progress=False)
    pd.testing.assert_frame_equal(a.trials, b.trials, check_exact=True)
    pd.testing.assert_frame_equal(a.resets, b.resets, check_exact=True)


def test_an_edited_export_flies_and_differs(exported, tmp_path):
    text = (exported / "af.yaml").read_text()
    heavy = tmp_path / "heavy.yaml"
    lines = [("mass: 4.2" if ln.startswith("mass:") else ln) for ln in text.splitlines()]
    heavy.write_text("\n".join(lines) + "\n")
    out = tmp_path / "o"
    res = _invoke("run", _cfg(tmp_path), "--airframe", heavy, "--out", out, "--quiet")
    assert res.exit_code == 0, res.output
    mine = pd.read_parquet(out / "trials.parquet")
    ref = ftc_mc.run_campaign(_cfg(tmp_path), progress=False).trials
    assert len(mine) == len(ref)
    assert not np.array_equal(mine["b1_hat_end"].to_numpy(), ref["b1_hat_end"].to_numpy())


def test_scenario_and_sweep_take_the_airframe(tmp_path):
    res = _invoke("scenario", _scenario(tmp_path), "--airframe",
                  "x8-gryte2018", "--out", tmp_path / "s")
    assert res.exit_code == 0, res.output
    res = _invoke("sweep", _cfg(tmp_path), "--thresholds", "25", "--trials", "2",
                  "--flights", "2", "--airframe", "x8-gryte2018", "--out", tmp_path / "w",
                  "--quiet", "--jobs", "1")
    assert res.exit_code == 0, res.output
    meta_s = ftc_mc.io.results.read_metadata(tmp_path / "s" / "timeseries.parquet")
    meta_w = ftc_mc.io.results.read_metadata(tmp_path / "w" / "sweep.parquet")
    assert meta_s["config"]["model"]["airframe"] == "x8-gryte2018"
    assert meta_w["config"]["model"]["airframe"] == "x8-gryte2018"


def _scenario(tmp_path):
    path = tmp_path / "sc.yaml"
    path.write_text(yaml.safe_dump({"scenario": {"duration_s": 5.0, "schedule": [
        {"time_s": 0.0, "fault": "nominal"},
        {"time_s": 2.0, "fault": "lock", "actuator": "engine", "position": 0.2}]}}))
    return path


def test_results_of_another_airframe_get_their_own_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cfg = _cfg(tmp_path)
    other = "x8-gryte2018" if DEFAULT_AIRFRAME != "x8-gryte2018" else "x8-pyfly"
    assert _invoke("run", cfg, "--quiet", "--trials", "1").exit_code == 0
    assert _invoke("run", cfg, "--quiet", "--trials", "1", "--airframe",
                   other).exit_code == 0
    assert (tmp_path / "results" / "cfg" / "trials.parquet").exists()
    assert (tmp_path / "results" / f"cfg-{other}" / "trials.parquet").exists()


def _bad_yaml(tmp_path, exported, change):
    text = (exported / "af.yaml").read_text().splitlines()
    path = tmp_path / "bad.yaml"
    path.write_text("\n".join(change(text)) + "\n")
    return path


@pytest.mark.parametrize("make, needle", [
    (lambda t, e: "x8-nope", "unknown preset 'x8-nope'"),
    (lambda t, e: _bad_yaml(t, e, lambda ls: [ln for ln in ls if not ln.startswith("Jy:")]),
     "Jy"),
    (lambda t, e: _bad_yaml(t, e, lambda ls: ls + ["wingspan: 2.1"]), "wingspan"),
    (lambda t, e: _bad_yaml(t, e, lambda ls: [("mass: -1.0" if ln.startswith("mass:")
                                               else ln) for ln in ls]), "mass"),
    (lambda t, e: _bad_yaml(t, e, lambda ls: [("c: 0.0" if ln.startswith("c:")
                                               else ln) for ln in ls]), "c"),
    (lambda t, e: _bad_yaml(t, e, lambda ls: [("Cma: .nan" if ln.startswith("Cma:")
                                               else ln) for ln in ls]), "Cma"),
    (lambda t, e: _empty(t), "empty"),
    (lambda t, e: _truncated(t, e), "linear model"),
    (lambda t, e: _wrong_shape(t, e), "A"),
])
def test_bad_airframes_are_one_line_exit_2_and_write_nothing(tmp_path, exported, make,
                                                             needle):
    spec = make(tmp_path, exported)
    out = tmp_path / "o"
    for args in (("run", _cfg(tmp_path), "--airframe", spec, "--out", out),
                 ("scenario", _scenario(tmp_path), "--airframe", spec, "--out", out),
                 ("sweep", _cfg(tmp_path), "--thresholds", "25", "--airframe", spec,
                  "--out", out)):
        res = _invoke(*args)
        assert res.exit_code == 2, res.output
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and needle in lines[0] and "model.airframe" in lines[0], \
            res.output
        assert not out.exists()


def _empty(tmp_path):
    path = tmp_path / "empty.yaml"
    path.write_text("")
    return path


def _truncated(tmp_path, exported):
    path = tmp_path / "cut.npz"
    path.write_bytes((exported / "lin.npz").read_bytes()[:300])
    return path


def _wrong_shape(tmp_path, exported):
    data = dict(np.load(exported / "lin.npz"))
    data["A"] = data["A"][:8, :8]
    path = tmp_path / "shape.npz"
    np.savez(path, **data)
    return path


def test_a_condition_the_airframe_cannot_fly_is_one_line(tmp_path):
    out = tmp_path / "o"
    path = _cfg(tmp_path, model={"airspeed_mps": 60.0})
    res = _invoke("run", path, "--out", out)
    assert res.exit_code == 2 and "cannot fly this condition" in res.output, res.output
    assert len(res.output.strip().splitlines()) == 1 and not out.exists()


def test_linear_model_refuses_the_nonlinear_plant_and_another_trim(tmp_path, exported):
    out = tmp_path / "o"
    res = _invoke("run", _cfg(tmp_path), "--airframe", exported / "lin.npz", "--plant",
                  "nonlinear", "--out", out)
    assert res.exit_code == 2 and "plant.kind" in res.output, res.output
    path = _cfg(tmp_path, model={"airframe": str(exported / "lin.npz"),
                                 "airspeed_mps": 22.0})
    res = _invoke("run", path, "--out", out)
    assert res.exit_code == 2 and "model.airspeed_mps" in res.output, res.output
    assert not out.exists()
