"""Write the compile plan, ``ftc_mc/sim/compile_plan.pkl`` (``ftc_mc/sim/compile_helper.py``).

For every compile path the shipped campaign configs (``configs/*.yaml``) take,
one fresh process with an empty Numba cache and no compile helper runs the
path's warm-up (``ftc_mc.campaign.chunk.warm_up``) and records, through
Numba's ``numba:compile`` events, the kernels of ``ftc_mc/core`` that
``advance`` compiles directly, in order, with their argument types and the
seconds each took, and the seconds compiled before ``advance`` begins.  A
stage that calls kernels by address (``core/linking.py``: ``trial_steps``,
``reconfigure``) is replaced by those kernels, and its own seconds count
with the setup's, as this process's: it compiles that stage itself while it
types ``advance``, and waits there for the kernels the helper has claimed.

Run it after a change of what ``advance`` calls or of its stages' signatures
(``tests/test_compile_helper.py`` fails when the default path's plan is stale),
or after a Numba upgrade (a plan from another Numba version is not used).
It takes a cold compile per path: about 20-30 minutes for all of them on 2 cores.

Usage: ``python scripts/maintenance/make_compile_plan.py [--only KEY ...]`` (``--only``
records the paths named, words as in the compile notice, and keeps the others).
"""

from __future__ import annotations

import argparse
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import ftc_mc  # noqa: E402,F401 -- before numpy (threads)


def paths_of_configs() -> dict:
    """``{path key: (config file, variant)}``: the first config and variant
    (signature variant or design) taking each compile path."""
    from ftc_mc.campaign.chunk import chunk_spec
    from ftc_mc.config import load_config
    from ftc_mc.errors import UserError
    from ftc_mc.sim.compile_helper import plan_key
    from ftc_mc.sim.paths import path_of

    found = {}
    for f in sorted((ROOT / "configs").glob("*.yaml")):
        try:
            cfg = load_config(f)
        except UserError:  # not a campaign config (the scenario's)
            continue
        spec = chunk_spec(cfg)
        for v in spec.variants:
            found.setdefault(plan_key(path_of(spec.setup.scheme(v), spec.setup.flight)),
                             (str(f.relative_to(ROOT)), v))
    return found


def record(config: str, variant: str, out: str) -> None:
    """In a fresh process: compile ``variant``'s path of ``config`` on an empty
    cache and pickle ``(before_s, stages)`` to ``out``."""
    import dataclasses

    from numba.core import event

    from ftc_mc.campaign.chunk import chunk_spec, warm_up
    from ftc_mc.config import load_config
    from ftc_mc.core import linking

    events, open_ = [], []

    class Listener(event.Listener):
        def on_start(self, ev):
            open_.append(time.perf_counter())

        def on_end(self, ev):
            t0 = open_.pop()
            d = ev.data["dispatcher"]
            events.append((d.py_func.__module__, d.py_func.__qualname__,
                           tuple(ev.data["args"]), t0, time.perf_counter(), len(open_)))

    event.register("numba:compile", Listener())
    cfg = load_config(ROOT / config)
    spec = dataclasses.replace(chunk_spec(cfg), variants=(variant,))
    t_start = time.perf_counter()
    warm_up(spec, cfg.campaign.transitions[0])
    [adv] = [e for e in events if e[:2] == ("ftc_mc.core.longitudinal.trial", "advance")]
    inside = [e for e in sorted(events, key=lambda e: e[3])
              if adv[3] <= e[3] <= adv[4] and e[0].startswith("ftc_mc.core.")]
    by_address = {(m, q) for m, q, _ in linking._STAGES.values()}
    stages, parents_s = [], 0.0
    for e in (e for e in inside if e[5] == adv[5] + 1):
        # a stage that calls kernels by address (trial_steps, reconfigure):
        # those are stages of their own, and its own seconds this process's
        kids = [f for f in inside if f[5] == e[5] + 1 and e[3] <= f[3] <= e[4]
                and f[:2] in by_address]
        stages += [(m, q, a, round(t1 - t0, 2)) for m, q, a, t0, t1, _ in kids]
        own = (e[4] - e[3]) - sum(f[4] - f[3] for f in kids)
        if kids:
            parents_s += own
        else:
            stages.append((e[0], e[1], e[2], round(own, 2)))
    with open(out, "wb") as f:
        pickle.dump((round(adv[3] - t_start + parents_s, 2), stages), f, protocol=4)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None, help="path keys to record")
    ap.add_argument("--record", nargs=3, metavar=("CONFIG", "VARIANT", "OUT"),
                    help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.record:
        record(*args.record)
        return
    import numba

    from ftc_mc.sim.compile_helper import PLAN_FILE, load_plan
    wanted = paths_of_configs()
    if args.only:
        unknown = set(args.only) - set(wanted)
        if unknown:
            sys.exit(f"no shipped config takes the path(s) {sorted(unknown)}")
        wanted = {k: wanted[k] for k in args.only}
    paths = load_plan() if args.only else {}
    if args.only and not paths and PLAN_FILE.exists():
        sys.exit(f"{PLAN_FILE}: unreadable or of another Numba version; record every "
                 "path (without --only)")
    for key, (config, variant) in wanted.items():
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, NUMBA_CACHE_DIR=tmp, FTC_MC_COMPILE_HELPER="0")
            out = Path(tmp) / "stages.pkl"
            t = time.perf_counter()
            rec = subprocess.run([sys.executable, __file__, "--record", config, variant,
                                  str(out)], cwd=ROOT, env=env, stderr=subprocess.PIPE,
                                 text=True)
            if rec.returncode != 0:
                sys.exit(f"recording {key} ({config}, {variant}) failed:\n{rec.stderr}")
            with open(out, "rb") as f:
                before_s, stages = pickle.load(f)
        paths[key] = {"before_s": before_s, "stages": stages}
        print(f"{key} ({config}, {variant}): {len(stages)} stages, "
              f"{sum(s[3] for s in stages):.1f} s of {time.perf_counter() - t:.1f} s",
              flush=True)
    tmp = PLAN_FILE.with_suffix(".tmp")
    with open(tmp, "wb") as f:
        pickle.dump({"numba": numba.__version__, "paths": paths}, f, protocol=4)
    os.replace(tmp, PLAN_FILE)
    print(f"wrote {PLAN_FILE.relative_to(ROOT)}: {len(paths)} paths")


if __name__ == "__main__":
    main()
