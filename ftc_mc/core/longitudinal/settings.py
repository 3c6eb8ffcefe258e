"""Namedtuples of arrays that carry settings into the kernels.

Built from the linear plant and the configuration by :mod:`ftc_mc.sim.setup`;
the kernels only read them.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ...conventions import RESIDUAL_NAMES, TABLE1, VARIANTS

FilterModel = namedtuple("FilterModel", [
    "A",        # (9, 9)  discrete state matrix (eq. 1)
    "B",        # (9, 3)  discrete input matrix (eq. 1)
    "Bb0",      # (9, 2)  input matrix of b0 (thrust, elevon sum), eq. (4)
    "C",        # (12, 9) output matrix (eq. 1)
    "c_ident",  # (12,) int64: state index when row r of C is a unit row, else -1
    "u0",       # (3,)  trim commands, absolute
    "q_diag",   # (14,) diagonal of Q (eq. 5; paper section 5.1)
    "r_diag",   # (12,) diagonal of R (paper section 5.1)
    "lo",       # (5,)  lower bounds of b0, b1 (eq. 6)
    "hi",       # (5,)  upper bounds of b0, b1 (eq. 6)
    "G",        # (9, ng)  gust-aware filter: gust states -> plant states (B_w C_d)
    "Ad",       # (ng, ng) gust-state transition (Dryden, core/shared/dryden.py)
    "Dg",       # (12, ng) gust states -> outputs (D_w C_d)
    "Qg",       # (ng, ng) gust-state process noise (B_d B_d^T)
    "nl",       # 0: linear prediction (eq. 5); 1: the nonlinear airframe predicts the
                #    state and the outputs (extended filter, core/longitudinal/gustfilter.py)
    "p",        # (25,) packed airframe parameters (nonlinear prediction)
    "x0",       # (9,)  trim state, absolute
    "y0",       # (12,) trim outputs, absolute
    "Cg",       # (3, ng) gust states -> u_g, w_g [m/s], q_g [rad/s] (C_d)
    "n_sub",    # RK4 sub-steps of the nonlinear prediction per period
    "dt",       # control period [s]
    "Bw",       # (9, 3)  trim wind Jacobian of the discrete state map (G = Bw Cg); zeros
                #         for the paper's filter
    "Dw",       # (12, 3) trim wind Jacobian of the outputs (Dg = Dw Cg); zeros likewise
    "relin",    # steps between re-linearisations of the extended filter's covariance
                #    about each lane's estimate (LaneState.JA ..); 0: the trim Jacobians
    "Dz",       # (12, ng) extra states added to the outputs as they are (a sensor-aware
                #          design's output biases; their columns of Dg too): the
                #          extended filter adds Dz g to h(x, C_d g); zeros for gust states
    "reset_g",  # (3, ng) variance an extra state takes when block 1 (thrust) or 2
                #         (elevons) of Table 1 is reset, row = block; 0: not reset
])
"""The augmented Kalman filter's model (paper eqs. 4-6).

