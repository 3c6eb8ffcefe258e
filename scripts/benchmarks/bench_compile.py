"""Benchmark of the cold compile of each compile path.

For each path below, a fresh interpreter with an empty Numba cache
(``NUMBA_CACHE_DIR`` pointed at an empty folder) warms the kernels of one
design of a config (``campaign.chunk.warm_up``), and reports:

* ``wall_s`` and ``cpu_s``: the warm-up's wall and CPU time, the setup's own
  kernels (trim, terminal costs) included;
* ``advance_s``: the CPU time of the trial kernel's compile alone (Numba's
  ``numba:compile`` event of ``advance``, callees included);
* the five callees that took longest.

Each path is measured on its own empty cache, so the kernels it shares with the
default path (the setup's, the paper filter's) count in every row; the cost one
path adds to another already cached is ``scripts/benchmarks/bench_campaign.py``'s
``compile_robust_s``.

The last line is ``compile_default_cpu_s=<x> compile_default_wall_s=<y>``.
Usage: ``python scripts/benchmarks/bench_compile.py [--only NAME ...]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PATHS = {
    # name: (config, design, overrides)
    "default": ("paper_tables.yaml", "paper", {}),
    "nominal": ("paper_tables.yaml", "paper", {"controller": {"kind": "nominal"}}),
    "nonlinear": ("paper_tables.yaml", "paper",
                  {"plant": {"kind": "nonlinear", "turbulence": "moderate"}}),
    "dense_glr": ("designs.yaml", "gust_glr", {}),
    "robust": ("robust_moderate.yaml", "robust", {}),
    "sixdof": ("sixdof_tables.yaml", "paper", {}),  # the 6-DOF plant's path
    # the 6-DOF plant in moderate turbulence: its side monitor the extended filter
    "sixdof_extended": ("sixdof_moderate.yaml", "paper", {}),
}

CHILD = r"""
import json, sys, time
from numba.core import event as ev
stack, rows = [], []
class Recorder(ev.Listener):
    def on_start(self, e):
        name = "?"
        if "dispatcher" in e.data:
            f = e.data["dispatcher"].py_func
            name = f.__qualname__
            # a dispatcher's call (core/shared/paths.on_path): name the kernel it calls
            for cell in (f.__closure__ or ()) if name.endswith("<lambda>") else ():
                if hasattr(cell.cell_contents, "py_func"):
                    name = "-> " + cell.cell_contents.py_func.__name__
        stack.append((name, time.process_time()))
    def on_end(self, e):
        name, t0 = stack.pop()
        rows.append((len(stack), name, time.process_time() - t0))
ev.register("numba:compile", Recorder())
from ftc_mc.config import load_config, with_overrides
from ftc_mc.campaign.chunk import chunk_spec, warm_up
import dataclasses
cfg_name, design, overrides = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
cfg = load_config("configs/" + cfg_name)
if design in cfg.designs:  # a design of the config's section: run it (built-ins always run)
    overrides = dict(overrides, campaign={"designs": [design]})
if overrides:
    cfg = with_overrides(cfg, **overrides)
spec = chunk_spec(cfg)
spec = dataclasses.replace(spec, variants=(design,))
t, c = time.perf_counter(), time.process_time()
warm_up(spec, cfg.campaign.transitions[0])
wall, cpu = time.perf_counter() - t, time.process_time() - c
adv = [r for r in rows if r[1] == "advance"]
top = sorted((r for r in rows if r[0] == 1), key=lambda r: -r[2])[:5]
print(json.dumps({"wall_s": wall, "cpu_s": cpu, "advance_s": sum(r[2] for r in adv),
                  "top": [[n, round(s, 1)] for _, n, s in top]}))
"""


def measure(cfg: str, design: str, overrides: dict) -> dict:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", CHILD, cfg, design, json.dumps(overrides)],
                             cwd=ROOT, env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", choices=sorted(PATHS), default=None)
    args = ap.parse_args()
    names = args.only or list(PATHS)
    rows = {}
    for name in names:
        rows[name] = r = measure(*PATHS[name])
        top = ", ".join(f"{n} {s:.1f}" for n, s in r["top"])
        print(f"{name:>10}: wall {r['wall_s']:6.1f} s  cpu {r['cpu_s']:6.1f} s  "
              f"advance {r['advance_s']:6.1f} s cpu  (top callees: {top})", flush=True)
    if "default" in rows:
        d = rows["default"]
        print(f"compile_default_cpu_s={d['cpu_s']:.1f} compile_default_wall_s={d['wall_s']:.1f}")


if __name__ == "__main__":
    main()
