"""Monte Carlo trials of the semi-closed estimation loop, many at once (lanes).

One lane is one trial: the truth plant (the linear model of eq. 4, or the
nonlinear X8, each with or without Dryden gusts) with the injected fault and
process/measurement noise, the nominal discounted-LQR controller with the
saturation of eqs. (15-16), the doublet / 3211 excitation on reset requests and
the re-sent doublet (section 4.1.1), the estimator (eqs. 5-11, Table 1), and the
belief (eqs. 12-14) every reconfiguration period.

Lane-last storage (``a[..., L]``) lets the inner loops vectorise across trials
(PERFORMANCE.md lesson 2).  Random numbers come in from outside (``w``, ``v``) so
each trial's stream depends only on its own seed.

Timeline of step ``k -> k+1`` (time ``t = k dt``):

1. controller ``U = -K x_hat_k``; commands ``u_k = f(U, s_k, A_k)`` (eq. 15);
2. truth: fault parameters of the schedule's current entry; effect
   ``e_k`` (eq. 2); gust ``g_k`` held over the step (none in still air); linear
   plant: ``x_{k+1} = A x_k + B e_k + B_w g_k + w_k`` and
   ``z_{k+1} = C x_{k+1} + D_w g_{k+1} + v_k``; nonlinear plant:
   ``x_{k+1} = RK4(x_k, u0 + e_k, g_k) + w_k`` and
   ``z_{k+1} = h(x_{k+1}, g_{k+1}) - y_0 + v_k`` (absolute state ``x0 + x``);
3. filter step with ``u_k`` and ``z_{k+1}`` (see :mod:`ftc_mc.core.step`);
4. a reset of the thrust block starts the doublet on the engine (unless one is
   running) and schedules a re-check ``resend_delay`` steps later, when the
   doublet is sent again if ``b1_thrust`` is estimated above ``resend_b1``; a
   reset of the elevon block starts the 3211 (+ on the left, - on the right
   elevon) unless one is running;
5. every ``reconf_every`` steps the belief is updated from the fault-parameter
   estimate and its marginal variances.
"""

from __future__ import annotations

import numpy as np

from .batch import STEP_ROWS, filter_step_lanes
from .belief import belief_update
from .control import C_ELEVON, controller_command, select_controller
from .dryden import gust_step
from .excitation import doublet, saturate, signal_3211
from .jit import kernel
from .nonlinear import make_work, outputs_nb, propagate
from .settings import LaneState

from ..conventions import (OUT_ALPHA, OUT_VA, STATUS_AIRSPEED, STATUS_ALPHA,  # noqa: E402
                           STATUS_NAMES, STATUS_NONFINITE, STATUS_NOT_PSD, STATUS_OK)

NO_SIGNAL = -(1 << 40)


@kernel
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


