"""The compile helper (sim/compile_helper.py) and the kernel claims it holds
(core/jit.py ``ContentFunctionCache``): a second process compiles the later
stages of a path into the cache while this one compiles the earlier ones.

The protocol runs on one small kernel of ``core/`` in a separate Numba cache
folder; the shipped plan is checked against the default path's own compile.
"""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import threading
import time
from pathlib import Path

import numba
import pytest

from ftc_mc.core import jit
from ftc_mc.core.shared import excitation
from ftc_mc.sim import compile_helper
from ftc_mc.sim.compile_helper import HELPER_START_S, load_plan, plan_key, split

ROOT = Path(__file__).resolve().parents[1]
MODULE, NAME = excitation.__name__, "doublet_length"
ARGS = (numba.int64,)

needs_cache = pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")


def _stage(name, seconds):
    return ("m", name, (), seconds)


def _names(share):
    return [s[1] for s in share]


def test_the_stages_are_split_longest_first_to_the_less_loaded_process():
    # by hand, the helper starting at HELPER_START_S (3 s), this process at `before`
    assert HELPER_START_S == 3.0
    four = [_stage(c, 10.0) for c in "abcd"]
    own, helper = split(four, 0.0)  # a -> own (0 < 3), b -> helper, c -> own, d -> helper
    assert _names(own) == ["a", "c"] and _names(helper) == ["b", "d"]
    own, helper = split(four, 20.0)  # a, b to the helper (3, 13 < 20), c here, d there
    assert _names(helper) == ["a", "b", "d"] and _names(own) == ["c"]  # 33 / 30
    assert split(four, 100.0) == ([], four)
    # the two largest go one to each process whatever their order in the plan
    default_like = [_stage("truth", 6.7), _stage("predict", 5.8), _stage("correct", 13.6),
                    _stage("belief", 0.9), _stage("select", 16.6)]
    own, helper = split(default_like, 4.0)
    assert _names(helper) == ["predict", "select"]  # 3 + 16.6 + 5.8 = 25.4
    assert _names(own) == ["truth", "correct", "belief"]  # 4 + 13.6 + 6.7 + 0.9 = 25.2
    assert split([], 5.0) == ([], [])
    # a partition, in the plan's order
    for stages, before in ((four, 7.0), (default_like, 0.0)):
        own, helper = split(stages, before)
        assert sorted(_names(own) + _names(helper)) == sorted(_names(stages))
        assert _names(own) == [n for n in _names(stages) if n in _names(own)]


def test_the_helper_shares_only_what_the_cache_lacks(monkeypatch):
    """Stages another path left in the cache cost nothing: the split is of the
    rest (by hand: a, b, d of 10 s each, c cached: a to this process, b to the
    helper, d to this one, at 10 / 13), and the helper compiles the indices
    it is given, or without them its own share, never waiting for claims."""
    compiled = []

    class Fake:
        def __init__(self, name):
            self.name = name

        def compile(self, args):
            compiled.append(self.name)

    plan = {"p": {"before_s": 0.0, "stages": [("m", c, (), 10.0) for c in "abcd"]}}
    monkeypatch.setattr(compile_helper, "load_plan", lambda f: plan)
    monkeypatch.setattr(compile_helper, "_dispatcher", lambda m, q: Fake(q))
    monkeypatch.setattr(jit, "cached_signature", lambda d, args: d.name == "c")
    monkeypatch.setattr(compile_helper, "_claim", lambda d, args: d.name)
    released = []
    monkeypatch.setattr(compile_helper, "_release", released.append)
    monkeypatch.setattr(jit.ContentFunctionCache, "awaits_claims", True)
    assert compile_helper.run("p") == 0
    assert compiled == ["b"] and released == ["b"]
    assert jit.ContentFunctionCache.awaits_claims is False
    compiled.clear()
    assert compile_helper.run("p", stages=[3, 2, 0]) == 0  # c is cached meanwhile
    assert compiled == ["a", "d"]
    assert compile_helper.run("unknown") == 1
    # this process's own share: what start() hands to compile_own()
    compiled.clear()
    compile_helper.compile_own([(Fake("a"), ()), (Fake("d"), ())])
    assert compiled == ["a", "d"]


def _write_plan(path: Path, version=None) -> Path:
    plan = {"numba": version or numba.__version__,
            "paths": {"probe path": {"before_s": 0.0,
                                     "stages": [(MODULE, NAME, ARGS, 1.0)]}}}
    path.write_bytes(pickle.dumps(plan, protocol=4))
    return path


