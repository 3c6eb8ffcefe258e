"""Threshold sweeps: Tables 2-3 and the false-reset rate at each threshold.

Sharing trials across thresholds.  Until its first reset, a trial does not
depend on the thresholds, so each chunk of trials is advanced once up to the
switch with resets disabled and every threshold point continues from there
(``ftc_mc/sim/lanes.py``); the chunks run through the same executor as
``ftc-mc run`` (:func:`ftc_mc.campaign.chunk.run_chunk` with threshold points).
The results are bit-identical to running each point on its own
(``tests/test_sweep.py``).  The fault-free flights that measure the false-reset
rate share whole flights in the same way: a flight whose residuals never reach
a threshold had no reset at that threshold.
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pandas as pd

from ..config.schema import Config
from ..errors import UserError
from ..stats import poisson_rate
from .assemble import sweep_rows
from .chunk import FLIGHT, chunk_spec
from .parallel import run_chunks
from .runner import plan_chunks, sort_rows
from .summary import summarize


def parse_spec(text: str, option: str) -> list:
    """Thresholds from ``start:stop:step`` (stop included) or ``a,b,c``.

    Raises
    ------
    UserError
        Empty, malformed or reversed specs, or a threshold that is not > 0.
    """
    text = (text or "").strip()
    if not text:
        raise UserError(f"{option}: empty threshold list")
    try:
        if ":" in text:
            parts = [float(p) for p in text.split(":")]
            if len(parts) != 3:
                raise ValueError
            start, stop, step = parts
            if not step > 0:
                raise UserError(f"{option}: step must be > 0, got {step:g}")
            if stop < start:
                raise UserError(f"{option}: reversed range {text!r} (stop < start)")
            n = int(math.floor((stop - start) / step + 1e-9)) + 1
            values = [start + i * step for i in range(n)]
        else:
            values = [float(p) for p in text.split(",")]
    except UserError:
        raise
    except ValueError:
        raise UserError(f"{option}: expected start:stop:step or a comma list of "
                        f"numbers, got {text!r}") from None
    bad = [v for v in values if not (math.isfinite(v) and v > 0)]
    if bad:
        raise UserError(f"{option}: thresholds must be finite and > 0, got {bad[0]:g}")
    if len(values) > 10_000:
        raise UserError(f"{option}: {len(values)} thresholds is more than 10 000")
    return sorted(set(values))


def threshold_points(thresholds=None, tq=None, tnx=None) -> list:
    """``(t_q, t_nx)`` pairs: ``thresholds`` sets both; ``tq`` x ``tnx`` is a grid."""
    if thresholds is not None:
        if tq is not None or tnx is not None:
            raise UserError("--thresholds: give either --thresholds or --tq and --tnx")
        return [(t, t) for t in parse_spec(thresholds, "--thresholds")]
    if tq is None or tnx is None:
        raise UserError("--thresholds: give --thresholds, or both --tq and --tnx")
    return [(a, b) for a in parse_spec(tq, "--tq") for b in parse_spec(tnx, "--tnx")]


@dataclasses.dataclass
class SweepResult:
    """Outputs of :func:`run_sweep`.

    Attributes
    ----------
    table : DataFrame
        One row per threshold point, transition and design (``variant``): the summary columns
        of :func:`~ftc_mc.campaign.summary.summarize` (among them the
        operating characteristic's correct-block rate ``correct_only_rate``
        with its Wilson interval and the correct-block delay
        ``correct_delay_median_s`` / ``_p95_s`` [s]) plus the false-reset rate
        per flight hour with its exact Poisson 95 % interval and the flight
        hours between false resets (:func:`add_hours_per_false_reset`).
    trials : DataFrame or None
        Every trial at every point; None for a sweep run with a chunk store
        (written to a folder), whose table is assembled one point at a time.
    simulated_steps, alone_steps : int
        Trial steps simulated, and what the points would cost run one by one.
    config : Config
    points : list
    """

    table: pd.DataFrame
    trials: pd.DataFrame
    simulated_steps: int
    alone_steps: int
    config: Config
    points: list

    @property
    def saving(self) -> float:
        """Fraction of trial steps saved by sharing trials across thresholds."""
        return 1.0 - self.simulated_steps / self.alone_steps


def _reciprocal(rate) -> np.ndarray:
    """``1 / rate`` with ``1 / 0 = inf`` and NaN kept."""
    r = np.asarray(rate, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(r == 0, np.inf, 1.0 / r)


def add_hours_per_false_reset(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` with the flight hours between false resets, from its rates.

    ``hours_per_false_reset`` = 1 / ``false_resets_per_hour`` [h]: infinite
    when no false reset was seen (the hours flown, ``flight_hours``, are then
    the lower bound a report shows); ``hours_per_false_reset_ci_low`` /
    ``_ci_high``: the reciprocals of the rate's exact 95 % bounds [h] (the
    upper one infinite when the rate's lower bound is 0).  NaN where no
    fault-free flight was judged.

    Parameters
    ----------
    table : DataFrame
        With ``false_resets_per_hour`` and its ``_ci_low`` / ``_ci_high`` [1/h].

    Returns
    -------
    DataFrame
        A copy with the three columns added.
    """
    out = table.copy()
    out["hours_per_false_reset"] = _reciprocal(out["false_resets_per_hour"])
    out["hours_per_false_reset_ci_low"] = _reciprocal(out["false_resets_per_hour_ci_high"])
    out["hours_per_false_reset_ci_high"] = _reciprocal(out["false_resets_per_hour_ci_low"])
    return out


