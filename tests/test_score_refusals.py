"""``ftc-mc score`` refuses every bad input it is handed: the name, the output
folder, the run folder and each of its files, and every part of a detector's
return.  Each refusal: exit code 2, one line naming the problem (no traceback),
nothing written anywhere, the run's files byte for byte as they were."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign.signals import signal_files
from ftc_mc.cli import cli
from ftc_mc.io.results import META_KEY

CFG = {"campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 4,
                    "chunk_size": 2, "seed": 11, "signature": "paper"},
       "controller": {"kind": "reconfiguring"},
       "model": {"airframe": "x8-gryte2018"},
       "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}
"""A small recorded run on the golden cases' linear path (kernels already compiled)."""

DURATION = 15.0

DETECTORS = '''
import sys
import numpy as np

def fine(s, names, dt):
    return np.full(s.shape[0], np.nan)

def late_ok(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], "elevons")

def raises(s, names, dt):
    raise RuntimeError("boom")

def raises_lines(s, names, dt):
    raise ValueError("first line\\nsecond line\\nthird line")

def exits(s, names, dt):
    sys.exit(3)

def none(s, names, dt):
    return None

def text(s, names, dt):
    return "soon"

def mapping(s, names, dt):
    return {"alarm": 1.0}

def too_many(s, names, dt):
    return np.full(s.shape[0] + 1, 6.0)

def too_few(s, names, dt):
    return np.full(s.shape[0] - 1, 6.0)

def two_d(s, names, dt):
    return np.full((s.shape[0], 1), 6.0)

def scalar(s, names, dt):
    return 6.0

def booleans(s, names, dt):
    return np.ones(s.shape[0], dtype=bool)

def complex_(s, names, dt):
    return np.full(s.shape[0], 6.0 + 1j)

def strings(s, names, dt):
    return np.full(s.shape[0], "6.0")

def inf(s, names, dt):
    return np.full(s.shape[0], np.inf)

def negative(s, names, dt):
    return np.full(s.shape[0], -1.0)

def zero(s, names, dt):
    return np.zeros(s.shape[0])

def half_step(s, names, dt):
    return np.full(s.shape[0], 0.5 * dt)

def after_end(s, names, dt):
    return np.full(s.shape[0], 1000.0)

def three(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], ""), None

def rudder(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], "rudder")

def block_none(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], "none")

def block_zero(s, names, dt):
    return np.full(s.shape[0], 6.0), np.zeros(s.shape[0], dtype=int)

def block_seven(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0], 7)

def block_bool(s, names, dt):
    return np.full(s.shape[0], 6.0), np.ones(s.shape[0], dtype=bool)

def block_short(s, names, dt):
    return np.full(s.shape[0], 6.0), np.full(s.shape[0] - 1, "thrust")

def block_scalar(s, names, dt):
    return np.full(s.shape[0], 6.0), "thrust"

def columns_text(s, names, dt):
    return np.full(s.shape[0], np.nan)
columns_text.columns = "innov_q"

def columns_unknown(s, names, dt):
    return np.full(s.shape[0], np.nan)
columns_unknown.columns = ("innov_q", "no_such_signal")

def columns_key(s, names, dt):
    return np.full(s.shape[0], np.nan)
columns_key.columns = ("trial_id", "innov_q")

def columns_twice(s, names, dt):
    return np.full(s.shape[0], np.nan)
columns_twice.columns = ("innov_q", "innov_q")

def columns_empty(s, names, dt):
    return np.full(s.shape[0], np.nan)
columns_empty.columns = ()

def reads_innov(s, names, dt):
    return np.full(s.shape[0], np.nan)
reads_innov.columns = ("innov_q",)

def reads_mode(s, names, dt):
    return np.full(s.shape[0], np.nan)
reads_mode.columns = ("mode",)

NOT_A_FUNCTION = 3
'''


@pytest.fixture(scope="module")
def master(tmp_path_factory):
    """A recorded run and a recorded endurance run, never written to."""
    base = tmp_path_factory.mktemp("score_refusals")
    ftc_mc.run_campaign(CFG, out=base / "run", record="signals", jobs=1, progress=False)
    cfg = {k: v for k, v in CFG.items() if k != "timing"}
    ftc_mc.run_endurance(cfg, 0.01, flight_s=DURATION, out=base / "end", record="signals",
                         jobs=1, progress=False)
    mods = base / "mods"
    mods.mkdir()
    (mods / "refusal_detectors.py").write_text(DETECTORS)
    (mods / "refusal_import_fails.py").write_text("raise ImportError('no numpy here')\n")
    return base


