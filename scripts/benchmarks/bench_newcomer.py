"""Benchmark of a newcomer's first minutes: the README's two commands on a fresh clone.

Clones this repository's current commit (``HEAD``; uncommitted changes are not
in it) into a temporary folder and, there, with every cache empty, runs what
the README's quick start says, timing each:

* ``python3 dev.py run``, split in its two parts, run back to back: dev.py's
  install (the virtual environment, pip, ftc-mc and its dependencies, their
  bytecode) and the main job, ``ftc-mc run configs/paper_tables.yaml`` (8,000
  trials: the eight rows of Tables 2-3, 1000 each, both variants of Table 1),
  itself split by the times its output appears: the start (imports, config,
  setup) up to the compile notice, the cold compile of the default path (the
  figure ``ftc-mc: compiled in X s`` reports), the trials (from the progress
  bar's first line to its last), and the table and result files after them;
* ``python3 dev.py test``, after the run as a newcomer would: its install of
  the test extras into the same ``.venv`` and the tests it runs (pytest's own
  figure is printed beside it).

Empty caches: the kernel and design caches (``FTC_MC_CACHE_DIR``), pip's
(``PIP_CACHE_DIR``, an empty folder: a fresh machine has none, and pip fills it
during the first install as it would there) and matplotlib's
(``MPLCONFIGDIR``).  ``HOME`` is kept, for pip's configuration (its index:
where that is a local mirror, as on the machine this was written on, pip
caches nothing and the install is quicker than from PyPI over a network).
``PYTHONPATH``, ``VIRTUAL_ENV``, ``NUMBA_CACHE_DIR``, ``FTC_MC_NUMBA_CACHE``,
``FTC_MC_COMPILE_HELPER``, ``PYTHONDONTWRITEBYTECODE`` and ``PYTHONHOME`` are removed from the
commands' environment.  The interpreter is the ``python3`` a newcomer would
type (``python3.11`` if there is one, as ``.ci/run`` picks it), outside any
virtual environment; ``--python`` names another.

Prints the machine (CPU model, cores, load average before and after: other
work on the machine slows every figure), each part, with each command's CPU
seconds (its processes' user and system time: on 2 cores an unshared wall time
is at least half of it), and as its last line
``first_run_s=<a> compile_s=<b> tests_s=<c>``: the wall time of ``python3
dev.py run`` (install, start, compile and trials), the cold compile of the
default path, and the wall time of ``python3 dev.py test`` (its install of the
test extras included); ``tests_s=nan`` with ``--skip-tests``.

With ``--tests-only``, only ``python3 dev.py test`` runs on the fresh clone,
every cache empty (the whole install and every kernel the tests need compiled
cold: the test command's own worst case); then ``first_run_s=nan
compile_s=nan``.

Usage: ``python scripts/benchmarks/bench_newcomer.py [--skip-tests |
--tests-only] [--keep] [--python PYTHON]`` (``--keep`` leaves the clone, its
caches and the commands' output, and prints where; a failure keeps them too).
It takes several minutes: a cold install, a cold compile, 8,000 trials, the
tests.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

DROPPED = ("PYTHONPATH", "VIRTUAL_ENV", "NUMBA_CACHE_DIR", "FTC_MC_NUMBA_CACHE",
           "FTC_MC_COMPILE_HELPER", "PYTHONDONTWRITEBYTECODE", "PYTHONHOME")
"""Variables of this process's environment a newcomer's shell would not have."""

COMPILING = "ftc-mc: compiling the simulation kernels"
COMPILED = re.compile(r"ftc-mc: compiled in ([0-9.]+) s")
PYTEST_SUMMARY = re.compile(r"(\d+) passed.* in ([0-9.]+)s")


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    out = subprocess.run(["lscpu"], capture_output=True, text=True)
    for line in out.stdout.splitlines():
        if line.startswith("Model name"):
            return line.split(":", 1)[1].strip()
    return "unknown"


def cores() -> str:
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None
    return f"{os.cpu_count()} cores" + (f" ({usable} usable here)"
                                       if usable and usable != os.cpu_count() else "")


def load() -> str:
    try:
        return " ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "unknown"


def newcomer_python(env: dict) -> str:
    """``python3.11`` or ``python3`` on ``PATH``, outside a virtual environment."""
    venv = os.environ.get("VIRTUAL_ENV")
    parts = [p for p in env.get("PATH", "").split(os.pathsep)
             if not (venv and Path(p).resolve().is_relative_to(Path(venv).resolve()))
             and not (Path(p) / "pyvenv.cfg").exists() and not (Path(p).parent / "pyvenv.cfg").exists()]
    for name in ("python3.11", "python3"):
        found = shutil.which(name, path=os.pathsep.join(parts))
        if found:
            return found
    sys.exit("bench_newcomer: no python3 on PATH outside a virtual environment (--python)")


CPU: dict = {}
"""The CPU seconds (user and system) of each command :func:`run` ran, in order:
on 2 cores its wall time can be no less than half of it, whatever else runs."""


def _children_cpu() -> float:
    """CPU seconds of this process's finished children and theirs."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(cmd, cwd: Path, env: dict, log: Path):
    """Run ``cmd``; return (wall seconds, [(seconds since start, line of its
    output)]).  Lines end at a newline or a carriage return (progress bars);
    the output is also written to ``log``.  Exits if the command fails."""
    t0 = time.perf_counter()
    cpu0 = _children_cpu()
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    lines = []

    def read():
        buf = b""
        while True:
            chunk = proc.stdout.read1(4096)
            if not chunk:
                break
            buf += chunk
            parts = re.split(rb"[\r\n]", buf)
            buf = parts.pop()
            now = time.perf_counter() - t0
            lines.extend((now, p.decode(errors="replace")) for p in parts if p.strip())
        if buf.strip():
            lines.append((time.perf_counter() - t0, buf.decode(errors="replace")))

    reader = threading.Thread(target=read)
    reader.start()
    code = proc.wait()
    reader.join()
    wall = time.perf_counter() - t0
    CPU[len(CPU)] = _children_cpu() - cpu0
    with open(log, "a") as f:
        f.write(f"$ {' '.join(map(str, cmd))}  (exit {code}, {wall:.1f} s)\n")
        f.writelines(f"[{t:8.2f}] {line}\n" for t, line in lines)
    if code:
        tail = "\n".join(line for _, line in lines[-20:])
        sys.exit(f"bench_newcomer: {' '.join(map(str, cmd))} failed (exit {code}):\n{tail}\n"
                 f"(full output: {log})")
    return wall, lines


