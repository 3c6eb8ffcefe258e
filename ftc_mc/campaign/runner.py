"""Run a Monte Carlo campaign: chunks in parallel, classified, summarised.

The Python API behind ``ftc-mc run``::

    import ftc_mc
    result = ftc_mc.run_campaign("configs/elevon_lock.yaml", trials=200, jobs=2)
    result.summary        # one row per transition and signature variant
    result.trials         # one row per trial and variant
    result.resets         # one row per reset event
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from ..config.load import load_config, parse_config, with_overrides
from ..config.schema import Config
from .assemble import write_run_tables
from .chunk import chunk_spec
from .parallel import run_chunks
from .signals import move_signals
from .summary import markdown_table, summarize
from .side import SIDE_COLUMNS, side_markdown, side_table
from .survival import (survival_markdown, survival_table, trimmable_markdown,
                       trimmable_sets, trimmable_table)


class CampaignResult:
    """Outputs of :func:`run_campaign`.

    Attributes
    ----------
    trials : DataFrame
        One row per trial and signature variant (see
        :func:`ftc_mc.campaign.chunk.classify` for the columns).  For a run
        written to a folder, read from its ``trials.parquet`` when first asked
        for (a big run's table need not fit in memory for the run to finish).
    resets : DataFrame
        One row per covariance reset (``campaign.reset_log``), the same way.
    summary : DataFrame
        One row per transition and variant (:func:`~.summary.summarize`).
    config : Config
        The resolved configuration.
    out : Path or None
        The folder the tables were written to.
    """

    def __init__(self, trials=None, resets=None, summary=None, config=None, out=None):
        self._trials, self._resets = trials, resets
        self.summary, self.config = summary, config
        self.out = None if out is None else Path(out)
        self._sets = None
        self.signals = None  # recorded signals of a run kept in memory (no out)

    @property
    def trials(self) -> pd.DataFrame:
        if self._trials is None and self.out is not None:
            return pd.read_parquet(self.out / "trials.parquet")
        return self._trials

    @property
    def resets(self) -> pd.DataFrame:
        if self._resets is None and self.out is not None:
            return pd.read_parquet(self.out / "resets.parquet")
        return self._resets

    def _trial_columns(self, cols) -> pd.DataFrame:
        """The trials, or of a run on disk only those of ``cols`` it has (a
        run of millions of trials is not read whole)."""
        if self._trials is None and self.out is not None:
            import pyarrow.parquet as pq
            names = pq.read_schema(self.out / "trials.parquet").names
            return pd.read_parquet(self.out / "trials.parquet",
                                   columns=[c for c in cols if c in names])
        return self.trials

    def survival(self) -> pd.DataFrame:
        """Survival after an elevon lock by lock offset
        (:func:`~.survival.survival_table`; empty without elevon-lock rows)."""
        trials = self._trial_columns(["transition", "variant", "lock_offset", "status",
                                      "stop_s", "height_lost_m"])
        t = self.config.timing
        return survival_table(trials, t.fault_time_s, t.duration_s)

    def trimmable_sets(self) -> dict:
        """:func:`~.survival.trimmable_sets` of the run's configuration, found
        once (``summary.parquet``'s metadata keeps them for the report)."""
        if self._sets is None:
            self._sets = trimmable_sets(self.config)
        return self._sets

    def trimmable(self) -> pd.DataFrame:
        """Survival inside and outside the trimmable set
        (:func:`~.survival.trimmable_table`; empty but on the 6-DOF plant; its
        first run per airframe on the nonlinear one searches the set, a minute or two)."""
        sets = self.trimmable_sets()
        if not sets:
            return pd.DataFrame()
        trials = self._trial_columns(["transition", "variant", "lock_offset",
                                      "lock_position", "status", "stop_s",
                                      "height_lost_m"])
        t = self.config.timing
        return trimmable_table(trials, t.fault_time_s, t.duration_s, sets)

    def side(self) -> pd.DataFrame:
        """Which actuator the 6-DOF side monitor named, per row and design
        (:func:`~.side.side_table`; empty without the monitor)."""
        trials = self._trial_columns(["transition", "variant", "stop_s", "lock_position",
                                      "loss_b1", *SIDE_COLUMNS])
        t = self.config.timing
        return side_table(trials, t.fault_time_s, t.window_s)

    def markdown(self) -> str:
        """The summary table in Markdown, then the survival after an elevon lock
        when the run has elevon-lock rows, and the side monitor's decisions
        when it flew (6-DOF plant)."""
        extra = ""
        if self.config is not None:
            extra = "".join("\n\n" + s for s in (survival_markdown(self.survival()),
                                                  trimmable_markdown(
                                                      self.trimmable(),
                                                      kind=self.config.plant.kind),
                                                  side_markdown(self.side())) if s)
        return markdown_table(self.summary) + extra


def resolve_config(config, trials=None, seed=None, signature=None) -> Config:
    """A :class:`Config` from a path, mapping or Config, with CLI-style overrides."""
    if isinstance(config, Config):
        cfg = config
    elif isinstance(config, dict):
        cfg = parse_config(config)
    else:
        cfg = load_config(config)
    over = {"trials": trials, "seed": seed, "signature": signature}
    if any(v is not None for v in over.values()):
        cfg = with_overrides(cfg, campaign=over)
    return cfg


def plan_chunks(cfg: Config):
    """Fixed work units ``(transition, trial_ids)``: independent of the job count."""
    c = cfg.campaign
    out = []
    for name in c.transitions:
        for start in range(0, c.trials, c.chunk_size):
            out.append((name, np.arange(start, min(start + c.chunk_size, c.trials))))
    return out


SMALL_RUN_STEPS = 3_000_000
"""Below this many (controller-weighted) trial steps, ``jobs=-1`` with worker
processes (``loky``, ``dask``) runs in-process: starting them (importing Numba
and loading the cached kernels, about 3 s here) would cost more than it saves.
Threads start at once, so the default backend does not wait for that."""


def auto_jobs(cfg: Config, n_variants: int, backend: str = "threads") -> int:
    """Worker count for ``jobs=-1``: every core (at most one per chunk), or 1 for
    a small run on worker processes (:data:`SMALL_RUN_STEPS`).

    A trial step of the reconfiguring loop costs about six of the nominal one
    (the controller selection predicts three controllers over the horizon); one
    on the nonlinear plant about four (``scripts/benchmarks/bench_truth.py``).
    """
    c = cfg.campaign
    weight = 6 if any(cfg.controller_of(d) == "reconfiguring" for d in c.runs()) else 1
    weight *= 4 if cfg.plant.kind == "nonlinear" else 1
    steps = c.trials * len(c.transitions) * n_variants * cfg.steps(cfg.timing.duration_s)
    if backend != "threads" and steps * weight < SMALL_RUN_STEPS:
        return 1
    return max(1, min(os.cpu_count() or 1, len(plan_chunks(cfg))))


def sort_rows(df: pd.DataFrame, transitions, variants, extra) -> pd.DataFrame:
    """Rows in (transition as configured, variant as configured, *extra) order (stable).

    Parameters
    ----------
    df : DataFrame
        With ``transition`` and ``variant`` columns and the columns ``extra``.
    transitions, variants : sequence of str
        Their order in the result.
    extra : list of str
        Further sort keys, most significant first.
    """
    order = {n: i for i, n in enumerate(transitions)}
    vorder = {v: i for i, v in enumerate(variants)}
    keys = [df[c].to_numpy() for c in reversed(extra)]
    keys += [df["variant"].map(vorder).to_numpy(), df["transition"].map(order).to_numpy()]
    return df.iloc[np.lexsort(keys)].reset_index(drop=True)


def run_campaign(config, *, trials=None, seed=None, signature=None, jobs: int = 1,
                 progress: bool = True, chunks=None, backend: str = "threads",
                 scheduler: str | None = None, out=None, meta=None) -> CampaignResult:
    """Run every transition of a configuration.

    Parameters
    ----------
    config : str, Path, dict or Config
        YAML path, parsed mapping or validated configuration.
    trials, seed : int, optional
        Override ``campaign.trials`` / ``campaign.seed``.
    signature : {"paper", "swapped", "both"}, optional
        Override ``campaign.signature``.
    jobs : int
        Workers (threads, processes or Dask workers, ``backend``); 1 runs in this
        process alone; -1 every core, or with worker processes this process
        alone for a small run (:func:`auto_jobs`).  Results are identical for
        every value.
    progress : bool
        Show a tqdm bar counting finished trials.
    backend : {"threads", "loky", "dask"}
        Where chunks run (:mod:`ftc_mc.campaign.parallel`).
    scheduler : str, optional
        Dask scheduler address (``backend="dask"``); a local cluster if None.
    chunks : ChunkStore, optional
        Where finished chunks are stored as they complete; chunks already in it
        are not run again (resume).  The result is then assembled from the
        stored chunks, so it is the same whether or not the run was resumed.
    out : Path, optional
        With ``chunks``: write ``trials.parquet`` and ``resets.parquet`` there,
        streamed from the chunk store one chunk at a time
        (:mod:`~ftc_mc.campaign.assemble`), with ``meta`` as their provenance;
        the summary comes from a chunked scan.  The result's tables are then
        read from those files on demand.
    meta : dict, optional
        Provenance of the files written to ``out``.

    Returns
    -------
    CampaignResult
    """
    out_dir = out
    cfg = resolve_config(config, trials, seed, signature)
    spec = chunk_spec(cfg)
    c = cfg.campaign
    n_jobs = (auto_jobs(cfg, len(spec.variants), backend) if jobs == -1
              else max(1, int(jobs)))
    if backend == "dask" and jobs == -1:
        n_jobs = os.cpu_count()
    units = plan_chunks(cfg)
    out = run_chunks(spec, units, n_jobs=n_jobs, backend_name=backend,
                     scheduler=scheduler, progress=progress, chunks=chunks, desc="trials")
    if chunks is not None and out_dir is not None:
        summary = write_run_tables(chunks, units, spec.variants, Path(out_dir), meta or {})
        if spec.record:
            move_signals(chunks, units, out_dir)
        return CampaignResult(summary=summary, config=cfg, out=out_dir)
    if chunks is not None:
        out = [dict(zip(spec.tables, chunks.read(n, int(ids[0]), spec.tables)))
               for n, ids in units]
    trials_df = sort_rows(pd.concat([o["trials"] for o in out], ignore_index=True),
                          c.transitions, spec.variants, ["trial_id"])
    resets_df = sort_rows(pd.concat([o["resets"] for o in out], ignore_index=True),
                          c.transitions, spec.variants, ["trial_id", "time_s"])
    result = CampaignResult(trials=trials_df, resets=resets_df,
                            summary=summarize(trials_df), config=cfg)
    if spec.record:  # in memory: the whole run's signals (small runs only)
        result.signals = pd.concat([o["signals"] for o in out], ignore_index=True)
    return result
