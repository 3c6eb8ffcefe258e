"""Big runs: result tables streamed from the chunk store equal the tables
sorted in memory and the golden files; the reset log's size is the user's choice
and never changes the summary; result files honour the umask; resuming lists the
chunk folder once.
"""

import json
import os
import stat

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign.chunk import chunk_spec, run_chunk
from ftc_mc.campaign.runner import plan_chunks
from ftc_mc.campaign.summary import summarize
from ftc_mc.cli import cli
from ftc_mc.errors import UserError
from ftc_mc.io.chunks import ChunkStore
from ftc_mc.io.results import read_metadata

from golden_cases import CAMPAIGNS, golden_path, read

MIXED = {"campaign": {"transitions": ["engine_loss", "sensor_bias:q", "elevon_lock"],
                      "trials": 10, "chunk_size": 3},
         "controller": {"kind": "nominal"},
         "timing": {"fault_time_s": 2, "window_s": 2, "duration_s": 6}}
"""Actuator and sensor transitions (columns only some chunks hold), chunks of
uneven size, both signature variants."""


def _same_bits(got: pd.DataFrame, want: pd.DataFrame) -> None:
    pd.testing.assert_frame_equal(got, want, check_exact=True)
    for col in want.columns:
        a, b = got[col].to_numpy(), want[col].to_numpy()
        if a.dtype.kind == "f":
            assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), col


def test_streamed_files_equal_the_golden_tables(tmp_path):
    """The golden campaign written through the chunk store (two workers: chunks
    finish in any order) gives the golden trials and resets, and the summary of
    the golden trials, with the provenance in every file."""
    out = tmp_path / "out"
    res = ftc_mc.run_campaign(CAMPAIGNS["linear"], jobs=2, progress=False, out=out)
    for table in ("trials", "resets"):
        want = read(golden_path("campaign", "linear", table))
        _same_bits(pd.read_parquet(out / f"{table}.parquet"), want)
        assert (pq.read_schema(out / f"{table}.parquet").remove_metadata()
                == pa.Table.from_pandas(want, preserve_index=False).schema.remove_metadata())
        assert read_metadata(out / f"{table}.parquet")["kind"] == "run"
    want = summarize(read(golden_path("campaign", "linear", "trials")))
    _same_bits(res.summary, want)
    _same_bits(pd.read_parquet(out / "summary.parquet"), want)


def test_streamed_mixed_run_equals_memory_in_small_row_groups(tmp_path, monkeypatch):
    monkeypatch.setattr("ftc_mc.io.stream.ROW_GROUP_ROWS", 7)
    mem = ftc_mc.run_campaign(MIXED, jobs=1, progress=False)
    out = tmp_path / "out"
    disk = ftc_mc.run_campaign(MIXED, jobs=2, progress=False, out=out)
    assert pq.ParquetFile(out / "trials.parquet").metadata.num_row_groups > 2
    for table in ("trials", "resets"):
        got = pd.read_parquet(out / f"{table}.parquet")
        _same_bits(got, getattr(mem, table))
        pd.testing.assert_series_equal(got.dtypes, getattr(mem, table).dtypes)
    _same_bits(disk.summary, mem.summary)
    assert set(mem.trials["transition"]) == set(MIXED["campaign"]["transitions"])


def test_streamed_sweep_equals_memory(tmp_path):
    cfg = {**MIXED, "campaign": {**MIXED["campaign"],
                                 "transitions": ["engine_loss", "elevon_lock"]}}
    mem = ftc_mc.run_sweep(cfg, "8,25", flights=4, jobs=1, progress=False)
    disk = ftc_mc.run_sweep(cfg, "8,25", flights=4, jobs=2, progress=False,
                            out=tmp_path / "sw")
    _same_bits(disk.table, mem.table)
    _same_bits(pd.read_parquet(tmp_path / "sw" / "sweep.parquet"), mem.table)
    assert (disk.simulated_steps, disk.alone_steps) == (mem.simulated_steps,
                                                        mem.alone_steps)


