"""The on-disk cache of offline computations: its folder, its keys, and atomic writes into it.

A cache file is written under a temporary name in its final folder and then
renamed onto its name (``os.replace``), so a reader never sees a half-written
file and concurrent processes at worst compute the same design twice.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

from ..io.atomic import new_file_mode


def default_cache_dir() -> Path:
    """Folder of the design cache.

    ``$FTC_MC_CACHE_DIR/design`` when the environment variable is set (it names
    the root of all ftc-mc caches), else ``~/.cache/ftc-mc/design``.
    """
    root = os.environ.get("FTC_MC_CACHE_DIR")
    if root:
        return Path(root).expanduser() / "design"
    return Path.home() / ".cache" / "ftc-mc" / "design"


def write_atomic(path: Path, write) -> None:
    """Call ``write(f)`` on a binary file that replaces ``path`` only once complete.

    Parameters
    ----------
    path : Path
        Final file name; its folder is created if missing.
    write : callable
        Writes the content to the open binary file object it is given.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.fchmod(fd, new_file_mode())  # mkstemp's 0600 would survive the rename
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def design_key(version: str, *parts, arrays=()) -> str:
    """SHA-256 cache key of a design: ``version``, the OpenBLAS kernels in
    force (``ftc_mc/blas.py``: they decide a design's last bits), each of
    ``parts`` as text, then each of ``arrays`` as float64 with its shape."""
    h = hashlib.sha256()
    h.update(version.encode())
    h.update(f"blas:{os.environ.get('OPENBLAS_CORETYPE')}".encode())
    for part in parts:
        h.update(part.encode() if isinstance(part, str) else part)
    for a in arrays:
        b = np.ascontiguousarray(a, dtype=np.float64)
        h.update(repr(b.shape).encode())
        h.update(b.tobytes())
    return h.hexdigest()
