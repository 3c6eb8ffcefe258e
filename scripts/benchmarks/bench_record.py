"""What recording signals costs, and how fast a NumPy detector is scored on them.

Runs ``ftc-mc run configs/paper_tables.yaml --trials N --jobs J`` twice as child
processes, without and with ``--record signals`` (both designs, 50 s trials),
and reads each child's CPU time, wall time and peak resident set size from
``os.wait4``.  Then, in a third child, ``ftc-mc score`` with the CUSUM of
``examples/cusum.py`` and, in a fourth, Table 1 offline
(``ftc_mc.campaign.detector.table1_detector``: three float64 columns) on the
recording.

``record_overhead`` is the ratio of the recorded run's time to the plain run's
(wall time on an idle machine; CPU time, user + system, on a shared one: pass
``--cpu``); ``score_s_per_100k`` is the CUSUM's scoring time scaled to 100,000
recorded trials of 50 s (a trial flown by one design; the run holds
``N x 8 transitions x 2 designs`` of them; the scoring timed alone, after the
child's imports).  The memory of a recorded run is
bounded by a chunk (``campaign.chunk_size`` trials) per worker, not by the run:
compare two ``--trials`` values to see it flat.

Usage::

    python scripts/benchmarks/bench_record.py --trials 100 --jobs 1 --cpu
    python scripts/benchmarks/bench_record.py --trials 1000 --jobs 2

Last line: ``record_overhead=<ratio> score_s_per_100k=<s>``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FTC_MC = [sys.executable, "-m", "ftc_mc"]
CONFIG = ROOT / "configs" / "paper_tables.yaml"


def measured(cmd, cwd=None):
    """Run ``cmd``: wall time [s], CPU time (user + system) [s], peak RSS [MB]."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=cwd)
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    err = p.stderr.read().decode()
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"failed: {' '.join(map(str, cmd))}\n{err}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


SCORE = """
import sys, time
sys.path.insert(0, ".")
import scipy.stats  # noqa: F401 -- imports before the clock starts
import ftc_mc
from ftc_mc.campaign.detector import table1_detector
from examples.cusum import cusum
det = cusum if sys.argv[3] == "cusum" else table1_detector("paper")
t0, c0 = time.perf_counter(), time.process_time()
ftc_mc.score_detector(sys.argv[1], det, out=sys.argv[2])
print(time.perf_counter() - t0, time.process_time() - c0)
"""


def scored(run_dir, out, which):
    """Score ``which`` in a child: wall and CPU time of the scoring alone (the
    imports before the clock), and the child's peak RSS [MB]."""
    p = subprocess.Popen([sys.executable, "-c", SCORE, str(run_dir), str(out), which],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=ROOT)
    _, status, usage = os.wait4(p.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(p.stderr.read().decode())
    wall, cpu = map(float, p.stdout.read().split())
    return wall, cpu, usage.ru_maxrss / 1024.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=100, help="trials per transition")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--cpu", action="store_true",
                    help="ratio of CPU times (a shared machine), not wall times")
    ap.add_argument("--keep", help="keep the recorded run in this folder")
    a = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="bench_record_"))
    try:
        base = [*FTC_MC, "run", str(CONFIG), "--trials", str(a.trials), "--jobs", str(a.jobs),
                "--quiet"]
        # warm: the kernels compiled and loaded once before timing
        measured([*base[:5], "--trials", "2", "--jobs", "1", "--quiet", "--out",
                  str(tmp / "warm"), "--record", "signals"])
        plain = measured([*base, "--out", str(tmp / "plain")])
        rec_dir = Path(a.keep) if a.keep else tmp / "rec"
        if rec_dir.exists():
            shutil.rmtree(rec_dir)
        rec = measured([*base, "--out", str(rec_dir), "--record", "signals"])
        files = sorted((rec_dir / "signals").glob("*.parquet"))
        size = sum(f.stat().st_size for f in files)
        import pyarrow.parquet as pq
        rows = sum(pq.read_metadata(f).num_rows for f in files)
        flights = a.trials * 8 * 2
        score = scored(rec_dir, tmp / "cusum", "cusum")
        t1 = scored(rec_dir, tmp / "t1", "table1")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    k = 1 if a.cpu else 0
    what = "CPU" if a.cpu else "wall"
    print(f"trials: {a.trials} per transition x 8 transitions x 2 designs = {flights} "
          f"recorded trials of 50 s, --jobs {a.jobs}")
    print(f"plain run:    wall {plain[0]:.1f} s  CPU {plain[1]:.1f} s  peak RSS {plain[2]:.0f} MB")
    print(f"recorded run: wall {rec[0]:.1f} s  CPU {rec[1]:.1f} s  peak RSS {rec[2]:.0f} MB")
    print(f"signals: {len(files)} files, {rows} rows, {size / 1e6:.1f} MB, "
          f"{size / rows:.1f} bytes per trial step and design")
    print(f"score CUSUM:     wall {score[0]:.1f} s  CPU {score[1]:.1f} s  peak RSS "
          f"{score[2]:.0f} MB (imports excluded)")
    print(f"score Table 1:   wall {t1[0]:.1f} s  CPU {t1[1]:.1f} s  peak RSS {t1[2]:.0f} MB")
    overhead = rec[k] / plain[k]
    per_100k = score[k] * 100_000 / flights
    print(f"({what} times; scoring scaled linearly from {flights} to 100,000 trials)")
    print(f"record_overhead={overhead:.2f} score_s_per_100k={per_100k:.1f}")


if __name__ == "__main__":
    main()
