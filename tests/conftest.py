"""Shared fixtures: the linear plant and paper-default estimator settings."""

import pytest

from ftc_mc.model.linear import build_plant
from ftc_mc.sim.estimator import EstimatorSettings


@pytest.fixture(scope="session")
def plant():
    """The X8 linearised at 20 m/s, -3 deg, ZOH at 0.1 s."""
    return build_plant()


@pytest.fixture(scope="session")
def settings():
    """Paper-default estimator settings (section 5.1)."""
    return EstimatorSettings()
