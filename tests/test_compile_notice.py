"""The one-line notice before the first run that compiles the trial kernel
(core/jit.py: ``needs_compile``, ``announce_compile``), and the lock that lets
one process compile it while others wait (io/lock.py ``waiting``,
sim/compiling.py ``compiled_once``).

A real cold compile takes about 1.5 minutes, so the decision is tested on fake
cache indexes and on the real trial kernel's cache pointed at an empty folder.
"""

from __future__ import annotations

import hashlib
import io
import re
import threading
from pathlib import Path

import numba
import pytest

from ftc_mc.core import jit
from ftc_mc.core.shared.paths import (DENSE_FILTER, LINEAR_PLANT, ONE_STEP_TEST, PAPER_FILTER,
                                      RECONFIGURING, describe)
from ftc_mc.core.shared.paths import Path as Path_
from ftc_mc.core.longitudinal.trial import advance
from ftc_mc.io.lock import waiting
from ftc_mc.sim.compiling import WAIT_NOTICE, compiled_once, lock_path

MAGIC = ("x86_64-unknown-linux-gnu", "znver4", "+avx512f")
CODE = hashlib.sha256(b"code").hexdigest()


def test_index_decision_on_fake_indexes():
    sig = (numba.float64,)
    assert not jit.index_has_overload([], MAGIC, CODE)  # missing or stale index
    assert jit.index_has_overload([(sig, MAGIC, (CODE, "c"))], MAGIC, CODE)
    # compiled for another CPU, or from other bytecode: not usable here
    assert not jit.index_has_overload([(sig, ("x", "other", ""), (CODE, "c"))], MAGIC, CODE)
    assert not jit.index_has_overload([(sig, MAGIC, ("other", "c"))], MAGIC, CODE)
    assert not jit.index_has_overload(["junk", (1, 2)], MAGIC, CODE)


class _FakeCacheFile:
    def __init__(self, index):
        self.index = index

    def _load_index(self):
        return self.index


class _FakeDispatcher:
    """What needs_compile reads of a Numba dispatcher."""

    def __init__(self, index, signatures=()):
        self.signatures = list(signatures)
        self._cache = type("C", (), {"_cache_file": _FakeCacheFile(index)})()
        self.targetctx = advance.targetctx
        self.py_func = advance.py_func


def _key(dispatcher):
    magic = advance.targetctx.codegen().magic_tuple()
    code = hashlib.sha256(dispatcher.py_func.__code__.co_code).hexdigest()
    return ((numba.float64,), magic, (code, ""))


def test_cold_then_warm(monkeypatch):
    monkeypatch.setattr(jit, "CACHE", True)
    cold = _FakeDispatcher({})
    out = io.StringIO()
    assert jit.needs_compile(cold) is True
    assert jit.announce_compile(cold, stream=out)
    assert out.getvalue().startswith("ftc-mc: compiling the simulation kernels of this path")
    assert out.getvalue().count("\n") == 1
    warm = _FakeDispatcher({_key(cold): "file.nbc"})
    out = io.StringIO()
    assert jit.needs_compile(warm) is False
    assert not jit.announce_compile(warm, stream=out) and out.getvalue() == ""
    # already compiled in this process: nothing to announce
    assert jit.needs_compile(_FakeDispatcher({}, signatures=["sig"])) is False
    # a caller that has just asked needs_compile passes its answer on
    out = io.StringIO()
    assert not jit.announce_compile(cold, stream=out, needed=False) and out.getvalue() == ""
    assert jit.announce_compile(warm, stream=out, needed=True) and out.getvalue()


def test_unknown_cache_layout_announces_nothing(monkeypatch):
    monkeypatch.setattr(jit, "CACHE", True)
    odd = _FakeDispatcher({})
    odd._cache = object()
    out = io.StringIO()
    assert jit.needs_compile(odd) is None
    assert not jit.announce_compile(odd, stream=out) and out.getvalue() == ""


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_real_trial_kernel_cache(tmp_path, monkeypatch):
    """Numba's own index reader on the trial kernel: an empty cache folder is
    cold; after the kernel was compiled or loaded in this process its index
    is warm."""
    cache_file = advance._cache._cache_file
    with monkeypatch.context() as m:
        m.setattr(cache_file, "_index_path", str(tmp_path / "none.nbi"))
        assert jit.in_disk_cache(advance) is False
    if advance.signatures:  # compiled or loaded by an earlier test
        assert jit.in_disk_cache(advance) is True
        assert jit.needs_compile(advance) is False


