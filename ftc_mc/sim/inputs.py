"""Trial inputs (:class:`~ftc_mc.core.longitudinal.settings.TrialInputs`) from per-lane schedules.

One builder, :func:`build_inputs`, lays out every kind of flight the kernels
run: a campaign trial (two schedule entries: the initial mode, and the final
mode from the fault step on; see ``Transition.schedule`` in
``ftc_mc/campaign/transitions.py``), a fault-free flight (one nominal entry,
:func:`flight_schedule`) and a scenario (the config's schedule,
:func:`scenario_schedule`).

Random numbers
--------------
Each lane owns its stream, ``numpy.random.default_rng([trial_id, root_seed])``,
and draws from it in this order (:func:`draw_lane`):

1. the fault value, uniform over the transition's range (lock position or
   effectiveness loss ``b1``; for a sensor transition the sensor fault's size,
   and a stuck sensor draws it over [0, 1] and ignores it, so that the other
   draws stay those of the actuator transitions); a fault-free flight draws it too and ignores it,
   so flight ``i`` flies the noise of trial ``i``; a scenario draws none;
2. the process noise, ``n_steps x 9``, scaled by ``setup.q_std``;
3. the measurement noise, ``n_steps x 12``, scaled by ``setup.r_std``;
4. in turbulence only: the gust draws ``eta`` (``n_steps x 4``), then the initial
   gust state ``g0 = gust_chol @ N(0, I_4)``; drawn last so that the still-air
   draws of a lane are the same with and without turbulence.

On the 6-DOF plant (``plant.dof: 6``) a lane also owns a second stream,
``numpy.random.default_rng([trial_id, root_seed, LATERAL_STREAM])``, for what
the longitudinal plants do not have (:func:`draw_lateral`): the noise of the
lateral loop's measured states (``n_steps x 5``), then in turbulence the
lateral gust draws (``n_steps x 4``) and the initial lateral gust state.  So a
6-DOF trial flies the same longitudinal draws as the longitudinal trial of the
same id.

Trial ``i`` of every transition uses the same stream (common random numbers),
and the signature variants run on identical inputs.  A scenario is lane 0 of
its own seed.  Results depend only on the trial ids and the seed, never on the
chunking or the worker count.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..conventions import (ACTUATOR_FAULT_KINDS, ACTUATOR_NAMES, FAULT_PARAM_NEUTRAL,
                           FP_DELAY, FP_FLOAT, FP_FLOAT_ANGLE, FP_FLOAT_GAIN, FP_OSC_AMP,
                           FP_OSC_FREQ, FP_OSC_PHASE, FP_RATE, FP_RUNAWAY, KIND_NONE,
                           LONGITUDINAL, MODE_NAMES, N_FAULT_PARAM, N_U, NO_SENSOR_FAULT,
                           OUTPUT_NAMES, SENSOR_FAULT_KINDS)
from ..core.longitudinal.settings import TrialInputs
from ..model.faults import estimator_params, mode_of

Schedule = namedtuple("Schedule", [
    "k_switch",  # (E,) int64 step from which each entry holds, k_switch[0] == 0
    "b0",        # (E, 3, L) per-actuator truth b0 of each entry (absolute lock position)
    "b1",        # (E, 3, L) per-actuator truth b1 of each entry
    "fp",        # (E, N_FAULT_PARAM, 3, L) the fault model's other parameters, or None:
                 #   neutral (conventions.FAULT_PARAM_NEUTRAL) throughout
    "kind",      # (E, 3, L) int64 conventions.ACTUATOR_FAULT_KINDS code of each
                 #   actuator's fault, KIND_NONE when healthy; or None: from b0, b1
    "mode",      # (E, L) int64 truth mode of each entry, or None: the box that holds b1
], defaults=(None, None, None))
"""Per-lane fault schedule: the truth in force from each switch step on."""

LaneDraws = namedtuple("LaneDraws", [
    "fault",  # (L,) the fault value of each lane (NaN when none was drawn)
    "w",      # (n_steps, 9, L) process noise, scaled
    "v",      # (n_steps, 12, L) measurement noise, scaled
    "eta",    # (n_steps, 4, L) gust draws, or (0, 4, L) in still air
    "g0",     # (4, L) initial gust states (zeros in still air)
    "v_lat",    # (n_steps, 5, L) lateral measurement noise, or (0, 5, L) (3 DOF)
    "eta_lat",  # (n_steps, 4, L) lateral gust draws, or (0, 0, L) (3 DOF)
    "g0_lat",   # (4, L) initial lateral gust states, or (0, L) (3 DOF)
])
"""Every random number of a chunk of lanes (module docstring)."""

SensorFaults = namedtuple("SensorFaults", [
    "out",   # (L,) int64 output index, or conventions.NO_SENSOR_FAULT
    "kind",  # (L,) int64 conventions.SENSOR_* kind
    "size",  # (L,) bias [unit], drift [unit/s], noise factor [-]; unused when stuck
    "k",     # (L,) int64 onset step
])
"""Per-lane sensor faults (``TrialInputs.sensor_*``, ``core/longitudinal/plant.py``)."""

LATERAL_STREAM = 6
"""Third key of a lane's lateral stream (module docstring)."""