@pytest.mark.parametrize("log, kept", [("none", 0), ("first-1", 1), ("first-3", 3)])
def test_reset_log_cuts_only_the_reset_table(tmp_path, log, kept):
    full = ftc_mc.run_campaign(MIXED, jobs=1, progress=False)
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(yaml.safe_dump(MIXED))
    res = CliRunner().invoke(cli, ["run", str(cfg), "--quiet", "--jobs", "2", "--reset-log",
                                   log, "--out", str(tmp_path / "o")])
    assert res.exit_code == 0, res.output
    out = tmp_path / "o"
    _same_bits(pd.read_parquet(out / "trials.parquet"), full.trials)
    _same_bits(pd.read_parquet(out / "summary.parquet"), full.summary)
    got = pd.read_parquet(out / "resets.parquet")
    rank = full.resets.groupby(["transition", "variant", "trial_id"], sort=False).cumcount()
    want = full.resets[rank < kept].reset_index(drop=True)
    assert len(want) < len(full.resets) and (kept == 0 or len(want) > 0)
    _same_bits(got, want) if len(want) else pd.testing.assert_index_equal(
        got.columns, full.resets.columns)
    assert read_metadata(out / "trials.parquet")["config"]["campaign"]["reset_log"] == log


@pytest.mark.parametrize("bad", ["first-0", "first", "some", "first-x", "first-01"])
def test_a_bad_reset_log_is_one_line(tmp_path, bad):
    with pytest.raises(UserError, match="reset_log"):
        ftc_mc.run_campaign(MIXED, reset_log=bad, out=tmp_path / "x")
    assert not (tmp_path / "x").exists()


def _modes(folder):
    return {p.relative_to(folder).as_posix(): stat.S_IMODE(p.stat().st_mode)
            for p in folder.rglob("*") if p.is_file() and p.name != ".ftc-mc.lock"}


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o027, 0o640)])
def test_files_honour_the_umask(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        cfg = {**MIXED, "campaign": {**MIXED["campaign"], "transitions": ["elevon_lock"],
                                     "trials": 3}}
        ftc_mc.run_campaign(cfg, jobs=1, progress=False, out=tmp_path / "run")
        ftc_mc.build_report(tmp_path / "run", tmp_path / "rep" / "report.md")
        store = ChunkStore(tmp_path / "chunks", "{}")
        store.open(resume=False)
        store.write("elevon_lock", 0, pd.DataFrame({"a": [1]}), resets=pd.DataFrame({"b": [2]}))
    finally:
        os.umask(old)
    modes = {**_modes(tmp_path / "run"), **_modes(tmp_path / "rep"),
             **_modes(tmp_path / "chunks")}
    assert any(k.endswith(".png") for k in modes) and any("chunks" in k for k in modes)
    assert {k: v for k, v in modes.items() if v != mode} == {}, oct(mode)


def test_resume_lists_the_chunk_folder_once(tmp_path):
    """``finished`` names every finished chunk, ignoring resets-only chunks and
    temporary files, without a look per chunk."""
    store = ChunkStore(tmp_path, "{}")
    store.open(resume=False)
    folder = tmp_path / ".chunks"
    for start in range(0, 3000, 3):
        (folder / f"sensor_bias:q-{start:09d}.trials.parquet").touch()
    (folder / "elevon_lock-000000006.resets.parquet").touch()
    (folder / ".elevon_lock-000000009.trials.parquet.x.parquet.tmp").touch()
    assert store.finished() == {("sensor_bias:q", s) for s in range(0, 3000, 3)}
    ChunkStore(tmp_path, "{}").open(resume=True)
    assert not list(folder.glob(".*.tmp"))


def test_resume_after_an_interrupt_while_writing_the_result_files(tmp_path):
    """Interrupted after ``resets.parquet`` was written but before the summary: the
    chunks are still there, and ``--resume`` writes the files again."""
    out = tmp_path / "out"
    ref = ftc_mc.run_campaign(MIXED, jobs=1, progress=False, out=out)
    want = {f: pd.read_parquet(out / f"{f}.parquet") for f in ("trials", "resets", "summary")}
    for f in ("summary.parquet", "summary.md", "trials.parquet"):
        (out / f).unlink()
    identity = json.dumps(ref.config.model_dump(mode="json"), sort_keys=True)
    store = ChunkStore(out, identity)
    store.open(resume=False)
    spec = chunk_spec(ref.config)
    for n, ids in plan_chunks(ref.config):
        parts = run_chunk(spec, n, ids)
        store.write(n, int(ids[0]), parts["trials"], resets=parts["resets"])
    with pytest.raises(UserError, match="already holds results"):
        ftc_mc.run_campaign(MIXED, progress=False, out=out)
    res = ftc_mc.run_campaign(MIXED, progress=False, out=out, resume=True)
    assert res is not None and not (out / ".chunks").exists()
    for f, df in want.items():
        _same_bits(pd.read_parquet(out / f"{f}.parquet"), df)
