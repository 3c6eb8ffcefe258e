"""Kernels compiled without their Python wrappers (``core/jit.py``:
``kernel(internal=True)``, :class:`ftc_mc.core.jit.InternalKernel`).

Such a kernel is called by other kernels as any kernel; a call from Python goes
to a twin compiled from the same function with its wrappers, cached in an index
of its own.  Checked on ``core/shared/excitation.saturate`` (eq. 15) against
its own Python function.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numba
import numpy as np

from ftc_mc.core import jit
from ftc_mc.core.longitudinal.trial import advance
from ftc_mc.core.shared.excitation import saturate

CASES = list(itertools.product([-1.2, -0.95, 0.0, 0.3, 0.95, 1.2], [0.0, 0.1, -0.1], [0.0, 0.2]))


@numba.njit
def _saturate_in_a_kernel(U, s, A):
    return saturate(U, s, A, -1.0, 1.0)


def test_an_internal_kernel_has_no_wrappers_and_is_called_from_kernels():
    assert isinstance(saturate, jit.InternalKernel)
    for opt in jit.NO_WRAPPERS:
        assert saturate.targetoptions[opt] is True
    for U, s, A in CASES:
        assert _saturate_in_a_kernel(U, s, A) == saturate.py_func(U, s, A, -1.0, 1.0)
    # the internal kernel's own overload was compiled (or loaded) for that call
    assert (numba.float64,) * 5 in saturate.overloads


def test_a_call_from_python_goes_to_a_twin_with_wrappers_and_its_own_index():
    for U, s, A in CASES:
        assert saturate(U, s, A, -1.0, 1.0) == saturate.py_func(U, s, A, -1.0, 1.0)
    twin = saturate._python_twin
    assert type(twin) is not jit.InternalKernel and twin.py_func is saturate.py_func
    assert not any(twin.targetoptions.get(opt) for opt in jit.NO_WRAPPERS)
    assert {k: v for k, v in twin.targetoptions.items() if k not in jit.NO_WRAPPERS} == \
        {k: v for k, v in saturate.targetoptions.items() if k not in jit.NO_WRAPPERS}
    if jit.CACHE:
        own = Path(saturate._cache._cache_file._index_path)
        other = Path(twin._cache._cache_file._index_path)
        assert own.parent == other.parent and own != other
        assert other.name.startswith(own.name.split(".py")[0] + "-python")


def test_entry_kernels_keep_their_wrappers():
    """The kernels Python calls in a run (here the trial kernel) are not internal."""
    assert not isinstance(advance, jit.InternalKernel)
    assert not any(advance.targetoptions.get(opt) for opt in jit.NO_WRAPPERS)


def test_an_internal_kernel_called_from_python_with_arrays():
    """Arrays through the twin: ``interp.locate`` against its Python function."""
    from ftc_mc.core.shared.interp import locate
    assert isinstance(locate, jit.InternalKernel)
    grid = np.array([0.0, 1.0, 2.5, 4.0])
    for x in (-1.0, 0.0, 0.5, 2.5, 3.9, 5.0):
        assert locate(grid, x) == locate.py_func(grid, x)
