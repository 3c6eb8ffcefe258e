"""Interrupted runs: SIGKILL at random moments, then --resume, gives the same data.

Only the interrupted runs get a process of their own; the reference runs and the
resumes run in this one (CliRunner), which spares a start (imports, kernel loads,
trim) of about 3 s of CPU each.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

from ftc_mc.cli import cli

CONFIG = """campaign:
  transitions: [elevon_lock, engine_loss]
  trials: 24
  chunk_size: 2
controller:
  kind: nominal
timing:
  fault_time_s: 2
  window_s: 2
  duration_s: 6
"""


def _run(args, **kw):
    return subprocess.Popen([sys.executable, "-m", "ftc_mc", "run", *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, **kw)


def _data(out: Path):
    return {f: pq.read_table(out / f).to_pandas()
            for f in ("trials.parquet", "resets.parquet", "summary.parquet")}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("ref")
    cfg = d / "cfg.yaml"
    cfg.write_text(CONFIG)
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(d / "out"), "--jobs", "1",
                                   "--quiet"])
    assert res.exit_code == 0, res.output
    return cfg, _data(d / "out")


@pytest.mark.parametrize("kill_after", [1, 5, 11])
def test_sigkill_then_resume_gives_the_same_data(tmp_path, reference, kill_after):
    cfg, ref = reference
    out = tmp_path / "out"
    p = _run([str(cfg), "--out", str(out), "--jobs", "1", "--quiet"])
    chunks = out / ".chunks"
    deadline = time.time() + 120
    while time.time() < deadline:
        if len(list(chunks.glob("*.trials.parquet"))) >= kill_after or p.poll() is not None:
            break
        time.sleep(0.01)
    p.send_signal(signal.SIGKILL)
    p.wait()
    n_done = len(list(chunks.glob("*.trials.parquet")))
    assert p.returncode == -signal.SIGKILL and n_done >= kill_after
    assert not (out / "summary.md").exists(), "the run finished before the kill"
    # nothing partial under a final name: final files absent or complete
    for f in ("trials.parquet", "resets.parquet", "summary.parquet"):
        if (out / f).exists():
            pq.read_table(out / f)
    for f in chunks.glob("*.parquet"):
        pq.read_table(f)  # every chunk file under its final name is whole
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out), "--resume",
                                   "--jobs", "1", "--quiet"])
    assert res.exit_code == 0, res.output
    got = _data(out)
    for f, df in ref.items():
        pd.testing.assert_frame_equal(got[f], df, check_exact=True)
    assert not chunks.exists()


def test_resume_refuses_another_config(tmp_path, reference):
    cfg, _ = reference
    out = tmp_path / "out"
    p = _run([str(cfg), "--out", str(out), "--jobs", "1", "--quiet"])
    while not list((out / ".chunks").glob("*.trials.parquet")) and p.poll() is None:
        time.sleep(0.01)
    p.send_signal(signal.SIGKILL)
    p.wait()
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out), "--resume",
                                   "--trials", "10", "--quiet"])
    assert res.exit_code == 2 and "another configuration" in res.output
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out), "--quiet"])
    assert res.exit_code == 2 and "--resume" in res.output
    res = CliRunner().invoke(cli, ["run", str(cfg), "--resume", "--quiet"])
    assert res.exit_code == 2 and "--out" in res.output


def test_resume_without_interrupted_run(tmp_path, reference):
    cfg, _ = reference
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(tmp_path / "x"),
                                   "--resume", "--quiet"])
    assert res.exit_code == 2 and "no interrupted run" in res.output


def test_sigint_keeps_finished_chunks(tmp_path, reference):
    cfg, ref = reference
    out = tmp_path / "out"
    p = _run([str(cfg), "--out", str(out), "--jobs", "1", "--quiet"])
    while len(list((out / ".chunks").glob("*.trials.parquet"))) < 3 and p.poll() is None:
        time.sleep(0.01)
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=60)[1].decode()
    if p.returncode == 130:
        assert "--resume" in err and "Traceback" not in err
        assert list((out / ".chunks").glob("*.trials.parquet"))
        assert not (out / ".ftc-mc.lock").exists()
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out), "--resume",
                                   "--jobs", "1", "--quiet"])
    if p.returncode == 130:
        assert res.exit_code == 0, res.output
        for f, df in ref.items():
            pd.testing.assert_frame_equal(_data(out)[f], df, check_exact=True)
    assert os.path.exists(out / "summary.md")


SWEEP = ["--thresholds", "6,12,25", "--flights", "8", "--jobs", "1", "--quiet"]


def _sweep(args):
    return subprocess.Popen([sys.executable, "-m", "ftc_mc", "sweep", *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


@pytest.fixture(scope="module")
def sweep_reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("sref")
    cfg = d / "cfg.yaml"
    cfg.write_text(CONFIG)
    res = CliRunner().invoke(cli, ["sweep", str(cfg), "--out", str(d / "out"), *SWEEP])
    assert res.exit_code == 0, res.output
    return cfg, pq.read_table(d / "out" / "sweep.parquet").to_pandas()


@pytest.mark.parametrize("kill_after", [2, 9])
def test_sweep_sigkill_then_resume(tmp_path, sweep_reference, kill_after):
    cfg, ref = sweep_reference
    out = tmp_path / "out"
    p = _sweep([str(cfg), "--out", str(out), *SWEEP])
    chunks = out / ".chunks"
    while len(list(chunks.glob("*.trials.parquet"))) < kill_after and p.poll() is None:
        time.sleep(0.01)
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert p.returncode == -signal.SIGKILL and not (out / "sweep.parquet").exists()
    for f in chunks.glob("*.parquet"):
        pq.read_table(f)
    res = CliRunner().invoke(cli, ["sweep", str(cfg), "--out", str(out), "--resume",
                                   *SWEEP])
    assert res.exit_code == 0, res.output
    pd.testing.assert_frame_equal(pq.read_table(out / "sweep.parquet").to_pandas(), ref,
                                  check_exact=True)
    bad = CliRunner().invoke(cli, ["sweep", str(cfg), "--out", str(tmp_path / "o2"),
                                   "--resume", *SWEEP])
    assert bad.exit_code == 2 and "no interrupted run" in bad.output


SCENARIO = Path(__file__).resolve().parents[1] / "configs" / "paper_scenario.yaml"


@pytest.fixture(scope="module")
def scenario_reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("scen") / "out"
    res = CliRunner().invoke(cli, ["scenario", str(SCENARIO), "--out", str(d)])
    assert res.exit_code == 0, res.output
    return {f: pq.read_table(d / f).to_pandas()
            for f in ("timeseries.parquet", "events.parquet", "segments.parquet")}


@pytest.mark.parametrize("delay", [0.8, 1.6, 2.4, 3.2])
def test_scenario_sigkill_leaves_only_whole_files(tmp_path, scenario_reference, delay):
    out = tmp_path / "out"
    p = subprocess.Popen([sys.executable, "-m", "ftc_mc", "scenario", str(SCENARIO),
                          "--out", str(out)], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    time.sleep(delay)
    p.send_signal(signal.SIGKILL)
    p.wait()
    for f in out.glob("*.parquet") if out.exists() else []:
        pq.read_table(f)  # whole, or absent
    for f in out.glob("*.png") if out.exists() else []:
        assert f.read_bytes().endswith(b"IEND\xaeB`\x82"), f
    # the stale lock is taken over and a rerun gives the same data
    res = CliRunner().invoke(cli, ["scenario", str(SCENARIO), "--out", str(out),
                                   "--overwrite"])
    assert res.exit_code == 0, res.output
    for f, df in scenario_reference.items():
        pd.testing.assert_frame_equal(pq.read_table(out / f).to_pandas(), df,
                                      check_exact=True)
