"""The stages of one trial step, each a kernel over every lane.

:func:`ftc_mc.core.longitudinal.trial.advance` runs, for step ``k -> k+1``:

1. :func:`commands` -- controller, saturation and excitation (eqs. 15-25, 44);
2. :func:`ftc_mc.core.longitudinal.plant.truth_step` -- effect (eq. 2), gusts, plant,
   measurement; then :func:`record_cost` -- the tracking error and command sums;
3. :func:`filter_update` -- the augmented filter with Table 1 and resets
   (eqs. 5-11, :func:`ftc_mc.core.longitudinal.batch.filter_step_lanes`);
4. :func:`check_validity` -- where a trial stops being trusted;
5. :func:`handle_resets` -- reset records and excitation requests (sections
   3.2.3 and 4.1.1), and the design's excitation policy (:func:`policy_signals`);
6. :func:`record_step` -- the per-step history (scenarios);
7. :func:`reconfigure` -- every reconfiguration period, the belief (eqs. 12-14)
   and the controller selection (eqs. 45-47);

and :func:`record_end` once at the end.  Stages communicate through the lane
state (:class:`~ftc_mc.core.longitudinal.settings.LaneState`), the record
(:class:`~ftc_mc.core.longitudinal.settings.TrialRecord`) and the scratch
(:class:`~ftc_mc.core.longitudinal.workspace.TrialWork`); each stage's docstring says what
it reads and writes.  Lane ``l`` of every array is one trial, lane index last.

Each stage has a plain-NumPy twin in ``tests/naive.py`` (same name with
``_ref``), compared in ``tests/test_stages.py``.

The stages of one step are compiled inline (``inline="always"``, Numba IR
inlining) into the loop of one kernel,
:func:`ftc_mc.core.longitudinal.trial.trial_steps`, which ``advance`` calls by
address once per reconfiguration period (``kernel(by_address=True)``,
:mod:`ftc_mc.core.linking`), as it calls :func:`reconfigure`: each is compiled
once, on its own, not again inside ``advance``, and a period costs one call,
not one per stage or step (``docs/findings/performance.md`` lesson 17).  Where the compile paths
part (``core/shared/paths.py``) a dispatcher compiles the one kernel its path
reaches, also called by address.  The stages remain
callable on their own (the tests do).
"""

from __future__ import annotations

import numpy as np

from ...conventions import (C_ELEVON, COST_TRACK_MAX, COST_TRACK_SQ, COST_U2, EXCITE_NONE,
                            EXCITE_PERIODIC, I_B1_LEFT, I_B1_THRUST, MODE_NOMINAL, N_AUG, N_FAULT,
                            N_MODES,
                            N_U, N_X, NO_RESET, RESET_THRUST, STATUS_AIRSPEED, STATUS_ALPHA,
                            STATUS_BANK, STATUS_NONFINITE, STATUS_NOT_PSD, STATUS_OK)
from .batch import filter_correct_lanes, filter_predict_lanes, innovations_lanes
from .signature import signature_lanes
from ..shared.glr import glr_lanes, glr_restart
from .gustfilter import gust_correct_lanes, gust_predict_lanes
from ..shared.belief import belief_update_lane
from .control import (U_LEFT, U_RIGHT, U_THRUST, controller_commands_lanes, feedback_lanes,
                      select_controllers_lanes)
from ..shared.excitation import (doublet, doublet_length, running, saturate, signal_3211,
                                 signal_3211_length)
from ..jit import kernel
from ..shared.paths import (DENSE_FILTER, EXTENDED_FILTER, GLR_TEST, NOMINAL_CONTROL,
                            ONE_STEP_TEST, PAPER_FILTER, RECONFIGURING, SELECT_FOUR,
                            SIXDOF_EXTENDED_PLANT,
                            SIXDOF_PLANT, on_path)
from .workspace import EXC_3211, EXC_3211_START, EXC_DOUBLET, EXC_DOUBLET_START

R_Q, R_NX = 0, 1
"""Rows of the residuals ``[r_q, r_nx, r_nz]`` kept in ``LaneState.rmax``."""


# ------------------------------------------------------------------ 1. commands
@kernel(inline="always")
def nominal_output(scheme, st, work):
    """The nominal controller's output ``U = -K x_hat`` (c0, eq. 19) of every
    lane into ``work.u`` (:func:`ftc_mc.core.longitudinal.control.feedback_lanes`)."""
    feedback_lanes(scheme.controller.K, st.xa, work.u)


