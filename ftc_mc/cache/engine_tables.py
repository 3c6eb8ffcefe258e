"""The Theorem 4.1 engine-fault tables, cached on disk.

:func:`ftc_mc.design.theorem41.engine_fault_tables` solves one discounted
Riccati equation per grid point of ``(b0, b1)``; the tables are kept as
``<cache>/engine_tables/<sha256>.npz`` (:func:`ftc_mc.cache.store.default_cache_dir`),
written atomically.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from ..core.shared.interp import EngineTables
from ..design.theorem41 import TABLES_VERSION, _defaults, engine_fault_tables
from .store import default_cache_dir, write_atomic


def _hash_array(h, name, a):
    a = np.ascontiguousarray(a, dtype=np.float64)
    h.update(f"{name}:{a.shape}:".encode())
    h.update(a.tobytes())


def engine_tables_key(plant, b0_grid=None, b1_grid=None, Q=None, R=None, alpha=None) -> str:
    """SHA-256 cache key of every input of :func:`~ftc_mc.design.theorem41.engine_fault_tables`.

    Covers ``A``, ``B``, ``u0``, both grids, ``Q``, ``R``, ``alpha``,
    :data:`~ftc_mc.design.theorem41.TABLES_VERSION` and the OpenBLAS kernels in
    force (``ftc_mc/blas.py``: tables computed with other kernels differ in
    their last bits), defaults resolved first, so passing a default explicitly
    gives the same key.

    Returns
    -------
    str
        64 hexadecimal digits.
    """
    b0_grid, b1_grid, Q, R, alpha = _defaults(plant, b0_grid, b1_grid, Q, R, alpha)
    h = hashlib.sha256()
    h.update(TABLES_VERSION.encode())
    h.update(f"blas:{os.environ.get('OPENBLAS_CORETYPE')}".encode())
    for name, a in (("A", plant.A), ("B", plant.B), ("u0", plant.u0), ("b0_grid", b0_grid),
                    ("b1_grid", b1_grid), ("Q", Q), ("R", R), ("alpha", [alpha])):
        _hash_array(h, name, a)
    return h.hexdigest()


def cached_engine_tables(plant, b0_grid=None, b1_grid=None, Q=None, R=None, alpha=None,
                         cache_dir=None):
    """:func:`~ftc_mc.design.theorem41.engine_fault_tables`, cached on disk as ``.npz``.

    The file is ``<cache_dir>/engine_tables/<sha256>.npz`` with the key of
    :func:`engine_tables_key`; it is written atomically (temporary file in the
    same folder, then ``os.replace``), so concurrent processes at worst compute
    the same tables twice.  An unreadable or mismatching file is recomputed and
    replaced.

    Parameters
    ----------
    plant, b0_grid, b1_grid, Q, R, alpha
        As in :func:`~ftc_mc.design.theorem41.engine_fault_tables`.
    cache_dir : str or Path, optional
        Cache root; default :func:`~ftc_mc.cache.store.default_cache_dir`
        (``~/.cache/ftc-mc/design``, or ``$FTC_MC_CACHE_DIR/design``).

    Returns
    -------
    EngineTables
    """
    key = engine_tables_key(plant, b0_grid, b1_grid, Q, R, alpha)
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = folder / "engine_tables" / f"{key}.npz"
    if path.exists():
        try:
            with np.load(path, allow_pickle=False) as z:
                if str(z["key"]) == key:
                    return EngineTables(K=np.ascontiguousarray(z["K"]),
                                        k=np.ascontiguousarray(z["k"]),
                                        b0_grid=np.ascontiguousarray(z["b0_grid"]),
                                        b1_grid=np.ascontiguousarray(z["b1_grid"]))
        except (OSError, ValueError, KeyError):
            pass  # corrupt or foreign file: recompute below
    tables = engine_fault_tables(plant, b0_grid, b1_grid, Q, R, alpha)
    # a file object: np.savez would append ".npz" to a name
    write_atomic(path, lambda f: np.savez(
        f, key=np.array(key), version=np.array(TABLES_VERSION), K=tables.K, k=tables.k,
        b0_grid=tables.b0_grid, b1_grid=tables.b1_grid))
    return tables


__all__ = ["engine_tables_key", "cached_engine_tables"]
