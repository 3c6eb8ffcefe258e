"""Metrics comparable with real-flight studies: ALFA scoring and
FDDBenchmark's names on hand-made trials, where each count is known."""

import numpy as np
import pandas as pd
import pytest

from ftc_mc.campaign.scoring import ALFA_TIMEOUT_S, real_flight_scores
from ftc_mc.campaign.summary import summarize
from ftc_mc.report.realflight import real_flight_lines

NAN = np.nan
# elevon lock: the correct block is "elevons"
HAND = pd.DataFrame({
    # a: a false alarm before the fault, then the elevons 0.5 s after it: FP and TP
    # b: thrust first (0.2 s), the elevons at 4.9 s: TP, not a correct diagnosis
    # c: the elevons at 5.5 s: after the 5 s timeout, a miss; a correct diagnosis
    # d: nothing in the window: a miss
    "false_resets": [1, 0, 0, 0],
    "correct_reset_s": [0.5, 4.9, 5.5, NAN],
    "first_reset_s": [0.5, 0.2, 5.5, NAN],
    "first_reset_block": ["elevons", "thrust", "elevons", "none"],
})


def test_alfa_and_fdd_scores_of_hand_made_trials():
    assert ALFA_TIMEOUT_S == 5.0  # the alfa-evaluate node's timeout
    s = real_flight_scores("elevon_lock", HAND)
    assert (s["alfa_tp"], s["alfa_fp"], s["alfa_fn"]) == (2, 1, 2)
    assert s["alfa_precision"] == pytest.approx(2 / 3)
    assert s["alfa_recall"] == pytest.approx(2 / 4)
    assert s["alfa_delay_mean_s"] == pytest.approx((0.5 + 4.9) / 2)
    assert s["alfa_delay_max_s"] == pytest.approx(4.9)
    assert s["add_s"] == pytest.approx((0.5 + 0.2 + 5.5) / 3)  # the miss d excluded
    assert s["cdr"] == pytest.approx(2 / 4)
    # the engine is the correct block of an engine row: the same resets score otherwise
    e = real_flight_scores("engine_loss", HAND.assign(
        first_reset_block=["thrust", "elevons", "thrust", "none"]))
    assert e["cdr"] == pytest.approx(2 / 4)


def test_no_detection_gives_nan_delays_and_no_precision():
    none = HAND.iloc[[3]]
    s = real_flight_scores("elevon_lock", none)
    assert s["alfa_tp"] == 0 and np.isnan(s["alfa_precision"])
    assert s["alfa_recall"] == 0.0 and np.isnan(s["alfa_delay_mean_s"])


def test_summary_and_report_carry_the_scores():
    trials = HAND.assign(transition="elevon_lock", variant="robust", trial_id=range(4),
                         judged=True, inappropriate=[False, True, False, False],
                         correct=[True, True, True, False], no_reset=[False] * 3 + [True],
                         small_b1=False, lock_near_trim=False, mode_changed=True,
                         detected=False, detection_s=NAN, resets_truncated=False,
                         status="ok")
    row = summarize(trials).iloc[0]
    assert row["alfa_precision"] == pytest.approx(2 / 3) and row["cdr"] == 0.5
    text = "\n".join(real_flight_lines(trials))
    row = next(line for line in text.splitlines() if line.startswith("| elevon_lock"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert cells == ["elevon_lock", "4", "2 / 1 / 2", "66.7", "50", "2.70 / 4.90", "2.07", "50"]
    assert "88.23 %" in text and "differ from ours" in text
