"""The gust-aware augmented filter on every lane (DESIGN.md section 9).

The paper's filter (:mod:`ftc_mc.core.longitudinal.batch`) models turbulence as white process
noise, which it is not: the Dryden gusts are coloured, and in moderate
turbulence the normalised residuals average 190 / 19 / 1220 instead of 1.
This filter carries the shaping filter's states ``g`` (``core/shared/dryden.py``)
after the fault parameters, ``X = [x (9), b (5), g (ng)]``:

    x_{k+1} = A x_k + B u_k + Phi(u_k) b_k + G g_k + w_k      G  = B_w C_d
    b_{k+1} = b_k + w^b_k                                      (eq. 3)
    g_{k+1} = A_d g_k + B_d eta_k                              Qg = B_d B_d^T
    z_{k+1} = C x_{k+1} + D_g g_{k+1} + v_k                    D_g = D_w C_d

with ``B_w``, ``D_w`` the wind Jacobians the truth plant uses
(``ftc_mc/model/wind.py``) and the Dryden model at a *design* turbulence level.
A sensor-aware design appends output biases ``s`` to ``g``: columns
of ``G`` and ``C_d`` zero, ``A_d`` the identity on them, ``Q_g`` their random
walk, ``D_g`` (and ``D_z``) a unit entry on the biased output; a reset of a
Table 1 block also resets the biases ``FilterModel.reset_g`` names.
The steps are those of the paper's filter (eqs. 5-11, Table 1, section 3.2.2,
eqs. 6-8): predict, residuals on the three outputs, reset of a block of
``P_{k|k}`` and a re-prediction, sequential scalar updates with the 12 outputs
in order, projection of the fault parameters.  The matrices are dense here
(``C`` rows gain gust columns), so the loops are plain ``F P F^T`` and
``P c^T`` over every lane, lane index innermost; ``P`` is kept exactly
symmetric.

Plain-NumPy twin: ``tests/naive.py::gust_filter_step_ref``.
"""

from __future__ import annotations

import math

import numpy as np

from ...conventions import (N_AUG, N_B0, N_U, N_X, N_Z, OUT_ALPHA, OUT_NX, OUT_NZ, OUT_VA,
                             RESIDUAL_OUTPUTS)
from ...conventions import N_FAULT as N_F
from .batch import UPDATE_ROWS, project_lanes, reset_lanes
from ..jit import kernel
from .nonlinear import (D_CA, D_COS, D_ME, D_MQ, D_MU, D_MW, D_SA, D_SIN, D_VA, D_XE,
                        D_XQ, D_XT, D_XU, D_XW, D_ZE, D_ZQ, D_ZU, D_ZW, N_DIRECT,
                        N_PARTIAL, OUT_CAS, OUT_GAMMA, P_G, P_GAMMA0, P_TAUE, P_TAUT, P_V0,
                        derivatives_partials_nb, outputs_nb, propagate)
from ..shared.paths import EXTENDED_FILTER, on_path

N_WIND = 3
"""Gust outputs ``u_g, w_g, q_g`` of the gust states (``FilterModel.Cg``)."""


@kernel(internal=True)
def _c_row(fm, r, crow):
    """Row ``r`` of ``C_aug = [C, 0, D_g]`` into ``crow`` (n,)."""
    n = crow.shape[0]
    for j in range(n):
        crow[j] = 0.0
    for j in range(N_X):
        crow[j] = fm.C[r, j]
    for g in range(n - N_AUG):
        crow[N_AUG + g] = fm.Dg[r, g]


@kernel(internal=True)
def _lane_point(xa, u, fm, l, xabs, cmd, wind):
    """Lane ``l``'s operating point for the airframe's equations: the absolute
    state ``x0 + x``, the absolute commands under the estimated faults (eq. 2
    with ``b_hat``: ``u0 + u + [b0_T, b0_e / 2, b0_e / 2] - b1 (u + u0)``, the
    terms ``B_b0 b0`` and ``Phi(u) b1`` of eq. 4) and the estimated gust
    ``C_d g``; ``u`` may be ``None`` for the state and wind only."""
    ng = xa.shape[0] - N_AUG
    for i in range(N_X):
        xabs[i] = fm.x0[i] + xa[i, l]
    if u is not None:
        b0t = xa[N_X, l]
        b0e = 0.5 * xa[N_X + 1, l]
        for j in range(N_U):
            bias = b0t if j == 0 else b0e
            cmd[j] = fm.u0[j] + u[j, l] + bias - xa[N_X + N_B0 + j, l] * (u[j, l] + fm.u0[j])
    for i in range(N_WIND):
        acc = 0.0
        for g in range(ng):
            acc += fm.Cg[i, g] * xa[N_AUG + g, l]
        wind[i] = acc


@kernel(internal=True)
def _c_rows_lanes(fm, st, r, cl):
    """Row ``r`` of every lane's re-linearised ``C_aug = [JC, 0, JHW C_d + D_z]``
    into ``cl`` (n, L)."""
    n = cl.shape[0]
    L = cl.shape[1]
    for j in range(N_X):
        for l in range(L):
            cl[j, l] = st.JC[r, j, l]
    for j in range(N_X, N_AUG):
        for l in range(L):
            cl[j, l] = 0.0
    for g in range(n - N_AUG):
        for l in range(L):
            acc = 0.0
            for w in range(N_WIND):
                acc += st.JHW[r, w, l] * fm.Cg[w, g]
            cl[N_AUG + g, l] = acc + fm.Dz[r, g]


