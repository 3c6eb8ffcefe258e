"""Flying on with one elevon in the trial loop (``ftc_mc/core/sixdof/lockturn.py``):
the law against its plain-NumPy twin, the design table's cache, a campaign in
which the ``lock_turn`` design keeps locked trials in the envelope where the
paper's loop does not, and the configs that cannot fly it."""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
import pandas as pd
import pytest

from ftc_mc import api
from ftc_mc.core.sixdof.lockturn import LockTurnTable, hands_back, lock_turn_law, turn_probe
from ftc_mc.cache import lock_turn as lt_cache
from ftc_mc.design import lock_turn as lt
from ftc_mc.model.presets import PRESETS
from ftc_mc.sim.monitor import MEASURED, lock_turn_table
from ftc_mc.sim.setup import CONTROLLER_KINDS, build_setup

from naive_sixdof import (guarded_law_ref, lock_turn_law_ref, rocking_law_ref, side_blocks_ref,
                          turn_probe_ref)

AF = PRESETS["x8-pyfly"].airframe


def test_lock_turn_kind_is_the_kernels():
    """The config's ``lock_turn`` is the kind the truth kernel tests for."""
    from ftc_mc.core.sixdof.lockturn import LOCK_TURN

    assert CONTROLLER_KINDS["lock_turn"] == LOCK_TURN
    assert len(set(CONTROLLER_KINDS.values())) == len(CONTROLLER_KINDS)


@pytest.mark.parametrize("measured", [True, False])
def test_law_matches_its_twin(measured):
    """Random tables, estimates and measurements, positions inside, between
    and beyond the grid: the kernel's commands equal the twin's."""
    rng = np.random.default_rng(7)
    n, nf, L = 5, len(lt.turn_states("left")), 6
    # the index maps of a real (empty) table, then random entries
    empty = build_empty_table(measured)
    tab = empty._replace(lo=np.array([-0.1, -0.12]), step=0.05,
                         x=rng.normal(0, 0.1, (2, n, nf)), u=rng.normal(0, 0.1, (2, n, 3)),
                         K=rng.normal(0, 1.0, (2, n, 2, nf)), k=rng.normal(0, 0.05, (2, n, 2)),
                         steady=np.array([[0.0, 1, 1, 1, 0], [1.0, 1, 1, 0, 0]]),
                         hold=np.array([0.01, -0.02, 0.03]))
    mx = rng.normal(0, 0.2, (20, L))
    z = rng.normal(0, 0.2, (12, L))
    lat = rng.normal(0, 0.2, (7, L))
    lo, hi = np.array([-0.4, -0.5, -0.5]), np.array([0.6, 0.5, 0.5])
    pl = rocking_setup(measured)[1]  # read by the rocking law only (off here: the trim held)
    for s in (0, 1):
        for p in (-0.3, -0.1, -0.07, 0.0, 0.0999, 0.1, 0.5):
            u = np.zeros((3, L))
            for l in range(L):
                lock_turn_law(tab, pl, s, p, mx, z, lat, l, lo, hi, u)
                meas = np.concatenate([z[:, l], lat[:5, l]])
                xhat = np.where(tab.meas[s] >= 0, meas[np.maximum(tab.meas[s], 0)],
                                mx[tab.rows[s], l])
                want = lock_turn_law_ref(tab, s, p, xhat, lo, hi)
                np.testing.assert_allclose(u[:, l], want, rtol=1e-12, atol=1e-14)
    # the measured sources are the sensors of the same states
    if measured:
        for s, side in enumerate(lt.SIDES):
            names = lt.turn_states(side)
            for r, o in enumerate(tab.meas[s]):
                assert (o < 0) == (names[r] in ("throttle", "left", "right"))
                if o >= 0:
                    assert MEASURED[o] == names[r]
    else:
        assert (tab.meas < 0).all()


@pytest.mark.parametrize("probe, unit, check", [(0.03, 2, 30), (0.05, 1, 7), (0.0, 2, 30)])
def test_probe_matches_its_twin(probe, unit, check):
    """The probe's 3211 on the named elevon and the hand-back decision, at every
    step from before the law took over to past the check, with estimates of
    ``b1`` and spreads either side of the threshold: the kernels equal the twin."""
    tab = build_empty_table(True)._replace(probe=probe, probe_unit=unit, check=check,
                                           hand_back=0.5, hand_back_sd=2.0)
    for t in range(-3, check + 5):
        for b1, var in ((0.0, 0.0), (0.49, 0.0), (0.5, 0.0), (0.97, 1e-4), (0.3, 0.0099),
                        (0.3, 0.0101), (0.1, -1e-18)):
            value, back = turn_probe_ref(tab, t, b1, var)
            assert turn_probe(tab, t) == value, (t, b1)
            assert hands_back(tab, t, b1, var) == back, (t, b1, var)
    # the probe is the paper's 3211 (Fig. 4): 7 units, of which one more up than down
    values = [turn_probe(tab, t) for t in range(0, 8 * unit)]
    assert sum(v != 0.0 for v in values) == (7 * unit if probe else 0)
    assert sum(values) == pytest.approx(unit * probe, abs=1e-15)


