"""Interrupts that stop: SIGINT (Ctrl-C) and SIGTERM (batch schedulers) end a long
command within seconds, keeping what is finished.

The one mechanism of every long command (``ftc-mc run``, ``ftc-mc sweep``, and
any later one that runs chunks): inside :func:`stop_on_signals`, the first
SIGINT or SIGTERM raises :class:`Interrupted` in the main thread, which unwinds
the command through its ``finally`` blocks (a file being written is removed
before it gets its final name, the output folder's lock is released, worker
processes are stopped); a second signal ends the process at once
(``os._exit``), whatever it was doing.  The command's workers never block the
main thread: it waits for chunks with a timeout (``campaign/parallel.py``),
so the signal is handled as soon as it arrives, not when the running Numba
kernels return.

The exit status is the shell's convention for a process ended by a signal:
128 + the signal number, i.e. 130 for SIGINT and 143 for SIGTERM.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

SIGNALS = (signal.SIGINT, signal.SIGTERM)
"""The signals that stop a command."""


class Interrupted(KeyboardInterrupt):
    """A stop signal arrived (a ``KeyboardInterrupt``, so code that already handles
    Ctrl-C handles SIGTERM the same way).

    Attributes
    ----------
    signum : int
        The signal (``signal.SIGINT`` or ``signal.SIGTERM``).
    """

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)

    @property
    def exit_code(self) -> int:
        """128 + the signal number: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


def exit_code(exc: BaseException) -> int:
    """The exit status for an interrupt: :attr:`Interrupted.exit_code`, or 130 for
    a plain ``KeyboardInterrupt`` (Ctrl-C under Python's own handler)."""
    return exc.exit_code if isinstance(exc, Interrupted) else 128 + signal.SIGINT


def hard_exit(code: int) -> None:
    """Flush stdout and stderr and end the process now (``os._exit``): worker
    threads inside a Numba kernel are not waited for, and no atexit handler runs
    (the caller has already released what it held)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


@contextlib.contextmanager
def stop_on_signals():
    """Inside the block, SIGINT and SIGTERM raise :class:`Interrupted` once; a second
    one ends the process at once with 128 + its number.

    Outside the main thread (where handlers cannot be set) the block runs with
    the handlers it finds.  The previous handlers come back when the block ends.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in SIGNALS}

    def again(signum, frame):
        os.write(2, f"\n{signal.Signals(signum).name} again: stopping now\n".encode())
        os._exit(128 + signum)

    def first(signum, frame):
        for s in SIGNALS:
            signal.signal(s, again)
        raise Interrupted(signum)

    for s in SIGNALS:
        signal.signal(s, first)
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