@kernel(internal=True)
def reconfiguring_output(scheme, st, work):
    """The output of each lane's controller in use into ``work.u``
    (:func:`ftc_mc.core.longitudinal.control.controller_commands_lanes`: c0,
    c1 of eq. 44 or c2 of eqs. 20-25, each lane bit for bit
    :func:`~ftc_mc.core.longitudinal.control.controller_command`, the nominal
    feedback across lanes); one-lane buffers ``xl``, ``Ul``."""
    controller_commands_lanes(st.cur, st.xa, scheme.controller.K, scheme.engine,
                              scheme.filter.u0, work.u, work.xl, work.Ul)


@on_path("control", {NOMINAL_CONTROL: nominal_output, RECONFIGURING: reconfiguring_output,
                     SELECT_FOUR: reconfiguring_output})
def controller_output(path, scheme, st, work):
    """The controller output of the path's scheme: :func:`nominal_output` or
    :func:`reconfiguring_output`."""


@kernel(inline="always")
def commands(path, scheme, st, k, work):
    """Stage 1: the commands ``u_k`` of every lane (deviations from trim).

    Controller output ``U`` from the estimate ``x_hat_k``
    (:func:`controller_output`): ``-K x_hat`` (c0, eq. 19) on the nominal
    controller's path, else the lane's controller in use (c0, c1 of eq. 44 or
    c2 of eqs. 20-25).  Then the saturation with excitation
    headroom (eq. 15, eq. 16 without a signal): the doublet on the engine while
    one runs; the 3211 on the left elevon and its negative on the right while
    one runs (each at the amplitude it was started with, ``st.d_amp`` and
    ``st.s_amp``: a reset's or the design's policy's), scaled by
    ``1 - b1_left_hat`` under c2 (eq. 23), or by the design's
    ``exc.s3211_floor`` where that is larger (0: eq. 23).

    Parameters
    ----------
    path : Path
        The compile path (``core/shared/paths.py``): its ``control``.
    scheme : Scheme
        Reads ``controller`` (gain, limits), ``excitation``, ``engine`` and
        ``filter.u0``.
    st : LaneState
        Reads ``xa``, ``cur``, ``d_start``, ``s_start``, ``d_amp``, ``s_amp``.
    k : int
        Step.
    work : TrialWork
        Writes ``u`` (3, L) and ``exc`` (4, L: doublet value, 3211 value, 1.0
        where each signal starts at ``k``); one-lane buffers ``xl``, ``Ul``.
    """
    ctl = scheme.controller
    exc = scheme.excitation
    xa = st.xa
    u = work.u
    out = work.exc
    L = xa.shape[1]
    controller_output(path, scheme, st, work)
    d_len = doublet_length(exc.doublet_half)
    s_len = signal_3211_length(exc.s3211_unit)
    lo = ctl.lo_dev
    hi = ctl.hi_dev
    for l in range(L):
        kd = k - st.d_start[l]
        if running(k, st.d_start[l], d_len):
            sd = doublet(kd, exc.doublet_half, st.d_amp[l])
            u[U_THRUST, l] = saturate(u[U_THRUST, l], sd, st.d_amp[l], lo[U_THRUST],
                                      hi[U_THRUST])
        else:
            sd = 0.0
            u[U_THRUST, l] = saturate(u[U_THRUST, l], 0.0, 0.0, lo[U_THRUST], hi[U_THRUST])
        out[EXC_DOUBLET, l] = sd
        out[EXC_DOUBLET_START, l] = 1.0 if kd == 0 else 0.0
        ks = k - st.s_start[l]
        if running(k, st.s_start[l], s_len):
            s = signal_3211(ks, exc.s3211_unit, st.s_amp[l])
            if st.cur[l] == C_ELEVON:  # eq. 23: scaled by the left elevon's efficiency
                g = 1.0 - xa[I_B1_LEFT, l]
                if exc.s3211_floor > 0.0 and g < exc.s3211_floor:  # the design's floor
                    g = exc.s3211_floor
                s *= g
            a = st.s_amp[l]
        else:
            s = 0.0
            a = 0.0
        out[EXC_3211, l] = s
        out[EXC_3211_START, l] = 1.0 if ks == 0 else 0.0
        u[U_LEFT, l] = saturate(u[U_LEFT, l], s, a, lo[U_LEFT], hi[U_LEFT])
        u[U_RIGHT, l] = saturate(u[U_RIGHT, l], -s, a, lo[U_RIGHT], hi[U_RIGHT])


