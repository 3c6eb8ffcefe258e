"""One compile of each path of the trial kernel at a time per kernel cache.

A cold compile of a path of :func:`ftc_mc.core.longitudinal.trial.advance`
(``core/shared/paths.py``) takes tens of seconds (``scripts/benchmarks/bench_campaign.py``,
``docs/findings/performance.md`` lesson 11).  Processes that start together on an empty
cache (two runs launched at once, Dask or test workers on one machine) would
each compile it, on cores they then share.  :func:`compiled_once` makes the
first one compile while the others wait for it and then load the result from
Numba's cache.  The lock sits in the cache folder, so it is shared by the
processes that would share the compiled kernel.
"""

from __future__ import annotations

import contextlib
import re
import sys
import time
from pathlib import Path

import numba

from ..core import jit
from ..core.shared.paths import (LinearPlant, NonlinearPlant, SixdofExtendedPlant, SixdofPlant,
                                 describe)
from ..io.lock import waiting
from . import compile_helper

WAIT_NOTICE = ("ftc-mc: another process is compiling the simulation kernels; waiting "
               "for it, then loading them")
"""Printed to stderr when the compile lock is busy."""

WAIT_LIMIT_S = 900.0
"""Longest wait for another process's compile [s] (a path's cold compile takes
minutes at most, ``docs/findings/performance.md`` lesson 11); a holder stopped for longer
is no longer waited for."""

GAVE_UP_NOTICE = ("ftc-mc: the other process has not finished compiling after {:.0f} s; "
                  "compiling here")


def lock_path(dispatcher, path=None) -> Path:
    """The compile lock of ``dispatcher`` (of its compile ``path``): a file beside
    its cached overloads (the folder of :func:`ftc_mc.core.jit.cache_dir`, or
    ``NUMBA_CACHE_DIR``)."""
    tag = "" if path is None else "." + re.sub(r"[^a-z0-9]+", "-", describe(path).lower())
    return Path(numba.config.CACHE_DIR) / f"{dispatcher.py_func.__name__}{tag}.compile.lock"


EXPECTED_COMPILE = {LinearPlant: "30 s", NonlinearPlant: "30 s",
                    SixdofPlant: "30-45 s", SixdofExtendedPlant: "30-45 s"}
"""What the compile notice says a path's cold compile takes, by its plant marker
(``core/shared/paths.py``), on 2 cores with the compile helper
(:mod:`ftc_mc.sim.compile_helper`), each path on an empty cache
(``scripts/benchmarks/bench_compile.py``, once the stages were called by
address: ``docs/findings/performance.md`` lesson 17): the default (linear) path 22.8 s
(``scripts/benchmarks/bench_campaign.py``'s ``compile_s``, setup included: 24.0-25.8 s),
the paper's design on the nonlinear plant 21.8 s, ``robust`` 28.8 s, the
paper's design on the 6-DOF plant 32.8 s; measured again later, the same 33.6
and 36.1 s, and the paper's design on the 6-DOF plant with the extended side
monitor (``configs/sixdof_moderate.yaml``) 34.5 and 33.7 s."""


def expected_compile(path) -> str:
    """The duration :data:`EXPECTED_COMPILE` gives the compile ``path``."""
    return EXPECTED_COMPILE[LinearPlant if path is None else type(path.plant)]


@contextlib.contextmanager
def compiled_once(dispatcher, path=None, stream=None):
    """Run the ``with`` block, which calls ``dispatcher`` (on the compile
    ``path``, its first argument) first in this process, as the machine's only
    compile of it.

    When the call would compile (:func:`ftc_mc.core.jit.needs_compile`), the
    block waits for the compile lock (:func:`lock_path`), saying so on
    ``stream`` (stderr) if another process holds it (at most
    :data:`WAIT_LIMIT_S`).  If the holder filled the cache meanwhile, the lock
    is let go at once and the block loads the kernel; otherwise the block
    announces the compile (:func:`ftc_mc.core.jit.announce_compile`) and runs
    holding the lock, with a compile helper (:mod:`ftc_mc.sim.compile_helper`)
    compiling part of the stages of ``path`` in a second process meanwhile,
    while this process compiles the other part before the block; the helper
    is ended when the block ends.
    Without a disk cache (``FTC_MC_NUMBA_CACHE=0``) there is nothing to share:
    the block only announces.

    Parameters
    ----------
    dispatcher : numba dispatcher
        The kernel the block calls (``advance``).
    path : Path, optional
        The compile path the block calls it on (``core/shared/paths.py``); the notice
        names it, and when the compile is done says how long it took.
    stream : file, optional
        Where the notices go (default stderr).
    """
    first = None if path is None else numba.typeof(path)
    what = "" if path is None else describe(path)
    out = sys.stderr if stream is None else stream
    needed = jit.needs_compile(dispatcher, first)
    if not jit.CACHE or needed is not True:
        with _timed(jit.announce_compile(dispatcher, what, expected_compile(path), out,
                                         needed), out):
            yield
        return

    def say_wait():
        print(WAIT_NOTICE, file=out, flush=True)

    def give_up():
        print(GAVE_UP_NOTICE.format(WAIT_LIMIT_S), file=out, flush=True)

    with contextlib.ExitStack() as stack:
        stack.enter_context(waiting(lock_path(dispatcher, path), on_wait=say_wait,
                                    timeout_s=WAIT_LIMIT_S, on_timeout=give_up))
        needed = jit.needs_compile(dispatcher, first)  # again: the holder may have filled it
        own = []  # this process's share of the path's stages (compile_helper.split)
        if needed is not True:
            stack.close()  # the holder filled the cache: load it without the lock
        elif path is not None:
            proc, own = compile_helper.start(path)
            stack.callback(compile_helper.stop, proc)
        with _timed(jit.announce_compile(dispatcher, what, expected_compile(path), out,
                                         needed), out):
            compile_helper.compile_own(own)
            yield


@contextlib.contextmanager
def _timed(announced: bool, out):
    """Say how long the block took (:data:`ftc_mc.core.jit.COMPILED_NOTICE`)
    when a compile was announced before it."""
    t0 = time.perf_counter()
    yield
    if announced:
        print(jit.COMPILED_NOTICE.format(time.perf_counter() - t0), file=out, flush=True)
