"""Kernel settings of the 6-DOF side monitor (:mod:`ftc_mc.core.sixdof.monitor`).

The monitor's model is the discrete 6-DOF linear model of the truth plant
(:func:`ftc_mc.model.sixdof.build_sixdof_plant`) on the states of
``layout.MONITOR_STATES`` (its Jacobians, and its prediction unless the
airframe's equations predict); its noise follows the paper's filter:

* ``Q``: ``sigma_qx^2 dt`` on every state and ``sigma_qb^2 dt`` on every fault
  parameter (the paper's ``Q^x``, ``Q^b``, estimator section of the config);
* ``R``: the paper's filter's ``R`` on the 12 longitudinal outputs, and on the
  5 lateral ones the variance of the longitudinal sensor of the same kind
  (:data:`ftc_mc.sim.noise.LATERAL_NOISE_AS`), as the truth draws them;
* ``P0``: ``10 Q`` on the states and the reset variances on the fault
  parameters, as the paper's filter starts (:func:`ftc_mc.sim.estimator.initial_covariance`);
* gust states (``monitor.design_turbulence`` other than ``none``): the
  longitudinal and lateral Dryden models at that level (:func:`gust_block`),
  their ``Q`` block ``B_d B_d^T`` and ``P0`` block their stationary covariance,
  as the truth's gusts start;
* reset variances: the paper's per block (section 3.2.2), the elevon block's
  ``b0`` variance for each elevon's ``b0``;
* prediction (``monitor.prediction``): the linear model, or the airframe's
  equations with ``monitor.substeps`` RK4 steps per period, or those equations
  with the gust states' wind and Jacobians per lane (``extended``; ``wind``
  maps the gust states to the wind); ``auto``: the linear model on the linear
  plant, on the nonlinear one the equations, extended with gust states;
* ``monitor.state_noise_scale`` multiplies ``Q`` (and so ``P0``) on the 6-DOF states.

Imported only on the 6-DOF path (by :func:`ftc_mc.sim.truth.sixdof_truth_plant`).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field

import numpy as np

from ..conventions import LONGITUDINAL
from ..core.sixdof.layout import (COMMAND, LAYOUT, MONITOR_DIRECTIONS, MONITOR_GUST_STATES,
                                  MONITOR_LATERAL, MONITOR_PARAMS, MONITOR_STATES, OUTPUT,
                                  STATE, WIND)
from ..core.sixdof.lockturn import LockTurnTable
from ..core.sixdof.monitor import EXTENDED, SideMonitor


NO_PROBE = dict(probe=0.0, probe_unit=1, check=0, hand_back=0.0, hand_back_sd=0.0)
"""The ``LockTurnTable`` fields of no probe and no hand-back (the same types as a
configured probe's, so that both compile to one signature)."""

NO_ROLLOUT = dict(ro_on=0, ro_steps=1, ro_sub=1, ro_first=np.ones(1, dtype=np.int64),
                  ro_u=np.zeros((2, 1, 2, 2)), ro_env=np.zeros(5), gd_on=0, gd_pairs=0,
                  gd_holds=np.ones(1, dtype=np.int64))
"""The ``LockTurnTable`` fields of no rocking law and no rollout guard
(``monitor.turn_beyond: hold``; the same types as the law's, one signature);
a monitor's table takes the envelope and the sub-steps of its flights
(``ro_env``, ``ro_sub``: the 6-DOF selection's predictions fly the airframe's
equations so) from the config all the same."""

MEASURED = LONGITUDINAL.outputs + MONITOR_LATERAL
"""The monitor's measured outputs in its order (``CAS`` and ``Va`` both the
6-DOF airspeed): the 12 longitudinal ones, then the lateral loop's."""


@dataclass(frozen=True)
class MonitorSpec:
    """What the config sets of the side monitor, in kernel units.

    Attributes
    ----------
    window, min_window, startup, snap : int
        GLR window, shortest change tested, start-up, and the time after the
        first decision at which the estimate is recorded [steps].
    q_x, q_b : float
        Process noise variance per step of each state, each fault parameter.
    r_lon : ndarray, shape (12,)
        Measurement noise variances of the longitudinal outputs (the paper's ``R``).
    r_lat : ndarray, shape (5,)
        Those of the lateral outputs of ``layout.MONITOR_LATERAL``.
    reset_var : ndarray, shape (6,)
        Variance of each fault parameter of ``layout.MONITOR_PARAMS`` after a reset.
    design_turbulence : str
        Dryden level of the gust states (``none``: no gust states).
    altitude_m : float
        Altitude of the Dryden scale lengths [m].
    turn_offsets : tuple of float
        Lock offsets from trim [rad] of the lock-turn table; empty: no design
        flies it.
    turn_measured : bool
        The lock-turn law feeds back the measured states (else the estimate).
    turn_linear : bool
        The lock-turn table is designed on the 6-DOF linear model
        (``monitor.turn_model``, resolved against the truth plant's kind).
    turn_probe : dict
        The lock-turn law's probe and hand-back, by their ``LockTurnTable``
        fields: ``probe`` [rad] (0: off), ``probe_unit`` and ``check`` [steps],
        ``hand_back`` and ``hand_back_sd`` [-].
    nonlinear : bool
        The airframe's equations predict (``monitor.prediction``, resolved
        against the truth plant's kind; ``extended`` too).
    substeps : int
        RK4 sub-steps of that prediction per period.
    extended : bool
        The extended filter (``monitor.prediction: extended``, or ``auto`` on
        the nonlinear plant with gust states; ``nonlinear`` is then True too).
    state_noise_scale : float
        Multiplies the process noise variance ``q_x`` of the 6-DOF states.
    turn_env : tuple
        The validity envelope the lock-turn table's predictions fly in
        (airspeed [m/s], angle of attack and bank [deg], :func:`rocking_table`'s
        ``env``).
    turn_sub : int
        Their RK4 sub-steps per period (``monitor.rollout_substeps``): the
        rocking law's, the guard's and the 6-DOF selection's.
    turn_rollout : dict or None
        The rocking law (``monitor.turn_beyond: rollout`` or ``guarded``):
        ``steps`` (its horizon), ``switches`` (the candidates' switch times)
        [periods], ``sub`` (RK4 sub-steps per period), ``levels`` (the healthy
        elevon's positions), ``env`` (the envelope: airspeed [m/s], angle of
        attack and bank [deg], :func:`rocking_table`'s order), ``holds`` (the
        rollout guard's hold times [periods]; empty: no guard); None: the trim
        is held (``hold``).
    turn_wide : tuple or None
        The lock-turn table's wide design box
        (:func:`ftc_mc.design.lock_turn.envelope_box`): the envelope's
        airspeed [m/s], angle-of-attack [deg] bounds and largest bank [deg],
        and the box's room below that bank [deg]; set for the rollout guard
        (``guarded``) and for a table on the linear model; None: no wide box.
    """

    window: int
    min_window: int
    startup: int
    snap: int
    q_x: float
    q_b: float
    r_lon: np.ndarray
    r_lat: np.ndarray
    reset_var: np.ndarray
    design_turbulence: str = "none"
    altitude_m: float = 100.0
    turn_offsets: tuple = ()
    turn_measured: bool = True
    turn_linear: bool = False
    turn_probe: dict = field(default_factory=lambda: dict(NO_PROBE))
    nonlinear: bool = False
    substeps: int = 5
    extended: bool = False
    state_noise_scale: float = 1.0
    turn_env: tuple = ()
    turn_sub: int = 2
    turn_rollout: dict | None = None
    turn_wide: tuple | None = None


def monitor_spec(cfg, fm, det, lock_turn: bool = False) -> MonitorSpec | None:
    """The side monitor of a campaign or scenario config, or None when it is off.

    Parameters
    ----------
    cfg : Config or ScenarioConfig
    fm : FilterModel
        The paper's filter model (its ``q_diag``, ``r_diag``).
    det : Detection
        The paper's detection (its ``reset_var``: ``[b0_T, b0_elevons, b1_T,
        b1_L, b1_R]``).
    lock_turn : bool
        A design flies ``controller: lock_turn`` or ``lock_turn_selected``: the
        spec carries the lock-turn table's offsets (``monitor.turn_offsets_deg``,
        ``turn_step_deg``).
    """
    from .noise import lateral_noise

    mc = cfg.monitor
    if not mc.enabled:
        return None
    rv = dict(zip(LONGITUDINAL.params, np.asarray(det.reset_var, dtype=float)))
    b0 = {"throttle": rv["b0_thrust"], "left": rv["b0_elevons"], "right": rv["b0_elevons"]}
    b1 = {"throttle": rv["b1_thrust"], "left": rv["b1_left"], "right": rv["b1_right"]}
    reset = np.array([b0[a] for a in MONITOR_DIRECTIONS] + [b1[a] for a in MONITOR_DIRECTIONS])
    r_lon = np.asarray(fm.r_diag, dtype=float).copy()
    env = (cfg.validity.airspeed_min_mps, cfg.validity.airspeed_max_mps,
           cfg.validity.alpha_min_deg, cfg.validity.alpha_max_deg, cfg.validity.bank_max_deg)
    linear = mc.turn_model == "linear" or (mc.turn_model == "auto" and cfg.plant.kind == "linear")
    return MonitorSpec(
        window=cfg.steps(mc.window_s),
        min_window=cfg.steps(mc.min_window_s), startup=cfg.steps(mc.startup_s),
        snap=cfg.steps(mc.estimate_after_s),
        q_x=float(fm.q_diag[0]), q_b=float(fm.q_diag[LONGITUDINAL.n_x]),
        r_lon=r_lon, r_lat=lateral_noise(np.sqrt(r_lon)) ** 2, reset_var=reset,
        design_turbulence=mc.design_turbulence, altitude_m=float(cfg.plant.altitude_m),
        turn_offsets=tuple(np.radians(mc.turn_offsets())) if lock_turn else (),
        turn_measured=mc.turn_feedback == "measured",
        turn_linear=linear,
        turn_probe=dict(probe=float(mc.turn_probe_rad),
                        probe_unit=cfg.steps(mc.turn_probe_unit_s),
                        check=cfg.steps(mc.hand_back_after_s),
                        hand_back=float(mc.hand_back_b1), hand_back_sd=float(mc.hand_back_sd)),
        nonlinear=(mc.prediction in ("nonlinear", "extended") or
                   (mc.prediction == "auto" and cfg.plant.kind == "nonlinear")),
        substeps=int(mc.substeps),
        extended=(mc.prediction == "extended" or
                  (mc.prediction == "auto" and cfg.plant.kind == "nonlinear"
                   and mc.design_turbulence != "none")),
        state_noise_scale=float(mc.state_noise_scale),
        turn_env=env, turn_sub=int(mc.rollout_substeps),
        turn_rollout=None if mc.turn_beyond == "hold" else dict(
            steps=cfg.steps(mc.rollout_horizon_s),
            switches=tuple(cfg.steps(t) for t in mc.rollout_switch_s),
            sub=int(mc.rollout_substeps), levels=int(mc.rollout_elevon_levels),
            env=env,
            holds=(tuple(cfg.steps(t) for t in mc.rollout_guard_holds_s)
                   if mc.turn_beyond == "guarded" else ())),
        turn_wide=((*env, float(mc.rollout_guard_bank_margin_deg))
                   if mc.turn_beyond == "guarded" or linear else None))


def gust_block(six, spec: MonitorSpec, span: float):
    """The gust states of a gust-aware monitor: ``(G, Dg, Ad, Qg, Pg, W)`` with
    ``G = B_w C_d`` (15, 8) their effect on the 6-DOF states, ``Dg = D_w C_d``
    (19, 8) on the outputs, their transition ``Ad`` and noise ``Qg = B_d B_d^T``
    (8, 8), stationary covariance ``Pg`` and wind ``W = C_d`` (6, 8, rows in
    the order of ``layout.LAYOUT.wind``); the longitudinal Dryden model's
    four states first (``u_g, w_g, q_g``), then the lateral one's
    (``v_g, p_g, r_g``), at ``spec.design_turbulence``."""
    from scipy.linalg import block_diag

    from ..model.turbulence import dryden_lateral_model, dryden_model

    V = float(six.trim.V0)
    lon = dryden_model(spec.design_turbulence, V=V, altitude_m=spec.altitude_m, dt=six.dt)
    lat = dryden_lateral_model(spec.design_turbulence, V=V, altitude_m=spec.altitude_m,
                               dt=six.dt, span=span)
    cols = [WIND[n] for n in ("u_g", "w_g", "q_g")], [WIND[n] for n in ("v_g", "p_g", "r_g")]
    W = np.zeros((len(WIND), lon.Cd.shape[1] + lat.Cd.shape[1]))
    W[cols[0], :lon.Cd.shape[1]] = lon.Cd
    W[cols[1], lon.Cd.shape[1]:] = lat.Cd
    G = np.hstack([six.Bw[:, cols[0]] @ lon.Cd, six.Bw[:, cols[1]] @ lat.Cd])
    Dg = np.hstack([six.Dw[:, cols[0]] @ lon.Cd, six.Dw[:, cols[1]] @ lat.Cd])
    return (G, Dg, block_diag(lon.Ad, lat.Ad), block_diag(lon.Bd @ lon.Bd.T, lat.Bd @ lat.Bd.T),
            block_diag(lon.P0, lat.P0), W)


def rocking_table(lo_dev, hi_dev, steps: int, switches, sub: int, env,
                  levels: int = 3, holds=()) -> dict:
    """The ``LockTurnTable`` fields of the rocking law and the rollout guard
    (``ro_*``, ``gd_*``; module docstring of :mod:`ftc_mc.core.sixdof.lockturn`).

    The pairs (throttle, healthy elevon) are the throttle's two limits by
    ``levels`` positions of the healthy elevon evenly spaced from its lower
    to its upper limit (throttle-major); the candidates are each pair held
    for the whole horizon, then, per switch time in ``switches``, every
    ordered pair of two different pairs (first pair-major): ``2 levels (1 +
    len(switches) (2 levels - 1))`` in all.

    Parameters
    ----------
    lo_dev, hi_dev : array_like, shape (3,)
        Command limits less the longitudinal trim ``u0``.
    steps : int
        Horizon [periods].
    switches : sequence of int
        Switch times [periods], each in ``1 .. steps - 1``.
    sub : int
        RK4 sub-steps per period.
    env : sequence of 5 float
        Airspeed min, max [m/s], angle of attack min, max [deg], largest bank [deg].
    levels : int
        Positions of the healthy elevon, at least 2 (its two limits).
    holds : sequence of int
        The rollout guard's hold times [periods], each at least 1 (its
        candidates hold one of the ``2 levels`` held pairs, then fly the LQR);
        empty: no guard.
    """
    from ..design.lock_turn import SIDES, healthy

    lo = np.asarray(lo_dev, dtype=float)
    hi = np.asarray(hi_dev, dtype=float)
    pairs = []
    for s, side in enumerate(SIDES):
        t, h = COMMAND["throttle"], COMMAND[healthy(side)]
        pairs.append([(a, b) for a in (lo[t], hi[t]) for b in np.linspace(lo[h], hi[h], levels)])
    n_p = len(pairs[0])
    order = [(i, i, steps) for i in range(n_p)]
    order += [(i, j, k) for k in switches for i in range(n_p) for j in range(n_p) if i != j]
    ro_u = np.array([[[pairs[s][i], pairs[s][j]] for i, j, _ in order] for s in range(2)])
    return dict(ro_on=1, ro_steps=int(steps), ro_sub=int(sub),
                ro_first=np.array([k for _, _, k in order], dtype=np.int64),
                ro_u=np.ascontiguousarray(ro_u, dtype=np.float64),
                ro_env=np.asarray(env, dtype=np.float64), gd_on=int(bool(len(holds))),
                gd_pairs=n_p if len(holds) else 0,
                gd_holds=np.array(list(holds) or [1], dtype=np.int64))


def lock_turn_table(six, u0: np.ndarray, offsets=(), airframe=None,
                    measured: bool = True, probe=None, rollout=None,
                    wide=None, linear: bool = False) -> LockTurnTable:
    """The kernels' :class:`LockTurnTable` (empty, ``x`` of shape ``(2, 0, 10)``,
    when ``offsets`` is).

    The designs come from :func:`ftc_mc.cache.lock_turn.cached_lock_turn_designs`
    at the 6-DOF trim's airspeed and air-path angle and the model's period;
    states become deviations from the 6-DOF trim on the monitor's rows
    (``layout.MONITOR_STATES``), commands deviations from the longitudinal trim.

    Parameters
    ----------
    six : SixDofPlant
        The 6-DOF model and trim.
    u0 : ndarray, shape (3,)
        The longitudinal trim commands (absolute).
    offsets : sequence of float
        Lock offsets from trim [rad], uniform and ascending.
    airframe : Airframe
        Needed when ``offsets`` is not empty.
    measured : bool
        Feed back the measured outputs of the states the sensors measure
        (``monitor.turn_feedback: measured``); else the monitor's estimate.
    probe : dict, optional
        The table's probe fields (:attr:`MonitorSpec.turn_probe`); default
        :data:`NO_PROBE`.
    rollout : dict, optional
        The table's rocking-law and guard fields (:func:`rocking_table`);
        default :data:`NO_ROLLOUT`.
    wide : DesignBox, optional
        The designs' wide box (:func:`ftc_mc.design.lock_turn.envelope_box`;
        the rollout guard's, and a table's on the linear model), or None.
    linear : bool
        Design on the 6-DOF linear model (``monitor.turn_model: linear``).

    Designs the cache does not hold are computed with a notice on stderr and
    their duration.
    """
    from ..cache.lock_turn import cached_lock_turn_designs
    from ..design.lock_turn import SIDES, healthy, turn_states

    nf = len(turn_states("left"))
    rows = np.array([[MONITOR_STATES.index(n) for n in turn_states(side)] for side in SIDES],
                    dtype=np.int64)
    cmd = np.array([[COMMAND["throttle"], COMMAND[healthy(side)]] for side in SIDES],
                   dtype=np.int64)
    locked = np.array([COMMAND[side] for side in SIDES], dtype=np.int64)
    seen = list(MEASURED) if measured else []
    meas = np.array([[seen.index(n) if n in seen else -1 for n in turn_states(side)]
                     for side in SIDES], dtype=np.int64)
    pr = dict(NO_PROBE if probe is None else probe)
    pr.update(NO_ROLLOUT if rollout is None else rollout)
    off = np.asarray(offsets, dtype=float)
    if off.size == 0:
        z = np.zeros
        return LockTurnTable(lo=z(2), step=1.0, x=z((2, 0, nf)), u=z((2, 0, len(COMMAND))),
                             K=z((2, 0, 2, nf)), k=z((2, 0, 2)), rows=rows, meas=meas,
                             cmd=cmd, locked=locked, steady=z((2, 0)), hold=z(len(COMMAND)),
                             **pr)
    d = cached_lock_turn_designs(airframe, off, float(six.trim.V0),
                                 float(np.degrees(six.trim.gamma0)), six.dt,
                                 stream=sys.stderr, wide=wide, linear=linear)
    ends = [f"{SIDES[s]} {math.degrees(off[i]):+g} deg" for s in range(2) for i in (0, -1)
            if d.steady[s, i]]
    if ends:
        model = "linear model" if linear else "airframe's equations"
        print(f"ftc-mc: note: the lock-turn table ends in a steady flight of the {model} "
              f"({', '.join(ends)}); locks beyond an end fly its design, which does not "
              "hold them: monitor.turn_offsets_deg should reach past the steady band "
              "(docs/findings/sixdof-lock-turn.md)", file=sys.stderr, flush=True)
    idx = np.array([[STATE[n] for n in turn_states(side)] for side in SIDES])
    x = np.stack([d.x[s][:, idx[s]] - six.trim.x0[idx[s]] for s in range(2)])
    c = np.ascontiguousarray
    return LockTurnTable(lo=c(d.lock[:, 0]), step=float(off[1] - off[0]) if off.size > 1
                         else 1.0, x=c(x), u=c(d.cmd - np.asarray(u0, dtype=float)),
                         K=c(d.K), k=c(d.k), rows=rows, meas=meas, cmd=cmd, locked=locked,
                         steady=c(d.steady, dtype=np.float64),
                         hold=c(six.u0 - np.asarray(u0, dtype=float)), **pr)


def side_monitor(six, u_ff: np.ndarray, u_lower, u_upper, lon_out: np.ndarray,
                 spec: MonitorSpec | None, span: float = 0.0,
                 airframe=None) -> SideMonitor:
    """The kernels' :class:`SideMonitor` (off, with empty arrays, if ``spec`` is None).

    Parameters
    ----------
    six : SixDofPlant
        The 6-DOF model (``A``, ``B``, ``C``) at the 6-DOF trim.
    u_ff : ndarray, shape (3,)
        The 6-DOF trim commands less the longitudinal trim ``u0``.
    u_lower, u_upper : array_like, shape (3,)
        Absolute command limits (the bounds of ``b0``, eq. 6).
    lon_out : ndarray of int, shape (12,)
        The 6-DOF output of each longitudinal output
        (:func:`ftc_mc.core.sixdof.truth.index_maps`).
    spec : MonitorSpec or None
    span : float
        Wing span [m] (the lateral Dryden model of a gust-aware monitor).
    airframe : Airframe, optional
        For the lock-turn table (``spec.turn_offsets`` not empty).
    """
    nu = len(LAYOUT.commands)
    if spec is None:
        z = np.zeros
        return SideMonitor(on=0, A=z((0, 0)), B=z((0, nu)), C=z((0, 0)), u0=z(nu),
                           u_ff=z(nu), lo=z(nu), hi=z(nu), P0=z((0, 0)), Q=z((0, 0)), r=z(0),
                           reset_var=z(2 * nu), window=1, min_window=1,
                           startup=0, snap=0, turn=lock_turn_table(six, six.u0 - u_ff),
                           nonlinear=0, states=z(0, dtype=np.int64),
                           outs=z(0, dtype=np.int64), n_sub=1, wind=z((len(WIND), 0)))
    states = np.array([STATE[n] for n in MONITOR_STATES])
    outs = np.concatenate([lon_out, [OUTPUT[n] for n in MONITOR_LATERAL]]).astype(np.int64)
    nx, npar = len(states), len(MONITOR_PARAMS)
    A = six.A[np.ix_(states, states)]
    B = six.B[states]
    C = six.C[np.ix_(outs, states)]
    q = np.concatenate([np.full(nx, spec.q_x * spec.state_noise_scale), np.full(npar, spec.q_b)])
    W = np.zeros((len(WIND), 0))
    P0 = np.diag(np.concatenate([10.0 * q[:nx], spec.reset_var]))
    Q = np.diag(q)
    if spec.design_turbulence != "none":  # the gust states after the 6-DOF ones
        G, Dg, Ad, Qg, Pg, W = gust_block(six, spec, span)
        ng = len(MONITOR_GUST_STATES)
        assert G.shape[1] == ng
        A = np.block([[A, G[states]], [np.zeros((ng, nx)), Ad]])
        B = np.vstack([B, np.zeros((ng, nu))])
        C = np.hstack([C, Dg[outs]])
        ns = nx + ng
        Q = np.zeros((ns + npar, ns + npar))
        Q[:nx, :nx] = np.diag(q[:nx])
        Q[nx:ns, nx:ns] = Qg
        Q[ns:, ns:] = np.diag(q[nx:])
        P0 = np.zeros_like(Q)
        P0[:nx, :nx] = np.diag(10.0 * q[:nx])
        P0[nx:ns, nx:ns] = Pg
        P0[ns:, ns:] = np.diag(spec.reset_var)
    c = np.ascontiguousarray
    u_lower = np.asarray(u_lower, dtype=float)
    u_upper = np.asarray(u_upper, dtype=float)
    u0 = six.u0 - u_ff
    ro = spec.turn_rollout
    rollout = dict(NO_ROLLOUT, ro_env=np.asarray(spec.turn_env, dtype=np.float64),
                   ro_sub=int(spec.turn_sub)) if ro is None else rocking_table(
        u_lower - u0, u_upper - u0, ro["steps"], ro["switches"], ro["sub"], ro["env"],
        ro["levels"], ro.get("holds", ()))
    wide = None
    if spec.turn_wide is not None:
        from ..design.lock_turn import envelope_box

        w = spec.turn_wide
        wide = envelope_box(w[0:2], w[2:4], w[4], bank_margin=w[5])
    return SideMonitor(
        on=1, A=c(A), B=c(B), C=c(C), u0=c(u0, dtype=np.float64),
        u_ff=c(u_ff, dtype=np.float64), lo=c(u_lower), hi=c(u_upper), P0=c(P0), Q=c(Q),
        r=c(np.concatenate([spec.r_lon, spec.r_lat])), reset_var=c(spec.reset_var),
        window=int(spec.window),
        min_window=int(spec.min_window), startup=int(spec.startup), snap=int(spec.snap),
        turn=lock_turn_table(six, u0, spec.turn_offsets, airframe, spec.turn_measured,
                             spec.turn_probe, rollout, wide, spec.turn_linear),
        nonlinear=EXTENDED if spec.extended else int(spec.nonlinear),
        states=c(states, dtype=np.int64), outs=outs, n_sub=int(spec.substeps), wind=c(W))
