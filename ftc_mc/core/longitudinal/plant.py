"""The truth step of a trial, on every lane: what the simulated aircraft does.

Stage 2 of :func:`ftc_mc.core.longitudinal.trial.advance`.  With the commands ``u_k`` of the
step (deviations from trim, ``TrialWork.u``):

1. the fault schedule's entry in force at step ``k`` gives the truth ``b0``,
   ``b1`` and the other fault parameters ``fp`` per actuator; each actuator
   follows its command through the generic fault model (delay, limit cycle,
   runaway, float, rate limit) and the effect is eq. (2)
   ``e_k = b0 + (1 - b1) c_k - b1 u0`` (:func:`actuator_effect`; ``c_k = u_k``
   with neutral parameters);
2. in turbulence the Dryden filter gives the gust ``g_k`` held over the step and
   advances (:func:`gust_lanes`, :mod:`ftc_mc.core.shared.dryden`);
3. linear plant (the filter's model, eq. 1):
   ``x_{k+1} = A x_k + B e_k + B_w g_k + w_k`` and
   ``z_{k+1} = C x_{k+1} + D_w g_{k+1} + v_k`` (:func:`linear_step`);
   nonlinear X8 (:mod:`ftc_mc.core.longitudinal.nonlinear`, RK4 with ``n_sub`` sub-steps):
   ``x_{k+1} = RK4(x0 + x_k, u0 + e_k, g_k) - x0 + w_k`` and
   ``z_{k+1} = h(x0 + x_{k+1}, g_{k+1}) - y0 + v_k`` (:func:`nonlinear_step`);
4. the true air-relative airspeed and angle of attack, for the validity check
   (``TrialWork.va``, ``TrialWork.alpha``);
5. the lane's sensor fault, if any, on its one output ``o`` from the onset step
   ``k_s`` on (:func:`sensor_fault`): bias ``z_o += size``; drift
   ``z_o += size (k + 1 - k_s) dt``; stuck ``z_o = `` the last healthy ``z_o``
   (``LaneState.zhold``); noise ``z_o += (size - 1) v_o`` (the noise scaled by
   ``size``).  The air data of step 4 stay true: a sensor fault misleads the
   estimator, not the validity check.

Plain-NumPy twins: ``tests/naive.py::truth_step_ref``, ``sensor_fault_ref``.
"""

from __future__ import annotations

import math

from ...conventions import (FP_DELAY, FP_FLOAT, FP_FLOAT_ANGLE, FP_FLOAT_GAIN, FP_OSC_AMP,
                            FP_OSC_FREQ, FP_OSC_PHASE, FP_RATE, FP_RUNAWAY, N_U, N_X, N_Z,
                            OUT_ALPHA, OUT_VA, SENSOR_BIAS, SENSOR_DRIFT, SENSOR_NOISE,
                            SENSOR_STUCK)
from ..shared.dryden import N_GUST_OUT, N_GUST_STATE, gust_step
from ..jit import kernel
from .nonlinear import outputs_nb, propagate
from ..shared.paths import (LINEAR_PLANT, NONLINEAR_PLANT, SIXDOF_EXTENDED_PLANT, SIXDOF_PLANT,
                            on_path)


@kernel
def schedule_entry(k_switch, k):
    """Index of the fault-schedule entry in force during step ``k``.

    Parameters
    ----------
    k_switch : ndarray of int64, shape (E,)
        Non-decreasing steps at which the truth switches, ``k_switch[0] == 0``.
    k : int
        Step.

    Returns
    -------
    int
        The last ``e`` with ``k_switch[e] <= k``.
    """
    ev = 0
    while ev + 1 < k_switch.shape[0] and k >= k_switch[ev + 1]:
        ev += 1
    return ev