TAN_STATES = (0, 1, 2, 5, 6, 7, 8)
"""The states the airframe's equations depend on (all but the positions ``x``,
``z``): the first columns of the tangent of :func:`relinearise_lanes`."""
N_TANGENT = len(TAN_STATES) + N_U + N_WIND
"""Columns of that tangent: the states of :data:`TAN_STATES`, the three
effects, the three wind components."""


@kernel(inline="always")
def _tangent_stage(S, St, Ks, K, D, xt, p, s, a):
    """One RK4 stage of the tangent of every lane: the slope ``K = J_f(xt) St +
    J_e e_c + J_w w_c`` of each column ``c`` (``e_c``, ``w_c``: the column's unit
    effect or wind, else zero), from the partials ``D`` (N_PARTIAL, L) of
    :func:`ftc_mc.core.longitudinal.nonlinear.derivatives_partials_nb` at the stage
    points ``xt`` (9, L); sets (stage ``s`` 0) or adds to ``Ks`` ``K`` (stages
    0, 3) or ``2 K`` and sets the next stage's tangent ``St = S + a K``.
    ``K`` (9, L) is work.  One loop per row, each writing one array: loops
    with several stores did not vectorise (lesson 2)."""
    L = xt.shape[1]
    g = p[P_G]
    itt = 1.0 / p[P_TAUT]
    ite = 1.0 / p[P_TAUE]
    ns = len(TAN_STATES)
    for c in range(N_TANGENT):
        e0 = 1.0 if c == ns else 0.0
        e1 = 1.0 if c == ns + 1 else 0.0
        e2 = 1.0 if c == ns + 2 else 0.0
        w0 = 1.0 if c == ns + N_U else 0.0
        w1 = 1.0 if c == ns + N_U + 1 else 0.0
        w2 = 1.0 if c == ns + N_U + 2 else 0.0
        for l in range(L):
            K[0, l] = (D[D_XU, l] * (St[0, c, l] - w0) + D[D_XW, l] * (St[1, c, l] - w1)
                       + D[D_XQ, l] * (St[2, c, l] - w2)
                       + D[D_XE, l] * (0.5 * (St[7, c, l] + St[8, c, l]))
                       + D[D_XT, l] * St[6, c, l] - xt[2, l] * St[1, c, l]
                       - xt[1, l] * St[2, c, l] - g * D[D_COS, l] * St[5, c, l])
        for l in range(L):
            K[1, l] = (D[D_ZU, l] * (St[0, c, l] - w0) + D[D_ZW, l] * (St[1, c, l] - w1)
                       + D[D_ZQ, l] * (St[2, c, l] - w2)
                       + D[D_ZE, l] * (0.5 * (St[7, c, l] + St[8, c, l]))
                       + xt[2, l] * St[0, c, l] + xt[0, l] * St[2, c, l]
                       - g * D[D_SIN, l] * St[5, c, l])
        for l in range(L):
            K[2, l] = (D[D_MU, l] * (St[0, c, l] - w0) + D[D_MW, l] * (St[1, c, l] - w1)
                       + D[D_MQ, l] * (St[2, c, l] - w2)
                       + D[D_ME, l] * (0.5 * (St[7, c, l] + St[8, c, l])))
        for l in range(L):
            K[3, l] = (D[D_COS, l] * St[0, c, l] + D[D_SIN, l] * St[1, c, l]
                       + (xt[1, l] * D[D_COS, l] - xt[0, l] * D[D_SIN, l]) * St[5, c, l])
        for l in range(L):
            K[4, l] = (-D[D_SIN, l] * St[0, c, l] + D[D_COS, l] * St[1, c, l]
                       - (xt[0, l] * D[D_COS, l] + xt[1, l] * D[D_SIN, l]) * St[5, c, l])
        for l in range(L):
            K[5, l] = St[2, c, l]
        for l in range(L):
            K[6, l] = (e0 - St[6, c, l]) * itt
        for l in range(L):
            K[7, l] = (e1 - St[7, c, l]) * ite
        for l in range(L):
            K[8, l] = (e2 - St[8, c, l]) * ite
        for i in range(N_X):
            if s == 0:
                for l in range(L):
                    Ks[i, c, l] = K[i, l]
            elif s < 3:
                for l in range(L):
                    Ks[i, c, l] += 2.0 * K[i, l]
            else:
                for l in range(L):
                    Ks[i, c, l] += K[i, l]
            if s < 3:
                for l in range(L):
                    St[i, c, l] = S[i, c, l] + a * K[i, l]