@kernel
def advance(scheme, flight, inp, rec, st, k0, k1):
    """Advance ``L`` trials from step ``k0`` to ``k1``, writing their records.

    Parameters
    ----------
    scheme : Scheme
        The FTC scheme: ``filter`` (FilterModel), ``detection`` (Detection),
        ``belief`` (Belief), ``controller`` (Controller), ``excitation``
        (Excitation), ``reconfig`` (Reconfig) and ``engine`` (EngineTables).
    flight : Flight
        ``timing`` (Timing), ``validity`` (Validity) and ``plant`` (TruthPlant).
    (fields, by the names used below)
    tim : Timing
    val : Validity
        A lane stops being recorded (its ``status`` and ``stop_k`` are set, later
        resets and detections are ignored) when its estimate or covariance is
        not finite, its covariance fails the Cholesky test (every
        ``psd_every`` steps), or the true airspeed or angle of attack leaves
        the validity bounds.  Both are air-relative, as the aerodynamics see
        them (linear plant: trim plus the linear outputs with the gust
        feed-through; nonlinear: its outputs).  The inertial angle of attack
        would be the wrong test in turbulence: the aircraft follows the air
        mass, so its inertial angle swings with the gust (1 sigma 4.8 deg in
        moderate turbulence) while the aerodynamic one stays near 1.5 deg.
    rc : Reconfig
        ``rc.kind == 0``: the nominal controller c0 throughout; ``1``: the
        controller is re-selected every reconfiguration period (eqs. 45-47)
        among c0, c1 and c2 (:mod:`ftc_mc.core.control`).
    eng : EngineTables
        Theorem 4.1 tables of c1.
    pl : TruthPlant
        The simulated plant: the linear model of eq. (1) or the nonlinear X8
        (:mod:`ftc_mc.core.nonlinear`, RK4 with ``pl.n_sub`` sub-steps), each
        with or without Dryden gusts (:mod:`ftc_mc.core.dryden`).
    inp : TrialInputs
        Per-lane fault schedule, initial estimates and noise.
    rec : TrialRecord
        Outputs, continued from step ``k0`` (initialised by :func:`init_state`).
    st : LaneState
        The trials' state at step ``k0``, advanced in place to ``k1``.  It holds
        everything a trial carries from one step to the next, so a state saved
        at some step and advanced later gives bit-identical results.
    k0, k1 : int
        First step and end step (``0 <= k0 <= k1 <= tim.n_steps``).
    """
    fm = scheme.filter
    det = scheme.detection
    bs = scheme.belief
    ctl = scheme.controller
    exc = scheme.excitation
    rc = scheme.reconfig
    eng = scheme.engine
    tim = flight.timing
    val = flight.validity
    pl = flight.plant
    L = inp.w.shape[2]
    nx = 9
    n_res_max = rec.reset_k.shape[0]
    x = st.x
    xa = st.xa
    P = st.P
    d_start = st.d_start
    s_start = st.s_start
    recheck = st.recheck
    belief = st.belief
    alive = st.alive
    cur = st.cur
    xn = np.zeros((nx, L))
    u = np.zeros((3, L))
    e = np.zeros((3, L))
    z = np.zeros((12, L))
    res = np.zeros((3, L))
    block = np.zeros(L, dtype=np.int64)
    phi = np.zeros((9, 5, L))
    T = np.zeros((9, 14, L))
    work = np.zeros((STEP_ROWS, 14, L))
    bl = np.zeros(4)
    bh = np.zeros(5)
    bv = np.zeros(5)
    bwork = np.zeros(8)
    chol = np.zeros((14, 14))
    xl = np.zeros(14)
    Ul = np.zeros(3)
    Pl = np.zeros((14, 14))
    xs = np.zeros(14)
    Ps = np.zeros((14, 14))
    sel_work = np.zeros((4, 14))
    phi1 = np.zeros((9, 5))
    T1 = np.zeros((9, 14))
    bsel = np.zeros(4)
    exc_now = np.zeros((4, L))
    turb = pl.turb != 0
    wind = np.zeros((3, L))
    wind_next = np.zeros((3, L))
    gs = np.zeros(4)
    eta = np.zeros(4)
    wl = np.zeros(3)
    xabs = np.zeros(nx)
    cmd = np.zeros(3)
    yl = np.zeros(12)
    nl_work = make_work()
    va_now = np.zeros(L)
    al_now = np.zeros(L)
    n_hist = rec.hist_x.shape[0]
    d_len = 2 * exc.doublet_half
    s_len = 7 * exc.s3211_unit
    period = k0 // tim.reconf_every
    ev = 0
    n_ev = inp.k_switch.shape[0]
    for k in range(k0, k1):
        # 1. controller and saturation with excitation headroom (eqs. 15-25, 44)
        if rc.kind == 0:
            for i in range(3):
                for l in range(L):
                    u[i, l] = 0.0
                for j in range(nx):
                    kij = ctl.K[i, j]
                    for l in range(L):
                        u[i, l] -= kij * xa[j, l]
        else:
            for l in range(L):
                for i in range(14):
                    xl[i] = xa[i, l]
                controller_command(cur[l], xl, ctl.K, eng, fm.u0, Ul)
                for i in range(3):
                    u[i, l] = Ul[i]
        for l in range(L):
            kd = k - d_start[l]
            if 0 <= kd < d_len:
                sd = doublet(kd, exc.doublet_half, exc.doublet_amp)
                u[0, l] = saturate(u[0, l], sd, exc.doublet_amp, ctl.lo_dev[0],
                                   ctl.hi_dev[0])
            else:
                sd = 0.0
                u[0, l] = saturate(u[0, l], 0.0, 0.0, ctl.lo_dev[0], ctl.hi_dev[0])
            exc_now[0, l] = sd
            exc_now[2, l] = 1.0 if kd == 0 else 0.0
            ks = k - s_start[l]
            if 0 <= ks < s_len:
                s = signal_3211(ks, exc.s3211_unit, exc.s3211_amp)
                if cur[l] == C_ELEVON:  # eq. 23: scaled by the left elevon's efficiency
                    s *= 1.0 - xa[12, l]
                a = exc.s3211_amp
            else:
                s = 0.0
                a = 0.0
            exc_now[1, l] = s
            exc_now[3, l] = 1.0 if ks == 0 else 0.0
            u[1, l] = saturate(u[1, l], s, a, ctl.lo_dev[1], ctl.hi_dev[1])
            u[2, l] = saturate(u[2, l], -s, a, ctl.lo_dev[2], ctl.hi_dev[2])
        # 2. truth: actuator effect (eq. 2), gusts, plant (eq. 4 or nonlinear)
        while ev + 1 < n_ev and k >= inp.k_switch[ev + 1]:
            ev += 1
        for i in range(3):
            u0 = fm.u0[i]
            for l in range(L):
                b1il = inp.b1[ev, i, l]
                e[i, l] = inp.b0[ev, i, l] + (1.0 - b1il) * u[i, l] - b1il * u0
        if turb:
            for l in range(L):
                for i in range(4):
                    gs[i] = st.gust[i, l]
                    eta[i] = inp.eta[k, i, l]
                gust_step(gs, eta, pl.Ad, pl.Bd, pl.Cd, wl)
                for i in range(4):
                    st.gust[i, l] = gs[i]
                for i in range(3):
                    wind[i, l] = wl[i]
                    # the gust at the next sample, seen by its measurement
                    acc = 0.0
                    for j in range(4):
                        acc += pl.Cd[i, j] * gs[j]
                    wind_next[i, l] = acc
        if pl.kind == 0:
            for i in range(nx):
                for l in range(L):
                    xn[i, l] = inp.w[k, i, l]
                for j in range(nx):
                    aij = fm.A[i, j]
                    for l in range(L):
                        xn[i, l] += aij * x[j, l]
                for j in range(3):
                    bij = fm.B[i, j]
                    for l in range(L):
                        xn[i, l] += bij * e[j, l]
                if turb:
                    for j in range(3):
                        bij = pl.Bw[i, j]
                        for l in range(L):
                            xn[i, l] += bij * wind[j, l]
            for i in range(nx):
                for l in range(L):
                    x[i, l] = xn[i, l]
            for r in range(12):
                for l in range(L):
                    z[r, l] = inp.v[k, r, l]
                for j in range(nx):
                    crj = fm.C[r, j]
                    if crj != 0.0:
                        for l in range(L):
                            z[r, l] += crj * x[j, l]
                if turb:
                    for j in range(3):
                        drj = pl.Dw[r, j]
                        for l in range(L):
                            z[r, l] += drj * wind_next[j, l]
            # airspeed and angle of attack for the validity check
            for l in range(L):
                va = val.va_trim
                al = val.alpha_trim
                for j in range(nx):
                    va += fm.C[OUT_VA, j] * x[j, l]
                    al += fm.C[OUT_ALPHA, j] * x[j, l]
                if turb:
                    for j in range(3):
                        va += pl.Dw[OUT_VA, j] * wind_next[j, l]
                        al += pl.Dw[OUT_ALPHA, j] * wind_next[j, l]
                va_now[l] = va
                al_now[l] = al
        else:
            for l in range(L):
                for i in range(nx):
                    xabs[i] = pl.x0[i] + x[i, l]
                for i in range(3):
                    cmd[i] = fm.u0[i] + e[i, l]
                    wl[i] = wind[i, l]
                propagate(xabs, cmd, pl.p, wl, pl.dt, pl.n_sub, nl_work)
                for i in range(nx):
                    xabs[i] += inp.w[k, i, l]
                    x[i, l] = xabs[i] - pl.x0[i]
                for i in range(3):
                    wl[i] = wind_next[i, l]
                outputs_nb(xabs, pl.p, wl, yl)
                for r in range(12):
                    z[r, l] = inp.v[k, r, l] + (yl[r] - pl.y0[r])
                va_now[l] = yl[OUT_VA]
                al_now[l] = yl[OUT_ALPHA]
        # 3. estimator
        filter_step_lanes(xa, P, u, z, fm, det, phi, T, work, res, block)
        for l in range(L):
            st.rmax[0, l] = max(st.rmax[0, l], res[0, l])
            st.rmax[1, l] = max(st.rmax[1, l], res[1, l])
        kn = k + 1
        # validity of the trial: numerics and the linear model's envelope
        check_psd = kn % val.psd_every == 0
        for l in range(L):
            if not alive[l]:
                continue
            status = STATUS_OK
            va = va_now[l]
            al = al_now[l]
            finite = np.isfinite(va) and np.isfinite(al)
            for i in range(14):
                if not (np.isfinite(xa[i, l]) and np.isfinite(P[i, i, l])):
                    finite = False
            if not finite:
                status = STATUS_NONFINITE
            elif check_psd and not is_psd(P, l, chol):
                status = STATUS_NOT_PSD
            elif not (val.va_min <= va <= val.va_max):
                status = STATUS_AIRSPEED
            elif not (val.alpha_min <= al <= val.alpha_max):
                status = STATUS_ALPHA
            if status != STATUS_OK:
                alive[l] = False
                rec.status[l] = status
                rec.stop_k[l] = kn
        # 4. resets, excitation requests, re-sent doublet
        for l in range(L):
            bk = block[l] if alive[l] else 0
            if bk != 0:
                n = rec.n_resets[l]
                if n < n_res_max:
                    rec.reset_k[n, l] = kn
                    rec.reset_block[n, l] = bk
                    for c in range(3):
                        rec.reset_res[n, c, l] = res[c, l]
                rec.n_resets[l] = n + 1
                if bk == 1:
                    if not (0 <= kn - d_start[l] < d_len):
                        d_start[l] = kn
                    recheck[l] = kn + exc.resend_delay
                elif not (0 <= kn - s_start[l] < s_len):
                    s_start[l] = kn
            if recheck[l] == kn:
                recheck[l] = -1
                if xa[11, l] > exc.resend_b1 and not (0 <= kn - d_start[l] < d_len):
                    d_start[l] = kn
        if k < n_hist:
            for l in range(L):
                for i in range(nx):
                    rec.hist_x[k, i, l] = x[i, l]
                for i in range(14):
                    rec.hist_xa[k, i, l] = xa[i, l]
                for j in range(5):
                    rec.hist_pdiag[k, j, l] = P[9 + j, 9 + j, l]
                for i in range(3):
                    rec.hist_u[k, i, l] = u[i, l]
                    rec.hist_res[k, i, l] = res[i, l]
                for i in range(4):
                    rec.hist_exc[k, i, l] = exc_now[i, l]
                for i in range(3):
                    rec.hist_wind[k, i, l] = wind[i, l]
                rec.hist_block[k, l] = block[l]
        # 5. belief every reconfiguration period (eqs. 13-14) and controller
        #    selection (eqs. 45-47)
        if kn % tim.reconf_every == 0:
            for l in range(L):
                for m in range(4):
                    bl[m] = belief[m, l]
                for j in range(5):
                    bh[j] = xa[9 + j, l]
                    bv[j] = P[9 + j, 9 + j, l]
                best = belief_update(bl, bs, bh, bv, bwork)
                for m in range(4):
                    belief[m, l] = bl[m]
                    rec.belief[period, m, l] = bl[m]
                for j in range(5):
                    rec.bhat[period, j, l] = bh[j]
                if rc.kind != 0:
                    for i in range(14):
                        xl[i] = xa[i, l]
                        for j in range(14):
                            Pl[i, j] = P[i, j, l]
                    cur[l] = select_controller(cur[l], xl, Pl, bl, fm, bs, rc, eng, ctl.K,
                                               ctl.lo_dev, ctl.hi_dev, xs, Ps, bsel, sel_work,
                                               phi1, T1)
                rec.controller[period, l] = cur[l]
                mp = inp.mode_post[l]
                if (alive[l] and kn > tim.k_fault and rec.detect_k[l] < 0 and best == mp
                        and bl[mp] >= tim.detect_prob):
                    rec.detect_k[l] = kn
            period += 1
    for i in range(14):
        for l in range(L):
            rec.xa_end[i, l] = xa[i, l]


