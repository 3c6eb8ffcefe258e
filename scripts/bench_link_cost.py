"""How much of a caller's compile is re-optimising the stages it links (issue 23).

``advance`` (``core/longitudinal/trial.py``) calls its stages as Numba kernels,
so Numba links each stage's LLVM module into ``advance``'s and optimises and
emits it again, even when the stage itself came from the kernel cache
(``docs/performance.md``, lesson 14).  A call through a first-class function
pointer (``numba.types.FunctionType``) links nothing: the stage is compiled
once, with its C wrapper, and called by address.

For each stage of the default path's compile plan, this script compiles, in
one fresh process with nothing cached in memory:

1. the stage alone, with its C wrapper (what a pointer call needs);
2. a three-call driver that calls it as ``advance`` does (linked);
3. the same driver calling it through a function pointer.

The difference of 2 and 3 is the time ``advance`` spends on that stage's
code.  Prints one line per stage and, last, ``link_s=<sum>``.  Nothing here
changes how ``ftc-mc`` compiles.

    python scripts/bench_link_cost.py [--stages paper_correct,select_lanes]
"""

from __future__ import annotations

import argparse
import time

import ftc_mc  # noqa: F401 -- the package first (its numba settings)
import numba
from numba import types

from ftc_mc.sim import compile_helper

DEFAULT_PATH = "linear plant, paper filter, one-step test, reconfiguring controller"
"""The plan key of the default path (``python3 dev.py run``)."""


def link_cost(module: str, qualname: str, args) -> tuple[float, float, float]:
    """Seconds to compile the stage with its C wrapper, a driver linking it,
    and a driver calling it through a function pointer."""
    stage = compile_helper._dispatcher(module, qualname)
    t = time.perf_counter()
    alone = numba.njit(no_cpython_wrapper=True)(stage.py_func)
    alone.compile(tuple(args))
    t_alone = time.perf_counter() - t
    names = ", ".join(f"a{i}" for i in range(len(args)))
    ns = {"STAGE": alone}
    exec(f"def linked({names}):\n    for _ in range(3):\n        STAGE({names})\n", ns)
    exec(f"def by_pointer(f, {names}):\n    for _ in range(3):\n        f({names})\n", ns)
    quiet = dict(no_cpython_wrapper=True, no_cfunc_wrapper=True)
    t = time.perf_counter()
    numba.njit(**quiet)(ns["linked"]).compile(tuple(args))
    t_linked = time.perf_counter() - t
    fn = types.FunctionType(alone.overloads[tuple(args)].signature)
    t = time.perf_counter()
    numba.njit(**quiet)(ns["by_pointer"]).compile((fn,) + tuple(args))
    return t_alone, t_linked, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stages", default="", help="comma-separated stage names "
                    "(default: every stage of the plan taking at least 1 s)")
    a = ap.parse_args()
    entry = compile_helper.load_plan()[DEFAULT_PATH]
    want = set(filter(None, a.stages.split(",")))
    total = 0.0
    for module, qualname, args, seconds in entry["stages"]:
        if (want and qualname not in want) or (not want and seconds < 1.0):
            continue
        alone, linked, pointer = link_cost(module, qualname, args)
        total += linked - pointer
        print(f"{qualname:>20}: alone with C wrapper {alone:5.1f} s, driver linking it "
              f"{linked:5.1f} s, through a pointer {pointer:5.1f} s")
    print(f"link_s={total:.1f}")


if __name__ == "__main__":
    main()