@kernel(internal=True)
def relinearise_lanes(xa, u, fm, st, tw):
    """Every lane's state-map Jacobians about its estimate ``X_{k|k}``, exact:
    the derivative of the one-period RK4 map, carried through its stages.

    The one-period map ``x_{k+1} = f(x0 + x, u0 + e, w)`` (:func:`_nl_state`: RK4
    over ``fm.dt`` with ``fm.n_sub`` steps, effect ``e`` of eq. 2 under the
    estimated faults, wind ``w = C_d g`` held), differentiated at the lane's
    estimate in forward mode: each RK4 stage's slope ``k = f(xt)`` gets the
    tangent ``J_f(xt) St`` (plus the effect's or the wind's own column), with
    the airframe's partials written out analytically
    (:func:`ftc_mc.core.longitudinal.nonlinear.derivatives_partials_nb`), and the
    tangents combine as the slopes do.  The positions enter no equation, so
    their columns of ``JA`` are unit columns.  The nominal RK4 here does
    :func:`_nl_state`'s arithmetic.  Writes ``st.JA`` (9, 9, L), ``JB`` (9, 3,
    L), ``JW`` (9, 3, L); work ``tw.jx``, ``jd``, ``jcw``, ``jt`` and the one-lane
    buffers of ``tw``.  The outputs' Jacobians are taken about the prediction
    (:func:`relinearise_outputs_lanes`).

    Against the forward differences it replaced (steps ``1e-6 max(1, |x|)``,
    16 RK4 periods per lane), it agrees to their own error, about 1e-6
    relative (``tests/test_design_kernels.py``), in the cost of one period's
    slopes and partials and the tangent's vector arithmetic.
    """
    L = xa.shape[1]
    x = tw.jx[0]
    xt = tw.jx[1]
    ks = tw.jx[2]
    kk = tw.jx[3]
    S = tw.jt[0]
    St = tw.jt[1]
    Ks = tw.jt[2]
    D = tw.jd
    cw = tw.jcw
    xabs = tw.xabs
    cmd = tw.cmd
    wl = tw.wl
    dxl = tw.rk4[0]
    dl = tw.jl
    for l in range(L):
        _lane_point(xa, u, fm, l, xabs, cmd, wl)
        for i in range(N_X):
            x[i, l] = xabs[i]
        for j in range(N_U):
            cw[j, l] = cmd[j]
        for j in range(N_WIND):
            cw[N_U + j, l] = wl[j]
    for i in range(N_X):
        for c in range(N_TANGENT):
            for l in range(L):
                S[i, c, l] = 0.0
    for c in range(len(TAN_STATES)):
        for l in range(L):
            S[TAN_STATES[c], c, l] = 1.0
    h = fm.dt / fm.n_sub
    h6 = h / 6.0
    vx0 = fm.p[P_V0] * math.cos(fm.p[P_GAMMA0])
    vz0 = fm.p[P_V0] * math.sin(fm.p[P_GAMMA0])
    for _ in range(fm.n_sub):
        for s in range(4):
            # the stage point, as nonlinear.rk4_step forms it
            for i in range(N_X):
                for l in range(L):
                    if s == 0:
                        xt[i, l] = x[i, l]
                    elif s < 3:
                        xt[i, l] = x[i, l] + 0.5 * h * kk[i, l]
                    else:
                        xt[i, l] = x[i, l] + h * kk[i, l]
            if s == 0:
                for i in range(N_X):
                    for c in range(N_TANGENT):
                        for l in range(L):
                            St[i, c, l] = S[i, c, l]
            # slopes and partials, a lane at a time
            for l in range(L):
                for i in range(N_X):
                    xabs[i] = xt[i, l]
                for j in range(N_U):
                    cmd[j] = cw[j, l]
                for j in range(N_WIND):
                    wl[j] = cw[N_U + j, l]
                derivatives_partials_nb(xabs, cmd, fm.p, wl, vx0, vz0, dxl, dl)
                for i in range(N_X):
                    kk[i, l] = dxl[i]
                for i in range(N_PARTIAL):
                    D[i, l] = dl[i]
            # the slopes' sum k1 + 2 k2 + 2 k3 + k4, in rk4_step's order
            for i in range(N_X):
                for l in range(L):
                    if s == 0:
                        ks[i, l] = kk[i, l]
                    elif s < 3:
                        ks[i, l] = ks[i, l] + 2.0 * kk[i, l]
                    else:
                        ks[i, l] = ks[i, l] + kk[i, l]
            _tangent_stage(S, St, Ks, tw.jx[4], D, xt, fm.p, s, 0.5 * h if s < 2 else h)
        for i in range(N_X):
            for l in range(L):
                x[i, l] += h6 * ks[i, l]
            for c in range(N_TANGENT):
                for l in range(L):
                    S[i, c, l] += h6 * Ks[i, c, l]
    ns = len(TAN_STATES)
    for i in range(N_X):
        for l in range(L):
            st.JA[i, 3, l] = 1.0 if i == 3 else 0.0
            st.JA[i, 4, l] = 1.0 if i == 4 else 0.0
        for c in range(ns):
            for l in range(L):
                st.JA[i, TAN_STATES[c], l] = S[i, c, l]
        for j in range(N_U):
            for l in range(L):
                st.JB[i, j, l] = S[i, ns + j, l]
        for j in range(N_WIND):
            for l in range(L):
                st.JW[i, j, l] = S[i, ns + N_U + j, l]