# ------------------------------------------------------------------ 2b. cost
@kernel(inline="always")
def record_cost(track, k_switch, st, kn, work, rec):
    """After the truth step: the costs of flying the step, and the
    height marks of the survivability study.

    For every live lane (its steps until it stops, the step that takes it out
    of the envelope included, as ``TrialRecord.sq_lat``): the cross-track error
    of the glide path ``c = x sin(gamma0) + z cos(gamma0)`` of the true state
    after the step (``scenario/run.py``'s ``cross_track_error_m``) adds ``c^2``
    to ``cost[COST_TRACK_SQ]`` and raises ``cost[COST_TRACK_MAX]`` to ``|c|``;
    each command ``u_i`` applied during the step (deviation from trim, the
    excitation included) adds ``u_i^2`` to ``cost[COST_U2 + i]``.  The vertical
    deviation ``z`` of the true state is written to ``z_switch_last[1]`` (so it
    holds the last step flown), and to ``z_switch_last[0]`` at the switch.

    Parameters
    ----------
    track : Track
        Rows of ``x`` and ``z`` in the truth state, ``sin`` and ``cos`` of gamma0.
    k_switch : int
        Step of the switch to the final mode (``Timing.k_fault``).
    st : LaneState
        Reads ``x`` (the true state after the step) and ``alive``.
    kn : int
        Step reached (``k + 1``).
    work : TrialWork
        Reads ``u``.
    rec : TrialRecord
        ``cost`` and ``z_switch_last`` updated.
    """
    x = st.x
    u = work.u
    cost = rec.cost
    marks = rec.z_switch_last
    for l in range(x.shape[1]):
        if not st.alive[l]:
            continue
        z = x[track.iz, l]
        marks[1, l] = z
        if kn == k_switch:
            marks[0, l] = z
        c = x[track.ix, l] * track.sin_g + z * track.cos_g
        cost[COST_TRACK_SQ, l] += c * c
        cost[COST_TRACK_MAX, l] = max(cost[COST_TRACK_MAX, l], abs(c))
        for i in range(N_U):
            cost[COST_U2 + i, l] += u[i, l] * u[i, l]


# ------------------------------------------------------------------ 3. filter
# The kernels the paths part into are kernels of their own, without the path:
# compiled once, and loaded from the cache by every other path that reaches them
# (core/shared/paths.py).  The filter's take the filter's marker (``fkind``), by
# which the general filter picks its prediction.

@kernel(internal=True)
def paper_predict(fkind, scheme, st, k, work):
    """The paper filter's prediction and one-step residuals
    (:func:`ftc_mc.core.longitudinal.batch.filter_predict_lanes`)."""
    filter_predict_lanes(st.xa, st.P, work.u, work.z, scheme.filter, work.phi, work.T,
                         work.fwork, work.res)


@kernel(internal=True)
def general_predict(fkind, scheme, st, k, work):
    """The general filter's prediction and residuals, with the airframe's
    equations on the extended filter's path
    (:func:`ftc_mc.core.longitudinal.gustfilter.gust_predict_lanes`)."""
    gust_predict_lanes(fkind, st.xa, st.P, scheme.filter, work, st, k)


@on_path("filter", {PAPER_FILTER: paper_predict, DENSE_FILTER: general_predict,
                    EXTENDED_FILTER: general_predict}, passes="marker")
def predict(path, scheme, st, k, work):
    """The first half of the path's filter step."""


@kernel(internal=True)
def paper_innovations(scheme, st, work):
    """The signed innovations the GLR test reads, of the paper's filter
    (:func:`ftc_mc.core.longitudinal.batch.innovations_lanes`; the general
    filter writes them as it predicts)."""
    innovations_lanes(st.xa, work.fwork[0:st.xa.shape[0]], work.z, scheme.filter, work.innov)


@on_path("filter", {PAPER_FILTER: paper_innovations})
def paper_innovations_on(path, scheme, st, work):
    """:func:`paper_innovations` on the paper filter's path."""


@on_path("test", {GLR_TEST: paper_innovations_on}, passes="path")
def innovations(path, scheme, st, work):
    """The paper filter's innovations on the GLR test's path."""


@on_path("test", {ONE_STEP_TEST: paper_innovations_on}, passes="path")
def innovations_kept(path, scheme, st, work):
    """The paper filter's innovations on the one-step test's path, which does not
    read them: computed only while a history is kept (recorded signals)."""


@kernel(internal=True)
def paper_correct(fkind, scheme, st, work):
    """Reset, update and projection of the paper's filter
    (:func:`ftc_mc.core.longitudinal.batch.filter_correct_lanes`)."""
    filter_correct_lanes(st.xa, st.P, work.u, work.z, scheme.filter, scheme.detection,
                         work.phi, work.T, work.fwork, work.block)


