"""One compile of the trial kernel at a time per kernel cache.

A cold compile of :func:`ftc_mc.core.trial.advance` takes about 1.5 minutes
(``scripts/bench_campaign.py``).  Processes that start together on an empty
cache (two runs launched at once, Dask or test workers on one machine) would
each compile it, on cores they then share.  :func:`compiled_once` makes the
first one compile while the others wait for it and then load the result from
Numba's cache.  The lock sits in the cache folder, so it is shared by the
processes that would share the compiled kernel.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import numba

from ..core import jit
from ..io.lock import waiting

WAIT_NOTICE = ("ftc-mc: another process is compiling the simulation kernels; waiting "
               "for it, then loading them")
"""Printed to stderr when the compile lock is busy."""

WAIT_LIMIT_S = 900.0
"""Longest wait for another process's compile [s] (a cold compile takes about
1.5 minutes); a holder stopped for longer is no longer waited for."""

GAVE_UP_NOTICE = ("ftc-mc: the other process has not finished compiling after {:.0f} s; "
                  "compiling here")


def lock_path(dispatcher) -> Path:
    """The compile lock of ``dispatcher``: a file beside its cached overloads
    (the folder of :func:`ftc_mc.core.jit.cache_dir`, or ``NUMBA_CACHE_DIR``)."""
    return Path(numba.config.CACHE_DIR) / f"{dispatcher.py_func.__name__}.compile.lock"


@contextlib.contextmanager
def compiled_once(dispatcher, stream=None):
    """Run the ``with`` block, which calls ``dispatcher`` first in this process,
    as the machine's only compile of it.

    When the call would compile (:func:`ftc_mc.core.jit.needs_compile`), the
    block waits for the compile lock (:func:`lock_path`), saying so on
    ``stream`` (stderr) if another process holds it (at most
    :data:`WAIT_LIMIT_S`).  If the holder filled the cache meanwhile, the lock
    is let go at once and the block loads the kernel; otherwise the block
    announces the compile (:func:`ftc_mc.core.jit.announce_compile`) and runs
    holding the lock.
    Without a disk cache (``FTC_MC_NUMBA_CACHE=0``) there is nothing to share:
    the block only announces.

    Parameters
    ----------
    dispatcher : numba dispatcher
        The kernel the block calls (``advance``).
    stream : file, optional
        Where the notices go (default stderr).
    """
    needed = jit.needs_compile(dispatcher)
    if not jit.CACHE or needed is not True:
        jit.announce_compile(dispatcher, stream=stream, needed=needed)
        yield
        return
    out = sys.stderr if stream is None else stream

    def say_wait():
        print(WAIT_NOTICE, file=out, flush=True)

    def give_up():
        print(GAVE_UP_NOTICE.format(WAIT_LIMIT_S), file=out, flush=True)

    with contextlib.ExitStack() as stack:
        stack.enter_context(waiting(lock_path(dispatcher), on_wait=say_wait,
                                    timeout_s=WAIT_LIMIT_S, on_timeout=give_up))
        needed = jit.needs_compile(dispatcher)  # again: the holder may have filled it
        if needed is not True:
            stack.close()  # the holder filled the cache: load it without the lock
        jit.announce_compile(dispatcher, stream=stream, needed=needed)
        yield
