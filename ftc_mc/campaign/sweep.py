"""Threshold sweeps: Tables 2-3 and the false-reset rate at each threshold.

Sharing trials across thresholds.  Until its first reset, a trial does not
depend on the thresholds: the residuals are the same, and the initial
covariance uses the paper's thresholds whatever is swept (see
:func:`ftc_mc.campaign.setup.build_setup`).  So each chunk of trials is first
advanced once up to the switch with resets disabled, recording the largest
``r_q`` and ``r_nx`` of every trial.  Then, for each threshold point:

* a trial whose residuals stayed below the point's thresholds continues from
  that shared state;
* any other trial runs again from the start.

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
from joblib import Parallel, delayed
from tqdm.auto import tqdm

from ..core.settings import TrialInputs
from ..core.trial import advance, init_state, new_state, run_trials
from ..errors import UserError
from ..estimator import detection
from ..io.config import Config
from ..stats import poisson_rate
from .chunk import build_inputs, classify, draw_lanes, new_record
from .parallel import backend as parallel_backend
from .runner import _sorted, plan_chunks
from .setup import CampaignSetup, build_setup, estimator_settings, variants_of
from .summary import summarize

FLIGHT = "fault_free"


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


def _take(nt, idx, shared=("k_switch", "P0")):
    """A namedtuple of lane-last arrays restricted to the lanes ``idx``."""
    return type(nt)(**{f: (v if f in shared else v[..., idx]) for f, v in nt._asdict().items()})


def _copy(nt):
    return type(nt)(**{f: v.copy() for f, v in nt._asdict().items()})


def _point_det(setup: CampaignSetup, cfg: Config, variant: str, tq: float, tnx: float):
    """Table 1 settings of one threshold point (infinite thresholds: no reset)."""
    if math.isinf(tq) and math.isinf(tnx):
        d = detection(setup.plant, estimator_settings(cfg, variant))
        return d._replace(t_q=math.inf, t_nx=math.inf)
    s = dataclasses.replace(estimator_settings(cfg, variant), t_q=tq, t_nx=tnx)
    return detection(setup.plant, s)


def _run(setup, det, inp, rec, st, k0, k1):
    advance(setup.scheme("paper", det), setup.flight, inp, rec, st, k0, k1)


def _rerun(setup, det, inp, rec, lanes, max_resets):
    """Run the lanes ``lanes`` from the start and write them into ``rec``."""
    if len(lanes) == 0:
        return 0
    sub_inp = _take(inp, lanes)
    sub = new_record(setup, len(lanes), max_resets)
    run_trials(setup.scheme("paper", det), setup.flight, sub_inp, sub)
    for f, v in sub._asdict().items():
        getattr(rec, f)[..., lanes] = v
    return len(lanes) * setup.tim.n_steps


def _shared_start(setup, cfg, inp, k_end: int, max_resets: int):
    """Record and state of every lane advanced to ``k_end`` with resets disabled:
    the part of a trial that every threshold point shares (module docstring)."""
    L = inp.w.shape[2]
    rec0 = new_record(setup, L, max_resets)
    st0 = new_state(L)
    init_state(inp, st0, rec0)
    _run(setup, _point_det(setup, cfg, "paper", math.inf, math.inf), inp, rec0, st0, 0,
         k_end)
    return rec0, st0


def sweep_chunk(setup: CampaignSetup, cfg: Config, tr_name: str, trial_ids, points,
                variants, max_resets: int, window: int):
    """Every threshold point and variant of one chunk; returns trials and a step count.

    Returns
    -------
    trials : dict of str to ndarray
        :func:`~ftc_mc.campaign.chunk.classify` columns plus ``t_q``, ``t_nx``.
    steps : (int, int)
        Trial steps simulated, and trial steps the points would cost run alone.
    """
    inp, draws = build_inputs(setup, tr_name, trial_ids, cfg.campaign.seed)
    L = len(trial_ids)
    n, kf = setup.tim.n_steps, setup.tim.k_fault
    rec0, st0 = _shared_start(setup, cfg, inp, kf, max_resets)
    simulated = L * kf
    parts = []
    for tq, tnx in points:
        dirty = np.flatnonzero((st0.rmax[0] >= tq) | (st0.rmax[1] >= tnx))
        for variant in variants:
            det = _point_det(setup, cfg, variant, tq, tnx)
            rec, st = _copy(rec0), _copy(st0)
            _run(setup, det, inp, rec, st, kf, n)
            simulated += L * (n - kf) + _rerun(setup, det, inp, rec, dirty, max_resets)
            t, _ = classify(setup, tr_name, variant, trial_ids, draws, inp, rec, window)
            t["t_q"] = np.full(L, tq)
            t["t_nx"] = np.full(L, tnx)
            parts.append(t)
    alone = L * n * len(points) * len(variants)
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}, (simulated, alone)


def flight_inputs(setup: CampaignSetup, ids, seed: int) -> TrialInputs:
    """Fault-free flights: nominal throughout, trial streams as in a campaign."""
    L = len(ids)
    tr = type("T", (), {"kind": "loss"})()
    _, w, v, eta, g0 = draw_lanes(setup, tr, ids, seed)
    zeros = np.zeros((1, 3, L))
    modes = np.zeros(L, dtype=np.int64)
    return TrialInputs(k_switch=np.zeros(1, dtype=np.int64), b0=zeros, b1=zeros.copy(),
                       mode_pre=modes, mode_post=modes.copy(), xa0=np.zeros((14, L)),
                       P0=setup.P0, w=w, v=v, eta=eta, g0=g0)


def flight_chunk(setup: CampaignSetup, cfg: Config, ids, points, variants,
                 max_resets: int):
    """Resets of fault-free flights at every threshold point (shared flights).

    Returns
    -------
    rows : list of dict
        ``t_q``, ``t_nx``, ``variant``, ``flights``, ``judged``, ``resets``.
    steps : (int, int)
    """
    inp = flight_inputs(setup, ids, cfg.campaign.seed)
    L, n = len(ids), setup.tim.n_steps
    rec0, st0 = _shared_start(setup, cfg, inp, n, max_resets)
    simulated = L * n
    rows = []
    for tq, tnx in points:
        dirty = np.flatnonzero((st0.rmax[0] >= tq) | (st0.rmax[1] >= tnx))
        for variant in variants:
            det = _point_det(setup, cfg, variant, tq, tnx)
            rec = _copy(rec0)
            simulated += _rerun(setup, det, inp, rec, dirty, max_resets)
            ok = rec.status == 0
            rows.append({"t_q": tq, "t_nx": tnx, "variant": variant, "flights": L,
                         "judged": int(ok.sum()), "resets": int(rec.n_resets[ok].sum())})
    return rows, (simulated, L * n * len(points) * len(variants))


@dataclasses.dataclass
class SweepResult:
    """Outputs of :func:`run_sweep`.

    Attributes
    ----------
    table : DataFrame
        One row per threshold point, transition and variant: the summary columns
        of :func:`~ftc_mc.campaign.summary.summarize` plus the false-reset rate
        per flight hour with its exact Poisson 95 % interval.
    trials : DataFrame
        Every trial at every point.
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


