"""Detection designs: the kernel settings of each estimator model x residual test x
thresholds.

A design (:class:`~ftc_mc.config.schema.DesignConfig`) becomes a :class:`Design`:
the filter model, the Table 1 detection at the design's thresholds with its
residual test, and the initial covariance.  The built-in designs ``paper`` and
``swapped`` are the paper's estimator with the one-step test at the ``estimator``
section's thresholds (:func:`builtin_design`); their settings are exactly those
the kernels ran before designs existed.

The paper's filter estimates ``[x (9), b (5)]``.  A ``gust_aware`` filter appends
the four states of the Dryden shaping filter (``[x, b, g (4)]``): gust states
drive the plant states through ``G = B_w C_d`` and the outputs through
``D_g = D_w C_d`` (``B_w, D_w``: the wind Jacobians at trim,
:func:`ftc_mc.model.wind.plant_wind_matrices`, whatever the truth plant), and
evolve as ``g+ = A_d g`` with process noise ``Q_g = B_d B_d^T`` of the design's
turbulence level.  Its gust states start at 0 with the stationary Dryden
covariance.  ``prediction: nonlinear`` makes it an extended filter: the airframe's
equations predict the plant states and the outputs
(:mod:`ftc_mc.core.longitudinal.gustfilter`), with or without gust states; its covariance
takes the Jacobians at trim, or with ``relinearise_s`` those about each lane's
estimate, re-computed every ``relinearise_s`` seconds (``FilterModel.relin``).

A sensor-aware design (``sensor_biases``) appends the biases of the
residuals' sensors (q, n_x, n_z) after any gust states: random walks that only
add to their output.  Table 1 still picks an actuator block; its reset also opens
the biases of the sensors sharing its residual (:data:`BIAS_BLOCK`), so the
filter, with the excitation the reset sends, sorts the change into an actuator
fault or an output bias (:func:`_with_sensor_biases`).

A design may also send excitation beyond the paper's requests on resets
(``excitation_policy``): its :attr:`Design.excitation` fills the
policy fields of the kernels' :class:`~ftc_mc.core.longitudinal.settings.Excitation`
(:data:`NO_POLICY` for the paper's, which leaves the kernels as before), and
the signals' amplitudes where the design sets its own (``doublet_amplitude``,
``s3211_amplitude_rad``; else the config's ``excitation`` section), the
policy's own (``policy_*_amplitude``) and its pause
(``excitation_pause_belief``).  A policy changes the flight before any reset,
so it is part of the design key.  A design's ``weights`` chooses the LQR
weights of its controllers (:class:`ftc_mc.sim.setup.SimSetup`'s ``laws``).

A design changes only what the filter assumes: the truth noise of every trial
comes from the config's ``estimator`` and ``noise`` sections, so all designs fly
the same trials (common random numbers); :func:`ftc_mc.sim.inputs.design_inputs`
only pads the initial estimate with zeros and sets the design's ``P0``.  The
truth starts at trim with a stationary gust draw, which the filter's first
steps do not match: a design's ``startup_s`` (``Detection.startup``) arms its
test only after that.  Histories keep the first 14 states, ``xa_end`` all of
them (a sensor-aware design's final bias estimates, for
:func:`ftc_mc.campaign.chunk.classify_sensor`'s ``isolated``).  The results'
``variant`` column holds the design's name; ``paper`` is the baseline of the
report's paired comparisons.

In the kernels (``core/longitudinal/stages.filter_update``) the paper's
14-state filter with a linear prediction runs the block-structured
``batch.filter_predict_lanes`` / ``filter_correct_lanes`` (the golden results);
anything else runs ``gustfilter.gust_predict_lanes`` / ``gust_correct_lanes``:
dense ``F P F^T + Q`` and ``P c^T`` over every lane, and with
``FilterModel.nl`` the airframe's RK4 predicting the plant states and ``h(x,
wind)`` the outputs.  Between the halves the decision statistics are the
one-step residuals or, with the GLR test, ``glr.glr_lanes`` over the lane's
window (a reset empties it; each innovation is clipped to ``Detection.clip``,
``inf`` without ``innovation_clip``).  The controller selection predicts with
the paper's model on the first 14 states.  ``state_noise`` adds process noise
on named plant states (the airframe model's error in turbulence).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg

from ..config.schema import BUILTIN_DESIGNS, DesignConfig, EstimatorConfig
from ..conventions import (EXCITATION_POLICIES, EXCITE_NONE, LONGITUDINAL, OUTPUT_NAMES,
                           RESET_ELEVONS, RESETS_NAMES, RESET_THRUST, STATE_NAMES, TEST_GLR,
                           TEST_NAMES, TEST_ONE_STEP)
from ..core.longitudinal.settings import Detection, FilterModel
from ..model.linear import LinearPlant
from ..model.turbulence import dryden_model
from ..model.wind import plant_wind_matrices
from .estimator import EstimatorSettings, detection, filter_model, initial_covariance


NO_POLICY = {"policy": EXCITE_NONE, "period": 1, "phase": 0, "belief_max": 0.0,
             "suspect": math.inf, "s3211_floor": 0.0, "pause_belief": math.inf}
"""The policy fields of :class:`~ftc_mc.core.longitudinal.settings.Excitation` of a
design without an excitation policy (the paper's: signals on resets only, the 3211
under c2 scaled by ``1 - b1_left_hat`` as eq. 23 prints)."""


def design_excitation(dc: DesignConfig, dt: float) -> dict:
    """The fields of the kernels' ``Excitation`` the design ``dc`` sets (``dt``:
    the control period [s]): the policy's, :data:`NO_POLICY` for ``none``, with
    the design's ``s3211_floor`` either way, and the signals'
    amplitudes where the design sets its own: ``doublet_amp`` and ``s3211_amp``
    (on resets, and by the policy unless it sets ``policy_doublet_amp`` or
    ``policy_s3211_amp``)."""
    own = {"s3211_floor": float(dc.s3211_floor)}
    if dc.doublet_amplitude is not None:
        own["doublet_amp"] = own["policy_doublet_amp"] = float(dc.doublet_amplitude)
    if dc.s3211_amplitude_rad is not None:
        own["s3211_amp"] = own["policy_s3211_amp"] = float(dc.s3211_amplitude_rad)
    if dc.policy_doublet_amplitude is not None:
        own["policy_doublet_amp"] = float(dc.policy_doublet_amplitude)
    if dc.policy_s3211_amplitude_rad is not None:
        own["policy_s3211_amp"] = float(dc.policy_s3211_amplitude_rad)
    if dc.excitation_policy == "none":
        return {**NO_POLICY, **own}
    return {"policy": EXCITATION_POLICIES.index(dc.excitation_policy),
            "period": int(round(dc.excitation_period_s / dt)),
            "phase": int(round(dc.excitation_phase_s / dt)),
            "belief_max": float(dc.excitation_belief),
            "suspect": (math.inf if dc.excitation_residual is None
                        else float(dc.excitation_residual)),
            "pause_belief": (math.inf if dc.excitation_pause_belief is None
                             else float(dc.excitation_pause_belief)),
            **own}


@dataclasses.dataclass(frozen=True)
class Design:
    """Kernel settings of one design.

    Attributes
    ----------
    name : str
        The design's name (the ``variant`` column of the results).
    est : EstimatorSettings
        Filter noise densities, thresholds and signature of the design.
    fm : FilterModel
        The filter model (gust arrays empty for the paper's estimator).
    det : Detection
        Table 1 settings at the design's thresholds, with its test and window.
    P0 : ndarray, shape (n, n)
        Initial covariance, ``n = 14 + ng`` (``ng`` gust states).
    test : int
        ``conventions.TEST_ONE_STEP`` or ``TEST_GLR``.
    window : int
        GLR window [steps] (1 with the one-step test).
    key : str
        Equal for designs whose runs may share a start (``ftc_mc/sim/lanes.py``):
        designs differing at most in Table 1's signature and thresholds.
    biases : tuple of str
        Outputs whose sensor bias the design estimates, in the order of their
        states (the last ``len(biases)`` of the estimate).
    excitation : dict
        The fields of the kernels' ``Excitation`` the design sets: its policy,
        ``s3211_floor`` and its own amplitudes (:func:`design_excitation`).
    controller : str or None
        ``nominal`` or ``reconfiguring``: the design's own controller kind;
        None: the config's ``controller.kind``.
    weights : str or None
        ``paper`` or ``airspeed``: the LQR weights of the design's controllers;
        None: the config's ``controller.weights``.
    reset_scale : float
        Factor on the reset variances of section 3.2.2 (:func:`scaled_reset`).
    """

    name: str
    est: EstimatorSettings
    fm: FilterModel
    det: Detection
    P0: np.ndarray
    test: int
    window: int
    key: str
    biases: tuple = ()
    excitation: dict = dataclasses.field(default_factory=lambda: dict(NO_POLICY))
    controller: str | None = None
    reset_scale: float = 1.0
    weights: str | None = None

    @property
    def n_aug(self) -> int:
        """Length of the augmented estimate, ``14 + ng``."""
        return self.P0.shape[0]

    def bias_row(self, output: str) -> int | None:
        """Row of the estimate holding the bias of ``output``, None if not estimated."""
        if output not in self.biases:
            return None
        return self.n_aug - len(self.biases) + self.biases.index(output)

    def detection(self, plant: LinearPlant, t_q: float, t_nx: float) -> Detection:
        """The design's detection at the thresholds ``(t_q, t_nx)``.

        Both infinite: Table 1 never resets (the reset variances are then those
        of the design's thresholds, and never used); a design whose resets come
        from the side monitor still resets.
        """
        if math.isinf(t_q) and math.isinf(t_nx):
            return self.det._replace(t_q=math.inf, t_nx=math.inf)
        # only the thresholds and the reset variances follow (t_q, t_nx); every other
        # field stays the design's (a sweep once lost its innovation_clip here)
        det = scaled_reset(detection(plant, dataclasses.replace(self.est, t_q=t_q, t_nx=t_nx)),
                           self.reset_scale)
        return self.det._replace(thresholds=det.thresholds, reset_var=det.reset_var)


def builtin_design(name: str, est: EstimatorConfig) -> DesignConfig:
    """The design ``paper`` or ``swapped``: the paper's estimator and one-step test
    at the ``estimator`` section's thresholds, Table 1 as printed or swapped."""
    assert name in BUILTIN_DESIGNS, name
    return DesignConfig(signature=name, t_q=est.t_q, t_nx=est.t_nx)


def scaled_reset(det: Detection, scale: float) -> Detection:
    """``det`` with its reset variances (section 3.2.2) multiplied by ``scale``
    (a design's ``reset_scale``; 1 leaves ``det`` as built, the paper's).

    Parameters
    ----------
    det : Detection
    scale : float
        Factor on the five variances, > 0 (dimensionless).

    Returns
    -------
    Detection
    """
    assert scale > 0, scale
    return det if scale == 1.0 else det._replace(reset_var=det.reset_var * scale)


def _with_test(det: Detection, test: int, window: int, min_window: int = 1) -> Detection:
    """``det`` with another residual test (a one-step detection is left as built)."""
    return det if test == TEST_ONE_STEP else det._replace(test=test, window=window,
                                                            min_window=min_window)


def _c(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def monitor_thresholds(dc: DesignConfig, run_threshold: float) -> np.ndarray:
    """The side monitor's GLR threshold of each direction (the commands' order:
    throttle, left, right elevon) on the flights of the design ``dc``: its
    ``monitor_threshold`` (else the run's ``run_threshold``), the throttle's
    ``monitor_throttle_threshold`` where it sets one."""
    thr = float(run_threshold if dc.monitor_threshold is None else dc.monitor_threshold)
    throttle = (thr if dc.monitor_throttle_threshold is None
                else float(dc.monitor_throttle_threshold))
    return np.array([throttle if c == "throttle" else thr for c in LONGITUDINAL.inputs])


def build_design(name: str, dc: DesignConfig, plant: LinearPlant, est: EstimatorConfig,
                 altitude_m: float, monitor_threshold: float = math.inf) -> Design:
    """The kernel settings of the design ``dc``.

    Parameters
    ----------
    name : str
    dc : DesignConfig
        A validated design (:func:`builtin_design` for ``paper``/``swapped``).
    plant : LinearPlant
        The linear model the filter is built on.
    est : EstimatorConfig
        The config's ``estimator`` section: noise densities unless the design
        overrides them, ``R``, mode boxes.
    altitude_m : float
        Altitude of the Dryden scale lengths of a gust-aware filter [m].
    monitor_threshold : float
        The side monitor's GLR threshold of the run (``monitor.threshold``;
        6-DOF), which the design's ``monitor_threshold`` overrides on its
        flights.

    Returns
    -------
    Design
    """
    s = EstimatorSettings.from_config(est, dc.signature)
    s = dataclasses.replace(
        s, t_q=dc.t_q, t_nx=dc.t_nx,
        sigma_qx=s.sigma_qx if dc.sigma_qx is None else dc.sigma_qx,
        sigma_qb=s.sigma_qb if dc.sigma_qb is None else dc.sigma_qb)
    fm = filter_model(plant, s)
    if dc.state_noise:  # the model-error allowance on named plant states
        q = fm.q_diag.copy()
        for state, sd in dc.state_noise.items():
            q[STATE_NAMES.index(state)] += sd ** 2
        fm = fm._replace(q_diag=q)
    # the paper's thresholds set the initial fault variances whatever thresholds are
    # run, so runs share their pre-fault part across thresholds (ftc_mc/sim/lanes.py)
    P0 = initial_covariance(fm, detection(plant, EstimatorSettings()))
    if dc.estimator == "gust_aware":
        Bw, Dw = plant_wind_matrices(plant)
        dm = dryden_model(dc.design_turbulence, V=plant.trim.V0, altitude_m=altitude_m,
                          dt=plant.dt)
        fm = fm._replace(G=_c(Bw @ dm.Cd), Ad=_c(dm.Ad), Dg=_c(Dw @ dm.Cd),
                         Qg=_c(dm.Bd @ dm.Bd.T), Bw=_c(Bw), Dw=_c(Dw))
        P0 = scipy.linalg.block_diag(P0, dm.P0)
        fm = fm._replace(Cg=_c(dm.Cd), Dz=np.zeros((fm.C.shape[0], dm.Ad.shape[0])),
                         reset_g=np.zeros((3, dm.Ad.shape[0])))
    if dc.sensor_biases:
        fm, P0 = _with_sensor_biases(fm, P0, dc, plant.dt)
    if dc.prediction == "nonlinear":
        fm = fm._replace(nl=1)
        if dc.relinearise_s is not None:  # Jacobians about each lane's estimate
            fm = fm._replace(relin=int(round(dc.relinearise_s / plant.dt)))
    test = TEST_NAMES.index(dc.test)
    window = int(round(dc.window_s / plant.dt)) if test == TEST_GLR else 1
    min_window = (1 if test != TEST_GLR or dc.min_change_s is None
                  else int(round(dc.min_change_s / plant.dt)))
    det = _with_test(scaled_reset(detection(plant, s), dc.reset_scale), test, window,
                     min_window)._replace(
        settle=int(round(dc.settle_s / plant.dt)), startup=int(round(dc.startup_s / plant.dt)),
        clip=math.inf if dc.innovation_clip is None else float(dc.innovation_clip),
        source=RESETS_NAMES.index(dc.resets),
        side_thresholds=monitor_thresholds(dc, monitor_threshold))
    # every field but those Table 1 reads only when it decides (a shared start runs
    # with resets disabled); the excitation policy's are in: it flies before any reset
    key = dc.model_dump_json(exclude={"signature", "t_q", "t_nx"})
    return Design(name=name, est=s, fm=fm, det=det, P0=_c(P0), test=test, window=window,
                  key=key, biases=tuple(dc.sensor_biases),
                  excitation=design_excitation(dc, plant.dt), controller=dc.controller,
                  reset_scale=dc.reset_scale, weights=dc.weights)


SENSOR_BIAS_SD = {"q": 5.0 * math.pi / 180.0, "n_x": 0.08, "n_z": 0.08}
"""Default standard deviation of a bias when its hypothesis opens [rad/s, g]: the
largest bias of a typical small-UAV sensor (the upper ends of the default
``sensor_draws``: gyro 5 deg/s, accelerometers 80 mg, InvenSense MPU-6000)."""

SENSOR_BIAS_WALK = {"q": 0.3, "n_x": 0.05, "n_z": 0.3}
"""Default random-walk density of each bias per sqrt(s), in measurement-noise
standard deviations: q and n_z fast enough that a bias below Table 1's
threshold is learnt within 30 s; n_x slower, as faster walks hide small thrust
losses (measured on Tables 2-3)."""

BIAS_BLOCK = {"q": RESET_ELEVONS, "n_x": RESET_THRUST, "n_z": RESET_ELEVONS}
"""The Table 1 block whose reset opens each bias: the one deciding on its residual
(``r_nx`` thrust; ``r_q`` elevons, whose third clause reads ``r_nz``)."""


def _with_sensor_biases(fm: FilterModel, P0: np.ndarray, dc: DesignConfig, dt: float):
    """``fm`` and ``P0`` with the output biases of ``dc.sensor_biases`` appended
    after the other extra states.

    Bias ``s_o`` of output ``o``: ``s+ = s + w``, ``Var w = (walk_o sigma_o)^2 dt``
    (``walk_o``: ``dc.sensor_bias_walk`` or :data:`SENSOR_BIAS_WALK`)
    (``sigma_o``: the output's measurement-noise standard deviation), no effect on
    the plant (``G``, ``C_d`` columns 0), ``z_o += s_o`` (unit entry of ``D_g``
    and ``D_z``), initial variance ``sigma_o^2``, and variance ``sd_o^2`` when the
    block of :data:`BIAS_BLOCK` is reset (``FilterModel.reset_g``).
    """
    outs = [OUTPUT_NAMES.index(o) for o in dc.sensor_biases]
    ns, ng0, nz = len(outs), fm.Ad.shape[0], fm.C.shape[0]
    sig = np.sqrt(fm.r_diag[outs])
    walk = np.array([dc.sensor_bias_walk.get(o, SENSOR_BIAS_WALK[o]) for o in dc.sensor_biases])
    E = np.zeros((nz, ns))
    E[outs, np.arange(ns)] = 1.0
    reset = np.zeros((3, ns))
    for j, o in enumerate(dc.sensor_biases):
        reset[BIAS_BLOCK[o], j] = dc.sensor_bias_sd.get(o, SENSOR_BIAS_SD[o]) ** 2
    fm = fm._replace(
        G=_c(np.hstack([fm.G, np.zeros((fm.G.shape[0], ns))])),
        Ad=_c(scipy.linalg.block_diag(fm.Ad, np.eye(ns))),
        Dg=_c(np.hstack([fm.Dg, E])),
        Qg=_c(scipy.linalg.block_diag(fm.Qg, np.diag((walk * sig) ** 2 * dt))),
        Cg=_c(np.hstack([fm.Cg, np.zeros((fm.Cg.shape[0], ns))])),
        Dz=_c(np.hstack([np.zeros((nz, ng0)), E])),
        reset_g=_c(np.hstack([np.zeros((3, ng0)), reset])))
    return fm, scipy.linalg.block_diag(P0, np.diag(sig ** 2))


def build_designs(names, designs: dict, plant: LinearPlant, est: EstimatorConfig,
                  altitude_m: float, monitor_threshold: float = math.inf) -> dict:
    """``name -> Design`` of the designs ``names`` run (built-in or keys of
    ``designs``, the config's validated ``designs`` section), in order;
    ``monitor_threshold`` the run's side monitor's (:func:`build_design`)."""
    return {n: build_design(n, builtin_design(n, est) if n in BUILTIN_DESIGNS
                            else designs[n], plant, est, altitude_m, monitor_threshold)
            for n in names}