def _tree(folder: Path) -> dict:
    """Every path under ``folder`` (files, folders, links) with its content's hash."""
    out = {}
    for root, dirs, files in os.walk(folder, followlinks=False):
        for d in dirs:
            p = Path(root) / d
            out[str(p.relative_to(folder))] = ("link", os.readlink(p)) if p.is_symlink() \
                else ("dir",)
        for f in files:
            p = Path(root) / f
            out[str(p.relative_to(folder))] = (
                ("link", os.readlink(p)) if p.is_symlink()
                else ("file", hashlib.sha256(p.read_bytes()).hexdigest()))
    return out


# ------------------------------------------------------------------ damage


def _rewrite(f: Path, change) -> None:
    """Rewrite the Parquet file ``f`` as ``change(table)``, metadata kept."""
    table = pq.read_table(f)
    pq.write_table(change(table).replace_schema_metadata(table.schema.metadata), f)


def _set_meta(f: Path, change) -> None:
    table = pq.read_table(f)
    md = dict(table.schema.metadata)
    md = change(md)
    pq.write_table(table.replace_schema_metadata(md), f)


def _config(change):
    def go(md):
        meta = json.loads(md[META_KEY])
        change(meta)
        return {**md, META_KEY: json.dumps(meta).encode()}
    return go


def _first_signals(run: Path) -> Path:
    return signal_files(run)[0]


def _set_column(name, values_of):
    def go(t):
        i = t.schema.get_field_index(name)
        return t.set_column(i, name, values_of(t))
    return go


def _drop_column(name):
    return lambda t: t.drop_columns([name])


def _filter_rows(keep_of):
    return lambda t: t.filter(pa.array(keep_of(t)))


# ------------------------------------------------------------------ cases
# (id, which run, setup(run, tmp), extra arguments(run, tmp), detector, message part)

def _none(run, tmp):
    pass


def _args(*a):
    return lambda run, tmp: [str(x).format(run=run, tmp=tmp) for x in a]


GOOD = "refusal_detectors:fine"