The estimate is ``[x (9), b (5), g (ng)]``: the paper's filter has ``ng = 0``
(the gust arrays are empty, :mod:`ftc_mc.core.longitudinal.batch`); a gust-aware filter
carries the ``ng = 4`` Dryden states of the longitudinal gusts
(:mod:`ftc_mc.core.longitudinal.gustfilter`); a sensor-aware design appends output
biases after them (``Dz``, ``reset_g``)."""

_DetectionFields = namedtuple("Detection", [
    "thresholds",  # (3,) threshold of each residual channel r_q, r_nx, r_nz (Table 1;
                   #      inf: a channel that is only compared, r_nz)
    "table",      # (8, 4) int64 Table 1's decision table: per hit pattern of the
                  #      channels, (block_if, block_else, cmp_a, cmp_b) (conventions.TABLE1)
    "reset_var",  # (5,) variance of each fault parameter after its block's reset
    "test",       # conventions.TEST_ONE_STEP (eqs. 9-11) or TEST_GLR (core/shared/glr.py)
    "window",     # GLR window [steps] (1 with the one-step test)
    "min_window", # shortest change the GLR tests [steps] (1: any; <= window)
    "clip",       # GLR: each normalised innovation enters the window clipped to
                  #      [-clip, clip] (inf: none; DesignConfig.innovation_clip)
    "settle",     # steps after a reset during which the other block is not reset (0: none)
    "startup",    # steps from the start before the test is armed: no reset, GLR window
                  # kept empty (0: armed at once; DesignConfig.startup_s)
    "source",     # conventions.RESETS_TABLE1 (Table 1 decides), RESETS_SIDE_MONITOR
                  # (the 6-DOF side monitor's decisions reset its actuator's block:
                  # core/sixdof/lockturn.py::side_blocks) or RESETS_EITHER (the
                  # monitor's where it decides, else Table 1's; DesignConfig.resets)
    "side_thresholds",  # (3,) the 6-DOF side monitor's GLR threshold of each direction
                        # (throttle, left, right elevon) on this design's lanes
                        # (sim/designs.py::monitor_thresholds)
])


class Detection(_DetectionFields):
    """Residual signature and covariance reset (paper section 3.2.2, Table 1).

    Table 1 is data (``thresholds``, ``table``: ``conventions.TABLE1``); the
    paper's names of its thresholds and variant are read-only views for the
    code outside the kernels, and :meth:`_replace` also takes them.
    """

    __slots__ = ()

    @property
    def t_q(self) -> float:
        """Threshold on ``r_q``."""
        return float(self.thresholds[RESIDUAL_NAMES.index("r_q")])

    @property
    def t_nx(self) -> float:
        """Threshold on ``r_nx``."""
        return float(self.thresholds[RESIDUAL_NAMES.index("r_nx")])

    @property
    def swapped(self) -> int:
        """1 when the table is the swapped variant's, 0 for Table 1 as printed."""
        return int(np.array_equal(self.table, decision_table("swapped")))

    def _replace(self, **kw):
        """``namedtuple._replace``, also taking ``t_q``, ``t_nx`` and ``swapped``."""
        if {"t_q", "t_nx"} & kw.keys():
            thr = np.array(self.thresholds, dtype=float, copy=True)
            for name in ("t_q", "t_nx"):
                if name in kw:
                    thr[RESIDUAL_NAMES.index("r_" + name[2:])] = float(kw.pop(name))
            kw["thresholds"] = thr
        if "swapped" in kw:
            kw["table"] = decision_table(VARIANTS[int(bool(kw.pop("swapped")))])
        return super()._replace(**kw)


def thresholds_of(t_q: float, t_nx: float) -> np.ndarray:
    """Table 1's thresholds vector (one per residual channel; ``inf`` on a
    channel that has none)."""
    thr = np.full(len(RESIDUAL_NAMES), np.inf)
    thr[RESIDUAL_NAMES.index("r_q")] = float(t_q)
    thr[RESIDUAL_NAMES.index("r_nx")] = float(t_nx)
    return thr


def decision_table(variant: str) -> np.ndarray:
    """Table 1's decision table of ``variant`` as the kernels' array (8, 4)."""
    return np.array(TABLE1[variant], dtype=np.int64)

Belief = namedtuple("Belief", [
    "TM",  # (4, 4) column-stochastic mode transition matrix (eq. 13)
    "lo",  # (4, 5) lower edge of each mode's box of (b0, b1) (eq. 12)
    "hi",  # (4, 5) upper edge of each mode's box
])
"""Four-mode belief: nominal, engine, left elevon, right elevon (section 3.3)."""

Controller = namedtuple("Controller", [
    "K",       # (3, 9) state-feedback gain, u = -K x_hat (eqs. 17, 19)
    "lo_dev",  # (3,) lower command limits as deviations from trim
    "hi_dev",  # (3,) upper command limits as deviations from trim
])
"""Nominal controller c0 with its saturation (paper section 4.1, eqs. 15-19)."""