@kernel(internal=True)
def general_correct(fkind, scheme, st, work):
    """Reset, re-prediction, update and projection of the general filter
    (:func:`ftc_mc.core.longitudinal.gustfilter.gust_correct_lanes`)."""
    gust_correct_lanes(fkind, st.xa, st.P, scheme.filter, scheme.detection, work, st)


@on_path("filter", {PAPER_FILTER: paper_correct, DENSE_FILTER: general_correct,
                    EXTENDED_FILTER: general_correct}, passes="marker")
def correct(path, scheme, st, work):
    """The second half of the path's filter step."""


@kernel(internal=True)
def glr_statistics(det, st, k, work):
    """The GLR statistics of the window (:func:`ftc_mc.core.shared.glr.glr_lanes`) in
    place of the one-step residuals ``work.res``."""
    glr_lanes(work.innov, st.ebuf, st.ecount, k, det.min_window, det.clip, work.res)


@on_path("test", {GLR_TEST: glr_statistics})
def decision_statistics(path, det, st, k, work):
    """The GLR test's statistics on its path; the one-step residuals stand
    otherwise."""


@on_path("test", {GLR_TEST: glr_restart})
def restart_window(path, block, ecount):
    """A reset restarts the lane's GLR window (on the GLR test's path)."""


@on_path("plant", {SIXDOF_PLANT: "ftc_mc.core.sixdof.lockturn:side_blocks",
                   SIXDOF_EXTENDED_PLANT: "ftc_mc.core.sixdof.lockturn:side_blocks"},
         passes="marker")
def side_blocks(path, scheme, st, block):
    """On the 6-DOF plant, a ``lock_turn`` design's side monitor decides which
    block Table 1's decisions reset (:func:`ftc_mc.core.sixdof.lockturn.side_blocks`,
    imported only by a path that flies the 6-DOF plant); nothing on the
    longitudinal plants."""


@kernel(inline="always")
def filter_update(path, scheme, st, k, work, keep_innov):
    """Stage 3: one step of every lane's augmented filter (eqs. 5-11, Table 1).

    Predict with ``u_k`` and the residuals on ``z_{k+1}``
    (:func:`predict`: :func:`ftc_mc.core.longitudinal.batch.filter_predict_lanes` on the
    paper filter's path, :func:`ftc_mc.core.longitudinal.gustfilter.gust_predict_lanes` on
    the dense and extended filters' paths); on the GLR test's path the
    statistics of :func:`ftc_mc.core.shared.glr.glr_lanes` replace the one-step
    residuals; Table 1
    on them (on the 6-DOF plant, a ``lock_turn`` design's block from its side
    monitor, :func:`side_blocks`), a decision for the other block withheld within
    ``detection.settle`` steps of a reset (:func:`settle_lanes`), and every
    decision before step ``detection.startup`` (then the GLR window is kept
    empty too: the test is armed after the start-up); reset, update
    and projection (the ``*_correct_lanes`` halves); a reset restarts the
    lane's GLR window.  Then
    the largest ``r_q`` and ``r_nx`` seen so far (threshold sweeps).

    Parameters
    ----------
    path : Path
        The compile path (``core/shared/paths.py``): its ``filter`` and ``test``.
    scheme : Scheme
        Reads ``filter`` and ``detection``.
    st : LaneState
        ``xa``, ``P`` advanced in place; ``rmax`` updated; the GLR window
        ``ebuf``, ``ecount``; the extended filter's Jacobians ``JA`` .. ``JHW``
        (re-computed about the estimate every ``filter.relin`` steps, read
        while ``relin > 0``).
    k : int
        Step (the GLR window's ring position).
    work : TrialWork
        Reads ``u``, ``z``; writes ``res`` (the decision statistics: one-step
        residuals or GLR), ``block`` and, for the GLR test or the general
        filter, ``innov``; filter work ``phi``, ``T``, ``fwork``, ``crow``.
    keep_innov : bool
        Write ``innov`` on every path (a kept history records it); the paper's
        one-step test does not read it, so it is skipped otherwise.
    """
    det = scheme.detection
    res = work.res
    predict(path, scheme, st, k, work)
    innovations(path, scheme, st, work)
    if keep_innov:
        innovations_kept(path, scheme, st, work)
    decision_statistics(path, det, st, k, work)
    signature_lanes(res, det, work.block)
    side_blocks(path, scheme, st, work.block)
    if det.settle > 0:
        settle_lanes(work.block, st.last_k, st.last_block, k, det.settle)
    if k < det.startup:  # not armed yet: no reset, and the GLR window stays empty
        for l in range(st.xa.shape[1]):
            work.block[l] = 0
            st.ecount[l] = 0
    correct(path, scheme, st, work)
    restart_window(path, work.block, st.ecount)
    if det.settle > 0:
        for l in range(st.xa.shape[1]):
            if work.block[l] != 0:
                st.last_k[l] = k
                st.last_block[l] = work.block[l]
    for l in range(st.xa.shape[1]):
        st.rmax[R_Q, l] = max(st.rmax[R_Q, l], res[R_Q, l])
        st.rmax[R_NX, l] = max(st.rmax[R_NX, l], res[R_NX, l])


