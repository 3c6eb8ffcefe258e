"""Shared fixtures: the linear plant and paper-default estimator settings; the
order that lets two test workers share the trial kernel's one cold compile."""

from pathlib import Path

import pytest

from ftc_mc.model.linear import build_plant
from ftc_mc.sim.estimator import EstimatorSettings

ROOT = Path(__file__).resolve().parents[1]

TRIAL_KERNEL_FILES = {
    "test_airframe_runs.py", "test_api.py", "test_campaign.py", "test_compile_notice.py",
    "test_dask.py", "test_designs.py", "test_fuzz_configs.py", "test_golden.py",
    "test_lock.py", "test_operating.py", "test_report.py", "test_report_plant.py",
    "test_resume.py", "test_scenario.py", "test_sensor_faults.py", "test_sweep.py",
    "test_trial_validity.py", "test_truth_plant.py",
}
"""Test files that run campaigns, sweeps or scenarios (the trial kernel
``core.trial.advance``); the other files test kernels and models piece by piece."""


def _late(item) -> bool:
    return item.path.name in TRIAL_KERNEL_FILES or "trial_kernel" in item.fixturenames


def pytest_collection_modifyitems(config, items):
    """Tests of the trial kernel after the piecewise ones (otherwise in file
    order).  ``python3 dev.py test`` runs a pytest-xdist worker per core: the
    first compiles the trial kernel before its first test
    (:func:`_compile_first`, about 1.5 minutes cold) while the others run
    piecewise tests (``--dist worksteal`` hands them the tests queued for the
    first), instead of all reaching the kernel at once and waiting for one of
    them (:func:`ftc_mc.sim.compiling.compiled_once`).  Only the order
    changes."""
    items.sort(key=_late)


@pytest.fixture(scope="session")
def trial_kernel():
    """The trial kernel compiled, or loaded from Numba's cache, in this process;
    a compile in another process is waited for.  Tests elsewhere that run
    ``core.trial.advance`` use it, so that they load what the first worker
    compiled instead of compiling it too."""
    from ftc_mc.campaign.chunk import chunk_spec, warm_up
    from ftc_mc.config import load_config
    cfg = load_config(ROOT / "configs" / "paper_tables.yaml")
    warm_up(chunk_spec(cfg), cfg.campaign.transitions[0])


@pytest.fixture(scope="session", autouse=True)
def _compile_first(request):
    """The first xdist worker gets the trial kernel before any test, when the
    session has tests that need it.  A failure here is left to those tests to
    report (they compile it again), so the piecewise tests still run."""
    if getattr(request.config, "workerinput", {}).get("workerid") != "gw0":
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