@kernel(internal=True)
def relinearise_outputs_lanes(xa, fm, st, tw):
    """Every lane's output Jacobians ``st.JC`` (12, 9, L) and ``st.JHW`` (12, 3,
    L) about its prediction ``X_{k+1|k}`` (``xa``: state and gust), where the
    update linearises the outputs, analytic from the airframe's partials
    (:func:`ftc_mc.core.longitudinal.nonlinear.derivatives_partials_nb`): the
    first six outputs are states; ``n_x = X / (m g)``, ``n_z = -Z / (m g)``,
    ``alpha`` (``d alpha = (cos alpha dW - sin alpha dU) / Va``), ``gamma =
    theta - alpha``, ``CAS = Va`` and ``Va`` (``d Va = cos alpha dU + sin
    alpha dW``) are air-relative, so their wind columns are minus their ``u``,
    ``w``, ``q`` columns.

    Taken about the estimate ``X_{k|k}`` instead, as before, they lagged the
    update by a step, and the re-linearised filter reset the thrust block 674
    times in 39.4 fault-free hours of moderate turbulence (38 about the
    prediction; ``docs/findings/turbulence-designs.md``)."""
    xs = tw.xabs
    w0 = tw.wl
    dxl = tw.rk4[0]
    dl = tw.jl
    D = tw.jd
    L = xa.shape[1]
    JC = st.JC
    vx0 = fm.p[P_V0] * math.cos(fm.p[P_GAMMA0])
    vz0 = fm.p[P_V0] * math.sin(fm.p[P_GAMMA0])
    ig = 1.0 / fm.p[P_G]
    for l in range(L):
        _lane_point(xa, None, fm, l, xs, tw.cmd, w0)
        derivatives_partials_nb(xs, tw.cmd, fm.p, w0, vx0, vz0, dxl, dl)
        for i in range(N_PARTIAL):
            D[i, l] = dl[i]
    for r in range(N_Z):
        for j in range(N_X):
            v = 1.0 if r == j and r < N_DIRECT else 0.0
            for l in range(L):
                JC[r, j, l] = v
    for l in range(L):
        JC[OUT_NX, 0, l] = D[D_XU, l] * ig
        JC[OUT_NX, 1, l] = D[D_XW, l] * ig
        JC[OUT_NX, 2, l] = D[D_XQ, l] * ig
        JC[OUT_NX, 6, l] = D[D_XT, l] * ig
        JC[OUT_NX, 7, l] = 0.5 * D[D_XE, l] * ig
        JC[OUT_NX, 8, l] = 0.5 * D[D_XE, l] * ig
        JC[OUT_NZ, 0, l] = -D[D_ZU, l] * ig
        JC[OUT_NZ, 1, l] = -D[D_ZW, l] * ig
        JC[OUT_NZ, 2, l] = -D[D_ZQ, l] * ig
        JC[OUT_NZ, 7, l] = -0.5 * D[D_ZE, l] * ig
        JC[OUT_NZ, 8, l] = -0.5 * D[D_ZE, l] * ig
        JC[OUT_ALPHA, 0, l] = -D[D_SA, l] / D[D_VA, l]
        JC[OUT_ALPHA, 1, l] = D[D_CA, l] / D[D_VA, l]
        JC[OUT_GAMMA, 0, l] = D[D_SA, l] / D[D_VA, l]
        JC[OUT_GAMMA, 1, l] = -D[D_CA, l] / D[D_VA, l]
        JC[OUT_GAMMA, 5, l] = 1.0
        JC[OUT_CAS, 0, l] = D[D_CA, l]
        JC[OUT_CAS, 1, l] = D[D_SA, l]
        JC[OUT_VA, 0, l] = D[D_CA, l]
        JC[OUT_VA, 1, l] = D[D_SA, l]
    for r in range(N_Z):
        for j in range(N_WIND):
            for l in range(L):
                st.JHW[r, j, l] = -JC[r, j, l] if r >= N_DIRECT else 0.0


@kernel(internal=True)
def _nl_state(xa, u, fm, xn, tw):
    """The extended filter's state prediction: ``x_{k+1|k} = f(x0 + x, u0 + e, C_d g) - x0``.

    ``f`` is the nonlinear airframe over one period (RK4, ``fm.n_sub`` steps,
    :func:`ftc_mc.core.longitudinal.nonlinear.propagate`), driven by the actuators' effect
    under the estimated faults (eq. 2 with the estimated ``b``:
    ``e = u + [b0_T, b0_e / 2, b0_e / 2] - b1 (u + u0)``, the terms ``B_b0 b0``
    and ``Phi(u) b1`` of eq. 4) and the estimated gust ``C_d g`` held over the
    period.  Writes ``xn[:9]`` (deviation from trim); one-lane buffers of ``tw``.
    """
    xabs = tw.xabs
    cmd = tw.cmd
    wl = tw.wl
    for l in range(xa.shape[1]):
        _lane_point(xa, u, fm, l, xabs, cmd, wl)
        propagate(xabs, cmd, fm.p, wl, fm.dt, fm.n_sub, tw.rk4)
        for i in range(N_X):
            xn[i, l] = xabs[i] - fm.x0[i]