@kernel(inline="always")
def settle_lanes(block, last_k, last_block, k, settle):
    """Withhold a reset of the other block within ``settle`` steps of a reset.

    After a reset the filter re-converges (its reset variances are large), and
    meanwhile the other block's residuals move too: on the nonlinear X8 a
    locked elevon's drag shows in ``n_x`` 0.3-3 s later (DESIGN.md section 9).
    A lane whose Table 1 decision at step ``k`` is the block other than its
    last reset's, within ``settle`` steps of it, resets nothing (``block`` 0).
    """
    for l in range(block.shape[0]):
        b = block[l]
        if (b != 0 and last_block[l] != 0 and b != last_block[l]
                and k - last_k[l] < settle):
            block[l] = 0


# ------------------------------------------------------------------ 4. validity
@kernel(inline="always")
def is_psd(P, l, work):
    """Cholesky test of ``P[:, :, l] + eps I`` (``eps = 1e-12 max diag``).

    Parameters
    ----------
    P : ndarray, shape (n, n, L)
    l : int
        Lane.
    work : ndarray, shape (n, n)

    Returns
    -------
    bool
        False if a pivot is not positive (or not finite).
    """
    n = P.shape[0]
    dmax = 0.0
    for i in range(n):
        dmax = max(dmax, abs(P[i, i, l]))
    eps = 1e-12 * dmax
    for i in range(n):
        for j in range(i + 1):
            acc = P[i, j, l] + (eps if i == j else 0.0)
            for m in range(j):
                acc -= work[i, m] * work[j, m]
            if i == j:
                if not acc > 0.0:
                    return False
                work[i, i] = np.sqrt(acc)
            else:
                work[i, j] = acc / work[j, j]
    return True


@kernel(inline="always")
def check_validity(validity, st, kn, work, rec):
    """Stage 4: stop trusting a lane that left the numerics or the envelope.

    A live lane stops (``alive`` False, ``status`` and ``stop_k = kn``
    recorded) when, in this order of precedence, its estimate, the diagonal of
    its covariance or its air data are not finite (``STATUS_NONFINITE``), its
    covariance fails the Cholesky test (every ``psd_every`` steps,
    ``STATUS_NOT_PSD``), or the true airspeed (``STATUS_AIRSPEED``) or angle of
    attack (``STATUS_ALPHA``) leave the validity bounds, or the true bank angle
    exceeds ``bank_max`` (``STATUS_BANK``; only the 6-DOF plant banks).  Both are
    air-relative, as the aerodynamics see them: the inertial angle of attack
    would be the wrong test in turbulence (the aircraft follows the air mass,
    so its inertial angle swings with the gust, 1 sigma 4.8 deg in moderate
    turbulence, while the aerodynamic one stays near 1.5 deg).

    Parameters
    ----------
    validity : Validity
    st : LaneState
        Reads ``xa``, ``P``; ``alive`` updated.
    kn : int
        Step reached (``k + 1``).
    work : TrialWork
        Reads ``va``, ``alpha``, ``bank``; buffers ``finite`` and ``chol``.
    rec : TrialRecord
        ``status`` and ``stop_k`` written for the lanes that stop.
    """
    xa = st.xa
    P = st.P
    n = xa.shape[0]
    L = xa.shape[1]
    check_psd = kn % validity.psd_every == 0
    # finiteness of every lane first, in loops over lanes (they vectorise)
    finite = work.finite
    for l in range(L):
        finite[l] = np.isfinite(work.va[l]) & np.isfinite(work.alpha[l])
    for i in range(n):
        for l in range(L):
            finite[l] = finite[l] & np.isfinite(xa[i, l]) & np.isfinite(P[i, i, l])
    for l in range(L):
        if not st.alive[l]:
            continue
        status = STATUS_OK
        va = work.va[l]
        al = work.alpha[l]
        if not finite[l]:
            status = STATUS_NONFINITE
        elif check_psd and not is_psd(P, l, work.chol):
            status = STATUS_NOT_PSD
        elif not (validity.va_min <= va <= validity.va_max):
            status = STATUS_AIRSPEED
        elif not (validity.alpha_min <= al <= validity.alpha_max):
            status = STATUS_ALPHA
        elif abs(work.bank[l]) > validity.bank_max:
            status = STATUS_BANK
        if status != STATUS_OK:
            st.alive[l] = False
            rec.status[l] = status
            rec.stop_k[l] = kn