@kernel
def init_state(inp, st, rec):
    """Initial state of every lane (trim, the initial estimate, the belief one-hot
    on the initial mode, no excitation) and the record's per-lane fields."""
    L = inp.w.shape[2]
    for l in range(L):
        for i in range(9):
            st.x[i, l] = 0.0
        for i in range(14):
            st.xa[i, l] = inp.xa0[i, l]
            for j in range(14):
                st.P[i, j, l] = inp.P0[i, j]
        st.d_start[l] = NO_SIGNAL
        st.s_start[l] = NO_SIGNAL
        st.recheck[l] = -1
        for m in range(4):
            st.belief[m, l] = 0.0
        st.belief[inp.mode_pre[l], l] = 1.0
        st.alive[l] = True
        st.cur[l] = 0
        st.rmax[0, l] = 0.0
        st.rmax[1, l] = 0.0
        rec.stop_k[l] = -1
        rec.n_resets[l] = 0
        rec.detect_k[l] = -1
        rec.status[l] = STATUS_OK
        for i in range(4):
            st.gust[i, l] = inp.g0[i, l]


@kernel
def new_state(L):
    """A :class:`LaneState` of ``L`` lanes (contents set by :func:`init_state`)."""
    return LaneState(x=np.zeros((9, L)), xa=np.zeros((14, L)), P=np.zeros((14, 14, L)),
                     d_start=np.zeros(L, dtype=np.int64),
                     s_start=np.zeros(L, dtype=np.int64),
                     recheck=np.zeros(L, dtype=np.int64), belief=np.zeros((4, L)),
                     alive=np.zeros(L, dtype=np.bool_), cur=np.zeros(L, dtype=np.int64),
                     rmax=np.zeros((2, L)), gust=np.zeros((4, L)))


@kernel
def run_trials(scheme, flight, inp, rec):
    """Simulate ``L`` trials from the start to the end (see :func:`advance`).

    Parameters are those of :func:`advance` without the state and step range;
    ``rec`` is overwritten.
    """
    st = new_state(inp.w.shape[2])
    init_state(inp, st, rec)
    advance(scheme, flight, inp, rec, st, 0, flight.timing.n_steps)