def run_sweep(cfg: Config, points, *, flights: int | None = None, jobs: int = 1,
              progress: bool = True, backend: str = "loky",
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
        Worker processes; results do not depend on it.
    progress : bool
        Show a tqdm bar.
    backend, scheduler
        Where chunks run (:mod:`ftc_mc.campaign.parallel`).
    chunks : ChunkStore, optional
        Finished chunks are stored there and skipped when resuming; the result
        is assembled from the stored chunks either way.
    """
    setup = build_setup(cfg)
    c = cfg.campaign
    variants = variants_of(c.signature)
    window = cfg.steps(cfg.timing.window_s)
    flights = c.trials if flights is None else int(flights)
    units = [(name, ids) for name, ids in plan_chunks(cfg)]
    units += [(FLIGHT, np.arange(s, min(s + c.chunk_size, flights)))
              for s in range(0, flights, c.chunk_size)]
    todo = [(n, ids) for n, ids in units if chunks is None or not chunks.done(n, int(ids[0]))]
    if todo:
        from .runner import warm_up
        warm_up(setup, cfg)
    n_jobs = (os.cpu_count() or 1) if jobs == -1 else max(1, int(jobs))

    stored = cfg.resets_stored()

    def task(name, ids):
        if name == FLIGHT:
            return delayed(flight_chunk)(setup, cfg, ids, points, variants, stored)
        return delayed(sweep_chunk)(setup, cfg, name, ids, points, variants, stored, window)

    done = {}
    with tqdm(total=sum(len(ids) for _, ids in units), unit="trial", disable=not progress,
              desc="sweep", dynamic_ncols=True) as bar:
        bar.update(sum(len(ids) for _, ids in units) - sum(len(ids) for _, ids in todo))
        with parallel_backend(backend, scheduler, n_jobs):
            results = Parallel(n_jobs=n_jobs, return_as="generator")(
                task(n, ids) for n, ids in todo)
            for (name, ids), (out, (s, a)) in zip(todo, results):
                frame = pd.DataFrame(out)
                steps = pd.DataFrame({"simulated": [s], "alone": [a]})
                if chunks is not None:
                    chunks.write(name, int(ids[0]), frame, steps=steps)
                else:
                    done[name, int(ids[0])] = (frame, steps)
                bar.update(len(ids))
    if chunks is not None:
        done = {(n, int(ids[0])): chunks.read(n, int(ids[0]), ("trials", "steps"))
                for n, ids in units}
    parts = [done[n, int(ids[0])][0] for n, ids in units if n != FLIGHT]
    frows = [done[n, int(ids[0])][0] for n, ids in units if n == FLIGHT]
    sim = int(sum(int(v[1]["simulated"].iloc[0]) for v in done.values()))
    alone = int(sum(int(v[1]["alone"].iloc[0]) for v in done.values()))
    trials = pd.concat(parts, ignore_index=True)
    order = {n: i for i, n in enumerate(c.transitions)}
    vorder = {v: i for i, v in enumerate(variants)}
    trials = _sorted(trials, order, vorder, ["trial_id"])
    trials = trials.sort_values(["t_q", "t_nx"], kind="stable").reset_index(drop=True)
    flights_df = pd.concat(frows, ignore_index=True)
    hours = cfg.timing.duration_s / 3600.0
    fsum = flights_df.groupby(["t_q", "t_nx", "variant"], as_index=False)[
        ["flights", "judged", "resets"]].sum()
    tables = []
    for (tq, tnx), g in trials.groupby(["t_q", "t_nx"], sort=True):
        s = summarize(g.drop(columns=["t_q", "t_nx"]))
        s.insert(0, "t_nx", tnx)
        s.insert(0, "t_q", tq)
        tables.append(s)
    table = pd.concat(tables, ignore_index=True)
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
    return SweepResult(table=table, trials=trials, simulated_steps=sim, alone_steps=alone,
                       config=cfg, points=list(points))


def sweep_markdown(res: SweepResult) -> str:
    """The sweep as one Markdown table per variant, with the sharing saving."""
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
        lines += [f"## Signature `{variant}`", "",
                  view.to_markdown(index=False, floatfmt=".3g"), ""]
    return "\n".join(lines)