def first(lines, pattern) -> tuple | None:
    for t, line in lines:
        m = re.search(pattern, line) if isinstance(pattern, str) else pattern.search(line)
        if m:
            return t, m
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--skip-tests", action="store_true",
                    help="do not run python3 dev.py test (tests_s=nan)")
    which.add_argument("--tests-only", action="store_true",
                    help="run only python3 dev.py test, on the fresh clone with every cache "
                    "empty (first_run_s=nan compile_s=nan)")
    ap.add_argument("--keep", action="store_true",
                    help="keep the clone and its caches, and print where they are")
    ap.add_argument("--python", default=None,
                    help="the interpreter a newcomer types (default: python3.11 or python3 "
                    "on PATH, outside a virtual environment)")
    args = ap.parse_args()

    env = {k: v for k, v in os.environ.items() if k not in DROPPED}
    python = args.python or newcomer_python(env)
    version = subprocess.run([python, "-c", "import sys; print(sys.version.split()[0])"],
                             capture_output=True, text=True, check=True).stdout.strip()
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True, check=True).stdout.strip()
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                           capture_output=True, text=True).stdout.strip()

    top = Path(tempfile.mkdtemp(prefix="ftc-mc-newcomer-"))
    clone, log = top / "ftc-mc", top / "output.log"
    for sub in ("cache", "pip-cache", "mpl"):
        (top / sub).mkdir()
    env.update(FTC_MC_CACHE_DIR=str(top / "cache"), PIP_CACHE_DIR=str(top / "pip-cache"),
               MPLCONFIGDIR=str(top / "mpl"))
    print(f"machine: {cpu_model()}, {cores()}; load average {load()} (1, 5, 15 min)")
    print(f"commit {commit[:12]}{' (the tree has uncommitted changes: not measured)' if dirty else ''}"
          f"; {python} (Python {version}); in {top}")
    done_ok = False
    try:
        subprocess.run(["git", "clone", "--quiet", "--no-checkout", str(ROOT), str(clone)],
                       check=True)
        subprocess.run(["git", "checkout", "--quiet", commit], cwd=clone, check=True)

        first_run_s = compile_s = float("nan")
        if not args.tests_only:
            first_run_s, compile_s = first_run(python, clone, env, log)

        tests_s = float("nan")
        if not args.skip_tests:
            tests_s, lines = run([python, "dev.py", "test"], clone, env, log)
            summary = first(lines, PYTEST_SUMMARY)
            print(f"python3 dev.py test             {tests_s:7.1f} s"
                  + (" (every cache empty)" if args.tests_only else "")
                  + f"  (CPU {CPU[len(CPU) - 1]:.1f} s)")
            if summary is not None:
                passed, pytest_s = summary[1].group(1), float(summary[1].group(2))
                print(f"  install{' of the test extras' if not args.tests_only else ''} "
                      f"and pytest's start: {tests_s - pytest_s:.1f} s")
                print(f"  pytest: {passed} passed in {pytest_s:.1f} s")
        print(f"load average after: {load()}; every command's output: "
              f"{log if args.keep else '(removed; --keep keeps it)'}")
        print(f"first_run_s={first_run_s:.1f} compile_s={compile_s:.1f} tests_s={tests_s:.1f}")
        done_ok = True
    finally:
        if args.keep or not done_ok:  # a failure keeps the log and the clone
            print(f"kept: {top}", file=sys.stderr)
        else:
            shutil.rmtree(top, ignore_errors=True)


