"""The 6-DOF side monitor (``ftc_mc/core/sixdof/monitor.py``):
its kernel against a plain-NumPy twin and against filterpy, its direction
projections against their no-fault distribution, and what a campaign makes of
it."""

from __future__ import annotations

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter

from ftc_mc import api
from ftc_mc.campaign.side import SIDE_COLUMNS, side_markdown, side_table
from ftc_mc.sim.lanes import new_state
from ftc_mc.core.longitudinal.workspace import new_trial_work
from ftc_mc.core.sixdof.layout import (MONITOR_DIRECTIONS, MONITOR_GUST_STATES, MONITOR_PARAMS,
                                       MONITOR_STATES)
from ftc_mc.core.sixdof.monitor import EXTENDED, sixdof_monitor, sixdof_monitor_extended
from ftc_mc.core.sixdof.truth import N_LAT
from ftc_mc.sim.lanes import new_record
from ftc_mc.sim.paths import path_of
from ftc_mc.sim.setup import build_setup

from naive_sixdof import SideMonitorRef, equation_outputs, fly_equations

L = 8


def monitor_config(kind="linear", **campaign):
    """A small 6-DOF campaign config (dict), the switch at 2 s."""
    return {"campaign": {"transitions": ["elevon_lock", "right_elevon_lock"], "trials": 8,
                         "seed": 5, "signature": "paper", "chunk_size": 8, **campaign},
            "plant": {"kind": kind, "dof": 6},
            "timing": {"fault_time_s": 2.0, "window_s": 2.0, "duration_s": 5.0}}


@pytest.fixture(scope="module", params=[("none", "linear"), ("moderate", "linear"),
                                        ("none", "nonlinear"), ("moderate", "nonlinear"),
                                        ("none", "extended"), ("moderate", "extended")])
def setup(request):
    """A 6-DOF setup whose monitor models no gusts, or the moderate Dryden
    ones; its prediction linear, the airframe's equations, or the extended
    filter."""
    turbulence, prediction = request.param
    cfg = monitor_config()
    cfg["monitor"] = {"design_turbulence": turbulence, "prediction": prediction}
    return build_setup(api.campaign_config(cfg))


def psd_sqrt(Q):
    """A square root of a positive semidefinite matrix (the gust block may be singular)."""
    lam, V = np.linalg.eigh(Q)
    return V * np.sqrt(np.clip(lam, 0.0, None))


def lanes(setup, mon):
    """A fresh lane state and record for the monitor's kernel."""
    window = mon.window
    st = new_state(L, 14, 1, setup.truth.x0.shape[0], N_LAT, 0, mon.P0.shape[0], window)
    st.alive[:] = True
    st.alive[-1] = False
    rec = new_record(setup, L, 4)
    rec.side_k[:] = -1
    return st, rec


def flown_data(setup, mon, n_steps, rng, faults):
    """Commands and the 17 measurements of lanes flying the monitor's own
    model with its noise (the linear one, or the airframe's equations when
    the monitor predicts with them, its gust states linear, or their wind
    through the equations for the extended filter), each lane's
    actuator ``faults[l]`` (or None) offset by 0.1 rad (throttle 0.1) from the
    switch on."""
    ns, nu = mon.B.shape
    nx = len(MONITOR_STATES)
    x = np.zeros((ns, L))
    u = 0.02 * rng.standard_normal((n_steps, nu, L))
    z = np.zeros((n_steps, mon.C.shape[0], L))
    kf = setup.tim.k_fault
    pl = setup.truth
    for k in range(n_steps):
        d = np.zeros((nu, L))
        if k >= kf:
            for l, a in enumerate(faults):
                if a is not None:
                    d[a, l] = 0.1
        w = psd_sqrt(mon.Q[:ns, :ns]) @ rng.standard_normal((ns, L))
        if mon.nonlinear == EXTENDED:
            xn = mon.A @ x  # the gust rows; the others fly the equations in their wind
            for l in range(L):
                xn[:nx, l] = fly_equations(pl, mon.states, x[:nx, l],
                                           mon.u0 + u[k, :, l] + d[:, l], mon.n_sub,
                                           mon.wind @ x[nx:, l])
            x = xn + w
            y = np.stack([equation_outputs(pl, mon.states, mon.outs, x[:nx, l],
                                           mon.wind @ x[nx:, l]) for l in range(L)], axis=1)
        elif mon.nonlinear:
            xn = mon.A @ x  # the gust rows; the others fly the equations
            for l in range(L):
                xn[:nx, l] = (fly_equations(pl, mon.states, x[:nx, l],
                                            mon.u0 + u[k, :, l] + d[:, l], mon.n_sub)
                              + mon.A[:nx, nx:] @ x[nx:, l])
            x = xn + w
            y = mon.C[:, nx:] @ x[nx:]
            for l in range(L):
                y[:, l] += equation_outputs(pl, mon.states, mon.outs, x[:nx, l])
        else:
            x = mon.A @ x + mon.B @ (u[k] - mon.u_ff[:, None] + d) + w
            y = mon.C @ x
        z[k] = y + np.sqrt(mon.r)[:, None] * rng.standard_normal((mon.C.shape[0], L))
    return u, z


