"""The one place that sets how every kernel is compiled.

``FTC_MC_NUMBA_CACHE=0`` in the environment turns Numba's on-disk cache off (for
example while editing kernels in several files, since the cache does not see
edits in other modules).  ``fastmath`` stays off: it was no faster here
(``scripts/bench_core.py``) and breaks bit-for-bit agreement with the NumPy
references.
"""

from __future__ import annotations

import os

import numba

CACHE = os.environ.get("FTC_MC_NUMBA_CACHE", "1") != "0"

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


def announce_compile(dispatcher, duration="1 min", stream=None) -> bool:
    """Print :data:`COMPILE_NOTICE` to stderr if ``dispatcher`` is about to be
    compiled (:func:`needs_compile`); return whether it was printed."""
    import sys
    if needs_compile(dispatcher) is not True:
        return False
    text = COMPILE_NOTICE if CACHE else COMPILE_NOTICE_NO_CACHE
    print(text.format(duration), file=sys.stderr if stream is None else stream, flush=True)
    return True