def test_the_kernel_cache_follows_every_kernel_module(tmp_path, monkeypatch):
    # Numba checks a cached kernel only against its own file; the cache folder is
    # named after all of core/ and conventions.py, so an edit of a module that a
    # kernel inlines (longitudinal/stages.py into longitudinal/trial.py) starts a new folder
    # (tests/test_kernel_cache.py: subpackages, and a second copy of the sources)
    import shutil

    src = Path(jit.__file__).resolve().parent
    copy = tmp_path / "ftc_mc"
    shutil.copytree(src, copy / "core", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(src.parent / "conventions.py", copy / "conventions.py")
    same = jit.source_digest(copy / "core")
    assert same == jit.source_digest()
    stages = copy / "core" / "longitudinal" / "stages.py"
    stages.write_text(stages.read_text() + "\n# an edit\n")
    assert jit.source_digest(copy / "core") != same
    conv = copy / "conventions.py"
    stages.write_text(stages.read_text()[:-len("\n# an edit\n")])
    assert jit.source_digest(copy / "core") == same
    conv.write_text(conv.read_text() + "\n")
    assert jit.source_digest(copy / "core") != same
    monkeypatch.setenv("FTC_MC_CACHE_DIR", str(tmp_path / "c"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert jit.cache_dir() == tmp_path / "c" / "numba" / same
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "n"))  # takes precedence
    assert jit.cache_dir() == tmp_path / "n" / same


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_sweep_reuses_the_trial_kernels_advance(tmp_path):
    """The campaign (``sim.lanes.run_trials``) and the sweep's shared start both
    call ``advance`` from Python.  Both must ask for one signature, or a user's
    first sweep compiles ``advance`` a second time (about 50 s cold): when a
    compiled ``run_trials`` called it, its constant ``0`` for the start step was
    typed ``Literal[int](0)``.  Read from Numba's on-disk index of
    ``advance``, which holds every signature compiled from this source (the
    folder is named after it, core/jit.py)."""
    import ftc_mc

    cfg = {"campaign": {"transitions": ["elevon_lock"], "trials": 2},
           "controller": {"kind": "nominal"},
           "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}
    ftc_mc.run_campaign(cfg, trials=2, jobs=1, progress=False, out=tmp_path / "run")
    before = set(advance._cache._cache_file._load_index())
    ftc_mc.run_sweep(cfg, "10,25", trials=2, jobs=1, progress=False, out=tmp_path / "sweep")
    after = set(advance._cache._cache_file._load_index())
    assert after == before, "the sweep compiled advance again"
    # and no signature of this machine's was compiled for a literal step (a
    # cache filled before this test could hold both)
    magic = advance.targetctx.codegen().magic_tuple()
    mine = [str(key[0]) for key in after if key[1] == magic]
    assert mine and not any("Literal" in sig for sig in mine), [s[-60:] for s in mine]


def _in_thread(fn):
    t = threading.Thread(target=fn, daemon=True)
    t.start()
    return t


def test_waiting_lock_waits_for_the_holder(tmp_path):
    path = tmp_path / "sub" / "x.lock"
    waited, inside = threading.Event(), threading.Event()

    def second():
        with waiting(path, on_wait=waited.set, poll_s=0.01) as held:
            assert held
            inside.set()

    with waiting(path) as held:
        assert held and path.exists()
        t = _in_thread(second)
        assert waited.wait(10)
        assert not inside.wait(0.2)  # still held here
    assert inside.wait(10)
    t.join(10)
    with waiting(path, on_wait=waited.clear) as held:  # free again: no wait
        assert held and waited.is_set()
        # a holder that never lets go is waited for at most timeout_s, then the
        # block runs unguarded
        gave_up = threading.Event()
        with waiting(path, poll_s=0.01, timeout_s=0.05, on_timeout=gave_up.set) as second:
            assert not second and gave_up.is_set()


@pytest.mark.parametrize("holder_compiles", [True, False])
def test_compiled_once_waits_then_loads(tmp_path, monkeypatch, holder_compiles):
    """A second process finds the compile lock busy: it says it waits, and once
    the holder has filled the cache it announces no compile of its own; if the
    holder ended without filling it, the waiter compiles and says so."""
    monkeypatch.setattr(jit, "CACHE", True)
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    index = {}
    fake = _FakeDispatcher(index)
    out = io.StringIO()
    inside, busy = threading.Event(), threading.Event()

    def waiter():
        with compiled_once(fake, stream=out):
            # the lock is kept only while this process compiles
            with waiting(lock_path(fake), on_wait=busy.set, timeout_s=0.0):
                pass
            inside.set()

    with waiting(lock_path(fake)):
        t = _in_thread(waiter)
        for _ in range(1000):
            if WAIT_NOTICE in out.getvalue():
                break
            inside.wait(0.01)
        assert out.getvalue() == WAIT_NOTICE + "\n" and not inside.is_set()
        if holder_compiles:
            index[_key(fake)] = "file.nbc"
    assert inside.wait(10)
    t.join(10)
    lines = out.getvalue().splitlines()
    assert lines[0] == WAIT_NOTICE
    assert busy.is_set() is not holder_compiles
    if holder_compiles:
        assert lines == [WAIT_NOTICE]
    else:
        assert len(lines) == 3 and lines[1].startswith("ftc-mc: compiling the simulation")
        assert re.fullmatch(r"ftc-mc: compiled in \d+\.\d s", lines[2]), lines[2]


def test_each_path_is_announced_on_its_own(monkeypatch):
    """A path is compiled (and announced, with its name) when neither this
    process nor the disk cache holds the trial kernel's signature for that
    path, whatever other paths they hold."""
    monkeypatch.setattr(jit, "CACHE", True)
    paper = Path_(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING)
    dense = paper._replace(filter=DENSE_FILTER)
    t_paper, t_dense = numba.typeof(paper), numba.typeof(dense)
    assert t_paper != t_dense
    key = _key(advance)
    cached = _FakeDispatcher({((t_paper, numba.float64), key[1], key[2]): "file.nbc"})
    assert jit.needs_compile(cached, t_paper) is False
    assert jit.needs_compile(cached, t_dense) is True
    loaded = _FakeDispatcher({}, signatures=[(t_dense, numba.float64)])
    assert jit.needs_compile(loaded, t_dense) is False
    assert jit.needs_compile(loaded, t_paper) is True
    out = io.StringIO()
    assert jit.announce_compile(cached, describe(dense), stream=out,
                                needed=jit.needs_compile(cached, t_dense))
    assert "linear plant, dense filter, one-step test, reconfiguring controller" in out.getvalue()


def test_the_notice_says_the_path_s_own_compile_time():
    """The notice's duration follows the path's plant family: the 6-DOF paths
    compile for longer than the longitudinal ones (``sim.compiling.EXPECTED_COMPILE``,
    measured figures in its docstring), and every plant marker has one."""
    from ftc_mc.core.shared import paths
    from ftc_mc.sim.compiling import EXPECTED_COMPILE, expected_compile

    assert set(EXPECTED_COMPILE) == {c for c in paths.NAMES if c.__name__.endswith("Plant")}
    lon = Path_(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING)
    six = lon._replace(plant=paths.SIXDOF_PLANT)
    ext = lon._replace(plant=paths.SIXDOF_EXTENDED_PLANT)
    said = [expected_compile(p) for p in (lon, six, ext)]
    assert said == ["30 s", "30-45 s", "30-45 s"]
    assert expected_compile(None) == said[0]
    out = io.StringIO()
    assert jit.announce_compile(_FakeDispatcher({}), describe(six), said[1], out, needed=True)
    assert "6-DOF plant" in out.getvalue() and "about 30-45 s" in out.getvalue()