@kernel(internal=True)
def _nl_outputs(xa, fm, hpred, xp, tw):
    """The extended filter's predicted outputs ``h(x0 + x, C_d g) - y0 + D_z g``
    (``D_z``: a sensor-aware design's output biases) into ``hpred[:12]`` and the prediction itself into ``xp`` (the update linearises
    about it: ``z_r - hpred_r - c_r (X - xp)``)."""
    n = xa.shape[0]
    xabs = tw.xabs
    wl = tw.wl
    y = tw.y
    for l in range(xa.shape[1]):
        for i in range(n):
            xp[i, l] = xa[i, l]
        _lane_point(xa, None, fm, l, xabs, tw.cmd, wl)
        outputs_nb(xabs, fm.p, wl, y)
        for r in range(N_Z):
            acc = y[r] - fm.y0[r]
            for g in range(n - N_AUG):
                acc += fm.Dz[r, g] * xa[N_AUG + g, l]
            hpred[r, l] = acc


# ------------------------------------------------------------------ path dispatch
NOT_FRESH = np.bool_(False)
"""``_gpredict``'s ``fresh`` on a re-prediction after a reset.  A NumPy bool,
not the literal ``False``: Numba types a literal as a signature of its own, and
the prediction was compiled twice (4 s of the 6-DOF extended
monitor's path)."""


# The airframe's equations run only on the extended filter's path
# (core/shared/paths.py): the general filter's kernels take the filter's marker
# (``fkind``), and on the dense filter's these calls compile to nothing.

@on_path("filter", {EXTENDED_FILTER: relinearise_outputs_lanes})
def relinearise_outputs(fkind, xa, fm, st, tw):
    """:func:`relinearise_outputs_lanes` on the extended filter's path."""


@on_path("filter", {EXTENDED_FILTER: _nl_state})
def nl_state(fkind, xa, u, fm, xn, tw):
    """:func:`_nl_state` on the extended filter's path."""


@on_path("filter", {EXTENDED_FILTER: _nl_outputs})
def nl_outputs(fkind, xa, fm, hpred, xp, tw):
    """:func:`_nl_outputs` on the extended filter's path."""


@on_path("filter", {EXTENDED_FILTER: relinearise_lanes})
def relinearise(fkind, xa, u, fm, st, tw):
    """:func:`relinearise_lanes` on the extended filter's path."""


