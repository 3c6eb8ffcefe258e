"""The 6-DOF truth step of a trial: the flying wing the paper's scheme flies.

The 6-DOF family's entry into the trial loop
(:func:`ftc_mc.core.longitudinal.trial.advance`): on the ``SIXDOF_PLANT``
path (``core/shared/paths.py``) stage 2 is :func:`sixdof_truth` instead of the
longitudinal truth step.  Everything else of the loop is the paper's: its
14-state longitudinal filter, Table 1, the belief and the controllers keep
their longitudinal model, as they would on a real aircraft, and read the
longitudinal outputs of the 6-DOF aircraft.  Beside them flies a
lateral-directional autopilot (:mod:`ftc_mc.design.lateral`: wings level,
heading hold), whose only command is differential.

One step ``k -> k+1`` on every lane, with the longitudinal commands ``u_k``
(``TrialWork.u``, deviations from the longitudinal trim ``u0``):

1. **Lateral loop.** (A ``controller: lock_turn`` design's lane whose side
   monitor has named an elevon flies the lock-turn law of
   :mod:`ftc_mc.core.sixdof.lockturn` instead: ``u`` is replaced, no
   ``da``, and the named elevon's command carries the law's probe; a lane
   the probe hands back flies this loop again from that step.  A
   ``controller: lock_turn_selected`` design's lane flies the law of the
   side its selection chose, and none hands back on the probe.)
   ``da = -K_lat lat_k``, ``lat_k`` the loop's measured state
   (``LaneState.lat``: bank, side velocity, roll and yaw rates and heading
   measured at ``k``, and its model of the commanded elevon positions).  The
   commands become ``u + u_ff + [0, da, -da]``, each saturated at the command
   limits; ``u_ff`` is the 6-DOF trim's commands
   minus the longitudinal trim's (2e-3 rad of aileron against the propeller
   torque on ``x8-pyfly``).  ``TrialWork.u`` holds the result, so the
   filter and the history see the commands sent to the actuators.  The
   elevon model advances: ``m_{k+1} = a m_k + (1 - a) (u - u_ff)``,
   ``a = exp(-dt / tau_elevon)``.
   With ``controller.coupling: coupled`` (``SixDofTruth.coupled``) a
   lane flying c0 or c1 takes the coupled 6-DOF law instead of ``da``:
   c0 ``u + u_ff - G0 s``, c1 ``u + u_ff - G1(b0, b1) s - g1(b0, b1)``
   (bilinear in the thrust's estimated ``b0, b1`` as the paper's c1, eq.
   44), ``s = [xhat, lat]`` the filter's estimate of the 9 longitudinal
   states and the lateral loop's state. ``G0``, ``G1`` and ``g1`` are the
   coupled laws (:func:`ftc_mc.design.lateral.coupled_lqr`,
   :func:`ftc_mc.design.lateral.coupled_engine_tables`) less the paper's
   c0 and c1, which ``u`` already holds (``ftc_mc/sim/truth.py``,
   ``coupled_controllers``).  The terms are added to the paper's command as
   the commands stage saturated it (with room for a running excitation), and
   the sum is clipped again: where the paper's command saturates, the lane
   flies that clipped sum, not the coupled law's own saturation.
2. **Faults.** The generic fault model and eq. (2) per actuator, as on the
   longitudinal plants (:func:`ftc_mc.core.longitudinal.plant.actuator_effect`:
   delay, limit cycle, runaway, float, rate limit, then
   ``e = b0 + (1 - b1) c - b1 u0``); the absolute command is ``u0 + e`` (a
   lock holds ``b0``).  A left and a right
   elevon fault are different faults here: elevator = (left + right)/2,
   aileron = (left - right)/2 (PyFly's mixing).
3. **Gusts.** The longitudinal Dryden gusts ``u_g, w_g, q_g``
   (:func:`ftc_mc.core.longitudinal.plant.gust_lanes`) and the lateral ones
   ``v_g, p_g, r_g`` (:func:`lateral_gusts`), held over the step.
4. **Plant.** Nonlinear: RK4 of the authors' 6-DOF equations
   (:func:`ftc_mc.core.sixdof.plant.propagate`, ``n_sub`` sub-steps); linear:
   ``x_{k+1} = A x_k + B (u0 + e - u0_6) + B_w wind``.  The process noise
   ``w_k`` (the longitudinal draws) is added to the 6-DOF states of the same
   names; the lateral states get none (turbulence and faults drive them).
5. **Measurements.** The filter's 12 outputs are the 6-DOF outputs of the
   same names (``CAS`` the airspeed, sea level), less the 6-DOF trim outputs,
   plus ``v_k``; the lateral loop's 5 are read the same way plus ``v_lat``.
   The lane's sensor fault applies to the filter's outputs as on the
   longitudinal plants.  The true air data (``va``, ``alpha``) and bank angle
   go to the validity check, and the squared bank and heading deviations are
   summed for their RMS (``TrialRecord.sq_lat``).

Plain-NumPy twin: ``tests/naive_sixdof.py::sixdof_truth_ref``.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ...conventions import (I_B0_THRUST, I_B1_THRUST, LONGITUDINAL,
                            N_U, N_X, N_Z)
from ..jit import kernel
from ..longitudinal.plant import actuator_effect, gust_lanes, schedule_entry, sensor_fault
from .layout import (N_OUTPUT, N_STATE, N_WIND, OUTPUT, SIXDOF_LINEAR, SIXDOF_NONLINEAR,
                     STATE, U_LEFT, U_RIGHT, W_P, W_Q, W_R, W_U, W_V, W_W, X_PHI, X_PSI,
                     Y_ALPHA, Y_VA, sixdof_name)
from .lockturn import LOCK_TURN, hands_back, lock_turn_law, turn_probe
from .loop import (LAT_LEFT, LAT_RIGHT, LATERAL_LOOP, N_LAT, N_LAT_MEASURED,  # noqa: F401
                   elevon_model, loop_command)
from .plant import N_WORK, linear_output, linear_step, outputs, propagate

N_LAT_GUST_STATE = 4
N_LAT_GUST_NOISE = 4
"""Lateral Dryden model (:func:`ftc_mc.model.turbulence.dryden_lateral_model`)."""

SixDofTruth = namedtuple("SixDofTruth", [
    "kind",       # SIXDOF_NONLINEAR or SIXDOF_LINEAR
    "n_sub",      # RK4 sub-steps per control period (nonlinear)
    "dt",         # control period [s]
    "p",          # (N_PARAM,) packed 6-DOF parameters (model/sixdof.pack_parameters)
    "x0",         # (15,) 6-DOF trim state, absolute (the truth is kept as x - x0)
    "y0",         # (19,) trim outputs, absolute
    "u0",         # (3,) 6-DOF trim commands, absolute
    "u_ff",       # (3,) u0 minus the longitudinal trim commands
    "A", "B",     # (15, 15), (15, 3) discrete linear 6-DOF model (linear kind)
    "C",          # (19, 15) its outputs
    "Bw", "Dw",   # (15, 6), (19, 6) its gust input and feed-through
    "turb",       # 0 still air, 1 Dryden gusts
    "Ad", "Bd", "Cd",     # longitudinal Dryden model, as TruthPlant's
    "Adl", "Bdl", "Cdl",  # (4, 4), (4, 4), (3, 4) lateral Dryden model
    "K_lat",      # (7,) lateral gain: da = -K_lat . lat  [rad]
    "coupled",    # 1: c0 and c1 fly the coupled 6-DOF LQR (G0, G1); 0: the separate loops
    "G0",         # (3, 16) coupled c0 minus the paper's c0, on [xhat (9), lat (7)]
    "G1",         # EngineTables: the coupled c1 (Theorem 4.1 on the 6-DOF model) minus
                  # the paper's c1, gains (nb0, nb1, 3, 16) on [xhat, lat] and affine terms
    "a_act",      # exp(-dt / tau_elevon): the loop's elevon model
    "lon_state",  # (9,) int64: the 6-DOF state of each longitudinal state
    "lon_out",    # (12,) int64: the 6-DOF output of each longitudinal output
    "lat_out",    # (5,) int64: the 6-DOF output of each measured lateral state
    "monitor",    # SideMonitor: the side monitor flown beside the scheme (monitor.py)
])
"""The 6-DOF truth plant a trial flies (module docstring); the kernels'
``Flight.plant`` on the ``SIXDOF_PLANT`` path."""

def index_maps():
    """``(lon_state, lon_out, lat_out)`` of :class:`SixDofTruth`: where the
    longitudinal family's states and outputs, and the lateral loop's measured
    states, sit in the 6-DOF state and outputs (by name; ``CAS`` is the
    airspeed, the longitudinal actuator states are the 6-DOF ones)."""
    lon_state = np.array([STATE[sixdof_name(n)] for n in LONGITUDINAL.states],
                         dtype=np.int64)
    lon_out = np.array([OUTPUT[sixdof_name(n)] for n in LONGITUDINAL.outputs],
                       dtype=np.int64)
    lat_out = np.array([OUTPUT[n] for n in LATERAL_LOOP[:N_LAT_MEASURED]], dtype=np.int64)
    return lon_state, lon_out, lat_out


@kernel(inline="always")
def lateral_gusts(pl, eta, glat, wlat, wlat_next):
    """Lateral Dryden gusts of every lane: ``v_g``, ``p_g``, ``r_g`` held over
    the step (``wlat``) and at the next sample (``wlat_next``); the states
    ``glat`` (4, L) advanced with the draws ``eta`` (4, L)."""
    L = glat.shape[1]
    s = np.empty(N_LAT_GUST_STATE)
    for l in range(L):
        for i in range(N_LAT_GUST_STATE):
            s[i] = glat[i, l]
        for r in range(3):
            acc = 0.0
            for j in range(N_LAT_GUST_STATE):
                acc += pl.Cdl[r, j] * s[j]
            wlat[r, l] = acc
        for i in range(N_LAT_GUST_STATE):
            acc = 0.0
            for j in range(N_LAT_GUST_STATE):
                acc += pl.Adl[i, j] * s[j]
            for j in range(N_LAT_GUST_NOISE):
                acc += pl.Bdl[i, j] * eta[j, l]
            glat[i, l] = acc
        for r in range(3):
            acc = 0.0
            for j in range(N_LAT_GUST_STATE):
                acc += pl.Cdl[r, j] * glat[j, l]
            wlat_next[r, l] = acc


@kernel(inline="always")
def wind6(wind, wlat, l, out):
    """The 6-DOF wind of lane ``l`` from the longitudinal (``u_g, w_g, q_g``)
    and lateral (``v_g, p_g, r_g``) gusts."""
    out[W_U] = wind[0, l]
    out[W_W] = wind[1, l]
    out[W_Q] = wind[2, l]
    out[W_V] = wlat[0, l]
    out[W_P] = wlat[1, l]
    out[W_R] = wlat[2, l]


@kernel(internal=True)
def sixdof_truth(plant, scheme, flight, inp, k, st, work, rec):
    """Stage 2 on the 6-DOF plant: lateral loop, faults, gusts, plant and
    measurements over step ``k -> k+1`` on every lane (module docstring).

    Parameters
    ----------
    plant : SixdofPlant
        The path's plant marker (unused: the dispatcher's calling convention).
    scheme : Scheme
        ``controller`` (command limits ``lo_dev``, ``hi_dev``) and
        ``filter.u0`` (the longitudinal trim commands).
    flight : Flight
        ``plant`` a :class:`SixDofTruth`.
    inp : TrialInputs
        Fault schedule, noise (``w``, ``v``, ``v_lat``) and gust draws
        (``eta``, ``eta_lat``), sensor faults.
    k : int
        Step.
    st : LaneState
        ``x`` (15, L) the 6-DOF state (deviation from its trim), ``gust``,
        ``glat``, ``lat`` advanced in place; ``zhold`` as on the other plants.
    work : TrialWork
        Reads and rewrites ``u``; writes ``e``, ``wind``, ``wind_next``,
        ``z``, ``va``, ``alpha``, ``bank``.
    rec : TrialRecord
        ``sq_lat`` summed on the live lanes.
    """
    pl = flight.plant
    ctl = scheme.controller
    u0 = scheme.filter.u0
    L = st.x.shape[1]
    u = work.u
    lag = pl.a_act
    turn = pl.monitor.turn
    turning = scheme.reconfig.kind >= LOCK_TURN and turn.x.shape[1] > 0
    handing = scheme.reconfig.kind == LOCK_TURN  # a selection switches back itself
    b1_row = pl.monitor.A.shape[0] + pl.monitor.B.shape[1]  # the monitor's b1 of actuator 0
    xl = np.empty(N_X + N_LAT)
    du = np.empty(N_U)
    for l in range(L):
        flies_turn = turning and st.mside[l] > 0
        if flies_turn:
            named = st.mside[l] - 1  # the named elevon's command (block code - 1)
            t = k - st.mturn[l]
            b1 = st.mx[b1_row + named, l]
            if handing and hands_back(turn, t, b1, st.mP[b1_row + named, b1_row + named, l]):
                st.mside[l] = -st.mside[l]  # the paper's loop from this step on
                flies_turn = False
        if flies_turn:
            # the monitor's lock estimate holds the probe sent last step; the law
            # is scheduled on the position without it
            p = st.mpos[l] - (1.0 - b1) * turn_probe(turn, t - 1)
            lock_turn_law(turn, pl, st.mside[l] - 2, p, st.mx, work.z, st.lat, l,
                          ctl.lo_dev, ctl.hi_dev, u)
            v = u[named, l] + turn_probe(turn, t)
            u[named, l] = min(ctl.hi_dev[named], max(ctl.lo_dev[named], v))
        else:
            for j in range(N_X):
                xl[j] = st.xa[j, l]
            for j in range(N_LAT):
                xl[N_X + j] = st.lat[j, l]
            loop_command(pl, ctl.lo_dev, ctl.hi_dev, st.cur[l], st.xa[I_B0_THRUST, l],
                         st.xa[I_B1_THRUST, l], xl, du, u, l)
        st.lat[LAT_LEFT, l] = elevon_model(lag, st.lat[LAT_LEFT, l], u[U_LEFT, l],
                                           pl.u_ff[U_LEFT])
        st.lat[LAT_RIGHT, l] = elevon_model(lag, st.lat[LAT_RIGHT, l], u[U_RIGHT, l],
                                            pl.u_ff[U_RIGHT])
    ev = schedule_entry(inp.k_switch, k)
    actuator_effect(u0, ctl.lo_dev, ctl.hi_dev, inp.b0[ev], inp.b1[ev], inp.fp[ev],
                    inp.k_switch[ev], k, pl.dt, work.alpha, st.uhist, st.uprev, u, work.e)
    wlat = np.zeros((3, L))
    wlat_next = np.zeros((3, L))
    if pl.turb != 0:
        gust_lanes(pl, inp.eta[k], st.gust, work.wind, work.wind_next, work)
        lateral_gusts(pl, inp.eta_lat[k], st.glat, wlat, wlat_next)
    x6 = np.empty(N_STATE)
    xn = np.empty(N_STATE)
    cmd = np.empty(N_U)
    wd = np.zeros(N_WIND)
    y = np.empty(N_OUTPUT)
    rk = np.empty((N_WORK, N_STATE))
    w = inp.w[k]
    v = inp.v[k]
    vl = inp.v_lat[k]
    linear = pl.kind == SIXDOF_LINEAR
    for l in range(L):
        for i in range(N_U):
            cmd[i] = u0[i] + work.e[i, l]
        wind6(work.wind, wlat, l, wd)
        if linear:
            linear_step(pl, st.x[:, l], cmd, wd, xn)
            for i in range(N_STATE):
                st.x[i, l] = xn[i]
        else:
            for i in range(N_STATE):
                x6[i] = pl.x0[i] + st.x[i, l]
            propagate(x6, cmd, pl.p, wd, pl.dt, pl.n_sub, rk)
            for i in range(N_STATE):
                st.x[i, l] = x6[i] - pl.x0[i]
        for i in range(pl.lon_state.shape[0]):
            st.x[pl.lon_state[i], l] += w[i, l]
        wind6(work.wind_next, wlat_next, l, wd)
        if linear:
            for r in range(N_OUTPUT):
                y[r] = linear_output(pl, st.x[:, l], wd, r)
        else:
            for i in range(N_STATE):
                x6[i] = pl.x0[i] + st.x[i, l]
            outputs(x6, pl.p, wd, y)
        for r in range(N_Z):
            o = pl.lon_out[r]
            work.z[r, l] = v[r, l] + (y[o] - pl.y0[o])
        for j in range(N_LAT_MEASURED):
            o = pl.lat_out[j]
            st.lat[j, l] = vl[j, l] + (y[o] - pl.y0[o])
        work.va[l] = y[Y_VA]
        work.alpha[l] = y[Y_ALPHA]
        bank = pl.x0[X_PHI] + st.x[X_PHI, l]
        work.bank[l] = bank
        if st.alive[l]:
            rec.sq_lat[0, l] += st.x[X_PHI, l] ** 2
            rec.sq_lat[1, l] += st.x[X_PSI, l] ** 2
    sensor_fault(inp, k, pl.dt, v, st.zhold, work.z)


def elevon_lag(tau: float, dt: float) -> float:
    """``exp(-dt / tau)``: the discrete first-order elevon of the lateral
    loop's model (``tau`` [s], ``dt`` [s])."""
    return math.exp(-dt / tau)
