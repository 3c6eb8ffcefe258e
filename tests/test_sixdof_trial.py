"""The 6-DOF plant in the trial loop: its truth stage against a
plain-NumPy twin, campaigns that run on it, reproducibility across chunks, the
bank-angle stop and the errors of a config that cannot fly it."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from ftc_mc import api
from ftc_mc.cli import cli
from ftc_mc.conventions import LONGITUDINAL, STATUS_BANK
from ftc_mc.core.longitudinal.workspace import new_trial_work
from ftc_mc.core.shared.paths import SIXDOF_PLANT
from ftc_mc.core.sixdof.truth import N_LAT_GUST_NOISE
from ftc_mc.sim.inputs import draw_lateral
from ftc_mc.sim.lanes import N_SQ_LAT
from ftc_mc.sim.setup import build_setup

from naive_sixdof import sixdof_truth_ref
from test_stages import new_rec, random_inputs, random_lanes

L = 8


def sixdof_config(kind="nonlinear", turbulence="moderate", **campaign):
    """A small 6-DOF campaign config (dict)."""
    return {"campaign": {"transitions": ["elevon_lock"], "trials": 16, "seed": 7,
                         "signature": "paper", "chunk_size": 8, **campaign},
            "plant": {"kind": kind, "dof": 6, "turbulence": turbulence},
            "timing": {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 12.0}}


def lateral_state(setup, rng, st, inp, k):
    """``st`` and ``inp`` given the 6-DOF sizes: a random 6-DOF state near
    trim, the lateral loop's state and gusts, and lateral draws."""
    n = setup.truth.x0.shape[0]
    x = 0.02 * rng.standard_normal((n, L)) * np.maximum(np.abs(setup.truth.x0), 1.0)[:, None]
    lat = 0.02 * rng.standard_normal((setup.truth.K_lat.shape[0], L))
    glat = setup.gust_lat_chol @ rng.standard_normal((4, L))
    st = st._replace(x=np.ascontiguousarray(x), lat=lat, glat=glat)
    n_steps = inp.w.shape[0]
    v_lat = np.zeros((n_steps, 5, L))
    eta_lat = np.zeros((n_steps, N_LAT_GUST_NOISE, L))
    for l in range(L):
        v_lat[:, :, l], (eta_lat[:, :, l], _) = draw_lateral(
            l, 3, n_steps, setup.lat_std, setup.gust_lat_chol, N_LAT_GUST_NOISE)
    inp = inp._replace(v_lat=v_lat, eta_lat=eta_lat, g0_lat=np.zeros((4, L)))
    return st, inp


@pytest.mark.parametrize("kind,coupling", [("nonlinear", "separate"), ("linear", "separate"),
                                      ("nonlinear", "coupled")])
def test_sixdof_truth_matches_its_twin(kind, coupling):
    """One truth step of every lane against ``naive_sixdof.sixdof_truth_ref``:
    random states, lateral loop states, gusts, commands at and beyond the
    limits, faults of every kind (the fault model's delay, rate limit, limit
    cycle, runaway and float among them) and sensor faults; with the coupled c0 and
    c1 (``controller.coupling: coupled``) on the lanes flying them (two
    thirds) and the separate loops on the lanes flying c2."""
    from ftc_mc.core.sixdof.truth import sixdof_truth

    cfg = sixdof_config(kind)
    cfg["controller"] = {"coupling": coupling}
    setup = build_setup(api.campaign_config(cfg))
    assert setup.truth.coupled == (coupling == "coupled")
    rng = np.random.default_rng(11)
    scheme = setup.scheme("paper")
    flight = setup.flight
    k = 4
    inp = random_inputs(setup, rng, 8, L)
    st = random_lanes(setup, rng, k, L)
    st, inp = lateral_state(setup, rng, st, inp, k)
    rec = new_rec(setup.tim, L)
    rec = rec._replace(sq_lat=rng.uniform(0, 1, (N_SQ_LAT, L)))
    u = 0.05 * rng.standard_normal((3, L))
    u[:, 0] = [2.0, 1.0, -1.0]  # beyond the limits: saturated
    want = sixdof_truth_ref(scheme, flight, inp, k, st, rec, u)
    sep = sixdof_truth_ref(scheme, flight._replace(plant=flight.plant._replace(coupled=0)),
                           inp, k, st, rec, u)["u"]
    work = new_trial_work(L, inp.xa0.shape[0])
    work.u[:] = u
    sixdof_truth(SIXDOF_PLANT, scheme, flight, inp, k, st, work, rec)
    got = dict(u=work.u, e=work.e, x=st.x, gust=st.gust, glat=st.glat, lat=st.lat,
               z=work.z, va=work.va, alpha=work.alpha, bank=work.bank, sq_lat=rec.sq_lat,
               zhold=st.zhold, uhist=st.uhist, uprev=st.uprev)
    for key, ref in want.items():
        np.testing.assert_allclose(got[key], ref, rtol=1e-10, atol=1e-12, err_msg=key)
    assert np.abs(work.bank).max() > 0  # a bank was flown, and compared
    if coupling == "coupled":  # c0's and c1's lanes differ from the separate loops', c2's not
        coupled_lanes = st.cur <= 1
        assert coupled_lanes.any() and (~coupled_lanes).any()
        assert np.abs(work.u[:, coupled_lanes] - sep[:, coupled_lanes]).max() > 1e-4
        np.testing.assert_allclose(work.u[:, ~coupled_lanes], sep[:, ~coupled_lanes],
                                   rtol=1e-10, atol=1e-12)