def test_side_blocks_match_their_twin():
    """Every combination of Table 1's block, the elevon flown about (none,
    either side, handed back) and the monitor's latest decision, under each
    controller kind: the kernel's blocks equal the twin's, and only a
    ``lock_turn`` design's move."""
    from collections import namedtuple

    from ftc_mc.conventions import RESETS_EITHER, RESETS_SIDE_MONITOR, RESETS_TABLE1
    from ftc_mc.core.shared.paths import SIXDOF_PLANT
    from ftc_mc.core.sixdof.lockturn import LOCK_TURN, side_blocks

    grid = np.array([(b, s, m) for b in (0, 1, 2) for s in (-3, -2, 0, 2, 3)
                     for m in (0, 1, 2, 3)], dtype=np.int64).T
    Reconfig = namedtuple("Reconfig", ["kind"])
    Det = namedtuple("Det", ["source"])
    Scheme = namedtuple("Scheme", ["detection", "reconfig"])
    State = namedtuple("State", ["mside", "mlast", "mnow"])
    # this step's decision: none or each actuator, on every combination above
    now = np.resize(np.array([0, 1, 2, 3], dtype=np.int64), grid.shape[1])
    st = State(mside=grid[1].copy(), mlast=grid[2].copy(), mnow=now[::-1].copy())
    moved = 0
    for source in (RESETS_TABLE1, RESETS_SIDE_MONITOR, RESETS_EITHER):
        for kind in (0, 1, LOCK_TURN):
            block = grid[0].copy()
            side_blocks(SIXDOF_PLANT, Scheme(Det(source), Reconfig(kind)), st, block)
            np.testing.assert_array_equal(block, side_blocks_ref(
                kind, st.mside, st.mlast, grid[0], source, st.mnow))
            if source == RESETS_TABLE1:
                moved += int((block != grid[0]).sum())
                if kind != LOCK_TURN:
                    np.testing.assert_array_equal(block, grid[0])
            elif source == RESETS_SIDE_MONITOR:  # the monitor's alone, whatever Table 1
                np.testing.assert_array_equal(block != 0, st.mnow != 0)
            else:  # either: a reset wherever one of them decides
                np.testing.assert_array_equal(block != 0, (st.mnow != 0) | (grid[0] != 0))
    assert moved > 0
    # the decision codes follow the monitor's directions, named as the
    # longitudinal commands
    from ftc_mc.conventions import INPUT_NAMES, RESET_ELEVONS, RESET_THRUST
    from ftc_mc.core.sixdof.layout import MONITOR_DIRECTIONS
    from ftc_mc.core.sixdof.lockturn import DECISION_BLOCK

    assert MONITOR_DIRECTIONS == tuple(n.replace("elevon_", "") for n in INPUT_NAMES)
    assert [DECISION_BLOCK[1 + MONITOR_DIRECTIONS.index(d)] for d in ("throttle", "left", "right")
            ] == [RESET_THRUST, RESET_ELEVONS, RESET_ELEVONS]


Mon = namedtuple("Mon", ["states", "u0"])
Pl = namedtuple("Pl", ["kind", "p", "x0", "dt", "A", "B", "Bw", "C", "Dw", "y0", "u0", "monitor"])
"""The truth plant fields the laws read (:func:`rocking_setup`), one class for
every test, so that each law's twin is compiled once for all of them."""


def rocking_setup(measured, kind="nonlinear"):
    """A table with the rocking law's candidates (0.6 s horizon, switches at 0.1
    and 0.3 s, 2 RK4 sub-steps, the trials' envelope) on the default 6-DOF
    model, and the truth plant fields it reads (``kind``, the equations' ``p``
    and ``dt``, the linear model's ``A``, ``B``, ``Bw``, ``C``, ``Dw``, ``y0``, ``u0``, the
    trim ``x0``, ``monitor.states``, ``monitor.u0``) of a ``kind`` plant."""
    from ftc_mc.core.sixdof.layout import (MONITOR_STATES, SIXDOF_LINEAR, SIXDOF_NONLINEAR,
                                           STATE)
    from ftc_mc.model.sixdof import build_sixdof_plant
    from ftc_mc.sim.monitor import rocking_table

    six = build_sixdof_plant(AF, 20.0, -3.0, 0.1)
    u0 = six.u0 - np.array([0.0, 0.004, -0.002])  # a longitudinal trim beside the 6-DOF one
    lo, hi = six.u_lower - u0, six.u_upper - u0
    tab = build_empty_table(measured)._replace(
        hold=six.u0 - u0,
        **rocking_table(lo, hi, 6, (1, 3), 2, (12.0, 30.0, -8.0, 12.0, 60.0)))
    pl = Pl(kind=SIXDOF_LINEAR if kind == "linear" else SIXDOF_NONLINEAR,
            p=six.trim.params, x0=six.trim.x0, dt=0.1, A=six.A, B=six.B, Bw=six.Bw, C=six.C,
            Dw=six.Dw, y0=six.trim.y0, u0=six.u0,
            monitor=Mon(states=np.array([STATE[n] for n in MONITOR_STATES]), u0=u0))
    return tab, pl, lo, hi


