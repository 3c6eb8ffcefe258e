"""The configuration schema: pydantic models of campaign, sweep and scenario files.

The only validator of user values.  Every field has a documented default (the
paper's value where it gives one); unknown keys, wrong types, NaN/inf,
out-of-range numbers and periods that are not whole sampling periods are
refused with a message that names the field (``section.field: problem``).
What is built from a validated config (:mod:`ftc_mc.sim.setup`) trusts it.
Reading YAML and formatting errors: :mod:`ftc_mc.config.load`.

Each field's docstring is its description: one line (``ftc-mc config show``
prints it beside the value, ``docs/reference/config.md`` is generated from it
by ``scripts/maintenance/make_config_reference.py``); what needs more points to
a notes section of that page.
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Literal

from pydantic import (AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field,
                      field_validator, model_validator)

from ..conventions import (ACTUATOR_NAMES, BIASED_OUTPUTS, EXCITATION_POLICIES,
                           KIND_TRANSITIONS, KINDS_BEYOND, MAX_DELAY_STEPS, OUTPUT_NAMES,
                           PLANT_KINDS, RESETS_NAMES, S3211_UNITS, SENSOR_FAULT_KINDS,
                           SENSOR_PREFIX, STATE_NAMES, TRANSITIONS, TURBULENCE_LEVELS)
from ..errors import UserError
from ..model.source import (DEFAULT_AIRFRAME, check_airframe, check_condition,
                            is_linear_model)


def _no_bool(value):
    """YAML reads yes/no/on/off as booleans: never accept them as numbers."""
    if isinstance(value, bool):
        raise ValueError(f"expected a number, got the boolean {value!r}")
    return value


NoBool = BeforeValidator(_no_bool)
Pos = Annotated[float, NoBool, Field(gt=0, allow_inf_nan=False)]
NonNeg = Annotated[float, NoBool, Field(ge=0, allow_inf_nan=False)]
Fraction = Annotated[float, NoBool, Field(gt=0, lt=1, allow_inf_nan=False)]
Finite = Annotated[float, NoBool, Field(allow_inf_nan=False)]
DoubletAmplitude = Annotated[float, NoBool, Field(gt=0, le=0.5, allow_inf_nan=False)]
"""An engine doublet amplitude [throttle fraction]: at most half the throttle range."""
S3211Amplitude = Annotated[float, NoBool, Field(gt=0, le=0.3, allow_inf_nan=False)]
"""An elevon 3211 amplitude [rad]."""
ControllerKind = Literal["nominal", "reconfiguring", "lock_turn", "lock_turn_selected"]
"""The controllers a design flies (``ControllerConfig.kind``)."""
LOCK_TURN_KINDS = ("lock_turn", "lock_turn_selected")
"""The kinds that fly the lock-turn controllers (6-DOF plant, side monitor on)."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, use_attribute_docstrings=True)


MAX_STEPS = 1_000_000
"""Longest run [control steps] of a trial or scenario."""


_MAY_BE_ZERO = ("excitation.resend_delay_s", "monitor.startup_s", "monitor.estimate_after_s")
"""Periods that may be zero steps."""


def _check_periods(dt: float, periods) -> None:
    """Each ``(name, seconds)`` must be a whole number of sampling periods ``dt``
    (at least one, except those of :data:`_MAY_BE_ZERO`) and at most 1e9 of them."""
    for name, value in periods:
        steps = value / dt
        if not math.isfinite(steps) or steps > 1e9:
            raise ValueError(f"{name}: {value:g} s is more than 1e9 steps of "
                             f"model.dt_s ({dt:g} s)")
        if abs(steps - round(steps)) > 1e-9 * max(1.0, steps) or (
                round(steps) < 1 and name not in _MAY_BE_ZERO):
            raise ValueError(f"{name}: must be a positive multiple of model.dt_s "
                             f"({dt:g} s), got {value:g}")


ROLLOUT_MAX_SUBSTEP_S = 0.05
"""Longest RK4 sub-step of the rocking law's flights [s]: x8-pyfly's roll mode,
-38.5 1/s, gives h lambda = 1.9 there, inside RK4's stability bound of 2.8."""


def _check_rollout(cfg, runs) -> None:
    """The rocking law's RK4 sub-step must be at most :data:`ROLLOUT_MAX_SUBSTEP_S`
    (when ``monitor.turn_beyond`` is ``rollout`` or ``guarded``, or a design of
    ``runs`` flies ``lock_turn_selected``, whose predictions fly the same way)."""
    m = cfg.monitor
    if m.turn_beyond == "hold" and not cfg.selects_four(runs):
        return
    h = cfg.model.dt_s / m.rollout_substeps
    if h > ROLLOUT_MAX_SUBSTEP_S * (1 + 1e-9):
        need = math.ceil(cfg.model.dt_s / ROLLOUT_MAX_SUBSTEP_S - 1e-9)
        raise ValueError(f"monitor.rollout_substeps: a sub-step of {h:g} s (model.dt_s / "
                         f"rollout_substeps) is longer than {ROLLOUT_MAX_SUBSTEP_S:g} s, "
                         f"where RK4 flies the roll mode unstably; use at least {need}")


def _check_length(name: str, duration_s: float, dt: float) -> None:
    """A run of ``duration_s`` must take at most :data:`MAX_STEPS` steps."""
    n_steps = round(duration_s / dt)
    if n_steps > MAX_STEPS:
        raise ValueError(f"{name}: {n_steps} steps is more than 1e6")


def _shared_periods(cfg) -> list:
    """``(name, seconds)`` of the periods in the sections a campaign and a scenario
    share (excitation, controller, validity, monitor; the rocking law's only
    when ``monitor.turn_beyond`` is ``rollout`` or ``guarded``, the guard's
    only when it is ``guarded``)."""
    e = cfg.excitation
    m = cfg.monitor
    periods = [("excitation.doublet_half_period_s", e.doublet_half_period_s),
               ("excitation.s3211_unit_s", e.s3211_unit_s),
               ("excitation.resend_delay_s", e.resend_delay_s),
               ("controller.horizon_s", cfg.controller.horizon_s),
               ("controller.terminal_horizon_s", cfg.controller.terminal_horizon_s),
               ("validity.psd_check_period_s", cfg.validity.psd_check_period_s),
               ("monitor.window_s", m.window_s),
               ("monitor.min_window_s", m.min_window_s),
               ("monitor.startup_s", m.startup_s),
               ("monitor.estimate_after_s", m.estimate_after_s),
               ("monitor.turn_probe_unit_s", m.turn_probe_unit_s),
               ("monitor.hand_back_after_s", m.hand_back_after_s)]
    if m.turn_beyond == "hold":
        return periods
    periods = periods + [("monitor.rollout_horizon_s", m.rollout_horizon_s)] + [
        (f"monitor.rollout_switch_s.{i}", t) for i, t in enumerate(m.rollout_switch_s)]
    if m.turn_beyond != "guarded":
        return periods
    return periods + [(f"monitor.rollout_guard_holds_s.{i}", t)
                      for i, t in enumerate(m.rollout_guard_holds_s)]


def _check_airframe_use(cfg) -> tuple:
    """Refuse the nonlinear truth plant with a linear model (it has no equations)
    and a trim condition the airframe cannot fly; return the airframe's absolute
    command limits ``(lower, upper)``."""
    m = cfg.model
    if cfg.plant.kind == "nonlinear" and is_linear_model(m.airframe):
        raise ValueError(f"plant.kind: nonlinear needs an airframe's equations, but "
                         f"model.airframe is a linear model ({m.airframe}); use a preset "
                         "or an airframe YAML file, or plant.kind: linear")
    for name, d in cfg.designs.items():
        if d.prediction == "nonlinear" and is_linear_model(m.airframe):
            raise ValueError(f"designs.{name}.prediction: nonlinear needs an airframe's "
                             f"equations, but model.airframe is a linear model "
                             f"({m.airframe}); use prediction: linear")
    alpha = (math.radians(cfg.validity.alpha_min_deg),
             math.radians(cfg.validity.alpha_max_deg))
    try:
        return check_condition(m.airframe, m.airspeed_mps, m.gamma_deg, m.dt_s, alpha)
    except UserError as exc:
        raise ValueError(str(exc)) from None