def test_sixdof_campaign_is_reproducible_and_summarised(tmp_path):
    """A 6-DOF campaign: the same trials whatever the chunking, the lateral
    columns in the trials and the summary, the bank stop counted."""
    a = api.run_campaign(sixdof_config(chunk_size=16), jobs=1, progress=False)
    b = api.run_campaign(sixdof_config(chunk_size=5), jobs=1, progress=False)
    ta = a.trials.sort_values(["variant", "trial_id"]).reset_index(drop=True)
    tb = b.trials.sort_values(["variant", "trial_id"]).reset_index(drop=True)
    assert ta.equals(tb)
    assert {"bank_rms_deg", "heading_rms_deg"} <= set(ta.columns)
    assert (ta["bank_rms_deg"] > 0).all()
    s = a.summary
    assert "stopped_bank_out_of_bounds" in s.columns
    assert np.isfinite(s["bank_rms_deg"]).all()


@pytest.mark.parametrize("coupling", ["separate", "coupled"])
def test_fault_free_sixdof_flight_holds_wings_level(coupling):
    """Fault-free in still air on the 6-DOF nonlinear plant, the paper's loop
    with the lateral autopilot (or c0 as the coupled 6-DOF LQR) flies 50 s
    with no exit and the bank within a degree (the open-loop Dutch roll is
    unstable: without the lateral loop it diverges in seconds,
    docs/reference/airframes.md)."""
    cfg = sixdof_config(turbulence="none")
    cfg["controller"] = {"coupling": coupling, "kind": "nominal"}
    res = api.run_endurance(cfg, hours=16 * 50 / 3600, flight_s=50.0, jobs=1, progress=False)
    f = res.flights
    assert (f["status"] == "ok").all()
    assert f["bank_rms_deg"].max() < 1.0
    assert f["heading_rms_deg"].max() < 2.0


def test_bank_stop_is_counted():
    """A locked elevon far from trim rolls the flying wing past the bank bound:
    the trial stops with ``bank_out_of_bounds`` (code STATUS_BANK)."""
    cfg = sixdof_config(turbulence="none")
    cfg["draws"] = {"elevon_lock_range_rad": [0.4, 0.45]}
    res = api.run_campaign(cfg, jobs=1, progress=False)
    from ftc_mc.conventions import STATUS_NAMES

    assert (res.trials["status"] == STATUS_NAMES[STATUS_BANK]).sum() > 0


def test_a_linear_model_file_cannot_fly_six_dof(tmp_path):
    """``--dof 6`` with a linear-model file: one line naming the field, exit 2,
    nothing written."""
    model = tmp_path / "m.npz"
    assert CliRunner().invoke(cli, ["model", "--save", str(model)]).exit_code == 0
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", "configs/elevon_lock.yaml", "--airframe",
                                   str(model), "--dof", "6", "--trials", "4", "--out",
                                   str(out)])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "model.airframe" in lines[0] and "dof 6" in lines[0], lines
    assert not out.exists()


def test_sixdof_layout_maps_the_longitudinal_names():
    """Every longitudinal state and output the filter reads is a 6-DOF state
    or output of the same meaning (by name)."""
    from ftc_mc.core.sixdof.layout import LAYOUT
    from ftc_mc.core.sixdof.truth import index_maps

    lon_state, lon_out, lat_out = index_maps()
    assert [LAYOUT.states[i] for i in lon_state] == [
        {"thrust": "throttle", "elevon_left": "left", "elevon_right": "right"}.get(n, n)
        for n in LONGITUDINAL.states]
    assert [LAYOUT.outputs[i] for i in lon_out] == [
        "Va" if n == "CAS" else n for n in LONGITUDINAL.outputs]
    assert [LAYOUT.outputs[i] for i in lat_out] == ["phi", "v", "p", "r", "psi"]


@pytest.mark.parametrize("dof", ["3", "6"])
def test_model_save_writes_matlab_files(tmp_path, dof):
    """``ftc-mc model --save FILE.mat`` writes the same variables as the
    ``.npz``, readable by scipy's MATLAB reader (and, longitudinal, flown back
    by the package's own reader with equal arrays)."""
    import scipy.io

    npz, mat = tmp_path / "m.npz", tmp_path / "m.mat"
    for path in (npz, mat):
        res = CliRunner().invoke(cli, ["model", "--dof", dof, "--save", str(path)])
        assert res.exit_code == 0, res.output
    want = np.load(npz)
    got = scipy.io.loadmat(mat)
    for name in ("A", "B", "C", "Bw", "Dw", "x0", "u0", "y0"):
        np.testing.assert_array_equal(np.squeeze(got[name]), np.squeeze(want[name]))
    if dof == "6":
        assert float(np.squeeze(got["airframe_Jxz"])) == float(want["airframe_Jxz"])
    else:
        from ftc_mc.model.airframe_files import load_linear_model

        a, b = load_linear_model(mat), load_linear_model(npz)
        np.testing.assert_array_equal(a.A, b.A)
        np.testing.assert_array_equal(a.Dw, b.Dw)


def test_a_coupled_c0_cannot_fly_the_longitudinal_plant(tmp_path):
    """``controller.coupling: coupled`` with ``--dof 3``: one line naming
    the field, exit 2, nothing written."""
    import yaml

    cfg = sixdof_config(turbulence="none")
    cfg["controller"] = {"coupling": "coupled"}
    path = tmp_path / "c.yaml"
    path.write_text(yaml.safe_dump(cfg))
    out = tmp_path / "out"
    res = CliRunner().invoke(cli, ["run", str(path), "--dof", "3", "--out", str(out)])
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "controller.coupling" in lines[0] and "dof" in lines[0], lines
    assert not out.exists()