@kernel(internal=True)
def actuator_effect(u0, lo, hi, b0, b1, fp, k_on, k, dt, alpha, uhist, uprev, u, e):
    """Effect of the actuators on every lane: the generic fault model, then eq. (2).

    Each actuator ``i`` of lane ``l`` follows a command ``c`` (deviation from
    trim) built from the commanded ``u`` by the parameters ``fp`` of the
    schedule entry in force (``docs/guides/fault-kinds.md``):

    1. transport delay of ``d = fp[FP_DELAY]`` steps: ``c = u_{k-d}`` (trim
       before the first step), from the ring ``uhist``;
    2. limit cycle and runaway, ``t = (k - k_on) dt`` the time since the
       entry's start: ``c += A sin(2 pi f t + phi) + r t``;
    3. float: ``c = (1 - w) c + w (delta_f0 + k_f alpha - u0)``, the
       surface trailing at its floating angle, linear in the true angle of
       attack ``alpha`` of the last sample;
    4. steps 2-3 (when any of ``A``, ``r``, ``w`` is nonzero) stop at the
       travel limits ``[lo, hi]``;
    5. rate limit ``R = fp[FP_RATE]``: ``c`` moves at most ``R dt`` from the
       last step's ``uprev``;
    6. eq. (2): ``e = b0 + (1 - b1) c - b1 u0``.

    With the neutral parameters (:data:`~ftc_mc.conventions.FAULT_PARAM_NEUTRAL`:
    no delay, an infinite rate limit, every other term zero) ``c = u`` and the
    arithmetic is eq. (2)'s, bit for bit.  A kernel of its own (not inlined):
    compiled once for the truth of both plant families.

    Parameters
    ----------
    u0 : ndarray, shape (3,)
        Trim commands (absolute).
    lo, hi : ndarray, shape (3,)
        Travel limits as deviations from trim.
    b0, b1 : ndarray, shape (3, L)
        Truth fault parameters per actuator (``b0`` the absolute lock position
        when locked).
    fp : ndarray, shape (N_FAULT_PARAM, 3, L)
        The entry's other parameters (:data:`~ftc_mc.conventions.FAULT_PARAM_NAMES`).
    k_on : int
        Step at which the entry took over.
    k : int
        Step.
    dt : float
        Control period [s].
    alpha : ndarray, shape (L,)
        True angle of attack at the last sample [rad] (0 before the first step).
    uhist : ndarray, shape (N_CMD_HIST, 3, L)
        Command ring, written with ``u`` at slot ``k % N_CMD_HIST``.
    uprev : ndarray, shape (3, L)
        The command followed last step, overwritten with this step's.
    u : ndarray, shape (3, L)
        Command deviations from trim.
    e : ndarray, shape (3, L)
        Written with the effect (deviation from trim).
    """
    L = u.shape[1]
    H = uhist.shape[0]
    slot = k % H
    t = (k - k_on) * dt
    for i in range(N_U):
        u0i = u0[i]
        for l in range(L):
            c = u[i, l]
            uhist[slot, i, l] = c
            d = int(fp[FP_DELAY, i, l])
            if d > 0:
                c = uhist[(k - d) % H, i, l] if k >= d else 0.0
            amp = fp[FP_OSC_AMP, i, l]
            run = fp[FP_RUNAWAY, i, l]
            wf = fp[FP_FLOAT, i, l]
            if amp != 0.0 or run != 0.0 or wf != 0.0:
                c += amp * math.sin(2.0 * math.pi * fp[FP_OSC_FREQ, i, l] * t
                                    + fp[FP_OSC_PHASE, i, l]) + run * t
                if wf != 0.0:
                    fl = fp[FP_FLOAT_ANGLE, i, l] + fp[FP_FLOAT_GAIN, i, l] * alpha[l] - u0i
                    c = (1.0 - wf) * c + wf * fl
                c = min(hi[i], max(lo[i], c))
            lim = fp[FP_RATE, i, l] * dt
            p = uprev[i, l]
            if c > p + lim:
                c = p + lim
            elif c < p - lim:
                c = p - lim
            uprev[i, l] = c
            b1il = b1[i, l]
            e[i, l] = b0[i, l] + (1.0 - b1il) * c - b1il * u0i


@kernel(inline="always")
def gust_lanes(plant, eta, gust, wind, wind_next, work):
    """Dryden gusts of every lane: the gust held over the step and the next one.

    Parameters
    ----------
    plant : TruthPlant
        ``Ad``, ``Bd``, ``Cd`` of the discrete Dryden model.
    eta : ndarray, shape (4, L)
        Standard normal draws of this step.
    gust : ndarray, shape (4, L)
        Gust filter states ``s_k``, advanced in place to ``s_{k+1}``.
    wind, wind_next : ndarray, shape (3, L)
        Written with ``Cd s_k`` and ``Cd s_{k+1}`` (``u_g``, ``w_g`` [m/s],
        ``q_g`` [rad/s]).
    work : TrialWork
        One-lane buffers ``gust``, ``eta``, ``wl``.
    """
    L = gust.shape[1]
    gs = work.gust
    et = work.eta
    wl = work.wl
    for l in range(L):
        for i in range(N_GUST_STATE):
            gs[i] = gust[i, l]
            et[i] = eta[i, l]
        gust_step(gs, et, plant.Ad, plant.Bd, plant.Cd, wl)
        for i in range(N_GUST_STATE):
            gust[i, l] = gs[i]
        for i in range(N_GUST_OUT):
            wind[i, l] = wl[i]
            acc = 0.0
            for j in range(N_GUST_STATE):
                acc += plant.Cd[i, j] * gs[j]
            wind_next[i, l] = acc


