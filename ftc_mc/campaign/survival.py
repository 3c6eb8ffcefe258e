"""Survivability after an elevon lock: does the aircraft stay
inside the validity envelope, and for how long, by how far the elevon locked
from trim?

From the trials of a run's elevon-lock rows (``elevon_lock``,
``right_elevon_lock``), per row, design and bin of lock offset from the trim
command (``lock_offset``, [deg]):

* ``flying``: trials still flying at the switch whose fate over the horizon is
  known: a trial that stopped numerically (``nonfinite``, ``not_psd``) within
  the horizon is left out and counted in ``unknown``; one that left the
  envelope before the switch is no lock trial and is left out;
* ``left``: those that left the envelope (airspeed, angle of attack, bank)
  within ``horizon_s`` of the lock; ``survived_rate`` the others' share, with
  its 95 % Wilson interval;
* ``median_leave_s``: the median time from the lock to the exit over all
  ``flying`` trials, a survivor counting as never leaving; NaN (shown ``>H``)
  when at least half survive the horizon;
* ``height_lost_median_m``: the median height lost from the lock to the exit of
  those that left (``height_lost_m``: the glide path's own descent, 1.05 m/s at
  20 m/s and -3 deg, included).

The horizon is 60 s after the lock, or the time a trial flies after it
(``timing.duration_s - timing.fault_time_s``) when that is shorter.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..conventions import (STATUS_AIRSPEED, STATUS_ALPHA, STATUS_BANK, STATUS_NAMES,
                           STATUS_NONFINITE, STATUS_NOT_PSD)
from ..stats import wilson
from .transitions import LEFT, transition_of

HORIZON_S = 60.0
"""Time after the lock over which survival is judged [s]."""

OFFSET_EDGES_DEG = (-math.inf, -20.0, -10.0, -5.0, -2.0, -0.5, 0.5, 2.0, 5.0, 10.0, math.inf)
"""Bins of lock offset from trim [deg]: the finer the nearer trim, where the
trimmable set's edges lie (``docs/findings/sixdof-survival.md``)."""

EXITS = tuple(STATUS_NAMES[s] for s in (STATUS_AIRSPEED, STATUS_ALPHA, STATUS_BANK))
"""Statuses of a trial that left the validity envelope."""

NUMERIC = tuple(STATUS_NAMES[s] for s in (STATUS_NONFINITE, STATUS_NOT_PSD))
"""Statuses of a trial that stopped numerically (the aircraft's fate unknown)."""


def horizon_of(fault_time_s: float, duration_s: float) -> float:
    """The survival horizon [s] of a run: :data:`HORIZON_S`, or the time its
    trials fly after the switch when shorter."""
    return min(HORIZON_S, duration_s - fault_time_s)


def _is_elevon_lock(name: str) -> bool:
    """Whether ``name`` locks an elevon from nominal (not an unlock, not a sensor)."""
    tr = transition_of(name)
    return (getattr(tr, "kind", None) == "lock" and getattr(tr, "onset", False)
            and tr.is_elevon)


def bin_label(lo: float, hi: float) -> str:
    """Text of the offset bin ``[lo, hi)`` [deg]."""
    if math.isinf(lo):
        return f"below {hi:g}"
    if math.isinf(hi):
        return f"{lo:g} and above"
    return f"{lo:g} to {hi:g}"