@pytest.mark.parametrize("levels, switches", [(2, ()), (3, (2, 10)), (5, (2, 10)), (4, (3,))])
def test_rocking_candidates(levels, switches):
    """The rocking law's candidates: the throttle's two limits by ``levels``
    elevon positions from limit to limit, each pair held, then per switch time
    every ordered pair of two different pairs switching there; the same pairs
    on both sides (each side's healthy elevon)."""
    from ftc_mc.sim.monitor import rocking_table

    lo, hi = np.array([-0.3, -0.5, -0.45]), np.array([0.7, 0.45, 0.5])
    ro = rocking_table(lo, hi, 30, switches, 2, (12.0, 30.0, -8.0, 12.0, 60.0), levels)
    n_p = 2 * levels
    assert ro["ro_first"].shape == (n_p * (1 + len(switches) * (n_p - 1)),)
    assert ro["ro_u"].shape == (2, len(ro["ro_first"]), 2, 2)
    held = ro["ro_first"] == 30
    assert held.sum() == n_p
    for s, h in ((0, 2), (1, 1)):  # the left elevon locked flies the right one, and back
        pairs = {tuple(p) for p in ro["ro_u"][s, held, 0]}
        want = {(a, b) for a in (lo[0], hi[0]) for b in np.linspace(lo[h], hi[h], levels)}
        assert pairs == want
        first, second = ro["ro_u"][s, ~held, 0], ro["ro_u"][s, ~held, 1]
        assert not (first == second).all(axis=1).any()
        for k in switches:
            at = ro["ro_first"][~held] == k
            assert len({(tuple(a), tuple(b)) for a, b in zip(first[at], second[at])}) == \
                n_p * (n_p - 1)


@pytest.mark.parametrize("measured, kind", [(True, "nonlinear"), (False, "nonlinear"),
                                            (True, "linear")])
def test_rocking_law_matches_its_twin(measured, kind):
    """Locks beyond the steady band either side, from trim and from rolled,
    pitched and slowed states: the kernel sends the first pair of the
    candidate the twin chooses, and the choices differ (throttle and elevon,
    held and switching) from state to state; from a state already outside
    the envelope, or one not finite, both hold the trim commands.  On the
    linear plant the candidates fly its own model."""
    from ftc_mc.core.sixdof.layout import MONITOR_STATES
    from ftc_mc.core.sixdof.lockturn import rocking_law
    from ftc_mc.sim.monitor import MEASURED

    tab, pl, lo, hi = rocking_setup(measured, kind)
    assert tab.ro_first.shape == (66,) and tab.ro_u.shape == (2, 66, 2, 2)
    rng = np.random.default_rng(26)
    nm, L = len(MONITOR_STATES), 5
    index = {n: i for i, n in enumerate(MONITOR_STATES)}
    chosen = set()
    for s in (0, 1):
        for off in (-20.0, 6.0, 14.0):
            p = pl.monitor.u0[1 + s] + math.radians(off)
            mx = np.zeros((nm + 6, L))
            mx[index["phi"], 1] = math.radians(35.0 * (1 - 2 * s))
            mx[index["theta"], 1] = math.radians(-20.0)
            mx[index["u"], 2] = -5.0
            mx[:nm, 2] += rng.normal(0, 0.02, nm)
            z = rng.normal(0, 0.01, (12, L))
            lat = rng.normal(0, 0.01, (7, L))
            # lane 3 already banked past the envelope, estimated and measured;
            # lane 4 with a diverged estimate of an actuator (never measured)
            mx[index["phi"], 3] = math.radians(75.0)
            o = tab.meas[s, list(MONITOR_STATES[i] for i in tab.rows[s]).index("phi")]
            if o >= 0:
                (z if o < 12 else lat)[o if o < 12 else o - 12, 3] = math.radians(75.0)
            mx[index["throttle"], 4] = np.nan
            u = np.zeros((3, L))
            for l in range(L):
                flew = rocking_law(tab, pl, s, p, mx, z, lat, l, lo, hi, u)
                x = pl.x0.copy()
                x[pl.monitor.states] += mx[:nm, l]
                meas = np.concatenate([z[:, l], lat[:5, l]])
                for r, o in enumerate(tab.meas[s]):
                    if o >= 0:
                        j = pl.monitor.states[tab.rows[s, r]]
                        x[j] = pl.x0[j] + meas[o]
                        assert MEASURED[o] == MONITOR_STATES[tab.rows[s, r]]
                want, best = rocking_law_ref(tab, pl, s, p, x, lo, hi)
                # the kernel leaves the trim to lock_turn_law (checked below)
                assert flew == (best != -1)
                if not flew:
                    want = np.zeros(2)
                    np.testing.assert_array_equal(u[:, l], 0.0)
                np.testing.assert_allclose(u[tab.cmd[s], l], want, rtol=0, atol=1e-15)
                assert (best == -1) == (l >= 3), (s, off, l, best)
                chosen.add(best)
    chosen.discard(-1)
    assert len({tuple(tab.ro_u[0, c, 0]) for c in chosen}) >= 2, chosen
    assert any(tab.ro_first[c] < tab.ro_steps for c in chosen), chosen
    # lock_turn_law flies it where neither design bracketing the estimate is
    # steady (and the trim without it, or where nothing stays in: lanes 3 and
    # 4), the locked elevon at its trim command
    designs = tab._replace(
        lo=np.array([pl.monitor.u0[1], pl.monitor.u0[2]]) - 0.1, step=0.1,
        x=np.zeros((2, 2, tab.rows.shape[1])), u=np.zeros((2, 2, 3)),
        K=np.zeros((2, 2, 2, tab.rows.shape[1])), k=np.zeros((2, 2, 2)),
        steady=np.zeros((2, 2)))
    for on in (1, 0):
        t = designs._replace(ro_on=on)
        u, want = np.zeros((3, L)), np.zeros((3, L))
        for l in range(L):
            lock_turn_law(t, pl, 0, p, mx, z, lat, l, lo, hi, u)
            if not (on and rocking_law(t, pl, 0, p, mx, z, lat, l, lo, hi, want)):
                assert not on or l >= 3
                want[tab.cmd[0], l] = tab.hold[tab.cmd[0]]
            want[tab.locked[0], l] = tab.hold[tab.locked[0]]
        np.testing.assert_array_equal(u, np.clip(want, lo[:, None], hi[:, None]))