@kernel(internal=True)
def _gpredict(fkind, xa, P, Pn, u, fm, phi, T, xn, tw, st, fresh):
    """Time update of every lane: ``X <- F X + B_aug u``, ``Pn <- F P F^T + Q``.

    ``F = [[A, Phi(u), G], [0, I, 0], [0, 0, A_d]]`` and ``Q`` block-diagonal
    (``q_diag`` on ``x`` and ``b``, ``Qg`` on ``g``).  ``P`` is read whole
    (symmetric), ``Pn`` written whole (exactly symmetric; may not be ``P``).
    ``phi`` (9, 5, L) holds ``Phi(u)`` on return; ``T`` (n, n, L) and ``xn``
    (n, L) are work arrays.  With ``fm.nl`` the plant states are predicted by
    the nonlinear airframe (:func:`_nl_state`); the covariance keeps the
    Jacobians at trim (``A``, ``Phi``, ``G``), or with ``fm.relin > 0`` takes
    each lane's (``st.JA``; ``Phi`` from ``st.JB``:
    ``[JB_0, (JB_1 + JB_2) / 2, -JB diag(u + u0)]``; ``G = st.JW C_d`` into
    ``tw.jg``).  With ``fresh`` the state map was just re-linearised about this
    ``X`` and ``u`` (:func:`relinearise_lanes`), whose RK4 left the nonlinear
    prediction in ``tw.jx[0]``, the same to the bit: it is taken from there.
    """
    n = xa.shape[0]
    L = xa.shape[1]
    ng = n - N_AUG
    relin = fm.relin > 0
    if relin:
        JB = st.JB
        jg = tw.jg
        for i in range(N_X):
            for l in range(L):
                phi[i, 0, l] = JB[i, 0, l]
                phi[i, 1, l] = 0.5 * (JB[i, 1, l] + JB[i, 2, l])
                for j in range(N_U):
                    phi[i, N_B0 + j, l] = -JB[i, j, l] * (u[j, l] + fm.u0[j])
            for g in range(ng):
                for l in range(L):
                    acc = 0.0
                    for w in range(N_WIND):
                        acc += st.JW[i, w, l] * fm.Cg[w, g]
                    jg[i, g, l] = acc
    else:
        for i in range(N_X):
            for l in range(L):
                phi[i, 0, l] = fm.Bb0[i, 0]
                phi[i, 1, l] = fm.Bb0[i, 1]
                for j in range(N_U):
                    phi[i, N_B0 + j, l] = -fm.B[i, j] * (u[j, l] + fm.u0[j])
    # state
    for i in range(N_X):
        for l in range(L):
            acc = 0.0
            for j in range(N_X):
                acc += fm.A[i, j] * xa[j, l]
            for j in range(N_U):
                acc += fm.B[i, j] * u[j, l]
            for j in range(N_F):
                acc += phi[i, j, l] * xa[N_X + j, l]
            for g in range(ng):
                acc += fm.G[i, g] * xa[N_AUG + g, l]
            xn[i, l] = acc
    for a in range(ng):
        for l in range(L):
            acc = 0.0
            for g in range(ng):
                acc += fm.Ad[a, g] * xa[N_AUG + g, l]
            xn[N_AUG + a, l] = acc
    if fm.nl != 0 and fresh:
        for i in range(N_X):
            for l in range(L):
                xn[i, l] = tw.jx[0, i, l] - fm.x0[i]
    elif fm.nl != 0:
        nl_state(fkind, xa, u, fm, xn, tw)
    for i in range(N_X):
        for l in range(L):
            xa[i, l] = xn[i, l]
    for a in range(ng):
        for l in range(L):
            xa[N_AUG + a, l] = xn[N_AUG + a, l]
    # T = F P
    if relin:
        # lane loops innermost, sums in the per-lane order (the same bits)
        JA = st.JA
        jg = tw.jg
        for i in range(N_X):
            for c in range(n):
                for l in range(L):
                    T[i, c, l] = 0.0
                for j in range(N_X):
                    for l in range(L):
                        T[i, c, l] += JA[i, j, l] * P[j, c, l]
                for j in range(N_F):
                    for l in range(L):
                        T[i, c, l] += phi[i, j, l] * P[N_X + j, c, l]
                for g in range(ng):
                    for l in range(L):
                        T[i, c, l] += jg[i, g, l] * P[N_AUG + g, c, l]
    else:
        for i in range(N_X):
            for c in range(n):
                for l in range(L):
                    acc = 0.0
                    for j in range(N_X):
                        acc += fm.A[i, j] * P[j, c, l]
                    for j in range(N_F):
                        acc += phi[i, j, l] * P[N_X + j, c, l]
                    for g in range(ng):
                        acc += fm.G[i, g] * P[N_AUG + g, c, l]
                    T[i, c, l] = acc
    for i in range(N_X, N_AUG):
        for c in range(n):
            for l in range(L):
                T[i, c, l] = P[i, c, l]
    for a in range(ng):
        for c in range(n):
            for l in range(L):
                acc = 0.0
                for g in range(ng):
                    acc += fm.Ad[a, g] * P[N_AUG + g, c, l]
                T[N_AUG + a, c, l] = acc
    # Pn = T F^T (upper triangle), + Q, mirrored
    for i in range(n):
        for k in range(i, n):
            if k < N_X and relin:
                for l in range(L):
                    Pn[i, k, l] = 0.0
                for j in range(N_X):
                    for l in range(L):
                        Pn[i, k, l] += T[i, j, l] * st.JA[k, j, l]
                for j in range(N_F):
                    for l in range(L):
                        Pn[i, k, l] += T[i, N_X + j, l] * phi[k, j, l]
                for g in range(ng):
                    for l in range(L):
                        Pn[i, k, l] += T[i, N_AUG + g, l] * tw.jg[k, g, l]
            elif k < N_X:
                for l in range(L):
                    acc = 0.0
                    for j in range(N_X):
                        acc += T[i, j, l] * fm.A[k, j]
                    for j in range(N_F):
                        acc += T[i, N_X + j, l] * phi[k, j, l]
                    for g in range(ng):
                        acc += T[i, N_AUG + g, l] * fm.G[k, g]
                    Pn[i, k, l] = acc
            elif k < N_AUG:
                for l in range(L):
                    Pn[i, k, l] = T[i, k, l]
            else:
                for l in range(L):
                    acc = 0.0
                    for g in range(ng):
                        acc += T[i, N_AUG + g, l] * fm.Ad[k - N_AUG, g]
                    Pn[i, k, l] = acc
    for i in range(N_AUG):
        qi = fm.q_diag[i]
        for l in range(L):
            Pn[i, i, l] += qi
    for a in range(ng):
        for b in range(a, ng):
            qab = fm.Qg[a, b]
            for l in range(L):
                Pn[N_AUG + a, N_AUG + b, l] += qab
    for i in range(n):
        for k in range(i + 1, n):
            for l in range(L):
                Pn[k, i, l] = Pn[i, k, l]