def run_kernel(setup, mon, st, rec, u, z, k, threshold=None):
    """One step of the monitor kernel (``threshold``: the design's GLR
    threshold, ``None`` the config's)."""
    scheme = setup.scheme("paper")
    if threshold is not None:
        scheme = scheme._replace(
            detection=scheme.detection._replace(side_thresholds=np.full(3, threshold)))
    flight = setup.flight._replace(plant=setup.truth._replace(monitor=mon))
    work = new_trial_work(L, 14)
    nz = work.z.shape[0]
    work.u[:] = u[k]
    work.z[:] = z[k, :nz]
    st.lat[:z.shape[1] - nz] = z[k, nz:]
    kernel = sixdof_monitor_extended if mon.nonlinear == EXTENDED else sixdof_monitor
    kernel(path_of(scheme, flight).plant, scheme, flight, k, st, work, rec)


def test_layout_names_the_monitor(setup):
    """The monitor's states, parameters and directions come from the 6-DOF layout;
    a gust-aware monitor appends the 8 Dryden states, modelled as the truth's."""
    assert "y" not in MONITOR_STATES and "x" in MONITOR_STATES and len(MONITOR_STATES) == 14
    mon = setup.truth.monitor
    ns = len(MONITOR_STATES) + (len(MONITOR_GUST_STATES) if mon.A.shape[0] > 14 else 0)
    assert mon.A.shape == (ns, ns) and mon.P0.shape == (ns + 6, ns + 6)
    if ns > 14:  # the gust block starts stationary: Ad Pg Ad^T + Qg = Pg
        Ad, Qg, Pg = mon.A[14:, 14:], mon.Q[14:ns, 14:ns], mon.P0[14:ns, 14:ns]
        np.testing.assert_allclose(Ad @ Pg @ Ad.T + Qg, Pg, rtol=1e-8, atol=1e-12)
        assert not Ad[:4, 4:].any() and not Ad[4:, :4].any()  # two independent models
        assert np.abs(mon.C[:, 14:]).max() > 0  # gusts reach the measured air data

    assert MONITOR_PARAMS == ("b0_throttle", "b0_left", "b0_right", "b1_throttle", "b1_left",
                              "b1_right")
    assert MONITOR_DIRECTIONS == ("throttle", "left", "right")