FLIGHT_FAULT_RANGE = (0.0, 1.0)
"""Range of the fault value a fault-free flight draws and ignores."""


def trial_stream(trial_id: int, seed: int) -> np.random.Generator:
    """The random stream of trial ``trial_id`` under the root seed ``seed``."""
    return np.random.default_rng([int(trial_id), seed])


def draw_lane(rng: np.random.Generator, n_steps: int, q_std: np.ndarray, r_std: np.ndarray,
              gust_chol=None, fault_range=None):
    """One lane's draws from its stream, in the order of the module docstring.

    Parameters
    ----------
    rng : numpy.random.Generator
        The lane's stream (:func:`trial_stream`).
    n_steps : int
    q_std : ndarray, shape (9,)
        Process-noise standard deviations.
    r_std : ndarray, shape (12,)
        Measurement-noise standard deviations.
    gust_chol : ndarray, shape (4, 4), optional
        Cholesky factor of the stationary Dryden state covariance
        (:class:`~ftc_mc.model.turbulence.DrydenModel`); ``None`` in still air.
    fault_range : (float, float), optional
        Uniform range of the fault value; ``None``: no fault value is drawn.

    Returns
    -------
    value : float
        The fault value (NaN without ``fault_range``).
    w : ndarray, shape (n_steps, 9)
    v : ndarray, shape (n_steps, 12)
    gust : tuple or None
        ``(eta, g0)`` of shapes (n_steps, 4) and (4,); ``None`` in still air.
    """
    value = np.nan if fault_range is None else rng.uniform(*fault_range)
    w = rng.standard_normal((n_steps, 9)) * q_std
    v = rng.standard_normal((n_steps, 12)) * r_std
    gust = None
    if gust_chol is not None:
        eta = rng.standard_normal((n_steps, 4))
        gust = eta, gust_chol @ rng.standard_normal(4)
    return value, w, v, gust


def lateral_arrays(setup, n: int, L: int):
    """Zeroed ``(v_lat, eta_lat, g0_lat)`` of ``L`` lanes: sized for the 6-DOF
    family's lateral loop and gusts (:mod:`ftc_mc.core.sixdof.truth`, imported
    only then), empty on the longitudinal plants."""
    if setup.dof != 6:
        return np.zeros((0, 0, L)), np.zeros((0, 0, L)), np.zeros((0, L))
    from ..core.sixdof.truth import N_LAT_GUST_NOISE, N_LAT_GUST_STATE

    turb = setup.gust_lat_chol is not None
    return (np.zeros((n, len(setup.lat_std), L)),
            np.zeros((n if turb else 0, N_LAT_GUST_NOISE, L)),
            np.zeros((N_LAT_GUST_STATE, L)))


