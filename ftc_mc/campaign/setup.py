"""Everything a campaign needs that does not change from trial to trial.

Built once in the parent process from the validated configuration and shipped
to the workers (small arrays in namedtuples, cheap to pickle).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..core.interp import EngineTables
from ..core.settings import (Belief, Controller, Excitation, FilterModel, Flight,
                             Reconfig, Scheme, Timing, TruthPlant, Validity)
from ..design.terminal import terminal_costs
from ..design.theorem41 import cached_engine_tables
from ..design.lqr import discounted_lqr, paper_q_lqr
from ..errors import UserError
from ..estimator import (EstimatorSettings, belief_settings, detection, filter_model,
                         initial_covariance)
from ..io.config import Config
from ..model.airframe import X8
from ..model.linear import LinearPlant, build_plant
from ..model.turbulence import DrydenModel
from ..truth import truth_plant

VARIANTS = ("paper", "swapped")


@dataclasses.dataclass(frozen=True)
class CampaignSetup:
    """Kernel settings of a campaign (all picklable).

    Attributes
    ----------
    plant : LinearPlant
    fm : FilterModel
    det : dict of str to Detection
        One per signature variant run.
    bs : Belief
    ctl : Controller
    exc : Excitation
    tim : Timing
    val : Validity
    rc : Reconfig
    eng : EngineTables
        Theorem 4.1 tables of the engine-fault controller c1.
    P0 : ndarray, shape (14, 14)
        Initial covariance.
    q_std, r_std : ndarray
        Truth noise standard deviations (9,) and (12,).
    lock_range : dict of int to tuple
        Lock position range per actuator index (0 engine, 1 left elevon).
    loss_range : tuple
    beta : tuple
        ``(beta_engine, beta_elevon)``.
    near_trim : tuple
        ``(engine, elevon)`` half-widths of a lock 'near trim'.
    truth : TruthPlant
        The simulated plant (linear or nonlinear, gusts or still air).
    gust : DrydenModel or None
        The gust model (None in still air).
    gust_chol : ndarray or None
        Cholesky factor of the stationary gust-state covariance (None in still air).
    """

    plant: LinearPlant
    fm: FilterModel
    det: dict
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
    lock_range: dict
    loss_range: tuple
    beta: tuple
    near_trim: tuple
    truth: TruthPlant
    gust: DrydenModel | None
    gust_chol: np.ndarray | None

    def scheme(self, variant: str, detection=None) -> Scheme:
        """The kernels' :class:`Scheme` for one signature variant (or ``detection``)."""
        return Scheme(filter=self.fm, detection=self.det[variant] if detection is None
                      else detection, belief=self.bs, controller=self.ctl,
                      excitation=self.exc, reconfig=self.rc, engine=self.eng)

    @property
    def flight(self) -> Flight:
        """The kernels' :class:`Flight`: timing, validity and truth plant."""
        return Flight(timing=self.tim, validity=self.val, plant=self.truth)


def variants_of(signature: str) -> tuple:
    """Signature variants named by the config's ``signature`` field."""
    return VARIANTS if signature == "both" else (signature,)


def estimator_settings(cfg: Config, signature: str) -> EstimatorSettings:
    """The estimator settings of a config for one signature variant."""
    e = cfg.estimator
    return EstimatorSettings(sigma_qx=e.sigma_qx, sigma_qb=e.sigma_qb, t_q=e.t_q,
                             t_nx=e.t_nx, signature=signature,
                             beta_engine=e.beta_engine, beta_elevon=e.beta_elevon,
                             b0_nominal_engine=e.b0_nominal_engine,
                             b0_nominal_elevon=e.b0_nominal_elevon)


