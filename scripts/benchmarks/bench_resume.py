"""Resuming at scale: a run of 15 000+ chunks resumes in time
proportional to the chunks still to run.

Builds the chunk store of ``elevon_lock`` (nominal controller, the paper's
signature, 6 s flights) with one trial per chunk, so ``--trials`` chunks, then
removes the marker of ``k`` chunks (as a run killed before writing them would
leave them) and times the resume of the chunks (``campaign.parallel.run_chunks``
on the store, which lists the folder once), for several ``k``; then times the
final assembly of the result files from all chunks (which reads every chunk
once per design, so it grows with the run, not with ``k``).

Usage: ``python scripts/benchmarks/bench_resume.py [--trials 15360] [--missing 0,160,1600]``.
Last line: ``chunks=<n> resume_s=<k>:<s>,... per_missing_chunk_ms=<m> assemble_s=<a>``.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=15_360)
    ap.add_argument("--missing", default="0,160,1600")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()

    from ftc_mc.campaign.assemble import write_run_tables
    from ftc_mc.campaign.chunk import chunk_spec
    from ftc_mc.campaign.parallel import run_chunks
    from ftc_mc.campaign.runner import plan_chunks
    from ftc_mc.config import parse_config
    from ftc_mc.io.chunks import ChunkStore

    cfg = parse_config({"campaign": {"transitions": ["elevon_lock"], "trials": args.trials,
                                     "chunk_size": 1, "signature": "paper"},
                        "controller": {"kind": "nominal"},
                        "timing": {"fault_time_s": 2, "window_s": 2, "duration_s": 6}})
    spec = chunk_spec(cfg)
    units = plan_chunks(cfg)
    tmp = Path(tempfile.mkdtemp(prefix="ftc-mc-resume-"))
    try:
        store = ChunkStore(tmp, "{}")
        store.open(resume=False)
        t = time.perf_counter()
        run_chunks(spec, units, n_jobs=args.jobs, progress=False, chunks=store)
        print(f"built {len(units)} chunks in {time.perf_counter() - t:.1f} s")
        rng = np.random.default_rng(0)
        times = []
        for k in (int(x) for x in args.missing.split(",")):
            for i in rng.choice(len(units), size=k, replace=False):
                name, ids = units[i]
                (store.folder / f"{name}-{int(ids[0]):09d}.trials.parquet").unlink()
            t = time.perf_counter()
            run_chunks(spec, units, n_jobs=args.jobs, progress=False, chunks=store)
            times.append((k, time.perf_counter() - t))
            print(f"resume with {k} of {len(units)} chunks missing: {times[-1][1]:.3f} s")
        (k0, t0), (k1, t1) = times[0], times[-1]
        per = (t1 - t0) / (k1 - k0) * 1e3 if k1 > k0 else float("nan")
        t = time.perf_counter()
        write_run_tables(store, units, spec.variants, tmp, {})
        assemble = time.perf_counter() - t
        print(f"assembled trials.parquet and resets.parquet from {len(units)} chunks in "
              f"{assemble:.1f} s")
        print(f"chunks={len(units)} resume_s=" + ",".join(f"{k}:{s:.3f}" for k, s in times)
              + f" per_missing_chunk_ms={per:.2f} assemble_s={assemble:.1f}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
