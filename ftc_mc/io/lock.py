"""Output-directory lock: one ``ftc-mc run`` or ``ftc-mc scenario`` per folder.

The lock is the file ``<dir>/.ftc-mc.lock``, created atomically with
``O_CREAT | O_EXCL`` and holding a JSON object::

    {"pid": 4242, "hostname": "vm", "started": "2026-01-02T03:04:05.123456+00:00",
     "command": "ftc-mc run configs/elevon_lock.yaml", "token": "9f1c..."}

A second process that finds the file refuses with a one-line
:class:`~ftc_mc.errors.UserError` naming the directory and the owner's pid,
unless the lock is stale:

* same host, and the owner pid no longer exists (``os.kill(pid, 0)`` raises
  :class:`ProcessLookupError`; :class:`PermissionError` means the process exists
  under another user, so the lock is live), or the pid now belongs to a process
  started after the lock was taken (pid reuse, checked on Linux through
  ``/proc``);
* another host, and the lock is older than ``max_age_s`` (the pid cannot be
  checked from here, so a recent foreign lock is always live);
* the file is not a valid lock (empty, not JSON, missing fields) and stays so
  for a short settling time (a writer may be between ``O_EXCL`` and ``write``).

A stale lock is replaced atomically (write a temporary file, ``os.replace``)
while holding ``flock`` on the directory itself, so that of several processes
racing to take over the same stale lock exactly one wins.  The lock is removed
when the ``with`` block ends, normally or by an exception, but only if it is
still ours.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import shlex
import socket
import sys
import tempfile
import time
import uuid
from pathlib import Path

from ..errors import UserError

LOCK_NAME = ".ftc-mc.lock"
"""File name of the lock inside the output directory."""

DEFAULT_MAX_AGE_S = 7 * 24 * 3600.0
"""Age [s] after which a lock taken on another host counts as stale (7 days)."""

_SETTLE_S = 0.25
"""How long an unreadable lock file may stay unreadable before it is corrupt [s]."""

_START_TOLERANCE_S = 30.0
"""Slack [s] when comparing a process start time with a lock's ``started`` (clock
steps, ``btime`` rounding); a pid reused sooner than this still counts as live."""

_ATTEMPTS = 20


def _now() -> _dt.datetime:
    return _dt.datetime.now(_dt.timezone.utc)


def _hostname() -> str:
    return socket.gethostname()


def _read(path: Path) -> bytes | None:
    """Raw bytes of the lock file, or None if it does not exist."""
    try:
        with open(path, "rb") as f:
            return f.read(65536)
    except FileNotFoundError:
        return None


def _decode(raw: bytes) -> dict | None:
    """The lock's fields, or None if ``raw`` is not a valid lock."""
    try:
        info = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        return None
    if not isinstance(info, dict):
        return None
    pid, host, started = info.get("pid"), info.get("hostname"), info.get("started")
    if (not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0
            or not isinstance(host, str) or not isinstance(started, str)):
        return None
    try:
        when = _dt.datetime.fromisoformat(started)
    except ValueError:
        return None
    if when.tzinfo is None:
        when = when.replace(tzinfo=_dt.timezone.utc)
    return dict(info, started_at=when)


def _pid_exists(pid: int) -> bool:
    """Whether a process with this pid exists on this host."""
    if os.name == "nt":  # os.kill(pid, 0) would terminate it on Windows
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # exists, owned by another user
    except OverflowError:
        return False  # not a valid pid at all
    return True


