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


LONGER = CONFIG.replace("trials: 24", "trials: 400").replace("chunk_size: 2", "chunk_size: 16")
"""Long enough (50 chunks, a few seconds on two workers) for a signal sent after
the third chunk to arrive while the run is going on."""


@pytest.fixture(scope="module")
def longer_reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("longer")
    cfg = d / "cfg.yaml"
    cfg.write_text(LONGER)
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(d / "out"), "--jobs", "2",
                                   "--quiet"])
    assert res.exit_code == 0, res.output
    return cfg, _data(d / "out")


def _stopped(p, sig):
    """Send ``sig`` to ``p``; its exit code, stderr and seconds to exit."""
    t0 = time.monotonic()
    p.send_signal(sig)
    try:
        err = p.communicate(timeout=60)[1]
    finally:
        p.kill()  # never left running by a failed test
    return p.returncode, err if isinstance(err, str) else err.decode(), time.monotonic() - t0


@pytest.mark.parametrize("backend, sig", [("threads", signal.SIGINT),
                                          ("threads", signal.SIGTERM),
                                          ("loky", signal.SIGTERM)])
def test_a_signal_stops_the_run_keeps_finished_chunks_and_resumes(tmp_path, longer_reference,
                                                                  backend, sig):
    cfg, ref = longer_reference
    out = tmp_path / "out"
    chunks = out / ".chunks"
    p = _run([str(cfg), "--out", str(out), "--jobs", "2", "--backend", backend, "--quiet"])
    deadline = time.time() + 120
    while len(list(chunks.glob("*.trials.parquet"))) < 3 and time.time() < deadline:
        assert p.poll() is None, p.communicate()[1].decode()
        time.sleep(0.01)
    code, err, wait = _stopped(p, sig)
    assert code == 128 + sig, err
    assert wait < 3.0, f"{wait:.1f} s from the signal to the exit"
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"interrupted ({signal.Signals(sig).name}): ")
    assert f"--resume --out {out}" in lines[0]
    kept = sorted(chunks.glob("*.trials.parquet"))
    assert len(kept) >= 3 and f"{len(kept)} finished chunk(s)" in lines[0]
    assert not (out / "summary.md").exists(), "the run finished before the signal"
    assert not (out / ".ftc-mc.lock").exists()
    for f in chunks.glob("*.parquet"):
        pq.read_table(f)  # whole: an in-flight chunk is absent, not half-written
    res = CliRunner().invoke(cli, ["run", str(cfg), "--out", str(out), "--resume",
                                   "--jobs", "2", "--quiet"])
    assert res.exit_code == 0, res.output
    got = _data(out)
    for f, df in ref.items():
        pd.testing.assert_frame_equal(got[f], df, check_exact=True)


def test_a_signal_does_not_wait_for_long_chunks(tmp_path):
    """Two chunks of 2048 trials each, several seconds of nogil kernel: the main
    thread does not wait for them, and nothing of them is written."""
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(CONFIG.replace("trials: 24", "trials: 4096")
                   .replace("chunk_size: 2", "chunk_size: 2048")
                   .replace("duration_s: 6", "duration_s: 60"))
    out = tmp_path / "out"
    p = _run([str(cfg), "--out", str(out), "--jobs", "2", "--quiet"])
    while not (out / ".chunks" / "manifest.json").exists():
        assert p.poll() is None, p.communicate()[1].decode()
        time.sleep(0.01)
    time.sleep(1.5)  # the kernels are loaded and the two chunks under way
    code, err, wait = _stopped(p, signal.SIGINT)
    assert code == 130, err
    assert wait < 3.0, f"{wait:.1f} s from the signal to the exit"
    assert "0 finished chunk(s)" in err and "--resume" in err
    assert [f.name for f in (out / ".chunks").iterdir()] == ["manifest.json"]


def test_a_second_signal_stops_at_once(tmp_path):
    """While the command cleans up after the first signal, a second one ends it."""
    script = tmp_path / "slow_cleanup.py"
    script.write_text(
        "import os, signal, time\n"
        "from ftc_mc.interrupt import Interrupted, stop_on_signals\n"
        "with stop_on_signals():\n"
        "    try:\n"
        "        print('ready', flush=True)\n"
        "        time.sleep(60)\n"
        "    except Interrupted:\n"
        "        print('cleaning up', flush=True)\n"
        "        time.sleep(60)\n")
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline() == "ready\n"
    p.send_signal(signal.SIGINT)
    assert p.stdout.readline() == "cleaning up\n"
    code, err, wait = _stopped(p, signal.SIGINT)
    assert code == 130 and wait < 1.0 and "again: stopping now" in err


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