def _notices(capsys, monkeypatch) -> list:
    """The lines this test printed to stderr; the plan's notice may be
    printed again afterwards (it is printed once per process)."""
    lines = capsys.readouterr().err.splitlines()
    monkeypatch.setattr(compile_helper, "_PLAN_NOTICED", False)
    return lines


def test_a_plan_of_another_numba_or_unreadable_is_not_used(tmp_path, capsys, monkeypatch):
    """Not used, and said in one line on stderr: a plan of another Numba
    version, one that does not unpickle; a missing plan is not used, and
    nothing is said (a source tree before its first plan)."""
    monkeypatch.setattr(compile_helper, "_PLAN_NOTICED", False)
    assert load_plan(_write_plan(tmp_path / "ok.pkl")) == {
        "probe path": {"before_s": 0.0, "stages": [(MODULE, NAME, ARGS, 1.0)]}}
    assert _notices(capsys, monkeypatch) == []
    assert load_plan(_write_plan(tmp_path / "old.pkl", version="0.1.0")) == {}
    [line] = _notices(capsys, monkeypatch)
    assert line.startswith("ftc-mc: the compile plan (old.pkl) was written by Numba 0.1.0, "
                           f"this is Numba {numba.__version__};")
    (tmp_path / "junk.pkl").write_bytes(b"not a pickle")
    assert load_plan(tmp_path / "junk.pkl") == {}
    [line] = _notices(capsys, monkeypatch)
    assert line.startswith("ftc-mc: the compile plan (junk.pkl) cannot be read")
    assert load_plan(tmp_path / "missing.pkl") == {}
    assert _notices(capsys, monkeypatch) == []
    # once per process
    assert load_plan(tmp_path / "junk.pkl") == load_plan(tmp_path / "old.pkl") == {}
    assert len(_notices(capsys, monkeypatch)) == 1


def test_a_plan_naming_a_numba_type_class_that_is_gone_falls_back(tmp_path, capsys,
                                                                  monkeypatch):
    """A newer Numba may have moved or renamed a type class the plan pickled:
    unpickling it raises, the plan is not used (no helper starts, this
    process compiles everything itself), one line on stderr, no traceback."""
    from numba.core.types import scalars

    from ftc_mc.core.shared.paths import (LINEAR_PLANT, ONE_STEP_TEST, PAPER_FILTER,
                                          RECONFIGURING, Path as Path_)

    class Gone(numba.types.Integer):
        pass

    Gone.__module__, Gone.__qualname__ = scalars.__name__, "IntegerOfAnOlderNumba"
    monkeypatch.setattr(scalars, "IntegerOfAnOlderNumba", Gone, raising=False)
    plan = tmp_path / "plan.pkl"
    plan.write_bytes(pickle.dumps({"numba": numba.__version__, "paths": {"probe path": {
        "before_s": 0.0, "stages": [(MODULE, NAME, (Gone("int64"),), 1.0)]}}}, protocol=4))
    monkeypatch.delattr(scalars, "IntegerOfAnOlderNumba")
    monkeypatch.setattr(compile_helper, "_PLAN_NOTICED", False)
    monkeypatch.setattr(compile_helper, "plan_key", lambda p: "probe path")
    monkeypatch.setattr(compile_helper, "enabled", lambda: True)
    path = Path_(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING)
    assert compile_helper.start(path, plan) == (None, [])
    [line] = _notices(capsys, monkeypatch)
    assert line.startswith("ftc-mc: the compile plan (plan.pkl) cannot be read with Numba ")
    assert "IntegerOfAnOlderNumba" in line and line.endswith("(slower, same results)")
    # the helper, given such a plan, does nothing and says why by its exit status
    assert compile_helper.run("probe path", plan) == 1


def test_a_stage_the_plan_names_that_no_longer_exists_is_skipped():
    """A plan written before a kernel moved or was renamed names a module or a
    kernel that is no longer there: that stage is left to ``advance``'s
    typing (no error), and the others are still shared."""
    assert compile_helper._dispatcher(MODULE, NAME) is not None
    assert compile_helper._dispatcher(MODULE, NAME + "_moved_away") is None
    assert compile_helper._dispatcher("ftc_mc.core.no_such_module", NAME) is None
    entry = {"before_s": 0.0, "stages": [(MODULE, NAME + "_moved_away", ARGS, 1.0),
                                         ("ftc_mc.core.no_such_module", NAME, ARGS, 1.0)]}
    assert compile_helper._to_compile(entry) == []