def draw_lateral(trial_id: int, seed: int, n_steps: int, lat_std: np.ndarray,
                 gust_lat_chol=None, n_noise: int = 0):
    """One lane's lateral draws on the 6-DOF plant, from its lateral stream
    (module docstring).

    ``gust_lat_chol`` (4, 4) is the Cholesky factor of the lateral gust states'
    stationary covariance (``None`` in still air), driven by ``n_noise`` draws
    per step.

    Returns
    -------
    v_lat : ndarray, shape (n_steps, 5)
        Noise of the lateral loop's measured states, scaled by ``lat_std``.
    gust : tuple or None
        ``(eta_lat, g0_lat)`` of shapes (n_steps, 4) and (4,); ``None`` in still air.
    """
    rng = np.random.default_rng([int(trial_id), seed, LATERAL_STREAM])
    v_lat = rng.standard_normal((n_steps, len(lat_std))) * lat_std
    gust = None
    if gust_lat_chol is not None:
        eta = rng.standard_normal((n_steps, n_noise))
        gust = eta, gust_lat_chol @ rng.standard_normal(gust_lat_chol.shape[0])
    return v_lat, gust


def draw_lanes(setup, trial_ids, seed: int, fault_range=None) -> LaneDraws:
    """Every lane's draws (:func:`draw_lane`), lane-last.

    Parameters
    ----------
    setup : SimSetup
        Supplies ``tim.n_steps``, ``q_std``, ``r_std`` and ``gust_chol``.
    trial_ids : array_like of int
        One lane per trial id.
    seed : int
        Root seed.
    fault_range : (float, float), optional
        Uniform range of each lane's fault value (none drawn if ``None``).

    Returns
    -------
    LaneDraws
    """
    n, L = setup.tim.n_steps, len(trial_ids)
    fault = np.empty(L)
    w = np.empty((n, 9, L))
    v = np.empty((n, 12, L))
    turbulent = setup.gust_chol is not None
    eta = np.zeros((n if turbulent else 0, 4, L))
    g0 = np.zeros((4, L))
    six = setup.dof == 6
    v_lat, eta_lat, g0_lat = lateral_arrays(setup, n, L)
    for l, tid in enumerate(trial_ids):
        fault[l], w[:, :, l], v[:, :, l], gust = draw_lane(
            trial_stream(tid, seed), n, setup.q_std, setup.r_std, setup.gust_chol,
            fault_range)
        if gust is not None:
            eta[:, :, l], g0[:, l] = gust
        if six:
            v_lat[:, :, l], gust_lat = draw_lateral(tid, seed, n, setup.lat_std,
                                                    setup.gust_lat_chol, eta_lat.shape[1])
            if gust_lat is not None:
                eta_lat[:, :, l], g0_lat[:, l] = gust_lat
    return LaneDraws(fault=fault, w=w, v=v, eta=eta, g0=g0, v_lat=v_lat, eta_lat=eta_lat,
                     g0_lat=g0_lat)


def entry_modes(schedule: Schedule, beta) -> np.ndarray:
    """Mode of every schedule entry and lane, shape (E, L): the schedule's own
    ``mode`` when it has one, else the box that holds its ``b1`` (:func:`mode_of`)."""
    if schedule.mode is not None:
        return np.asarray(schedule.mode, dtype=np.int64)
    return np.stack([mode_of(b1, *beta) for b1 in schedule.b1])


def neutral_params(E: int, L: int) -> np.ndarray:
    """The fault model's parameters of ``E`` entries of ``L`` lanes with every
    actuator following eq. (2) alone (:data:`FAULT_PARAM_NEUTRAL`), shape
    (E, N_FAULT_PARAM, 3, L)."""
    fp = np.empty((E, N_FAULT_PARAM, N_U, L))
    fp[:] = np.asarray(FAULT_PARAM_NEUTRAL)[None, :, None, None]
    return fp


def schedule_kinds(schedule: Schedule) -> np.ndarray:
    """Kind code of every entry, actuator and lane, shape (E, 3, L): the
    schedule's own ``kind``, else ``lock`` where ``b1 = 1``, ``loss`` where
    ``0 < b1 < 1`` and :data:`KIND_NONE` where healthy."""
    if schedule.kind is not None:
        return np.asarray(schedule.kind, dtype=np.int64)
    b1 = np.asarray(schedule.b1)
    return np.where(b1 >= 1.0, ACTUATOR_FAULT_KINDS.index("lock"),
                    np.where(b1 > 0.0, ACTUATOR_FAULT_KINDS.index("loss"),
                             KIND_NONE)).astype(np.int64)