Excitation = namedtuple("Excitation", [
    "doublet_amp",      # amplitude of the engine doublet a reset sends [throttle]
    "doublet_half",     # steps of each half of the doublet
    "s3211_amp",        # amplitude of the elevon 3211 a reset sends [rad]
    "s3211_unit",       # steps of one unit of the 3211
    "resend_delay",     # steps after a thrust reset before the doublet re-check (3 s)
    "resend_b1",        # re-send the doublet if b1_thrust estimate exceeds this (0.7)
    # the design's excitation policy beyond the requests on resets
    "policy",           # conventions.EXCITE_NONE (the paper), EXCITE_PERIODIC or
                        #    EXCITE_AMBIGUOUS (stages.policy_signals)
    "period",           # periodic: steps between two doublets (the 3211 half-way);
                        #    ambiguous: fewest steps from a signal's start to a sent one
    "phase",            # periodic: the doublets start at steps phase + n period
    "belief_max",       # ambiguous: send while the most probable mode's probability
                        #    is below this (0: never)
    "suspect",          # ambiguous: send when r_q or r_nx (the decision statistics)
                        #    reach this (inf: never)
    "s3211_floor",      # under c2 the 3211 is scaled by max(1 - b1_left_hat, this)
                        #    (0: eq. 23 as printed; DesignConfig.s3211_floor)
    "policy_doublet_amp",  # amplitude of the doublets the policy sends [throttle]
    "policy_s3211_amp",    # amplitude of the 3211s the policy sends [rad]
    "pause_belief",     # the policy sends nothing while a fault mode's probability is
                        #    at least this (inf: never pauses)
])
"""Excitation on reset requests (paper sections 3.2.3 and 4.1.1), and the
design's policy of sending more."""

Timing = namedtuple("Timing", [
    "n_steps",        # steps simulated
    "k_fault",        # step at which the truth switches to the final mode
    "reconf_every",   # steps between belief updates (reconfiguration period)
    "detect_prob",    # belief of the final mode that counts as detected
])
"""Trial timing (Tables 2-3; ``docs/reference/paper-map.md``)."""

TrialInputs = namedtuple("TrialInputs", [
    "k_switch",   # (E,) int64 steps at which the truth switches, k_switch[0] == 0
    "b0",         # (E, 3, L) truth b0 per actuator from each switch on (absolute
                  #           lock position when locked)
    "b1",         # (E, 3, L) truth b1 per actuator from each switch on
    "mode_pre",   # (L,) int64 mode whose box holds the initial truth
    "mode_post",  # (L,) int64 mode whose box holds the final truth
    "xa0",        # (n, L) initial augmented estimate (n = 14 + the design's extra states)
    "P0",         # (n, n) initial covariance (shared)
    "w",          # (n_steps, 9, L) process noise, already scaled
    "v",          # (n_steps, 12, L) measurement noise, already scaled
    "eta",        # (n_steps, 4, L) standard normal gust draws, or (0, 4, L) without
                  #           turbulence (core/shared/dryden.py)
    "g0",         # (4, L) initial gust filter state (stationary draw, or zeros)
    "sensor_out",   # (L,) int64 output index of the lane's sensor fault, or -1 (none)
    "sensor_kind",  # (L,) int64 conventions.SENSOR_* kind (bias, stuck, drift, noise)
    "sensor_size",  # (L,) bias [unit], drift [unit/s] or noise factor [-]; stuck: unused
    "sensor_k",     # (L,) int64 onset step: z_{k+1} is faulty from truth step k on
    # the 6-DOF family's lateral draws (core/sixdof/truth.py; zero-sized otherwise)
    "v_lat",      # (n_steps, 5, L) noise of the measured lateral states, scaled, or (0, 5, L)
    "eta_lat",    # (n_steps, 4, L) lateral Dryden draws, or (0, 4, L) in still air
    "g0_lat",     # (4, L) initial lateral gust state (stationary draw, or zeros), or (0, L)
    "fp",         # (E, N_FAULT_PARAM, 3, L) the fault model's other parameters per
                  #           actuator from each switch on (conventions.FAULT_PARAM_NAMES;
                  #           FAULT_PARAM_NEUTRAL: eq. 2 alone)
])
"""Per-lane inputs of :func:`ftc_mc.sim.lanes.run_trials` (a fault schedule)."""