def test_monitor_matches_its_twin(setup):
    """Every step of every lane against ``naive_sixdof.SideMonitorRef``:
    initialisation, prediction, the 17 sequential updates, projection,
    the three GLR statistics, decisions with their resets, and the record
    (a lane stopped: no record)."""
    mon = setup.truth.monitor
    rng = np.random.default_rng(3)
    n_steps = setup.tim.k_fault + 15
    faults = [1, 2, 0, 1, 2, None, 1, 2]
    u, z = flown_data(setup, mon, n_steps, rng, faults)
    st, rec = lanes(setup, mon)
    # the extended twin takes its Jacobians by differences of Python RK4 steps
    # (about 0.1 s per lane and step): there, one lane of each fault, the
    # fault-free one and the stopped one are compared (the others repeat a fault)
    compared = (0, 1, 2, 5, L - 1) if mon.nonlinear == EXTENDED else tuple(range(L))
    refs = {l: SideMonitorRef(mon, setup.tim.k_fault, setup.truth,
                              setup.scheme("paper").detection.side_thresholds)
            for l in compared}
    # relative errors in the norm: the order of the sums differs; the extended
    # filter's forward differences (step 1e-6) turn the rounding of two
    # implementations of the equations (1e-16) into 1e-10 in its Jacobians,
    # 1e-7 in the estimate after 2 s of the open-loop wing in gusts
    tol = 1e-6 if mon.nonlinear == EXTENDED else 1e-10
    for k in range(n_steps):
        run_kernel(setup, mon, st, rec, u, z, k)
        for l, ref in refs.items():
            ref.step(k, u[k, :, l], z[k, :, l], bool(st.alive[l]))
            assert st.mnow[l] == ref.now, f"this step's decision, step {k}, lane {l}"
            for got, want, what in ((st.mx[:, l], ref.X, "X"), (st.mP[:, :, l], ref.P, "P")):
                err = np.linalg.norm(got - want) / np.linalg.norm(want)
                assert err < tol, f"{what}, step {k}, lane {l}: {err:.1e}"
    for l, ref in refs.items():
        assert (rec.side_k[l], rec.side_block[l], rec.side_pre[l], rec.side_n[l]) == (
            ref.side_k, ref.side_block, ref.side_pre, ref.side_n), l
        np.testing.assert_allclose(rec.mon_b[:, l], ref.b, rtol=10 * tol, atol=1e-12)
        assert (st.mside[l], st.mturn[l], st.mlast[l]) == (ref.side, ref.turn_k, ref.last), l
        np.testing.assert_allclose(st.mpos[l], ref.pos, rtol=10 * tol, atol=1e-12)
    # the stopped lane recorded nothing; without gusts in the data, the faulted
    # live lanes decided, on their own actuator
    assert rec.side_k[-1] == -1 and not rec.mon_b[:, -1].any()
    assert (rec.side_k[:-1] >= 0).any()  # decisions and resets were compared
    if mon.A.shape[0] == len(MONITOR_STATES):
        live = [l for l in range(L - 1) if faults[l] is not None]
        assert all(rec.side_block[l] == faults[l] + 1 for l in live)


def test_monitor_filter_equals_filterpy(setup):
    """Step 0 of the monitor's filter (no decision possible in the start-up)
    against filterpy's ``KalmanFilter`` (batch update: equal to the sequential
    scalar updates for a diagonal ``R``), fault parameters clipped as eq. 6;
    the linear prediction (filterpy's filter is linear)."""
    if setup.truth.monitor.nonlinear:
        pytest.skip("the linear filter: the same case as the linear fixtures'")
    mon = setup.truth.monitor
    rng = np.random.default_rng(8)
    u, z = flown_data(setup, mon, 1, rng, [None] * L)
    z += 0.05 * rng.standard_normal(z.shape)  # innovations that move the fault parameters
    st, rec = lanes(setup, mon)
    run_kernel(setup, mon, st, rec, u, z, 0)
    ns, nu = mon.B.shape
    n = ns + 2 * nu
    for l in range(L):
        kf = KalmanFilter(dim_x=n, dim_z=mon.C.shape[0], dim_u=nu)
        F = np.eye(n)
        F[:ns, :ns] = mon.A
        F[:ns, ns:ns + nu] = mon.B
        F[:ns, ns + nu:] = -mon.B * (u[0, :, l] + mon.u0)
        kf.F, kf.Q, kf.P, kf.x = F, mon.Q.copy(), mon.P0.copy(), np.zeros(n)
        kf.B = np.vstack([mon.B, np.zeros((2 * nu, nu))])
        kf.H = np.hstack([mon.C, np.zeros((mon.C.shape[0], 2 * nu))])
        kf.R = np.diag(mon.r)
        kf.predict(u=u[0, :, l] - mon.u_ff)
        kf.update(z[0, :, l])
        want = kf.x.copy()
        want[ns:ns + nu] = np.clip(want[ns:ns + nu], mon.lo, mon.hi)
        want[ns + nu:] = np.clip(want[ns + nu:], 0.0, 1.0)
        np.testing.assert_allclose(st.mx[:, l], want, rtol=1e-7, atol=1e-10)
        np.testing.assert_allclose(st.mP[:, :, l], kf.P, rtol=1e-7, atol=1e-12)