@kernel(inline="always")
def gust_residuals_lanes(xa, P, z, fm, crow, hpred, res, innov, st, cl):
    """Normalised residuals ``r_q, r_nx, r_nz`` (eqs. 9-11) with the gust columns
    of ``C_aug``: ``r_i = mu_i^2 / (c_i P c_i^T + R_ii)``, ``mu_i = z_i - c_i X``.

    ``P`` is the full symmetric prediction; ``crow`` (n,) is work; with
    ``fm.nl`` the predicted output is ``hpred`` (12, L) instead of ``c_i X``;
    ``res`` and ``innov`` (3, L) are written with ``r_i`` and
    ``mu_i / sqrt(S_ii)``.  With ``fm.relin > 0`` the rows are each lane's
    (:func:`_c_rows_lanes` of ``st`` into ``cl`` (n, L)).
    """
    n = xa.shape[0]
    L = xa.shape[1]
    if fm.relin > 0:
        # lane loops innermost (sums in the per-lane order: the same bits);
        # ``res[o]`` accumulates ``c P c^T``, ``innov[o]`` each ``(P c^T)_j``
        for o in range(len(RESIDUAL_OUTPUTS)):
            r = RESIDUAL_OUTPUTS[o]
            _c_rows_lanes(fm, st, r, cl)
            rr = fm.r_diag[r]
            for l in range(L):
                res[o, l] = 0.0
            for j in range(n):
                for l in range(L):
                    innov[o, l] = 0.0
                for k in range(n):
                    for l in range(L):
                        innov[o, l] += P[j, k, l] * cl[k, l]
                for l in range(L):
                    res[o, l] += cl[j, l] * innov[o, l]
            for l in range(L):
                mu = z[r, l] - hpred[r, l]
                s = res[o, l] + rr
                res[o, l] = mu * mu / s
                innov[o, l] = mu / np.sqrt(s)
        return
    for o in range(len(RESIDUAL_OUTPUTS)):
        r = RESIDUAL_OUTPUTS[o]
        _c_row(fm, r, crow)
        rr = fm.r_diag[r]
        for l in range(L):
            pred = 0.0
            s = 0.0
            for j in range(n):
                pred += crow[j] * xa[j, l]
                acc = 0.0
                for k in range(n):
                    acc += P[j, k, l] * crow[k]
                s += crow[j] * acc
            if fm.nl != 0:
                pred = hpred[r, l]
            mu = z[r, l] - pred
            s = s + rr
            res[o, l] = mu * mu / s
            innov[o, l] = mu / np.sqrt(s)


@kernel(inline="always")
def _apply_gain(xa, P, h, v, gs):
    """One scalar update of every lane from ``h = P c^T`` and ``gs = [(z - pred) / s,
    1 / s]``: ``X += h gs_0``, ``v = h gs_1``, ``P -= v h^T`` on the upper triangle."""
    n = xa.shape[0]
    L = xa.shape[1]
    for a in range(n):
        for l in range(L):
            xa[a, l] += h[a, l] * gs[0, l]
            v[a, l] = h[a, l] * gs[1, l]
    for a in range(n):
        for b in range(a, n):
            for l in range(L):
                P[a, b, l] -= v[a, l] * h[b, l]


@kernel(internal=True)
def _gupdate(xa, P, z, fm, crow, h, v, gs, hpred, xp, st, cl):
    """Sequential scalar updates with the 12 outputs in order, on the upper
    triangle of ``P`` (mirrored by the caller): ``h = P c^T``, ``s = c h + R``,
    ``X += h (z - c X) / s``, ``P -= (h / s) h^T``; with ``fm.nl`` the
    predicted output is ``hpred_r + c (X - xp)`` (linearised about the
    prediction ``xp``); with ``fm.relin > 0`` each lane's rows (``cl``, as in
    :func:`gust_residuals_lanes`)."""
    n = xa.shape[0]
    L = xa.shape[1]
    if fm.relin > 0:
        # lane loops innermost, each sum in the order of the per-lane loops it
        # replaced (so the same bits): a sum over j inside the lane loop did
        # not vectorise (lesson 2)
        for r in range(z.shape[0]):
            _c_rows_lanes(fm, st, r, cl)
            rr = fm.r_diag[r]
            for a in range(n):
                for l in range(L):
                    h[a, l] = 0.0
                for j in range(n):
                    if j < a:
                        for l in range(L):
                            h[a, l] += P[j, a, l] * cl[j, l]
                    else:
                        for l in range(L):
                            h[a, l] += P[a, j, l] * cl[j, l]
            for l in range(L):
                gs[0, l] = hpred[r, l]
                gs[1, l] = rr
            for j in range(n):
                for l in range(L):
                    gs[0, l] += cl[j, l] * (xa[j, l] - xp[j, l])
                    gs[1, l] += cl[j, l] * h[j, l]
            for l in range(L):
                sv = gs[1, l]
                gs[0, l] = (z[r, l] - gs[0, l]) / sv
                gs[1, l] = 1.0 / sv
            _apply_gain(xa, P, h, v, gs)
        return
    for r in range(z.shape[0]):
        _c_row(fm, r, crow)
        rr = fm.r_diag[r]
        for a in range(n):
            for l in range(L):
                acc = 0.0
                for j in range(n):
                    cj = crow[j]
                    if j < a:
                        acc += P[j, a, l] * cj
                    else:
                        acc += P[a, j, l] * cj
                h[a, l] = acc
        for l in range(L):
            pred = 0.0
            sv = rr
            if fm.nl != 0:
                pred = hpred[r, l]
                for j in range(n):
                    pred += crow[j] * (xa[j, l] - xp[j, l])
                    sv += crow[j] * h[j, l]
            else:
                for j in range(n):
                    pred += crow[j] * xa[j, l]
                    sv += crow[j] * h[j, l]
            gs[0, l] = (z[r, l] - pred) / sv
            gs[1, l] = 1.0 / sv
        _apply_gain(xa, P, h, v, gs)


