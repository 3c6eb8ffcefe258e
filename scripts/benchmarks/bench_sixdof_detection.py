"""Detection on the flying wing in moderate turbulence: the designs of
configs/sixdof_moderate.yaml side by side on the same trials and flights.

Flies the config's designs (the paper's Table 1, ``sixdof_robust`` and the
recommended ``sixdof_monitor``, whose resets come from the 6-DOF side monitor)
on the nonlinear ``x8-pyfly`` in moderate Dryden turbulence:

* ``--hours`` fault-free flight hours per design (40 s flights, seed
  ``--seed-flights``): false resets and side-monitor decisions per flight hour,
  and the share of flights that left the envelope;
* the twelve rows of the config at ``--trials`` trials each (seed
  ``--seed-rows``): the mean unexplained no-reset over the rows
  (docs/reference/glossary.md#unexplained), the worst row's inappropriate
  resets, the correct side after elevon locks and after losses with
  ``b1 >= 0.5``, each side, and the survival of the locks from -5 to +2 deg
  of trim: the share still inside the envelope 30 s after the lock (the
  run's horizon; ``ftc_mc.campaign.survival``), each side.

The default seeds are the held-out ones of docs/findings/sixdof-monitor-resets.md
(the designs were chosen on others).  Usage::

    python scripts/benchmarks/bench_sixdof_detection.py --hours 30 --trials 200
    python scripts/benchmarks/bench_sixdof_detection.py --turbulence severe --design sixdof_monitor

Last line, the recommended design's:
``sixdof_false_resets_per_h=<x> sixdof_side_decisions_per_h=<y> sixdof_unexplained=<z>``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "sixdof_moderate.yaml"
RECOMMENDED = "sixdof_monitor"


def fault_free(hours: float, seed: int, jobs: int, over: dict):
    """Per design: false resets and side decisions per flight hour, exit share."""
    from ftc_mc.api import campaign_config
    from ftc_mc.campaign.endurance import run_endurance

    res = run_endurance(campaign_config(CONFIG, seed=seed, **over), hours, jobs=jobs,
                        progress=False)
    out = {}
    for design, g in res.flights.groupby("variant", sort=False):
        s = res.summary.set_index("variant").loc[design]
        h = float(s["flight_hours"])
        out[design] = {"hours": h, "false_per_h": float(s["false_resets"]) / h,
                       "side_per_h": float(s["side_decisions"]) / h,
                       "exits": float((g["status"] != "ok").mean())}
    return out


def rows(trials: int, seed: int, jobs: int, over: dict):
    """Per design: the twelve rows' detection, side and survival figures."""
    from ftc_mc.api import campaign_config, run_campaign
    from ftc_mc.campaign.survival import survival_table

    cfg = campaign_config(CONFIG, trials=trials, seed=seed, **over)
    res = run_campaign(cfg, jobs=jobs, progress=False)
    s, t = res.summary, res.trials
    band = survival_table(t, cfg.timing.fault_time_s, cfg.timing.duration_s,
                          edges=(-np.inf, -5.0, 2.0, np.inf))
    band = band[band["offset_lo_deg"] == -5.0]  # the locks from -5 to +2 deg of trim
    out = {}
    for design, g in s.groupby("variant", sort=False):
        unexplained = g["no_reset_rate"] * (1.0 - g["no_reset_explained_share"].fillna(0.0))
        d = t[(t["variant"] == design) & t["side_correct"].notna()]
        side = {}
        for key, row in (("lock_left", "elevon_lock"), ("lock_right", "right_elevon_lock")):
            side[key] = float(d.loc[d["transition"] == row, "side_correct"].mean())
        for key, row in (("loss_left", "elevon_loss"), ("loss_right", "right_elevon_loss")):
            big = d[(d["transition"] == row) & (d["loss_b1"] >= 0.5)]
            side[key] = float(big["side_correct"].mean())
        for key, row in (("survive_left", "elevon_lock"), ("survive_right", "right_elevon_lock")):
            b = band[(band["variant"] == design) & (band["transition"] == row)]
            side[key] = (int(b["flying"].sum() - b["left"].sum()), int(b["flying"].sum()))
        out[design] = {"unexplained": float(unexplained.mean()),
                       "inappropriate_max": float(g["inappropriate_rate"].max()), **side}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=30.0)
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--seed-flights", type=int, default=6102)
    ap.add_argument("--seed-rows", type=int, default=6101)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--turbulence", default=None, help="override plant.turbulence (severe)")
    ap.add_argument("--design", action="append", default=None,
                    help="the designs flown (repeatable; default: the config's)")
    args = ap.parse_args()
    over = {k: v for k, v in (("turbulence", args.turbulence), ("design", args.design))
            if v is not None}

    t0 = time.perf_counter()
    free = fault_free(args.hours, args.seed_flights, args.jobs, over)
    t1 = time.perf_counter()
    table = rows(args.trials, args.seed_rows, args.jobs, over)
    t2 = time.perf_counter()
    print(f"configs/sixdof_moderate.yaml {over or ''}: {args.hours} fault-free h per design (seed "
          f"{args.seed_flights}, {t1 - t0:.0f} s), {args.trials} trials a row (seed "
          f"{args.seed_rows}, {t2 - t1:.0f} s)")
    print("| design | false resets / h | side decisions / h | exits % | mean unexplained "
          "no-reset % | worst inappropriate % | side, locks L / R % | side, losses "
          "b1 >= 0.5 L / R % | in 30 s after a lock -5 to +2 deg, L / R |")
    print("|---|---|---|---|---|---|---|---|---|")
    pct = lambda v: "-" if np.isnan(v) else f"{100 * v:.1f}"  # noqa: E731
    for design, f in free.items():
        r = table[design]
        print(f"| {design} | {f['false_per_h']:.3f} ({f['hours']:.1f} h) | "
              f"{f['side_per_h']:.3f} | {100 * f['exits']:.2f} | {pct(r['unexplained'])} | "
              f"{pct(r['inappropriate_max'])} | {pct(r['lock_left'])} / {pct(r['lock_right'])} "
              f"| {pct(r['loss_left'])} / {pct(r['loss_right'])} | "
              f"{'{}/{}'.format(*r['survive_left'])} / {'{}/{}'.format(*r['survive_right'])} |")
    f, r = free[RECOMMENDED], table[RECOMMENDED]
    print(f"sixdof_false_resets_per_h={f['false_per_h']:.4f} "
          f"sixdof_side_decisions_per_h={f['side_per_h']:.4f} "
          f"sixdof_unexplained={r['unexplained']:.4f}")


if __name__ == "__main__":
    main()
