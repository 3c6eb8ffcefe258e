"""The compiled-kernel cache follows the content of the kernel sources
(core/jit.py: ``source_digest``, ``ContentCacheLocator``).

A copy of the package in another folder (a second clone or install) loads the
kernels that the first compiled; an edit of any kernel source, including one
in a subpackage of core/, starts a new cache folder and compiles, so a stale
kernel is never loaded.  Each case runs a small kernel added to a copy of the
package (``core/probe.py``, inlining ``core/probe_parts/scale.py``) in its own
Python process, with ``PYTHONPATH`` at the copy and one shared
``FTC_MC_CACHE_DIR``, and reads Numba's cache hits and misses.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ftc_mc.core import jit

PACKAGE = Path(jit.__file__).resolve().parents[1]

PROBE = '''"""A small kernel for tests/test_kernel_cache.py."""
from ..conventions import N_X
from .jit import kernel
from .probe_parts.scale import scaled


@kernel
def probe(x):
    return scaled(x) + N_X
'''

SCALE = '''from ..jit import kernel

FACTOR = {factor}


@kernel
def scaled(x):
    return FACTOR * x
'''

RUN = '''
import json
from ftc_mc.core import jit
from ftc_mc.core.probe import probe
needed = jit.needs_compile(probe)
value = probe(1.5)
print(json.dumps({
    "file": probe.py_func.__code__.co_filename, "needed": needed, "value": value,
    "hits": sum(probe.stats.cache_hits.values()),
    "misses": sum(probe.stats.cache_misses.values()),
    "cache": probe._cache.cache_path, "digest": jit.source_digest(),
    "in_disk": jit.in_disk_cache(probe)}))
'''


def _copy(root: Path, factor: float = 2.0) -> Path:
    """A copy of the package under ``root`` with the probe kernel added; its
    files' modification times are a minute later than the originals'."""
    core = root / "ftc_mc" / "core"
    shutil.copytree(PACKAGE, root / "ftc_mc", ignore=shutil.ignore_patterns("__pycache__"))
    (core / "probe.py").write_text(PROBE)
    (core / "probe_parts").mkdir()
    (core / "probe_parts" / "__init__.py").write_text("")
    (core / "probe_parts" / "scale.py").write_text(SCALE.format(factor=factor))
    later = time.time() + 60.0
    for path in (root / "ftc_mc").rglob("*.py"):
        os.utime(path, (later, later))
    return root


def _run(root: Path, cache: Path, **env) -> dict:
    full = {k: v for k, v in os.environ.items()
            if k not in ("NUMBA_CACHE_DIR", "FTC_MC_NUMBA_CACHE", "PYTHONPATH")}
    full.update(PYTHONPATH=str(root), FTC_MC_CACHE_DIR=str(cache), **env)
    out = subprocess.run([sys.executable, "-c", RUN], cwd=root, env=full,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout.splitlines()[-1])
    assert Path(res["file"]).resolve().is_relative_to(root.resolve())  # the copy ran
    res["stderr"] = out.stderr
    return res


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_a_second_copy_loads_and_an_edit_compiles(tmp_path):
    cache = tmp_path / "cache"
    first = _run(_copy(tmp_path / "a"), cache)
    assert first["needed"] is True and first["misses"] == 1 and first["hits"] == 0
    assert first["value"] == 2.0 * 1.5 + 9 and first["in_disk"] is True

    # identical sources in another folder, other modification times: loaded
    b = _copy(tmp_path / "b")
    second = _run(b, cache)
    assert second["digest"] == first["digest"] and second["cache"] == first["cache"]
    assert second["needed"] is False and second["hits"] == 1 and second["misses"] == 0
    assert second["value"] == first["value"]
    # the folder is named after the sources' digest, not after the clone's path
    folder = cache / "numba" / first["digest"] / "core"
    assert Path(first["cache"]) == folder and any(folder.glob("probe.probe-*.nbi"))

    # an edit in a subpackage of core/ (a kernel that probe inlines): new folder,
    # compiled again, the new value
    (b / "ftc_mc" / "core" / "probe_parts" / "scale.py").write_text(SCALE.format(factor=3.0))
    edited = _run(b, cache)
    assert edited["digest"] != first["digest"] and edited["cache"] != first["cache"]
    assert edited["needed"] is True and edited["misses"] == 1 and edited["hits"] == 0
    assert edited["value"] == 3.0 * 1.5 + 9

    # an edit of a core module that probe does not import: compiled again too
    glr = b / "ftc_mc" / "core" / "shared" / "glr.py"
    glr.write_text(glr.read_text() + "\n# an edit\n")
    other = _run(b, cache)
    assert other["digest"] not in (first["digest"], edited["digest"])
    assert other["needed"] is True and other["misses"] == 1


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_a_cache_of_another_numba_or_damaged_is_compiled_again_with_one_line(tmp_path):
    """A kernel cache the installed Numba cannot use (an index written by
    another Numba version, an index or a compiled kernel that cannot be
    unpickled) is a cache miss: the kernel is compiled again, gives the same
    value, is saved over it, and stderr holds one line saying so (no
    traceback)."""
    import pickle

    root, cache = _copy(tmp_path / "a"), tmp_path / "cache"
    first = _run(root, cache)
    assert first["misses"] == 1 and first["stderr"] == ""
    [index] = Path(first["cache"]).glob("probe.probe-*.nbi")
    [data] = Path(first["cache"]).glob("probe.probe-*.nbc")
    with open(index, "rb") as f:
        version, body = pickle.load(f), f.read()

    def again(expect: str, needed: bool = True) -> dict:
        res = _run(root, cache)
        assert res["needed"] is needed and res["misses"] == 1 and res["hits"] == 0
        assert res["value"] == first["value"]
        lines = res["stderr"].splitlines()
        assert len(lines) == 1 and lines[0].startswith("ftc-mc: ") and expect in lines[0], lines
        return res

    # an index of another Numba version (which Numba reads as empty)
    index.write_bytes(pickle.dumps("0.0.1") + body)
    again(f"written by Numba 0.0.1, this is Numba {version}")
    # an index that does not unpickle
    index.write_bytes(pickle.dumps(version) + body[: len(body) // 2])
    again("cannot be read with this Numba")
    loaded = _run(root, cache)  # saved anew: loaded, nothing said
    assert loaded["hits"] == 1 and loaded["stderr"] == ""
    # a compiled kernel that does not unpickle (the index still lists it)
    data.write_bytes(data.read_bytes()[:100])
    again("cannot be read with this Numba", needed=False)
    assert _run(root, cache)["hits"] == 1


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_numba_cache_dir_and_cache_off(tmp_path):
    root = _copy(tmp_path / "a")
    cache = tmp_path / "cache"
    assert _run(root, cache)["misses"] == 1
    # NUMBA_CACHE_DIR takes precedence over FTC_MC_CACHE_DIR: empty, so compiled
    numba_dir = tmp_path / "numba"
    res = _run(root, cache, NUMBA_CACHE_DIR=str(numba_dir))
    assert res["needed"] is True and res["misses"] == 1
    assert Path(res["cache"]) == numba_dir / res["digest"] / "core"
    assert _run(root, cache, NUMBA_CACHE_DIR=str(numba_dir))["hits"] == 1
    # FTC_MC_NUMBA_CACHE=0: no disk cache, every process compiles
    off = _run(root, tmp_path / "off", FTC_MC_NUMBA_CACHE="0")
    assert off["needed"] is True and off["hits"] == 0 and off["cache"] is None
    assert not (tmp_path / "off").exists()


def test_the_digest_reads_core_recursively_and_what_it_imports(tmp_path):
    root = _copy(tmp_path / "a")
    core = root / "ftc_mc" / "core"
    files = {p.relative_to(root / "ftc_mc").as_posix() for p in jit.kernel_sources(core)}
    assert {"core/longitudinal/trial.py", "core/probe.py", "core/probe_parts/scale.py",
            "conventions.py"} <= files
    assert "api.py" not in files and "__init__.py" not in files
    digest = jit.source_digest(core)
    nested = core / "probe_parts" / "deeper"
    nested.mkdir()
    (nested / "__init__.py").write_text("")
    assert jit.source_digest(core) != digest  # a new file, even an empty one
    (nested / "__init__.py").unlink()
    nested.rmdir()
    assert jit.source_digest(core) == digest
    # a module outside core/ that a kernel module imports joins the digest
    (root / "ftc_mc" / "layouts.py").write_text("N = 3\n")
    assert jit.source_digest(core) == digest
    scale = core / "probe_parts" / "scale.py"
    scale.write_text("from ...layouts import N\n" + scale.read_text())
    with_import = jit.source_digest(core)
    assert with_import != digest
    (root / "ftc_mc" / "layouts.py").write_text("N = 4\n")
    assert jit.source_digest(core) != with_import


LATE = '''"""A kernel module imported after an edit, for tests/test_kernel_cache.py."""
from .jit import kernel
from .probe_parts.scale import scaled


@kernel
def late(x):
    return scaled(x) - 1.0
'''

RACE = '''
import json, sys
from pathlib import Path
from ftc_mc.core import jit
from ftc_mc.core.probe_parts import scale   # imported with FACTOR = 2
Path(scale.__file__).write_text(sys.argv[1])   # then edited: FACTOR = 3
from ftc_mc.core.late import late            # imported after the edit
value = late(1.5)                            # inlines the scale it imported: 2
print(json.dumps({"value": value, "digest": jit.source_digest(),
                  "unchanged": jit.sources_unchanged(),
                  "files": [p.name for p in Path(late._cache.cache_path).glob("late.*")]}))
'''


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_sources_edited_while_a_process_runs_never_leave_a_stale_kernel(tmp_path):
    """A process that imported a kernel source before an edit and another after
    it compiles a kernel of old and new code.  Its folder and stamp are the new
    digest's, so saved, it would be loaded stale by every later process of the
    new sources.  It is not saved, and the next process compiles the new value."""
    root = _copy(tmp_path / "a")
    (root / "ftc_mc" / "core" / "late.py").write_text(LATE)
    cache = tmp_path / "cache"
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "FTC_MC_NUMBA_CACHE", "PYTHONPATH")}
    env.update(PYTHONPATH=str(root), FTC_MC_CACHE_DIR=str(cache))
    out = subprocess.run([sys.executable, "-c", RACE, SCALE.format(factor=3.0)], cwd=root,
                         env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    race = json.loads(out.stdout.splitlines()[-1])
    assert race["value"] == 2.0 * 1.5 - 1.0 and race["unchanged"] is False
    assert race["files"] == [] and "not cached" in out.stderr
    after = subprocess.run(
        [sys.executable, "-c", "import json; from ftc_mc.core import jit; "
         "from ftc_mc.core.late import late; "
         "print(json.dumps({'value': late(1.5), 'digest': jit.source_digest(), "
         "'hits': sum(late.stats.cache_hits.values())}))"],
        cwd=root, env=env, capture_output=True, text=True, timeout=300)
    assert after.returncode == 0, after.stderr
    res = json.loads(after.stdout.splitlines()[-1])
    assert res["digest"] == race["digest"] and res["hits"] == 0
    assert res["value"] == 3.0 * 1.5 - 1.0
    assert "not cached" not in after.stderr


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_an_unwritable_cache_folder_caches_nothing(tmp_path):
    """When the content-keyed folder cannot be written, a kernel of core/ is not
    cached at all: Numba's own locators (the source tree's ``__pycache__``) stamp
    an index with the kernel's own file only, so after an edit of a kernel it
    inlines, the next process loaded the old value."""
    root = _copy(tmp_path / "a")
    (tmp_path / "blocker").write_text("a file, not a folder")
    cache = tmp_path / "blocker" / "cache"  # mkdir fails, even as root
    first = _run(root, cache)
    assert first["value"] == 2.0 * 1.5 + 9 and first["cache"] is None
    assert not list((root / "ftc_mc" / "core").rglob("probe.*.nbi"))
    (root / "ftc_mc" / "core" / "probe_parts" / "scale.py").write_text(SCALE.format(factor=3.0))
    edited = _run(root, cache)
    assert edited["value"] == 3.0 * 1.5 + 9 and edited["hits"] == 0


def test_a_source_removed_while_a_process_runs_is_a_change(tmp_path):
    """``sources_unchanged`` is asked at each save, inside Numba's compile: a
    module a kernel source imports, removed while the importer kept its stamp,
    raised FileNotFoundError there (and failed the compile) instead of saying
    the sources changed."""
    root = tmp_path / "b"
    shutil.copytree(PACKAGE, root / "ftc_mc", ignore=shutil.ignore_patterns("__pycache__"))
    core = root / "ftc_mc" / "core"
    (root / "ftc_mc" / "layouts.py").write_text("N = 3\n")
    (core / "uses.py").write_text("from ..layouts import N\n")
    jit.full_source_digest(core)  # the first stamps of these sources
    assert jit.sources_unchanged(core)
    (root / "ftc_mc" / "layouts.py").unlink()
    assert jit.sources_unchanged(core) is False


HELPER = '''"""A test helper kernel (tests/helper.py of a copied tree)."""
from ftc_mc.core.jit import kernel

OFFSET = {offset}


@kernel
def shifted(x):
    return x + OFFSET
'''

USER = '''"""A test-side kernel (tests/user.py) inlining a helper and a core kernel."""
from ftc_mc.core.jit import kernel
from ftc_mc.core.probe import probe
from helper import shifted


@kernel
def used(x):
    return shifted(probe(x))
'''

RUN_TREE = '''
import json, sys
sys.path.insert(0, "tests")
from user import used
value = used(1.5)
print(json.dumps({"value": value, "hits": sum(used.stats.cache_hits.values()),
                  "misses": sum(used.stats.cache_misses.values()),
                  "cache": used._cache.cache_path}))
'''


def _tree(root: Path, offset: float = 1.0) -> Path:
    """A source tree: a package copy with ``pyproject.toml`` and ``tests/``."""
    _copy(root)
    (root / "pyproject.toml").write_text("[project]\nname = 'copy'\n")
    (root / "tests").mkdir()
    (root / "tests" / "helper.py").write_text(HELPER.format(offset=offset))
    (root / "tests" / "user.py").write_text(USER)
    return root


def _run_tree(root: Path, cache: Path) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "FTC_MC_NUMBA_CACHE", "PYTHONPATH")}
    env.update(PYTHONPATH=str(root), FTC_MC_CACHE_DIR=str(cache))
    out = subprocess.run([sys.executable, "-c", RUN_TREE], cwd=root, env=env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.splitlines()[-1])


@pytest.mark.skipif(not jit.CACHE, reason="FTC_MC_NUMBA_CACHE=0")
def test_a_test_kernel_is_keyed_on_the_tree_s_content_not_its_path(tmp_path):
    """A kernel of a tree's ``tests/`` (jit.CloneFolderLocator): another clone of
    the same files loads it; an edit of another file of ``tests/`` that it
    inlines, or of a core kernel it inlines, compiles it again (Numba's own
    locator stamped it with ``tests/user.py`` alone and loaded it stale)."""
    cache = tmp_path / "cache"
    first = _run_tree(_tree(tmp_path / "a"), cache)
    assert first["misses"] == 1 and first["hits"] == 0
    assert first["value"] == 2.0 * 1.5 + 9 + 1.0
    assert "/clone/" in first["cache"] and str(tmp_path / "a") not in first["cache"]
    b = _tree(tmp_path / "b")
    second = _run_tree(b, cache)
    assert second["hits"] == 1 and second["misses"] == 0 and second["cache"] == first["cache"]
    (b / "tests" / "helper.py").write_text(HELPER.format(offset=5.0))
    helper = _run_tree(b, cache)
    assert helper["misses"] == 1 and helper["value"] == 2.0 * 1.5 + 9 + 5.0
    (b / "ftc_mc" / "core" / "probe_parts" / "scale.py").write_text(SCALE.format(factor=3.0))
    core = _run_tree(b, cache)
    assert core["misses"] == 1 and core["value"] == 3.0 * 1.5 + 9 + 5.0
    # without pyproject.toml (an installed package's neighbours): Numba's own locator
    (b / "pyproject.toml").unlink()
    assert "/clone/" not in _run_tree(b, cache)["cache"]


def test_an_index_holding_a_type_this_process_cannot_import_stays_readable(tmp_path,
                                                                           monkeypatch):
    """The tests compile package kernels on namedtuples of their own modules; a
    process without those modules (``ftc-mc`` after the tests, on one shared
    cache) once failed to load the kernel's whole index. Such entries are now
    left out (a cache miss), the others still load."""
    import importlib
    import pickle

    from numba.core import caching

    (tmp_path / "foreign_types.py").write_text(
        "from collections import namedtuple\nP = namedtuple('P', ['a'])\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    foreign = importlib.import_module("foreign_types")
    index = caching.IndexDataCacheFile(cache_path=str(tmp_path), filename_base="k",
                                       source_stamp=("stamp",))
    index._save_index({("native", 1): "k-1.nbc", (foreign.P(1), 1): "k-2.nbc"})
    monkeypatch.delitem(sys.modules, "foreign_types")
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p != str(tmp_path)])
    with pytest.raises(ImportError):
        index._load_index()  # Numba's own reader
    tolerant = jit.TolerantIndexFile(cache_path=str(tmp_path), filename_base="k",
                                     source_stamp=("stamp",))
    assert tolerant._load_index() == {("native", 1): "k-1.nbc"}
    stale = jit.TolerantIndexFile(cache_path=str(tmp_path), filename_base="k",
                                  source_stamp=("other",))
    assert stale._load_index() == {}
    assert pickle.dumps(("native", 1))
