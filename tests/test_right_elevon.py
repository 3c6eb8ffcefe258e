"""The right elevon's campaign rows and the ``correct_side`` metric."""

import re

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import ftc_mc
from ftc_mc.campaign.chunk import chunk_spec, classify, correct_side, trial_inputs
from ftc_mc.campaign.summary import markdown_table, side_text, summarize
from ftc_mc.campaign.transitions import TRANSITION_TABLE, paper_counts
from ftc_mc.cli import TERMINAL_WIDTH, cli, terminal_table
from ftc_mc.config import Config
from ftc_mc.conventions import (ACTUATOR_NAMES, MODE_LEFT_ELEVON, MODE_NOMINAL,
                                MODE_RIGHT_ELEVON, PAPER_TRANSITIONS, RESET_ELEVONS,
                                RIGHT_ELEVON_TRANSITIONS, STATUS_AIRSPEED, TRANSITIONS,
                                KIND_TRANSITIONS)
from ftc_mc.sim.lanes import new_record
from ftc_mc.stats import wilson
from test_campaign import small_config

LEFT = ACTUATOR_NAMES.index("left_elevon")
RIGHT = ACTUATOR_NAMES.index("right_elevon")


@pytest.fixture(scope="module")
def spec():
    return chunk_spec(small_config(["elevon_lock", "right_elevon_lock"]))


def test_the_twelve_rows_and_the_paper_default():
    assert TRANSITIONS == PAPER_TRANSITIONS + RIGHT_ELEVON_TRANSITIONS
    assert tuple(TRANSITION_TABLE) == TRANSITIONS + KIND_TRANSITIONS  # then the fault kinds
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


def _record(setup, left_right_at_end):
    """A record without resets whose belief at the end of the window holds
    ``(p_left, p_right)`` per lane (the rest of the mass nominal)."""
    L = len(left_right_at_end)
    rec = new_record(setup, L, 4)
    rec.detect_k[:] = -1
    rec.belief[:, MODE_NOMINAL] = 1.0
    p = (setup.tim.k_fault + 50) // setup.tim.reconf_every - 1  # window 5 s = 50 steps
    for l, (pl, pr) in enumerate(left_right_at_end):
        rec.belief[p, :, l] = [1.0 - pl - pr, 0.0, pl, pr]
    return rec, p


def test_correct_side_of_hand_made_beliefs(spec):
    setup = spec.setup
    ends = [(0.9, 0.1), (0.1, 0.9), (0.3, 0.3), (0.0, 0.2), (0.45, 0.4)]
    ids = np.arange(len(ends))
    rec, p = _record(setup, ends)
    # before the window's end the belief held the other way round: only the end counts
    rec.belief[p - 1, MODE_LEFT_ELEVON] = rec.belief[p, MODE_RIGHT_ELEVON]
    rec.belief[p - 1, MODE_RIGHT_ELEVON] = rec.belief[p, MODE_LEFT_ELEVON]
    # after it, too
    rec.belief[p + 1:, MODE_LEFT_ELEVON] = 0.0
    rec.belief[p + 1:, MODE_RIGHT_ELEVON] = 1.0
    inp, values = trial_inputs(spec, "elevon_lock", ids)
    left, _ = classify(spec, "elevon_lock", "paper", ids, values, inp, rec)
    # left fault: right, wrong, tie (names neither side: wrong), wrong, right
    np.testing.assert_array_equal(left["correct_side"], [1.0, 0.0, 0.0, 0.0, 1.0])
    inp, values = trial_inputs(spec, "right_elevon_lock", ids)
    right, _ = classify(spec, "right_elevon_lock", "paper", ids, values, inp, rec)
    np.testing.assert_array_equal(right["correct_side"], [0.0, 1.0, 0.0, 1.0, 0.0])
    # a trial that left the envelope inside the window is not judged: NaN
    rec.status[1] = STATUS_AIRSPEED
    rec.stop_k[1] = setup.tim.k_fault + 10
    right2, _ = classify(spec, "right_elevon_lock", "paper", ids, values, inp, rec)
    assert not right2["judged"][1] and np.isnan(right2["correct_side"][1])
    s = summarize(pd.concat([pd.DataFrame(left), pd.DataFrame(right2)])).set_index(
        "transition")
    assert s.loc["elevon_lock", "correct_side"] == 2
    assert s.loc["elevon_lock", "correct_side_trials"] == 5
    assert s.loc["elevon_lock", "correct_side_rate"] == 0.4
    lo, hi = wilson(2, 5)
    assert (s.loc["elevon_lock", "correct_side_ci_low"],
            s.loc["elevon_lock", "correct_side_ci_high"]) == (lo, hi)
    assert s.loc["right_elevon_lock", "correct_side_trials"] == 4
    assert s.loc["right_elevon_lock", "correct_side_rate"] == 0.25
    assert np.isnan(s.loc["right_elevon_lock", "paper_trials"])
    md = markdown_table(s.reset_index())
    assert "2/5 (40.0 %" in md and "1/4 (25.0 %" in md
    right_line = next(x for x in md.splitlines() if "Right elevon nominal" in x)
    cells = [c.strip() for c in right_line.strip().strip("|").split("|")]
    assert cells[-2:] == ["-", "not in the paper"]  # no paper counts, no verdict