def build_inputs(setup, schedule: Schedule, draws: LaneDraws,
                 sensor: "SensorFaults | None" = None) -> TrialInputs:
    """The kernels' inputs of lanes flying ``schedule`` with ``draws``.

    Each lane starts with its initial mode identified: the belief is one-hot on
    the first entry's mode and the estimate holds its fault parameters.

    Parameters
    ----------
    setup : SimSetup
    schedule : Schedule
    draws : LaneDraws
    sensor : SensorFaults, optional
        Each lane's sensor fault; ``None``: no lane has one.

    Returns
    -------
    TrialInputs
    """
    E, _, L = schedule.b0.shape
    assert schedule.k_switch.shape == (E,) and schedule.k_switch[0] == 0
    fp = neutral_params(E, L) if schedule.fp is None else schedule.fp
    assert fp.shape == (E, N_FAULT_PARAM, N_U, L)
    assert draws.w.shape[2] == L
    modes = entry_modes(schedule, setup.beta)
    xa0 = np.zeros((LONGITUDINAL.n_aug, L))
    xa0[LONGITUDINAL.faults] = estimator_params(schedule.b0[0], schedule.b1[0])
    sensor = no_sensor_faults(L) if sensor is None else sensor
    return TrialInputs(k_switch=schedule.k_switch, b0=schedule.b0, b1=schedule.b1,
                       mode_pre=modes[0].copy(), mode_post=modes[-1].copy(), xa0=xa0,
                       P0=setup.P0, w=draws.w, v=draws.v, eta=draws.eta, g0=draws.g0,
                       sensor_out=sensor.out, sensor_kind=sensor.kind,
                       sensor_size=sensor.size, sensor_k=sensor.k, v_lat=draws.v_lat,
                       eta_lat=draws.eta_lat, g0_lat=draws.g0_lat, fp=fp)


def design_inputs(inp: TrialInputs, design) -> TrialInputs:
    """``inp`` as the design ``design`` starts it: its initial covariance, and the
    initial estimate padded with zeros for its extra (gust) states; every array
    C-contiguous (the kernels' one signature).

    The draws, the schedule and the sensor faults are untouched, so every design
    flies the same trials (common random numbers).

    Parameters
    ----------
    inp : TrialInputs
        From :func:`build_inputs` (14-state estimate).
    design : Design
        ``ftc_mc/sim/designs.py``.
    """
    n, L = design.n_aug, inp.xa0.shape[1]
    xa0 = inp.xa0
    if n != xa0.shape[0]:
        xa0 = np.zeros((n, L))
        xa0[:inp.xa0.shape[0]] = inp.xa0
    inp = inp._replace(xa0=xa0, P0=design.P0)
    # one memory layout whatever built the inputs (a sweep's lanes taken by index
    # are not C-contiguous): each layout is another signature, compiled anew
    return type(inp)(*(np.ascontiguousarray(v) for v in inp))


def no_sensor_faults(L: int) -> "SensorFaults":
    """Sensor faults of ``L`` healthy lanes (output -1: the kernel skips them)."""
    return SensorFaults(out=np.full(L, NO_SENSOR_FAULT, dtype=np.int64),
                        kind=np.zeros(L, dtype=np.int64), size=np.zeros(L),
                        k=np.zeros(L, dtype=np.int64))


def sensor_faults(out: int, kind: int, sizes, k_onset: int) -> "SensorFaults":
    """The same sensor fault (output and kind indices, onset step) on every lane,
    with per-lane ``sizes``."""
    sizes = np.asarray(sizes, dtype=float)
    L = len(sizes)
    return SensorFaults(out=np.full(L, out, dtype=np.int64),
                        kind=np.full(L, kind, dtype=np.int64), size=sizes.copy(),
                        k=np.full(L, k_onset, dtype=np.int64))


def flight_schedule(L: int) -> Schedule:
    """Nominal throughout: one entry, every actuator healthy."""
    return Schedule(k_switch=np.zeros(1, dtype=np.int64), b0=np.zeros((1, 3, L)),
                    b1=np.zeros((1, 3, L)))