class _Sampled(_Strict):
    """A whole file: its ``model.dt_s`` turns seconds into control steps."""

    def steps(self, seconds: float) -> int:
        """Number of sampling periods in ``seconds``."""
        return int(round(seconds / self.model.dt_s))

    def controller_of(self, design: str) -> str:
        """The controller kind the design ``design`` flies: its own
        ``controller``, else the ``controller`` section's ``kind``."""
        dc = self.designs.get(design)
        return dc.controller if dc is not None and dc.controller else self.controller.kind

    def flies_lock_turn(self, runs) -> bool:
        """Whether a design of ``runs`` flies the lock-turn controllers
        (``controller: lock_turn`` or ``lock_turn_selected``)."""
        return any(self.controller_of(r) in LOCK_TURN_KINDS for r in runs)

    def selects_four(self, runs) -> bool:
        """Whether a design of ``runs`` flies ``controller: lock_turn_selected``."""
        return any(self.controller_of(r) == "lock_turn_selected" for r in runs)


def _check_coupling(cfg, runs) -> None:
    """Coupled c0 and c1 are 6-DOF controllers: on the longitudinal plant
    the field names the mismatch; a design's own LQR weights fly the
    separate laws, and not under a 6-DOF selection."""
    if cfg.controller.coupling == "coupled" and cfg.plant.dof != 6:
        raise ValueError("controller.coupling: coupled flies the 6-DOF plant "
                         f"(plant.dof: 6), got plant.dof {cfg.plant.dof}")
    for name, d in cfg.designs.items():
        if (name in runs and d.weights not in (None, cfg.controller.weights)
                and cfg.controller_of(name) == "lock_turn_selected"):
            raise ValueError(f"designs.{name}.weights: a lock_turn_selected design flies "
                             "the controller section's weights (its selection is designed "
                             "once a run); set controller.weights instead")
    if cfg.controller.coupling == "coupled":
        for name, d in cfg.designs.items():
            if d.weights == "airspeed":
                raise ValueError(f"designs.{name}.weights: airspeed flies with "
                                 "controller.coupling: separate only (the coupled 6-DOF "
                                 "LQR sums the paper's weights with the lateral loop's)")


def _check_lock_turn(cfg, runs) -> None:
    """A ``lock_turn`` controller, and resets from the side monitor, need the
    6-DOF plant and its side monitor; the error names the field that asks
    for it."""
    for r in runs:
        dc = cfg.designs.get(r)
        if dc is not None and dc.resets != "table1":
            if cfg.plant.dof != 6:
                raise ValueError(f"designs.{r}.resets: {dc.resets} reads the 6-DOF "
                                 f"plant's side monitor (plant.dof: 6), got plant.dof "
                                 f"{cfg.plant.dof}")
            if not cfg.monitor.enabled:
                raise ValueError(f"designs.{r}.resets: {dc.resets} reads the side "
                                 "monitor, but monitor.enabled is false")
    for r in runs:
        kind = cfg.controller_of(r)
        if kind not in LOCK_TURN_KINDS:
            continue
        dc = cfg.designs.get(r)
        field = (f"designs.{r}.controller" if dc is not None and dc.controller
                 else "controller.kind")
        if cfg.plant.dof != 6:
            raise ValueError(f"{field}: {kind} flies the 6-DOF plant (plant.dof: 6), "
                             f"got plant.dof {cfg.plant.dof}")
        if not cfg.monitor.enabled:
            raise ValueError(f"{field}: {kind} is scheduled on the side monitor, but "
                             "monitor.enabled is false")


class ModelConfig(_Strict):
    """Airframe, trim point and sampling (paper section 5.1)."""

    airframe: str = DEFAULT_AIRFRAME
    """Preset (`ftc-mc airframes` lists them), airframe YAML file, or linear model (.npz/.mat: linear plant only)."""
    airspeed_mps: Pos = 20.0
    """Trim airspeed [m/s]."""
    gamma_deg: Annotated[float, NoBool, Field(gt=-30, lt=30, allow_inf_nan=False)] = -3.0
    """Trim flight-path angle [deg]."""
    dt_s: Annotated[float, NoBool, Field(gt=0, le=1, allow_inf_nan=False)] = 0.1
    """Control sampling period [s]."""

    @field_validator("airframe")
    @classmethod
    def _airframe(cls, spec: str) -> str:
        if not spec.strip():
            raise ValueError("must name a preset or a file, got an empty string")
        try:
            check_airframe(spec)
        except UserError as exc:
            raise ValueError(str(exc)) from None
        return spec


class PlantConfig(_Strict):
    """Truth plant the trials fly (the estimator and controllers keep the linear model)."""

    kind: Literal[PLANT_KINDS] = "linear"
    """linear: the model of eq. (1), as in the paper; nonlinear: the X8 equations, RK4."""
    substeps: Annotated[int, NoBool, Field(ge=1, le=1000)] = 10
    """RK4 sub-steps per control period of the nonlinear plant (10: 6e-7 m/s error)."""
    turbulence: Literal[TURBULENCE_LEVELS] = "none"
    """MIL-F-8785C Dryden gusts: W20 = 0, 15, 30, 45 kt."""
    altitude_m: Annotated[float, NoBool, Field(ge=3.048, le=304.8, allow_inf_nan=False)] = 100.0
    """Altitude for the Dryden scale lengths [m] (low-altitude model: 10-1000 ft)."""
    dof: Literal[3, 6] = 3
    """3: the longitudinal plane (the paper's); 6: the flying wing, two elevons, a lateral autopilot (docs/reference/config.md#the-6-dof-plant)."""


class EstimatorConfig(_Strict):
    """Filter noise, Table 1 thresholds and mode boxes (sections 3.2-3.3, 5.1)."""

    sigma_qx: Pos = 0.01
    """Process-noise density of the plant states: Q^x = sigma_qx^2 dt I."""
    sigma_qb: Pos = 0.001
    """Random-walk density of the fault parameters: Q^b = sigma_qb^2 dt I."""
    t_q: Pos = 25.0
    """Threshold on r_q (Table 1)."""
    t_nx: Pos = 25.0
    """Threshold on r_nx (Table 1)."""
    beta_engine: Fraction = 0.2
    """b1 of the engine above which the engine counts as faulty."""
    beta_elevon: Fraction = 0.1
    """b1 of an elevon above which it counts as faulty."""
    b0_nominal_engine: Pos = 0.05
    """Half-width of the nominal box of the thrust b0 [-]."""
    b0_nominal_elevon: Pos = 0.05
    """Half-width of the nominal box of the elevon-sum b0 [rad]."""


class ControllerConfig(_Strict):
    """Controllers and their selection (sections 4.1-4.2, 5.1)."""

    kind: ControllerKind = "reconfiguring"
    """nominal: c0 only; reconfiguring: c0/c1/c2 chosen by eqs. 45-47; lock_turn, lock_turn_selected: 6-DOF (docs/reference/config.md#controllers)."""
    discount: Annotated[float, NoBool, Field(gt=0, lt=1, allow_inf_nan=False)] = 0.999
    """Discount factor alpha (< 1: a locked engine needs it, section 4.1.2)."""
    r_lqr: Pos = 0.1
    """R_lqr = r_lqr I_3."""
    horizon_s: Pos = 1.0
    """Prediction horizon H of the selection (eq. 45) [s]."""
    switch_penalty: NonNeg = 0.1
    """Penalty P(c, a) of changing controller (eq. 46; paper 0.1)."""
    terminal_horizon_s: Pos = 100.0
    """Simulated rest of the mission for the terminal costs J^N (eq. 46) [s] (100: the paper's mission)."""
    coupling: Literal["separate", "coupled"] = "separate"
    """6-DOF c0 and c1: separate (the paper's laws and a lateral LQR) or coupled (6-DOF LQRs) (docs/reference/config.md#controllers)."""
    weights: Literal["paper", "airspeed"] = "paper"
    """LQR weights of c0-c2 and J^N: paper (section 5.1) or airspeed (Bryson, scales below); a design's own override (docs/reference/config.md#controllers)."""
    airspeed_scale_mps: Pos = 2.0
    """airspeed weights: largest accepted deviation of the body velocity u, the airspeed's proxy [m/s]."""
    height_scale_m: Pos = 1.0
    """airspeed weights: largest accepted height deviation (the state z) [m]."""
    pitch_scale_deg: Pos = 10.0
    """airspeed weights: largest accepted pitch deviation [deg]."""
    pitch_rate_scale_dps: Pos = 30.0
    """airspeed weights: largest accepted pitch rate [deg/s]."""
    throttle_scale: Pos = 3.0
    """airspeed weights: largest accepted throttle command deviation [-]."""
    elevon_scale_rad: Pos = 0.1
    """airspeed weights: largest accepted elevon command deviation [rad]."""

    @model_validator(mode="after")
    def _weights_and_coupling(self):
        if self.weights == "airspeed" and self.coupling == "coupled":
            raise ValueError("weights: airspeed flies with coupling: separate only (the coupled "
                             "6-DOF LQR sums the paper's weights with the lateral loop's)")
        return self