CASES = [
    # --- the name: a plain name, never a path
    ("name_parent", "run", _none, _args("--name", "../escape"), GOOD, "not a plain name"),
    ("name_absolute", "run", _none, _args("--name", "{tmp}/abs"), GOOD, "not a plain name"),
    ("name_nested", "run", _none, _args("--name", "a/b"), GOOD, "not a plain name"),
    ("name_dotdot", "run", _none, _args("--name", ".."), GOOD, "not a plain name"),
    ("name_empty", "run", _none, _args("--name", ""), GOOD, "not a plain name"),
    ("name_hidden", "run", _none, _args("--name", ".hidden"), GOOD, "not a plain name"),
    ("name_at", "run", _none, _args("--name", "x@paper"), GOOD, "not a plain name"),
    ("name_space", "run", _none, _args("--name", "my detector"), GOOD, "not a plain name"),
    ("name_backslash", "run", _none, _args("--name", "a\\b"), GOOD, "not a plain name"),
    ("name_too_long", "run", _none, _args("--name", "a" * 101), GOOD, "not a plain name"),
    # --- the output folder: the run's own files are never written
    ("out_run_itself", "run", _none, _args("-o", "{run}"), GOOD, "inside the run folder"),
    ("out_signals", "run", _none, _args("-o", "{run}/signals"), GOOD,
     "inside the run folder"),
    ("out_detectors_itself", "run", _none, _args("-o", "{run}/detectors"), GOOD,
     "inside the run folder"),
    ("out_is_a_file", "run", lambda run, tmp: (tmp / "afile").write_text("x"),
     _args("-o", "{tmp}/afile"), GOOD, "is a file"),
    ("out_below_a_file", "run", lambda run, tmp: (tmp / "afile").write_text("x"),
     _args("-o", "{tmp}/afile/sub"), GOOD, "is a file"),
    ("detectors_link_out", "run",
     lambda run, tmp: ((tmp / "elsewhere").mkdir(),
                       (run / "detectors").symlink_to(tmp / "elsewhere")),
     _args(), GOOD, "leads out of"),
    # --- the run folder and its tables
    ("run_missing", "run", lambda run, tmp: shutil.rmtree(run), _args(), GOOD,
     "no such folder"),
    ("run_is_a_file", "run", lambda run, tmp: (shutil.rmtree(run), run.write_text("x")),
     _args(), GOOD, "not a folder"),
    ("run_empty", "run", lambda run, tmp: (shutil.rmtree(run), run.mkdir()), _args(), GOOD,
     "not a finished run"),
    ("trials_damaged", "run", lambda run, tmp: (run / "trials.parquet").write_bytes(
        b"not parquet at all" * 10), _args(), GOOD, "not a readable Parquet file"),
    ("trials_truncated", "run", lambda run, tmp: (run / "trials.parquet").write_bytes(
        (run / "trials.parquet").read_bytes()[:300]), _args(), GOOD,
     "not a readable Parquet file"),
    ("trials_a_folder", "run", lambda run, tmp: ((run / "trials.parquet").unlink(),
                                                 (run / "trials.parquet").mkdir()),
     _args(), GOOD, "not a file"),
    ("trials_no_metadata", "run", lambda run, tmp: _set_meta(
        run / "trials.parquet", lambda md: {k: v for k, v in md.items()
                                            if k != META_KEY}),
     _args(), GOOD, "no ftc-mc metadata"),
    ("trials_metadata_not_json", "run", lambda run, tmp: _set_meta(
        run / "trials.parquet", lambda md: {**md, META_KEY: b"{not json"}),
     _args(), GOOD, "damaged ftc-mc metadata"),
    ("trials_metadata_no_config", "run", lambda run, tmp: _set_meta(
        run / "trials.parquet", _config(lambda m: m.pop("config"))),
     _args(), GOOD, "damaged ftc-mc metadata"),
    ("trials_metadata_kind", "run", lambda run, tmp: _set_meta(
        run / "trials.parquet", _config(lambda m: m.update(kind="sweep"))),
     _args(), GOOD, "metadata of kind 'sweep'"),
    ("trials_metadata_bad_dt", "run", lambda run, tmp: _set_meta(
        run / "trials.parquet", _config(lambda m: m["config"]["model"].update(dt_s=-0.1))),
     _args(), GOOD, "model.dt_s"),
    ("trials_no_mode_pre", "run", lambda run, tmp: _rewrite(
        run / "trials.parquet", _drop_column("mode_pre")), _args(), GOOD,
     "no columns ['mode_pre']"),
    ("trials_listed_twice", "run", lambda run, tmp: _rewrite(
        run / "trials.parquet", lambda t: pa.concat_tables([t, t.slice(0, 1)])),
     _args(), GOOD, "listed twice"),
    ("trials_judged_text", "run", lambda run, tmp: _rewrite(
        run / "trials.parquet", _set_column("judged", lambda t: pa.array(
            ["yes"] * t.num_rows))), _args(), GOOD, "judged not booleans"),
    # --- the signals files
    ("no_signals", "run", lambda run, tmp: shutil.rmtree(run / "signals"), _args(), GOOD,
     "recorded without signals"),
    ("signals_damaged", "run", lambda run, tmp: _first_signals(run).write_bytes(
        b"PAR1" + b"\0" * 64 + b"PAR1"), _args(), GOOD, "not a readable Parquet file"),
    ("signals_truncated", "run", lambda run, tmp: _first_signals(run).write_bytes(
        _first_signals(run).read_bytes()[:-100]), _args(), GOOD,
     "not a readable Parquet file"),
    ("signals_a_folder", "run", lambda run, tmp: (run / "signals" / "zz.parquet").mkdir(),
     _args(), GOOD, "not a file"),
    ("signals_no_rows", "run", lambda run, tmp: _rewrite(
        _first_signals(run), lambda t: t.slice(0, 0)), _args(), GOOD, "no rows"),
    ("signals_no_step", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _drop_column("step")), _args(), GOOD, "no key columns"),
    ("signals_no_innov", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _drop_column("innov_q")), _args(),
     "refusal_detectors:reads_innov", "no signal columns ['innov_q']"),
    ("signals_step_zero", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("step", lambda t: pa.array(
            np.asarray(t["step"]) - 1, pa.int32()))), _args(), GOOD, "outside the flight"),
    ("signals_step_beyond", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("step", lambda t: pa.array(
            np.asarray(t["step"]) + 10_000, pa.int32()))), _args(), GOOD,
     "outside the flight"),
    ("signals_step_twice", "run", lambda run, tmp: _rewrite(
        _first_signals(run), lambda t: pa.concat_tables([t, t.slice(0, 3)])), _args(), GOOD,
     "recorded twice"),
    ("signals_unknown_mode", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("mode", lambda t: pa.array(
            ["broken"] * t.num_rows))), _args(), "refusal_detectors:reads_mode",
     "mode 'broken'"),
    ("signals_unknown_trial", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("trial_id", lambda t: pa.array(
            np.asarray(t["trial_id"]) + 1000, pa.int64()))), _args(), GOOD,
     "does not list"),
    ("signals_unknown_transition", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("transition", lambda t: pa.array(
            ["rudder_jam"] * t.num_rows))), _args(), GOOD, "not a transition"),
    ("signals_two_transitions", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("transition", lambda t: pa.array(
            (["elevon_lock", "engine_loss"] * t.num_rows)[:t.num_rows]))), _args(), GOOD,
     "more than one transition"),
    ("signals_text_column", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("innov_q", lambda t: pa.array(
            ["0.1"] * t.num_rows))), _args(), GOOD, "not numbers"),
    ("signals_float_step", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("step", lambda t: pa.array(
            np.asarray(t["step"], dtype=float)))), _args(), GOOD, "not integers"),
    ("signals_null_trial", "run", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("trial_id", lambda t: pa.array(
            [None] * t.num_rows, pa.int64()))), _args(), GOOD, "empty values"),
    # --- the detector and what it returns
    ("raises", "run", _none, _args(), "refusal_detectors:raises",
     "detector raised RuntimeError"),
    ("raises_many_lines", "run", _none, _args(), "refusal_detectors:raises_lines",
     "first line second line"),
    ("exits", "run", _none, _args(), "refusal_detectors:exits", "detector raised SystemExit"),
    ("returns_none", "run", _none, _args(), "refusal_detectors:none", "returned None"),
    ("returns_text", "run", _none, _args(), "refusal_detectors:text", "not numbers"),
    ("returns_mapping", "run", _none, _args(), "refusal_detectors:mapping", "not numbers"),
    ("too_many", "run", _none, _args(), "refusal_detectors:too_many", "one per trial"),
    ("too_few", "run", _none, _args(), "refusal_detectors:too_few", "one per trial"),
    ("two_d", "run", _none, _args(), "refusal_detectors:two_d", "one per trial"),
    ("scalar", "run", _none, _args(), "refusal_detectors:scalar", "one per trial"),
    ("booleans", "run", _none, _args(), "refusal_detectors:booleans", "booleans"),
    ("complex", "run", _none, _args(), "refusal_detectors:complex_", "complex"),
    ("strings", "run", _none, _args(), "refusal_detectors:strings", "not numbers"),
    ("infinite", "run", _none, _args(), "refusal_detectors:inf", "finite or NaN"),
    ("negative", "run", _none, _args(), "refusal_detectors:negative", "before the flight"),
    ("at_zero", "run", _none, _args(), "refusal_detectors:zero", "before the flight"),
    ("half_a_step", "run", _none, _args(), "refusal_detectors:half_step",
     "before the flight"),
    ("after_the_end", "run", _none, _args(), "refusal_detectors:after_end",
     "after the trial's last recorded sample"),
    ("tuple_of_three", "run", _none, _args(), "refusal_detectors:three", "a tuple of 3"),
    ("block_rudder", "run", _none, _args(), "refusal_detectors:rudder", "block 'rudder'"),
    ("block_none", "run", _none, _args(), "refusal_detectors:block_none", "block 'none'"),
    ("block_zero", "run", _none, _args(), "refusal_detectors:block_zero", "block 0"),
    ("block_seven", "run", _none, _args(), "refusal_detectors:block_seven", "block 7"),
    ("block_bool", "run", _none, _args(), "refusal_detectors:block_bool", "block True"),
    ("block_short", "run", _none, _args(), "refusal_detectors:block_short", "blocks"),
    ("block_scalar", "run", _none, _args(), "refusal_detectors:block_scalar", "blocks"),
    ("columns_text", "run", _none, _args(), "refusal_detectors:columns_text",
     "tuple of signal names"),
    ("columns_unknown", "run", _none, _args(), "refusal_detectors:columns_unknown",
     "no signal columns ['no_such_signal']"),
    ("columns_key", "run", _none, _args(), "refusal_detectors:columns_key", "is a key"),
    ("columns_twice", "run", _none, _args(), "refusal_detectors:columns_twice",
     "given twice"),
    ("columns_empty", "run", _none, _args(), "refusal_detectors:columns_empty",
     "tuple of signal names"),
    ("no_module", "run", _none, _args(), "refusal_no_such_module:f", "cannot import"),
    ("import_fails", "run", _none, _args(), "refusal_import_fails:f", "cannot import"),
    ("no_colon", "run", _none, _args(), "refusal_detectors", "module:function"),
    ("no_function", "run", _none, _args(), "refusal_detectors:nothing", "no function"),
    ("not_a_function", "run", _none, _args(), "refusal_detectors:NOT_A_FUNCTION",
     "no function"),
    # --- an endurance run
    ("endurance_after_the_end", "end", _none, _args(), "refusal_detectors:after_end",
     "after the trial's last recorded sample"),
    ("endurance_negative", "end", _none, _args(), "refusal_detectors:negative",
     "before the flight"),
    ("endurance_flights_damaged", "end", lambda run, tmp: (run / "flights.parquet")
     .write_bytes(b"junk" * 50), _args(), GOOD, "not a readable Parquet file"),
    ("endurance_no_flown_s", "end", lambda run, tmp: _rewrite(
        run / "flights.parquet", _drop_column("flown_s")), _args(), GOOD,
     "no columns ['flown_s']"),
    ("endurance_transition", "end", lambda run, tmp: _rewrite(
        _first_signals(run), _set_column("transition", lambda t: pa.array(
            ["elevon_lock"] * t.num_rows))), _args(), GOOD, "not an endurance run's flights"),
]
@pytest.fixture()
def sandbox(master, tmp_path, monkeypatch):
    """A fresh copy of the runs, the detectors importable, the current folder
    inside the sandbox, no bytecode written."""
    shutil.copytree(master / "run", tmp_path / "run")
    shutil.copytree(master / "end", tmp_path / "end")
    mods = master / "mods"
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    monkeypatch.syspath_prepend(str(mods))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)
    return tmp_path