@pytest.mark.parametrize("measured, kind", [(True, "nonlinear"), (False, "nonlinear"),
                                            (True, "linear")])
def test_guarded_law_matches_its_twin(measured, kind):
    """The rollout guard on designs about steady flights (random gains and
    design states near trim, guard candidates holding for 1 and 3 periods of
    a 0.6 s horizon): from trim, rolled either way, slowed, and past the
    envelope, the kernel leaves the LQR to fly exactly where the twin does,
    sends the twin's pair elsewhere, and ``lock_turn_law`` sends one or the
    other; both branches are taken."""
    from ftc_mc.core.sixdof.layout import MONITOR_STATES
    from ftc_mc.core.sixdof.lockturn import guarded_law
    from ftc_mc.sim.monitor import rocking_table

    tab, pl, lo, hi = rocking_setup(measured, kind)
    tab = tab._replace(**{k: v for k, v in rocking_table(
        lo, hi, 6, (1, 3), 2, (12.0, 30.0, -8.0, 12.0, 60.0), 3, holds=(1, 3)).items()
        if k.startswith("gd_")})
    assert tab.gd_on == 1 and tab.gd_pairs == 6 and list(tab.gd_holds) == [1, 3]
    rng = np.random.default_rng(27)
    nf, n = tab.rows.shape[1], 3
    nm, L = len(MONITOR_STATES), 6
    index = {k: i for i, k in enumerate(MONITOR_STATES)}
    hold_dev = np.broadcast_to(tab.hold, (2, n, 3))
    flew, held, holds = 0, 0, set()
    for s in (0, 1):
        t = tab._replace(lo=pl.monitor.u0[1:] - math.radians(16.0), step=math.radians(2.0),
                         x=rng.normal(0, 0.01, (2, n, nf)),
                         u=hold_dev + rng.normal(0, 0.01, (2, n, 3)),
                         K=rng.normal(0, 0.05, (2, n, 2, nf)), k=np.zeros((2, n, 2)),
                         steady=np.ones((2, n)))
        for off in (-14.5, -12.0):
            p = pl.monitor.u0[1 + s] + math.radians(off)
            mx = np.zeros((nm + 6, L))
            mx[index["phi"], 1] = math.radians(50.0)
            mx[index["phi"], 2] = math.radians(-50.0)
            mx[index["u"], 3] = -6.0
            mx[index["phi"], 4] = math.radians(75.0)
            mx[:nm, 5] += rng.normal(0, 0.02, nm)
            z = np.zeros((12, L))
            lat = np.zeros((7, L))
            for r, o in enumerate(t.meas[s]):  # the sensors read the estimate's states
                if o >= 0:
                    (z if o < 12 else lat)[o if o < 12 else o - 12] = mx[t.rows[s, r]]
            u = np.zeros((3, L))
            law = np.zeros((3, L))
            for l in range(L):
                f = min(n - 1.0, (p - t.lo[s]) / t.step)  # lock_turn_law's bracket
                i = min(int(f), n - 2)
                ran = guarded_law(t, pl, s, i, i + 1, f - i, p, mx, z, lat, l, lo, hi, u)
                x = pl.x0.copy()
                x[pl.monitor.states] += mx[:nm, l]
                ref = guarded_law_ref(t, pl, s, p, x, lo, hi)
                lock_turn_law(t, pl, s, p, mx, z, lat, l, lo, hi, law)
                if ref is None:
                    assert not ran, (s, off, l)
                    np.testing.assert_array_equal(u[:, l], 0.0)
                    xhat = x[[pl.monitor.states[r] for r in t.rows[s]]] - \
                        pl.x0[[pl.monitor.states[r] for r in t.rows[s]]]
                    np.testing.assert_allclose(law[:, l], lock_turn_law_ref(t, s, p, xhat, lo, hi),
                                               rtol=1e-12, atol=1e-14)
                    held += 1
                else:
                    assert ran, (s, off, l)
                    np.testing.assert_allclose(u[t.cmd[s], l], ref[0], rtol=0, atol=1e-15)
                    np.testing.assert_array_equal(law[t.cmd[s], l], u[t.cmd[s], l])
                    flew += 1
                    holds.add(ref[1][1])
    assert flew > 0 and held > 0, (flew, held)
    assert holds, holds