@kernel(inline="always")
def linear_step(model, flight, w, v, x, work):
    """Linear plant of eq. (1) on every lane, with gusts when ``flight.plant.turb``.

    Parameters
    ----------
    model : FilterModel
        ``A``, ``B``, ``C`` (the truth uses the filter's own linear model).
    flight : Flight
        ``plant`` (gust matrices ``Bw``, ``Dw``) and ``validity`` (trim airspeed
        and angle of attack).
    w : ndarray, shape (9, L)
        Process noise of the step.
    v : ndarray, shape (12, L)
        Measurement noise of the step.
    x : ndarray, shape (9, L)
        True state (deviation from trim), advanced in place.
    work : TrialWork
        Reads ``e``, ``wind``, ``wind_next``; writes ``x_next``, ``z``, ``va``,
        ``alpha``.
    """
    pl = flight.plant
    val = flight.validity
    turb = pl.turb != 0
    L = x.shape[1]
    xn = work.x_next
    e = work.e
    wind = work.wind
    wind_next = work.wind_next
    z = work.z
    for i in range(N_X):
        for l in range(L):
            xn[i, l] = w[i, l]
        for j in range(N_X):
            aij = model.A[i, j]
            for l in range(L):
                xn[i, l] += aij * x[j, l]
        for j in range(N_U):
            bij = model.B[i, j]
            for l in range(L):
                xn[i, l] += bij * e[j, l]
        if turb:
            for j in range(N_GUST_OUT):
                bij = pl.Bw[i, j]
                for l in range(L):
                    xn[i, l] += bij * wind[j, l]
    for i in range(N_X):
        for l in range(L):
            x[i, l] = xn[i, l]
    for r in range(N_Z):
        for l in range(L):
            z[r, l] = v[r, l]
        for j in range(N_X):
            crj = model.C[r, j]
            if crj != 0.0:
                for l in range(L):
                    z[r, l] += crj * x[j, l]
        if turb:
            for j in range(N_GUST_OUT):
                drj = pl.Dw[r, j]
                for l in range(L):
                    z[r, l] += drj * wind_next[j, l]
    # airspeed and angle of attack, air-relative, for the validity check
    for l in range(L):
        va = val.va_trim
        al = val.alpha_trim
        for j in range(N_X):
            va += model.C[OUT_VA, j] * x[j, l]
            al += model.C[OUT_ALPHA, j] * x[j, l]
        if turb:
            for j in range(N_GUST_OUT):
                va += pl.Dw[OUT_VA, j] * wind_next[j, l]
                al += pl.Dw[OUT_ALPHA, j] * wind_next[j, l]
        work.va[l] = va
        work.alpha[l] = al


@kernel(inline="always")
def nonlinear_step(u0, plant, w, v, x, work):
    """Nonlinear X8 on every lane, one lane at a time (RK4, ``plant.n_sub`` steps).

    Parameters
    ----------
    u0 : ndarray, shape (3,)
        Trim commands (absolute).
    plant : TruthPlant
        ``p``, ``x0``, ``y0``, ``dt``, ``n_sub``.
    w, v : ndarray, shapes (9, L) and (12, L)
        Process and measurement noise of the step.
    x : ndarray, shape (9, L)
        True state (deviation from trim ``plant.x0``), advanced in place.
    work : TrialWork
        Reads ``e``, ``wind``, ``wind_next``; writes ``z``, ``va``, ``alpha``;
        one-lane buffers ``xabs``, ``cmd``, ``wl``, ``y``, ``rk4``.
    """
    L = x.shape[1]
    xabs = work.xabs
    cmd = work.cmd
    wl = work.wl
    y = work.y
    for l in range(L):
        for i in range(N_X):
            xabs[i] = plant.x0[i] + x[i, l]
        for i in range(N_U):
            cmd[i] = u0[i] + work.e[i, l]
        for i in range(N_GUST_OUT):
            wl[i] = work.wind[i, l]
        propagate(xabs, cmd, plant.p, wl, plant.dt, plant.n_sub, work.rk4)
        for i in range(N_X):
            xabs[i] += w[i, l]
            x[i, l] = xabs[i] - plant.x0[i]
        for i in range(N_GUST_OUT):
            wl[i] = work.wind_next[i, l]
        outputs_nb(xabs, plant.p, wl, y)
        for r in range(N_Z):
            work.z[r, l] = v[r, l] + (y[r] - plant.y0[r])
        work.va[l] = y[OUT_VA]
        work.alpha[l] = y[OUT_ALPHA]