def survival_table(trials: pd.DataFrame, fault_time_s: float, duration_s: float,
                   edges=OFFSET_EDGES_DEG) -> pd.DataFrame:
    """Survival by lock offset bin (module docstring).

    Parameters
    ----------
    trials : DataFrame
        A run's trials (``transition``, ``variant``, ``lock_offset`` [rad],
        ``status``, ``stop_s``, ``height_lost_m``).
    fault_time_s, duration_s : float
        The run's ``timing`` [s].
    edges : sequence of float
        Bin edges of the lock offset [deg], increasing.

    Returns
    -------
    DataFrame
        One row per elevon-lock row, design and non-empty bin: ``transition``,
        ``variant``, ``offset_lo_deg``, ``offset_hi_deg``, ``bin``, ``flying``,
        ``left``, ``survived_rate``, ``survived_ci_low``, ``survived_ci_high``,
        ``median_leave_s``, ``height_lost_median_m``, ``unknown``,
        ``horizon_s``; empty when the run has no elevon-lock row or its trials
        lack the columns (a run written before them); trials without a
        ``lock_offset`` (older chunks of a resumed run) are left out.
    """
    need = {"lock_offset", "height_lost_m", "status", "stop_s"}
    rows = []
    if not need <= set(trials.columns):
        return pd.DataFrame(rows)
    horizon = horizon_of(fault_time_s, duration_s)
    edges = np.asarray(edges, dtype=float)
    for name, variant, g, fate in _lock_groups(trials, fault_time_s, horizon):
        off = np.degrees(g["lock_offset"].to_numpy(dtype=float))
        which = np.digitize(off, edges[1:-1])
        for b in range(len(edges) - 1):
            row = _stats(fate, which == b, g)
            if row is not None:
                rows.append({"transition": name, "variant": variant,
                             "offset_lo_deg": edges[b], "offset_hi_deg": edges[b + 1],
                             "bin": bin_label(edges[b], edges[b + 1]), **row,
                             "horizon_s": horizon})
    return pd.DataFrame(rows)


def _lock_groups(trials: pd.DataFrame, fault_time_s: float, horizon: float):
    """Per elevon-lock row and design: ``(name, variant, trials, fate)``, the
    trials with a lock offset and their fate over ``horizon`` (:func:`lock_fate`)."""
    # a trial without an offset (an older chunk of a resumed run) is in no bin
    locks = trials[trials["transition"].map(_is_elevon_lock)
                   & np.isfinite(trials["lock_offset"].to_numpy(dtype=float))]
    for (name, variant), g in locks.groupby(["transition", "variant"], sort=False):
        yield name, variant, g, lock_fate(g, fault_time_s, horizon)


def lock_fate(g: pd.DataFrame, fault_time_s: float, horizon: float) -> dict:
    """What became of each trial of ``g`` over ``horizon`` after the lock:
    ``after`` (its stop from the lock [s]), ``left`` (left the envelope
    within the horizon), ``numeric`` (stopped numerically within it) and
    ``keep`` (counted: neither that nor stopped before the lock)."""
    status = g["status"].to_numpy()
    after = g["stop_s"].to_numpy(dtype=float) - fault_time_s
    stopped = np.isfinite(after)
    before_switch = stopped & (after <= 0.0)
    within = stopped & (after <= horizon) & ~before_switch
    numeric = within & np.isin(status, NUMERIC)
    return {"after": after, "left": within & np.isin(status, EXITS), "numeric": numeric,
            "keep": ~before_switch & ~numeric}


def _stats(fate: dict, sel: np.ndarray, g: pd.DataFrame):
    """The survival figures of the trials ``sel`` selects (module docstring),
    or None when it selects none."""
    n = int((sel & fate["keep"]).sum())
    unknown = int((sel & fate["numeric"]).sum())
    if not n and not unknown:
        return None
    left = fate["left"]
    k_left = int((sel & left).sum())
    lo, hi = wilson(n - k_left, n) if n else (math.nan, math.nan)
    leave = np.where(left, fate["after"], math.inf)[sel & fate["keep"]]
    lost = g["height_lost_m"].to_numpy(dtype=float)[sel & left]
    return {"flying": n, "left": k_left,
            "survived_rate": (n - k_left) / n if n else math.nan,
            "survived_ci_low": lo, "survived_ci_high": hi,
            "median_leave_s": float(np.median(leave)) if n and k_left * 2 > n else math.nan,
            "height_lost_median_m": float(np.median(lost)) if len(lost) else math.nan,
            "unknown": unknown}