def build_empty_table(measured):
    """A table with no designs (its index maps only) on the default 6-DOF model."""
    from ftc_mc.model.sixdof import build_sixdof_plant

    six = build_sixdof_plant(AF, 20.0, -3.0, 0.1)
    tab = lock_turn_table(six, np.zeros(3), measured=measured)
    assert isinstance(tab, LockTurnTable) and tab.x.shape[1] == 0
    return tab


def test_designs_are_cached(tmp_path, monkeypatch):
    """The second call loads the designs from the cache (it does not design),
    equal to the bit; another grid is another file; a steady lock is designed
    about itself."""
    off = np.radians([-2.0, 0.0])
    first = lt_cache.cached_lock_turn_designs(AF, off, cache_dir=tmp_path)
    assert len(list((tmp_path / "lock_turn").glob("*.npz"))) == 1

    def refuse(*a, **k):
        raise AssertionError("designed again")

    monkeypatch.setattr(lt_cache, "lock_turn_designs", refuse)
    again = lt_cache.cached_lock_turn_designs(AF, off, cache_dir=tmp_path)
    for f in ("offsets", "lock", "x", "cmd", "K", "k", "steady"):
        assert np.array_equal(getattr(first, f), getattr(again, f)), f
    assert first.steady.all()  # -2 and 0 deg are inside the trimmable set
    with pytest.raises(AssertionError, match="designed again"):
        lt_cache.cached_lock_turn_designs(AF, np.radians([-2.0, 1.0]), cache_dir=tmp_path)
    # the entries are lock_turn_lqr's, on one BLAS thread
    from threadpoolctl import threadpool_limits

    monkeypatch.undo()
    with threadpool_limits(limits=1, user_api="blas"):
        d = lt.lock_turn_lqr(AF, "right", float(first.lock[1, 0]))
    np.testing.assert_array_equal(first.K[1, 0], d.K)


def flies_on_config(trim):
    """Nonlinear 6-DOF, still air: locks within -4 to +1 deg of trim at 5 s,
    60 s flown after them; the paper's loop and the lock-turn design."""
    lo, hi = trim + math.radians(-4.0), trim + math.radians(1.0)
    return {"campaign": {"transitions": ["elevon_lock", "right_elevon_lock"], "trials": 6,
                         "seed": 11, "signature": "paper", "designs": ["sixdof"],
                         "chunk_size": 6},
            "plant": {"kind": "nonlinear", "dof": 6},
            "draws": {"elevon_lock_range_rad": [lo, hi]},
            "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 65.0},
            "monitor": {"turn_offsets_deg": [-6.0, 2.0], "turn_step_deg": 2.0},
            "designs": {"sixdof": {"controller": "lock_turn"}}}


def test_lock_turn_design_flies_on(tmp_path, monkeypatch):
    """Every trial of the lock-turn design stays inside the envelope for the
    60 s after a lock within -4 to +1 deg of trim (the trimmable band;
    the oracle study flies -10 to +2 deg), where the paper's loop keeps at most
    half; both fly the same trials, and the monitor's first decision is the
    same in both (the flights are the same until it).  From that decision on,
    the lock-turn design resets only the elevon block, where the paper's
    Table 1 resets the thrust block too."""
    trim = float(build_setup(api.campaign_config(
        {"plant": {"kind": "linear", "dof": 6}})).truth.u0[1])
    t = api.run_campaign(flies_on_config(trim), jobs=1, progress=False,
                         out=tmp_path / "run").trials
    paper, six = (t[t["variant"] == v].set_index(["transition", "trial_id"])
                  for v in ("paper", "sixdof"))
    assert (six["lock_position"] == paper["lock_position"]).all()
    assert (paper["side_s"] == six["side_s"]).all()
    assert (six["side_correct"] == 1).all()
    assert (six["status"] == "ok").all(), six["status"].value_counts()
    assert (paper["status"] == "ok").mean() <= 0.5
    summary = (tmp_path / "run" / "summary.md").read_text()
    assert "sixdof: stay in" in summary
    # the split at the trimmable set, of the equations the truth flies (its
    # search replaced by the linear model's set here, tests/conftest.py); the
    # run keeps the sets in summary.parquet's metadata, and the report splits
    # at those without finding them again
    assert "## Inside and outside the trimmable set" in summary
    assert "of the airframe's equations" in summary
    from ftc_mc.campaign import survival
    from ftc_mc.io.results import read_metadata
    from ftc_mc.report.load import load_result_dir
    from ftc_mc.report.runs import survival_lines

    stored = read_metadata(tmp_path / "run" / "summary.parquet")["trimmable_sets"]
    assert set(stored) == {"elevon_lock", "right_elevon_lock"}
    r = load_result_dir(tmp_path / "run")

    def not_again(config, stream=None):
        raise AssertionError("the report found the sets again")

    monkeypatch.setattr(survival, "trimmable_sets", not_again)
    lines = "\n".join(survival_lines(r.tables["trials"], r.meta["config"],
                                      tmp_path / "s.png", tmp_path / "r.md",
                                      r.meta.get("trimmable_sets")))
    table = summary[summary.index("## Inside and outside"):].split("\n\n")[2]
    assert table in lines
    # from the monitor's decision on, the lock-turn design resets only the
    # elevon block (core/sixdof/lockturn.side_blocks); the paper's Table 1 on
    # the same flights does not
    resets = pd.read_parquet(tmp_path / "run" / "resets.parquet")
    wrong = {}
    for v, trials in (("paper", paper), ("sixdof", six)):
        named = trials[(trials["side_correct"] == 1) & (trials["side_false"] == 0)]
        r = resets[resets["variant"] == v].join(named["side_s"], on=["transition", "trial_id"],
                                                how="inner")
        wrong[v] = int(((r["time_from_fault_s"] >= r["side_s"])
                        & (r["block"] != "elevons")).sum())
    assert wrong["sixdof"] == 0 and wrong["paper"] > 0, wrong