def _process_start(pid: int) -> _dt.datetime | None:
    """Start time of process ``pid`` (Linux ``/proc``), or None if unknown."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as f:
            stat = f.read().decode("ascii", "replace")
        ticks = int(stat[stat.rindex(")") + 2:].split()[19])  # field 22: starttime
        with open("/proc/stat", "rb") as f:
            btime = next(int(line.split()[1]) for line in f
                         if line.startswith(b"btime "))
        hz = os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return None
    return _dt.datetime.fromtimestamp(btime + ticks / hz, _dt.timezone.utc)


def _is_live(info: dict, max_age_s: float | None) -> bool:
    """Whether the owner described by ``info`` may still be running."""
    if info["hostname"] != _hostname():
        if max_age_s is None:
            return True
        return (_now() - info["started_at"]).total_seconds() <= max_age_s
    pid = info["pid"]
    if not _pid_exists(pid):
        return False
    start = _process_start(pid)
    if start is not None and (start - info["started_at"]).total_seconds() > _START_TOLERANCE_S:
        return False  # the pid was reused by a process started after the lock
    return True


@contextlib.contextmanager
def _dir_guard(directory: Path):
    """Hold ``flock(LOCK_EX)`` on the directory itself (no-op where unsupported)."""
    try:
        import fcntl
    except ImportError:  # Windows
        yield
        return
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        yield
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:
            pass  # filesystem without flock: best effort
        yield
    finally:
        os.close(fd)  # closing releases the flock


def _one_line(text: str, limit: int) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _describe(info: dict, directory: Path) -> str:
    host = info["hostname"]
    where = "" if host == _hostname() else f" on host {_one_line(host, 80)}"
    cmd = info.get("command")
    what = f" ({_one_line(cmd, 120)})" if isinstance(cmd, str) and cmd.strip() else ""
    return (f"{directory}: output directory is in use by pid {info['pid']}{where}"
            f"{what}, started {info['started']}; wait for it to "
            f"finish or choose another --out (delete {directory / LOCK_NAME} only if "
            "that process is gone)")


class OutputLock:
    """Exclusive lock on an output directory, held for the duration of a ``with``.

    Parameters
    ----------
    directory : str or Path
        Output directory; created (with parents) if missing, and the folders this
        lock created are removed again on release while they are empty.
    command : str, optional
        Recorded in the lock file for the message another process shows;
        default: this process's command line.
    max_age_s : float or None
        A lock taken on another host is live unless older than this [s]; None:
        always live.

    Attributes
    ----------
    path : Path
        The lock file, ``directory / ".ftc-mc.lock"``.
    info : dict or None
        The JSON written to the lock file while held.
    """

    def __init__(self, directory, command: str | None = None,
                 max_age_s: float | None = DEFAULT_MAX_AGE_S):
        self.directory = Path(directory)
        self.path = self.directory / LOCK_NAME
        self.command = command if command is not None else shlex.join(sys.argv)
        self.max_age_s = max_age_s
        self.info: dict | None = None
        self._payload: bytes | None = None
        self._owner_pid: int | None = None
        self._created_dirs: list[Path] = []

    # -- context manager ------------------------------------------------------
    def __enter__(self) -> OutputLock:
        self.acquire()
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.release()

    @property
    def held(self) -> bool:
        """Whether this object currently holds the lock."""
        return self._payload is not None

    # -- acquire / release ----------------------------------------------------
    def acquire(self) -> None:
        """Take the lock, replacing a stale or corrupt one.

        Raises
        ------
        UserError
            The lock is held by a live process (the message names the directory
            and the owner pid), or the directory cannot be created or written.
        """
        if self.held:
            raise UserError(f"{self.directory}: lock already held by this object")
        self._make_dir()
        self.info = {"pid": os.getpid(), "hostname": _hostname(),
                     "started": _now().isoformat(), "command": self.command,
                     "token": uuid.uuid4().hex}
        payload = (json.dumps(self.info) + "\n").encode()
        try:
            for _ in range(_ATTEMPTS):
                if self._create(payload):
                    break
                raw = self._settled_read()
                if raw is None:
                    continue  # released meanwhile: try O_EXCL again
                info = _decode(raw)
                if info is not None and _is_live(info, self.max_age_s):
                    raise UserError(_describe(info, self.directory))
                if self._take_over(raw, payload):
                    break
            else:
                raise UserError(f"{self.directory}: could not take the output-directory "
                                f"lock {self.path} (contended); try again")
        except OSError as exc:  # e.g. the lock path is a folder, or no permission
            self._cleanup_dir()
            raise UserError(f"{self.directory}: cannot use the lock file {self.path} "
                            f"({exc.strerror or exc})") from None
        except BaseException:
            self._cleanup_dir()
            raise
        self._payload = payload
        self._owner_pid = os.getpid()

    def release(self) -> None:
        """Remove the lock file if it is still ours (no-op if not held).

        A process forked while the lock was held does not release it.
        """
        if not self.held or self._owner_pid != os.getpid():
            return
        payload, self._payload = self._payload, None
        try:
            with _dir_guard(self.directory):
                if _read(self.path) == payload:
                    self.path.unlink()
        except OSError:
            pass
        self._cleanup_dir()

    # -- helpers --------------------------------------------------------------
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

    def _create(self, payload: bytes) -> bool:
        """Create the lock file with O_EXCL; False if it already exists."""
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            return False
        except OSError as exc:
            raise UserError(f"{self.directory}: cannot create the lock file "
                            f"{self.path} ({exc.strerror})") from None
        try:
            os.write(fd, payload)
            os.fsync(fd)
        except OSError as exc:
            os.close(fd)
            with contextlib.suppress(OSError):
                self.path.unlink()
            raise UserError(f"{self.directory}: cannot write the lock file "
                            f"{self.path} ({exc.strerror})") from None
        os.close(fd)
        return True

    def _settled_read(self) -> bytes | None:
        """The lock file's bytes, re-read for a moment while they are not a valid lock."""
        deadline = time.monotonic() + _SETTLE_S
        while True:
            raw = _read(self.path)
            if raw is None or _decode(raw) is not None or time.monotonic() > deadline:
                return raw
            time.sleep(0.02)

    def _take_over(self, stale: bytes, payload: bytes) -> bool:
        """Replace the lock file if it still holds ``stale``; True on success."""
        fd, tmp = tempfile.mkstemp(prefix=LOCK_NAME + ".", suffix=".tmp",
                                   dir=self.directory)
        try:
            os.write(fd, payload)
            os.fsync(fd)
            os.close(fd)
            fd = -1
            with _dir_guard(self.directory):
                if _read(self.path) != stale:
                    return False  # changed meanwhile: look again
                os.replace(tmp, self.path)
                return True
        finally:
            if fd >= 0:
                os.close(fd)
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def acquire(directory, command: str | None = None,
            max_age_s: float | None = DEFAULT_MAX_AGE_S) -> OutputLock:
    """Lock an output directory for the duration of a ``with`` block.

    Parameters
    ----------
    directory : str or Path
        Output directory (created if missing; removed on release if this call
        created it and nothing was written into it).
    command : str, optional
        Command recorded in the lock file; default: ``sys.argv`` joined.
    max_age_s : float or None
        Age [s] after which a lock taken on another host counts as stale; None
        never expires a foreign lock.  Default :data:`DEFAULT_MAX_AGE_S`.

    Returns
    -------
    OutputLock
        A context manager; the lock is taken on entry and released on exit,
        also when the block raises.

    Raises
    ------
    UserError
        On entry, if a live process holds the lock (one line naming the
        directory and the owner pid), or the directory is not writable.

    Examples
    --------
    >>> with acquire(out_dir, command="ftc-mc run cfg.yaml"):   # doctest: +SKIP
    ...     prepare_output_dir(out_dir, overwrite)
    ...     write_run(out_dir, ...)
    """
    return OutputLock(directory, command=command, max_age_s=max_age_s)


def holder(directory, max_age_s: float | None = DEFAULT_MAX_AGE_S) -> dict | None:
    """The fields of the live lock on ``directory``, or None if it is free or stale.

    Parameters
    ----------
    directory : str or Path
    max_age_s : float or None
        As in :func:`acquire`.

    Returns
    -------
    dict or None
        ``pid``, ``hostname``, ``started``, ``command`` (and ``started_at``, a
        datetime) of the owner.
    """
    raw = _read(Path(directory) / LOCK_NAME) if Path(directory).is_dir() else None
    info = _decode(raw) if raw is not None else None
    if info is None or not _is_live(info, max_age_s):
        return None
    return info