@kernel(inline="always")
def sensor_fault(inp, k, dt, v, zhold, z):
    """Apply each lane's sensor fault to the measurement ``z_{k+1}`` (module docstring).

    Parameters
    ----------
    inp : TrialInputs
        ``sensor_out`` (output index or -1), ``sensor_kind``, ``sensor_size``,
        ``sensor_k`` (onset step).
    k : int
        Step (the measurement is ``z_{k+1}``).
    dt : float
        Control period [s].
    v : ndarray, shape (12, L)
        Measurement noise of the step (already in ``z``).
    zhold : ndarray, shape (L,)
        Last healthy value of the faulty output: written before the onset, read
        by a stuck fault after it.
    z : ndarray, shape (12, L)
        Measurements, modified in place on the faulty output of each lane.
    """
    for l in range(z.shape[1]):
        o = inp.sensor_out[l]
        if o < 0:
            continue
        ks = inp.sensor_k[l]
        if k < ks:
            zhold[l] = z[o, l]
            continue
        kind = inp.sensor_kind[l]
        size = inp.sensor_size[l]
        if kind == SENSOR_BIAS:
            z[o, l] += size
        elif kind == SENSOR_DRIFT:
            z[o, l] += size * (k + 1 - ks) * dt
        elif kind == SENSOR_STUCK:
            z[o, l] = zhold[l]
        elif kind == SENSOR_NOISE:
            z[o, l] += (size - 1.0) * v[o, l]


@kernel(internal=True)
def linear_truth(model, flight, w, v, x, work):
    """:func:`linear_step` as a kernel of its own (one compile for every path
    that flies the linear plant)."""
    linear_step(model, flight, w, v, x, work)


@kernel(internal=True)
def nonlinear_truth(model, flight, w, v, x, work):
    """:func:`nonlinear_step` with :func:`linear_step`'s parameters, as a kernel
    of its own."""
    nonlinear_step(model.u0, flight.plant, w, v, x, work)


@on_path("plant", {LINEAR_PLANT: linear_truth, NONLINEAR_PLANT: nonlinear_truth})
def plant_step(path, model, flight, w, v, x, work):
    """The path's truth plant over one step: :func:`linear_step` or the
    nonlinear X8 (:func:`nonlinear_step`)."""


@kernel(inline="always")
def truth_step(path, model, ctl, flight, inp, k, st, work):
    """Stage 2: the truth plant over step ``k -> k+1`` on every lane (module docstring).

    Parameters
    ----------
    path : Path
        The compile path (``core/shared/paths.py``): its ``plant``.
    model : FilterModel
        The linear model (``A``, ``B``, ``C``) and the trim commands ``u0``.
    ctl : Controller
        ``lo_dev``, ``hi_dev``: the actuators' travel (command limits) from trim.
    flight : Flight
        ``plant`` (TruthPlant) and ``validity`` (trim air data).
    inp : TrialInputs
        Fault schedule (``k_switch``, ``b0``, ``b1``, ``fp``), the noise and gust
        draws of step ``k`` and the lanes' sensor faults.
    k : int
        Step.
    st : LaneState
        ``x`` (true state, deviation from trim) and ``gust`` (gust filter
        states; untouched in still air) advanced in place; ``zhold`` (the last
        healthy value of a faulty output) kept up to the onset; ``uhist``,
        ``uprev`` (the actuators' command ring and last command) advanced.
    work : TrialWork
        Reads ``u``; writes ``e``, ``wind``, ``wind_next``, ``z``, ``va``,
        ``alpha`` (and ``x_next`` on the linear plant).
    """
    pl = flight.plant
    ev = schedule_entry(inp.k_switch, k)
    actuator_effect(model.u0, ctl.lo_dev, ctl.hi_dev, inp.b0[ev], inp.b1[ev], inp.fp[ev],
                    inp.k_switch[ev], k, pl.dt, work.alpha, st.uhist, st.uprev, work.u,
                    work.e)
    if pl.turb != 0:
        gust_lanes(pl, inp.eta[k], st.gust, work.wind, work.wind_next, work)
    plant_step(path, model, flight, inp.w[k], inp.v[k], st.x, work)
    sensor_fault(inp, k, pl.dt, inp.v[k], st.zhold, work.z)


@kernel(internal=True)
def longitudinal_truth(plant, scheme, flight, inp, k, st, work, rec):
    """:func:`truth_step` on a longitudinal plant (``plant`` its marker), as a
    kernel of its own."""
    truth_step(plant, scheme.filter, scheme.controller, flight, inp, k, st, work)


@on_path("plant", {LINEAR_PLANT: longitudinal_truth, NONLINEAR_PLANT: longitudinal_truth,
                   SIXDOF_PLANT: "ftc_mc.core.sixdof.truth:sixdof_truth",
                   SIXDOF_EXTENDED_PLANT: "ftc_mc.core.sixdof.truth:sixdof_truth"},
         passes="marker")
def truth(path, scheme, flight, inp, k, st, work, rec):
    """Stage 2 of the path's plant family: :func:`truth_step` on the
    longitudinal plants, :func:`ftc_mc.core.sixdof.truth.sixdof_truth` on the
    6-DOF one (imported only by a path that flies it)."""
