"""The test order that lets xdist workers share the trial kernel's cold compile
(tests/conftest.py), checked against pytest-xdist's own worksteal scheduler."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from conftest import TRIAL_KERNEL_FILES, _worksteal_order


def _items(n_piece, n_late):
    """``n_piece`` piecewise tests, ``n_late`` tests in a trial-kernel file and
    one piecewise-file test that asks for the ``trial_kernel`` fixture."""
    late_file = sorted(TRIAL_KERNEL_FILES)[0]
    piece = [SimpleNamespace(path=Path(f"tests/test_piece{i}.py"), fixturenames=[],
                             nodeid=f"p{i}") for i in range(n_piece)]
    late = [SimpleNamespace(path=Path(f"tests/{late_file}"), fixturenames=[],
                            nodeid=f"l{i}") for i in range(n_late)]
    fixture = ([SimpleNamespace(path=Path("tests/test_piece.py"),
                                fixturenames=["trial_kernel"], nodeid=f"l{n_late}")]
               if n_late else [])
    return piece + late + fixture


class _Worker:
    """What the scheduler reads of a worker (hashable, unlike a namespace)."""

    shutting_down = False

    def __init__(self, name):
        self.gateway = SimpleNamespace(id=name)

    def send_runtest_some(self, indices):
        pass

    def send_steal(self, indices):
        pass

    def shutdown(self):
        pass


def _first_parts(order, workers):
    """The tests each worker gets first from pytest-xdist's worksteal scheduler
    (``xdist.scheduler.worksteal``, run on fake workers)."""
    worksteal = pytest.importorskip("xdist.scheduler.worksteal")
    config = SimpleNamespace(getvalue=lambda name: [f"{workers}*popen"] if name == "tx"
                             else None)
    sched = worksteal.WorkStealingScheduling(config)
    nodes = [_Worker(f"gw{i}") for i in range(workers)]
    names = [it.nodeid for it in order]
    for node in nodes:
        sched.add_node(node)
    for node in nodes:
        sched.add_node_collection(node, names)
    sched.schedule()
    return [[names[i] for i in sched.node2pending[node]] for node in nodes]


@pytest.mark.parametrize("n_piece,n_late,workers", [
    (300, 400, 2), (500, 100, 2), (50, 600, 2), (300, 400, 3), (260, 120, 4),
    (40, 0, 2), (0, 30, 2), (2, 1, 4)])
def test_worksteal_order(n_piece, n_late, workers):
    items = _items(n_piece, n_late)
    order = _worksteal_order(items, workers)
    assert sorted(map(id, order)) == sorted(map(id, items))  # a permutation
    parts = _first_parts(order, workers)
    assert sum(map(len, parts)) == len(items)
    first, others = parts[0], parts[1:]
    n_late_all = n_late + (1 if n_late else 0)
    # the first worker starts with the kernel's tests, as many as fit
    head = min(n_late_all, len(first))
    assert all(name[0] == "l" for name in first[:head])
    # every other worker starts with piecewise tests, spread evenly while they
    # last, then the rest of the kernel's
    left_piece = n_piece - sum(name[0] == "p" for name in first)
    counts = [sum(name[0] == "p" for name in part) for part in others]
    for part, count in zip(others, counts):
        assert [name[0] for name in part] == ["p"] * count + ["l"] * (len(part) - count)
    if left_piece:
        assert max(counts) - min(counts) <= 1 or min(counts) == min(map(len, others))
    # file order is kept within each kind
    for kind in "pl":
        names = [it.nodeid for it in order if it.nodeid[0] == kind]
        assert names == sorted(names, key=lambda s: int(s[1:]))