def test_no_helper_when_switched_off_or_the_path_is_unknown(tmp_path, monkeypatch):
    from ftc_mc.core.shared.paths import (LINEAR_PLANT, ONE_STEP_TEST, PAPER_FILTER,
                                          RECONFIGURING, Path as Path_)
    path = Path_(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING)
    plan = _write_plan(tmp_path / "plan.pkl")  # knows only "probe path"
    assert compile_helper.start(path, plan) == (None, [])
    monkeypatch.setenv("FTC_MC_COMPILE_HELPER", "0")
    assert not compile_helper.enabled()
    monkeypatch.setattr(compile_helper, "plan_key", lambda p: "probe path")
    assert compile_helper.start(path, plan) == (None, [])


@pytest.mark.skipif(not compile_helper.enabled(), reason="one core, or the helper is off")
def test_start_runs_the_helper_for_a_known_path_and_stop_ends_it(tmp_path, monkeypatch):
    """A path the plan knows starts a helper process, which exits 0 when its
    share is done; :func:`stop` ends one that still runs (here a process that
    sleeps) and leaves a finished one alone."""
    from ftc_mc.core.shared.paths import (LINEAR_PLANT, ONE_STEP_TEST, PAPER_FILTER,
                                          RECONFIGURING, Path as Path_)
    plan = _write_plan(tmp_path / "plan.pkl")
    monkeypatch.setattr(compile_helper, "plan_key", lambda p: "probe path")
    # one stage of 1 s, not cached: the helper's (it starts at 3 s of work,
    # this process at the plan's 5 s before the stages)
    plan.write_bytes(pickle.dumps({"numba": numba.__version__, "paths": {"probe path": {
        "before_s": 5.0, "stages": [(MODULE, NAME, ARGS, 1.0)]}}}, protocol=4))
    monkeypatch.setattr(jit, "cached_signature", lambda d, args: False)
    proc, own = compile_helper.start(Path_(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST,
                                           RECONFIGURING), plan)
    assert own == [] and proc is not None and proc.wait(300) == 0
    assert proc.args[-2:] == ["--stages", "0"]
    compile_helper.stop(proc)
    assert proc.returncode == 0
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    compile_helper.stop(sleeper)
    assert sleeper.returncode is not None and sleeper.returncode != 0


@needs_cache
def test_a_held_claim_is_waited_for_and_a_free_one_is_not():
    """``load_overload`` waits while another open file holds the claim's flock
    (flocks of two open files conflict within one process as across two), and
    not once it is let go, nor in a process that claims itself."""
    d = getattr(excitation, NAME)
    cache = d._cache
    claim = compile_helper._claim(d, ARGS)
    assert claim is not None and claim[1] == cache.claim_path(ARGS)
    assert claim[1].parent == Path(cache.cache_path)
    done = threading.Event()

    def load():
        cache.load_overload(ARGS, d.targetctx)
        done.set()

    t0 = time.perf_counter()
    th = threading.Thread(target=load, daemon=True)
    try:
        th.start()
        assert not done.wait(0.5)  # held: it waits
        cache.awaits_claims = False  # a helper's own loads do not wait
        t1 = time.perf_counter()
        cache.load_overload(ARGS, d.targetctx)
        assert time.perf_counter() - t1 < 0.4
    finally:
        cache.__dict__.pop("awaits_claims", None)
        compile_helper._release(claim)
    assert done.wait(10) and time.perf_counter() - t0 >= 0.5
    th.join(10)
    assert not claim[1].exists()
    # a claim file nobody holds (a helper that died before deleting it)
    claim[1].touch()
    try:
        t1 = time.perf_counter()
        cache.load_overload(ARGS, d.targetctx)
        assert time.perf_counter() - t1 < 0.4
    finally:
        claim[1].unlink()


# the stage is an internal kernel (no Python wrappers), called by another
# kernel as the trial kernel calls its stages
PROBE = f'''
import json, sys
import numba
from ftc_mc.core import jit
from ftc_mc.core.shared import excitation
d = excitation.{NAME}
value = numba.njit(lambda n: d(n))(3)
print(json.dumps({{"value": value, "hits": sum(d.stats.cache_hits.values()),
                  "misses": sum(d.stats.cache_misses.values())}}))
'''


def _env(cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "FTC_MC_NUMBA_CACHE"}
    env.update(NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT))
    return env


