"""How often fault-free flights in moderate turbulence leave the validity envelope.

Flies ``--hours`` fault-free flight hours (50 s flights) of the default design of
configs/robust_moderate.yaml (``excited_airspeed``) on the nonlinear X8 and
``--hours-6dof`` of ``sixdof_robust_airspeed`` of configs/sixdof_moderate.yaml on
the flying wing, both in moderate Dryden turbulence, on a held-out ``--seed``,
and beside each the same design under the paper's c0 weights on the same
flights (``weights: paper``).
Prints, per design, the flights that left the envelope (by airspeed, by angle
of attack, by bank), the false resets and the flight hours.  Why c0 leaves and
what the airspeed weights change: docs/findings/turbulence-envelope.md.

Usage::

    python scripts/benchmarks/bench_envelope.py --hours 20 --hours-6dof 5 --seed 777

Last line: ``fault_free_exit_rate=<x> exit_rate_6dof=<y>`` (shares of the
flights that left the envelope, the shipped default designs).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def flown(config: str, name: str, hours: float, seed: int, jobs: int):
    """The endurance run of the config's design ``name`` (airspeed weights) and of
    the same design on c0's weights, ``<name>_c0``, on the same flights."""
    from ftc_mc.api import campaign_config
    from ftc_mc.campaign.endurance import run_endurance

    data = campaign_config(ROOT / "configs" / config).model_dump()
    data["designs"][f"{name}_c0"] = {**data["designs"][name], "weights": "paper"}
    cfg = campaign_config(data, seed=seed, design=[name, f"{name}_c0"])
    return run_endurance(cfg, hours, jobs=jobs, progress=False)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=20.0)
    ap.add_argument("--hours-6dof", type=float, default=5.0)
    ap.add_argument("--seed", type=int, default=777)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()

    rates = {}
    for key, config, name, hours in (
            ("3dof", "robust_moderate.yaml", "excited_airspeed", args.hours),
            ("6dof", "sixdof_moderate.yaml", "sixdof_robust_airspeed", args.hours_6dof)):
        t = time.perf_counter()
        res = flown(config, name, hours, args.seed, args.jobs)
        f = res.flights
        for design, g in f.groupby("variant", sort=False):
            left = g[g.status != "ok"]
            by = left.status.value_counts().to_dict()
            s = res.summary.set_index("variant").loc[design]
            print(f"{config} {design}: {len(left)} of {len(g)} flights left the envelope "
                  f"({100 * len(left) / len(g):.3f} %; {by}), {int(s['false_resets'])} "
                  f"false resets in {s['flight_hours']:.1f} h"
                  + (f", {int(s['side_decisions'])} side-monitor decisions"
                     if "side_decisions" in s.index else ""))
            if design == name:
                rates[key] = len(left) / len(g)
        print(f"  ({time.perf_counter() - t:.0f} s wall)")
    print(f"fault_free_exit_rate={rates['3dof']:.5f} exit_rate_6dof={rates['6dof']:.5f}")


if __name__ == "__main__":
    main()
