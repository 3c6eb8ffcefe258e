"""Shared fixtures: the linear plant and paper-default estimator settings; the
order that lets two test workers share the trial kernel's one cold compile;
the newcomer's tier (``--newcomer``, what ``python3 dev.py test`` runs)."""

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


NEWCOMER = {
    "the install": [
        "test_install.py::test_the_command_is_installed_and_runs",
        "test_install.py::test_numba_is_a_tested_version",
    ],
    "every golden file": [
        "test_golden.py::test_campaign_is_golden[linear]",
        "test_golden.py::test_campaign_is_golden[nonlinear_moderate]",
        "test_golden.py::test_campaign_is_golden[sixdof_moderate]",
        "test_golden.py::test_scenario_is_golden[linear]",
        "test_golden.py::test_scenario_is_golden[nonlinear_moderate]",
        "test_golden.py::test_scenario_is_golden[sixdof]",
        "test_config_equivalence.py::test_every_shipped_config_has_a_record",
    ] + [f"test_config_equivalence.py::test_shipped_config_resolves_as_recorded[{f.stem}]"
         for f in sorted((ROOT / "tests" / "golden" / "configs").glob("*.json"))],
    "longitudinal kernels against their NumPy twins": [
        "test_stages.py::test_advance_matches_the_chained_twins[linear-none]",
    ],
    "6-DOF kernels against their NumPy twins": [
        "test_sixdof_trial.py::test_sixdof_truth_matches_its_twin[nonlinear-separate]",
    ],
}
"""The newcomer's tier, ``pytest --newcomer`` (``python3 dev.py test``; the
whole suite is ``python3 dev.py test --all``): the cheapest tests that show
the install works, every file of ``tests/golden/`` holds, and each kernel
family agrees with its plain-NumPy twin on one path.  Chosen by compile cost
(each test's cold compile measured with two pytest-xdist workers): the golden
cases compile the default, nonlinear and 6-DOF paths, and the scenarios
reuse them (the recorded configs of ``tests/golden/configs/`` compile
nothing); the longitudinal twin runs the whole trial loop on the default
path the golden linear case compiled (under a second); the 6-DOF twin runs
the flying wing's truth stage (equations, lateral loops, gusts, faults)
against its twin, its stage compiled again with Python wrappers (about 10 s
more CPU in the tier, 34 s alone on an empty cache, where the side monitor's
twin took 63 s and the equations' twin 3 s; one sitting, a shared machine).  Node ids relative to ``tests/``; ``tests/test_newcomer.py`` checks
each exists and what the tier covers."""


def _newcomer_ids() -> set:
    return {f"tests/{i}" for ids in NEWCOMER.values() for i in ids}


def pytest_addoption(parser):
    parser.addoption("--newcomer", action="store_true", default=False,
                     help="run only the newcomer's tier (tests/conftest.py NEWCOMER): the "
                     "install, the golden files, a kernel-vs-twin test per family")


def pytest_ignore_collect(collection_path, config):
    """With ``--newcomer``, test files outside the tier are not even imported."""
    if (config.getoption("newcomer") and collection_path.suffix == ".py"
            and collection_path.name.startswith("test_")
            and collection_path.name not in {i.split("::")[0] for ids in NEWCOMER.values()
                                             for i in ids}):
        return True
    return None


def _select_newcomer(config, items) -> None:
    """With ``--newcomer``, keep the tier's tests only; a test it names that a
    collected file no longer holds (renamed, parametrised otherwise), or
    whose file is gone, stops the run, so the tier never shrinks unnoticed."""
    if not config.getoption("newcomer"):
        return
    wanted = _newcomer_ids()
    collected_files = {item.nodeid.split("::")[0] for item in items}
    found = {item.nodeid for item in items}
    missing = sorted(i for i in wanted if i not in found
                     and (i.split("::")[0] in collected_files
                          or not (ROOT / i.split("::")[0]).is_file()))
    if missing:
        raise pytest.UsageError("the newcomer's tier (tests/conftest.py NEWCOMER) names tests "
                                "that do not exist: " + ", ".join(missing))
    keep = [item for item in items if item.nodeid in wanted]
    deselected = [item for item in items if item.nodeid not in wanted]
    if deselected:
        config.hook.pytest_deselected(items=deselected)
    items[:] = keep


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
    good).  With ``--newcomer``, the tier's tests are chosen first
    (:func:`_select_newcomer`)."""
    _select_newcomer(config, items)
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

