"""How long could any controller keep a run's locks outside the trimmable set in?

Feeds ``docs/findings/sixdof.md``.  The aim for elevon locks outside the
trimmable set: the reconfiguring loop at least doubles the nominal
controller's median time to leave the envelope.
``scripts/studies/study_recoverable.py --json F`` finds, per lock offset, the
longest stay any command history it searched keeps the aircraft inside (an
oracle: side and lock known from the lock's first instant).  This script puts
that beside a run's trials:

* the run's elevon-lock trials of the studied side outside the trimmable set
  of the model the run flies, in its validity envelope
  (:func:`ftc_mc.campaign.survival.trimmable_sets`: on the linear plant
  exact, on the nonlinear one from its cache or searched);
* per design, their median time from the lock to the exit as the run's
  survival tables count it (:func:`ftc_mc.campaign.survival.lock_fate`: a
  trial that stays in the horizon counts as never leaving, one that stopped
  numerically or before the lock is left out);
* the oracle's median over the same trials: each trial's longest stay
  interpolated linearly in its offset from the 6-DOF trim (the study's
  offsets; ends held beyond the studied range; a lock the study flew for
  60 s counts as never leaving), and the share of trials whose oracle stay
  is at least twice the design's own exit.

The oracle's searches are local (SLSQP) and its stays interpolated, so its
median is evidence of what a controller can reach, not a proof.  Its rows
must cover the run's offsets; the script says how far they reach.

    python scripts/studies/oracle_bound.py STUDY.json RUN_DIR [--side left]
"""

from __future__ import annotations

import argparse
import json
import math

import ftc_mc  # noqa: F401 -- the package first (its numba settings)
import numpy as np

from ftc_mc.campaign.survival import horizon_of, lock_fate, trimmable_sets
from ftc_mc.campaign.transitions import LEFT, transition_of
from ftc_mc.config.load import parse_config
from ftc_mc.core.sixdof.layout import COMMAND
from ftc_mc.model.presets import resolve_airframe
from ftc_mc.model.sixdof import build_sixdof_plant
from ftc_mc.report.load import load_result_dir

T_END = 60.0
"""The study's flight [s]: a lock flown this long counts as never leaving."""


def oracle_stays(rows: list, side: str):
    """Offsets [deg] (increasing) and longest stays [s] (``inf`` where the
    study flew 60 s) of the study's rows of ``side``."""
    mine = sorted((r for r in rows if r["side"] == side), key=lambda r: r["offset_deg"])
    if not mine:
        raise SystemExit(f"the study has no {side} rows")
    off = np.array([r["offset_deg"] for r in mine])
    stay = np.array([math.inf if r["survived_s"] == T_END else r["longest_stay_s"]
                     for r in mine], dtype=float)
    return off, stay


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", help="scripts/studies/study_recoverable.py --json output")
    ap.add_argument("run", help="a run's folder (trials.parquet)")
    ap.add_argument("--side", choices=("left", "right"), default="left")
    a = ap.parse_args(argv)
    off, stay = oracle_stays(json.load(open(a.study)), a.side)
    r = load_result_dir(a.run)
    cfg = parse_config(r.meta["config"])
    m = cfg.model
    six = build_sixdof_plant(resolve_airframe(m.airframe), m.airspeed_mps, m.gamma_deg, m.dt_s)
    trials = r.tables["trials"]
    rows = [n for n in trials["transition"].unique()
            if n in cfg.campaign.transitions and transition_of(n).is_elevon
            and transition_of(n).kind == "lock" and transition_of(n).onset
            and (transition_of(n).actuator == LEFT) == (a.side == "left")]
    sets = trimmable_sets(cfg)
    t_lock = cfg.timing.fault_time_s
    horizon = horizon_of(t_lock, cfg.timing.duration_s)
    trim = six.u0[COMMAND[a.side]]
    for name in rows:
        if name not in sets:
            print(f"{name}: no trimmable set (a longitudinal run, or no steady flight "
                  "at trim)")
            continue
        lo, hi = sets[name]
        t = trials[trials["transition"] == name]
        pos = t["lock_position"].to_numpy(dtype=float)
        t = t[(pos < lo) | (pos > hi)]
        if not len(t):
            print(f"{name}: no trials outside the trimmable set")
            continue
        o = np.degrees(t["lock_position"].to_numpy(dtype=float) - trim)
        print(f"{name}: {len(t) // t['variant'].nunique()} trials per design outside the "
              f"trimmable set ({math.degrees(lo - trim):+.2f} to {math.degrees(hi - trim):+.2f}"
              f" deg); their offsets from the 6-DOF trim {o.min():+.1f} to {o.max():+.1f} "
              f"deg, the study's {off[0]:+g} to {off[-1]:+g} deg")
        for variant, g in t.groupby("variant", sort=False):
            fate = lock_fate(g, t_lock, horizon)
            keep = fate["keep"]
            leave = np.where(fate["left"], fate["after"], math.inf)[keep]
            b = np.interp(np.degrees(g["lock_position"].to_numpy(dtype=float) - trim),
                          off, stay)[keep]
            print(f"  {variant:16s} median exit {np.median(leave):5.2f} s | oracle "
                  f"{np.median(b):5.2f} s | oracle >= 2 x this design's exit in "
                  f"{100 * np.mean(b >= 2 * leave):5.1f} % of the trials")


if __name__ == "__main__":
    main()