TrialRecord = namedtuple("TrialRecord", [
    "reset_k",      # (R, L) int64 step of each reset (time = k dt)
    "reset_block",  # (R, L) int64 block of each reset (1 thrust, 2 elevons)
    "reset_res",    # (R, 3, L) residuals r_q, r_nx, r_nz at each reset
    "n_resets",     # (L,) int64 number of resets (may exceed R; extra not stored)
    "belief",       # (n_periods, 4, L) belief after each reconfiguration period
    "bhat",         # (n_periods, 5, L) fault-parameter estimate at each period
    "detect_k",     # (L,) int64 first period end after the switch where the final
                    #      mode is most probable with at least detect_prob, or -1
    "status",       # (L,) int64 0 when the trial ran to its end, else a
                    #      trial.STATUS_* reason
    "stop_k",       # (L,) int64 step at which an invalid trial stopped, or -1
    "xa_end",       # (m, L) final augmented estimate, its first m states (m = n: all of
                    #        a design's extra states too, sim/lanes.py::new_record)
    "controller",   # (n_periods, L) int64 controller in use after each period
    "hist_x",       # (n_hist, 9, L) true state after each step (n_hist 0: none kept)
    "hist_xa",      # (n_hist, 14, L) augmented estimate after each step (first 14)
    "hist_pdiag",   # (n_hist, 5, L) variances of the fault parameters
    "hist_u",       # (n_hist, 3, L) commands applied during each step
    "hist_res",     # (n_hist, 3, L) residuals r_q, r_nx, r_nz
    "hist_exc",     # (n_hist, 4, L) doublet (engine) and 3211 (left elevon) values,
                    #      then 1.0 where each signal started at that step
    "hist_block",   # (n_hist, L) int64 block reset at each step
    "hist_wind",    # (n_hist, 3, L) gust u_g, w_g [m/s], q_g [rad/s] held over each step
    "hist_z",       # (n_hist, 12, L) measurements z_{k+1} (deviations from the trim outputs)
    "hist_innov",   # (n_hist, 3, L) signed normalised innovations of r_q, r_nx, r_nz's outputs
    "hist_lat",     # (n_hist, 5, L) the lateral loop's measurements after each step (bank,
                    #      side velocity, roll and yaw rates, heading; 6-DOF plant, else
                    #      no columns)
    "hist_mon",     # (n_hist, 3, L) the side monitor's direction projections (its GLR's
                    #      input) of each step (6-DOF plant, else no columns)
    "sq_lat",       # (2, L) sums over the valid steps of the squared bank and heading
                    #      deviations [rad^2] (6-DOF plant; zeros otherwise)
    "cost",         # (N_COST, L) over the valid steps (conventions.COST_NAMES): sum of
                    #      the squared cross-track error [m^2], its largest magnitude [m],
                    #      sums of each squared command deviation (stages.record_cost)
    "z_switch_last",  # (2, L) the truth's vertical deviation z [m] (down) from the glide
                      #   path's reference point after the step reaching the switch
                      #   (timing.k_fault; NaN if the lane stopped before) and after
                      #   the last step flown (stages.record_cost)
    # the 6-DOF side monitor (core/sixdof/monitor.py; -1 / 0 / zeros otherwise)
    "side_k",       # (L,) int64 step of its first decision at or after timing.k_fault, or -1
    "side_block",   # (L,) int64 that decision's direction: 1 throttle, 2 left, 3 right; 0 none
    "side_pre",     # (L,) int64 its decisions before timing.k_fault (while the lane lived)
    "side_n",       # (L,) int64 all its decisions while the lane lived
    "mon_b",        # (9, L) its b0 (3), b1 (3) and estimated actuator positions (3)
                    #        SideMonitor.snap steps after side_k, or after the last step
                    #        flown if earlier (0 rows off the 6-DOF plant)
])
"""Per-lane outputs of :func:`ftc_mc.sim.lanes.run_trials`."""