WEIGHT_SCALES = ("airspeed_scale_mps", "height_scale_m", "pitch_scale_deg",
                 "pitch_rate_scale_dps", "throttle_scale", "elevon_scale_rad")
"""``ControllerConfig`` fields that set the ``airspeed`` weights."""


class ExcitationConfig(_Strict):
    """Excitation signals sent on covariance resets (sections 3.2.3, 4.1.1)."""

    doublet_amplitude: DoubletAmplitude = 0.1
    """Engine doublet amplitude [throttle fraction]."""
    doublet_half_period_s: Pos = 1.0
    """Duration of each half of the doublet [s] (engine time constant 0.3 s)."""
    s3211_amplitude_rad: S3211Amplitude = 0.05
    """Elevon 3211 amplitude [rad], + on the left and - on the right elevon."""
    s3211_unit_s: Pos = 0.2
    """One unit of the 3211 [s] (the signal lasts 7 units)."""
    resend_delay_s: NonNeg = 3.0
    """Delay after a thrust reset before the doublet re-check [s]."""
    resend_b1_threshold: Annotated[float, NoBool, Field(ge=0, le=1, allow_inf_nan=False)] = 0.7
    """Re-send the doublet if the estimated engine b1 exceeds this."""


class NoiseConfig(_Strict):
    """Truth noise as multiples of the filter's Q and R standard deviations."""

    process_scale: NonNeg = 1.0
    """Process-noise standard deviation / the filter's."""
    measurement_scale: NonNeg = 1.0
    """Measurement-noise standard deviation / the filter's."""


class DrawsConfig(_Strict):
    """Per-trial draws (docs/reference/paper-map.md)."""

    engine_lock_range: tuple[Finite, Finite] | None = None
    """Absolute throttle lock position range; null = the command range [0, 1]."""
    elevon_lock_range_rad: tuple[Finite, Finite] | None = None
    """Absolute elevon lock position range [rad] of the left and right rows; null = the command range."""
    loss_b1_range: tuple[Annotated[float, NoBool, Field(ge=0, le=1)],
                         Annotated[float, NoBool, Field(ge=0, le=1)]] = (0.0, 1.0)
    """Uniform range of the effectiveness loss b1."""

    @model_validator(mode="after")
    def _ordered(self):
        for name in ("engine_lock_range", "elevon_lock_range_rad", "loss_b1_range"):
            r = getattr(self, name)
            if r is not None and not r[0] < r[1]:
                raise ValueError(f"{name}: must be [low, high] with low < high, got {list(r)}")
        return self


PosRange = tuple[Pos, Pos]


class KindDrawsConfig(_Strict):
    """Per-trial draws of the fault kinds beyond lock and loss (the
    ``<actuator>_<kind>`` transitions; docs/guides/fault-kinds.md gives each
    range's source).  Every value is uniform over its ``[low, high]``; a sign
    drawn with equal odds where a field says so."""

    elevon_rate_limit_deg_s: PosRange = (5.0, 30.0)
    """slow: the elevon's rate limit [deg/s] (nominal servo: 200 deg/s)."""
    engine_rate_limit_per_s: PosRange = (0.05, 0.3)
    """slow: the throttle's rate limit [1/s] (nominal: about 3 per s from its 0.3 s lag)."""
    delay_s: PosRange = (0.2, 1.0)
    """delayed: the transport delay [s], rounded to whole control periods."""
    elevon_osc_amp_deg: PosRange = (1.0, 5.0)
    """oscillatory: the elevon's limit-cycle amplitude [deg]."""
    engine_osc_amp: PosRange = (0.05, 0.2)
    """oscillatory: the throttle's limit-cycle amplitude [-]."""
    osc_freq_hz: PosRange = (0.2, 2.0)
    """oscillatory: the limit cycle's frequency [Hz] (below the Nyquist frequency of the control period); its phase is uniform."""
    elevon_runaway_deg_s: PosRange = (0.5, 5.0)
    """runaway: the elevon's drift rate from its command [deg/s], either sign."""
    engine_runaway_per_s: PosRange = (0.01, 0.05)
    """runaway: the throttle's drift rate [1/s], either sign."""
    float_gain: tuple[Annotated[float, NoBool, Field(ge=-2, le=0)],
                      Annotated[float, NoBool, Field(ge=-2, le=0)]] = (-1.0, -0.3)
    """float: the floating angle's gain on the angle of attack, -C_h_alpha / C_h_delta [rad/rad]."""
    float_angle_deg: tuple[Finite, Finite] = (-2.0, 2.0)
    """float: the floating angle at zero angle of attack, -C_h_0 / C_h_delta [deg]."""
    intermittent_on_s: PosRange = (0.5, 3.0)
    """intermittent: how long each stuck spell lasts [s] (whole multiples of the 0.5 s grid)."""
    intermittent_off_s: PosRange = (0.5, 3.0)
    """intermittent: how long the actuator works between spells [s] (same grid)."""

    @model_validator(mode="after")
    def _ordered(self):
        for name in type(self).model_fields:
            lo, hi = getattr(self, name)
            if not lo < hi:
                raise ValueError(f"{name}: must be [low, high] with low < high, "
                                 f"got {[lo, hi]}")
        for name in ("intermittent_on_s", "intermittent_off_s"):
            if getattr(self, name)[0] < INTERMITTENT_GRID_S:
                raise ValueError(f"{name}: spells last at least the {INTERMITTENT_GRID_S:g} s "
                                 f"grid, got {list(getattr(self, name))}")
        return self


INTERMITTENT_GRID_S = 0.5
"""Grid of an intermittent fault's spells [s]: the switch steps of a schedule are
shared by a chunk's lanes, so each lane's spells start and end on it."""


class TimingConfig(_Strict):
    """Trial timing: the switch at fault_time_s, judged over the window after it."""

    fault_time_s: Pos = 20.0
    """Time of the switch to the final mode [s]."""
    window_s: Pos = 10.0
    """Judging window after the switch for resets [s]."""
    duration_s: Pos = 50.0
    """Simulated time of a trial [s] (>= fault_time_s + window_s)."""
    reconfiguration_period_s: Pos = 1.0
    """Belief update period [s] (paper: 1 s)."""
    detection_probability: Fraction = 0.5
    """Belief of the final mode (also the most probable) that counts as detected."""

    @model_validator(mode="after")
    def _consistent(self):
        if self.duration_s < self.fault_time_s + self.window_s:
            raise ValueError("duration_s: must be at least fault_time_s + window_s "
                             f"({self.fault_time_s + self.window_s:g}), got {self.duration_s:g}")
        return self


class ExplainConfig(_Strict):
    """When a no-reset trial counts as explained (the paper's explanations)."""

    engine_lock_near_trim: Pos = 0.05
    """|lock - trim throttle| below which an engine lock is 'near trim' [-]."""
    elevon_lock_near_trim_rad: Pos = 0.02
    """|lock - trim elevon| below which an elevon lock is 'near trim' [rad]."""


class ValidityConfig(_Strict):
    """Envelope where a trial is trusted; a trial leaving it stops and is flagged."""

    airspeed_min_mps: Pos = 12.0
    """Lowest true airspeed [m/s] (about 1.2 times the X8's stall speed at this weight)."""
    airspeed_max_mps: Pos = 30.0
    """Highest true airspeed [m/s] (1.5 times trim: beyond it the linearisation is poor)."""
    alpha_min_deg: Annotated[float, NoBool, Field(ge=-45, le=0, allow_inf_nan=False)] = -8.0
    """Lowest angle of attack [deg] (range of the aerodynamic fit)."""
    alpha_max_deg: Annotated[float, NoBool, Field(ge=0, le=45, allow_inf_nan=False)] = 12.0
    """Highest angle of attack [deg] (below stall, range of the aerodynamic fit)."""
    psd_check_period_s: Pos = 1.0
    """Period of the full Cholesky check of the filter covariance [s]."""
    bank_max_deg: Annotated[float, NoBool, Field(gt=0, le=90, allow_inf_nan=False)] = 60.0
    """Largest bank angle [deg] (6-DOF plant): beyond it the longitudinal filter's model no longer holds."""

    @model_validator(mode="after")
    def _ordered(self):
        if not self.airspeed_min_mps < self.airspeed_max_mps:
            raise ValueError("airspeed_max_mps: must exceed airspeed_min_mps")
        return self


