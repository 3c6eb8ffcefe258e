"""Whether a summary row agrees with the paper's Tables 2-3 (the ``paper_p_*``
and ``paper_agrees*`` columns), on hand-made trials tables.

References: the paper's counts (``PAPER_TABLES``, its Tables 2-3), and
Fisher's exact test as :func:`ftc_mc.stats.two_proportion_p` computes it
(checked against the hypergeometric sum in ``tests/test_stats.py``).  A row
agrees only if both quantities do; rows the paper did not run (the right
elevon's, sensor faults) and rows without a judged trial have no verdict (NA).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ftc_mc.campaign.summary import agreement_text, markdown_table, summarize
from ftc_mc.campaign.transitions import PAPER_TABLES
from ftc_mc.io.results import write_parquet
from ftc_mc.stats import two_proportion_p


def _trials(name: str, n: int, inappropriate: int, no_reset: int, judged: int | None = None,
            variant: str = "swapped") -> pd.DataFrame:
    """``n`` trials of ``name``: the first ``inappropriate`` reset the wrong block,
    the last ``no_reset`` reset nothing; only the first ``judged`` are judged."""
    i = np.arange(n)
    nr = i >= n - no_reset
    return pd.DataFrame({
        "transition": name, "variant": variant, "trial_id": i, "status": "ok",
        "resets_truncated": False, "judged": i < (n if judged is None else judged),
        "no_reset": nr, "small_b1": False, "lock_near_trim": False,
        "inappropriate": i < inappropriate, "correct": ~nr,
        "first_reset_s": np.where(nr, np.nan, 0.1), "false_resets": 0,
        "mode_changed": True, "detected": True, "detection_s": 2.0})


def _sensor_trials(n: int) -> pd.DataFrame:
    """``n`` judged trials of a q-gyro bias, none misattributed."""
    return pd.DataFrame({
        "transition": "sensor_bias:q", "variant": "swapped", "trial_id": np.arange(n),
        "status": "ok", "resets_truncated": False, "judged": True, "actuator_reset": False,
        "wrong_mode": False, "controller_switch": False, "envelope_exit": False,
        "actuator_reset_s": np.nan, "wrong_mode_s": np.nan, "controller_switch_s": np.nan,
        "first_action_s": np.nan, "false_resets": 0})


def test_the_paper_counts_agree_with_themselves():
    # our counts equal to the paper's (engine loss: 0 and 165 of 1000): p = 1 twice
    n, inap, nr = PAPER_TABLES["engine_loss"]
    s = summarize(_trials("engine_loss", n, inap, nr)).iloc[0]
    assert s["paper_p_inappropriate"] == 1.0 and s["paper_p_no_reset"] == 1.0
    assert s["paper_agrees_inappropriate"] and s["paper_agrees_no_reset"]
    assert s["paper_agrees"]
    assert agreement_text(s) == "agrees (p 1 / 1)"


def test_one_quantity_that_differs_makes_the_row_differ():
    # elevon unlock: paper 17 inappropriate and 0 no-reset of 1000; ours 0 and 0 of 888:
    # inappropriate differs (p = 2.2e-5 < 0.05), no reset agrees (p = 1), the row differs
    s = summarize(_trials("elevon_unlock", 900, 0, 0, judged=888)).iloc[0]
    assert s["trials"] == 888
    assert s["paper_p_inappropriate"] == pytest.approx(two_proportion_p(0, 888, 17, 1000),
                                                       rel=1e-12)
    assert s["paper_p_inappropriate"] < 0.05
    assert s["paper_p_no_reset"] == 1.0
    assert not s["paper_agrees_inappropriate"] and s["paper_agrees_no_reset"]
    assert not s["paper_agrees"]
    assert agreement_text(s).startswith("differs: inappropriate (p 2.2e-05 / 1)")


def test_far_apart_and_near_counts():
    # no reset 999 of 1000 against the paper's 0 (elevon lock): differs
    far = summarize(_trials("elevon_lock", 1000, 0, 999)).iloc[0]
    assert far["paper_p_no_reset"] < 1e-100 and not far["paper_agrees_no_reset"]
    # 72 against 70 of 1000 (engine lock): agrees
    near = summarize(_trials("engine_lock", 1000, 0, 72)).iloc[0]
    assert near["paper_p_no_reset"] == pytest.approx(two_proportion_p(72, 1000, 70, 1000))
    assert near["paper_p_no_reset"] > 0.8 and near["paper_agrees"]


def test_rows_the_paper_did_not_run_have_no_verdict(tmp_path):
    trials = pd.concat([_trials("engine_loss", 40, 0, 6), _trials("right_elevon_lock", 40, 1, 0),
                        _trials("elevon_lock", 10, 0, 0, judged=0), _sensor_trials(20)],
                       ignore_index=True)
    s = summarize(trials).set_index("transition")
    assert s.loc["engine_loss", "paper_agrees"]  # 6/40 against 165/1000
    for name in ("right_elevon_lock", "elevon_lock", "sensor_bias:q"):
        for q in ("inappropriate", "no_reset"):
            assert np.isnan(s.loc[name, f"paper_p_{q}"]), (name, q)
            assert s.loc[name, f"paper_agrees_{q}"] is pd.NA, (name, q)
        assert s.loc[name, "paper_agrees"] is pd.NA, name
    assert agreement_text(s.loc["right_elevon_lock"]) == "not in the paper"
    assert agreement_text(s.loc["elevon_lock"]) == "-"  # no judged trial
    # the NA (not False) survives the Parquet file the run writes
    write_parquet(s.reset_index(), tmp_path / "summary.parquet", {"kind": "run"})
    back = pd.read_parquet(tmp_path / "summary.parquet").set_index("transition")
    assert str(back["paper_agrees"].dtype) == "boolean"
    assert back["paper_agrees"].isna().to_dict() == s["paper_agrees"].isna().to_dict()
    assert back.loc["engine_loss", "paper_agrees"]


def test_summary_markdown_shows_the_verdict():
    trials = pd.concat([_trials("engine_loss", 1000, 0, 165), _trials("engine_lock", 1000, 0, 11),
                        _trials("right_elevon_loss", 20, 0, 3)], ignore_index=True)
    s = summarize(trials)
    text = markdown_table(s)
    assert "How agreement is judged" in text
    for _, r in s.iterrows():
        line = next(x for x in text.splitlines() if x.startswith(f"| {r['label']} "))
        assert f"| {agreement_text(r)} " in line
    lock = s.set_index("transition").loc["engine_lock"]  # 11 against 70 of 1000
    assert agreement_text(lock).startswith("differs: no reset (p 1 / ")
    assert agreement_text(lock.drop(["paper_agrees"])) == "not recorded"  # an older summary
