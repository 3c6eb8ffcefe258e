"""The test order that lets xdist workers share the trial kernel's cold compile
(tests/conftest.py)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import TRIAL_KERNEL_FILES, _worksteal_order


def _items(n_piece, n_late):
    late_file = sorted(TRIAL_KERNEL_FILES)[0]
    piece = [SimpleNamespace(path=Path(f"tests/test_piece{i}.py"), fixturenames=[], name=f"p{i}")
             for i in range(n_piece)]
    late = [SimpleNamespace(path=Path(f"tests/{late_file}"), fixturenames=[], name=f"l{i}")
            for i in range(n_late)]
    fixture = [SimpleNamespace(path=Path("tests/test_piece.py"),
                               fixturenames=["trial_kernel"], name="f")]
    return piece + late + fixture


def _parts(order, workers):
    """The contiguous parts xdist's worksteal scheduler hands out first."""
    parts, left = [], list(order)
    for i in range(workers):
        k = len(left) // (workers - i)
        parts.append(left[:k])
        left = left[k:]
    return parts


@pytest.mark.parametrize("n_piece,n_late,workers", [(300, 400, 2), (500, 100, 2),
                                                     (50, 600, 2), (300, 400, 3),
                                                     (10, 3, 4)])
def test_worksteal_order(n_piece, n_late, workers):
    items = _items(n_piece, n_late)
    order = _worksteal_order(items, workers)
    assert sorted(map(id, order)) == sorted(map(id, items))  # a permutation
    parts = _parts(order, workers)
    is_late = [[it.name[0] in "lf" for it in part] for part in parts]
    # the first worker starts with the kernel's tests, as many as fit
    assert is_late[0][:min(n_late + 1, len(parts[0]))] == [True] * min(n_late + 1,
                                                                       len(parts[0]))
    # the others start with piecewise tests while any are left for them
    for flags in is_late[1:]:
        if flags and not all(flags):
            assert not flags[0]
            assert flags == sorted(flags)  # piecewise first, then the kernel's
    # file order is kept within each kind
    pieces = [it.name for it in order if it.name[0] == "p"]
    assert pieces == sorted(pieces, key=lambda s: int(s[1:]))
