"""The Python API (ftc_mc.api) and the command line over it: same files, same data;
``--resume`` of a finished output; errors; the width of the run table."""

import hashlib
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import yaml
from click.testing import CliRunner

import ftc_mc
from ftc_mc.cli import TERMINAL_WIDTH, cli, terminal_table
from ftc_mc.errors import UserError
from ftc_mc.config import Config, ScenarioConfig
from ftc_mc.io.results import read_metadata

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 4,
                      "chunk_size": 2},
         "controller": {"kind": "nominal"},
         "timing": {"fault_time_s": 2, "window_s": 2, "duration_s": 6}}
SCENARIO = {"scenario": {"duration_s": 20.0, "schedule": [
    {"time_s": 0.0, "fault": "nominal"},
    {"time_s": 5.0, "fault": "lock", "actuator": "engine", "position": 0.2}]}}
SWEEP = ["--thresholds", "10,25", "--flights", "2", "--jobs", "1", "--quiet"]


def _yaml(tmp_path, data, name="cfg.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


def _files(d: Path) -> dict:
    """Name -> (mtime, sha256) of every file under ``d``."""
    return {str(p.relative_to(d)): (p.stat().st_mtime_ns,
                                    hashlib.sha256(p.read_bytes()).hexdigest())
            for p in sorted(d.rglob("*")) if p.is_file()}


def test_import_is_cheap_and_exports_the_api():
    code = ("import sys, ftc_mc; print(sorted(m for m in ('numpy', 'pandas', 'pydantic', "
            "'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"
    assert set(ftc_mc.__all__) == {"run_campaign", "run_sweep", "run_endurance",
                                   "run_scenario", "build_report", "load_config",
                                   "score_detector"}
    assert all(callable(getattr(ftc_mc, name)) for name in ftc_mc.__all__)


def test_load_config_tells_campaign_from_scenario(tmp_path):
    assert isinstance(ftc_mc.load_config(ROOT / "configs" / "paper_tables.yaml"), Config)
    assert isinstance(ftc_mc.load_config(ROOT / "configs" / "sweep.yaml"), Config)
    sc = ftc_mc.load_config(ROOT / "configs" / "paper_scenario.yaml")
    assert isinstance(sc, ScenarioConfig)
    assert ftc_mc.load_config(sc) is sc
    assert isinstance(ftc_mc.load_config(SCENARIO), ScenarioConfig)
    cfg = ftc_mc.load_config(_yaml(tmp_path, SMALL))
    assert isinstance(cfg, Config) and cfg.campaign.trials == 4
    assert ftc_mc.load_config(SMALL) == cfg
    with pytest.raises(UserError, match="campaign.trials"):
        ftc_mc.load_config({"campaign": {"trials": -1}})
    with pytest.raises(UserError, match=r"scenario\.duration_s"):
        ftc_mc.load_config(_yaml(tmp_path, {"scenario": {"duration_s": "long"}}))
    with pytest.raises(UserError, match="no such file"):
        ftc_mc.load_config(tmp_path / "missing.yaml")
    with pytest.raises(UserError, match="run_scenario"):
        ftc_mc.run_campaign(sc)
    with pytest.raises(UserError, match="scenario config"):
        ftc_mc.run_scenario(cfg)


def test_api_writes_what_the_cli_writes(tmp_path):
    cfg = _yaml(tmp_path, SMALL)
    res = ftc_mc.run_campaign(cfg, jobs=1, progress=False, out=tmp_path / "api")
    cli_res = CliRunner().invoke(cli, ["run", str(cfg), "--jobs", "1", "--quiet", "--out",
                                       str(tmp_path / "cli")])
    assert cli_res.exit_code == 0, cli_res.output
    for f in ("trials.parquet", "resets.parquet", "summary.parquet"):
        api_df, cli_df = (pd.read_parquet(tmp_path / d / f) for d in ("api", "cli"))
        pd.testing.assert_frame_equal(api_df, cli_df, check_exact=True)
        meta = read_metadata(tmp_path / "api" / f)
        assert meta["kind"] == "run" and meta["config"] == res.config.model_dump(mode="json")
    assert ((tmp_path / "api" / "summary.md").read_text()
            == (tmp_path / "cli" / "summary.md").read_text())
    pd.testing.assert_frame_equal(res.summary, pd.read_parquet(tmp_path / "api" /
                                                               "summary.parquet"))
    # without out nothing is written, and the data is the same
    alone = ftc_mc.run_campaign(SMALL, jobs=1, progress=False)
    pd.testing.assert_frame_equal(alone.trials, res.trials, check_exact=True)
    # the API refuses what the CLI refuses
    with pytest.raises(UserError, match="already holds results"):
        ftc_mc.run_campaign(cfg, progress=False, out=tmp_path / "api")
    with pytest.raises(UserError, match="--jobs"):
        ftc_mc.run_campaign(cfg, jobs=0, out=tmp_path / "new")
    assert not (tmp_path / "new").exists()
    rep = ftc_mc.build_report(tmp_path / "api", tmp_path / "report.md")
    assert rep == tmp_path / "report.md" and "# ftc-mc report" in rep.read_text()


def test_resume_of_a_finished_run_is_a_no_op(tmp_path):
    cfg = _yaml(tmp_path, SMALL)
    out = tmp_path / "out"
    args = ["run", str(cfg), "--jobs", "1", "--quiet", "--out", str(out)]
    assert CliRunner().invoke(cli, args).exit_code == 0
    before = _files(out)
    res = CliRunner().invoke(cli, [*args, "--resume"])
    assert res.exit_code == 0, res.output
    assert res.output.strip() == f"{out}: the run is already complete; nothing to resume"
    assert _files(out) == before
    assert ftc_mc.run_campaign(cfg, progress=False, out=out, resume=True) is None
    # chunks left by a process that died after its last file are cleared
    (out / ".chunks").mkdir()
    (out / ".chunks" / "manifest.json").write_text("{}")
    assert CliRunner().invoke(cli, [*args, "--resume"]).exit_code == 0
    assert _files(out) == before and not (out / ".chunks").exists()
    # ... but not for another configuration
    res = CliRunner().invoke(cli, [*args, "--resume", "--trials", "3"])
    assert res.exit_code == 2 and "another configuration" in res.output
    assert _files(out) == before


def test_resume_of_a_finished_sweep_is_a_no_op(tmp_path):
    cfg = _yaml(tmp_path, SMALL)
    out = tmp_path / "out"
    args = ["sweep", str(cfg), *SWEEP, "--out", str(out)]
    res = CliRunner().invoke(cli, args)
    assert res.exit_code == 0, res.output
    before = _files(out)
    res = CliRunner().invoke(cli, [*args, "--resume"])
    assert res.exit_code == 0, res.output
    assert res.output.strip() == f"{out}: the sweep is already complete; nothing to resume"
    assert _files(out) == before
    res = CliRunner().invoke(cli, ["sweep", str(cfg), "--thresholds", "10,30", "--flights",
                                   "2", "--quiet", "--out", str(out), "--resume"])
    assert res.exit_code == 2 and "another configuration" in res.output
    # the API: a sequence of thresholds is the same sweep
    assert ftc_mc.run_sweep(cfg, [25, 10], flights=2, progress=False, out=out,
                            resume=True) is None
    sw = ftc_mc.run_sweep(cfg, [10, 25], flights=2, progress=False)
    pd.testing.assert_frame_equal(sw.table, pd.read_parquet(out / "sweep.parquet"),
                                  check_exact=True)


def test_api_scenario(tmp_path):
    res = ftc_mc.run_scenario(SCENARIO, out=tmp_path / "s")
    assert res.status == "ok" and len(res.timeseries) == 200
    pd.testing.assert_frame_equal(res.timeseries,
                                  pd.read_parquet(tmp_path / "s" / "timeseries.parquet"))
    assert read_metadata(tmp_path / "s" / "events.parquet")["kind"] == "scenario"
    assert len(list((tmp_path / "s").glob("fig*.png"))) == 7
    other = ftc_mc.run_scenario(SCENARIO, seed=3)
    assert not other.timeseries.equals(res.timeseries)


def test_bad_parameters_below_the_config_are_one_line(tmp_path):
    # values the schema lets through but the model or the draws refuse
    for args, needle in ((["model", "--airspeed", "300"], "cannot fly this condition"),
                         (["model", "--gamma", "45"], "model.gamma_deg"),
                         (["run", str(_yaml(tmp_path, {**SMALL, "draws": {
                             "engine_lock_range": [0.0, 2.0]}})), "--out",
                           str(tmp_path / "o")], "draws.engine_lock_range")):
        res = CliRunner().invoke(cli, args)
        assert res.exit_code == 2, res.output
        assert needle in res.output and len(res.output.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_an_unexpected_value_error_is_not_hidden(tmp_path, monkeypatch):
    import ftc_mc.campaign.runner
    import ftc_mc.model.source

    def bug(*args, **kwargs):
        raise ValueError("a bug, not the user's input")

    monkeypatch.setattr(ftc_mc.model.source, "load_plant", bug)
    res = CliRunner().invoke(cli, ["model"])
    assert res.exit_code == 1 and type(res.exception) is ValueError
    assert "ftc-mc: error" not in res.output
    monkeypatch.setattr(ftc_mc.campaign.runner, "run_campaign", bug)
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", str(_yaml(tmp_path, SMALL)), "--out", str(out)])
    assert res.exit_code == 1 and type(res.exception) is ValueError
    assert "ftc-mc: error" not in res.output
    assert not out.exists()  # the lock is released and the empty chunk store removed


def test_run_table_fits_the_terminal_and_summary_md_keeps_all(tmp_path):
    data = {**SMALL, "campaign": {"transitions": list(ftc_mc.load_config(
        ROOT / "configs" / "paper_tables.yaml").campaign.transitions), "trials": 2,
        "signature": "both"}}
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", str(_yaml(tmp_path, data)), "--jobs", "1",
                                   "--quiet", "--out", str(out)])
    assert res.exit_code == 0, res.output
    lines = [line for line in res.output.splitlines() if line.startswith("|")]
    assert len(lines) == 2 + 16 and max(map(len, lines)) <= TERMINAL_WIDTH
    assert sum(line.startswith("| engine_loss_recover ") for line in lines) == 2
    md = (out / "summary.md").read_text()
    assert "Engine less efficient → Engine nominal" in md and "95% CI" in md
    # the widest values fit too: 1000 judged trials, 100 %, three-digit counts
    s = pd.read_parquet(out / "summary.parquet").assign(
        trials=1000, inappropriate_rate=1.0, no_reset_rate=1.0,
        no_reset_explained_share=1.0, delay_median_s=999.9, paper_inappropriate=999,
        paper_no_reset=999)
    assert max(map(len, terminal_table(s).splitlines())) <= TERMINAL_WIDTH
