"""One flight of the full loop with a fault schedule (paper section 5, Table 4).

One trajectory of the full reconfiguring loop (estimator, belief, controller
selection among c0/c1/c2, excitation) on the truth plant with the config's
fault schedule, kept step by step, under the design ``scenario.design`` (or the
signature variant ``scenario.signature``).  :func:`run_scenario` builds the setup from
the scenario config (``ftc_mc/sim/setup.py``), maps the schedule to the trial
inputs (``ftc_mc/sim/inputs.py``), runs the kernel and returns the time series,
the events (fault switches, resets, excitations, detections, controller
switches) and one row per schedule entry.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from ..config.schema import KIND_FIELDS, ScenarioConfig, expanded_schedule
from ..conventions import LONGITUDINAL, MODE_NAMES, STATUS_NAMES
from ..core.longitudinal.trial import advance
from ..core.longitudinal.workspace import EXC_3211, EXC_3211_START, EXC_DOUBLET, EXC_DOUBLET_START
from ..model.faults import estimator_params, mode_of
from ..sim.compiling import compiled_once
from ..sim.paths import path_of
from ..sim.inputs import entry_modes, scenario_inputs, scenario_schedule
from ..sim.lanes import HISTORY_RESETS, run_alone
from ..sim.setup import SimSetup, build_setup, controller_names, runs_of
from ..paper import PAPER_TIMELINE


@dataclasses.dataclass
class ScenarioResult:
    """Outputs of :func:`run_scenario`.

    Attributes
    ----------
    timeseries : DataFrame
        One row per control step (see :func:`_timeseries` for the columns).
    events : DataFrame
        ``time_s``, ``kind``, ``detail`` of each event.
    segments : DataFrame
        One row per schedule entry: expected mode, detection delay, tracking.
    config : ScenarioConfig
    status : str
        ``ok`` or why the run stopped being trusted (see core/longitudinal/trial.py).
    controller_names : tuple of str
        The name of each controller code the design flew (the ``controller``
        column's values index it): recorded with the result, so figures and
        reports drawn later read what was flown instead of rebuilding it from
        the config with code that may have changed.
    """

    timeseries: pd.DataFrame
    events: pd.DataFrame
    segments: pd.DataFrame
    config: ScenarioConfig
    status: str
    controller_names: tuple


def run_scenario(sc: ScenarioConfig, seed: int | None = None,
                 setup: SimSetup | None = None) -> ScenarioResult:
    """Simulate the scenario.

    Parameters
    ----------
    sc : ScenarioConfig
    seed : int, optional
        Overrides ``scenario.seed``; the noise is ``default_rng([0, seed])``.
    setup : SimSetup, optional
        Prebuilt kernel settings (benchmarks); built from ``sc`` when omitted.

    Returns
    -------
    ScenarioResult
    """
    if seed is not None:
        sc = sc.model_copy(update={"scenario": sc.scenario.model_copy(update={"seed": seed})})
    if setup is None:
        setup = build_setup(sc)
    name = runs_of(sc)[0]
    inp = scenario_inputs(setup, sc.scenario)
    with compiled_once(advance, path_of(setup.scheme(name), setup.flight)):
        rec = run_alone(setup, name, setup.det[name], inp, HISTORY_RESETS, history=True)
    k_sw, b0, b1 = inp.k_switch, inp.b0[:, :, 0], inp.b1[:, :, 0]
    sched = scenario_schedule(expanded_schedule(sc.scenario), setup.plant.u0, setup.plant.dt,
                              setup.plant.u_lower, setup.plant.u_upper)
    modes = entry_modes(sched, setup.beta)[:, 0]
    ts = _timeseries(setup, sc, rec, k_sw, b0, b1)
    events = _events(ts, sc, rec, setup)
    segments = _segments(ts, sc, modes, setup)
    status = STATUS_NAMES[int(rec.status[0])]
    segments["run_status"] = status
    return ScenarioResult(timeseries=ts, events=events, segments=segments, config=sc,
                          status=status, controller_names=tuple(controller_names(sc)))


LATERAL_COLUMNS = ("y", "phi", "psi", "v", "p", "r")
"""6-DOF scenario: the lateral states written as ``<name>_true`` (cross-track
position [m], bank and heading [rad], side velocity [m/s], roll and yaw rates
[rad/s]), deviations from trim."""


def _timeseries(setup, sc, rec, k_sw, b0, b1) -> pd.DataFrame:
    """Columns: time, true and estimated states, tracking errors, true and
    estimated fault parameters with their standard deviations, residuals and
    thresholds, gusts (zero in still air), belief, controller, absolute commands,
    excitation, resets."""
    plant = setup.plant
    dt = plant.dt
    n = rec.hist_x.shape[0]
    t = (np.arange(n) + 1) * dt
    lay = LONGITUDINAL
    cols = {"time_s": t}
    # the truth's row of each longitudinal state: its own on the longitudinal
    # plants, the 6-DOF state of the same name on the 6-DOF one
    rows = setup.truth.lon_state if setup.dof == 6 else range(lay.n_x)
    for i, nm in enumerate(lay.states):
        cols[f"{nm}_true"] = rec.hist_x[:, rows[i], 0]
        cols[f"{nm}_est"] = rec.hist_xa[:, i, 0]
    if setup.dof == 6:  # the lateral motion (deviations from trim)
        from ..core.sixdof.layout import STATE

        for nm in LATERAL_COLUMNS:
            cols[f"{nm}_true"] = rec.hist_x[:, STATE[nm], 0]
    g = plant.trim.gamma0
    ix, iz = lay.state("x"), lay.state("z")
    x, z = cols["x_true"], cols["z_true"]  # the truth's rows of x and z (above)
    cols["along_track_error_m"] = x * math.cos(g) - z * math.sin(g)
    cols["cross_track_error_m"] = x * math.sin(g) + z * math.cos(g)
    cols["x_est_error_m"] = rec.hist_xa[:, ix, 0] - x
    cols["z_est_error_m"] = rec.hist_xa[:, iz, 0] - z
    idx = np.searchsorted(k_sw, np.arange(n), side="right") - 1  # entry in force at step k
    truth = estimator_params(b0.T, b1.T).T  # (entries, parameters)
    for j, nm in enumerate(lay.params):
        cols[f"{nm}_true"] = truth[idx, j]
        cols[f"{nm}_est"] = rec.hist_xa[:, lay.n_x + j, 0]
        cols[f"{nm}_sd"] = np.sqrt(np.maximum(rec.hist_pdiag[:, j, 0], 0.0))
    for j, nm in enumerate(lay.residuals):
        cols[nm] = rec.hist_res[:, j, 0]
    det = setup.det[runs_of(sc)[0]]
    cols["t_q"] = np.full(n, det.t_q)
    cols["t_nx"] = np.full(n, det.t_nx)
    for j, nm in enumerate(("gust_u_mps", "gust_w_mps", "gust_q_radps")):
        cols[nm] = rec.hist_wind[:, j, 0]  # zero in still air
    every = setup.tim.reconf_every
    per = np.clip((np.arange(n) + 1) // every - 1, -1, rec.belief.shape[0] - 1)
    for m, nm in enumerate(MODE_NAMES):
        col = np.where(per >= 0, rec.belief[np.maximum(per, 0), m, 0], np.nan)
        cols[f"belief_{nm}"] = col
    first = np.zeros(4)
    first[int(mode_of(b1[0], *setup.beta))] = 1.0
    for m, nm in enumerate(MODE_NAMES):
        cols[f"belief_{nm}"] = np.where(per >= 0, cols[f"belief_{nm}"], first[m])
    cols["controller"] = np.where(per >= 0, rec.controller[np.maximum(per, 0), 0], 0)
    for i, nm in enumerate(("throttle", "elevon_left", "elevon_right")):
        cols[f"cmd_{nm}"] = plant.u0[i] + rec.hist_u[:, i, 0]
        cols[f"cmd_{nm}_dev"] = rec.hist_u[:, i, 0]
    cols["excitation_doublet"] = rec.hist_exc[:, EXC_DOUBLET, 0]
    cols["excitation_3211"] = rec.hist_exc[:, EXC_3211, 0]
    cols["excitation_doublet_start"] = rec.hist_exc[:, EXC_DOUBLET_START, 0] != 0.0
    cols["excitation_3211_start"] = rec.hist_exc[:, EXC_3211_START, 0] != 0.0
    cols["reset_block"] = rec.hist_block[:, 0]
    cols["schedule_entry"] = idx
    df = pd.DataFrame(cols)
    # steps before k_switch[idx] belong to the previous entry; the commands of
    # step k act during (k dt, (k+1) dt], logged at the end of the step
    return df


def _events(ts: pd.DataFrame, sc: ScenarioConfig, rec, setup) -> pd.DataFrame:
    rows = []
    dt = setup.plant.dt  # a signal applied during step k is logged at (k + 1) dt
    for e in expanded_schedule(sc.scenario):
        params = ", ".join(f"{f}={getattr(e, f)}" for f in KIND_FIELDS[e.fault])
        what = ("nominal" if e.fault == "nominal" else
                f"{e.actuator} {e.fault} " + (f"at {e.position}" if e.fault == "lock"
                                               else f"b1={e.b1:g}" if e.fault == "loss"
                                               else params))
        rows.append((e.time_s, "fault_switch", what))
    sf = sc.scenario.sensor_fault
    if sf is not None:
        size = "" if sf.size is None else f" {sf.size:g}"
        rows.append((sf.time_s, "sensor_fault", f"{sf.output} {sf.kind}{size}"))
    blocks = ts["reset_block"].to_numpy()
    for k in np.flatnonzero(blocks):
        r = ts.iloc[k]
        rows.append((r.time_s, "reset", ("thrust" if blocks[k] == 1 else "elevons")
                     + f" (r_q={r.r_q:.3g}, r_nx={r.r_nx:.3g}, r_nz={r.r_nz:.3g})"))
    for col, name in (("excitation_doublet_start", "doublet"),
                      ("excitation_3211_start", "3211")):
        for k in np.flatnonzero(ts[col].to_numpy()):
            rows.append((ts.time_s.iloc[k] - dt, "excitation", name))
    ctrl = rec.controller[:, 0]
    every = setup.tim.reconf_every
    names = controller_names(sc)
    prev = 0
    for p, c in enumerate(ctrl):
        if c != prev:
            rows.append(((p + 1) * every * dt, "controller_switch",
                         f"{names[prev]} -> {names[c]}"))
            prev = c
    bel = np.stack([ts[f"belief_{m}"].to_numpy() for m in MODE_NAMES], axis=1)
    top = np.argmax(bel, axis=1)
    change = np.flatnonzero(top[1:] != top[:-1]) + 1
    for k in change:
        rows.append((ts.time_s.iloc[k], "mode_estimate", f"most probable: {MODE_NAMES[top[k]]} "
                     f"({bel[k, top[k]]:.3f})"))
    ev = pd.DataFrame(rows, columns=["time_s", "kind", "detail"])
    return ev.sort_values(["time_s", "kind"], kind="stable").reset_index(drop=True)


def _segments(ts: pd.DataFrame, sc: ScenarioConfig, modes, setup) -> pd.DataFrame:
    """Detection delay and tracking per schedule entry."""
    dt = setup.plant.dt
    p_det = sc.scenario.detection_probability
    entries = expanded_schedule(sc.scenario)
    t = ts.time_s.to_numpy()
    bel = np.stack([ts[f"belief_{m}"].to_numpy() for m in MODE_NAMES], axis=1)
    rows = []
    for i, e in enumerate(entries):
        t0 = e.time_s
        t1 = entries[i + 1].time_s if i + 1 < len(entries) else sc.scenario.duration_s
        seg = (t > t0 + 1e-9) & (t <= t1 + 1e-9)
        m = int(modes[i])
        detected = np.nan
        if i > 0 and modes[i] != modes[i - 1]:
            hit = seg & (np.argmax(bel, axis=1) == m) & (bel[:, m] >= p_det)
            if hit.any():
                detected = float(t[np.argmax(hit)] - t0)
        pos = np.hypot(ts["x_true"].to_numpy(), ts["z_true"].to_numpy())
        cross = np.abs(ts["cross_track_error_m"].to_numpy())
        rows.append({"start_s": t0, "end_s": t1, "truth_mode": MODE_NAMES[m],
                     "mode_changed": bool(i > 0 and modes[i] != modes[i - 1]),
                     "detection_s": detected,
                     "paper_detection_s": PAPER_TIMELINE["detection_s"].get(t0, np.nan),
                     "max_cross_track_m": float(np.abs(ts.cross_track_error_m[seg]).max()),
                     "max_along_track_m": float(np.abs(ts.along_track_error_m[seg]).max()),
                     "position_error_end_m": float(pos[seg][-1]),
                     "cross_track_recovery_s": _recovery(cross[seg], dt),
                     "position_recovery_s": _recovery(pos[seg], dt)})
    return pd.DataFrame(rows)


def _recovery(err: np.ndarray, dt: float, tol: float = 1.0) -> float:
    """Time from the segment start after which ``err <= tol`` [m] holds to its end."""
    inside = err <= tol
    if not inside.size or not inside[-1]:
        return np.nan
    out = np.flatnonzero(~inside)
    return float((out[-1] + 1) * dt if out.size else 0.0)