def test_the_cases_are_many_and_distinct():
    ids = [c[0] for c in CASES]
    assert len(ids) == len(set(ids)) and len(ids) >= 60


def test_the_good_detector_is_scored(sandbox):
    """The cases' baseline: untouched runs, a valid detector and name: scored."""
    for which in ("run", "end"):
        for det in (GOOD, "refusal_detectors:late_ok"):
            r = CliRunner().invoke(cli, ["score", str(sandbox / which), "--detector", det,
                                         "--name", "fine.v2-b+c_d"])
            assert r.exit_code == 0, r.output
            assert (sandbox / which / "detectors" / "fine.v2-b+c_d" / "summary.md").exists()


@pytest.mark.parametrize("case_id, which, setup, args, detector, says", CASES,
                         ids=[c[0] for c in CASES])
def test_refused(sandbox, case_id, which, setup, args, detector, says):
    run = sandbox / which
    setup(run, sandbox)
    before = _tree(sandbox)
    r = CliRunner().invoke(cli, ["score", str(run), "--detector", detector,
                                 *args(run, sandbox)])
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1, r.output
    assert lines[0].startswith("ftc-mc: error: ") and "Traceback" not in r.output
    assert says in lines[0], lines[0]
    assert _tree(sandbox) == before  # nothing written, the run's files unchanged