Validity = namedtuple("Validity", [
    "va_trim",     # trim airspeed [m/s]
    "va_min",      # lowest airspeed the linear model is trusted at [m/s]
    "va_max",      # highest [m/s]
    "alpha_trim",  # trim angle of attack [rad]
    "alpha_min",   # lowest angle of attack [rad]
    "alpha_max",   # highest [rad]
    "psd_every",   # steps between full positive-semi-definiteness checks of P
    "bank_max",    # largest |bank angle| [rad] (6-DOF plant; the longitudinal ones have none)
])
"""Where a trial stops as numerically or physically invalid (see core/longitudinal/trial.py)."""

Reconfig = namedtuple("Reconfig", [
    "kind",      # 0: nominal controller c0 only; 1: reconfiguring (eqs. 45-47)
    "horizon",   # H, steps of the short-horizon prediction (eq. 45), >= 1
    "alpha",     # discount factor (eqs. 18, 45)
    "q_lqr",     # (9,) diagonal of Q_lqr (section 5.1)
    "r_lqr",     # (3,) diagonal of R_lqr
    "JN",        # (4, 3) terminal cost J^N(m, a) of mode m under controller a (eq. 46)
    "penalty",   # (3, 3) switching penalty P(c, a) (eq. 46)
])
"""Controller selection settings (paper section 4.2)."""

Scheme = namedtuple("Scheme", [
    "filter",      # FilterModel: the augmented Kalman filter (eqs. 4-6)
    "detection",   # Detection: Table 1 thresholds, variant and reset variances
    "belief",      # Belief: mode boxes and T_M (eqs. 12-14)
    "controller",  # Controller: nominal gain and command limits (eqs. 15-19)
    "excitation",  # Excitation: doublet and 3211 on resets (section 4.1.1)
    "reconfig",    # Reconfig: controller selection (eqs. 45-47)
    "engine",      # EngineTables: Theorem 4.1 tables of c1 (core/shared/interp.py)
])
"""The fault-tolerant control scheme under test: estimator, detector, belief,
controllers and their selection.  A threshold sweep varies only ``detection``."""

Track = namedtuple("Track", [
    "ix",     # row of the along-path position deviation x [m] in the truth state
    "iz",     # row of the vertical deviation z [m] (down) in the truth state
    "sin_g",  # sin of the trim flight-path angle gamma0
    "cos_g",  # cos of gamma0
])
"""The glide path's cross-track error ``x sin(gamma0) + z cos(gamma0)`` [m] of the
truth state (as ``scenario/run.py`` computes ``cross_track_error_m``)."""

Flight = namedtuple("Flight", [
    "timing",    # Timing: steps, fault step, reconfiguration period
    "validity",  # Validity: where a trial stops being trusted
    "plant",     # TruthPlant: the simulated aircraft and air
    "track",     # Track: the glide path's cross-track error (TrialRecord.cost)
])
"""What the scheme flies: the truth plant, how long, and its validity envelope."""

