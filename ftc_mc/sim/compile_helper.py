"""A second process that compiles part of a path while this one compiles the rest.

Numba compiles a kernel on one core: a path's cold compile
(:func:`ftc_mc.sim.compiling.compiled_once`) types :func:`advance
<ftc_mc.core.longitudinal.trial.advance>`, and each stage it calls (the truth
plant, the filter's prediction and correction, the selection, ...) is compiled
in full, one after another, when its call is typed.  Those stages do not depend
on each other, so on a machine with two cores they are split in two shares of
about equal work (:func:`split`): a helper process compiles one into the kernel
cache while this process compiles the other before it types ``advance``
(:func:`compile_own`); when the typing reaches a stage the helper has done it
loads it from the cache, and one the helper is still compiling it waits for
(the *claims* of :class:`ftc_mc.core.jit.ContentFunctionCache`).  ``advance``'s
own compile, which calls its stages by address (:mod:`ftc_mc.core.linking`),
stays in this process (measured: ``docs/findings/performance.md``, lessons 11, 14 and
17).

The helper must know each stage's Numba signature before ``advance`` is typed.
The *compile plan* (:data:`PLAN_FILE`, written by ``scripts/maintenance/make_compile_plan.py``)
holds, per path of the shipped configs, the stages ``advance`` compiles, in the
order it compiles them, with their argument types and the seconds each took.
A plan that no longer matches the kernels costs only the work of compiling
its stages: the cache is keyed on the signature and the kernel sources, so a
stage compiled for a signature ``advance`` no longer uses is never loaded, and
``advance``'s typing compiles whatever it finds missing.  Results never depend
on the helper.

Run as ``python -m ftc_mc.sim.compile_helper KEY [--plan FILE] [--stages I,J,...]`` by
:func:`start`; ``FTC_MC_COMPILE_HELPER=0`` turns it off.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pickle
import subprocess
import sys
from pathlib import Path

import numba

from ..core import jit
from ..core.shared.paths import describe

PLAN_FILE = Path(__file__).with_name("compile_plan.pkl")
"""The compile plan shipped with the package (module docstring)."""

PACKAGE_ROOT = Path(__file__).resolve().parents[2]
"""The folder holding this ``ftc_mc`` package: the helper's working folder, so
that ``python -m`` imports the same package and nothing else from elsewhere."""

STOP_WAIT_S = 5.0
"""How long :func:`stop` waits for a helper it asked to end [s]."""


def enabled() -> bool:
    """Whether a compile helper may run: the disk cache is on, ``flock``
    exists, ``FTC_MC_COMPILE_HELPER`` is not ``0`` and this process may use at
    least two cores."""
    if not jit.CACHE or os.environ.get("FTC_MC_COMPILE_HELPER", "1") == "0":
        return False
    try:
        import fcntl  # noqa: F401 -- the claims are flocks
    except ImportError:
        return False
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return (cores or 1) >= 2


def plan_key(path) -> str:
    """The key of a compile path in the plan: its words
    (:func:`ftc_mc.core.shared.paths.describe`)."""
    return describe(path)


PLAN_NOTICE = ("ftc-mc: the compile plan ({}) {}; this process compiles the kernels "
               "without its helper (slower, same results)")
"""Printed to stderr, once per process, when the shipped plan cannot be used
with the installed Numba (:func:`load_plan`)."""

_PLAN_NOTICED = False


def _plan_notice(plan_file: Path, why: str) -> None:
    global _PLAN_NOTICED
    if not _PLAN_NOTICED:
        _PLAN_NOTICED = True
        print(" ".join(PLAN_NOTICE.format(Path(plan_file).name, why).split()),
              file=sys.stderr, flush=True)


def load_plan(plan_file: Path = PLAN_FILE) -> dict:
    """The plan's paths: ``{key: {"before_s": s, "stages": [(module, qualname,
    argument types, seconds), ...]}}``; empty when the file is missing, cannot
    be read (a Numba whose type classes moved, a damaged file), or was written
    by another Numba version (whose types may differ).  A plan that is there
    but cannot be used is said once on stderr (:data:`PLAN_NOTICE`): the
    compile then runs in this process alone."""
    try:
        with open(plan_file, "rb") as f:
            plan = pickle.load(f)
    except FileNotFoundError:
        return {}
    except Exception as exc:  # noqa: BLE001 -- no plan: this process compiles alone
        why = " ".join(f"{type(exc).__name__}: {exc}".split())[:120]
        _plan_notice(plan_file, f"cannot be read with Numba {numba.__version__} ({why})")
        return {}
    if not isinstance(plan, dict) or plan.get("numba") != numba.__version__:
        written = plan.get("numba") if isinstance(plan, dict) else None
        _plan_notice(plan_file, f"was written by Numba {written}, this is Numba "
                     f"{numba.__version__}")
        return {}
    return plan.get("paths", {})


HELPER_START_S = 3.0
"""Seconds a helper takes to start (Python, Numba and ``ftc_mc`` imported,
the plan read) before it compiles: its load at the start of :func:`split`."""


def split(stages, before_s: float) -> tuple[list, list]:
    """The stages this process compiles and those the helper compiles: the
    longest first, each to the process with less work so far (this one
    starting at ``before_s``, the helper at :data:`HELPER_START_S`), both
    shares in the plan's order.

    The stages do not depend on each other, so any partition is valid; this
    process compiles its share before it types ``advance``
    (:func:`compile_own`), not when ``advance``'s typing reaches each stage,
    so the two largest stages can go one to each process whatever their
    order in ``advance``.

    Parameters
    ----------
    stages : list of tuple
        One tuple per stage, its compile seconds last (the plan's ``(module,
        qualname, argument types, seconds)``).
    before_s : float
        Seconds this process compiles besides the stages (the setup kernels
        before ``advance``, and the own work of the stages that call the
        plan's stages by address, ``trial_steps`` and ``reconfigure``, which
        it compiles while it types ``advance``) [s].

    Returns
    -------
    own, helper : list of tuple
        The two shares of ``stages``.
    """
    load = [before_s, HELPER_START_S]
    where = {}
    for i in sorted(range(len(stages)), key=lambda i: -stages[i][-1]):
        p = 0 if load[0] <= load[1] else 1
        where[i] = p
        load[p] += stages[i][-1]
    return ([s for i, s in enumerate(stages) if where[i] == 0],
            [s for i, s in enumerate(stages) if where[i] == 1])


def _to_compile(entry) -> list:
    """``(index, dispatcher, args, seconds)`` of each stage of the plan's
    ``entry`` the kernel cache lacks (a stage another path left in the cache
    costs nothing)."""
    todo = []
    for i, (module, qualname, args, seconds) in enumerate(entry["stages"]):
        dispatcher = _dispatcher(module, qualname)
        if dispatcher is not None and not jit.cached_signature(dispatcher, args):
            todo.append((i, dispatcher, args, seconds))
    return todo


def start(path, plan_file: Path = PLAN_FILE):
    """Start the helper for the compile ``path`` if it may run (:func:`enabled`)
    and the plan knows the path.

    Returns
    -------
    proc : subprocess.Popen or None
        The helper, compiling its share of :func:`split` (its stages' indices
        in the plan passed as ``--stages``).
    own : list of tuple
        ``(dispatcher, argument types)`` of this process's share, for
        :func:`compile_own`; empty without a helper.
    """
    if not enabled():
        return None, []
    key = plan_key(path)
    entry = load_plan(plan_file).get(key)
    if entry is None:
        return None, []
    own, theirs = split(_to_compile(entry), entry["before_s"])
    if not theirs:
        return None, []
    cmd = [sys.executable, "-m", __name__, key, "--plan", str(plan_file),
           "--parent", str(os.getpid()), "--stages", ",".join(str(t[0]) for t in theirs)]
    try:  # run from the folder this package is in: the helper imports this ftc_mc
        proc = subprocess.Popen(cmd, cwd=PACKAGE_ROOT, stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return None, []
    return proc, [(t[1], t[2]) for t in own]


def compile_own(own) -> None:
    """Compile this process's share (:func:`start`) into the kernel cache,
    before ``advance`` is typed; a stage that fails to compile (a stale plan)
    is left to that typing."""
    for dispatcher, args in own:
        try:
            dispatcher.compile(tuple(args))
        except Exception:  # noqa: BLE001 -- advance's typing compiles what it lacks
            pass


def stop(proc) -> None:
    """End the helper ``proc`` (from :func:`start`) if it still runs: this
    process has compiled the path, so what is left of the helper's work is
    for signatures the path did not use (a stale plan)."""
    if proc is None or proc.poll() is not None:
        return
    proc.terminate()
    try:
        proc.wait(STOP_WAIT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def _dispatcher(module: str, qualname: str):
    """The kernel ``module.qualname`` if it is a cached kernel of ``core/``;
    None if it is not, or no longer exists (a stale plan: a kernel moved or
    renamed since the plan was written)."""
    try:
        obj = importlib.import_module(module)
        for part in qualname.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        return None
    return obj if isinstance(getattr(obj, "_cache", None), jit.ContentFunctionCache) else None


def _claim(dispatcher, args):
    """Take the claim of ``dispatcher``'s signature ``args``; the open file,
    or None if another process holds it."""
    import fcntl
    try:
        path = dispatcher._cache.claim_path(args)
        fd = os.open(path, os.O_CREAT | os.O_RDWR, 0o644)
    except (OSError, ValueError, TypeError):  # e.g. a cache folder of another user
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # held by another helper, or no flock on this file system
        os.close(fd)
        return None
    return fd, path


def _release(claim) -> None:
    """Let go of a claim from :func:`_claim`, deleting its file first."""
    fd, path = claim
    try:
        path.unlink()
    except OSError:
        pass
    os.close(fd)


def run(key: str, plan_file: Path = PLAN_FILE, parent: int | None = None,
        stages=None) -> int:
    """The helper's work: claim its share of the path ``key``'s stages that
    the cache lacks (the plan indices ``stages`` that :func:`start` chose;
    without them, the helper's share of :func:`split`), then compile them in
    the plan's order, letting go of each claim when its kernel is saved.  A
    stage that is cached meanwhile is skipped; one that fails to compile (a
    stale plan) is left to the process it works for.  Stops when that
    process, ``parent`` (default: this one's parent), has gone.  Returns the
    exit status (0, or 1 when the plan does not know ``key``)."""
    entry = load_plan(plan_file).get(key)
    if entry is None:
        return 1
    parent = os.getppid() if parent is None else parent
    jit.ContentFunctionCache.awaits_claims = False  # never wait: no cycle of waits
    todo = _to_compile(entry)
    if stages is None:
        share = split(todo, entry["before_s"])[1]
    else:
        chosen = set(stages)
        share = [t for t in todo if t[0] in chosen]
    claimed = []
    for _, dispatcher, args, _ in share:
        claim = _claim(dispatcher, args)
        if claim is not None:
            claimed.append((dispatcher, args, claim))
    for dispatcher, args, claim in claimed:
        if os.getppid() != parent:  # the process it works for has gone
            return 0
        try:
            dispatcher.compile(tuple(args))
        except Exception:  # noqa: BLE001 -- that process compiles what it lacks
            pass
        finally:
            _release(claim)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m ftc_mc.sim.compile_helper",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("key", help="the path's key in the plan (its words)")
    ap.add_argument("--plan", type=Path, default=PLAN_FILE, help="the compile plan file")
    ap.add_argument("--parent", type=int, default=None,
                    help="the process it works for (default: its parent)")
    ap.add_argument("--stages", default=None,
                    help="the plan indices of the stages to compile, comma-separated "
                    "(default: the helper's share of the balance)")
    a = ap.parse_args(argv)
    stages = None if a.stages is None else [int(i) for i in a.stages.split(",") if i]
    return run(a.key, a.plan, a.parent, stages)


if __name__ == "__main__":
    sys.exit(main())
