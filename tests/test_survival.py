"""Survival after an elevon lock (ftc_mc/campaign/survival.py):
the table's counts, censored medians and exclusions against a hand-made trials
table, its Markdown and figure, and the columns it reads on a real run."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from ftc_mc.campaign.survival import (OFFSET_EDGES_DEG, horizon_of, survival_markdown,
                                      survival_table)


def _trials():
    """Ten left-elevon locks 3 deg above trim (bin 2 to 5) and three 1 deg below
    (-2 to -0.5), switch at 20 s, 80 s flights, and one engine lock."""
    rows = []
    # bin 2..5: four leave (at 21, 22, 23 s and at 85 s: after the horizon), one
    # stops numerically at 30 s, one left before the switch, four fly to the end
    for i, (status, stop, lost) in enumerate(
            [("bank_out_of_bounds", 21.0, 5.0), ("airspeed_out_of_bounds", 22.0, 7.0),
             ("alpha_out_of_bounds", 23.0, 9.0), ("bank_out_of_bounds", 85.0, 99.0),
             ("nonfinite", 30.0, 1.0), ("airspeed_out_of_bounds", 10.0, math.nan),
             ("ok", math.nan, 60.0), ("ok", math.nan, 61.0), ("ok", math.nan, 62.0),
             ("ok", math.nan, 63.0)]):
        rows.append(("elevon_lock", "paper", math.radians(3.0), status, stop, lost))
    for status, stop in (("ok", math.nan), ("bank_out_of_bounds", 50.0), ("ok", math.nan)):
        rows.append(("elevon_lock", "paper", math.radians(-1.0), status, stop, 30.0))
    rows.append(("engine_lock", "paper", 0.3, "airspeed_out_of_bounds", 25.0, 3.0))
    rows.append(("elevon_unlock", "paper", math.nan, "ok", math.nan, 0.0))
    return pd.DataFrame(rows, columns=["transition", "variant", "lock_offset", "status",
                                       "stop_s", "height_lost_m"])


def test_counts_medians_and_exclusions():
    tab = survival_table(_trials(), fault_time_s=20.0, duration_s=100.0)
    assert set(tab["transition"]) == {"elevon_lock"}  # no engine, no unlock rows
    assert (tab["horizon_s"] == 60.0).all()
    up = tab[tab["offset_lo_deg"] == 2.0].iloc[0]
    # 10 trials: 1 left before the switch and 1 numerical within the horizon are out
    assert (up["flying"], up["left"], up["unknown"]) == (8, 3, 1)
    assert up["survived_rate"] == 5 / 8
    assert up["survived_ci_low"] < 5 / 8 < up["survived_ci_high"]
    # at least half stay in: no median exit; heights of the three that left
    assert math.isnan(up["median_leave_s"]) and up["height_lost_median_m"] == 7.0
    down = tab[tab["offset_lo_deg"] == -2.0].iloc[0]
    assert (down["flying"], down["left"]) == (3, 1) and math.isnan(down["median_leave_s"])
    assert len(tab) == 2  # empty bins are left out


def test_censored_median_and_a_short_horizon():
    t = _trials()
    t = t[t["lock_offset"] > 0].copy()
    t.loc[t.index[6:9], ["status", "stop_s"]] = ["bank_out_of_bounds", 24.0]
    tab = survival_table(t, 20.0, 100.0)
    # leave times 1, 2, 3, 4, 4, 4 s and 2 survivors (inf): median of 8 = 4 s
    assert tab.iloc[0]["left"] == 6 and tab.iloc[0]["median_leave_s"] == 4.0
    # flights shorter than 60 s after the lock: the horizon is what they fly
    assert horizon_of(20.0, 50.0) == 30.0
    short = survival_table(t, 20.0, 50.0)
    assert short.iloc[0]["horizon_s"] == 30.0 and short.iloc[0]["left"] == 6


def test_markdown_and_figure(tmp_path):
    from ftc_mc.plots.campaign import survival_figure

    t = _trials()
    both = pd.concat([t, t.assign(variant="robust")])
    tab = survival_table(both, 20.0, 100.0)
    md = survival_markdown(tab)
    assert "## Survival after an elevon lock (60 s horizon)" in md
    assert "5/8 (62 %" in md and ", 1 unknown" in md and ">60" in md
    assert "paper: stay in" in md and "robust: stay in" in md
    png = survival_figure(tab, tmp_path / "s.png")
    assert png.stat().st_size > 1000
    assert survival_markdown(survival_table(t[t.transition == "engine_lock"], 20, 100)) == ""


def test_old_runs_without_the_columns_give_no_table():
    t = _trials().drop(columns=["height_lost_m"])
    assert survival_table(t, 20.0, 100.0).empty


def test_bins_cover_every_offset():
    assert OFFSET_EDGES_DEG[0] == -math.inf and OFFSET_EDGES_DEG[-1] == math.inf
    assert np.all(np.diff(OFFSET_EDGES_DEG) > 0)


def test_trials_without_a_lock_offset_are_in_no_bin():
    """A resumed run assembles older chunks without ``lock_offset`` beside newer
    ones (the column union, nulls in the older rows): those trials have no
    offset, and np.digitize put NaN in the last bin ("10 and above")."""
    t = _trials()
    old = t[t["transition"] == "elevon_lock"].assign(lock_offset=math.nan,
                                                     height_lost_m=math.nan)
    tab = survival_table(pd.concat([t, old], ignore_index=True), 20.0, 100.0)
    ref = survival_table(t, 20.0, 100.0)
    assert list(tab["bin"]) == list(ref["bin"])
    assert list(tab["flying"]) == list(ref["flying"])


def test_markdown_rows_follow_the_offset_whatever_design_has_them():
    """A bin only the second design has is placed by its offset, not after the
    first design's bins."""
    t = _trials()
    a = t[(t["lock_offset"] > 0) | (t["transition"] != "elevon_lock")]
    tab = survival_table(pd.concat([a, t.assign(variant="robust")]), 20.0, 100.0)
    md = survival_markdown(tab)
    assert md.index("| -2 to -0.5") < md.index("| 2 to 5")


