"""One simulation setup from a validated config: campaign, sweep or scenario.

Everything that does not change from trial to trial, built once in the parent
process and shipped to the workers (small arrays in namedtuples, cheap to
pickle): the linear plant, the designs run (filter model, Table 1 detection
with its residual test, initial covariance: ``ftc_mc/sim/designs.py``), the belief, the controllers with their Theorem 4.1 tables
and terminal costs, the truth plant and its gust model, the timing, the
validity envelope, the truth noise and the initial covariance.

A campaign or sweep (:class:`~ftc_mc.config.schema.Config`) and a scenario
(:class:`~ftc_mc.config.schema.ScenarioConfig`) share every section but the
timing: a campaign's comes from its ``timing`` section, a scenario's from its
``scenario`` section and schedule.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..cache.engine_tables import cached_engine_tables
from ..config.schema import Config, ScenarioConfig
from ..conventions import (CONTROLLER_NAMES, LONGITUDINAL, SELECTED_CONTROLLER_NAMES,
                           VARIANTS)
from ..core.shared.interp import EngineTables
from ..core.longitudinal.settings import (Belief, Controller, Detection, Excitation, FilterModel,
                                          Flight, Reconfig, Scheme, Timing, Track, TruthPlant,
                                          Validity)
from ..design.lqr import controller_weights, discounted_lqr
from ..design.terminal import terminal_costs
from ..model.linear import LinearPlant
from ..model.source import load_plant
from ..model.turbulence import DrydenModel
from .designs import NO_POLICY, Design, build_designs
from .estimator import (EstimatorSettings, belief_settings, detection, filter_model,
                        initial_covariance)
from .noise import lateral_noise
from .truth import sixdof_truth_plant, truth_plant

CONTROLLER_KINDS = {"nominal": 0, "reconfiguring": 1, "lock_turn": 2, "lock_turn_selected": 3}
"""``Reconfig.kind`` of each controller kind (``controller.kind``, a design's
``controller``)."""


@dataclasses.dataclass(frozen=True)
class SimSetup:
    """Kernel settings of a campaign, sweep or scenario (all picklable).

    Attributes
    ----------
    plant : LinearPlant
    est : EstimatorSettings
        The config's estimator settings (signature of the first design run).
    fm : FilterModel
        The paper's filter model at the config's estimator settings (the
        controllers' terminal costs are built on it).
    det : dict of str to Detection
        Each design run's detection at its thresholds.
    designs : dict of str to Design
        The designs run, in order (``ftc_mc/sim/designs.py``).
    bs : Belief
    ctl : Controller
    exc : Excitation
    tim : Timing
    val : Validity
    rc : Reconfig
    eng : EngineTables
        Theorem 4.1 tables of the engine-fault controller c1.
    P0 : ndarray, shape (14, 14)
        Initial covariance of the paper's filter.
    q_std, r_std : ndarray
        Truth noise standard deviations (9,) and (12,).
    beta : tuple
        ``(beta_engine, beta_elevon)``: the ``b1`` above which an actuator's
        truth counts as faulty (the mode of a schedule entry).
    truth : TruthPlant
        The simulated plant (linear or nonlinear, gusts or still air).
    gust : DrydenModel or None
        The gust model (None in still air).
    gust_chol : ndarray or None
        Cholesky factor of the stationary gust-state covariance (None in still air).
    dof : int
        3 (longitudinal truth) or 6 (``truth`` a ``SixDofTruth``).
    lat_std : ndarray or None
        6-DOF: noise standard deviations (5,) of the lateral loop's measured states.
    gust_lat_chol : ndarray or None
        6-DOF in turbulence: Cholesky factor of the lateral gust states' stationary
        covariance.
    track : Track or None
        The glide path's cross-track error of the truth state (None: built from
        ``plant`` and ``truth`` when read, :attr:`flight`).
    selection : tuple or None
        ``(Reconfig, Belief)`` of a ``lock_turn_selected`` design
        (:func:`ftc_mc.sim.selection.selection_settings`); None when no design
        of the run flies one.
    laws : dict or None
        ``(ctl, eng, rc)`` of each LQR weighting a design of the run flies
        (``paper``, ``airspeed``: :func:`control_laws`); ``ctl``, ``eng`` and
        ``rc`` are the controller section's entry.
    """

    plant: LinearPlant
    est: EstimatorSettings
    fm: FilterModel
    det: dict
    designs: dict
    bs: Belief
    ctl: Controller
    exc: Excitation
    tim: Timing
    val: Validity
    rc: Reconfig
    eng: EngineTables
    P0: np.ndarray
    q_std: np.ndarray
    r_std: np.ndarray
    beta: tuple
    truth: TruthPlant
    gust: DrydenModel | None
    gust_chol: np.ndarray | None
    dof: int = 3
    lat_std: np.ndarray | None = None
    gust_lat_chol: np.ndarray | None = None
    track: Track | None = None
    selection: tuple | None = None
    laws: dict | None = None

    def scheme(self, name: str, detection: Detection | None = None) -> Scheme:
        """The kernels' :class:`Scheme` of the design ``name``: its filter, its
        detection (or ``detection``), its excitation policy, its controller
        kind and settings (:meth:`reconfig_of`), the belief its selection reads,
        and c0's gain and c1's tables of its LQR weights (its own ``weights``,
        from :attr:`laws`; else the config's)."""
        d: Design = self.designs[name]
        rc = self.reconfig_of(name)
        bs = self.selection[1] if rc.kind == CONTROLLER_KINDS["lock_turn_selected"] else self.bs
        ctl, eng = self.ctl, self.eng
        if d.weights is not None:
            ctl, eng, _ = self.laws[d.weights]
        return Scheme(filter=d.fm, detection=d.det if detection is None else detection,
                      belief=bs, controller=ctl,
                      excitation=self.exc._replace(**d.excitation),
                      reconfig=rc, engine=eng)

    def reconfig_of(self, name: str) -> Reconfig:
        """The kernels' :class:`Reconfig` of the design ``name``: the config's,
        or that of the design's own LQR weights (its ``q_lqr``, ``r_lqr`` and
        J^N, from :attr:`laws`), with the design's own controller kind when it
        sets one; a ``lock_turn_selected`` design's is the 6-DOF selection's
        (``selection``)."""
        d: Design = self.designs[name]
        base = self.rc if d.weights is None else self.laws[d.weights][2]
        code = self.rc.kind if d.controller is None else CONTROLLER_KINDS[d.controller]
        if code == CONTROLLER_KINDS["lock_turn_selected"]:
            return self.selection[0]
        return base._replace(kind=code)

    @property
    def flight(self) -> Flight:
        """The kernels' :class:`Flight`: timing, validity, truth plant and the
        glide path's cross-track error."""
        return Flight(timing=self.tim, validity=self.val, plant=self.truth,
                      track=self.track if self.track is not None else
                      track_of(self.plant, self.truth, self.dof))

    def detection(self, name: str, t_q: float, t_nx: float) -> Detection:
        """Table 1 settings of the design ``name`` at the thresholds ``(t_q, t_nx)``
        (its residual test kept).

        Both infinite: no reset ever happens (the reset variances are then those
        of the design's thresholds, and never used).
        """
        return self.designs[name].detection(self.plant, t_q, t_nx)


def track_of(plant: LinearPlant, truth, dof: int) -> Track:
    """The :class:`Track` of a truth plant: the rows of ``x`` and ``z`` in its
    state (the 6-DOF state's of the same names on the 6-DOF plant) and the trim
    flight-path angle's sine and cosine."""
    ix, iz = LONGITUDINAL.state("x"), LONGITUDINAL.state("z")
    if dof == 6:
        ix, iz = int(truth.lon_state[ix]), int(truth.lon_state[iz])
    g = float(plant.trim.gamma0)
    return Track(ix=ix, iz=iz, sin_g=math.sin(g), cos_g=math.cos(g))


def runs_of(cfg: Config | ScenarioConfig) -> tuple:
    """Names of the designs a config runs, in order: a campaign's signature
    variants then ``campaign.designs``; a scenario's ``scenario.design``, or its
    signature variant."""
    if isinstance(cfg, ScenarioConfig):
        return (cfg.scenario.design or cfg.scenario.signature,)
    return cfg.campaign.runs()


def controller_names(sc: ScenarioConfig) -> tuple:
    """The names of the controller codes a scenario's design flies: the
    paper's three, or the four of a ``lock_turn_selected`` design."""
    selected = sc.controller_of(runs_of(sc)[0]) == "lock_turn_selected"
    return SELECTED_CONTROLLER_NAMES if selected else CONTROLLER_NAMES


def timing_of(cfg: Config | ScenarioConfig) -> Timing:
    """The kernels' :class:`Timing` of a config.

    A campaign switches to the final mode at ``timing.fault_time_s``; a scenario
    at its last schedule entry (the kernels' ``k_fault`` only starts the search
    for the detection of the final mode, which a scenario does not read).
    """
    if isinstance(cfg, ScenarioConfig):
        sc = cfg.scenario
        return Timing(n_steps=cfg.steps(sc.duration_s),
                      k_fault=cfg.steps(sc.schedule[-1].time_s),
                      reconf_every=cfg.steps(sc.reconfiguration_period_s),
                      detect_prob=float(sc.detection_probability))
    t = cfg.timing
    return Timing(n_steps=cfg.steps(t.duration_s), k_fault=cfg.steps(t.fault_time_s),
                  reconf_every=cfg.steps(t.reconfiguration_period_s),
                  detect_prob=float(t.detection_probability))


def control_laws(cfg: Config | ScenarioConfig, plant: LinearPlant, fm, weights: str):
    """c0's gain, c1's Theorem 4.1 tables and the selection's settings under the
    LQR ``weights`` (``paper`` or ``airspeed``, on ``cfg.controller``'s scales).

    Returns
    -------
    ctl : Controller
        c0 (eq. 19) and the command limits.
    eng : EngineTables
        c1's tables (eq. 44), cached on disk by their weights.
    rc : Reconfig
        The selection's settings (eqs. 45-47) with its terminal costs J^N.
    """
    c = cfg.controller
    Q, R = controller_weights(c, plant.trim.gamma0, weights)
    K, _ = discounted_lqr(plant.A, plant.B, Q, R, c.discount)
    ctl = Controller(K=np.ascontiguousarray(K), lo_dev=plant.u_lower - plant.u0,
                     hi_dev=plant.u_upper - plant.u0)
    eng = cached_engine_tables(plant, Q=Q, R=R, alpha=c.discount)
    q_diag, r_diag = np.ascontiguousarray(np.diag(Q)), np.ascontiguousarray(np.diag(R))
    JN = terminal_costs(fm, ctl.K, eng, ctl.lo_dev, ctl.hi_dev, c.discount, q_diag,
                        r_diag, cfg.steps(c.terminal_horizon_s))
    rc = Reconfig(kind=CONTROLLER_KINDS[c.kind], horizon=cfg.steps(c.horizon_s),
                  alpha=float(c.discount), q_lqr=q_diag, r_lqr=r_diag, JN=JN,
                  penalty=c.switch_penalty * (1.0 - np.eye(3)))
    return ctl, eng, rc


def build_setup(cfg: Config | ScenarioConfig) -> SimSetup:
    """Trim, linearise, design the controllers and pack the kernel settings.

    Parameters
    ----------
    cfg : Config or ScenarioConfig
        A validated campaign, sweep or scenario configuration.

    Returns
    -------
    SimSetup
    """
    runs = runs_of(cfg)
    m = cfg.model
    vc = cfg.validity
    plant = load_plant(m.airframe, m.airspeed_mps, m.gamma_deg, m.dt_s,
                       (math.radians(vc.alpha_min_deg), math.radians(vc.alpha_max_deg)))
    first = runs[0] if runs[0] in VARIANTS else VARIANTS[0]
    est = EstimatorSettings.from_config(cfg.estimator, first)
    fm = filter_model(plant, est)
    designs = build_designs(runs, cfg.designs, plant, cfg.estimator, cfg.plant.altitude_m,
                            float(cfg.monitor.threshold))
    bs = belief_settings(plant, est)
    c = cfg.controller
    laws = {w: control_laws(cfg, plant, fm, w)
            for w in dict.fromkeys([c.weights, *(d.weights for d in designs.values()
                                                 if d.weights is not None)])}
    ctl, eng, rc = laws[c.weights]
    x = cfg.excitation
    exc = Excitation(doublet_amp=float(x.doublet_amplitude),
                     doublet_half=cfg.steps(x.doublet_half_period_s),
                     s3211_amp=float(x.s3211_amplitude_rad),
                     s3211_unit=cfg.steps(x.s3211_unit_s),
                     resend_delay=cfg.steps(x.resend_delay_s),
                     resend_b1=float(x.resend_b1_threshold),
                     policy_doublet_amp=float(x.doublet_amplitude),
                     policy_s3211_amp=float(x.s3211_amplitude_rad),
                     **NO_POLICY)
    val = Validity(va_trim=float(plant.trim.y0[LONGITUDINAL.output("Va")]),
                   va_min=vc.airspeed_min_mps,
                   va_max=vc.airspeed_max_mps, alpha_trim=plant.trim.alpha,
                   alpha_min=math.radians(vc.alpha_min_deg),
                   alpha_max=math.radians(vc.alpha_max_deg),
                   psd_every=cfg.steps(vc.psd_check_period_s),
                   bank_max=math.radians(vc.bank_max_deg))
    pc = cfg.plant
    r_std = cfg.noise.measurement_scale * np.sqrt(fm.r_diag)
    lat_std = gust_lat_chol = selection = None
    if pc.dof == 6:
        from .monitor import monitor_spec  # the 6-DOF family only on its path

        truth, gust, gust_lat = sixdof_truth_plant(
            plant, pc.kind, pc.substeps, pc.turbulence, pc.altitude_m,
            monitor=monitor_spec(cfg, fm, detection(plant, EstimatorSettings()),
                                 lock_turn=cfg.flies_lock_turn(runs)),
            paper=((ctl.K, eng, *controller_weights(c, plant.trim.gamma0), c.discount)
                   if c.coupling == "coupled" else None))
        lat_std = lateral_noise(r_std)
        gust_lat_chol = None if gust_lat is None else gust_lat.P0_chol
        if cfg.selects_four(runs):
            from .selection import selection_settings

            selection = selection_settings(truth, ctl, eng, rc, bs,
                                           cfg.steps(c.terminal_horizon_s))
    else:
        truth, gust = truth_plant(plant, pc.kind, pc.substeps, pc.turbulence, pc.altitude_m)
    return SimSetup(
        plant=plant, est=est, fm=fm, det={n: d.det for n, d in designs.items()},
        designs=designs, bs=bs, ctl=ctl, exc=exc, tim=timing_of(cfg),
        val=val, rc=rc, eng=eng,
        # the paper's thresholds set the initial fault variances whatever thresholds
        # are run, so trials share their pre-fault part across a threshold sweep
        P0=initial_covariance(fm, detection(plant, EstimatorSettings())),
        q_std=cfg.noise.process_scale * np.sqrt(fm.q_diag[:LONGITUDINAL.n_x]),
        r_std=r_std,
        beta=(cfg.estimator.beta_engine, cfg.estimator.beta_elevon),
        truth=truth, gust=gust, gust_chol=None if gust is None else gust.P0_chol,
        dof=pc.dof, lat_std=lat_std, gust_lat_chol=gust_lat_chol,
        track=track_of(plant, truth, pc.dof), selection=selection, laws=laws)