@kernel(inline="always")
def gust_predict_lanes(fkind, xa, P, fm, tw, st, k):
    """First half of a general filter step: predict into ``tw.fwork[:n]`` and the
    residuals; ``X_{k|k}`` is kept in ``tw.fwork`` for a re-prediction.

    Parameters
    ----------
    fkind : DenseFilter or ExtendedFilter
        The filter's marker (``core/shared/paths.py``): the airframe's
        equations predict on the extended filter's path only.
    xa : ndarray, shape (n, L)
        ``X_{k|k}``, replaced by ``X_{k+1|k}``.
    P : ndarray, shape (n, n, L)
        ``P_{k|k}`` (left unchanged).
    fm : FilterModel
        With the gust fields ``G``, ``Ad``, ``Dg``, ``Qg`` (``ng = n - 14``,
        possibly 0) and ``nl`` (nonlinear prediction).
    tw : TrialWork
        Reads ``u`` (commands of the step) and ``z`` (measurements ``z_{k+1}``);
        writes ``res``, ``innov`` (3, L); work ``phi``, ``T`` (n, n, L),
        ``fwork`` (rows ``n + 3`` .. ``n + 5``: prediction scratch, predicted
        outputs, the prediction; row ``n + 13``: ``X_{k|k}``), ``crow``, ``jg``,
        ``jc`` and the one-lane buffers of the nonlinear airframe.
    st : LaneState
        The lanes' Jacobians ``JA`` .. ``JHW`` (read with ``fm.relin > 0``;
        when ``k`` is a multiple of it, the state map's are re-computed about
        ``X_{k|k}`` first, :func:`relinearise_lanes`, and the outputs' about
        ``X_{k+1|k}`` after the prediction, :func:`relinearise_outputs_lanes`).
    k : int
        Step.
    """
    n = xa.shape[0]
    work = tw.fwork
    x_prev = work[n + UPDATE_ROWS]
    for i in range(n):
        for l in range(xa.shape[1]):
            x_prev[i, l] = xa[i, l]
    fresh = fm.relin > 0 and k % fm.relin == 0
    if fresh:
        relinearise(fkind, xa, tw.u, fm, st, tw)
    _gpredict(fkind, xa, P, work[0:n], tw.u, fm, tw.phi, tw.T, work[n + 3], tw, st, fresh)
    if fresh:
        relinearise_outputs(fkind, xa, fm, st, tw)
    if fm.nl != 0:
        nl_outputs(fkind, xa, fm, work[n + 4], work[n + 5], tw)
    gust_residuals_lanes(xa, work[0:n], tw.z, fm, tw.crow, work[n + 4], tw.res, tw.innov,
                         st, tw.jc)


@kernel(internal=True)
def reset_extra_lanes(P, block, reset_g):
    """Reset the extra states that go with each lane's block.

    A sensor-aware design opens the hypothesis of an output bias beside the
    actuator block whose residuals it shares: for each extra state ``g`` with
    ``reset_g[block, g] > 0`` the rows and columns of ``N_AUG + g`` are zeroed
    and its variance set to ``reset_g[block, g]``, as section 3.2.2 does for the
    fault parameters (:func:`ftc_mc.core.longitudinal.batch.reset_lanes`).

    Parameters
    ----------
    P : ndarray, shape (n, n, L)
        Covariances, updated in place.
    block : ndarray of int64, shape (L,)
        Table 1's block per lane (0: none).
    reset_g : ndarray, shape (3, n - 14)
        Variance after a reset, row = block.
    """
    n = P.shape[0]
    for l in range(P.shape[2]):
        b = block[l]
        if b <= 0 or b >= reset_g.shape[0]:
            continue
        for g in range(reset_g.shape[1]):
            v = reset_g[b, g]
            if v > 0.0:
                i = N_AUG + g
                for k in range(n):
                    P[i, k, l] = 0.0
                    P[k, i, l] = 0.0
                P[i, i, l] = v


@kernel(inline="always")
def gust_correct_lanes(fkind, xa, P, fm, det, tw, st):
    """Second half, once ``tw.block`` is decided: reset the block of ``P_{k|k}``
    (section 3.2.2, with the extra states that go with it,
    :func:`reset_extra_lanes`) of every lane that resets and predict all lanes again from
    ``X_{k|k}`` (identical for the others), update, projection (eqs. 6-8).
    Parameters as :func:`gust_predict_lanes` (the Jacobians of ``st`` as they
    left it); ``P`` gets ``P_{k+1|k+1}``."""
    n = xa.shape[0]
    L = xa.shape[1]
    work = tw.fwork
    Pn = work[0:n]
    x_prev = work[n + UPDATE_ROWS]
    block = tw.block
    n_reset = 0
    for l in range(L):
        if block[l] != 0:
            n_reset += 1
    if n_reset > 0:
        reset_lanes(P, block, det.reset_var)
        reset_extra_lanes(P, block, fm.reset_g)
        for i in range(n):
            for l in range(L):
                xa[i, l] = x_prev[i, l]
        _gpredict(fkind, xa, P, Pn, tw.u, fm, tw.phi, tw.T, work[n + 3], tw, st, NOT_FRESH)
        if fm.nl != 0:
            nl_outputs(fkind, xa, fm, work[n + 4], work[n + 5], tw)
    _gupdate(xa, Pn, tw.z, fm, tw.crow, work[n], work[n + 1], work[n + 2], work[n + 4],
             work[n + 5], st, tw.jc)
    for i in range(n):
        for k in range(i, n):
            for l in range(L):
                P[i, k, l] = Pn[i, k, l]
                P[k, i, l] = Pn[i, k, l]
    project_lanes(xa, fm)
