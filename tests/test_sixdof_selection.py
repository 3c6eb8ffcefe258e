"""The selection among the four 6-DOF controllers (``ftc_mc/core/sixdof/selection.py``):
eq. 45's prediction and eq. 47's choice against their plain-NumPy twins, the
belief's boxes on the side monitor's six parameters, the terminal costs' order,
the compile path, and a campaign in which the selection flies on after locks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftc_mc import api
from ftc_mc.sim.lanes import new_state
from ftc_mc.core.longitudinal.workspace import new_trial_work
from ftc_mc.core.shared.paths import SELECT_FOUR
from ftc_mc.core.sixdof.lockturn import SELECTED_TURN
from ftc_mc.core.sixdof.selection import N_SELECTED, action_cost, sixdof_select
from ftc_mc.sim.paths import path_of
from ftc_mc.sim.setup import CONTROLLER_KINDS, build_setup

from naive import belief_update_log_ref
from naive_sixdof import action_cost_ref, sixdof_select_ref

TABLE = {"turn_offsets_deg": [-6.0, 2.0], "turn_step_deg": 2.0}
"""A small lock-turn table (the lock-turn loop's tests design the same one)."""


def selected_config(kind="linear", coupling="separate", **campaign):
    """A 6-DOF run with the design ``sel`` (``controller: lock_turn_selected``)."""
    return {"campaign": {"transitions": ["elevon_lock"], "trials": 4, "seed": 5,
                         "signature": "paper", "designs": ["sel"], **campaign},
            "plant": {"kind": kind, "dof": 6}, "monitor": dict(TABLE),
            "controller": {"coupling": coupling},
            "designs": {"sel": {"controller": "lock_turn_selected"}}}


@pytest.fixture(scope="module")
def setups():
    """The linear 6-DOF setup with separate and with coupled laws, and the
    nonlinear one (its predictions fly the airframe's equations)."""
    out = {c: build_setup(api.campaign_config(selected_config(coupling=c)))
           for c in ("separate", "coupled")}
    out["nonlinear"] = build_setup(api.campaign_config(selected_config(kind="nonlinear")))
    return out


def test_the_cli_offers_every_controller():
    """``--controller`` offers the config's controller kinds, no more, no fewer."""
    from typing import get_args

    from ftc_mc.cli import run
    from ftc_mc.config.schema import ControllerKind

    [opt] = [p for p in run.params if p.name == "controller"]
    assert tuple(opt.type.choices) == get_args(ControllerKind)


def test_kind_and_path():
    """The config's ``lock_turn_selected`` is the kernels' kind, and its
    design takes the compile path of its own (the paper's selection is not
    compiled on it); the paper's design beside it keeps its path."""
    assert CONTROLLER_KINDS["lock_turn_selected"] == SELECTED_TURN
    su = build_setup(api.campaign_config(selected_config()))
    sel = su.scheme("sel")
    assert sel.reconfig.kind == SELECTED_TURN
    assert path_of(sel, su.flight).control == SELECT_FOUR
    assert path_of(su.scheme("paper"), su.flight).control != SELECT_FOUR
    # its belief reads the monitor's six parameters, the paper's its five
    assert sel.belief.lo.shape == (4, 6) and su.scheme("paper").belief.lo.shape == (4, 5)
    assert sel.reconfig.JN.shape == (4, N_SELECTED)
    assert sel.reconfig.penalty.shape == (N_SELECTED, N_SELECTED)


@pytest.mark.parametrize("which", ["separate", "coupled", "nonlinear"])
def test_action_cost_matches_its_twin(setups, which):
    """Random states, faults and elevon models, each of the four controllers,
    over a short and a long horizon, on the linear plant's model (separate and
    coupled laws) and on the airframe's equations: the kernel's eq. 45 equals
    the twin's."""
    su = setups[which]
    pl, sch = su.truth, su.scheme("sel")
    rc = sch.reconfig
    rng = np.random.default_rng(3)
    for trial in range(6):
        xm = pl.x0 + rng.normal(0, 0.02, pl.x0.shape[0])
        mlr = rng.normal(0, 0.02, 2)
        b0 = np.concatenate([rng.uniform(0.0, 1.0, 1), rng.normal(0.0, 0.05, 2)])
        b1 = rng.uniform(0.0, 1.0, 3)
        bhat = np.concatenate([b0, b1])
        btrue = bhat if trial % 2 == 0 else np.concatenate([b0 + 0.01, np.clip(b1 - 0.1, 0, 1)])
        for a in range(N_SELECTED):
            for n in (1, 10, 40):
                got = action_cost(pl, sch.controller, sch.engine, rc, a, xm, mlr, bhat, btrue, n)
                want = action_cost_ref(pl, sch.controller, sch.engine, rc, a, xm, mlr, bhat,
                                       btrue, n)
                rtol = 1e-9 if which != "nonlinear" else 1e-7
                np.testing.assert_allclose(got, want, rtol=rtol, err_msg=f"a={a}, n={n}")


def lanes(su, rng, L=8):
    """A lane state and work of ``L`` lanes with random monitor estimates
    (covariances positive definite), beliefs, controllers in use and elevon
    models; lane 5 no longer alive."""
    mon = su.truth.monitor
    n_m = mon.P0.shape[0]
    st = new_state(L, 14, 1, 15, 7, 4, n_m, mon.window)
    ns = mon.A.shape[0]
    for l in range(L):
        st.mx[:ns, l] = rng.normal(0, 0.05, ns)
        st.mx[ns:ns + 3, l] = [rng.uniform(0, 1), *rng.normal(0.0, 0.1, 2)]
        st.mx[ns + 3:, l] = rng.uniform(0, 1, 3)
        G = rng.normal(0, 0.03, (n_m, n_m))
        st.mP[:, :, l] = G @ G.T + 1e-4 * np.eye(n_m)
        b = rng.uniform(0, 1, 4)
        st.belief[:, l] = b / b.sum()
        st.cur[l] = rng.integers(0, N_SELECTED)
        st.mside[l] = st.cur[l] if st.cur[l] >= 2 else 0
        st.mturn[l] = 3 if st.cur[l] >= 2 else -1
        st.lat[:, l] = rng.normal(0, 0.02, 7)
    st.alive[:] = True
    st.alive[[2, 5]] = False
    # lanes 0-3 made to decide: no fault in c1 and in c0 (the penalty keeps
    # each), a left lock flown by c0 and a right lock flown by the left turn
    trim = mon.u0 + mon.u_ff
    for l, cur, side in ((0, 1, 0), (1, 0, 0), (2, 0, 1), (3, 2, 2)):
        st.alive[l] = True
        st.mx[:, l] = 0.0
        st.mP[:, :, l] = 1e-6 * np.eye(n_m)
        if side:
            st.mx[ns + side, l] = trim[side] + 0.03
            st.mx[ns + 3 + side, l] = 0.98
        st.belief[:, l] = 0.25
        st.cur[l] = cur
        st.mside[l] = cur if cur >= 2 else 0
        st.lat[:, l] = 0.0
    work = new_trial_work(L, 14)
    work.u[:] = rng.normal(0, 0.05, (3, L))
    return st, work


def test_selection_matches_its_twin(setups):
    """Every lane's belief on the monitor's parameters and its choice among the
    four (controller, side, start step, lock position) equal the twin's; lanes
    no longer alive keep their controller."""
    su = setups["separate"]
    pl, sch = su.truth, su.scheme("sel")
    rng = np.random.default_rng(11)
    chosen = set()
    for rep in range(4):
        st, work = lanes(su, rng)
        want = sixdof_select_ref(pl, sch, 40, st, work.u)
        sixdof_select(pl, sch, 40, st, work)
        np.testing.assert_allclose(st.belief, want["belief"], rtol=1e-10, atol=1e-300)
        for f in ("cur", "mside", "mturn"):
            np.testing.assert_array_equal(getattr(st, f), want[f], err_msg=f)
        np.testing.assert_allclose(st.mpos, want["mpos"], rtol=1e-12)
        chosen |= set(st.cur[st.alive].tolist())
        # the lanes made to decide: the penalty keeps c1 and c0 with no
        # fault; a left lock switches c0 to c2, a right lock c2 to c3, each
        # turn starting at this step
        np.testing.assert_array_equal(st.cur[:4], [1, 0, 2, 3])
        np.testing.assert_array_equal(st.mside[:4], [0, 0, 2, 3])
        np.testing.assert_array_equal(st.mturn[2:4], [40, 40])
    assert len(chosen) >= 3, chosen  # the test saw the choice move


def test_belief_boxes_per_elevon(setups):
    """The six-parameter boxes are the paper's per actuator: a left elevon
    locked away from trim (its ``b0`` off, ``b1`` near 1) is mode 2, the same
    on the right mode 3, neither with every ``b1`` near 0 and ``b0`` near 0
    (mode 0), and a throttle lock mode 1; the paper's filter cannot tell the
    two elevons' ``b0`` apart (one sum), the monitor's belief can."""
    bs = setups["separate"].scheme("sel").belief
    var = np.full(6, 1e-4)
    flat = np.array([0.25, 0.25, 0.25, 0.25])
    cases = {0: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1: [0.6, 0.0, 0.0, 0.95, 0.0, 0.0],
             2: [0.0, 0.2, 0.0, 0.0, 0.95, 0.0], 3: [0.0, 0.0, 0.2, 0.0, 0.0, 0.95]}
    for mode, bhat in cases.items():
        _, best = belief_update_log_ref(flat, np.eye(4), bs.lo, bs.hi, np.array(bhat), var)
        assert best == mode, (mode, bhat)


def test_terminal_costs_prefer_the_fault_s_controller(setups):
    """``J^N`` (regrets): in each mode the controller made for it costs least
    (c0 nominal, c1 engine, c2 left, c3 right elevon), and under an elevon
    fault flying the other side's turn costs more than the paper's loop."""
    JN = setups["separate"].scheme("sel").reconfig.JN
    assert JN[0, 0] == 0.0
    for mode in (1, 2, 3):
        assert JN[mode, mode] == 0.0, JN
    assert JN[2, 3] > JN[2, 0] > 0.0 and JN[3, 2] > JN[3, 0] > 0.0, JN


def test_selected_design_flies_on(tmp_path):
    """Linear 6-DOF plant, locks within -4 to +1 deg of trim at 5 s: every
    trial of the selected design stays in the envelope to the end (60 s
    after the lock), where the paper's loop on the same trials does not, and
    its belief names the locked side's mode by the end."""
    su = build_setup(api.campaign_config(selected_config()))
    trim = float(su.truth.u0[1])
    lo, hi = trim + math.radians(-4.0), trim + math.radians(1.0)
    cfg = selected_config(transitions=["elevon_lock", "right_elevon_lock"], trials=6,
                          chunk_size=6)
    cfg.update(draws={"elevon_lock_range_rad": [lo, hi]},
               timing={"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 65.0})
    t = api.run_campaign(cfg, jobs=1, progress=False, out=tmp_path / "run").trials
    sel, paper = (t[t["variant"] == v] for v in ("sel", "paper"))
    assert (sel["status"] == "ok").all(), sel["status"].value_counts()
    assert (paper["status"] == "ok").mean() < 1.0
    assert (sel["detected"] == 1).all(), sel[["transition", "detected", "detection_s"]]


def test_only_a_selecting_design_imports_the_selection(tmp_path):
    """A run of the ``lock_turn`` design alone (6-DOF plant) never imports the
    selection's kernels: its compile path does not reach them (a
    run compiles only what it flies)."""
    import json
    import subprocess
    import sys

    cfg = selected_config(signature="none", designs=["six"], trials=2)
    cfg["designs"] = {"six": {"controller": "lock_turn"}}
    code = (
        "import json, sys\n"
        "from ftc_mc import api\n"
        f"api.run_campaign(json.loads({json.dumps(json.dumps(cfg))}), jobs=1, progress=False,"
        f" out={str(tmp_path / 'run')!r})\n"
        "print('selection' if 'ftc_mc.core.sixdof.selection' in sys.modules else 'none')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip().endswith("none"), out