def test_the_api_refuses_too(sandbox):
    """The same checks from Python: a name that is a path, a detector that is
    not a function, an alarm before the flight started."""
    run = sandbox / "run"
    before = _tree(sandbox)

    def early(signals, names, dt):
        return np.full(signals.shape[0], -0.5)

    for kwargs in ({"detector": early},
                   {"detector": lambda s, n, dt: np.full(s.shape[0], np.nan)},
                   {"detector": lambda s, n, dt: None, "name": "../../x"},
                   {"detector": 3, "name": "x"}):
        with pytest.raises(ftc_mc.errors.UserError) as err:
            ftc_mc.score_detector(run, **kwargs)
        assert "\n" not in str(err.value)
    assert _tree(sandbox) == before


def test_a_run_being_written(sandbox):
    """A run folder another ftc-mc command holds is not scored."""
    from ftc_mc.io.lock import acquire
    run = sandbox / "run"
    with acquire(run, "ftc-mc run cfg.yaml"):
        before = _tree(sandbox)
        r = CliRunner().invoke(cli, ["score", str(run), "--detector", GOOD])
        assert _tree(sandbox) == before
    assert r.exit_code == 2, r.output
    lines = r.output.strip().splitlines()
    assert len(lines) == 1 and "being written by `ftc-mc run cfg.yaml`" in lines[0], r.output