# ------------------------------------------------------------------ 5. resets
@kernel(inline="always")
def handle_resets(excitation, st, kn, work, rec):
    """Stage 5: record the resets and start the excitation they request.

    For a live lane whose filter reset a block at this step: the reset is
    recorded (step, block, residuals; counted beyond the record's capacity); a
    thrust reset starts the doublet unless one is running and schedules a
    re-check ``resend_delay`` steps later; an elevon reset starts the 3211
    unless one is running (section 3.2.3), each at the section's (or the
    design's) amplitude.  At a pending re-check the doublet is sent again if
    ``b1_thrust`` is estimated above ``resend_b1`` and none is running
    (section 4.1.1).  Resets of a lane that stopped are ignored.  Then
    the design's excitation policy, if it has one (:func:`policy_signals`).

    Parameters
    ----------
    excitation : Excitation
    st : LaneState
        Reads ``alive``, ``xa``; ``d_start``, ``s_start``, ``d_amp``, ``s_amp``,
        ``recheck`` updated.
    kn : int
        Step reached (``k + 1``).
    work : TrialWork
        Reads ``block`` and ``res``.
    rec : TrialRecord
        ``reset_k``, ``reset_block``, ``reset_res``, ``n_resets`` appended.
    """
    n_res_max = rec.reset_k.shape[0]
    d_len = doublet_length(excitation.doublet_half)
    s_len = signal_3211_length(excitation.s3211_unit)
    d_start = st.d_start
    for l in range(st.xa.shape[1]):
        bk = work.block[l] if st.alive[l] else NO_RESET
        if bk != NO_RESET:
            m = rec.n_resets[l]
            if m < n_res_max:
                rec.reset_k[m, l] = kn
                rec.reset_block[m, l] = bk
                for c in range(work.res.shape[0]):
                    rec.reset_res[m, c, l] = work.res[c, l]
            rec.n_resets[l] = m + 1
            if bk == RESET_THRUST:
                if not running(kn, d_start[l], d_len):
                    d_start[l] = kn
                    st.d_amp[l] = excitation.doublet_amp
                st.recheck[l] = kn + excitation.resend_delay
            elif not running(kn, st.s_start[l], s_len):
                st.s_start[l] = kn
                st.s_amp[l] = excitation.s3211_amp
        if st.recheck[l] == kn:
            st.recheck[l] = -1
            if (st.xa[I_B1_THRUST, l] > excitation.resend_b1
                    and not running(kn, d_start[l], d_len)):
                d_start[l] = kn
                st.d_amp[l] = excitation.doublet_amp
    if excitation.policy != EXCITE_NONE:
        policy_signals(excitation, st, kn, work)


