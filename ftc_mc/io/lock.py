"""Output-directory lock: one ftc-mc command writes a folder at a time.

The lock is an exclusive ``flock`` held on the open file ``<dir>/.ftc-mc.lock``
for as long as the command runs.  The kernel drops it when the holder's file is
closed, so when the holder exits or dies (even by SIGKILL) nothing stale is left
to recover: a leftover file that no process has locked is simply taken.  The
file's text only describes the holder, for the message a refused command shows::

    {"pid": 4242, "hostname": "vm", "started": "2026-01-02T03:04:05.123456+00:00",
     "command": "ftc-mc run configs/elevon_lock.yaml"}

On release the holder deletes the file while still holding it, and only if the
path still names the file it locked.  A process that locked a file which was
meanwhile deleted from the path sees so and tries again, so two processes never
both hold one directory.

:func:`waiting` is the same ``flock`` for work that others wait for rather than
refuse, such as the one compile of the trial kernel: it blocks (with a time
limit) while the file is held, and leaves the file in place.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import shlex
import socket
import sys
import time
from pathlib import Path

from ..errors import UserError

LOCK_NAME = ".ftc-mc.lock"
"""File name of the lock inside the output directory."""

_WAIT_S = 0.25
"""How long a busy lock is tried again before refusing [s]: a :func:`holder`
probe or a holder still writing its text keeps the file busy for microseconds."""

try:
    import fcntl

    def _try_lock(fd: int, shared: bool = False) -> bool:
        """Take ``flock`` on ``fd`` without waiting; False if another file holds it."""
        try:
            fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True
except ImportError:  # Windows: lock one byte far past the text (not tested here)
    import msvcrt

    def _try_lock(fd: int, shared: bool = False) -> bool:
        os.lseek(fd, 1 << 30, os.SEEK_SET)
        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the file open as ``fd``."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except FileNotFoundError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _read_info(path: Path) -> dict | None:
    """The holder's fields from the lock file's text, or None if unreadable."""
    try:
        with open(path, "rb") as f:
            info = json.loads(f.read(65536).decode("utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return None
    return info if isinstance(info, dict) else None


def _one_line(text, limit: int) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _describe(info: dict | None, directory: Path) -> str:
    """One line naming the directory and, as far as known, its holder."""
    info = info or {}
    who = f" pid {info['pid']}" if "pid" in info else " another process"
    host = info.get("hostname")
    if isinstance(host, str) and host != socket.gethostname():
        who += f" on host {_one_line(host, 80)}"
    cmd = info.get("command")
    if isinstance(cmd, str) and cmd.strip():
        who += f" ({_one_line(cmd, 120)})"
    if isinstance(info.get("started"), str):
        who += f", started {_one_line(info['started'], 40)}"
    return (f"{directory}: output directory is in use by{who}; wait for it to finish "
            "or choose another --out")


class OutputLock:
    """Exclusive lock on an output directory, held for the duration of a ``with``.

    Parameters
    ----------
    directory : str or Path
        Output directory; created (with parents) if missing, and the folders this
        lock created are removed again on release while they are empty.
    command : str, optional
        Written to the lock file for the message another process shows;
        default: this process's command line.

    Attributes
    ----------
    path : Path
        The lock file, ``directory / ".ftc-mc.lock"``.
    info : dict or None
        The fields written to the lock file while held.
    """

    def __init__(self, directory, command: str | None = None):
        self.directory = Path(directory)
        self.path = self.directory / LOCK_NAME
        self.command = command if command is not None else shlex.join(sys.argv)
        self.info: dict | None = None
        self._fd: int | None = None
        self._owner_pid: int | None = None
        self._created_dirs: list[Path] = []

    def __enter__(self) -> OutputLock:
        self.acquire()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.release()

    @property
    def held(self) -> bool:
        """Whether this object currently holds the lock."""
        return self._fd is not None

    def acquire(self) -> None:
        """Take the lock.

        Raises
        ------
        UserError
            Another open file holds the lock (the message names the directory and
            the holder's pid and command), or the directory or the lock file
            cannot be created.
        """
        if self.held:
            raise UserError(f"{self.directory}: lock already held by this object")
        self._make_dir()
        try:
            self._fd = self._lock_file()
        except BaseException:
            self._cleanup_dir()
            raise
        self._owner_pid = os.getpid()

    def _lock_file(self) -> int:
        deadline = time.monotonic() + _WAIT_S
        while True:
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as exc:  # e.g. the lock path is a folder, or no permission
                raise UserError(f"{self.directory}: cannot use the lock file {self.path} "
                                f"({exc.strerror or exc})") from None
            try:
                got = _try_lock(fd)
                if got and _same_file(fd, self.path):
                    self.info = {"pid": os.getpid(), "hostname": socket.gethostname(),
                                 "started": _dt.datetime.now(_dt.timezone.utc).isoformat(),
                                 "command": self.command}
                    os.ftruncate(fd, 0)
                    os.lseek(fd, 0, os.SEEK_SET)
                    os.write(fd, (json.dumps(self.info) + "\n").encode())
                    return fd
            except OSError as exc:  # a file system without locks, a full disk...
                os.close(fd)
                raise UserError(f"{self.directory}: cannot lock {self.path} "
                                f"({exc.strerror or exc})") from None
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)  # busy, or deleted from the path meanwhile: look again
            if not got and time.monotonic() > deadline:
                raise UserError(_describe(_read_info(self.path), self.directory))
            time.sleep(0.01)

    def release(self) -> None:
        """Delete the lock file if the path still names ours, and unlock (no-op if
        not held).  A process forked while the lock was held does not release it."""
        if self._fd is None or self._owner_pid != os.getpid():
            return
        fd, self._fd = self._fd, None
        try:
            if _same_file(fd, self.path):
                self.path.unlink()
        except OSError:
            pass
        finally:
            os.close(fd)  # closing the last descriptor drops the lock
        self._cleanup_dir()

    def _make_dir(self) -> None:
        d = self.directory
        try:
            if d.exists() and not d.is_dir():
                raise UserError(f"--out: {d} exists and is not a directory")
            missing, p = [], d.absolute()
            while not p.exists() and p != p.parent:
                missing.append(p)  # deepest first
                p = p.parent
            d.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UserError(f"--out: cannot create {d} ({exc.strerror})") from None
        self._created_dirs = missing

    def _cleanup_dir(self) -> None:
        """Remove the folders this lock created, deepest first, while they are empty."""
        created, self._created_dirs = self._created_dirs, []
        for p in created:
            try:
                p.rmdir()  # only succeeds if still empty
            except OSError:
                break


def acquire(directory, command: str | None = None) -> OutputLock:
    """Lock an output directory for the duration of a ``with`` block.

    Parameters
    ----------
    directory : str or Path
        Output directory (created if missing; removed on release if this call
        created it and nothing was written into it).
    command : str, optional
        Command written to the lock file; default: ``sys.argv`` joined.

    Returns
    -------
    OutputLock
        A context manager; the lock is taken on entry and released on exit,
        also when the block raises.

    Raises
    ------
    UserError
        On entry, if another process (or another lock in this one) holds the
        directory, or the directory is not writable.

    Examples
    --------
    >>> with acquire(out_dir, command="ftc-mc run cfg.yaml"):   # doctest: +SKIP
    ...     prepare_output_dir(out_dir, overwrite)
    ...     write_summary(out_dir, ...)
    """
    return OutputLock(directory, command=command)


def holder(directory) -> dict | None:
    """The fields of the process holding ``directory``'s lock, or None if it is free.

    Returns
    -------
    dict or None
        ``pid``, ``hostname``, ``started`` and ``command`` of the holder (None
        values if it has not written them yet).
    """
    path = Path(directory) / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return None
    try:
        if _try_lock(fd, shared=True):
            return None  # nobody holds it; closing drops our probe
    except OSError:
        return None  # a file system without locks: no holder can be seen
    finally:
        os.close(fd)
    deadline = time.monotonic() + _WAIT_S
    info = _read_info(path)
    while info is None and time.monotonic() < deadline:  # holder between lock and write
        time.sleep(0.01)
        info = _read_info(path)
    return {"pid": None, "hostname": None, "started": None, "command": None, **(info or {})}


@contextlib.contextmanager
def waiting(path, on_wait=None, poll_s: float = 0.5, timeout_s: float | None = None,
            on_timeout=None):
    """Hold an exclusive lock on the file ``path`` for a ``with`` block, waiting
    while another process (or another open of it in this one) holds it.

    Unlike :class:`OutputLock` this waits instead of refusing, and leaves the
    file in place: it serialises work that others then reuse, such as the one
    compile of the trial kernel (:func:`ftc_mc.sim.compiling.compiled_once`).
    A holder that dies drops the lock with its file descriptor.

    Parameters
    ----------
    path : str or Path
        The lock file; created with its folders if missing.
    on_wait : callable, optional
        Called once, without arguments, when the lock is busy at first.
    poll_s : float
        How often a busy lock is tried again [s].
    timeout_s : float, optional
        Longest wait [s]; then the block runs unguarded (a holder stopped in a
        debugger, or a file system whose locks always look busy).  None: no limit.
    on_timeout : callable, optional
        Called once, without arguments, when ``timeout_s`` runs out.

    Yields
    ------
    bool
        True when the lock is held; False when the file cannot be opened or
        locked (a read-only folder, a file system without locks) or the wait
        ran out, in which case the block runs unguarded.
    """
    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield False
        return
    try:
        try:
            held = _try_lock(fd)
            if not held and on_wait is not None:
                on_wait()
            deadline = None if timeout_s is None else time.monotonic() + timeout_s
            while not held:
                if deadline is not None and time.monotonic() >= deadline:
                    if on_timeout is not None:
                        on_timeout()
                    break
                time.sleep(poll_s)
                held = _try_lock(fd)
        except OSError:  # no locks on this file system
            held = False
        yield held
    finally:
        os.close(fd)  # drops the lock