def fly_both_ways(tmp_path, offsets_deg, table_deg, beyond, duration_s):
    """Two trials per elevon row, locked at ``offsets_deg`` (lowest, highest)
    from trim at 5 s and flown to ``duration_s``, with ``turn_beyond: hold``
    and with ``beyond`` (the lock-turn table over ``table_deg``): the trials
    of each, indexed by transition and trial."""
    trim = float(build_setup(api.campaign_config(
        {"plant": {"kind": "linear", "dof": 6}})).truth.u0[1])
    out = []
    for way in ("hold", beyond):
        cfg = flies_on_config(trim)
        cfg["campaign"].update(transitions=["elevon_lock", "right_elevon_lock"], trials=2,
                               chunk_size=2, signature="none")
        cfg["draws"] = {"elevon_lock_range_rad": [trim + math.radians(offsets_deg[0]),
                                                  trim + math.radians(offsets_deg[1])]}
        cfg["timing"]["duration_s"] = duration_s
        cfg["monitor"].update(turn_beyond=way, turn_offsets_deg=table_deg)
        t = api.run_campaign(cfg, jobs=1, progress=False, out=tmp_path / way).trials
        out.append(t.set_index(["transition", "trial_id"]))
    return out


def test_the_rocking_law_outlasts_the_held_trim(tmp_path):
    """Locks 5-12 deg above trim, beyond the steady band (no steady flight
    exists there with the healthy elevon and the throttle): with the trim
    held (``turn_beyond: hold``) every trial leaves the envelope within 15 s
    of the lock; the rocking law keeps every one of the same trials inside
    for the 30 s flown (docs/findings/sixdof-rocking-guard.md has the campaign)."""
    hold, rock = fly_both_ways(tmp_path, (5.0, 12.0), [-2.0, 6.0], "rollout", 30.0)
    assert (hold["lock_position"] == rock["lock_position"]).all()
    assert (rock["side_correct"] == 1).all()
    assert (hold["status"] != "ok").all(), hold["status"].value_counts()
    assert (hold["stop_s"] < 5.0 + 15.0).all(), hold["stop_s"]
    assert (rock["status"] == "ok").all(), rock[["status", "stop_s"]]


def test_the_guard_flies_locks_the_design_box_cannot(tmp_path):
    """Locks 11.5-13 deg below trim have steady turns in the envelope (at up
    to 50 deg of bank and 13-14 m/s) but none in the design box: with the
    trim held (``turn_beyond: hold``) every trial leaves the envelope within
    5 s of the lock; with the guard (``guarded``), which designs about those
    turns and flies the LQR under its rollouts, every one of the same trials
    stays inside for the 30 s flown (docs/findings/sixdof-rocking-guard.md has the campaign)."""
    # the table reaches the trim side too: the monitor's first lock estimates
    # lie there (with it cut at -4 deg, a right lock at -12.5 deg left after 3.8 s)
    hold, guard = fly_both_ways(tmp_path, (-13.0, -11.5), [-14.0, 4.0], "guarded", 35.0)
    assert (hold["lock_position"] == guard["lock_position"]).all()
    assert (guard["side_correct"] == 1).all()
    assert (hold["status"] != "ok").all(), hold["status"].value_counts()
    assert (hold["stop_s"] < 5.0 + 5.0).all(), hold["stop_s"]
    assert (guard["status"] == "ok").all(), guard[["status", "stop_s"]]