@kernel(inline="always")
def policy_signals(excitation, st, kn, work):
    """The design's excitation beyond the requests on resets.

    A live lane on which neither signal runs at step ``kn`` (after the
    requests of this step, :func:`handle_resets`), and whose belief holds no
    fault mode at ``pause_belief`` or more, starts one, at the policy's
    amplitudes (``policy_doublet_amp``, ``policy_s3211_amp``):

    * ``EXCITE_PERIODIC``: the doublet at the steps ``phase + n period`` and the
      3211 at ``phase + period // 2 + n period`` (``n`` any integer), so the two
      alternate and, when each lasts at most half a period, never overlap;
    * ``EXCITE_AMBIGUOUS``: at least ``period`` steps after the latest start of
      either signal, when the belief's most probable mode has a probability
      below ``belief_max`` or ``r_q`` or ``r_nx`` (this step's decision
      statistics, ``work.res``: the one-step residuals or the GLR's) reach
      ``suspect``: the 3211 if the doublet was the latest sent, else the doublet.

    Neither depends on Table 1's thresholds, so a lane with no reset flies the
    same under every threshold (a sweep shares its start, ``sim/lanes.py``).

    Parameters
    ----------
    excitation : Excitation
        ``policy`` (not ``EXCITE_NONE``), ``period``, ``phase``, ``belief_max``,
        ``suspect``, ``pause_belief``, the policy's amplitudes and the signals'
        lengths.
    st : LaneState
        Reads ``alive``, ``belief``; ``d_start``, ``s_start``, ``d_amp``,
        ``s_amp`` updated.
    kn : int
        Step reached (``k + 1``).
    work : TrialWork
        Reads ``res``.
    """
    d_len = doublet_length(excitation.doublet_half)
    s_len = signal_3211_length(excitation.s3211_unit)
    period = excitation.period
    d_start = st.d_start
    s_start = st.s_start
    for l in range(st.xa.shape[1]):
        if (not st.alive[l] or running(kn, d_start[l], d_len)
                or running(kn, s_start[l], s_len)):
            continue
        fault = 0.0  # the most probable fault mode's probability
        for m in range(st.belief.shape[0]):
            if m != MODE_NOMINAL:
                fault = max(fault, st.belief[m, l])
        if fault >= excitation.pause_belief:
            continue
        if excitation.policy == EXCITE_PERIODIC:
            ph = (kn - excitation.phase) % period
            if ph < 0:
                ph += period
            if ph == 0:
                d_start[l] = kn
                st.d_amp[l] = excitation.policy_doublet_amp
            elif ph == period // 2:
                s_start[l] = kn
                st.s_amp[l] = excitation.policy_s3211_amp
        else:  # EXCITE_AMBIGUOUS
            if kn - max(d_start[l], s_start[l]) < period:
                continue
            pmax = 0.0
            for m in range(st.belief.shape[0]):
                pmax = max(pmax, st.belief[m, l])
            if (pmax < excitation.belief_max or work.res[R_Q, l] >= excitation.suspect
                    or work.res[R_NX, l] >= excitation.suspect):
                if d_start[l] > s_start[l]:
                    s_start[l] = kn
                    st.s_amp[l] = excitation.policy_s3211_amp
                else:
                    d_start[l] = kn
                    st.d_amp[l] = excitation.policy_doublet_amp


# ------------------------------------------------------------------ 6. history
@kernel(inline="always")
def record_step(k, st, work, rec):
    """Stage 6: the history of step ``k`` (only while ``k < n_hist``).

    Parameters
    ----------
    k : int
        Step (its row of the history).
    st : LaneState
        Reads ``x`` (true state after the step), ``xa``, ``P``.
    work : TrialWork
        Reads ``u``, ``res``, ``exc``, ``wind``, ``block``, ``z``, ``innov``.
    rec : TrialRecord
        ``hist_*`` rows ``k`` written: true state, estimate, fault-parameter
        variances, commands, residuals, excitation, gust, block, measurements
        and normalised innovations (written on every path while a history is
        kept, :func:`filter_update`), the lateral loop's measurements (6-DOF;
        the side monitor writes its own row, ``hist_mon``).
    """
    if k >= rec.hist_x.shape[0]:
        return
    x = st.x
    xa = st.xa
    P = st.P
    for l in range(xa.shape[1]):
        for i in range(x.shape[0]):
            rec.hist_x[k, i, l] = x[i, l]
        for i in range(rec.hist_xa.shape[1]):  # the paper's 14 (no gust states)
            rec.hist_xa[k, i, l] = xa[i, l]
        for j in range(N_FAULT):
            rec.hist_pdiag[k, j, l] = P[N_X + j, N_X + j, l]
        for i in range(work.u.shape[0]):
            rec.hist_u[k, i, l] = work.u[i, l]
        for i in range(work.res.shape[0]):
            rec.hist_res[k, i, l] = work.res[i, l]
        for i in range(work.exc.shape[0]):
            rec.hist_exc[k, i, l] = work.exc[i, l]
        for i in range(work.wind.shape[0]):
            rec.hist_wind[k, i, l] = work.wind[i, l]
        rec.hist_block[k, l] = work.block[l]
        for i in range(rec.hist_z.shape[1]):
            rec.hist_z[k, i, l] = work.z[i, l]
        for i in range(work.innov.shape[0]):
            rec.hist_innov[k, i, l] = work.innov[i, l]
        for i in range(rec.hist_lat.shape[1]):  # the 6-DOF plant's lateral sensors
            rec.hist_lat[k, i, l] = st.lat[i, l]


