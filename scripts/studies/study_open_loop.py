"""How much open loop matters: Table 1 scored offline on recorded signals beside the
closed loop that flew it (docs/guides/your-detector.md, "What is open loop").

Usage::

    python scripts/studies/study_open_loop.py RECORDED_RUN [--thresholds 40] [--jobs 1]

RECORDED_RUN is a run of ``ftc-mc run ... --record signals`` (built-in designs).
Printed, per transition, for the ``paper`` design:

1. the closed loop's rates (``summary.parquet``);
2. Table 1 re-run offline on the recorded statistics at the run's thresholds
   (equal first reset in every trial; the rates differ only because a detector
   is judged by its first alarm, the loop by all its resets in the window);
3. Table 1 offline at ``--thresholds`` on the same recorded signals, beside
4. the closed loop flown at those thresholds on the same trials (run here):
   the difference is what the loop's own resets and excitation did to the
   signals after its first reset.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import ftc_mc  # noqa: E402
from ftc_mc.campaign.detector import run_meta, table1_detector  # noqa: E402
from ftc_mc.config import parse_config, with_overrides  # noqa: E402

COLS = ["correct_rate", "inappropriate_rate", "no_reset_rate"]


def first_alarm_view(trials: pd.DataFrame) -> pd.DataFrame:
    """Per transition: the closed loop's rates when only its first reset counts."""
    ok = trials[trials["judged"]]
    first_in = ok["first_reset_s"].notna()
    return pd.DataFrame({
        "correct_rate": (first_in & (ok["first_reset_block"] == ok["transition"].map(
            _correct))).groupby(ok["transition"]).mean(),
        "inappropriate_rate": (first_in & (ok["first_reset_block"] != ok["transition"].map(
            _correct))).groupby(ok["transition"]).mean(),
        "no_reset_rate": (~first_in).groupby(ok["transition"]).mean()})


def _correct(name: str) -> str:
    from ftc_mc.campaign.transitions import TRANSITION_TABLE
    from ftc_mc.conventions import BLOCK_NAMES
    return BLOCK_NAMES[TRANSITION_TABLE[name].correct_block]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run")
    ap.add_argument("--thresholds", type=float, default=40.0)
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    run = Path(a.run)
    cfg = parse_config(run_meta(run)["config"])
    closed = pd.read_parquet(run / "summary.parquet")
    closed = closed[closed["variant"] == "paper"].set_index("transition")[COLS]
    tr = pd.read_parquet(run / "trials.parquet")
    first = first_alarm_view(tr[tr["variant"] == "paper"])
    off = ftc_mc.score_detector(run, table1_detector("paper"), out=run / ".open_loop" / "t1")
    off = off["summary"]
    off = off[off["variant"] == "table1_paper@paper"].set_index("transition")[COLS]
    t = a.thresholds
    off_t = ftc_mc.score_detector(run, table1_detector("paper", t, t),
                                  out=run / ".open_loop" / "t")["summary"]
    off_t = off_t[off_t["variant"].str.endswith("@paper")].set_index("transition")[COLS]
    cfg_t = with_overrides(cfg, estimator={"t_q": t, "t_nx": t},
                           campaign={"signature": "paper", "record": "none"})
    res = ftc_mc.run_campaign(cfg_t, jobs=a.jobs, progress=False)
    tt = res.trials
    closed_t_first = first_alarm_view(tt)
    pct = lambda df: (100 * df).round(1)  # noqa: E731
    print(f"# Table 1 (paper) at {cfg.estimator.t_q:g}/{cfg.estimator.t_nx:g}, "
          f"{cfg.campaign.trials} trials per row, % of judged trials\n")
    print("closed loop, every reset in the window (Tables 2-3):")
    print(pct(closed).to_string())
    print("\nclosed loop, its first reset only:")
    print(pct(first).to_string())
    print("\nTable 1 offline on the recorded statistics, first alarm:")
    print(pct(off).to_string())
    print(f"\n# at thresholds {t:g}: offline on the recorded signals vs flown closed loop "
          "(first alarm / first reset)\n")
    print("offline:")
    print(pct(off_t).to_string())
    print("closed loop:")
    print(pct(closed_t_first).to_string())


if __name__ == "__main__":
    main()