def test_on_the_linear_plant_the_table_is_the_linear_models(tmp_path, capfd):
    """On the linear plant, locks 4.3-5.2 deg above trim have steady flights
    of the linear model (which the plant flies) but none of the airframe's
    equations (their band ends near +2.25 deg): with the table designed on
    the linear model (``monitor.turn_model: auto`` there) every trial stays
    inside the envelope for the 30 s flown; with the table designed on the
    equations (``nonlinear``) every one of the same trials leaves within 5 s
    of the lock (docs/findings/sixdof-lock-turn.md has the campaign).  Each run notes once
    that the table's -2 deg ends lie inside the steady band (the linear
    model's, -4.75 / -5.25 to +5.5 deg; the equations', -29 to +2.25 deg),
    and not its +6 deg ends, beyond both."""
    trim = float(build_setup(api.campaign_config(
        {"plant": {"kind": "linear", "dof": 6}})).truth.u0[1])
    out = {}
    capfd.readouterr()
    for model in ("auto", "nonlinear"):
        cfg = flies_on_config(trim)
        cfg["campaign"].update(trials=2, chunk_size=2, signature="none")
        cfg["plant"]["kind"] = "linear"
        cfg["draws"] = {"elevon_lock_range_rad": [trim + math.radians(4.3),
                                                  trim + math.radians(5.2)]}
        cfg["timing"]["duration_s"] = 35.0
        cfg["monitor"].update(turn_offsets_deg=[-2.0, 6.0], turn_model=model)
        t = api.run_campaign(cfg, jobs=1, progress=False, out=tmp_path / model).trials
        out[model] = t.set_index(["transition", "trial_id"])
        notes = [ln for ln in capfd.readouterr().err.splitlines() if "note: the lock-turn" in ln]
        assert len(notes) == 1 and "(left -2 deg, right -2 deg)" in notes[0], notes
        assert ("linear model" if model == "auto" else "airframe's equations") in notes[0]
    lin, eq = out["auto"], out["nonlinear"]
    assert (lin["lock_position"] == eq["lock_position"]).all()
    assert (lin["side_correct"] == 1).all()
    assert (lin["status"] == "ok").all(), lin[["status", "stop_s"]]
    assert (eq["status"] != "ok").all() and (eq["stop_s"] < 5.0 + 5.0).all(), eq["stop_s"]


def test_the_linear_models_table_has_its_own_cache_entry():
    off = np.radians([-2.0, 0.0])
    keys = {lt_cache.lock_turn_designs_key(AF, off, 20.0, -3.0, 0.1, linear=lin)
            for lin in (False, True)}
    assert len(keys) == 2


def probe_config(probe_rad):
    """Nonlinear 6-DOF, still air: left-elevon losses of 10-40 % at 5 s (which
    the monitor names like locks) and locks within 1 deg of trim, 30 s flown."""
    cfg = flies_on_config(0.0)
    cfg["campaign"].update(transitions=["elevon_loss", "elevon_lock"], trials=4, chunk_size=4)
    cfg["draws"] = {"loss_b1_range": [0.1, 0.4], "elevon_lock_range_rad": [0.04, 0.075]}
    cfg["timing"]["duration_s"] = 30.0
    cfg["monitor"].update(turn_probe_rad=probe_rad, hand_back_after_s=3.0,
                          estimate_after_s=3.0)  # side_b1: the estimate the hand-back reads
    return cfg


def test_the_probe_hands_a_loss_back_and_keeps_a_lock(tmp_path):
    """Without the probe the lock-turn law flies a partial loss as a lock and
    circles; with it, the monitor's ``b1`` of the named elevon learns the loss,
    the lane hands back to the paper's loop and holds its heading, while a lock
    (``b1`` learnt near 1) keeps turning.  The same trials either way."""
    runs = {p: api.run_campaign(probe_config(p), jobs=1, progress=False,
                                out=tmp_path / f"run{p}").trials for p in (0.0, 0.03)}
    off, on = (runs[p][runs[p]["variant"] == "sixdof"].set_index(["transition", "trial_id"])
               for p in (0.0, 0.03))
    assert (off["status"] == "ok").all() and (on["status"] == "ok").all()
    loss_off, loss_on = off.loc["elevon_loss"], on.loc["elevon_loss"]
    assert (loss_off["side_correct"] == 1).all()
    assert (loss_off["heading_rms_deg"] > 20).all(), loss_off["heading_rms_deg"]
    assert (loss_on["heading_rms_deg"] < 10).all(), loss_on["heading_rms_deg"]
    lock_off, lock_on = off.loc["elevon_lock"], on.loc["elevon_lock"]
    assert (lock_on["side_b1"] > 0.5).all(), lock_on["side_b1"]  # learnt: not handed back
    assert (lock_off["side_b1"] < 0.2).all()  # without the probe, b0 takes the lock
    # the same turn (the probe moves the monitor's estimate the law reads, a
    # little); a lock handed back would fly the paper's loop instead
    np.testing.assert_allclose(lock_on["heading_rms_deg"], lock_off["heading_rms_deg"],
                               rtol=0.25)