def test_extended_jacobians_at_trim_are_the_trim_model():
    """The extended filter's Jacobians, taken by the kernel at the trim (the
    estimate's start, commands at the longitudinal trim), against the trim's
    linear model built by ``model/sixdof.py`` (zero-order hold of the
    continuous Jacobians, the gusts through ``B_w C_d``): the predicted
    covariance ``F P0 F^T + Q`` of step 0, read with measurements of no weight,
    equals the trim's within 1 % in the norm, block by block: the 6-DOF
    states' rows against themselves, the gust states and the fault
    parameters (the ``b0`` and ``b1`` columns with ``g = -(u + u0)``)."""
    cfg = monitor_config("nonlinear")
    cfg["plant"]["turbulence"] = "moderate"
    cfg["monitor"] = {"design_turbulence": "moderate"}
    setup = build_setup(api.campaign_config(cfg))
    mon = setup.truth.monitor._replace(r=np.full(setup.truth.monitor.r.shape, 1e30),
                                       startup=10)
    assert mon.nonlinear == EXTENDED and mon.wind.shape[1] > 0
    ns, nu = mon.B.shape
    n = ns + 2 * nu
    F = np.eye(n)
    F[:ns, :ns] = mon.A
    F[:ns, ns:ns + nu] = mon.B
    F[:ns, ns + nu:] = -mon.B * mon.u0
    want = F @ mon.P0 @ F.T + mon.Q
    st, rec = lanes(setup, mon)
    u = np.zeros((1, nu, L))
    z = np.zeros((1, mon.C.shape[0], L))
    run_kernel(setup, mon, st, rec, u, z, 0)
    nx = len(MONITOR_STATES)
    rigid = slice(0, nx)
    for cols in (slice(0, nx), slice(nx, ns), slice(ns, n)):
        w = want[rigid, cols]
        # the block moves from P0: a wrong Jacobian block would show
        assert np.linalg.norm((mon.P0 + mon.Q)[rigid, cols] - w) > 0.1 * np.linalg.norm(w)
        for l in range(L):
            err = np.linalg.norm(st.mP[rigid, cols, l] - w) / np.linalg.norm(w)
            assert err < 1e-2, (cols, l, err)


def test_direction_projections_are_standard_normal_without_fault(setup, request):
    """On data from the monitor's own model with no fault, each direction's
    projection (the GLR's input, read from the window ``mbuf``) is standard
    normal: over 8 lanes x 150 steps x 3 directions its mean lies within 4
    standard errors of 0 and its mean square inside the chi-square (1 degree
    of freedom) 99.99 % interval.  With gust states and the airframe's
    equations predicting it fails (35 steps, expected: known limits, below)."""
    from scipy.stats import chi2

    mon = setup.truth.monitor._replace(startup=0)
    n_steps, transient = 150, 20
    if mon.nonlinear and mon.A.shape[0] > len(MONITOR_STATES):
        # Known limits (docs/findings/sixdof-side-monitor.md, scripts/studies/study_monitor_consistency.py):
        # at the excursions of moderate gusts (bank RMS about 10 deg) the trim
        # Jacobians misstate the covariance (mean square here about 8 over the
        # three directions, 16 on the throttle's); the extended filter's, taken
        # at each estimate, still miss the second-order effect of the uncertain
        # gusts' wind (about 4, and 10 on the throttle's). Strict, so that a fix
        # shows; a diverging filter is an error, not this failure. 3.5 s: the
        # open-loop wing (its Dutch roll unstable) leaves the equations' range
        # within the 15 s.
        request.applymarker(pytest.mark.xfail(
            strict=True, raises=AssertionError,
            reason="the trim Jacobians of the nonlinear prediction do not hold at the "
                   "excursions of moderate gusts" if mon.nonlinear != EXTENDED else
                   "the extended filter's linearisation of the gusts' wind"))
        n_steps, transient = 35, 15
    rng = np.random.default_rng(21)
    u, z = flown_data(setup, mon, n_steps, rng, [None] * L)
    st, rec = lanes(setup, mon)
    d = []
    for k in range(n_steps):
        run_kernel(setup, mon, st, rec, u, z, k, threshold=np.inf)
        if k >= transient:  # past the filter's transient from P0
            d.append(st.mbuf[k % mon.window].copy())
    d = np.array(d)
    assert d.shape[1] == 3
    if not np.isfinite(d[..., :-1]).all():
        raise FloatingPointError("the monitor's projections are not finite")
    N = d[..., :-1].size
    assert abs(d.mean()) < 4.0 / np.sqrt(N)
    lo, hi = chi2.ppf([5e-5, 1 - 5e-5], N) / N
    assert lo < (d[..., :-1] ** 2).mean() < hi