@pytest.mark.parametrize("name", ["engine_lock", "elevon_unlock", "right_elevon_loss_recover"])
def test_correct_side_does_not_apply(name):
    sp = chunk_spec(small_config([name]))
    ids = np.arange(3)
    rec, _ = _record(sp.setup, [(0.9, 0.1), (0.1, 0.9), (0.5, 0.2)])
    inp, values = trial_inputs(sp, name, ids)
    t, _ = classify(sp, name, "paper", ids, values, inp, rec)
    assert np.isnan(t["correct_side"]).all()
    s = summarize(pd.DataFrame(t)).iloc[0]
    assert s["correct_side_trials"] == 0 and np.isnan(s["correct_side_rate"])
    assert side_text(s) == "-"


def test_loss_inside_the_nominal_box_has_no_side():
    tr = TRANSITION_TABLE["right_elevon_loss"]
    belief = np.zeros((3, 4, 3))
    belief[:, MODE_RIGHT_ELEVON] = 0.7
    belief[:, MODE_LEFT_ELEVON] = 0.2
    got = correct_side(tr, np.array([MODE_RIGHT_ELEVON, MODE_NOMINAL, MODE_RIGHT_ELEVON]),
                       belief, np.array([True, True, False]), k_end=30, every=10)
    np.testing.assert_array_equal(got, [1.0, np.nan, np.nan])
    # a window ending before the first belief update: nothing to read
    assert np.isnan(correct_side(tr, np.array([MODE_RIGHT_ELEVON]), belief[:, :, :1],
                                 np.array([True]), k_end=5, every=10)).all()


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


def test_small_right_elevon_campaign_end_to_end(tmp_path):
    cfg = tmp_path / "right.yaml"
    cfg.write_text("campaign:\n  transitions: [elevon_lock, right_elevon_lock]\n"
                   "  trials: 4\n  chunk_size: 4\n"
                   "timing:\n  fault_time_s: 5\n  window_s: 5\n  duration_s: 15\n")
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", str(cfg), "--jobs", "1", "--quiet",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    t = pd.read_parquet(out / "trials.parquet")
    right = t[t.transition == "right_elevon_lock"]
    assert len(right) == 8 and (right["mode_post"] == "right_elevon").all()
    left = t[t.transition == "elevon_lock"]
    assert (left["mode_post"] == "left_elevon").all()
    # common random numbers: the same lock positions on either side
    np.testing.assert_array_equal(right["lock_position"], left["lock_position"])
    judged = right[right["judged"]]
    assert len(judged) and judged["correct_side"].isin([0.0, 1.0]).all()
    s = pd.read_parquet(out / "summary.parquet").set_index(["transition", "variant"])
    for v in ("paper", "swapped"):
        r = s.loc[("right_elevon_lock", v)]
        assert r["correct_side_trials"] == r["trials"]
        assert r["correct_side"] == judged.loc[judged.variant == v, "correct_side"].sum()
        assert np.isnan(r["paper_trials"])
        assert s.loc[("elevon_lock", v), "paper_trials"] == 1000
    md = (out / "summary.md").read_text()
    assert "Right elevon nominal → Right elevon locked" in md and "correct side" in md
    report = tmp_path / "report.md"
    res = CliRunner().invoke(cli, ["report", str(out), "-o", str(report)])
    assert res.exit_code == 0, res.output
    text = report.read_text().split("### Excluded trials")[0]
    lines = text.splitlines()
    head = next(x for x in lines if x.startswith("| transition") and "correct side" in x)
    col = [c.strip() for c in head.strip("|").split("|")].index("correct side")
    cells = {}
    for x in lines[lines.index(head):]:
        c = [c.strip() for c in x.strip("|").split("|")]
        if len(c) > col and c[0] not in cells:  # the first design's table: paper
            cells[c[0]] = c
    r = s.loc[("right_elevon_lock", "paper")]
    right_row = cells["Right elevon nominal → Right elevon locked"]
    assert right_row[col].startswith(f"{r['correct_side']}/{r['correct_side_trials']} (")
    assert right_row[-1] == "not in the paper" and "-" in right_row