def test_the_report_loads_the_columns_it_needs(tmp_path):
    """The report reads only ``report.load.TRIAL_COLUMNS`` of trials.parquet: the
    survival table's columns must be among them, or the report's section and
    figure never appear."""
    from ftc_mc.io.results import write_parquet
    from ftc_mc.report.load import load_result_dir
    from ftc_mc.report.runs import survival_lines

    cfg = {"timing": {"fault_time_s": 20.0, "duration_s": 100.0}}
    meta = {"kind": "run", "config": cfg, "seed": 0}
    t = _trials().assign(trial_id=np.arange(len(_trials())))
    write_parquet(t, tmp_path / "trials.parquet", meta)
    write_parquet(pd.DataFrame({"transition": ["elevon_lock"]}), tmp_path / "summary.parquet",
                  meta)
    r = load_result_dir(tmp_path)
    assert len(survival_table(r.tables["trials"], 20.0, 100.0)) == 2
    lines = survival_lines(r.tables["trials"], cfg, tmp_path / "s.png", tmp_path / "r.md")
    assert lines and "### Survival after an elevon lock" in lines[0]


TRIM = 0.05
"""The trim command of the hand-made trials [rad]: ``lock_position = TRIM + lock_offset``."""


def test_inside_and_outside_the_trimmable_set(tmp_path):
    """:func:`trimmable_table` splits each row's trials at its set's ends: with
    the set from trim to 5 deg above it, the 3 deg locks are inside (the 2 to 5
    bin's figures) and the -1 deg ones outside (the -2 to -0.5 bin's); the ends
    are reported as offsets of the trials' own frame; rows without a set are
    left out; the Markdown and the figure's shading follow."""
    from ftc_mc.campaign.survival import trimmable_markdown, trimmable_table
    from ftc_mc.plots.campaign import survival_figure

    t = _trials()
    t = pd.concat([t, t[t["transition"] == "elevon_lock"].assign(transition="right_elevon_lock")])
    t = t.assign(lock_position=TRIM + t["lock_offset"])
    sets = {"elevon_lock": (TRIM, TRIM + math.radians(5.0))}
    tab = trimmable_table(t, 20.0, 100.0, sets)
    assert set(tab["transition"]) == {"elevon_lock"}
    bins = survival_table(t, 20.0, 100.0).set_index(["transition", "offset_lo_deg"])
    for where, lo in (("inside", 2.0), ("outside", -2.0)):
        row = tab[tab["where"] == where].iloc[0]
        ref = bins.loc[("elevon_lock", lo)]
        for col in ("flying", "left", "unknown", "survived_rate", "height_lost_median_m"):
            assert row[col] == ref[col] or (np.isnan(row[col]) and np.isnan(ref[col])), col
    assert tab["set_lo_deg"].iloc[0] == 0.0 and abs(tab["set_hi_deg"].iloc[0] - 5.0) < 1e-12
    md = trimmable_markdown(tab)
    assert "## Inside and outside the trimmable set" in md
    assert "+0.00 to +5.00" in md and "5/8 (62.5 %" in md and "2/3 (66.7 %" in md
    assert trimmable_markdown(trimmable_table(t, 20.0, 100.0, {})) == ""
    # a split where every trial stopped numerically: no share, its count shown
    odd = t[(t["transition"] == "elevon_lock") & (t["status"] == "nonfinite")]
    md = trimmable_markdown(trimmable_table(odd, 20.0, 100.0, sets))
    assert "-, 1 unknown" in md and "nan" not in md
    png = survival_figure(survival_table(t, 20.0, 100.0), tmp_path / "s.png", None, tab)
    assert png.stat().st_size > 1000


