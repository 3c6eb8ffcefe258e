"""The trimmable set of an airframe's equations, cached on disk.

:func:`ftc_mc.model.trimmable.equations_trimmable_set` runs about 20
steady-flight searches per elevon: both elevons of ``x8-pyfly`` in 75 s on 2
cores, of ``x8-gryte2018`` in 14 s.  A run on the
6-DOF nonlinear plant with elevon-lock rows reports its survival inside and
outside that set (:func:`ftc_mc.campaign.survival.trimmable_sets`), so the
set is found once per airframe and envelope and kept as JSON under
``<cache>/trimmable/<sha256>.json`` (:func:`ftc_mc.cache.store.default_cache_dir`),
written atomically.  The two elevons are searched in parallel.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
from pathlib import Path

from ..model.airframe import Airframe
from ..model.sixdof import trim6
from ..model.trimmable import Envelope, equations_trimmable_set
from .store import default_cache_dir, design_key, write_atomic

TRIMMABLE_SET_VERSION = "1"
"""Bump when :func:`~ftc_mc.model.trimmable.steady_flight` or the bisection
changes what they find: older cache files then no longer match."""


def trimmable_set_key(airframe: Airframe, side: str, envelope: Envelope) -> str:
    """SHA-256 key of every input of the search: the packed 6-DOF parameters
    and command limits of the airframe, the side, the envelope,
    :data:`TRIMMABLE_SET_VERSION` and the OpenBLAS kernels in force."""
    return design_key(TRIMMABLE_SET_VERSION, f"{side}:{dataclasses.astuple(envelope)!r}",
                      arrays=(trim6(airframe).params, airframe.command_lower,
                              airframe.command_upper))


def cached_trimmable_sets(airframe: Airframe, sides, envelope: Envelope = Envelope(),
                          name: str = "the airframe", cache_dir=None, stream=None) -> dict:
    """:func:`~ftc_mc.model.trimmable.equations_trimmable_set` of each side,
    from the cache or found and cached.

    Parameters
    ----------
    airframe : Airframe
    sides : iterable of str
        ``"left"``, ``"right"``.
    envelope : Envelope
    name : str
        The airframe's name, for the notice.
    cache_dir : str or Path, optional
        Cache root; default :func:`~ftc_mc.cache.store.default_cache_dir`.
    stream : file, optional
        Where the notice goes when a set is searched (default stderr).

    Returns
    -------
    dict
        Side -> ``(lo, hi)`` [rad, absolute] or None (no steady flight at trim).
    """
    folder = (Path(cache_dir) if cache_dir is not None else default_cache_dir()) / "trimmable"
    out, todo = {}, []
    for side in sides:
        key = trimmable_set_key(airframe, side, envelope)
        path = folder / f"{key}.json"
        ends = _read(path, key)
        if ends is not _MISSING:
            out[side] = ends
            continue
        todo.append((side, key, path))
    if todo:
        print(f"ftc-mc: finding the trimmable set of {name}'s equations "
              f"({', '.join(s for s, _, _ in todo)} elevon; a bisection of steady "
              "flights, up to a minute or two; cached afterwards)", file=stream or sys.stderr,
              flush=True)
        from joblib import Parallel, delayed

        found = Parallel(n_jobs=min(2, len(todo)))(
            delayed(equations_trimmable_set)(airframe, side, envelope) for side, _, _ in todo)
        for (side, key, path), ends in zip(todo, found):
            out[side] = ends
            text = json.dumps({"key": key, "ends": None if ends is None else list(ends)})
            try:
                write_atomic(path, lambda f, t=text: f.write(t.encode()))
            except OSError as e:  # a read-only or full cache: the set is still known
                print(f"ftc-mc: warning: could not cache the trimmable set in {path.parent} "
                      f"({e.strerror or e}); it is searched again next time",
                      file=stream or sys.stderr, flush=True)
    return out


_MISSING = object()
"""What :func:`_read` returns for a cache file that is absent or unusable."""


def _read(path: Path, key: str):
    """The cached ends of ``path`` (``(lo, hi)`` or None), or :data:`_MISSING`
    when the file is absent, unreadable, of another key, or not two finite
    increasing numbers."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return _MISSING
    if not isinstance(data, dict) or data.get("key") != key or "ends" not in data:
        return _MISSING
    ends = data["ends"]
    if ends is None:
        return None
    if (isinstance(ends, list) and len(ends) == 2
            and all(isinstance(v, (int, float)) and math.isfinite(v) for v in ends)
            and ends[0] <= ends[1]):
        return (float(ends[0]), float(ends[1]))
    return _MISSING
