"""Shared fixtures: the linear plant and paper-default estimator settings; the
order that lets two test workers share the trial kernel's one cold compile."""

from pathlib import Path

import pytest

from ftc_mc.model.linear import build_plant
from ftc_mc.sim.estimator import EstimatorSettings

ROOT = Path(__file__).resolve().parents[1]

TRIAL_KERNEL_FILES = {
    "test_airframe_runs.py", "test_api.py", "test_big_runs.py", "test_campaign.py",
    "test_detector.py", "test_score_refusals.py",
    "test_compile_notice.py", "test_dask.py", "test_designs.py", "test_fuzz_configs.py",
    "test_golden.py", "test_lock.py", "test_operating.py", "test_report.py",
    "test_report_plant.py", "test_reset_scale.py", "test_resume.py", "test_scenario.py",
    "test_sensor_faults.py", "test_sweep.py", "test_trial_validity.py", "test_truth_plant.py",
}
"""Test files that run campaigns, sweeps or scenarios (the trial kernel
``core.longitudinal.trial.advance``); the other files test kernels and models piece by piece."""


def _late(item) -> bool:
    return item.path.name in TRIAL_KERNEL_FILES or "trial_kernel" in item.fixturenames


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """pytest-xdist, in the controller: tell each worker how tests are shared
    (a worker's own ``dist`` option reads ``"no"``)."""
    node.workerinput["ftc_mc_dist"] = node.config.getoption("dist")


def _worksteal_workers(config) -> int:
    """The number of pytest-xdist workers when they share the tests by
    ``--dist worksteal`` (``python3 dev.py test``), else 0."""
    workerinput = getattr(config, "workerinput", {})
    workers = workerinput.get("workercount", 0)
    return workers if workers > 1 and workerinput.get("ftc_mc_dist") == "worksteal" else 0


def _worksteal_order(items, workers: int) -> list:
    """``items`` arranged for pytest-xdist's worksteal scheduler.

    It hands each worker a contiguous part of the list (the first
    ``N // workers`` tests, then ``N // (workers - 1)`` of the rest, ...) and
    later moves queued tests from busy workers to idle ones.  The first part
    starts with the trial kernel's tests, so its worker compiles the kernel at
    once; every other part starts with piecewise tests, so their workers run
    those meanwhile and reach the kernel's tests once it is cached."""
    late = [item for item in items if _late(item)]
    piece = [item for item in items if not _late(item)]
    sizes, left = [], len(items)
    for i in range(workers):
        sizes.append(left // (workers - i))
        left -= sizes[-1]
    n_late = min(len(late), sizes[0])
    order = late[:n_late] + piece[:sizes[0] - n_late]
    late, piece = late[n_late:], piece[sizes[0] - n_late:]
    for i in range(1, workers):
        n_piece = min(len(piece) // (workers - i), sizes[i])
        n_late = sizes[i] - n_piece
        order += piece[:n_piece] + late[:n_late]
        piece, late = piece[n_piece:], late[n_late:]
    return order + piece + late


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Order the tests so that two or more test workers share the trial
    kernel's one cold compile (about 1.5 minutes) instead of all reaching the
    kernel at once and waiting for one of them
    (:func:`ftc_mc.sim.compiling.compiled_once`).  Only the order changes.

    * ``--dist worksteal`` (``python3 dev.py test``): :func:`_worksteal_order`.
    * Otherwise the tests of the trial kernel run after the piecewise ones
      (otherwise in file order); with pytest-xdist's default ``load`` order
      every worker takes tests from the front of the list, and the first
      compiles the kernel before its first test (:func:`_compile_first`).

    Runs last (``trylast``), after ``-k``, ``-m`` and ``--deselect`` have
    removed tests, so that the parts match what xdist hands out; ``--lf`` and
    ``--ff`` still change the list afterwards (the order is then only less
    good)."""
    items.sort(key=_late)
    workers = _worksteal_workers(config)
    if workers:
        items[:] = _worksteal_order(items, workers)


@pytest.fixture(scope="session")
def trial_kernel():
    """The trial kernel compiled, or loaded from Numba's cache, in this process;
    a compile in another process is waited for.  Tests elsewhere that run
    ``core.longitudinal.trial.advance`` use it, so that they load what the first worker
    compiled instead of compiling it too."""
    from ftc_mc.campaign.chunk import chunk_spec, warm_up
    from ftc_mc.config import load_config
    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    warm_up(chunk_spec(cfg), cfg.campaign.transitions[0])


@pytest.fixture(scope="session", autouse=True)
def _compile_first(request):
    """The first xdist worker gets the trial kernel before any test, when the
    session has tests that need it (the ``load`` order; the worksteal order
    needs no head start, its first part starts with those tests).  A failure
    here is left to those tests to report (they compile it again), so the
    piecewise tests still run."""
    if (getattr(request.config, "workerinput", {}).get("workerid") != "gw0"
            or _worksteal_workers(request.config)):
        return
    if any(_late(item) for item in request.session.items):
        try:
            request.getfixturevalue("trial_kernel")
        except Exception:  # noqa: BLE001 -- reported by the tests that need it
            pass


@pytest.fixture(scope="session")
def plant():
    """The X8 linearised at 20 m/s, -3 deg, ZOH at 0.1 s."""
    return build_plant()


@pytest.fixture(scope="session")
def settings():
    """Paper-default estimator settings (section 5.1)."""
    return EstimatorSettings()


@pytest.fixture(autouse=True)
def _quick_trimmable_sets(request, monkeypatch):
    """A run on the 6-DOF nonlinear plant with elevon-lock rows reports its
    survival inside and outside the airframe's equations' trimmable set, whose
    search takes a minute or two per airframe the first time
    (``ftc_mc/cache/trimmable.py``).  Tests get the 6-DOF linear model's
    exact set in its place (milliseconds, cached nowhere); a test marked
    ``trimmable_search`` gets the real search and cache."""
    if request.node.get_closest_marker("trimmable_search"):
        return
    import ftc_mc.cache.trimmable as tc
    from ftc_mc.model.sixdof import build_sixdof_plant
    from ftc_mc.model.trimmable import Envelope, linear_trimmable_set

    def linear_sets(airframe, sides, envelope=Envelope(), name="", cache_dir=None,
                    stream=None):
        plant = build_sixdof_plant(airframe)
        return {side: linear_trimmable_set(plant, side, envelope) for side in sides}

    monkeypatch.setattr(tc, "cached_trimmable_sets", linear_sets)

