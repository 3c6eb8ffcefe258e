"""Benchmark: the paper's 14-state filter problem through its own structured
kernels and through the dense (general) filter's kernels.

Both fly the same 256 trials of ``configs/paper_tables.yaml``'s
``elevon_loss`` row (linear plant, still air, one thread, the controller given
as the first argument: ``nominal`` by default, or ``reconfiguring``), in one
process, alternately, three times each; the first call of each compiles.  The
dense path is the paper's scheme with ``Path.filter = DENSE_FILTER``: the
general filter with no gust or bias states.  Prints each path's best trial-step
rate and whether the records agree (reset counts, statuses, final estimates).

The last line is ``paper_steps_per_s=<x> dense_steps_per_s=<y> ratio=<x/y>
identical=<bool>``.  Usage: ``python scripts/benchmarks/bench_dense_vs_paper.py [nominal|reconfiguring]``.
"""

from __future__ import annotations

import os

for _var in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ[_var] = "1"

import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from ftc_mc import api  # noqa: E402
from ftc_mc.campaign.chunk import chunk_spec, trial_inputs  # noqa: E402
from ftc_mc.core.longitudinal.trial import advance  # noqa: E402
from ftc_mc.core.shared.paths import DENSE_FILTER  # noqa: E402
from ftc_mc.sim.inputs import design_inputs  # noqa: E402
from ftc_mc.sim.lanes import new_record, start_lanes  # noqa: E402
from ftc_mc.sim.paths import path_of  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
L = 256


def main() -> None:
    ctl = sys.argv[1] if len(sys.argv) > 1 else "nominal"
    cfg = api.campaign_config(ROOT / "configs" / "paper_tables.yaml", trials=L,
                              controller=ctl)
    spec = chunk_spec(cfg)
    setup = spec.setup
    inp, _ = trial_inputs(spec, "elevon_loss", np.arange(L))
    dinp = design_inputs(inp, setup.designs["paper"])
    scheme, flight = setup.scheme("paper"), setup.flight
    paths = {"paper": path_of(scheme, flight)}
    paths["dense"] = paths["paper"]._replace(filter=DENSE_FILTER)
    times, recs = {}, {}
    for _ in range(3):
        for label, path in paths.items():
            rec = new_record(setup, L, 64, n_est=setup.designs["paper"].n_aug)
            st = start_lanes(scheme, flight, dinp, rec)
            t0 = time.perf_counter()
            advance(path, scheme, flight, dinp, rec, st, 0, setup.tim.n_steps)
            times.setdefault(label, []).append(time.perf_counter() - t0)
            recs[label] = rec
    steps = L * setup.tim.n_steps
    rate = {}
    for label, ts in times.items():
        rate[label] = steps / min(ts[1:])
        print(f"{label:>6}: first call (compile or cache load) {ts[0]:.1f} s; runs "
              f"{', '.join(f'{t:.3f}' for t in ts[1:])} s; best "
              f"{rate[label] / 1e6:.3f} M trial steps/s")
    a, b = recs["paper"], recs["dense"]
    same = (np.array_equal(a.n_resets, b.n_resets) and np.array_equal(a.status, b.status)
            and np.array_equal(a.xa_end, b.xa_end))
    print(f"controller {ctl}: records identical: {same}")
    print(f"paper_steps_per_s={rate['paper']:.0f} dense_steps_per_s={rate['dense']:.0f} "
          f"ratio={rate['paper'] / rate['dense']:.2f} identical={same}")


if __name__ == "__main__":
    main()