class MonitorConfig(_Strict):
    """The 6-DOF side monitor: which actuator failed, from roll and pitch (6-DOF plant only)."""

    enabled: bool = True
    """Fly the side monitor beside every design on the 6-DOF plant (docs/reference/config.md#the-side-monitor)."""
    design_turbulence: Literal[TURBULENCE_LEVELS] = "none"
    """Dryden level the monitor's filter models (none: no gust states; else 8 gust states at that level)."""
    prediction: Literal["auto", "linear", "nonlinear", "extended"] = "auto"
    """What predicts the monitor's states: linear, nonlinear, extended or auto (docs/reference/config.md#the-side-monitor)."""
    substeps: Annotated[int, NoBool, Field(ge=1, le=100)] = 5
    """RK4 sub-steps per control period of the monitor's nonlinear prediction."""
    state_noise_scale: Annotated[float, NoBool, Field(ge=1.0, le=1e6, allow_inf_nan=False)] = 1.0
    """Factor on the process noise variance of the monitor's 6-DOF states (docs/reference/config.md#the-side-monitor)."""
    threshold: Pos = 30.0
    """GLR threshold on each actuator's statistic (chi-square, 1 degree of freedom)."""
    window_s: Pos = 2.0
    """GLR window [s]: the oldest change tested."""
    min_window_s: Pos = 0.3
    """Shortest change tested [s] (a multiple of model.dt_s, at most window_s)."""
    startup_s: NonNeg = 1.0
    """Time from the start before a decision may be made [s]."""
    estimate_after_s: NonNeg = 1.0
    """Time after the first decision at which the monitor's estimate is recorded [s]."""
    turn_offsets_deg: tuple[Finite, Finite] = (-14.0, 4.0)
    """Lock offsets from trim [deg] the lock-turn table spans, each side (docs/reference/config.md#the-lock-turn-law)."""
    turn_step_deg: Pos = 1.0
    """Step of that table [deg]: its range must hold a whole number of steps."""
    turn_feedback: Literal["measured", "estimate"] = "measured"
    """What the lock-turn law feeds back: measured (the sensors) or estimate (the monitor's estimate)."""
    turn_model: Literal["auto", "linear", "nonlinear"] = "auto"
    """What the lock-turn table is designed on: nonlinear, linear or auto (docs/reference/config.md#the-lock-turn-law)."""
    turn_probe_rad: Annotated[float, NoBool, Field(ge=0, le=0.3, allow_inf_nan=False)] = 0.0
    """Amplitude of a 3211 the lock-turn law sends on the named elevon [rad]; 0: none (docs/reference/config.md#the-lock-turn-law)."""
    turn_probe_unit_s: Pos = 0.2
    """One unit of that 3211 [s] (it lasts 7 units; the paper's 3211 unit by default)."""
    hand_back_after_s: Pos = 3.0
    """Time after the lock-turn law took over at which a probed lane is judged [s]: at least the probe's 7 units."""
    hand_back_b1: Annotated[float, NoBool, Field(gt=0, le=1, allow_inf_nan=False)] = 0.5
    """A probed lane whose estimated b1 of the named elevon falls below this hands back to the paper's loop."""
    hand_back_sd: NonNeg = 2.0
    """Standard deviations of that b1 estimate by which b1 must lie below hand_back_b1 to hand back."""
    turn_beyond: Literal["hold", "rollout", "guarded"] = "hold"
    """Where no steady flight exists about the lock: hold, rollout or guarded (docs/reference/config.md#the-rocking-law-and-the-rollout-guard)."""
    rollout_horizon_s: Pos = 3.0
    """rollout: how far ahead each candidate history is flown [s] (a multiple of model.dt_s)."""
    rollout_switch_s: tuple[Pos, ...] = (0.2, 1.0)
    """rollout: times at which a candidate history switches to its second pair [s]; []: held pairs only."""
    rollout_elevon_levels: Annotated[int, NoBool, Field(ge=2, le=9)] = 5
    """rollout: positions of the healthy elevon in the candidates, from its lower to its upper limit."""
    rollout_guard_holds_s: tuple[Pos, ...] = (0.2, 0.5, 1.0)
    """guarded: how long each guard candidate holds its pair before the LQR takes over [s]."""
    rollout_guard_bank_margin_deg: Annotated[float, NoBool, Field(ge=0.5, le=30, allow_inf_nan=False)] = 10.0
    """Bank room [deg] below validity.bank_max_deg of designs outside the design box (docs/reference/config.md#the-rocking-law-and-the-rollout-guard)."""
    rollout_substeps: Annotated[int, NoBool, Field(ge=1, le=100)] = 2
    """rollout: RK4 sub-steps per control period of those flights (a sub-step of at most 0.05 s)."""

    @model_validator(mode="after")
    def _ordered(self):
        if not self.min_window_s <= self.window_s:
            raise ValueError("min_window_s: must not exceed window_s")
        probe_s = sum(S3211_UNITS) * self.turn_probe_unit_s
        if self.turn_probe_rad > 0 and self.hand_back_after_s < probe_s * (1 - 1e-9):
            raise ValueError(f"hand_back_after_s: must be at least the probe's length "
                             f"({probe_s:g} s), got {self.hand_back_after_s:g}")
        if len(set(self.rollout_switch_s)) < len(self.rollout_switch_s):
            raise ValueError(f"rollout_switch_s: the times must differ, got "
                             f"{list(self.rollout_switch_s)}")
        late = [t for t in self.rollout_switch_s if not t < self.rollout_horizon_s]
        if late:
            raise ValueError(f"rollout_switch_s: each must be below rollout_horizon_s "
                             f"({self.rollout_horizon_s:g} s), got {late[0]:g}")
        if self.turn_beyond == "guarded":
            holds = list(self.rollout_guard_holds_s)
            if not holds:
                raise ValueError("rollout_guard_holds_s: the guard needs at least one time")
            if len(set(holds)) < len(holds):
                raise ValueError(f"rollout_guard_holds_s: the times must differ, got {holds}")
            late = [t for t in holds if not t < self.rollout_horizon_s]
            if late:
                raise ValueError(f"rollout_guard_holds_s: each must be below "
                                 f"rollout_horizon_s ({self.rollout_horizon_s:g} s), "
                                 f"got {late[0]:g}")
        lo, hi = self.turn_offsets_deg
        if not lo < hi:
            raise ValueError(f"turn_offsets_deg: the first must be below the second, got "
                             f"[{lo:g}, {hi:g}]")
        n = (hi - lo) / self.turn_step_deg
        if abs(n - round(n)) > 1e-9 * max(1.0, n) or n > 200:
            raise ValueError(f"turn_step_deg: must divide turn_offsets_deg's range "
                             f"({hi - lo:g} deg) into at most 200 steps, got "
                             f"{self.turn_step_deg:g}")
        return self

    def turn_offsets(self) -> list:
        """The lock-turn table's offsets from trim [deg], ascending."""
        lo, hi = self.turn_offsets_deg
        n = int(round((hi - lo) / self.turn_step_deg))
        return [lo + i * self.turn_step_deg for i in range(n + 1)]


def parse_sensor_transition(name: str):
    """``(kind, output)`` of a transition named ``sensor_<kind>:<output>``, or None
    when ``name`` is not a sensor transition; ValueError when it is a malformed one."""
    if not name.startswith(SENSOR_PREFIX):
        return None
    kind, sep, output = name[len(SENSOR_PREFIX):].partition(":")
    if not sep or kind not in SENSOR_FAULT_KINDS:
        raise ValueError(f"{name!r} is not sensor_<kind>:<output> with kind one of "
                         f"{list(SENSOR_FAULT_KINDS)}")
    if output not in OUTPUT_NAMES:
        raise ValueError(f"{name!r}: unknown output {output!r}; outputs are "
                         f"{list(OUTPUT_NAMES)}")
    return kind, output