def run_sweep(cfg: Config, points, *, flights: int | None = None, jobs: int = 1,
              progress: bool = True, backend: str = "threads",
              scheduler: str | None = None, chunks=None) -> SweepResult:
    """Run a threshold sweep.

    Parameters
    ----------
    cfg : Config
        Campaign configuration (transitions, trials, seed, signature...).
    points : list of (float, float)
        ``(t_q, t_nx)`` threshold points (:func:`threshold_points`).
    flights : int, optional
        Fault-free flights per point for the false-reset rate (default: the
        number of trials per transition); each lasts ``timing.duration_s``.
    jobs : int
        Workers (``backend``); results do not depend on it.
    progress : bool
        Show a tqdm bar.
    backend, scheduler
        Where chunks run (:mod:`ftc_mc.campaign.parallel`).
    chunks : ChunkStore, optional
        Finished chunks are stored there and skipped when resuming; the table is
        then assembled from the stored chunks one (transition, point) at a time
        (:func:`~ftc_mc.campaign.assemble.sweep_rows`), the same as in memory.
    """
    spec = chunk_spec(cfg, points=points)
    c = cfg.campaign
    flights = c.trials if flights is None else int(flights)
    units = plan_chunks(cfg)
    units += [(FLIGHT, np.arange(s, min(s + c.chunk_size, flights)))
              for s in range(0, flights, c.chunk_size)]
    n_jobs = (os.cpu_count() or 1) if jobs == -1 else max(1, int(jobs))
    out = run_chunks(spec, units, n_jobs=n_jobs, backend_name=backend, scheduler=scheduler,
                     progress=progress, chunks=chunks, desc="sweep")
    if chunks is not None:
        tables, flights_df, (sim, alone) = sweep_rows(chunks, units, spec.variants, points,
                                                      FLIGHT)
        trials = None
    else:
        parts = [o["trials"] for (n, _), o in zip(units, out) if n != FLIGHT]
        frows = [o["trials"] for (n, _), o in zip(units, out) if n == FLIGHT]
        sim = int(sum(int(o["steps"]["simulated"].iloc[0]) for o in out))
        alone = int(sum(int(o["steps"]["alone"].iloc[0]) for o in out))
        trials = sort_rows(pd.concat(parts, ignore_index=True), c.transitions, spec.variants,
                           ["trial_id"])
        trials = trials.sort_values(["t_q", "t_nx"], kind="stable").reset_index(drop=True)
        flights_df = pd.concat(frows, ignore_index=True)
        tables = [(tq, tnx, summarize(g.drop(columns=["t_q", "t_nx"])))
                  for (tq, tnx), g in trials.groupby(["t_q", "t_nx"], sort=True)]
    hours = cfg.timing.duration_s / 3600.0
    fsum = flights_df.groupby(["t_q", "t_nx", "variant"], as_index=False)[
        ["flights", "judged", "resets"]].sum()
    for tq, tnx, s in tables:
        s.insert(0, "t_nx", tnx)
        s.insert(0, "t_q", tq)
    table = pd.concat([s for _, _, s in tables], ignore_index=True)
    rates = []
    for _, r in fsum.iterrows():
        exposure = r["judged"] * hours
        rate, lo, hi = poisson_rate(int(r["resets"]), exposure)
        rates.append({"t_q": r["t_q"], "t_nx": r["t_nx"], "variant": r["variant"],
                      "flight_hours": exposure, "flight_false_resets": int(r["resets"]),
                      "false_resets_per_hour": rate,
                      "false_resets_per_hour_ci_low": lo,
                      "false_resets_per_hour_ci_high": hi})
    table = table.merge(pd.DataFrame(rates), on=["t_q", "t_nx", "variant"], how="left")
    table = add_hours_per_false_reset(table)
    return SweepResult(table=table, trials=trials, simulated_steps=sim, alone_steps=alone,
                       config=cfg, points=list(points))


def sweep_markdown(res: SweepResult) -> str:
    """The sweep as one Markdown table per design, with the sharing saving."""
    t = res.table
    lines = ["# ftc-mc sweep", "",
             f"{len(res.points)} threshold points; trial steps simulated "
             f"{res.simulated_steps:,} against {res.alone_steps:,} for the points run "
             f"one by one (saving {100 * res.saving:.1f} %).", ""]
    for variant, g in t.groupby("variant", sort=False):
        view = pd.DataFrame({
            "t_q": g["t_q"], "t_nx": g["t_nx"], "transition": g["transition"],
            "judged": g["trials"],
            "inappropriate %": 100 * g["inappropriate_rate"],
            "no reset %": 100 * g["no_reset_rate"],
            "delay median [s]": g["delay_median_s"],
            "false resets / h": g["false_resets_per_hour"]})
        lines += [f"## Design `{variant}`", "",
                  view.to_markdown(index=False, floatfmt=".3g"), ""]
    return "\n".join(lines)
