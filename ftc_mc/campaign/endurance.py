"""Endurance runs: false resets per fault-free flight hour (``ftc-mc endurance``).

A false-alarm target such as "at most one false reset per 100 flight hours" is
shown only by hundreds of fault-free flight hours (0 events in 300 h give a
one-sided 95 % upper bound of 0.00999 per hour, :func:`ftc_mc.stats.poisson_upper`).
An endurance run flies ``ceil(hours * 3600 / flight_s)`` fault-free flights,
every design of the config (or of ``--design``) on the same flights: flight
``i`` draws its process and measurement noise and its gusts from
``default_rng([i, seed])``, exactly as flight ``i`` of a sweep
(:func:`ftc_mc.sim.inputs.flight_inputs`), so the flights are independent of
each other and common to the designs.  The chunks run through the executor of
``ftc-mc run`` (:func:`ftc_mc.campaign.chunk.run_chunk` with
:data:`~ftc_mc.campaign.chunk.ENDURANCE`), so they resume, run on threads,
worker processes or Dask, and give bit-identical results whatever the workers.

Per design (one row of :attr:`EnduranceResult.summary`): the flight hours
flown to their end, the false resets (every reset of a fault-free flight is
one), the rate per hour with its exact two-sided 95 % interval
(:func:`ftc_mc.stats.poisson_rate`), the one-sided 95 % upper bound the
false-alarm target is checked against, whether the target is shown, and the
hours that would show it with no further event (:func:`ftc_mc.stats.hours_to_show`).
The time of each false reset from its flight's start is in
:attr:`EnduranceResult.resets`.
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pandas as pd

from ..config.load import with_overrides
from ..config.schema import Config
from ..conventions import STATUS_NAMES
from ..errors import UserError
from ..stats import hours_to_show, poisson_rate, poisson_upper
from .chunk import ENDURANCE, chunk_spec
from .parallel import run_chunks
from .signals import move_signals
from .runner import sort_rows
from .summary import lateral_summary

FALSE_RESET_TARGET_PER_H = 0.01
"""Default false-alarm target: one false reset per 100 flight hours [1/h]."""
RESETS_STORED = 64
"""Resets of a flight stored with their time and residuals (all are counted)."""
EARLY_S = 5.0
"""The start of a flight whose false resets are counted apart (``early_false_resets``) [s]."""
MAX_FLIGHT_S = 600.0
"""Longest flight [s]: a chunk of 128 flights of 600 s holds about 150 MB of noise."""


def startup_s(setup, variants) -> float:
    """The filters' start-up [s]: per design, its start-up hold (``startup_s``:
    the test is not armed before it) plus its residual-test window (a GLR window
    not yet full tests fewer samples), the longest over the designs flown, and
    at least the first belief update (one reconfiguration period).  A flight
    must be longer."""
    dt = setup.plant.dt
    longest = max(setup.designs[v].det.startup + setup.designs[v].window for v in variants)
    return max(longest * dt, setup.tim.reconf_every * dt)


def endurance_config(cfg: Config, flight_s: float | None) -> Config:
    """``cfg`` with its flights ``flight_s`` long (``timing.duration_s``).

    A fault-free flight has no switch: ``fault_time_s`` and ``window_s`` only
    need to fit in it, so they are shortened to at most half the flight each.
    """
    if flight_s is None:
        return cfg
    if not (isinstance(flight_s, (int, float)) and math.isfinite(flight_s) and flight_s > 0):
        raise UserError(f"--flight-s: must be a finite number of seconds > 0, got {flight_s}")
    if flight_s > MAX_FLIGHT_S:
        raise UserError(f"--flight-s: at most {MAX_FLIGHT_S:g} s (memory of a chunk's "
                        f"noise), got {flight_s:g}")
    dt = cfg.model.dt_s
    steps = flight_s / dt
    if abs(steps - round(steps)) > 1e-9 * max(1.0, steps):
        raise UserError(f"--flight-s: must be a multiple of model.dt_s ({dt:g} s), "
                        f"got {flight_s:g}")
    t = cfg.timing
    half = max(1, int(round(steps)) // 2) * dt
    return with_overrides(cfg, timing={"duration_s": float(flight_s),
                                       "fault_time_s": min(t.fault_time_s, half),
                                       "window_s": min(t.window_s, half)})


def check_hours(hours) -> float:
    """``hours`` as a float, or a one-line :class:`UserError` (zero, negative,
    non-finite or not a number)."""
    try:
        h = float(hours)
    except (TypeError, ValueError):
        raise UserError(f"--hours: expected a number of flight hours, got {hours!r}") from None
    if not (math.isfinite(h) and h > 0):
        raise UserError(f"--hours: must be finite and > 0, got {hours!r}")
    if h > 1e6:
        raise UserError(f"--hours: at most 1e6 flight hours, got {h:g}")
    return h


def plan_flights(cfg: Config, hours: float) -> list:
    """Work units ``(ENDURANCE, flight_ids)``: enough flights of
    ``timing.duration_s`` for ``hours``, in chunks of ``campaign.chunk_size``."""
    n = int(math.ceil(hours * 3600.0 / cfg.timing.duration_s - 1e-9))
    size = cfg.campaign.chunk_size
    return [(ENDURANCE, np.arange(s, min(s + size, n))) for s in range(0, n, size)]


@dataclasses.dataclass
class EnduranceResult:
    """Outputs of :func:`run_endurance`.

    Attributes
    ----------
    summary : DataFrame
        One row per design (:func:`summarize_endurance`).
    flights : DataFrame
        One row per flight and design: ``variant, flight_id, status, stop_s,
        judged, false_resets, first_false_reset_s``.
    resets : DataFrame
        One row per stored false reset: ``variant, flight_id, time_s`` (from the
        flight's start) ``, block, r_q, r_nx, r_nz``.
    config : Config
    hours : float
        Flight hours asked for.
    """

    summary: pd.DataFrame
    flights: pd.DataFrame
    resets: pd.DataFrame
    config: Config
    hours: float

    def markdown(self) -> str:
        """The summary as a Markdown table."""
        return endurance_markdown(self.summary)


def summarize_endurance(flights: pd.DataFrame, resets: pd.DataFrame, cfg: Config,
                        variants, target: float = FALSE_RESET_TARGET_PER_H) -> pd.DataFrame:
    """One row per design: hours, false resets and their rate.

    Columns: the condition (``plant``, ``turbulence``, ``airframe``), ``variant``,
    its thresholds ``t_q``, ``t_nx``, ``flights``, ``judged`` (flown to the end),
    ``stopped_<reason>``, ``flight_s``, ``flight_hours`` (the time the judged flights
    flew: to their end or to their exit from the validity envelope [h]),
    ``false_resets``, ``flights_with_false_reset``, ``false_resets_per_hour`` with
    the exact two-sided 95 % interval ``_ci_low`` / ``_ci_high`` [1/h],
    ``false_resets_per_hour_upper95`` (one-sided 95 % bound [1/h]),
    ``hours_per_false_reset`` [h] (infinite with none), ``target_per_h``,
    ``target_shown`` (the one-sided bound at most the target), ``hours_to_show``
    [h] (:func:`ftc_mc.stats.hours_to_show` at the count seen), ``early_false_resets``
    (in the first :data:`EARLY_S` s of a flight, judged flights) and
    ``median_false_reset_s`` (median time of a false reset from the flight's start);
    on the 6-DOF plant with its side monitor, ``side_decisions`` (the monitor's
    decisions, all false) and their rate ``side_decisions_per_hour`` with its
    exact 95 % interval.
    """
    flight_s = cfg.timing.duration_s
    rows = []
    for v in variants:
        f = flights[flights["variant"] == v]
        ok = f[f["judged"].astype(bool)]
        r = resets[(resets["variant"] == v) & resets["flight_id"].isin(ok["flight_id"])]
        k = int(ok["false_resets"].sum())
        hours = float(ok["flown_s"].sum()) / 3600.0
        rate, lo, hi = poisson_rate(k, hours)
        up = poisson_upper(k, hours)
        row = {"plant": cfg.plant.kind, "turbulence": cfg.plant.turbulence,
               "airframe": str(cfg.model.airframe), "variant": v,
               "t_q": np.nan, "t_nx": np.nan,
               "flights": len(f), "judged": len(ok)}
        for reason in STATUS_NAMES[1:]:
            row[f"stopped_{reason}"] = int((f["status"] == reason).sum())
        row.update({
            "flight_s": flight_s, "flight_hours": hours, "false_resets": k,
            "flights_with_false_reset": int((ok["false_resets"] > 0).sum()),
            "false_resets_per_hour": rate, "false_resets_per_hour_ci_low": lo,
            "false_resets_per_hour_ci_high": hi, "false_resets_per_hour_upper95": up,
            "hours_per_false_reset": (np.inf if k == 0 else hours / k) if hours else np.nan,
            "target_per_h": target, "target_shown": bool(up <= target),
            "hours_to_show": hours_to_show(k, target),
            "early_false_resets": int((r["time_s"] <= EARLY_S).sum()),
            "median_false_reset_s": float(r["time_s"].median()) if len(r) else np.nan})
        row.update(lateral_summary(f))  # 6-DOF: bank and heading RMS
        if "side_decisions" in ok:  # 6-DOF: the side monitor's false decisions
            n = int(ok["side_decisions"].sum())
            rate, lo, hi = poisson_rate(n, hours)
            row.update({"side_decisions": n, "side_decisions_per_hour": rate,
                        "side_decisions_per_hour_ci_low": lo,
                        "side_decisions_per_hour_ci_high": hi})
        rows.append(row)
    return pd.DataFrame(rows)


def endurance_spec(cfg: Config):
    """The chunk spec of an endurance run of ``cfg`` (flights already set), or a
    one-line :class:`UserError` when a flight is not longer than the filters'
    start-up (:func:`startup_s`).  Builds the simulation setup (trim, designs)."""
    spec = chunk_spec(cfg)
    start = startup_s(spec.setup, spec.variants)
    if cfg.timing.duration_s <= start:
        raise UserError(f"--flight-s: a flight of {cfg.timing.duration_s:g} s is not longer "
                        f"than the filters' start-up ({start:g} s: the longest start-up hold "
                        "plus residual window, and the first belief update)")
    return dataclasses.replace(spec, max_resets=min(RESETS_STORED, spec.max_resets))


def run_endurance(cfg: Config, hours, *, flight_s: float | None = None, jobs: int = 1,
                  progress: bool = True, backend: str = "threads",
                  scheduler: str | None = None, chunks=None,
                  target: float = FALSE_RESET_TARGET_PER_H, spec=None) -> EnduranceResult:
    """Fly every design of ``cfg`` fault-free for ``hours`` flight hours.

    Parameters
    ----------
    cfg : Config
        Campaign config: the designs (``campaign.signature`` and
        ``campaign.designs``), the truth plant and turbulence, the seed and
        ``campaign.chunk_size``; ``campaign.transitions`` and ``trials`` are not used.
    hours : float
        Flight hours to fly (> 0, finite); rounded up to whole flights.
    flight_s : float, optional
        Length of each flight [s] (default ``timing.duration_s``); longer than
        the filters' start-up (:func:`startup_s`).
    jobs : int
        Workers (``backend``); -1: every core.  Results do not depend on it.
    progress : bool
        Show a tqdm bar counting finished flights.
    backend, scheduler
        Where chunks run (:mod:`ftc_mc.campaign.parallel`).
    chunks : ChunkStore, optional
        Finished chunks are stored there and skipped when resuming.
    target : float
        False-alarm target [1/h] of ``target_shown`` and ``hours_to_show``.
    spec : ChunkSpec, optional
        :func:`endurance_spec` of ``cfg`` when already built (``flight_s`` then
        already applied).

    Raises
    ------
    UserError
        Bad hours or flight length (one line, before anything runs).
    """
    hours = check_hours(hours)
    if spec is None:
        cfg = endurance_config(cfg, flight_s)
        spec = endurance_spec(cfg)
    units = plan_flights(cfg, hours)
    n_jobs = (os.cpu_count() or 1) if jobs == -1 else max(1, int(jobs))
    out = run_chunks(spec, units, n_jobs=n_jobs, backend_name=backend, scheduler=scheduler,
                     progress=progress, chunks=chunks, desc="flights")
    if chunks is not None:  # stored chunk by chunk: read back in chunk order (small tables)
        tables = ("trials", "resets")  # recorded signals stay on disk
        out = [dict(zip(tables, chunks.read(name, int(ids[0]), tables)))
               for name, ids in units]
        if spec.record:
            move_signals(chunks, units, chunks.folder.parent)
    flights = pd.concat([o["trials"] for o in out], ignore_index=True)
    resets = pd.concat([o["resets"] for o in out], ignore_index=True)
    flights = _sorted(flights, spec.variants, ["flight_id"])
    resets = _sorted(resets, spec.variants, ["flight_id", "time_s"])
    summary = summarize_endurance(flights, resets, cfg, spec.variants, target)
    summary["t_q"] = [spec.setup.det[v].t_q for v in spec.variants]
    summary["t_nx"] = [spec.setup.det[v].t_nx for v in spec.variants]
    return EnduranceResult(summary=summary, flights=flights, resets=resets, config=cfg,
                           hours=hours)


def _sorted(df: pd.DataFrame, variants, extra) -> pd.DataFrame:
    """``df`` in (variant as run, *extra) order."""
    df = df.assign(transition=ENDURANCE)
    return sort_rows(df, [ENDURANCE], variants, extra).drop(columns="transition")


def endurance_markdown(summary: pd.DataFrame) -> str:
    """Per design: hours, false resets, rate with its 95 % interval, the one-sided
    bound and whether the target is shown (else the hours that would show it)."""
    def fmt(x, f="{:.3g}"):
        return "-" if not np.isfinite(x) else f.format(x)

    view = pd.DataFrame({
        "design": summary["variant"],
        "plant / turbulence": summary["plant"] + " / " + summary["turbulence"],
        "flight hours": summary["flight_hours"].map("{:.4g}".format),
        "false resets": summary["false_resets"],
        "per h (95 % CI)": [f"{fmt(r)} ({fmt(lo)}-{fmt(hi)})" for r, lo, hi in zip(
            summary["false_resets_per_hour"], summary["false_resets_per_hour_ci_low"],
            summary["false_resets_per_hour_ci_high"])],
        "one-sided 95 % bound / h": summary["false_resets_per_hour_upper95"].map(fmt),
        "in the first 5 s": summary["early_false_resets"],
        "target": [f"<= {t:g} / h: " + ("shown" if s else
                                         f"not shown ({h:.4g} h would show it"
                                         + (")" if k == 0 else " with no further one)"))
                   for s, h, t, k in zip(summary["target_shown"], summary["hours_to_show"],
                                         summary["target_per_h"], summary["false_resets"])],
    })
    if "side_decisions" in summary:  # the 6-DOF side monitor
        view["side monitor decisions (per h, 95 % CI)"] = [
            f"{n} ({fmt(r)}, {fmt(lo)}-{fmt(hi)})" for n, r, lo, hi in zip(
                summary["side_decisions"], summary["side_decisions_per_hour"],
                summary["side_decisions_per_hour_ci_low"],
                summary["side_decisions_per_hour_ci_high"])]
    if "bank_rms_deg" in summary:  # the 6-DOF plant
        view["bank / heading RMS [deg]"] = [f"{b:.2f} / {h:.2f}" for b, h in zip(
            summary["bank_rms_deg"], summary["heading_rms_deg"])]
    return view.to_markdown(index=False)