def flight_inputs(setup, trial_ids, seed: int) -> TrialInputs:
    """Fault-free flights on the streams of the campaign's trials ``trial_ids``."""
    return build_inputs(setup, flight_schedule(len(trial_ids)),
                        draw_lanes(setup, trial_ids, seed, FLIGHT_FAULT_RANGE))


def scenario_schedule(events, u0: np.ndarray, dt: float, u_lower=None,
                      u_upper=None) -> Schedule:
    """The schedule of a scenario (one lane).

    Parameters
    ----------
    events : list of FaultEvent
        A validated ``scenario.schedule`` with its durations written out
        (:func:`ftc_mc.config.schema.expanded_schedule`).
    u0 : ndarray, shape (3,)
        Trim commands: the position of a lock ``at trim``.
    dt : float
        Control period [s].
    u_lower, u_upper : ndarray, shape (3,), optional
        Absolute travel limits: where a hard-over locks (needed only by one).

    Returns
    -------
    Schedule
        With the fault model's parameters, kinds and truth modes of each entry
        when an entry names a kind beyond lock and loss (a kind's truth mode is
        its actuator's); otherwise those of eq. (2) alone, as before.
    """
    k = np.array([int(round(e.time_s / dt)) for e in events], dtype=np.int64)
    E = len(events)
    b0 = np.zeros((E, 3, 1))
    b1 = np.zeros((E, 3, 1))
    beyond = any(e.fault not in ("nominal", "lock", "loss") for e in events)
    fp = neutral_params(E, 1)
    kind = np.full((E, 3, 1), KIND_NONE, dtype=np.int64)
    mode = np.zeros((E, 1), dtype=np.int64)
    for i, e in enumerate(events):
        if e.fault == "nominal":
            continue
        a = ACTUATOR_NAMES.index(e.actuator)
        kind[i, a, 0] = ACTUATOR_FAULT_KINDS.index(e.fault)
        mode[i, 0] = MODE_NAMES.index(e.actuator)
        if e.fault == "lock":
            b1[i, a, 0] = 1.0
            b0[i, a, 0] = u0[a] if e.position == "trim" else float(e.position)
        elif e.fault == "loss":
            b1[i, a, 0] = e.b1
        elif e.fault == "hardover":
            b1[i, a, 0] = 1.0
            b0[i, a, 0] = (u_upper if e.side == "upper" else u_lower)[a]
        elif e.fault == "float":
            fp[i, FP_FLOAT, a, 0] = 1.0
            fp[i, FP_FLOAT_ANGLE, a, 0] = e.float_angle
            fp[i, FP_FLOAT_GAIN, a, 0] = e.float_gain
        elif e.fault == "slow":
            fp[i, FP_RATE, a, 0] = e.rate_limit
        elif e.fault == "delayed":
            fp[i, FP_DELAY, a, 0] = round(e.delay_s / dt)
        elif e.fault == "oscillatory":
            fp[i, FP_OSC_AMP, a, 0] = e.amplitude
            fp[i, FP_OSC_FREQ, a, 0] = e.frequency_hz
            fp[i, FP_OSC_PHASE, a, 0] = e.phase_rad
        elif e.fault == "runaway":
            fp[i, FP_RUNAWAY, a, 0] = e.rate
    if not beyond:
        return Schedule(k_switch=k, b0=b0, b1=b1)
    return Schedule(k_switch=k, b0=b0, b1=b1, fp=fp, kind=kind, mode=mode)


def scenario_inputs(setup, spec) -> TrialInputs:
    """The inputs of a scenario: its schedule, on lane 0 of its seed's stream.

    Parameters
    ----------
    setup : SimSetup
    spec : ScenarioSpec
        The validated ``scenario`` section (schedule, sensor fault and seed).
    """
    plant = setup.plant
    sf = spec.sensor_fault
    sensor = None if sf is None else sensor_faults(
        OUTPUT_NAMES.index(sf.output), SENSOR_FAULT_KINDS.index(sf.kind),
        [0.0 if sf.size is None else sf.size], int(round(sf.time_s / plant.dt)))
    from ..config.schema import expanded_schedule

    return build_inputs(setup, scenario_schedule(expanded_schedule(spec), plant.u0, plant.dt,
                                                 plant.u_lower, plant.u_upper),
                        draw_lanes(setup, [0], spec.seed), sensor)
