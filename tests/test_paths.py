"""Compile paths (core/shared/paths.py, sim/paths.py): a run compiles only the
kernels its plant, filter, residual test and controller reach.

The mechanism is checked on small kernels: an implementation that Numba
cannot type for the arguments given would fail the compile if it were ever
typed, so a caller that compiles proves the other paths were left out.  The
mapping from settings to paths is checked on the shipped configs' designs.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numba
import numpy as np
import pytest

from ftc_mc.config import load_config, with_overrides
from ftc_mc.core.jit import kernel
from ftc_mc.core.shared.paths import (DENSE_FILTER, EXTENDED_FILTER, GLR_TEST, LINEAR_PLANT,
                                      NOMINAL_CONTROL, NONLINEAR_PLANT, ONE_STEP_TEST,
                                      PAPER_FILTER, RECONFIGURING, SELECT_FOUR,
                                      SIXDOF_EXTENDED_PLANT,
                                      SIXDOF_PLANT, describe, on_path, takes)
from ftc_mc.core.shared.paths import Path as CPath
from ftc_mc.sim.paths import path_of
from ftc_mc.sim.setup import build_setup

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@kernel
def _add_one(x, out):
    out[0] = x + 1.0


@kernel
def _untypable(x, out):
    out[0] = x.no_such_attribute  # a float has none: typing this fails


@on_path("filter", {PAPER_FILTER: _add_one, DENSE_FILTER: _untypable})
def _step(path, x, out):
    """A dispatcher of the test."""


@on_path("test", {GLR_TEST: _untypable})
def _only_glr(path, x, out):
    """A dispatcher with no entry for the one-step test."""


@numba.njit
def _caller(path, x, out):
    out[0] = -1.0
    _only_glr(path, x, out)
    _step(path, x, out)
    return out[0]


def test_a_path_compiles_only_its_own_kernels():
    out = np.zeros(1)
    paper = CPath(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, NOMINAL_CONTROL)
    assert _caller(paper, 2.0, out) == 3.0
    # the dense path would type _untypable: it fails, so the paper path did not
    with pytest.raises(numba.core.errors.TypingError):
        _caller(paper._replace(filter=DENSE_FILTER), 2.0, out)
    with pytest.raises(numba.core.errors.TypingError):
        _caller(paper._replace(test=GLR_TEST), 2.0, out)
    assert len(_caller.signatures) == 1


def test_markers_are_distinct_values_and_types():
    a = CPath(LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING)
    b = CPath(NONLINEAR_PLANT, DENSE_FILTER, GLR_TEST, NOMINAL_CONTROL)
    # empty namedtuples would all be equal (and merge in a dict or set)
    assert a != b and len({a, b}) == 2 and len({LINEAR_PLANT, NONLINEAR_PLANT}) == 2
    assert pickle.loads(pickle.dumps(a)) == a  # sent to loky and Dask workers
    assert numba.typeof(a) != numba.typeof(b)
    assert takes(numba.typeof(a), "filter", PAPER_FILTER)
    assert not takes(numba.typeof(b), "filter", PAPER_FILTER)
    assert describe(b) == "nonlinear plant, dense filter, GLR test, nominal controller"
    with pytest.raises(TypeError):
        takes(numba.float64, "filter", PAPER_FILTER)


SMALL_TABLE = {"monitor": {"turn_offsets_deg": [-6.0, 2.0], "turn_step_deg": 2.0}}
"""The 6-DOF configs' lock-turn tables cut to 5 lock positions per elevon (those
of ``tests/test_lock_turn_loop.py``, whose designs the suite computes anyway):
a path does not depend on the table's size, and the shipped 23 positions take
minutes to design on an empty cache."""


@pytest.mark.parametrize("config, overrides, want", [
    ("paper_tables.yaml", {}, {"paper": (LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST,
                                         RECONFIGURING)}),
    ("elevon_lock.yaml", {"controller": {"kind": "nominal"}},
     {"swapped": (LINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST, NOMINAL_CONTROL)}),
    ("designs.yaml", {}, {"gust_one_step": (LINEAR_PLANT, DENSE_FILTER, ONE_STEP_TEST,
                                            RECONFIGURING),
                          "gust_glr": (LINEAR_PLANT, DENSE_FILTER, GLR_TEST, RECONFIGURING)}),
    ("robust_moderate.yaml", {}, {"excited_airspeed": (NONLINEAR_PLANT, EXTENDED_FILTER,
                                                       GLR_TEST, RECONFIGURING),
                                  "swapped": (NONLINEAR_PLANT, PAPER_FILTER, ONE_STEP_TEST,
                                              RECONFIGURING)}),
    ("sensor_aware.yaml", {}, {"sensor_aware": (LINEAR_PLANT, DENSE_FILTER, ONE_STEP_TEST,
                                                RECONFIGURING)}),
    ("sixdof_tables.yaml", SMALL_TABLE, {"paper": (SIXDOF_PLANT, PAPER_FILTER, ONE_STEP_TEST,
                                                   RECONFIGURING)}),
    # the extended side monitor (gust states on the nonlinear plant) is a path of its own
    ("sixdof_moderate.yaml", SMALL_TABLE, {
        "paper": (SIXDOF_EXTENDED_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING),
        "sixdof_robust": (SIXDOF_EXTENDED_PLANT, EXTENDED_FILTER, GLR_TEST, RECONFIGURING)}),
    # the selection among four 6-DOF controllers is a controller path of its own
    ("sixdof_survival.yaml", SMALL_TABLE, {
        "sixdof": (SIXDOF_PLANT, PAPER_FILTER, ONE_STEP_TEST, RECONFIGURING),
        "sixdof_selected": (SIXDOF_PLANT, PAPER_FILTER, ONE_STEP_TEST, SELECT_FOUR)}),
])
def test_path_of_the_shipped_designs(config, overrides, want):
    cfg = load_config(CONFIGS / config)
    if overrides:
        cfg = with_overrides(cfg, **overrides)
    setup = build_setup(cfg)
    for name, markers in want.items():
        assert path_of(setup.scheme(name), setup.flight) == CPath(*markers), name
    # the stages that do not fly (filter-only tests) take the linear plant
    name = next(iter(want))
    assert path_of(setup.scheme(name)).plant == LINEAR_PLANT