def _transition_name(name: str) -> str:
    if name in TRANSITIONS or name in KIND_TRANSITIONS or parse_sensor_transition(name) is not None:
        return name
    raise ValueError(f"unknown transition {name!r}: one of {list(TRANSITIONS)}, a fault "
                     f"kind <elevon|right_elevon|engine>_<kind> (kinds {list(KINDS_BEYOND)}; "
                     "float on the elevons only) or "
                     f"sensor_<kind>:<output> (kinds {list(SENSOR_FAULT_KINDS)})")


TransitionName = Annotated[str, AfterValidator(_transition_name)]

SizeRange = tuple[NonNeg, NonNeg]

_DEG = math.pi / 180.0
DEFAULT_SENSOR_BIAS = {
    "u": (0.2, 1.0), "w": (0.2, 1.0),
    "q": (round(1 * _DEG, 6), round(5 * _DEG, 6)),
    "x": (1.0, 5.0), "z": (1.0, 5.0),
    "theta": (round(1 * _DEG, 6), round(3 * _DEG, 6)),
    "n_x": (0.02, 0.08), "n_z": (0.02, 0.08),
    "alpha": (round(1 * _DEG, 6), round(3 * _DEG, 6)),
    "gamma": (round(0.5 * _DEG, 6), round(2 * _DEG, 6)),
    "CAS": (0.5, 2.0), "Va": (0.5, 2.0),
}
"""Default bias magnitudes per output, in the output's unit (module docs of
:class:`SensorDrawsConfig`)."""


class SensorDrawsConfig(_Strict):
    """Sizes of the sensor faults of ``sensor_<kind>:<output>`` transitions.

    Each trial's size is the first draw of its stream: a magnitude uniform in
    ``[low, high]`` with a random sign (one uniform draw over (-1, 1): its sign
    and its magnitude), so the later draws (noise, gusts) are those of the actuator
    transitions.  A stuck sensor holds its last healthy value and has no size.
    """

    bias: dict[str, SizeRange] = Field(default_factory=lambda: dict(DEFAULT_SENSOR_BIAS))
    """Bias magnitude range per output, in its unit; outputs left out keep their default (docs/reference/config.md#sensor-fault-sizes)."""
    drift_per_s: Pos = 0.1
    """Drift rate range = this x the bias range, per second [1/s] (the bias range after 10 s)."""
    noise_factor: SizeRange = (2.0, 10.0)
    """Range of the factor on the output's measurement noise standard deviation."""

    @field_validator("bias")
    @classmethod
    def _bias(cls, ranges: dict) -> dict:
        for out, (lo, hi) in ranges.items():
            if out not in OUTPUT_NAMES:
                raise ValueError(f"unknown output {out!r}; outputs are {list(OUTPUT_NAMES)}")
            if not lo < hi:
                raise ValueError(f"{out}: must be [low, high] with low < high, "
                                 f"got {[lo, hi]}")
        return {**DEFAULT_SENSOR_BIAS, **ranges}

    @model_validator(mode="after")
    def _ordered(self):
        lo, hi = self.noise_factor
        if not lo < hi:
            raise ValueError(f"noise_factor: must be [low, high] with low < high, "
                             f"got {[lo, hi]}")
        return self

    def size_range(self, kind: str, output: str) -> tuple:
        """``(low, high)`` of the size magnitude of ``kind`` on ``output``."""
        if kind == "bias":
            return tuple(self.bias[output])
        if kind == "drift":
            lo, hi = self.bias[output]
            return (lo * self.drift_per_s, hi * self.drift_per_s)
        if kind == "noise":
            return tuple(self.noise_factor)
        return (0.0, 1.0)


BUILTIN_DESIGNS = ("paper", "swapped")
"""The built-in designs: the paper's estimator and one-step test at the ``estimator``
section's thresholds, with Table 1 as printed or swapped (the signature variants)."""
DESIGN_NAME = re.compile(r"[A-Za-z0-9_-]+")
"""What a design's name may hold (it names result rows and files)."""
RESERVED_DESIGN_NAMES = (*BUILTIN_DESIGNS, "both", "none")


class DesignConfig(_Strict):
    """A detection design: estimator model x residual test x thresholds."""

    estimator: Literal["paper", "gust_aware"] = "paper"
    """paper: the 14-state filter of eqs. 4-6; gust_aware: plus the 4 Dryden gust states."""
    prediction: Literal["linear", "nonlinear"] = "linear"
    """linear: the model of eq. 5; nonlinear: the airframe's equations predict (an extended filter)."""
    design_turbulence: Literal["light", "moderate", "severe"] = "moderate"
    """Dryden level of the gust states' process noise and initial covariance (gust_aware only)."""
    test: Literal["one_step", "glr"] = "one_step"
    """Residual test: one_step (the paper's eqs. 9-11) or glr (a mean change over a sliding window)."""
    window_s: Pos = 2.0
    """GLR window [s] (a multiple of model.dt_s; glr only)."""
    settle_s: NonNeg = 0.0
    """After a reset, the other block is not reset for this long [s]; 0: no wait."""
    startup_s: NonNeg = 0.0
    """The test is armed this long after the start [s]; 0: at once (docs/reference/config.md#detection-designs)."""
    min_change_s: Pos | None = None
    """Shortest change the GLR tests [s] (at most window_s); null: one step (glr only)."""
    innovation_clip: Pos | None = None
    """Clip each normalised innovation to [-c, c] in the GLR window (glr only); null: no clip (docs/reference/config.md#detection-designs)."""
    signature: Literal["paper", "swapped"] = "swapped"
    """Table 1 as printed (paper) or with its third clause swapped."""
    resets: Literal[RESETS_NAMES] = "table1"
    """What resets the blocks: table1, side_monitor (6-DOF) or either of them (docs/reference/config.md#detection-designs)."""
    monitor_threshold: Pos | None = None
    """The 6-DOF side monitor's GLR threshold on this design's flights; null: monitor.threshold."""
    monitor_throttle_threshold: Pos | None = None
    """Its threshold on the throttle's direction; null: as the elevons' (docs/reference/config.md#the-side-monitor)."""
    t_q: Pos = 25.0
    """Threshold on r_q (Table 1)."""
    t_nx: Pos = 25.0
    """Threshold on r_nx (Table 1)."""
    sigma_qx: Pos | None = None
    """Filter process-noise density of the plant states; null: estimator.sigma_qx (the truth noise never changes)."""
    sigma_qb: Pos | None = None
    """Filter random-walk density of the fault parameters; null: estimator.sigma_qb."""
    state_noise: dict[Literal[STATE_NAMES], NonNeg] = Field(default_factory=dict)
    """Extra filter process-noise standard deviation per step on named plant states (u, w, q, ...); {}: none."""
    relinearise_s: Pos | None = None
    """prediction nonlinear: re-compute the covariance's Jacobians every this many s (an EKF); null: at trim."""
    sensor_biases: list[Literal[BIASED_OUTPUTS]] = Field(default_factory=list)
    """Outputs whose sensor bias the filter estimates (of q, n_x, n_z); []: none (docs/reference/config.md#detection-designs)."""
    sensor_bias_sd: dict[Literal[BIASED_OUTPUTS], Pos] = Field(default_factory=dict)
    """Standard deviation a bias takes when its hypothesis opens, per output [rad/s, g]; left out: a typical sensor's."""
    sensor_bias_walk: dict[Literal[BIASED_OUTPUTS], NonNeg] = Field(default_factory=dict)
    """Random-walk density of each bias per sqrt(s), in measurement-noise sds (docs/reference/config.md#detection-designs)."""
    reset_scale: Pos = 1.0
    """Factor on the variances a covariance reset gives the fault parameters (docs/reference/config.md#detection-designs)."""
    excitation_policy: Literal[EXCITATION_POLICIES] = "none"
    """Excitation beyond the paper's on resets: none, periodic or ambiguous (docs/reference/config.md#excitation)."""
    doublet_amplitude: DoubletAmplitude | None = None
    """This design's engine doublet amplitude [throttle fraction], on resets (and by its policy); null: the excitation section's."""
    s3211_amplitude_rad: S3211Amplitude | None = None
    """This design's elevon 3211 amplitude [rad], on resets (and by its policy); null: the excitation section's."""
    s3211_floor: Annotated[float, NoBool, Field(ge=0, le=1, allow_inf_nan=False)] = 0.0
    """Under c2 the elevon 3211 is scaled by max(1 - b1_left_hat, s3211_floor) (docs/reference/config.md#excitation)."""
    excitation_period_s: Pos = 5.0
    """periodic: time between two doublets [s]; ambiguous: shortest time between two signals."""
    excitation_phase_s: NonNeg = 0.0
    """periodic: the doublets start at this time plus whole periods [s]; the 3211s half a period later."""
    excitation_belief: Annotated[float, NoBool, Field(ge=0, le=1, allow_inf_nan=False)] = 0.9
    """ambiguous: send while the belief's most probable mode has a probability below this (0: never on the belief)."""
    excitation_residual: Pos | None = None
    """ambiguous: send when r_q or r_nx reach this; null: never on the residuals."""
    excitation_pause_belief: Fraction | None = None
    """The policy sends nothing while the belief gives a fault mode at least this probability; null: never pauses."""
    policy_doublet_amplitude: DoubletAmplitude | None = None
    """The policy's doublets [throttle fraction]; null: as on resets (doublet_amplitude)."""
    policy_s3211_amplitude_rad: S3211Amplitude | None = None
    """The policy's 3211s [rad]; null: as on resets (s3211_amplitude_rad)."""

    controller: ControllerKind | None = None
    """Controller of this design's flights (as controller.kind); null: the controller section's kind."""
    weights: Literal["paper", "airspeed"] | None = None
    """LQR weights of this design's controllers (as controller.weights, on its scales); null: the controller section's."""

    @model_validator(mode="after")
    def _biases(self):
        if len(set(self.sensor_biases)) != len(self.sensor_biases):
            raise ValueError("sensor_biases: outputs must not repeat")
        for field in ("sensor_bias_sd", "sensor_bias_walk"):
            extra = sorted(set(getattr(self, field)) - set(self.sensor_biases))
            if extra:
                raise ValueError(f"{field}: {', '.join(extra)} not in sensor_biases")
        return self


