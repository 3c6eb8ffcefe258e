"""Scratch arrays of the trial kernels, two namedtuples built once per call.

:class:`TrialWork` holds everything :func:`ftc_mc.core.longitudinal.trial.advance` and its
stages (:mod:`ftc_mc.core.longitudinal.stages`, :mod:`ftc_mc.core.longitudinal.plant`) need between the
state of a trial (:class:`~ftc_mc.core.longitudinal.settings.LaneState`) and its record:
lane arrays (lane index last, see :mod:`ftc_mc.core.longitudinal.batch`) that one stage
writes and the next reads, and small one-lane buffers for the kernels that run
a lane at a time (nonlinear plant, belief, controller selection).
:class:`LaneSelectionWork` is the scratch of :func:`ftc_mc.core.longitudinal.control.select_controllers_lanes`.

Every size comes from :mod:`ftc_mc.conventions` or from the augmented dimension
``n`` passed in (taken from the state's arrays), never from a literal.  The
builders are kernels, so ``advance`` allocates its workspace once per call.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ...conventions import (N_AUG, N_CONTROLLERS, N_FAULT, N_MODES, N_U, N_X, N_Z, RESIDUAL_NAMES)
from .batch import UPDATE_ROWS, step_rows
from ..shared.dryden import N_GUST_NOISE, N_GUST_OUT, N_GUST_STATE
from ..jit import kernel
from .gustfilter import N_TANGENT, N_WIND
from .nonlinear import N_PARTIAL, N_WORK

N_RES = len(RESIDUAL_NAMES)

EXC_DOUBLET, EXC_3211, EXC_DOUBLET_START, EXC_3211_START = range(4)
"""Rows of :attr:`TrialWork.exc` and of the record's ``hist_exc``: the doublet
value on the engine, the 3211 value on the left elevon (minus on the right),
then 1.0 on the step where each signal started."""
N_EXC = 4


LaneSelectionWork = namedtuple("LaneSelectionWork", [
    # lane arrays (lane index last)
    "xs",      # (n L,) estimates predicted over the horizon, viewed as (n, L') (L' <= L)
    "Ps",      # (n n L,) their covariances, viewed as (n, n, L')
    "U",       # (N_U, L) commands of the controller under test
    "z",       # (N_Z, L) predicted measurements (zero innovation)
    "phi",     # (N_X, N_FAULT, L) Phi(u) (batch.predict_lanes)
    "T",       # (N_X, n, L) [A Phi] P (batch.predict_lanes)
    "h",       # (UPDATE_ROWS, n, L) gains of the update (batch.update_lanes)
    "cost",    # (L,) discounted short-horizon cost (eq. 45)
    "obj",     # (N_CONTROLLERS, L) objective of each controller (eq. 47), +inf if not computed
    "floor",   # (N_CONTROLLERS, L) lower bound of each objective from its cost alone
    "cand",    # (L,) int64 controller of each predicted entry
    "lane",    # (L,) int64 lane of each predicted entry
    # one lane at a time
    "xl",      # (n,) a lane's predicted estimate (engine controller c1)
    "Ul",      # (N_U,) its command
    "bl",      # (N_MODES,) a lane's belief updated with the prediction
    "bhat",    # (N_FAULT,) its predicted fault parameters
    "bvar",    # (N_FAULT,) their predicted variances
    "bwork",   # (2 N_MODES,) work of belief.belief_update
])
"""Scratch of the lane-interleaved controller selection
(:func:`ftc_mc.core.longitudinal.control.select_controllers_lanes`)."""

TrialWork = namedtuple("TrialWork", [
    # lane arrays, written by one stage and read by the next
    "u",          # (N_U, L) commands applied during the step (eq. 15)
    "exc",        # (N_EXC, L) excitation values and starts (EXC_* rows)
    "e",          # (N_U, L) actuator effects (eq. 2)
    "wind",       # (3, L) gust u_g, w_g [m/s], q_g [rad/s] held over the step
    "wind_next",  # (3, L) gust at the next sample, seen by its measurement
    "x_next",     # (N_X, L) next state of the linear plant
    "z",          # (N_Z, L) measurements (deviations from the trim outputs)
    "va",         # (L,) true airspeed [m/s] (air-relative)
    "alpha",      # (L,) true angle of attack [rad] (air-relative)
    "bank",       # (L,) true bank angle [rad] (6-DOF plant; zeros otherwise)
    "phi",        # (N_X, N_FAULT, L) filter work (batch.filter_step_lanes)
    "T",          # (n, n, L) filter work (the paper's filter uses N_X rows)
    "fwork",      # (step_rows(n), n, L) filter work
    "res",        # (N_RES, L) residuals r_q, r_nx, r_nz (eqs. 9-11)
    "block",      # (L,) int64 block reset this step (Table 1)
    "innov",      # (N_RES, L) signed normalised innovations (the GLR test's input)
    "xsel",       # (N_AUG, L) the paper's part of a gust-aware estimate (selection)
    "Psel",       # (N_AUG, N_AUG, L) its covariance
    "finite",     # (L,) bool: the lane's estimate, variances and air data are finite
    "jg",         # (N_X, n - N_AUG, L) a re-linearised extended filter's G = JW C_d
    "jc",         # (n, L) a row of its C_aug per lane, [JC_r, 0, JHW_r C_d]
    "jx",         # (5, N_X, L) its RK4 of the state map: state, stage point, slope sum,
                  # slope, a tangent column's slope
    "jd",         # (N_PARTIAL, L) the airframe's partials at the stage points
    "jcw",        # (N_U + N_WIND, L) each lane's commands and wind held over the period
    "jt",         # (3, N_X, N_TANGENT, L) the tangent: Jacobian so far, stage's, slope sum
    # one lane at a time
    "xl",         # (n,) a lane's estimate
    "Ul",         # (N_U,) a lane's command
    "chol",       # (n, n) Cholesky factor of the positive-definiteness test
    "crow",       # (n,) a row of the gust-aware filter's C_aug
    "gust",       # (N_GUST_STATE,) a lane's gust filter state
    "eta",        # (N_GUST_NOISE,) a lane's gust draws
    "wl",         # (N_GUST_OUT,) a lane's gust
    "xabs",       # (N_X,) a lane's absolute state (nonlinear plant)
    "cmd",        # (N_U,) a lane's absolute effective commands
    "y",          # (N_Z,) a lane's absolute outputs
    "jl",         # (N_PARTIAL,) a lane's partials (nonlinear.derivatives_partials_nb)
    "rk4",        # (N_WORK, N_X) RK4 work (nonlinear.propagate)
    "bl",         # (N_MODES,) a lane's belief
    "bhat",       # (N_FAULT,) a lane's fault-parameter estimate
    "bvar",       # (N_FAULT,) its marginal variances
    "bwork",      # (2 N_MODES,) work of belief.belief_update
    "lsel",       # LaneSelectionWork
])
"""Scratch of one :func:`ftc_mc.core.longitudinal.trial.advance` call (see module docstring)."""


@kernel(internal=True)
def new_lane_selection_work(L, n):
    """Zeroed :class:`LaneSelectionWork` for ``L`` lanes and augmented dimension ``n``."""
    return LaneSelectionWork(
        xs=np.zeros(n * L), Ps=np.zeros(n * n * L), U=np.zeros((N_U, L)),
        z=np.zeros((N_Z, L)), phi=np.zeros((N_X, N_FAULT, L)), T=np.zeros((N_X, n, L)),
        h=np.zeros((UPDATE_ROWS, n, L)), cost=np.zeros(L), obj=np.zeros((N_CONTROLLERS, L)),
        floor=np.zeros((N_CONTROLLERS, L)),
        cand=np.zeros(L, dtype=np.int64), lane=np.zeros(L, dtype=np.int64),
        xl=np.zeros(n), Ul=np.zeros(N_U), bl=np.zeros(N_MODES), bhat=np.zeros(N_FAULT),
        bvar=np.zeros(N_FAULT), bwork=np.zeros(2 * N_MODES))


@kernel(by_address=True)
def new_trial_work(L, n):
    """Zeroed :class:`TrialWork` for ``L`` lanes and augmented dimension ``n``.

    The gust arrays stay zero in still air (nothing writes them then).
    """
    return TrialWork(
        u=np.zeros((N_U, L)), exc=np.zeros((N_EXC, L)), e=np.zeros((N_U, L)),
        wind=np.zeros((N_GUST_OUT, L)), wind_next=np.zeros((N_GUST_OUT, L)),
        x_next=np.zeros((N_X, L)), z=np.zeros((N_Z, L)), va=np.zeros(L),
        alpha=np.zeros(L), bank=np.zeros(L), phi=np.zeros((N_X, N_FAULT, L)), T=np.zeros((n, n, L)),
        fwork=np.zeros((step_rows(n), n, L)), res=np.zeros((N_RES, L)),
        block=np.zeros(L, dtype=np.int64), innov=np.zeros((N_RES, L)),
        xsel=np.zeros((N_AUG, L)), Psel=np.zeros((N_AUG, N_AUG, L)),
        finite=np.zeros(L, dtype=np.bool_),
        jg=np.zeros((N_X, max(n - N_AUG, 0), L)), jc=np.zeros((n, L)),
        jx=np.zeros((5, N_X, L)), jd=np.zeros((N_PARTIAL, L)),
        jcw=np.zeros((N_U + N_WIND, L)), jt=np.zeros((3, N_X, N_TANGENT, L)),
        xl=np.zeros(n), Ul=np.zeros(N_U), chol=np.zeros((n, n)),
        crow=np.zeros(n),
        gust=np.zeros(N_GUST_STATE), eta=np.zeros(N_GUST_NOISE), wl=np.zeros(N_GUST_OUT),
        xabs=np.zeros(N_X), cmd=np.zeros(N_U), y=np.zeros(N_Z), jl=np.zeros(N_PARTIAL),
        rk4=np.zeros((N_WORK, N_X)), bl=np.zeros(N_MODES), bhat=np.zeros(N_FAULT),
        bvar=np.zeros(N_FAULT), bwork=np.zeros(2 * N_MODES),
        lsel=new_lane_selection_work(L, N_AUG))