def trimmable_table(trials: pd.DataFrame, fault_time_s: float, duration_s: float,
                    sets: dict) -> pd.DataFrame:
    """Survival inside and outside the trimmable set of each elevon-lock row
    (what a lock-turn design aims at: 90 % of the locks inside stay in; outside,
    the median time to leave).

    Parameters
    ----------
    trials : DataFrame
        As :func:`survival_table`'s, with ``lock_position`` [rad].
    fault_time_s, duration_s : float
        The run's ``timing`` [s].
    sets : dict
        Transition name -> ``(lo, hi)``: the locks [rad, absolute] of its
        elevon with a steady flight (:func:`trimmable_sets`); rows not in it
        are left out.

    Returns
    -------
    DataFrame
        Per row, design and ``where`` (``inside``, ``outside``): the columns of
        :func:`survival_table` but the bin's, with ``set_lo_deg`` and
        ``set_hi_deg``, the set's ends as offsets from the trim command of the
        trials' ``lock_offset`` [deg].
    """
    rows = []
    if not {"lock_offset", "lock_position", "height_lost_m", "status",
            "stop_s"} <= set(trials.columns):
        return pd.DataFrame(rows)
    horizon = horizon_of(fault_time_s, duration_s)
    for name, variant, g, fate in _lock_groups(trials, fault_time_s, horizon):
        if name not in sets:
            continue
        lo, hi = sets[name]
        off = g["lock_offset"].to_numpy(dtype=float)
        trim = float(np.nanmedian(g["lock_position"].to_numpy(dtype=float) - off))
        inside = (off >= lo - trim) & (off <= hi - trim)
        for where, sel in (("inside", inside), ("outside", ~inside)):
            row = _stats(fate, sel, g)
            if row is not None:
                rows.append({"transition": name, "variant": variant, "where": where,
                             "set_lo_deg": math.degrees(lo - trim),
                             "set_hi_deg": math.degrees(hi - trim), **row,
                             "horizon_s": horizon})
    return pd.DataFrame(rows)


def trimmable_sets(config, stream=None) -> dict:
    """The trimmable set of each elevon-lock row of a run on the 6-DOF plant:
    transition name -> ``(lo, hi)``, the locks [rad, absolute] of its elevon
    with a steady flight inside the run's validity envelope, of the model the
    truth flies (:data:`SET_MODELS`); ``{}`` on the longitudinal plants.

    * linear plant: the linear model's set, exact
      (:func:`ftc_mc.model.trimmable.linear_trimmable_set`);
    * nonlinear plant: the airframe's equations' set, by bisection of
      steady-flight searches from the trim (a minute or two on the first run per
      airframe and envelope, then cached:
      :func:`ftc_mc.cache.trimmable.cached_trimmable_sets`; ``stream``
      gets its notice).
    """
    if config.plant.dof != 6:
        return {}
    from ..model.presets import resolve_airframe
    from ..model.trimmable import Envelope

    m, v = config.model, config.validity
    af = resolve_airframe(m.airframe)
    env = Envelope(airspeed=(v.airspeed_min_mps, v.airspeed_max_mps),
                   alpha=(math.radians(v.alpha_min_deg), math.radians(v.alpha_max_deg)),
                   bank=math.radians(v.bank_max_deg))
    rows = {name: "left" if transition_of(name).actuator == LEFT else "right"
            for name in config.campaign.transitions if _is_elevon_lock(name)}
    if not rows:
        return {}
    if config.plant.kind == "linear":
        from ..model.sixdof import build_sixdof_plant
        from ..model.trimmable import linear_trimmable_set

        plant = build_sixdof_plant(af, m.airspeed_mps, m.gamma_deg, m.dt_s)
        ends = {side: linear_trimmable_set(plant, side, env) for side in set(rows.values())}
    else:
        from ..cache.trimmable import cached_trimmable_sets

        ends = cached_trimmable_sets(af, sorted(set(rows.values())), env, name=m.airframe,
                                     stream=stream)
    return {name: ends[side] for name, side in rows.items() if ends[side] is not None}


SET_MODELS = {"linear": "the 6-DOF linear model (exact: two linear programmes, "
                        "`ftc_mc/model/trimmable.py`)",
              "nonlinear": "the airframe's equations (a bisection of steady-flight searches "
                           "from the trim, to 0.05 deg, `ftc_mc/model/trimmable.py`)"}
"""What the trimmable set is of, by truth plant kind (:func:`trimmable_sets`)."""