def first_run(python: str, clone: Path, env: dict, log: Path) -> tuple[float, float]:
    """Time ``python3 dev.py run`` on the clone and print its parts; return
    its wall time and the cold compile's."""
    # python3 dev.py run, in its two parts: the install, then the same
    # command finding it done (the main job)
    install_s, _ = run([python, "-c", "import dev; dev.ensure_venv('')"], clone, env, log)
    job_s, lines = run([python, "dev.py", "run"], clone, env, log)
    first_run_s = install_s + job_s
    notice, done = first(lines, COMPILING), first(lines, COMPILED)
    if notice is None or done is None:
        sys.exit(f"bench_newcomer: the main job printed no compile notice (a cache was "
                 f"not empty?); its output: {log}")
    compile_s = float(done[1].group(1))
    start_s = notice[0]
    bars = [t for t, line in lines if line.startswith("trials:")]  # the progress bar
    cpu_install, cpu_job = CPU[len(CPU) - 2], CPU[len(CPU) - 1]
    print(f"python3 dev.py run              {first_run_s:7.1f} s  "
          f"(CPU {cpu_install + cpu_job:.1f} s)")
    print(f"  install (venv, pip, ftc-mc)   {install_s:7.1f} s  (CPU {cpu_install:.1f} s)")
    print(f"  ftc-mc run configs/paper_tables.yaml, 8,000 trials {job_s:.1f} s "
          f"(CPU {cpu_job:.1f} s):")
    print(f"    start to the compile notice {start_s:7.1f} s")
    print(f"    cold compile, default path  {compile_s:7.1f} s  (ftc-mc: compiled in ...)")
    if bars:
        print(f"    then to the first trial     {bars[0] - done[0]:7.1f} s")
        print(f"    trials (the progress bar)   {bars[-1] - bars[0]:7.1f} s")
        print(f"    table and result files      {job_s - bars[-1]:7.1f} s")
    else:
        print(f"    trials and result files     {job_s - done[0]:7.1f} s")
    other = done[0] - start_s - compile_s
    if abs(other) > 0.5:
        print(f"    (between the two notices, besides the compile: {other:.1f} s)")
    return first_run_s, compile_s


if __name__ == "__main__":
    main()