@pytest.mark.parametrize("change, field", [
    ({"plant": {"dof": 3}}, "designs.sixdof.controller: lock_turn flies the 6-DOF plant"),
    ({"monitor": {"enabled": False}}, "designs.sixdof.controller: lock_turn is scheduled "
                                      "on the side monitor"),
    ({"campaign": {"designs": []}, "controller": {"kind": "lock_turn"}, "plant": {"dof": 3}},
     "controller.kind: lock_turn flies the 6-DOF plant"),
    ({"designs": {"sixdof": {"controller": "lock_turn_selected"}}, "plant": {"dof": 3}},
     "designs.sixdof.controller: lock_turn_selected flies the 6-DOF plant"),
    ({"designs": {"sixdof": {"controller": "lock_turn_selected"}},
      "monitor": {"enabled": False}},
     "designs.sixdof.controller: lock_turn_selected is scheduled on the side monitor"),
    ({"monitor": {"turn_offsets_deg": [2.0, -2.0]}}, "turn_offsets_deg: the first must be"),
    ({"monitor": {"turn_step_deg": 0.7}}, "turn_step_deg: must divide"),
    ({"monitor": {"turn_probe_rad": 0.03, "hand_back_after_s": 1.0}},
     "hand_back_after_s: must be at least the probe's length (1.4 s)"),
    ({"monitor": {"rollout_switch_s": [0.2, 3.0]}},
     "rollout_switch_s: each must be below rollout_horizon_s (3 s), got 3"),
    ({"monitor": {"rollout_horizon_s": 3.05, "turn_beyond": "rollout"}},
     "monitor.rollout_horizon_s: must be a positive multiple of model.dt_s"),
    ({"monitor": {"turn_beyond": "rock"}}, "monitor.turn_beyond"),
    ({"monitor": {"rollout_switch_s": [0.2, 0.2]}}, "rollout_switch_s: the times must differ"),
    ({"monitor": {"rollout_switch_s": [0.25], "turn_beyond": "rollout"}},
     "monitor.rollout_switch_s.0: must be a positive multiple of model.dt_s"),
    ({"monitor": {"rollout_substeps": 1, "turn_beyond": "rollout"}},
     "monitor.rollout_substeps: a sub-step of 0.1 s (model.dt_s / rollout_substeps) is "
     "longer than 0.05 s, where RK4 flies the roll mode unstably; use at least 2"),
    ({"monitor": {"rollout_substeps": 1, "turn_beyond": "guarded"}},
     "monitor.rollout_substeps: a sub-step of 0.1 s"),
    ({"monitor": {"turn_beyond": "guarded", "rollout_guard_holds_s": []}},
     "rollout_guard_holds_s: the guard needs at least one time"),
    ({"monitor": {"turn_beyond": "guarded", "rollout_guard_holds_s": [0.5, 0.5]}},
     "rollout_guard_holds_s: the times must differ"),
    ({"monitor": {"turn_beyond": "guarded", "rollout_guard_holds_s": [0.2, 3.0]}},
     "rollout_guard_holds_s: each must be below rollout_horizon_s (3 s), got 3"),
    ({"monitor": {"turn_beyond": "guarded", "rollout_guard_holds_s": [0.25]}},
     "monitor.rollout_guard_holds_s.0: must be a positive multiple of model.dt_s"),
    ({"monitor": {"rollout_guard_bank_margin_deg": 0.1}},
     "monitor.rollout_guard_bank_margin_deg"),
])
def test_configs_that_cannot_fly_it_are_one_line(tmp_path, change, field):
    """A lock-turn design on the longitudinal plant or without the monitor, and
    a bad table grid: one line naming the field, exit 2, nothing written."""
    import yaml
    from click.testing import CliRunner

    from ftc_mc.cli import cli

    cfg = flies_on_config(0.05)
    for section, values in change.items():
        cfg.setdefault(section, {}).update(values)
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["run", str(path), "--quiet", "--out", str(out)])
    assert r.exit_code == 2, r.output
    assert field in r.output and "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not out.exists()


def test_rocking_fields_are_checked_only_when_it_flies():
    """A config that holds the trim is not refused for the rocking law's
    settings (a sub-step over 0.05 s, a switch time off the sampling grid),
    nor one that rocks for the guard's."""
    cfg = flies_on_config(0.05)
    cfg["monitor"].update(rollout_substeps=1, rollout_switch_s=[0.25],
                          rollout_guard_holds_s=[0.25, 0.25])
    api.campaign_config(cfg)
    cfg["monitor"]["turn_beyond"] = "rollout"
    with pytest.raises(Exception, match="monitor.rollout_switch_s.0"):
        api.campaign_config(cfg)
    cfg["monitor"].update(rollout_switch_s=[0.2], rollout_substeps=2)
    api.campaign_config(cfg)  # the guard's holds are read only when it flies
    cfg["monitor"]["turn_beyond"] = "guarded"
    with pytest.raises(Exception, match="rollout_guard_holds_s: the times must differ"):
        api.campaign_config(cfg)


def test_designs_do_not_depend_on_the_blas_threads(tmp_path):
    """The table is computed on one BLAS thread: processes started with one and
    with two OpenBLAS threads design the same table to the bit.  One offset is
    enough to fail: without the limit, the design points at -6 deg alone
    differ by 1.6e-7 between the two (measured, ``_designs`` called
    in both processes)."""
    import os
    import subprocess
    import sys

    code = ("import sys, numpy as np\n"
            "import ftc_mc\n"
            "from ftc_mc.model.presets import PRESETS\n"
            "from ftc_mc.design.lock_turn import lock_turn_designs\n"
            "d = lock_turn_designs(PRESETS['x8-pyfly'].airframe, np.radians([-6.0]))\n"
            "np.savez(sys.argv[1], x=d.x, K=d.K, k=d.k, cmd=d.cmd)\n")
    out = {}
    for n in ("1", "2"):
        env = dict(os.environ, OPENBLAS_NUM_THREADS=n)
        path = tmp_path / f"t{n}.npz"
        subprocess.run([sys.executable, "-c", code, str(path)], env=env, check=True)
        out[n] = np.load(path)
    for f in ("x", "K", "k", "cmd"):
        assert np.array_equal(out["1"][f], out["2"][f]), f
