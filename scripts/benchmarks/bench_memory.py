"""Peak memory and wall time of a big run, and of the report on it.

Runs ``ftc-mc run CONFIG --controller nominal --trials N`` (both signature
variants, the default threads backend and ``--jobs``) as a child process and
reads that child's own peak resident set size from ``os.wait4`` (Linux reports
``ru_maxrss`` in KiB).  With ``--report`` it then runs ``ftc-mc report`` on the
result in a second child and prints its figures the same way.  With
``--signal SIGINT|SIGTERM --after S`` it instead sends that signal S seconds
after the start and prints the time from the signal to the exit, the exit code
and the last line of stderr.

Usage::

    python scripts/benchmarks/bench_memory.py --trials 20000
    python scripts/benchmarks/bench_memory.py --trials 160000 --report --out results/bench160k
    python scripts/benchmarks/bench_memory.py --trials 2000000 --signal SIGINT --after 12

Before it, the run's CPU time (user + system: on a shared machine the wall time
depends on the load, the CPU time much less).  Last line:
``peak_rss_mb=<m> trials=<n> wall_s=<s>`` (of the run).
"""

from __future__ import annotations

import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FTC_MC = [sys.executable, "-m", "ftc_mc"]


def measured(cmd, sig=None, after=None):
    """Run ``cmd``; its wall time [s], peak RSS [MB], exit code, stderr, (with
    ``sig``) the seconds from the signal to the exit, and its CPU time (user +
    system) [s]."""
    err = tempfile.TemporaryFile()
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
    stop_s = None
    if sig is not None:
        time.sleep(after)
        t_sig = time.perf_counter()
        p.send_signal(sig)
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if sig is not None:
        stop_s = time.perf_counter() - t_sig
    err.seek(0)
    return (wall, usage.ru_maxrss / 1024.0, p.returncode, err.read().decode(), stop_s,
            usage.ru_utime + usage.ru_stime)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20_000)
    ap.add_argument("--config", default=str(ROOT / "configs" / "elevon_lock.yaml"))
    ap.add_argument("--controller", default="nominal", choices=["nominal", "reconfiguring"])
    ap.add_argument("--jobs", type=int, default=-1)
    ap.add_argument("--out", help="Result folder (kept) [default: a temporary one].")
    ap.add_argument("--report", action="store_true", help="Also measure ftc-mc report.")
    ap.add_argument("--signal", choices=["SIGINT", "SIGTERM"])
    ap.add_argument("--after", type=float, default=12.0,
                    help="Seconds from the start to the signal.")
    args = ap.parse_args()

    tmp = None if args.out else tempfile.mkdtemp(prefix="ftc-mc-bench-")
    out = Path(args.out or tmp) / "run"
    try:
        cmd = [*FTC_MC, "run", args.config, "--controller", args.controller,
               "--trials", str(args.trials), "--jobs", str(args.jobs), "--quiet",
               "--overwrite", "--out", str(out)]
        sig = getattr(signal, args.signal) if args.signal else None
        wall, rss, code, err, stop_s, cpu = measured(cmd, sig, args.after)
        if sig is not None:
            last = (err.strip().splitlines() or [""])[-1]
            print(f"signal={args.signal} after_s={args.after:g} exit_code={code} "
                  f"exit_after_signal_s={stop_s:.2f}")
            print(f"stderr: {last}")
        elif code != 0:
            sys.exit(f"ftc-mc run failed ({code}):\n{err}")
        else:
            sizes = {f: (out / f).stat().st_size / 1e6
                     for f in ("trials.parquet", "resets.parquet")}
            print("files: " + ", ".join(f"{f} {mb:.1f} MB" for f, mb in sizes.items()))
        if args.report and sig is None:
            rwall, rrss, rcode, rerr, _, rcpu = measured(
                [*FTC_MC, "report", str(out), "-o", str(out.parent / "report.md")])
            if rcode != 0:
                sys.exit(f"ftc-mc report failed ({rcode}):\n{rerr}")
            print(f"report_peak_rss_mb={rrss:.0f} report_wall_s={rwall:.1f} "
                  f"report_cpu_s={rcpu:.1f}")
        print(f"cpu_s={cpu:.1f} (user + system of the run; the wall time on a shared "
              f"machine depends on its load, this does not)")
        print(f"peak_rss_mb={rss:.0f} trials={args.trials} wall_s={wall:.1f}")
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
