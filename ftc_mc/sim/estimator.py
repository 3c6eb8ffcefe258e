"""The estimator's kernel settings (namedtuples of arrays) from the plant and options.

This is the bridge between the linear plant and :mod:`ftc_mc.core`: the
augmented filter model (eqs. 4-6), the Table 1 detection with its reset
variances (section 3.2.2), and the mode boxes of the belief (eq. 12).  Paper
values (section 5.1): ``Q^x = 0.01^2 dt I_9``, ``Q^b = 0.001^2 dt I_5``, R from
the sensor accuracies (``e^{-2}`` read as 1e-2 and ``e^{-6}`` as 1e-6,
docs/reference/paper-map.md), thresholds ``t_q = t_nx = 25`` and the transition matrix
``T_M``.  The tunable values come from the validated ``estimator`` section
(:class:`~ftc_mc.config.schema.EstimatorConfig`, which holds their defaults);
the builders here trust them.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..config.schema import EstimatorConfig
from ..conventions import LONGITUDINAL, N_AUG, N_U, RESETS_TABLE1, TEST_ONE_STEP, VARIANTS
from ..core.longitudinal.settings import (Belief, Detection, FilterModel, decision_table,
                                          thresholds_of)
from ..model.faults import bias_matrix, fault_bounds
from ..model.linear import LinearPlant

DEG = math.pi / 180.0
_ANG = (0.05 * DEG) ** 2

PAPER_R_DIAG = (1e-2, 1e-2, _ANG, 1e-2, 1e-2, _ANG, 1e-6, 1e-6, _ANG, _ANG, 1e-2, 1e-2)
"""Measurement noise variances of the 12 outputs (paper section 5.1)."""

PAPER_TM = (
    (1 - 1e-7 - 2e-8, 1e-9, 1e-9, 1e-9),
    (1e-7, 1 - 1e-9 - 2e-17, 1e-16, 1e-16),
    (1e-8, 1e-17, 1 - 1e-9 - 1e-16 - 1e-17, 1e-17),
    (1e-8, 1e-17, 1e-17, 1 - 1e-9 - 1e-16 - 1e-17),
)
"""Mode transition matrix T_M (paper section 5.1), column j = from mode j."""

_PAPER = EstimatorConfig()
"""The schema's defaults: the paper's values (section 5.1)."""


@dataclasses.dataclass(frozen=True)
class EstimatorSettings:
    """Settings of the estimation, detection and belief (section 3), as the builders
    below read them: the ``estimator`` section of a validated config plus the
    signature variant, ``R`` and ``T_M``.  Defaults are the schema's; nothing is
    validated here (:meth:`from_config` takes values the schema has checked).

    Parameters
    ----------
    sigma_qx : float
        Process-noise density of the plant states: ``Q^x = sigma_qx^2 dt I``.
    sigma_qb : float
        Random-walk density of the fault parameters: ``Q^b = sigma_qb^2 dt I``.
    r_diag : tuple of 12 float
        Measurement noise variances (output units squared).
    t_q, t_nx : float
        Residual thresholds of Table 1 (dimensionless, > 0).
    signature : str
        ``"paper"`` (Table 1 as printed) or ``"swapped"``.
    beta_engine, beta_elevon : float
        Effectiveness loss above which an actuator counts as faulty in the mode
        boxes (docs/reference/paper-map.md).
    b0_nominal_engine, b0_nominal_elevon : float
        Half-width of the nominal box of b0 (throttle [-], elevon sum [rad]).
    tm : tuple
        Mode transition matrix (column-stochastic).
    """

    sigma_qx: float = _PAPER.sigma_qx
    sigma_qb: float = _PAPER.sigma_qb
    r_diag: tuple = PAPER_R_DIAG
    t_q: float = _PAPER.t_q
    t_nx: float = _PAPER.t_nx
    signature: str = VARIANTS[0]
    beta_engine: float = _PAPER.beta_engine
    beta_elevon: float = _PAPER.beta_elevon
    b0_nominal_engine: float = _PAPER.b0_nominal_engine
    b0_nominal_elevon: float = _PAPER.b0_nominal_elevon
    tm: tuple = PAPER_TM

    @classmethod
    def from_config(cls, est: EstimatorConfig, signature: str) -> "EstimatorSettings":
        """The settings of a validated ``estimator`` section for one signature variant."""
        return cls(signature=signature, **est.model_dump())


def unit_rows(C: np.ndarray) -> np.ndarray:
    """For each row of ``C``, the state index if it is a unit row, else -1."""
    out = np.full(C.shape[0], -1, dtype=np.int64)
    for r, row in enumerate(C):
        nz = np.flatnonzero(row != 0.0)
        if len(nz) == 1 and row[nz[0]] == 1.0:
            out[r] = nz[0]
    return out


def filter_model(plant: LinearPlant, s: EstimatorSettings) -> FilterModel:
    """Augmented filter model (eqs. 4-6) of a plant.

    Parameters
    ----------
    plant : LinearPlant
    s : EstimatorSettings

    Returns
    -------
    FilterModel
    """
    assert s.sigma_qx > 0 and s.sigma_qb > 0 and len(s.r_diag) == plant.C.shape[0], s
    C = plant.C
    n = plant.A.shape[0]
    q = np.empty(N_AUG)
    q[:n] = s.sigma_qx ** 2 * plant.dt
    q[n:] = s.sigma_qb ** 2 * plant.dt
    lo, hi = fault_bounds(plant.u_lower, plant.u_upper)
    return FilterModel(
        A=np.ascontiguousarray(plant.A), B=np.ascontiguousarray(plant.B),
        Bb0=np.ascontiguousarray(bias_matrix(plant.B)), C=np.ascontiguousarray(C),
        c_ident=unit_rows(C), u0=plant.u0.copy(), q_diag=q,
        r_diag=np.asarray(s.r_diag, dtype=float).copy(), lo=lo, hi=hi,
        # the paper's filter has no gust states (a gust-aware design adds them)
        G=np.zeros((n, 0)), Ad=np.zeros((0, 0)), Dg=np.zeros((C.shape[0], 0)),
        Qg=np.zeros((0, 0)),
        # linear prediction; an extended design switches nl on (sim/designs.py)
        nl=0, p=(np.zeros(25) if plant.trim.params is None  # a linear-model file
                 else np.ascontiguousarray(plant.trim.params, dtype=np.float64)),
        x0=np.ascontiguousarray(plant.trim.x0, dtype=np.float64),
        y0=np.ascontiguousarray(plant.trim.y0, dtype=np.float64), Cg=np.zeros((3, 0)),
        n_sub=10, dt=float(plant.dt),
        # no wind Jacobians (a gust-aware design sets them) and no re-linearisation
        Bw=np.zeros((n, 3)), Dw=np.zeros((C.shape[0], 3)), relin=0,
        Dz=np.zeros((C.shape[0], 0)), reset_g=np.zeros((3, 0)))


def detection(plant: LinearPlant, s: EstimatorSettings) -> Detection:
    """Table 1 settings and the reset variances of section 3.2.2.

    Thrust block: ``((u_max - u_min)/t_nx)^2`` for b0, ``1/t_nx^2`` for b1;
    elevon block: ``((u_max - u_min)/t_q)^2`` (one elevon's range) for the b0
    sum, ``1/t_q^2`` for both b1.
    """
    assert s.t_q > 0 and s.t_nx > 0 and s.signature in VARIANTS, s
    rng = plant.u_upper - plant.u_lower
    reset_var = np.array([(rng[0] / s.t_nx) ** 2, (rng[1] / s.t_q) ** 2,
                          1.0 / s.t_nx ** 2, 1.0 / s.t_q ** 2, 1.0 / s.t_q ** 2])
    return Detection(thresholds=thresholds_of(s.t_q, s.t_nx),
                     table=decision_table(s.signature), reset_var=reset_var,
                     test=TEST_ONE_STEP, window=1, min_window=1, clip=math.inf, settle=0,
                     startup=0, source=RESETS_TABLE1, side_thresholds=np.full(N_U, math.inf))


def belief_settings(plant: LinearPlant, s: EstimatorSettings) -> Belief:
    """Mode boxes of eq. (12) and ``T_M`` (docs/reference/paper-map.md).

    Parameters are ``[b0_T, b0_e, b1_T, b1_L, b1_R]``.  Nominal: every ``b1`` in
    ``[0, beta]`` and each ``b0`` within ``+-b0_nominal``.  Actuator ``i`` faulty:
    its ``b1`` in ``[beta_i, 1]``, its ``b0`` free over its command range (a lock
    has ``b1 = 1``, ``b0`` = the lock position), every other parameter nominal.
    """
    assert 0 < s.beta_engine < 1 and 0 < s.beta_elevon < 1, s
    be, bt = s.beta_elevon, s.beta_engine
    d_t, d_e = s.b0_nominal_engine, s.b0_nominal_elevon
    nom_lo = np.array([-d_t, -d_e, 0.0, 0.0, 0.0])
    nom_hi = np.array([d_t, d_e, bt, be, be])
    lo = np.tile(nom_lo, (4, 1))
    hi = np.tile(nom_hi, (4, 1))
    lo[1, 0], hi[1, 0] = plant.u_lower[0], plant.u_upper[0]
    lo[1, 2], hi[1, 2] = bt, 1.0
    for m, j in ((2, 3), (3, 4)):
        lo[m, 1], hi[m, 1] = plant.u_lower[1], plant.u_upper[1]
        lo[m, j], hi[m, j] = be, 1.0
    return Belief(TM=np.asarray(s.tm, dtype=float).copy(), lo=lo, hi=hi)


def initial_covariance(fm: FilterModel, det: Detection) -> np.ndarray:
    """Initial covariance: ``10 Q`` on the states, the reset variances on the faults.

    The fault variances equal those of a reset of both blocks, i.e. the filter
    starts as if every fault parameter had just been suspected.
    """
    P = np.diag(10.0 * fm.q_diag)
    P[LONGITUDINAL.faults, LONGITUDINAL.faults] = np.diag(det.reset_var)
    return P