def test_the_trimmable_sets_of_a_run():
    """:func:`trimmable_sets`: on the 6-DOF linear plant, each elevon-lock row's
    set is :func:`~ftc_mc.model.trimmable.linear_trimmable_set` of its side,
    in the run's validity envelope (a narrower bank bound narrows it); on the
    longitudinal plant, none."""
    from ftc_mc.campaign.runner import resolve_config
    from ftc_mc.campaign.survival import trimmable_sets
    from ftc_mc.model.presets import PRESETS
    from ftc_mc.model.sixdof import build_sixdof_plant
    from ftc_mc.model.trimmable import linear_trimmable_set

    def config(**over):
        plant = {"kind": "linear", "dof": 6, **over.pop("plant", {})}
        return resolve_config({"model": {"airframe": "x8-pyfly"}, "plant": plant,
                               "campaign": {"transitions": ["elevon_lock", "engine_lock",
                                                            "right_elevon_lock"]},
                               **over})

    sets = trimmable_sets(config())
    pl = build_sixdof_plant(PRESETS["x8-pyfly"].airframe)
    assert sets == {"elevon_lock": linear_trimmable_set(pl, "left"),
                    "right_elevon_lock": linear_trimmable_set(pl, "right")}
    narrow = trimmable_sets(config(validity={"bank_max_deg": 20.0}))
    lo, hi = sets["elevon_lock"]
    assert lo < narrow["elevon_lock"][0] and narrow["elevon_lock"][1] < hi
    assert trimmable_sets(config(plant={"dof": 3})) == {}


def test_bisect_band_finds_the_ends_of_an_interval():
    """:func:`bisect_band` on a known interval: its ends within the tolerance
    and inside it; a limit inside the interval is its end; a start outside
    gives None."""
    from ftc_mc.model.trimmable import bisect_band

    calls = []

    def steady(lock):
        calls.append(lock)
        return -0.3 <= lock <= 0.05

    lo, hi = bisect_band(steady, 0.0, (-0.6, 0.6), 1e-4)
    assert -0.3 <= lo < -0.3 + 1e-4 and 0.05 - 1e-4 < hi <= 0.05
    assert len(calls) < 40
    assert bisect_band(steady, 0.0, (-0.2, 0.6), 1e-4)[0] == -0.2
    assert bisect_band(steady, 0.4, (-0.6, 0.6), 1e-4) is None
    # a tolerance finer than the floats' spacing ends at adjacent floats
    lo, hi = bisect_band(steady, 0.0, (-0.6, 0.6), 1e-300)
    assert lo == -0.3 and np.nextafter(hi, 1.0) > 0.05
    with pytest.raises(ValueError, match="tol"):
        bisect_band(steady, 0.0, (-0.6, 0.6), 0.0)


