"""The one place that sets how every kernel is compiled.

``FTC_MC_NUMBA_CACHE=0`` in the environment turns Numba's on-disk cache off (for
example while editing kernels in several files, since the cache does not see
edits in other modules).  ``fastmath`` stays off: it was no faster here
(``scripts/bench_core.py``) and breaks bit-for-bit agreement with the NumPy
references.
"""

from __future__ import annotations

import os

import numba

CACHE = os.environ.get("FTC_MC_NUMBA_CACHE", "1") != "0"

OPTIONS = dict(cache=CACHE, fastmath=False, nogil=True, error_model="numpy")


def kernel(func=None, **overrides):
    """``numba.njit`` with the project's defaults (see module docstring).

    Parameters
    ----------
    func : callable, optional
        Function to compile; when omitted, returns a decorator.
    **overrides
        Options that replace the defaults for this kernel.
    """
    opts = dict(OPTIONS, **overrides)
    if func is None:
        return lambda f: numba.njit(**opts)(f)
    return numba.njit(**opts)(func)