def test_campaign_names_the_locked_elevon(tmp_path):
    """On the 6-DOF linear plant, the monitor names the locked elevon, left or
    right, in every trial flying at the switch, within a second; it makes no
    decision before the switch; the summary and the report show it."""
    res = api.run_campaign(monitor_config(), jobs=1, progress=False, out=tmp_path / "run")
    t = res.trials
    assert set(SIDE_COLUMNS) <= set(t.columns)
    for tr, side in (("elevon_lock", "left"), ("right_elevon_lock", "right")):
        g = t[t["transition"] == tr]
        flying = np.isfinite(g["side_correct"])
        assert flying.sum() >= 6
        assert (g.loc[flying, "side_block"] == side).all(), g["side_block"].tolist()
        assert (g.loc[flying, "side_s"] <= 1.0).all()
    assert (t["side_false"] == 0).all()
    table = side_table(t, 2.0, 2.0)
    assert (table["side_correct_rate"] == 1.0).all()
    md = side_markdown(table)
    assert "the 6-DOF side monitor" in md and "100.0 %" in md
    assert "the 6-DOF side monitor" in (tmp_path / "run" / "summary.md").read_text()
    report = api.build_report([tmp_path / "run"], out=tmp_path / "r.md")
    assert "the 6-DOF side monitor" in report.read_text()


def test_nonlinear_prediction_reads_an_engine_unlock_as_the_engine():
    """On the nonlinear 6-DOF plant, an engine locked at 0.6-0.8 for 10 s
    under the paper's loop, then unlocked: the monitor that predicts with the
    airframe's equations names the throttle or nothing in every trial; the
    linear one, on the same trials, names an elevon in at least 5 of 32 (13
    when written: the propeller's torque and the moments off the trim
    airspeed it does not model; ``docs/findings/sixdof-side-monitor.md``)."""
    named = {}
    for prediction in ("linear", "nonlinear"):
        cfg = monitor_config("nonlinear", transitions=["engine_unlock"], trials=32,
                             chunk_size=32, signature="paper")
        cfg["draws"] = {"engine_lock_range": [0.6, 0.8]}
        cfg["timing"] = {"fault_time_s": 10.0, "window_s": 4.0, "duration_s": 14.0}
        cfg["monitor"] = {"prediction": prediction}
        t = api.run_campaign(cfg, jobs=1, progress=False).trials
        named[prediction] = t["side_block"].isin(["left", "right"]).sum()
        if prediction == "nonlinear":
            assert (t["side_block"] == "throttle").sum() >= 24
    assert named["nonlinear"] == 0 and named["linear"] >= 5, named


def test_prediction_auto_follows_the_truth_plant():
    """``monitor.prediction: auto`` predicts with the linear model on the
    linear plant and with the airframe's equations on the nonlinear one, the
    extended filter when the monitor has gust states; ``linear``,
    ``nonlinear`` and ``extended`` hold on either."""
    for kind, prediction, gusts, want in (
            ("linear", "auto", "none", 0), ("nonlinear", "auto", "none", 1),
            ("linear", "auto", "moderate", 0), ("nonlinear", "auto", "light", EXTENDED),
            ("nonlinear", "linear", "moderate", 0), ("linear", "nonlinear", "none", 1),
            ("nonlinear", "nonlinear", "moderate", 1), ("linear", "extended", "none", EXTENDED)):
        cfg = monitor_config(kind)
        cfg["monitor"] = {"prediction": prediction, "substeps": 3, "design_turbulence": gusts}
        mon = build_setup(api.campaign_config(cfg)).truth.monitor
        assert (mon.nonlinear, mon.n_sub) == (want, 3), (kind, prediction, gusts)


def test_state_noise_scale_scales_only_the_6dof_states():
    """``monitor.state_noise_scale`` multiplies ``Q`` and ``P0`` on the 6-DOF
    states and leaves the gust states' and the fault parameters' alone."""
    mons = []
    for scale in (1.0, 100.0):
        cfg = monitor_config("nonlinear")
        cfg["monitor"] = {"design_turbulence": "moderate", "state_noise_scale": scale}
        mons.append(build_setup(api.campaign_config(cfg)).truth.monitor)
    nx = len(MONITOR_STATES)
    for a in ("Q", "P0"):
        one, hundred = getattr(mons[0], a), getattr(mons[1], a)
        np.testing.assert_allclose(hundred[:nx, :nx], 100.0 * one[:nx, :nx], rtol=1e-15)
        np.testing.assert_array_equal(hundred[nx:, nx:], one[nx:, nx:])
        assert np.diag(one)[:nx].min() > 0.0