LaneState = namedtuple("LaneState", [
    "x",        # (n_x, L) true plant state (deviation from trim; 15 on the 6-DOF plant)
    "xa",       # (n, L) augmented estimate [x, b, g] (n = 14 for the paper's filter)
    "P",        # (n, n, L) covariance
    "d_start",  # (L,) int64 step the running doublet started at (or far past)
    "s_start",  # (L,) int64 step the running 3211 started at (or far past)
    "d_amp",    # (L,) amplitude of the running (or last) doublet [throttle]
    "s_amp",    # (L,) amplitude of the running (or last) 3211 [rad]
    "recheck",  # (L,) int64 step of the pending doublet re-check, or -1
    "belief",   # (4, L) mode probabilities
    "alive",    # (L,) bool: the trial is still valid (see trial.advance)
    "cur",      # (L,) int64 controller in use
    "rmax",     # (2, L) largest r_q and r_nx seen so far (threshold sharing)
    "gust",     # (4, L) Dryden gust filter state (zeros without turbulence)
    "zhold",    # (L,) last healthy measurement of the lane's faulty output (stuck)
    "ebuf",     # (W, 3, L) signed normalised innovations of the GLR window (ring)
    "ecount",   # (L,) int64 innovations in the window since the start or last reset
    "last_k",   # (L,) int64 step of the last reset (Detection.settle), or far past
    "last_block",  # (L,) int64 block of the last reset, or 0
    # the 6-DOF family's lateral loop (core/sixdof/truth.py; zero rows otherwise)
    "lat",      # (7, L) the lateral loop's measured state: bank, side velocity, roll
                #        and yaw rates, heading (deviations), then its model of the
                #        commanded left and right elevon positions
    "glat",     # (4, L) lateral Dryden gust state, or (0, L)
    "mx",       # (n_m, L) the side monitor's estimate [x (14), b0 (3), b1 (3)], or (0, L)
    "mP",       # (n_m, n_m, L) its covariance
    "mbuf",     # (W_m, 3, L) its GLR window of each direction's projection (ring)
    "mcount",   # (L,) int64 projections in that window
    "mside",    # (L,) int64 the first elevon it named (a lock_turn_selected design: the
                #        elevon whose lock-turn law the selection chose): 0 none, else its
                #        block code (2, 3)
    "mpos",     # (L,) that elevon's estimated absolute position [rad] (core/sixdof/lockturn.py)
    "mturn",    # (L,) int64 the step from which the lock-turn law may fly (the monitor's
                #        first elevon decision, k + 1, or the selection's step), or -1;
                #        ``mside`` < 0 once handed back
    "mlast",    # (L,) int64 its latest decision: 0 none, else its block code (1-3)
    "mnow",     # (L,) int64 its decision at this step: 0 none, else its block code (1-3)
    # the extended filter's Jacobians about the lane's estimate (FilterModel.relin > 0;
    # the trim matrices otherwise, never read)
    "JA",       # (9, 9, L)  d x_{k+1} / d x_k of the one-period airframe map
    "JB",       # (9, 3, L)  d x_{k+1} / d e (actuator effects)
    "JW",       # (9, 3, L)  d x_{k+1} / d wind (u_g, w_g [m/s], q_g [rad/s])
    "JC",       # (12, 9, L) d h / d x of the outputs
    "JHW",      # (12, 3, L) d h / d wind
    # the truth's actuators (core/longitudinal/plant.py::actuator_effect)
    "uhist",    # (N_CMD_HIST, 3, L) the commands of the last steps, step k at k % N_CMD_HIST
    "uprev",    # (3, L) the command each actuator followed last step (after delay,
                #        limit cycle, runaway, float and rate limit) [deviation from trim]
])
"""Everything a trial carries from one step to the next (core/longitudinal/trial.py)."""

TruthPlant = namedtuple("TruthPlant", [
    "kind",   # 0: the linear plant of eq. (1) (the filter's model); 1: the nonlinear
              #    X8 of core/longitudinal/nonlinear.py integrated by RK4
    "n_sub",  # RK4 sub-steps per control period (nonlinear plant)
    "dt",     # control period [s]
    "p",      # (25,) packed airframe parameters (model/dynamics.pack_parameters)
    "x0",     # (9,) trim state, absolute (the truth state is kept as x - x0)
    "y0",     # (12,) trim outputs (measurements are y - y0 + v)
    "turb",   # 0: still air; 1: Dryden gusts from TrialInputs.eta
    "Ad",     # (4, 4) discrete Dryden transition (model/turbulence.py)
    "Bd",     # (4, 4) discrete Dryden noise input
    "Cd",     # (3, 4) gust outputs u_g, w_g, q_g
    "Bw",     # (9, 3) linear plant: discrete (zero-order hold) input matrix of the gust
    "Dw",     # (12, 3) linear plant: gust feed-through into the outputs
])
"""The truth plant a trial simulates: linear or nonlinear, with or
without turbulence.  The estimator and the controllers always use the linear
model (:class:`FilterModel`)."""
