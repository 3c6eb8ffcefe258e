"""The lock-turn controllers' table over lock offsets, cached on disk.

:func:`ftc_mc.design.lock_turn.lock_turn_designs` designs the steady-turn LQR
of each side at each lock offset of a grid; that takes seconds to minutes per
airframe, so the table is kept as ``<cache>/lock_turn/<sha256>.npz``
(:func:`ftc_mc.cache.store.default_cache_dir`), written atomically.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from ..design.lock_turn import (LOCK_TOLERANCE, LOCK_TURN_TABLE_VERSION, DesignBox,
                                DesignWeights, LockTurnDesigns, TurnWeights, lock_turn_designs)
from ..design.theorem41 import ALPHA
from ..model.airframe import Airframe
from ..model.sixdof import trim6
from .store import default_cache_dir, design_key, write_atomic


def lock_turn_designs_key(airframe: Airframe, offsets, V0: float, gamma0_deg: float,
                          dt: float, wide: DesignBox | None = None,
                          linear: bool = False) -> str:
    """SHA-256 cache key of every input of
    :func:`~ftc_mc.design.lock_turn.lock_turn_designs`: the packed 6-DOF
    parameters and command limits of the airframe, the grid, the glide, the
    period, the default design box and weights, the wide box if any, the linear
    model if designed on it, :data:`~ftc_mc.design.lock_turn.LOCK_TURN_TABLE_VERSION`
    and the OpenBLAS kernels in force (``ftc_mc/blas.py``)."""
    parts = [repr((DesignBox(), DesignWeights(), TurnWeights(), ALPHA, LOCK_TOLERANCE))]
    if wide is not None:
        parts.append(f"wide:{wide!r}")
    if linear:
        parts.append("model:linear")
    return design_key(LOCK_TURN_TABLE_VERSION, *parts,
                      arrays=(trim6(airframe, V0, gamma0_deg).params, airframe.command_lower,
                              airframe.command_upper, offsets, [V0, gamma0_deg, dt]))


def cached_lock_turn_designs(airframe: Airframe, offsets, V0: float = 20.0,
                             gamma0_deg: float = -3.0, dt: float = 0.1,
                             cache_dir=None, stream=None,
                             wide: DesignBox | None = None,
                             linear: bool = False) -> LockTurnDesigns:
    """:func:`~ftc_mc.design.lock_turn.lock_turn_designs`, cached on disk as ``.npz``
    (``<cache_dir>/lock_turn/<sha256>.npz``, key :func:`lock_turn_designs_key`,
    written atomically; an unreadable or mismatching file is recomputed).

    Parameters
    ----------
    airframe, offsets, V0, gamma0_deg, dt, wide, linear
        As :func:`~ftc_mc.design.lock_turn.lock_turn_designs`.
    cache_dir : str or Path, optional
        Cache root; default :func:`~ftc_mc.cache.store.default_cache_dir`.
    stream : file, optional
        When the designs are computed (not in the cache), a line saying so
        before and one with the time taken after.

    Returns
    -------
    LockTurnDesigns
    """
    offsets = np.asarray(offsets, dtype=float)
    key = lock_turn_designs_key(airframe, offsets, V0, gamma0_deg, dt, wide, linear)
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    path = folder / "lock_turn" / f"{key}.npz"
    fields = [f.name for f in dataclasses.fields(LockTurnDesigns)]
    if path.exists():
        try:
            with np.load(path, allow_pickle=False) as z:
                if str(z["key"]) == key:
                    return LockTurnDesigns(**{f: np.ascontiguousarray(z[f]) for f in fields})
        except (OSError, ValueError, KeyError):
            pass  # corrupt or foreign file: recompute below
    if stream is not None:
        print(f"ftc-mc: designing the lock-turn controllers ({offsets.size} lock positions "
              "per elevon; cached afterwards)", file=stream, flush=True)
    t0 = time.perf_counter()
    d = lock_turn_designs(airframe, offsets, V0, gamma0_deg, dt, wide, linear)
    if stream is not None:
        print(f"ftc-mc: lock-turn controllers designed in {time.perf_counter() - t0:.1f} s",
              file=stream, flush=True)
    write_atomic(path, lambda f: np.savez(f, key=np.array(key),
                                          **{n: getattr(d, n) for n in fields}))
    return d


__all__ = ["lock_turn_designs_key", "cached_lock_turn_designs"]
