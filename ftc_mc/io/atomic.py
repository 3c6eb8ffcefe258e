"""Atomic file writing: write to a temporary file in the target folder, then rename.

A reader never sees a half-written file under its final name, and a failed
write leaves the previous file (if any) untouched.  The file gets the mode any
other tool would give it, ``0o666`` less the process's umask (0644 under umask
022): :func:`tempfile.mkstemp` creates its files with mode 0600, and
``os.replace`` keeps the mode of the temporary file, so every writer here sets
it (:func:`new_file_mode`) before the rename.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import threading
from pathlib import Path

_UMASK_LOCK = threading.Lock()


def current_umask() -> int:
    """The process's umask, read without changing it where the system allows.

    Linux reports it in ``/proc/self/status`` (kernel 4.7 and later); elsewhere
    it is read by setting and restoring it under a lock (``os.umask`` has no
    read-only form).
    """
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    with _UMASK_LOCK:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def new_file_mode() -> int:
    """Mode of a new regular file under the current umask (``0o666 & ~umask``)."""
    return 0o666 & ~current_umask()


def temp_path(path: Path, suffix: str = "") -> Path:
    """A new empty temporary file beside ``path`` (its folder is created), with
    the mode of :func:`new_file_mode`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix + ".tmp",
                               dir=path.parent)
    try:
        os.fchmod(fd, new_file_mode())
    finally:
        os.close(fd)
    return Path(tmp)


def commit(tmp: Path, path: Path) -> None:
    """Flush ``tmp`` to disk and rename it onto ``path``."""
    with open(tmp, "rb") as f:
        os.fsync(f.fileno())
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path, suffix=""):
    """Yield a temporary path beside ``path``; rename it onto ``path`` on success.

    Parameters
    ----------
    path : str or Path
        Final file name.
    suffix : str
        Suffix of the temporary name (some writers infer the format from it).

    Yields
    ------
    Path
        Where to write (mode ``0o666 & ~umask``).  Removed if the block raises.
    """
    path = Path(path)
    tmp = temp_path(path, suffix)
    try:
        yield tmp
        commit(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