def test_monitor_off_and_on_the_longitudinal_plant():
    """``monitor.enabled: false`` leaves the monitor's columns out, and the
    other columns equal to the bit; a longitudinal run has none either."""
    on = api.run_campaign(monitor_config(trials=4), jobs=1, progress=False).trials
    cfg = monitor_config(trials=4)
    cfg["monitor"] = {"enabled": False}
    off = api.run_campaign(cfg, jobs=1, progress=False).trials
    assert not set(SIDE_COLUMNS) & set(off.columns)
    assert on.drop(columns=list(SIDE_COLUMNS)).equals(off)
    cfg = monitor_config(trials=4)
    cfg["plant"]["dof"] = 3
    lon = api.run_campaign(cfg, jobs=1, progress=False).trials
    assert not set(SIDE_COLUMNS) & set(lon.columns)


@pytest.mark.parametrize("field, value, message", [
    ("min_window_s", 3.0, "min_window_s: must not exceed window_s"),
    ("window_s", 1.25, "monitor.window_s: must be a positive multiple of model.dt_s"),
    ("threshold", -1.0, "monitor.threshold"),
    ("prediction", "quadratic", "monitor.prediction"),
    ("state_noise_scale", 0.5, "monitor.state_noise_scale"),
    ("substeps", 0, "monitor.substeps"),
])
def test_bad_monitor_config_is_one_line(tmp_path, field, value, message):
    """A wrong monitor field is one line naming it, exit 2, nothing written."""
    import yaml
    from click.testing import CliRunner

    from ftc_mc.cli import cli

    cfg = monitor_config()
    cfg["monitor"] = {field: value}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    r = CliRunner().invoke(cli, ["run", str(path), "--quiet", "--out", str(out)])
    assert r.exit_code == 2
    assert message in r.output and "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not out.exists()


def test_side_columns_count_false_decisions_only_from_a_fault_free_start():
    """``side_columns``: a decision before the switch is a false alarm in an
    onset row, not in a recover row (its truth is faulted before the switch);
    the first decision after the switch names the actuator within the window
    or misses; a trial stopped before the switch is not judged."""
    from types import SimpleNamespace

    from ftc_mc.campaign.side import side_columns

    i8 = np.int64
    rec = SimpleNamespace(side_k=np.array([25, 40, -1, 22], i8),
                          side_block=np.array([2, 2, 0, 3], i8),
                          side_pre=np.array([1, 0, 2, 0], i8),
                          status=np.zeros(4, i8), stop_k=np.array([-1, -1, -1, 15], i8),
                          mon_b=np.arange(36, dtype=float).reshape(9, 4))
    on = side_columns(rec, 1, True, 20, 10, 0.1)
    off = side_columns(rec, 1, False, 20, 10, 0.1)
    assert on["side_false"].tolist() == [1, 0, 2, 0]
    assert off["side_false"].tolist() == [0, 0, 0, 0]
    np.testing.assert_array_equal(on["side_correct"], [1.0, 0.0, 0.0, np.nan])
    np.testing.assert_allclose(on["side_s"], [0.5, 2.0, np.nan, 0.2])
    assert on["side_block"].tolist() == ["left", "left", "none", "right"]
    np.testing.assert_array_equal(on["side_position"], rec.mon_b[7])


def test_endurance_counts_the_monitors_false_decisions():
    """An endurance run on the 6-DOF plant counts every decision of the side
    monitor as a false alarm, per flight and per design with its exact
    interval; in still air on the linear plant it makes none, and in
    unmodelled moderate turbulence (no gust states) it makes some."""
    cfg = monitor_config()
    res = api.run_endurance(cfg, hours=8 * 20 / 3600, flight_s=20.0, jobs=1, progress=False)
    assert (res.flights["side_decisions"] == 0).all()
    s = res.summary.iloc[0]
    assert s["side_decisions"] == 0 and s["side_decisions_per_hour"] == 0.0
    assert s["side_decisions_per_hour_ci_high"] > 0  # the exact upper bound of 0 events
    assert "side monitor decisions" in res.markdown()
    cfg["plant"]["turbulence"] = "moderate"
    gusty = api.run_endurance(cfg, hours=8 * 20 / 3600, flight_s=20.0, jobs=1, progress=False)
    assert gusty.flights["side_decisions"].sum() > 0
    assert gusty.summary.iloc[0]["side_decisions"] == gusty.flights["side_decisions"].sum()