def _design_names(designs: dict) -> dict:
    for name in designs:
        if not DESIGN_NAME.fullmatch(name):
            raise ValueError(f"{name!r}: a design name holds only letters, digits, _ and -")
        if name in RESERVED_DESIGN_NAMES:
            raise ValueError(f"{name!r}: reserved (built-in designs: "
                             f"{', '.join(BUILTIN_DESIGNS)}); choose another name")
    return designs


Designs = Annotated[dict[str, DesignConfig], AfterValidator(_design_names)]


def _check_designs(cfg, listed, where: str, duration: tuple) -> None:
    """Every name of ``listed`` must be a key of ``cfg.designs``; every GLR window a
    whole number of sampling periods, at most the run's ``duration = (name, s)``."""
    for name in listed:
        if name in BUILTIN_DESIGNS:
            field = "campaign.signature" if where.startswith("campaign") else "scenario.signature"
            raise ValueError(f"{where}: {name!r} is a built-in design; choose it with {field}")
        if name not in cfg.designs:
            known = ", ".join(cfg.designs) or "none (the designs section is empty)"
            raise ValueError(f"{where}: unknown design {name!r}; designs defined: {known}")
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.window_s", d.window_s)
                                    for n, d in cfg.designs.items() if d.test == "glr"])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.min_change_s", d.min_change_s)
                                    for n, d in cfg.designs.items()
                                    if d.test == "glr" and d.min_change_s is not None])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.settle_s", d.settle_s)
                                    for n, d in cfg.designs.items() if d.settle_s > 0])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.startup_s", d.startup_s)
                                    for n, d in cfg.designs.items() if d.startup_s > 0])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.relinearise_s", d.relinearise_s)
                                    for n, d in cfg.designs.items()
                                    if d.relinearise_s is not None])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.excitation_period_s", d.excitation_period_s)
                                    for n, d in cfg.designs.items()
                                    if d.excitation_policy != "none"])
    _check_periods(cfg.model.dt_s, [(f"designs.{n}.excitation_phase_s", d.excitation_phase_s)
                                    for n, d in cfg.designs.items()
                                    if d.excitation_policy == "periodic"
                                    and d.excitation_phase_s > 0])
    e = cfg.excitation
    longest = max(2 * e.doublet_half_period_s, sum(S3211_UNITS) * e.s3211_unit_s)
    for n, d in cfg.designs.items():
        for field in ("excitation_pause_belief", "policy_doublet_amplitude",
                      "policy_s3211_amplitude_rad"):
            if d.excitation_policy == "none" and getattr(d, field) is not None:
                raise ValueError(f"designs.{n}.{field}: only with an excitation_policy "
                                 "(got excitation_policy: none)")
        if d.excitation_policy != "periodic":
            continue
        if d.excitation_period_s < 2 * longest - 1e-9:
            raise ValueError(f"designs.{n}.excitation_period_s: must be at least twice the "
                             f"longer excitation signal ({2 * longest:g} s), so the doublet "
                             f"and the 3211 never overlap; got {d.excitation_period_s:g}")
        if d.excitation_phase_s >= d.excitation_period_s:
            raise ValueError(f"designs.{n}.excitation_phase_s: must be below "
                             f"excitation_period_s ({d.excitation_period_s:g} s), got "
                             f"{d.excitation_phase_s:g}")
    for n, d in cfg.designs.items():
        if d.relinearise_s is not None and d.prediction != "nonlinear":
            raise ValueError(f"designs.{n}.relinearise_s: only with prediction: nonlinear "
                             f"(got prediction: {d.prediction})")
        if d.innovation_clip is not None and d.test != "glr":
            raise ValueError(f"designs.{n}.innovation_clip: only with test: glr "
                             f"(got test: {d.test})")
        if d.test == "glr" and d.min_change_s is not None and d.min_change_s > d.window_s:
            raise ValueError(f"designs.{n}.min_change_s: must not exceed window_s "
                             f"({d.window_s:g} s), got {d.min_change_s:g}")
        if d.test == "glr" and d.window_s > duration[1]:
            raise ValueError(f"designs.{n}.window_s: must not exceed {duration[0]} "
                             f"({duration[1]:g} s), got {d.window_s:g}")


class CampaignConfig(_Strict):
    """What to run."""

    transitions: list[TransitionName] = Field(default_factory=lambda: ["elevon_lock"],
                                              min_length=1)
    """Transitions: <elevon|right_elevon|engine>_<lock|unlock|loss|loss_recover>, or sensor_<kind>:<output>."""
    trials: Annotated[int, NoBool, Field(gt=0, le=10_000_000)] = 1000
    """Trials per transition."""
    seed: Annotated[int, NoBool, Field(ge=0, lt=2 ** 63)] = 2026
    """Root seed: trial i draws from numpy.random.default_rng([i, seed])."""
    signature: Literal["paper", "swapped", "both", "none"] = "both"
    """Table 1 variant(s) (the built-in designs) run on the same draws and noise; none: only campaign.designs."""
    designs: list[str] = Field(default_factory=list)
    """Designs (keys of the designs section) run after the signature variants, on the same trials."""
    chunk_size: Annotated[int, NoBool, Field(gt=0, le=4096)] = 128
    """Trials per chunk (one kernel call, lanes); results do not depend on it."""
    max_resets: Annotated[int, NoBool, Field(gt=0, le=100_000)] | None = None
    """Resets stored per trial (more are counted, not stored); null: one per step, all."""
    reset_log: str = "all"
    """Resets written to resets.parquet: all, none or first-N (per trial and design)."""
    record: Literal["none", "signals"] = "none"
    """none, or signals: ftc-mc run and endurance write every step of every trial and design to signals/."""

    @field_validator("reset_log")
    @classmethod
    def _reset_log(cls, v):
        if v in ("all", "none"):
            return v
        head, _, n = v.partition("-")
        if head != "first" or not n.isdigit() or int(n) < 1 or n != str(int(n)):
            raise ValueError(f"must be all, none or first-N with N >= 1, got {v!r}")
        return v

    def resets_kept(self) -> int | None:
        """Resets of each trial and design written to ``resets.parquet``
        (``reset_log``): None for all of them."""
        return (None if self.reset_log == "all" else 0 if self.reset_log == "none"
                else int(self.reset_log.partition("-")[2]))

    @model_validator(mode="after")
    def _unique(self):
        if len(set(self.transitions)) != len(self.transitions):
            raise ValueError("transitions: names must not repeat")
        if len(set(self.designs)) != len(self.designs):
            raise ValueError("designs: names must not repeat")
        if self.signature == "none" and not self.designs:
            raise ValueError("signature: none runs nothing; name designs in campaign.designs")
        return self

    def runs(self) -> tuple:
        """Names of the designs run, in order: the signature variants, then ``designs``."""
        sig = (BUILTIN_DESIGNS if self.signature == "both" else
               () if self.signature == "none" else (self.signature,))
        return (*sig, *self.designs)


