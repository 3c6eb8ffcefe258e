"""The one place that sets how every kernel is compiled.

Compiled kernels are cached on disk (``docs/performance.md``, lesson 6).  Numba
checks a cached kernel only against its own file, so a kernel that inlines
others would be loaded stale after an edit of theirs.  The cache therefore lives
in a folder named after a digest of every kernel module's source
(:func:`source_digest`): ``$FTC_MC_CACHE_DIR/numba/<digest>``
(``~/.cache/ftc-mc/numba/<digest>`` by default); any edit of ``ftc_mc/core/`` or
``ftc_mc/conventions.py`` starts a new folder.  ``NUMBA_CACHE_DIR`` in the
environment takes precedence (the benchmarks point it at an empty folder), and
``FTC_MC_NUMBA_CACHE=0`` turns caching off.  ``fastmath`` stays off: it was no
faster here (``scripts/bench_core.py``) and breaks bit-for-bit agreement with the
NumPy references.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numba

CACHE = os.environ.get("FTC_MC_NUMBA_CACHE", "1") != "0"


def source_digest(core: Path | None = None) -> str:
    """SHA-256 (16 hex digits) of the source of every module kernels compile from:
    ``core/**/*.py`` (subpackages such as ``core/sixdof/`` included, each file by
    its path relative to ``core``) and ``conventions.py`` beside it (``core``:
    this package's)."""
    core = Path(__file__).resolve().parent if core is None else Path(core)
    h = hashlib.sha256()
    files = [(p.relative_to(core).as_posix(), p) for p in sorted(core.rglob("*.py"))]
    for name, path in files + [("conventions.py", core.parent / "conventions.py")]:
        h.update(name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def cache_dir() -> Path:
    """The folder of the compiled kernels of this source (module docstring)."""
    root = os.environ.get("FTC_MC_CACHE_DIR") or Path.home() / ".cache" / "ftc-mc"
    return Path(root) / "numba" / source_digest()


if CACHE and not os.environ.get("NUMBA_CACHE_DIR"):
    # read by Numba when each kernel below is decorated (its cache locator)
    numba.config.CACHE_DIR = str(cache_dir())

OPTIONS = dict(cache=CACHE, fastmath=False, nogil=True, error_model="numpy")


def kernel(func=None, **overrides):
    """``numba.njit`` with the project's defaults (see module docstring).

    Parameters
    ----------
    func : callable, optional
        Function to compile; when omitted, returns a decorator.
    **overrides
        Options that replace the defaults for this kernel.
    """
    opts = dict(OPTIONS, **overrides)
    if func is None:
        return lambda f: numba.njit(**opts)(f)
    return numba.njit(**opts)(func)


COMPILE_NOTICE = ("ftc-mc: compiling the simulation kernels once (about {} on 2 cores; "
                  "later runs start at once)")
"""Printed to stderr before the first run that compiles the trial kernel."""

COMPILE_NOTICE_NO_CACHE = ("ftc-mc: compiling the simulation kernels (about {} on 2 "
                           "cores; FTC_MC_NUMBA_CACHE=0, so every run compiles)")


def index_has_overload(index_keys, magic, code_hash) -> bool:
    """Whether a Numba cache index holds an overload for this machine and code.

    Parameters
    ----------
    index_keys : iterable
        Keys of the index (``(signature, codegen magic tuple, (code hash,
        closure hash))``, ``numba.core.caching.Cache._index_key``); empty when
        the index is missing or stale (its source stamp differs).
    magic : tuple
        The codegen's magic tuple (target triple, CPU name, features).
    code_hash : str
        SHA-256 hex digest of the function's bytecode.
    """
    for key in index_keys:
        try:
            _, key_magic, (key_code, _) = key
        except (TypeError, ValueError):
            continue
        if key_magic == magic and key_code == code_hash:
            return True
    return False


def in_disk_cache(dispatcher) -> bool | None:
    """Whether Numba's on-disk cache holds an overload of ``dispatcher`` for this
    machine and source (so calling it loads instead of compiling).

    Reads the cache index the way Numba's ``FunctionCache`` does (the source
    stamp of the function's file, then the key's target and bytecode hash); the
    signature itself is not checked, since the campaign, sweep and scenario
    paths call the trial kernel with one and the same signature.  Returns
    ``None`` when the cache's layout is not the expected one (a Numba version
    that changed it).
    """
    import hashlib
    try:
        index = dispatcher._cache._cache_file._load_index()
        magic = dispatcher.targetctx.codegen().magic_tuple()
    except Exception:  # noqa: BLE001 -- numba internals; the notice is optional
        return None
    code_hash = hashlib.sha256(dispatcher.py_func.__code__.co_code).hexdigest()
    return index_has_overload(index.keys(), magic, code_hash)


def needs_compile(dispatcher) -> bool | None:
    """Whether calling ``dispatcher`` will compile it: no overload in this
    process and none in the on-disk cache (:func:`in_disk_cache`).  ``None``
    when that cannot be told (then nothing is announced)."""
    if dispatcher.signatures:
        return False
    if not CACHE:
        return True
    cached = in_disk_cache(dispatcher)
    return None if cached is None else not cached


def announce_compile(dispatcher, duration="1.5 min", stream=None, needed=None) -> bool:
    """Print :data:`COMPILE_NOTICE` to stderr if ``dispatcher`` is about to be
    compiled (:func:`needs_compile`, or ``needed`` when the caller has just
    asked it); return whether it was printed.  The
    duration is measured by ``scripts/bench_campaign.py``: 91-100 s since the
    trial kernel is no longer wrapped in a compiled ``run_trials`` and the
    kernels between it and the leaves are inlined (120-144 s before,
    ``docs/performance.md`` lesson 6)."""
    import sys
    if (needs_compile(dispatcher) if needed is None else needed) is not True:
        return False
    text = COMPILE_NOTICE if CACHE else COMPILE_NOTICE_NO_CACHE
    print(text.format(duration), file=sys.stderr if stream is None else stream, flush=True)
    return True