# ------------------------------------------------------------------ 7. reconfigure
@kernel(internal=True)
def select_lanes(scheme, st, work):
    """The controller selection (eqs. 45-47) of every lane
    (:func:`ftc_mc.core.longitudinal.control.select_controllers_lanes`) on the estimate's
    first 14 states (a design's extra states are left out); ``st.cur``
    updated."""
    xa = st.xa
    P = st.P
    L = xa.shape[1]
    if xa.shape[0] != N_AUG:  # the selection predicts with the paper's model: the first 14 states
        for i in range(N_AUG):
            for l in range(L):
                work.xsel[i, l] = xa[i, l]
            for j in range(N_AUG):
                for l in range(L):
                    work.Psel[i, j, l] = P[i, j, l]
        xa = work.xsel
        P = work.Psel
    # one call site: the selection is inlined here once (each call site is a
    # copy of it, half of this stage's compile)
    select_controllers_lanes(st.cur, xa, P, st.belief, scheme, work.lsel)


@on_path("control", {RECONFIGURING: select_lanes})
def select(path, scheme, st, work):
    """The controller selection on the reconfiguring path (:func:`select_lanes`);
    c0 stays in use on the nominal one."""


@kernel(by_address=True)
def reconfigure(path, scheme, timing, inp, st, kn, period, work, rec):
    """Stage 7, every reconfiguration period: belief, controller, detection.

    Per lane: the belief update (eqs. 13-14) with the fault-parameter estimate
    and its marginal variances (eq. 12), unless the belief's boxes read other
    parameters than the paper's five (a ``lock_turn_selected`` design: its
    belief reads the side monitor's six, and its stage updated it at this
    step, :func:`ftc_mc.core.sixdof.selection.sixdof_select`); on the reconfiguring controller's
    path the controller selection (eqs. 45-47, :func:`select`) on the
    estimate's first 14 states (a design's gust states are left out), for every
    lane at once (:func:`ftc_mc.core.longitudinal.control.select_controllers_lanes`, per
    lane bit-identical to ``tests/single_trajectory.py::select_controller``; the
    horizon predictions run lane-interleaved, and the covariance's only for
    the controllers whose objective can be the smallest,
    ``docs/findings/performance.md`` lesson 19); and the detection time: the
    first period end after the switch ``k_fault`` where the final mode is the
    most probable with at least ``detect_prob`` (live lanes only).

    Parameters
    ----------
    path : Path
        The compile path (``core/shared/paths.py``): its ``control``.
    scheme : Scheme
        Reads ``belief`` (and, when reconfiguring, ``reconfig``, ``filter``,
        ``controller``, ``engine``).
    timing : Timing
        ``k_fault``, ``detect_prob``.
    inp : TrialInputs
        ``mode_post``: the final mode of each lane.
    st : LaneState
        Reads ``xa``, ``P``, ``alive``; ``belief`` and ``cur`` updated.
    kn : int
        Step reached (``k + 1``), a multiple of the period.
    period : int
        Index of the period that ends at ``kn`` (row of the record).
    work : TrialWork
        One-lane buffers ``bl``, ``bhat``, ``bvar``, ``bwork``; the selection's
        scratch ``lsel``.
    rec : TrialRecord
        ``belief``, ``bhat``, ``controller`` rows ``period`` written;
        ``detect_k`` set once.
    """
    xa = st.xa
    P = st.P
    L = xa.shape[1]
    bl = work.bl
    bh = work.bhat
    bv = work.bvar
    # boxes on other parameters than the paper's five: the 6-DOF selection's
    # belief, updated before this stage (trial.six_dof_selection)
    update = scheme.belief.lo.shape[1] == N_FAULT
    for l in range(L):
        best = belief_update_lane(st.belief, l, scheme.belief, xa, P, N_X, update, bl, bh, bv,
                                  work.bwork)
        for m in range(N_MODES):
            rec.belief[period, m, l] = bl[m]
        for j in range(N_FAULT):
            rec.bhat[period, j, l] = bh[j]
        mp = inp.mode_post[l]
        if (st.alive[l] and kn > timing.k_fault and rec.detect_k[l] < 0 and best == mp
                and bl[mp] >= timing.detect_prob):
            rec.detect_k[l] = kn
    select(path, scheme, st, work)
    for l in range(L):
        rec.controller[period, l] = st.cur[l]


# ------------------------------------------------------------------ end
@kernel(by_address=True)
def record_end(st, rec):
    """The final augmented estimate of every lane (``rec.xa_end``: its first
    ``rec.xa_end.shape[0]`` states)."""
    for i in range(rec.xa_end.shape[0]):
        for l in range(st.xa.shape[1]):
            rec.xa_end[i, l] = st.xa[i, l]