class Config(_Sampled):
    """A whole campaign configuration (one YAML file)."""

    campaign: CampaignConfig = Field(default_factory=CampaignConfig)
    model: ModelConfig = Field(default_factory=ModelConfig)
    plant: PlantConfig = Field(default_factory=PlantConfig)
    estimator: EstimatorConfig = Field(default_factory=EstimatorConfig)
    controller: ControllerConfig = Field(default_factory=ControllerConfig)
    excitation: ExcitationConfig = Field(default_factory=ExcitationConfig)
    noise: NoiseConfig = Field(default_factory=NoiseConfig)
    draws: DrawsConfig = Field(default_factory=DrawsConfig)
    timing: TimingConfig = Field(default_factory=TimingConfig)
    explain: ExplainConfig = Field(default_factory=ExplainConfig)
    validity: ValidityConfig = Field(default_factory=ValidityConfig)
    monitor: MonitorConfig = Field(default_factory=MonitorConfig)
    sensor_draws: SensorDrawsConfig = Field(default_factory=SensorDrawsConfig)
    kind_draws: KindDrawsConfig = Field(default_factory=KindDrawsConfig)
    designs: Designs = Field(default_factory=dict)
    """Detection designs compared on the same trials: name -> design; run them with campaign.designs or --design NAME."""

    @model_validator(mode="after")
    def _steps(self):
        dt = self.model.dt_s
        t = self.timing
        _check_designs(self, self.campaign.designs, "campaign.designs",
                       ("timing.duration_s", t.duration_s))
        _check_periods(dt, [("timing.fault_time_s", t.fault_time_s),
                            ("timing.window_s", t.window_s),
                            ("timing.duration_s", t.duration_s),
                            ("timing.reconfiguration_period_s",
                             t.reconfiguration_period_s),
                            *_shared_periods(self)])
        _check_rollout(self, self.campaign.runs())
        if self.controller.horizon_s > t.duration_s:
            raise ValueError("controller.horizon_s: must not exceed timing.duration_s "
                             f"({t.duration_s:g} s), got {self.controller.horizon_s:g}")
        _check_length("timing.duration_s", t.duration_s, dt)
        _check_lock_turn(self, self.campaign.runs())
        _check_coupling(self, self.campaign.runs())
        lower, upper = _check_airframe_use(self)
        for actuator, name in (("engine", "engine_lock_range"),
                               ("left_elevon", "elevon_lock_range_rad"),
                               ("right_elevon", "elevon_lock_range_rad")):
            a = ACTUATOR_NAMES.index(actuator)
            r = getattr(self.draws, name)
            if r is not None and (r[0] < lower[a] or r[1] > upper[a]):
                raise ValueError(f"draws.{name}: must lie within the {actuator} command "
                                 f"range [{lower[a]:g}, {upper[a]:g}], got {list(r)}")
        kd = self.kind_draws
        if kd.delay_s[1] > MAX_DELAY_STEPS * dt + 1e-12:
            raise ValueError(f"kind_draws.delay_s: at most {MAX_DELAY_STEPS} control periods "
                             f"({MAX_DELAY_STEPS * dt:g} s), got {list(kd.delay_s)}")
        if round(kd.delay_s[0] / dt) < 1:
            raise ValueError(f"kind_draws.delay_s: at least one control period ({dt:g} s), "
                             f"got {list(kd.delay_s)}")
        if kd.osc_freq_hz[1] >= 0.5 / dt:
            raise ValueError(f"kind_draws.osc_freq_hz: below the Nyquist frequency "
                             f"{0.5 / dt:g} Hz of the control period, got {list(kd.osc_freq_hz)}")
        for i, name in enumerate(self.campaign.transitions):
            sensor = parse_sensor_transition(name)
            if sensor and sensor[0] == "noise" and self.noise.measurement_scale == 0:
                raise ValueError(f"campaign.transitions.{i}: {name} scales the measurement "
                                 "noise, but noise.measurement_scale is 0 (none is simulated)")
        return self

    def resets_stored(self) -> int:
        """Resets stored per trial: ``campaign.max_resets``, or every step's when null
        (a trial resets at most one block per step, so then none is lost)."""
        m = self.campaign.max_resets
        return self.steps(self.timing.duration_s) if m is None else m


SCENARIO_KINDS = tuple(k for k in KINDS_BEYOND if k != "intermittent")
"""Fault kinds a scenario entry may name besides nominal, lock and loss (an
intermittent fault is a list of entries with durations)."""
KIND_FIELDS = {"lock": ("position",), "loss": ("b1",), "hardover": ("side",),
               "float": ("float_angle", "float_gain"), "slow": ("rate_limit",),
               "delayed": ("delay_s",),
               "oscillatory": ("amplitude", "frequency_hz", "phase_rad"),
               "runaway": ("rate",), "nominal": ()}
"""The parameters each fault of a scenario entry takes (all of them, no others)."""


class FaultEvent(_Strict):
    """One entry of a scenario's fault schedule: from ``time_s`` on (for
    ``duration_s`` if given, RflyMAD's start and duration), one actuator's fault
    with its parameters (docs/guides/fault-kinds.md)."""

    time_s: NonNeg
    """Time from which this entry holds [s]."""
    fault: Literal[("nominal", "lock", "loss") + SCENARIO_KINDS]
    """``nominal`` (all healthy), ``lock``, ``loss`` (of effectiveness) or a kind: hardover, float (elevons), slow, delayed, oscillatory, runaway."""
    actuator: Literal[ACTUATOR_NAMES] | None = None
    """Faulty actuator (``engine``, ``left_elevon``, ``right_elevon``); not for nominal."""
    duration_s: Pos | None = None
    """How long the fault acts [s]; then every actuator is healthy until the next entry (null: until the next entry)."""
    position: Finite | Literal["trim"] | None = None
    """Lock position (absolute command: throttle [-] or elevon [rad]) or ``trim``."""
    b1: Annotated[float, NoBool, Field(ge=0, le=1, allow_inf_nan=False)] | None = None
    """Effectiveness loss of a ``loss`` fault (0 healthy, 1 no effect)."""
    side: Literal["upper", "lower"] | None = None
    """hardover: the travel limit the actuator locks at."""
    float_angle: Finite | None = None
    """float: the floating angle at zero angle of attack [rad]."""
    float_gain: Annotated[float, NoBool, Field(ge=-2, le=0, allow_inf_nan=False)] | None = None
    """float: the floating angle's gain on the angle of attack [rad/rad]."""
    rate_limit: Pos | None = None
    """slow: the rate limit [command unit/s]."""
    delay_s: Pos | None = None
    """delayed: the transport delay [s] (whole control periods, at most 20)."""
    amplitude: Pos | None = None
    """oscillatory: the limit cycle's amplitude [command unit]."""
    frequency_hz: Pos | None = None
    """oscillatory: its frequency [Hz]."""
    phase_rad: Finite | None = None
    """oscillatory: its phase at the entry's start [rad]."""
    rate: Finite | None = None
    """runaway: the drift rate from the command [command unit/s], either sign."""

    @model_validator(mode="after")
    def _fields(self):
        if self.fault == "nominal":
            if self.actuator is not None or self.position is not None or self.b1 is not None:
                raise ValueError("actuator: a nominal entry takes no actuator, position or b1")
        elif self.actuator is None:
            raise ValueError(f"actuator: a {self.fault} entry needs one of {list(ACTUATOR_NAMES)}")
        elif self.fault == "lock" and (self.position is None or self.b1 is not None):
            raise ValueError("position: a lock entry needs a position (number or 'trim') "
                             "and no b1")
        elif self.fault == "loss" and (self.b1 is None or self.position is not None):
            raise ValueError("b1: a loss entry needs b1 in [0, 1] and no position")
        if self.fault == "float" and self.actuator == "engine":
            raise ValueError("actuator: a float entry is an elevon's (a throttle cannot float)")
        wanted = KIND_FIELDS[self.fault]
        for name in sorted({f for fs in KIND_FIELDS.values() for f in fs}):
            given = getattr(self, name) is not None
            if name in wanted and not given:
                raise ValueError(f"{name}: a {self.fault} entry needs it")
            if given and name not in wanted:
                raise ValueError(f"{name}: a {self.fault} entry takes no {name}")
        if self.fault == "nominal" and self.duration_s is not None:
            raise ValueError("duration_s: a nominal entry takes no duration")
        return self