@needs_cache
def test_the_helper_compiles_its_share_and_this_process_loads_it(tmp_path):
    """``python -m ftc_mc.sim.compile_helper KEY --plan F --stages 0`` compiles
    the plan's stage into the cache and leaves no claim; a process then loads the kernel
    (a cache hit, no compile) and computes the same value as one that
    compiled it itself."""
    plan = _write_plan(tmp_path / "plan.pkl")
    alone = subprocess.run([sys.executable, "-c", PROBE], env=_env(tmp_path / "alone"),
                           capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert alone.returncode == 0, alone.stderr
    alone = json.loads(alone.stdout)
    assert alone["misses"] == 1 and alone["hits"] == 0
    env = _env(tmp_path / "shared")
    helper = subprocess.run([sys.executable, "-m", "ftc_mc.sim.compile_helper", "probe path",
                             "--plan", str(plan), "--stages", "0"], env=env,
                            capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert helper.returncode == 0, helper.stderr
    assert not list((tmp_path / "shared").rglob("*.claim"))
    assert list((tmp_path / "shared").rglob("excitation.doublet_length-*.nbi"))
    loaded = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                            text=True, timeout=300, cwd=ROOT)
    assert loaded.returncode == 0, loaded.stderr
    loaded = json.loads(loaded.stdout)
    assert loaded == {"value": alone["value"], "hits": 1, "misses": 0}
    unknown = subprocess.run([sys.executable, "-m", "ftc_mc.sim.compile_helper", "no such path",
                              "--plan", str(plan)], env=env, capture_output=True, timeout=300,
                             cwd=ROOT)
    assert unknown.returncode == 1


def _type_only(dispatcher, sig) -> None:
    """Type ``dispatcher`` for ``sig`` with Numba's own passes up to type
    inference, and no further: the kernels it calls are compiled, or loaded
    from the cache, as a compile would, while it is not lowered."""
    from numba.core import compiler, typed_passes
    from numba.core.compiler_machinery import PassManager

    class TypeOnly(compiler.CompilerBase):
        def define_pipelines(self):
            pm = PassManager("type only")
            pm.passes.extend(compiler.DefaultPassBuilder.define_untyped_pipeline(
                self.state).passes)
            pm.add_pass(typed_passes.NopythonTypeInference, "nopython type inference")
            pm.finalize()
            return [pm]

    flags = compiler.Flags()
    flags.no_compile = True
    try:
        compiler.compile_extra(dispatcher.typingctx, dispatcher.targetctx,
                               dispatcher.py_func, sig, None, flags, {},
                               pipeline_class=TypeOnly)
    except AttributeError as exc:  # no lowering pass: no compile result to return
        assert str(exc) == "cr", exc


@needs_cache
def test_the_shipped_plan_matches_the_default_path(trial_kernel):
    """Every stage the plan lists for the default path (``paper_tables.yaml``'s
    first variant) is a signature that path's ``advance`` calls: typing
    ``advance`` for the path (loaded from the cache, so typed again here)
    loads or compiles exactly those.  A stale plan fails here
    (``scripts/maintenance/make_compile_plan.py`` writes it again)."""
    from ftc_mc.campaign.chunk import chunk_spec
    from ftc_mc.config import load_config
    from ftc_mc.core.longitudinal.trial import advance
    from ftc_mc.sim.paths import path_of
    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    spec = chunk_spec(cfg)
    path = path_of(spec.setup.scheme(spec.variants[0]), spec.setup.flight)
    plan = load_plan()
    assert plan_key(path) in plan, f"the compile plan lacks the default path {plan_key(path)!r}"
    stages = plan[plan_key(path)]["stages"]
    assert len(stages) >= 5 and all(s[3] >= 0 for s in stages)
    [sig] = [s for s in advance.signatures if s[0] == numba.typeof(path)]
    _type_only(advance, sig)
    for module, qualname, args, _ in stages:
        d = compile_helper._dispatcher(module, qualname)
        assert d is not None, f"{module}.{qualname} is not a cached kernel of core/"
        assert tuple(args) in d.overloads, f"{qualname}: {args} not called by the path"
    # the helper's share is real work: at least a third of the stages' seconds
    own, share = split(stages, plan[plan_key(path)]["before_s"])
    assert sum(s[3] for s in share) >= sum(s[3] for s in stages) / 3


@needs_cache
def test_a_kernel_s_index_is_saved_under_its_lock(monkeypatch):
    """Numba rewrites a kernel's cache index unlocked; here each save holds an
    ``flock`` of ``<index>.lock`` (another open file cannot take it meanwhile)."""
    import fcntl

    from numba.core import caching
    cache = getattr(excitation, NAME)._cache
    lock = Path(cache._cache_file._index_path + ".lock")
    seen = []

    def probe(self, sig, data):
        fd = os.open(lock, os.O_RDWR)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            seen.append("free")
        except BlockingIOError:
            seen.append("held")
        finally:
            os.close(fd)

    monkeypatch.setattr(caching.Cache, "_save_overload", probe)
    cache._save_overload(ARGS, None)
    assert seen == ["held"]
    fd = os.open(lock, os.O_RDWR)  # and let go after
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    finally:
        os.close(fd)