def survival_markdown(table: pd.DataFrame, level: int = 2) -> str:
    """The survival table in Markdown, one block per elevon-lock row: a line per
    offset bin, a column group per design; headings at ``level`` (``#`` count),
    one deeper per row."""
    if not len(table):
        return ""
    horizon = table["horizon_s"].iloc[0]
    head = "#" * level
    out = [f"{head} Survival after an elevon lock ({horizon:g} s horizon)", "",
           "Share of the trials flying at the lock that stay inside the validity envelope "
           f"for {horizon:g} s after it (95 % Wilson interval), median time from the lock "
           "to the exit (`>H`: at least half stay in), median height lost until the exit "
           "(the glide path's own descent included), by lock offset from the trim "
           "command. Trials that stopped numerically within the horizon are left out "
           "(`unknown`).", ""]
    for name, g in table.groupby("transition", sort=False):
        out += [f"{head}# `{name}`", ""]
        rows = []
        for b, gb in g.sort_values("offset_lo_deg", kind="stable").groupby("bin",
                                                                          sort=False):
            row = {"lock offset [deg]": b}
            for _, r in gb.iterrows():
                v = r["variant"]
                row[f"{v}: stay in"] = _stay_text(r, 0)
                row[f"{v}: median exit [s]"] = (f">{horizon:g}" if not np.isfinite(
                    r["median_leave_s"]) else f"{r['median_leave_s']:.1f}")
                row[f"{v}: height lost [m]"] = ("-" if not np.isfinite(
                    r["height_lost_median_m"]) else f"{r['height_lost_median_m']:.1f}")
            rows.append(row)
        out += [pd.DataFrame(rows).fillna("-").to_markdown(index=False), ""]
    return "\n".join(out)


def _stay_text(r, digits: int) -> str:
    """``stayed/flying (share %, 95 % interval)`` of a survival row, its
    percentages to ``digits`` decimals, ``-`` when none flew, and the count
    of numerical stops when there are some."""
    text = (f"{r['flying'] - r['left']}/{r['flying']} "
            f"({100 * r['survived_rate']:.{digits}f} %, {100 * r['survived_ci_low']:.{digits}f}-"
            f"{100 * r['survived_ci_high']:.{digits}f})" if r["flying"] else "-")
    return text + (f", {r['unknown']} unknown" if r["unknown"] else "")


def trimmable_markdown(table: pd.DataFrame, level: int = 2, kind: str = "linear") -> str:
    """:func:`trimmable_table` in Markdown: a line per elevon-lock row and
    design, the locks inside the trimmable set beside those outside it;
    headings at ``level``; ``kind``: the truth plant's (:data:`SET_MODELS`);
    ``""`` for an empty table."""
    if not len(table):
        return ""
    horizon = table["horizon_s"].iloc[0]
    out = ["#" * level + " Inside and outside the trimmable set", "",
           "The trimmable set: the locks with a steady flight, straight or turning, "
           "inside the validity envelope with the healthy elevon and the throttle within "
           f"their limits, of {SET_MODELS[kind]}; its ends from the trim command, as the "
           "survival table's offsets. Share staying inside the envelope for "
           f"{horizon:g} s after the lock (95 % Wilson interval) and median time from the "
           "lock to the exit (`>H`: at least half stay in), as in the survival table.", ""]
    rows = []
    for (name, variant), g in table.groupby(["transition", "variant"], sort=False):
        row = {"row": f"`{name}`", "design": variant,
               "trimmable set [deg from trim]": f"{g['set_lo_deg'].iloc[0]:+.2f} to "
                                                f"{g['set_hi_deg'].iloc[0]:+.2f}"}
        for _, r in g.iterrows():
            w = r["where"]
            row[f"{w}: stay in"] = _stay_text(r, 1)
            row[f"{w}: median exit [s]"] = ("-" if not r["flying"] else f">{horizon:g}"
                                            if not np.isfinite(r["median_leave_s"])
                                            else f"{r['median_leave_s']:.1f}")
        rows.append(row)
    return "\n".join(out + [pd.DataFrame(rows).fillna("-").to_markdown(index=False)])
