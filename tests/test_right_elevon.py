"""The right elevon's campaign rows (issue 24, item 5)."""

import re

import numpy as np
import pandas as pd
import pytest

import ftc_mc
from ftc_mc.campaign.chunk import chunk_spec, trial_inputs
from ftc_mc.campaign.transitions import TRANSITION_TABLE, paper_counts
from ftc_mc.cli import TERMINAL_WIDTH, terminal_table
from ftc_mc.config import Config
from ftc_mc.conventions import (ACTUATOR_NAMES, MODE_LEFT_ELEVON, MODE_NOMINAL,
                                MODE_RIGHT_ELEVON, PAPER_TRANSITIONS, RESET_ELEVONS,
                                RIGHT_ELEVON_TRANSITIONS, TRANSITIONS)

LEFT = ACTUATOR_NAMES.index("left_elevon")
RIGHT = ACTUATOR_NAMES.index("right_elevon")
SMALL = {"timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}}


def small_config(transitions, trials=8, **campaign):
    return Config.model_validate({"campaign": {"transitions": list(transitions),
                                               "trials": trials, "chunk_size": 4,
                                               **campaign}, **SMALL})


@pytest.fixture(scope="module")
def spec():
    return chunk_spec(small_config(["elevon_lock", "right_elevon_lock"]))


def test_the_twelve_rows_and_the_paper_default():
    assert TRANSITIONS == PAPER_TRANSITIONS + RIGHT_ELEVON_TRANSITIONS
    assert tuple(TRANSITION_TABLE) == TRANSITIONS
    for name in RIGHT_ELEVON_TRANSITIONS:
        tr, left = TRANSITION_TABLE[name], TRANSITION_TABLE[name[len("right_"):]]
        assert (tr.actuator, tr.fault_mode, tr.correct_block) == (
            RIGHT, MODE_RIGHT_ELEVON, RESET_ELEVONS)
        assert (left.actuator, left.fault_mode) == (LEFT, MODE_LEFT_ELEVON)
        assert (tr.kind, tr.onset) == (left.kind, left.onset)
        assert np.isnan(paper_counts(name)).all()
    assert paper_counts("elevon_unlock") == (1000, 17, 0)
    shipped = ftc_mc.load_config("configs/paper_tables.yaml").campaign.transitions
    assert tuple(shipped) == PAPER_TRANSITIONS


def test_config_names_the_right_rows():
    assert small_config(RIGHT_ELEVON_TRANSITIONS).campaign.transitions == list(
        RIGHT_ELEVON_TRANSITIONS)
    with pytest.raises(ValueError, match="right_elevon_loss_recover"):
        small_config(["right_elevon_jam"])
    with pytest.raises(ValueError, match="elevon_lock_range_rad: must lie within the "
                                         "left_elevon command range"):
        Config.model_validate({"draws": {"elevon_lock_range_rad": [-3.0, 0.1]}})


@pytest.mark.parametrize("name", RIGHT_ELEVON_TRANSITIONS)
def test_right_rows_fault_the_right_elevon(spec, name):
    ids = np.arange(16)
    inp, values = trial_inputs(spec, name, ids)
    tr = TRANSITION_TABLE[name]
    faulty = 1 if tr.onset else 0
    healthy = 1 - faulty
    others = [a for a in range(len(ACTUATOR_NAMES)) if a != RIGHT]
    assert not inp.b0[:, others].any() and not inp.b1[:, others].any()
    assert not inp.b0[healthy].any() and not inp.b1[healthy].any()
    plant = spec.setup.plant
    if tr.kind == "lock":
        assert (inp.b1[faulty, RIGHT] == 1.0).all()
        np.testing.assert_array_equal(inp.b0[faulty, RIGHT], values)
        assert (plant.u_lower[RIGHT] <= values).all() and (values <= plant.u_upper[RIGHT]).all()
        modes = np.full(len(ids), MODE_RIGHT_ELEVON)
    else:
        np.testing.assert_array_equal(inp.b1[faulty, RIGHT], values)
        modes = np.where(values > spec.setup.beta[1], MODE_RIGHT_ELEVON, MODE_NOMINAL)
    nominal = np.full(len(ids), MODE_NOMINAL)
    pre, post = (nominal, modes) if tr.onset else (modes, nominal)
    np.testing.assert_array_equal(inp.mode_pre, pre)
    np.testing.assert_array_equal(inp.mode_post, post)
    # the same draws as the left row: only the side differs
    left_inp, left_values = trial_inputs(spec, name[len("right_"):], ids)
    np.testing.assert_array_equal(values, left_values)
    np.testing.assert_array_equal(left_inp.b1[:, LEFT], inp.b1[:, RIGHT])


def test_terminal_table_fits_with_right_rows():
    names = list(TRANSITIONS)
    s = pd.DataFrame({"transition": names * 2, "variant": ["paper"] * 12 + ["swapped"] * 12,
                      "trials": 1000, "inappropriate_rate": 1.0, "no_reset_rate": 1.0,
                      "no_reset_explained_share": 1.0, "delay_median_s": 999.9,
                      "paper_inappropriate": [paper_counts(n)[1] for n in names] * 2,
                      "paper_no_reset": [paper_counts(n)[2] for n in names] * 2})
    text = terminal_table(s)
    assert max(map(len, text.splitlines())) <= TERMINAL_WIDTH
    assert re.search(r"\| elevon_unlock .*\| +17 / 0 \|", text)
    assert all(line.rstrip(" |").endswith("-") for line in text.splitlines()
               if "| right_elevon" in line)