def expanded_schedule(spec) -> list:
    """A scenario's schedule with each duration written out: an entry with
    ``duration_s`` is followed by a nominal entry at its end, unless the next
    entry starts then (the result has no durations; a schedule without any
    is returned as it is)."""
    events = list(spec.schedule)
    if all(e.duration_s is None for e in events):
        return events
    out = []
    for i, e in enumerate(events):
        out.append(e.model_copy(update={"duration_s": None}))
        if e.duration_s is not None:
            end = e.time_s + e.duration_s
            nxt = events[i + 1].time_s if i + 1 < len(events) else spec.duration_s
            if end < nxt - 1e-9:
                out.append(FaultEvent(time_s=end, fault="nominal"))
    return out


class SensorFaultEvent(_Strict):
    """A sensor fault of a scenario: on one output, from ``time_s`` to the end."""

    time_s: NonNeg
    """Onset [s] (a multiple of model.dt_s)."""
    kind: Literal[SENSOR_FAULT_KINDS]
    """bias (a step), stuck (frozen), drift (a ramp) or noise (the noise multiplied)."""
    output: Literal[OUTPUT_NAMES]
    """Faulty output (u, w, q, x, z, theta, n_x, n_z, alpha, gamma, CAS, Va)."""
    size: Finite | None = None
    """Bias [output unit], drift [unit/s] (either sign), noise factor (> 0); none for stuck."""

    @model_validator(mode="after")
    def _size(self):
        if self.kind == "stuck":
            if self.size is not None:
                raise ValueError("size: a stuck sensor takes no size")
        elif self.size is None:
            raise ValueError(f"size: a {self.kind} fault needs a size")
        elif self.kind == "noise" and not self.size > 0:
            raise ValueError(f"size: a noise factor must be > 0, got {self.size:g}")
        return self


class ScenarioSpec(_Strict):
    """The closed-loop scenario: fault schedule, length, seed, signature."""

    duration_s: Pos = 100.0
    """Simulated time [s] (paper: 100 s)."""
    seed: Annotated[int, NoBool, Field(ge=0, lt=2 ** 63)] = 2026
    """Seed of the process and measurement noise."""
    signature: Literal["paper", "swapped"] = "swapped"
    """Table 1 variant (swapped: fewer inappropriate resets in ftc-mc run, docs/findings/paper-tables.md)."""
    design: str | None = None
    """A key of the designs section flown instead of the signature variant (null: the variant)."""
    reconfiguration_period_s: Pos = 1.0
    """Belief update and controller selection period [s] (paper: 1 s)."""
    detection_probability: Fraction = 0.5
    """Belief of the true mode (also the most probable) that counts as detected."""
    schedule: list[FaultEvent] = Field(default_factory=lambda: [
        FaultEvent(time_s=0.0, fault="nominal"),
        FaultEvent(time_s=10.0, fault="lock", actuator="engine", position=0.2),
        FaultEvent(time_s=30.0, fault="nominal"),
        FaultEvent(time_s=50.0, fault="loss", actuator="engine", b1=0.5),
        FaultEvent(time_s=70.0, fault="nominal"),
        FaultEvent(time_s=90.0, fault="lock", actuator="left_elevon", position="trim"),
    ], min_length=1)
    """Fault schedule, sorted by time, first entry at 0 s (default: paper Table 4)."""
    sensor_fault: SensorFaultEvent | None = None
    """A sensor fault from its onset to the end (null: healthy sensors)."""

    @model_validator(mode="after")
    def _sorted(self):
        times = [e.time_s for e in self.schedule]
        if times[0] != 0.0:
            raise ValueError(f"schedule: the first entry must start at 0 s, got {times[0]:g}")
        for a, b in zip(times, times[1:]):
            if not b > a:
                raise ValueError(f"schedule: times must be strictly increasing "
                                 f"(overlapping or unsorted entries at {a:g} s and {b:g} s)")
        if times[-1] >= self.duration_s:
            raise ValueError(f"schedule: entry at {times[-1]:g} s is not before the end "
                             f"of the run ({self.duration_s:g} s)")
        for i, e in enumerate(self.schedule):
            if e.duration_s is not None and i + 1 < len(times) \
                    and e.time_s + e.duration_s > times[i + 1] + 1e-9:
                raise ValueError(f"schedule.{i}.duration_s: the fault would outlast the next "
                                 f"entry at {times[i + 1]:g} s")
        return self


class ScenarioConfig(_Sampled):
    """A scenario file: ``ftc-mc scenario CONFIG``."""

    scenario: ScenarioSpec = Field(default_factory=ScenarioSpec)
    model: ModelConfig = Field(default_factory=ModelConfig)
    plant: PlantConfig = Field(default_factory=PlantConfig)
    estimator: EstimatorConfig = Field(default_factory=EstimatorConfig)
    controller: ControllerConfig = Field(default_factory=ControllerConfig)
    excitation: ExcitationConfig = Field(default_factory=ExcitationConfig)
    noise: NoiseConfig = Field(default_factory=NoiseConfig)
    validity: ValidityConfig = Field(default_factory=ValidityConfig)
    monitor: MonitorConfig = Field(default_factory=MonitorConfig)
    designs: Designs = Field(default_factory=dict)
    """Detection designs: name -> design; fly one with scenario.design or --design NAME."""

    @model_validator(mode="after")
    def _steps(self):
        dt = self.model.dt_s
        sc = self.scenario
        _check_designs(self, [] if sc.design is None else [sc.design], "scenario.design",
                       ("scenario.duration_s", sc.duration_s))
        _check_periods(dt, [("scenario.duration_s", sc.duration_s),
                            ("scenario.reconfiguration_period_s",
                             sc.reconfiguration_period_s)])
        if self.controller.horizon_s > sc.duration_s:
            raise ValueError(f"controller.horizon_s: must not exceed scenario.duration_s "
                             f"({sc.duration_s:g} s), got {self.controller.horizon_s:g}")
        _check_lock_turn(self, (sc.design or sc.signature,))
        _check_coupling(self, (sc.design or sc.signature,))
        lower, upper = _check_airframe_use(self)
        for i, e in enumerate(sc.schedule):
            if e.fault == "lock" and e.position != "trim":
                a = ACTUATOR_NAMES.index(e.actuator)
                if not lower[a] <= e.position <= upper[a]:
                    raise ValueError(f"scenario.schedule.{i}.position: {e.position:g} is "
                                     f"outside the {e.actuator} command range "
                                     f"[{lower[a]:g}, {upper[a]:g}]")
        for i, e in enumerate(sc.schedule):
            for name in ("time_s", "duration_s", "delay_s"):
                v = getattr(e, name)
                n = math.nan if v is None else v / dt
                if v is not None and (not math.isfinite(n)
                                      or abs(n - round(n)) > 1e-9 * max(1.0, n)):
                    raise ValueError(f"scenario.schedule.{i}.{name}: must be a multiple of "
                                     f"model.dt_s ({dt:g} s), got {v:g}")
            if e.delay_s is not None and round(e.delay_s / dt) > MAX_DELAY_STEPS:
                raise ValueError(f"scenario.schedule.{i}.delay_s: at most {MAX_DELAY_STEPS} "
                                 f"control periods, got {e.delay_s:g} s")
            if e.frequency_hz is not None and e.frequency_hz >= 0.5 / dt:
                raise ValueError(f"scenario.schedule.{i}.frequency_hz: below the Nyquist "
                                 f"frequency {0.5 / dt:g} Hz, got {e.frequency_hz:g}")
        sf = sc.sensor_fault
        if sf is not None:
            n = sf.time_s / dt
            if not math.isfinite(n) or abs(n - round(n)) > 1e-9 * max(1.0, n):
                raise ValueError(f"scenario.sensor_fault.time_s: must be a multiple of "
                                 f"model.dt_s ({dt:g} s), got {sf.time_s:g}")
            if not sf.time_s < sc.duration_s:
                raise ValueError(f"scenario.sensor_fault.time_s: must be before "
                                 f"scenario.duration_s ({sc.duration_s:g} s), got "
                                 f"{sf.time_s:g}")
        _check_periods(dt, _shared_periods(self))
        _check_rollout(self, (sc.design or sc.signature,))
        _check_length("scenario.duration_s", sc.duration_s, dt)
        return self