def test_the_equations_set_searches_from_the_trim_to_the_elevon_limits(monkeypatch):
    """:func:`equations_trimmable_set` starts at the 6-DOF trim's position of
    the elevon, bisects towards the airframe's elevon limits and asks
    :func:`steady_flight` of that side in the given envelope (its search
    stubbed by a band 3 deg below and 1 deg above the trim)."""
    import ftc_mc.model.trimmable as tm
    from ftc_mc.core.sixdof.layout import COMMAND
    from ftc_mc.model.presets import PRESETS
    from ftc_mc.model.sixdof import trim6

    af = PRESETS["x8-pyfly"].airframe
    trim = trim6(af).u0[COMMAND["right"]]
    env = tm.Envelope(bank=0.7)
    asked = []

    def steady_flight(airframe, side, lock, envelope):
        asked.append((side, lock, envelope))
        ok = trim - math.radians(3.0) <= lock <= trim + math.radians(1.0)
        return tm.SteadyFlight(side, lock, lock - trim, 0.0 if ok else 1.0, {})

    monkeypatch.setattr(tm, "steady_flight", steady_flight)
    lo, hi = tm.equations_trimmable_set(af, "right", env, tol=1e-6)
    assert asked[0][1] == trim and {a[0] for a in asked} == {"right"}
    assert all(a[2] is env for a in asked)
    assert set(af.elevon_limits) <= {a[1] for a in asked}
    assert abs(lo - (trim - math.radians(3.0))) < 1e-6
    assert abs(hi - (trim + math.radians(1.0))) < 1e-6


@pytest.mark.trimmable_search
def test_the_equations_set_is_searched_once_and_cached(tmp_path, monkeypatch):
    """:func:`cached_trimmable_sets`: the first call searches (one notice) and
    writes the cache; the next reads it without searching; an unreadable or
    malformed file is searched again; an unwritable cache still gives the set;
    another envelope is another key.  On the 6-DOF nonlinear plant,
    :func:`trimmable_sets` reads the same cache.  The search is stubbed (the
    real one takes about a minute per side), one side at a time, so that
    joblib runs it in this process, where the stub holds."""
    import io

    import ftc_mc.cache.trimmable as tc
    from ftc_mc.campaign.runner import resolve_config
    from ftc_mc.campaign.survival import trimmable_sets
    from ftc_mc.model.presets import PRESETS
    from ftc_mc.model.trimmable import Envelope

    searched = []

    def search(airframe, side, envelope):
        searched.append((side, envelope))
        return (-0.5, 0.1)

    monkeypatch.setattr(tc, "equations_trimmable_set", search)
    af = PRESETS["x8-pyfly"].airframe
    out = io.StringIO()
    assert tc.cached_trimmable_sets(af, ["left"], cache_dir=tmp_path / "design", stream=out) \
        == {"left": (-0.5, 0.1)}
    assert "finding the trimmable set" in out.getvalue() and len(searched) == 1
    out = io.StringIO()
    assert tc.cached_trimmable_sets(af, ["left"], cache_dir=tmp_path / "design", stream=out) \
        == {"left": (-0.5, 0.1)}
    assert out.getvalue() == "" and len(searched) == 1
    (file,) = (tmp_path / "design" / "trimmable").glob("*.json")
    for bad in ("{not json", "[]", '{"key": "%s", "ends": [1, 2, 3]}' % file.stem,
                '{"key": "%s", "ends": [0.2, 0.1]}' % file.stem):
        file.write_text(bad)
        n = len(searched)
        tc.cached_trimmable_sets(af, ["left"], cache_dir=tmp_path / "design",
                                 stream=io.StringIO())
        assert len(searched) == n + 1, bad
    # an unwritable cache: the set is still returned, with a warning
    real_write = tc.write_atomic

    def refuse(path, write):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tc, "write_atomic", refuse)
    out = io.StringIO()
    assert tc.cached_trimmable_sets(af, ["right"], cache_dir=tmp_path / "design",
                                    stream=out) == {"right": (-0.5, 0.1)}
    assert "could not cache" in out.getvalue()
    monkeypatch.setattr(tc, "write_atomic", real_write)
    n = len(searched)
    tc.cached_trimmable_sets(af, ["left"], Envelope(bank=0.5), cache_dir=tmp_path / "design",
                             stream=io.StringIO())
    assert len(searched) == n + 1
    assert len(list((tmp_path / "design" / "trimmable").glob("*.json"))) == 2
    monkeypatch.setenv("FTC_MC_CACHE_DIR", str(tmp_path))
    cfg = resolve_config({"model": {"airframe": "x8-pyfly"},
                          "plant": {"kind": "nonlinear", "dof": 6},
                          "campaign": {"transitions": ["elevon_lock", "engine_lock"]}})
    assert trimmable_sets(cfg, stream=io.StringIO()) == {"elevon_lock": (-0.5, 0.1)}
    assert len(searched) == n + 1  # the default envelope's file, written above