def build_setup(cfg: Config) -> CampaignSetup:
    """Trim, linearise, design the controller and pack the kernel settings.

    Parameters
    ----------
    cfg : Config

    Returns
    -------
    CampaignSetup
    """
    m = cfg.model
    plant = build_plant(X8, m.airspeed_mps, m.gamma_deg, m.dt_s)
    variants = variants_of(cfg.campaign.signature)
    settings = {v: estimator_settings(cfg, v) for v in variants}
    s0 = settings[variants[0]]
    fm = filter_model(plant, s0)
    det = {v: detection(plant, s) for v, s in settings.items()}
    bs = belief_settings(plant, s0)
    K, _ = discounted_lqr(plant.A, plant.B, paper_q_lqr(plant.trim.gamma0),
                          cfg.controller.r_lqr * np.eye(3), cfg.controller.discount)
    ctl = Controller(K=np.ascontiguousarray(K), lo_dev=plant.u_lower - plant.u0,
                     hi_dev=plant.u_upper - plant.u0)
    c = cfg.controller
    Q = paper_q_lqr(plant.trim.gamma0)
    R = c.r_lqr * np.eye(3)
    eng = cached_engine_tables(plant, Q=Q, R=R, alpha=c.discount)
    q_diag, r_diag = np.ascontiguousarray(np.diag(Q)), np.ascontiguousarray(np.diag(R))
    JN = terminal_costs(fm, ctl.K, eng, ctl.lo_dev, ctl.hi_dev, c.discount, q_diag,
                        r_diag, cfg.steps(c.terminal_horizon_s))
    penalty = c.switch_penalty * (1.0 - np.eye(3))
    rc = Reconfig(kind=0 if c.kind == "nominal" else 1, horizon=cfg.steps(c.horizon_s),
                  alpha=float(c.discount), q_lqr=q_diag, r_lqr=r_diag, JN=JN,
                  penalty=penalty)
    x = cfg.excitation
    exc = Excitation(doublet_amp=float(x.doublet_amplitude),
                     doublet_half=cfg.steps(x.doublet_half_period_s),
                     s3211_amp=float(x.s3211_amplitude_rad),
                     s3211_unit=cfg.steps(x.s3211_unit_s),
                     resend_delay=cfg.steps(x.resend_delay_s),
                     resend_b1=float(x.resend_b1_threshold))
    t = cfg.timing
    tim = Timing(n_steps=cfg.steps(t.duration_s), k_fault=cfg.steps(t.fault_time_s),
                 reconf_every=cfg.steps(t.reconfiguration_period_s),
                 detect_prob=float(t.detection_probability))
    vc = cfg.validity
    val = Validity(va_trim=float(plant.trim.y0[11]), va_min=vc.airspeed_min_mps,
                   va_max=vc.airspeed_max_mps, alpha_trim=plant.trim.alpha,
                   alpha_min=math.radians(vc.alpha_min_deg),
                   alpha_max=math.radians(vc.alpha_max_deg),
                   psd_every=cfg.steps(vc.psd_check_period_s))
    d = cfg.draws
    lock_range = {0: tuple(d.engine_lock_range or (plant.u_lower[0], plant.u_upper[0])),
                  1: tuple(d.elevon_lock_range_rad or (plant.u_lower[1], plant.u_upper[1]))}
    for a, (lo, hi) in lock_range.items():
        if lo < plant.u_lower[a] or hi > plant.u_upper[a]:
            name = "draws.engine_lock_range" if a == 0 else "draws.elevon_lock_range_rad"
            raise UserError(f"{name}: must lie within the command range "
                            f"[{plant.u_lower[a]:g}, {plant.u_upper[a]:g}], "
                            f"got {[lo, hi]}")
    pc = cfg.plant
    truth, gust = truth_plant(plant, pc.kind, pc.substeps, pc.turbulence, pc.altitude_m)
    return CampaignSetup(
        plant=plant, fm=fm, det=det, bs=bs, ctl=ctl, exc=exc, tim=tim, val=val, rc=rc,
        eng=eng,
        # the paper's thresholds set the initial fault variances whatever thresholds
        # are run, so trials share their pre-fault part across a threshold sweep
        P0=initial_covariance(fm, detection(plant, EstimatorSettings())),
        q_std=cfg.noise.process_scale * np.sqrt(fm.q_diag[:9]),
        r_std=cfg.noise.measurement_scale * np.sqrt(fm.r_diag),
        lock_range=lock_range, loss_range=tuple(d.loss_b1_range),
        beta=(cfg.estimator.beta_engine, cfg.estimator.beta_elevon),
        near_trim=(cfg.explain.engine_lock_near_trim,
                   cfg.explain.elevon_lock_near_trim_rad),
        truth=truth, gust=gust, gust_chol=None if gust is None else gust.P0_chol)
