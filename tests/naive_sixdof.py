"""Plain-NumPy twins of the 6-DOF kernels (:mod:`ftc_mc.core.sixdof.plant`).

Written in the matrix form of the authors' simulator (krisgry/x8 ``dynamics.m``
and ``forces.m``), not by transcribing the kernels' scalar code: Fossen's
rigid-body mass matrix ``M_rb`` and Coriolis matrix ``C_rb`` (his eq. 3.56,
``r_cg = 0``) solved with ``np.linalg.solve``, the rotation matrices ``Rzyx`` and
the Euler-rate matrix ``T`` as the authors' ``Rzyx.m`` and
``TransformationMatrix.m``, the aerodynamic forces rotated by
``Rzyx(0, alpha, beta)^T``.  States, commands, outputs and parameters are
unpacked by their names in :data:`ftc_mc.core.sixdof.layout.LAYOUT`.
"""

from __future__ import annotations

import numpy as np

from ftc_mc.core.sixdof.layout import LAYOUT
from ftc_mc.core.sixdof.monitor import EXTENDED


def _named(values, names):
    return dict(zip(names, np.asarray(values, dtype=float)))


def rzyx(phi, theta, psi):
    """Body -> NED rotation, zyx Euler angles (the authors' ``Rzyx.m``)."""
    cphi, sphi = np.cos(phi), np.sin(phi)
    cth, sth = np.cos(theta), np.sin(theta)
    cpsi, spsi = np.cos(psi), np.sin(psi)
    return np.array([
        [cpsi * cth, -spsi * cphi + cpsi * sth * sphi, spsi * sphi + cpsi * cphi * sth],
        [spsi * cth, cpsi * cphi + sphi * sth * spsi, -cpsi * sphi + sth * spsi * cphi],
        [-sth, cth * sphi, cth * cphi]])


def euler_rates_matrix(phi, theta):
    """``T(Theta)`` of ``TransformationMatrix.m``: Euler rates = T (p, q, r)."""
    return np.array([
        [1.0, np.sin(phi) * np.tan(theta), np.cos(phi) * np.tan(theta)],
        [0.0, np.cos(phi), -np.sin(phi)],
        [0.0, np.sin(phi) / np.cos(theta), np.cos(phi) / np.cos(theta)]])


def smtrx(v):
    """Skew-symmetric matrix: ``smtrx(a) @ b = a x b`` (``Smtrx.m``)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def inertia(a):
    """``I_cg`` of ``simX8.m``."""
    return np.array([[a["Jx"], 0.0, -a["Jxz"]], [0.0, a["Jy"], 0.0],
                     [-a["Jxz"], 0.0, a["Jz"]]])


def forces_ref(x, p, wind):
    """Body forces (aerodynamic + thrust, no gravity), moments, alpha, beta, Va.

    ``forces.m`` with the wind rates subtracted (``ftc_mc.core.sixdof.plant``).
    """
    s = _named(x, LAYOUT.states)
    a = _named(p, LAYOUT.params)
    wd = _named(wind, LAYOUT.wind)
    vel_r = np.array([s["u"] - wd["u_g"], s["v"] - wd["v_g"], s["w"] - wd["w_g"]])
    pr, qr, rr = s["p"] - wd["p_g"], s["q"] - wd["q_g"], s["r"] - wd["r_g"]
    Va = np.linalg.norm(vel_r)
    alpha = np.arctan2(vel_r[2], vel_r[0])
    beta = np.arcsin(vel_r[1] / Va)
    elevator = (s["left"] + s["right"]) / 2
    aileron = (s["left"] - s["right"]) / 2
    qbar = 0.5 * a["rho"] * Va ** 2
    S, b, c = a["S"], a["b"], a["c"]
    lift = qbar * S * (a["CL0"] + a["CLa"] * alpha + a["CLq"] * c / (2 * Va) * qr
                       + a["CLde"] * elevator)
    drag = qbar * S * (a["CD0"] + a["CDa"] * alpha + a["CDa2"] * alpha ** 2
                       + a["C_D_beta1"] * beta + a["C_D_beta2"] * beta ** 2
                       + a["CDde2"] * elevator ** 2)
    pitch = qbar * S * c * (a["Cm0"] + a["Cma"] * alpha + a["Cmq"] * c / (2 * Va) * qr
                            + a["Cmde"] * elevator)

    def lateral(k):
        return (a[f"C_{k}_0"] + a[f"C_{k}_beta"] * beta
                + a[f"C_{k}_p"] * b / (2 * Va) * pr + a[f"C_{k}_r"] * b / (2 * Va) * rr
                + a[f"C_{k}_delta_a"] * aileron)

    side = qbar * S * lateral("Y")
    roll = qbar * S * b * lateral("l")
    yaw = qbar * S * b * lateral("n")
    F_aero = rzyx(0.0, alpha, beta).T @ np.array([-drag, side, -lift])
    Vd = Va + s["throttle"] * (a["k_motor"] - Va)
    F_prop = np.array([0.5 * a["rho"] * a["S_prop"] * a["C_prop"] * Vd * (Vd - Va), 0, 0])
    T_prop = np.array([-a["k_T_P"] * (a["k_Omega"] * s["throttle"]) ** 2, 0.0, 0.0])
    return F_aero + F_prop, np.array([roll, pitch, yaw]) + T_prop, alpha, beta, Va


def derivatives_ref(x, cmd, p, wind):
    """``dx/dt`` (15): ``dynamics.m`` (``M_rb nu' = tau - C_rb nu``) plus the
    reference point's velocity and three first-order actuators."""
    s = _named(x, LAYOUT.states)
    a = _named(p, LAYOUT.params)
    u = _named(cmd, LAYOUT.commands)
    F, M, _, _, _ = forces_ref(x, p, wind)
    Theta = np.array([s["phi"], s["theta"], s["psi"]])
    vel = np.array([s["u"], s["v"], s["w"]])
    Omega = np.array([s["p"], s["q"], s["r"]])
    R = rzyx(*Theta)
    gravity = R.T @ np.array([0.0, 0.0, a["mass"] * a["g"]])
    I = inertia(a)
    # Fossen's 6 x 6 block matrices, filled block by block (np.block is a
    # tenth of the extended filter's twin test's time)
    M_rb = np.zeros((6, 6))
    M_rb[:3, :3] = a["mass"] * np.eye(3)
    M_rb[3:, 3:] = I
    C_rb = np.zeros((6, 6))
    C_rb[:3, 3:] = C_rb[3:, :3] = -a["mass"] * smtrx(vel)
    C_rb[3:, 3:] = -smtrx(I @ Omega)
    tau = np.concatenate([F + gravity, M])
    nu_dot = np.linalg.solve(M_rb, tau - C_rb @ np.concatenate([vel, Omega]))
    ref = a["V0"] * np.array([np.cos(a["gamma0"]), 0.0, -np.sin(a["gamma0"])])
    pos_dot = R @ vel - ref
    Theta_dot = euler_rates_matrix(s["phi"], s["theta"]) @ Omega
    tau_act = {"throttle": a["tau_thrust"], "left": a["tau_elevon"],
               "right": a["tau_elevon"]}
    act = [(u[n] - s[n]) / tau_act[n] for n in LAYOUT.actuators]
    named = dict(zip(("x", "y", "z"), pos_dot))
    named.update(zip(("phi", "theta", "psi"), Theta_dot))
    named.update(zip(("u", "v", "w", "p", "q", "r"), nu_dot))
    named.update(zip(LAYOUT.actuators, act))
    return np.array([named[n] for n in LAYOUT.states])


def outputs_ref(x, p, wind):
    """The 19 outputs: rigid-body states, specific forces over g (n_z up),
    alpha, beta, the air-path angle (from the air-relative velocity rotated
    to NED) and Va."""
    s = _named(x, LAYOUT.states)
    a = _named(p, LAYOUT.params)
    F, _, alpha, beta, Va = forces_ref(x, p, wind)
    mg = a["mass"] * a["g"]
    # air-relative velocity in NED, from alpha and beta
    v_air = Va * np.array([np.cos(alpha) * np.cos(beta), np.sin(beta),
                           np.sin(alpha) * np.cos(beta)])
    v_ned = rzyx(s["phi"], s["theta"], s["psi"]) @ v_air
    named = {n: s[n] for n in LAYOUT.rigid}
    named.update(n_x=F[0] / mg, n_y=F[1] / mg, n_z=-F[2] / mg, alpha=alpha, beta=beta,
                 gamma=np.arcsin(-v_ned[2] / Va), Va=Va)
    return np.array([named[n] for n in LAYOUT.outputs])


def rk4_ref(x, cmd, p, wind, dt, n_sub):
    """``n_sub`` classical RK4 steps over ``dt`` with commands and wind held."""
    def f(s):
        return derivatives_ref(s, cmd, p, wind)

    h = dt / n_sub
    x = np.array(x, dtype=float)
    for _ in range(n_sub):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


# ------------------------------------------------------------------ trial truth step
LATERAL_MEASURED = ("phi", "v", "p", "r", "psi")
"""The lateral loop's measured states (then its two elevon-model states)."""
LONGITUDINAL_AS_SIXDOF = {"thrust": "throttle", "elevon_left": "left",
                          "elevon_right": "right", "CAS": "Va"}
"""Longitudinal names whose 6-DOF state or output has another name."""


def sixdof_truth_ref(scheme, flight, inp, k, st, rec, u):
    """The 6-DOF truth over step ``k``, written from the module docstring of
    ``ftc_mc/core/sixdof/truth.py`` with whole vectors and names, one lane at a
    time: the lateral loop's aileron (or, with ``coupled`` on a lane flying
    c0 or c1, the coupled law's terms on the estimate and the loop's state,
    c1's bilinear in the thrust's estimated faults) and the
    summed, saturated commands; the
    elevon model; eq. (2); the longitudinal and lateral Dryden gusts; RK4 (or
    the linear 6-DOF model); the longitudinal measurements, the lateral ones,
    the air data, the bank angle and the squared bank and heading.

    Returns a dict of the new ``u``, ``e``, ``x``, ``gust``, ``glat``, ``lat``,
    ``z``, ``va``, ``alpha``, ``bank``, ``sq_lat``.
    """
    from ftc_mc.conventions import LONGITUDINAL
    from naive import actuator_model_ref
    from naive import B0_T, B1_T, C0, C1, dryden_ref, engine_gain_ref, sensor_fault_ref

    fm, ctl, pl = scheme.filter, scheme.controller, flight.plant
    L = st.x.shape[1]
    n_meas = len(LATERAL_MEASURED)
    u = np.array(u, dtype=float, copy=True)
    lat = st.lat.copy()
    for l in range(L):
        s = np.concatenate([st.xa[:len(LONGITUDINAL.states), l], st.lat[:, l]])
        if pl.coupled and st.cur[l] == C0:  # c0 as the coupled 6-DOF LQR
            extra = -pl.G0 @ s
        elif pl.coupled and st.cur[l] == C1:  # c1 as Theorem 4.1 on the 6-DOF model
            G, g = engine_gain_ref(pl.G1, st.xa[B0_T, l], st.xa[B1_T, l])
            extra = -G @ s - g
        else:
            da = -pl.K_lat @ st.lat[:, l]
            extra = np.zeros(3)
            extra[LAYOUT.commands.index("left")] = da
            extra[LAYOUT.commands.index("right")] = -da
        u[:, l] = np.clip(u[:, l] + pl.u_ff + extra, ctl.lo_dev, ctl.hi_dev)
        for row, side in ((n_meas, "left"), (n_meas + 1, "right")):
            c = LAYOUT.commands.index(side)
            lat[row, l] = pl.a_act * st.lat[row, l] + (1 - pl.a_act) * (u[c, l] - pl.u_ff[c])
    ev = int(np.searchsorted(inp.k_switch, k, side="right")) - 1
    e, uhist, uprev = actuator_model_ref(
        u, fm.u0, ctl.lo_dev, ctl.hi_dev, inp.b0[ev], inp.b1[ev], inp.fp[ev],
        inp.k_switch[ev], k, pl.dt, np.zeros(L), st.uhist, st.uprev)
    eta, eta_lat = (inp.eta[k], inp.eta_lat[k]) if pl.turb else (None, None)
    lon_w, gust, lon_wn = dryden_ref(pl.turb, pl.Ad, pl.Bd, pl.Cd, st.gust, eta)
    lat_w, glat, lat_wn = dryden_ref(pl.turb, pl.Adl, pl.Bdl, pl.Cdl, st.glat, eta_lat)

    def wind(lon, latw, l):
        w = np.zeros(len(LAYOUT.wind))
        for j, name in enumerate(("u_g", "w_g", "q_g")):
            w[LAYOUT.wind.index(name)] = lon[j, l]
        for j, name in enumerate(("v_g", "p_g", "r_g")):
            w[LAYOUT.wind.index(name)] = latw[j, l]
        return w

    six_state = [LAYOUT.states.index(LONGITUDINAL_AS_SIXDOF.get(n, n))
                 for n in LONGITUDINAL.states]
    six_out = [LAYOUT.outputs.index(LONGITUDINAL_AS_SIXDOF.get(n, n))
               for n in LONGITUDINAL.outputs]
    x = np.zeros_like(st.x)
    z = np.zeros((len(LONGITUDINAL.outputs), L))
    va, alpha, bank = np.zeros(L), np.zeros(L), np.zeros(L)
    sq = rec.sq_lat.copy()
    for l in range(L):
        cmd = fm.u0 + e[:, l]
        if pl.kind == 3:  # linear 6-DOF
            xd = pl.A @ st.x[:, l] + pl.B @ (cmd - pl.u0) + pl.Bw @ wind(lon_w, lat_w, l)
        else:
            xd = rk4_ref(pl.x0 + st.x[:, l], cmd, pl.p, wind(lon_w, lat_w, l), pl.dt,
                         pl.n_sub) - pl.x0
        xd[six_state] += inp.w[k][:, l]
        x[:, l] = xd
        wn = wind(lon_wn, lat_wn, l)
        if pl.kind == 3:
            y = pl.y0 + pl.C @ xd + pl.Dw @ wn
        else:
            y = outputs_ref(pl.x0 + xd, pl.p, wn)
        z[:, l] = y[six_out] - pl.y0[six_out] + inp.v[k][:, l]
        meas = [LAYOUT.outputs.index(n) for n in LATERAL_MEASURED]
        lat[:n_meas, l] = y[meas] - pl.y0[meas] + inp.v_lat[k][:, l]
        va[l] = y[LAYOUT.outputs.index("Va")]
        alpha[l] = y[LAYOUT.outputs.index("alpha")]
        bank[l] = pl.x0[LAYOUT.states.index("phi")] + xd[LAYOUT.states.index("phi")]
        if st.alive[l]:
            sq[0, l] += xd[LAYOUT.states.index("phi")] ** 2
            sq[1, l] += xd[LAYOUT.states.index("psi")] ** 2
    zhold = st.zhold.copy()
    for l in range(L):
        z[:, l], zhold[l] = sensor_fault_ref(
            z[:, l], inp.v[k][:, l], zhold[l], k, pl.dt, int(inp.sensor_out[l]),
            int(inp.sensor_kind[l]), float(inp.sensor_size[l]), int(inp.sensor_k[l]))
    return dict(u=u, e=e, x=x, gust=gust, glat=glat, lat=lat, z=z, va=va, alpha=alpha,
                bank=bank, sq_lat=sq, zhold=zhold, uhist=uhist, uprev=uprev)


class SideMonitorRef:
    """The 6-DOF side monitor of one lane (``ftc_mc/core/sixdof/monitor.py``),
    written from that module's docstring with whole matrices: the augmented
    ``F`` built as a block matrix, ``F P F^T + Q``, one scalar update per
    measurement with its gain ``K = P c^T / S``, the direction signatures
    ``s <- s - K c s``, the projection, each direction's statistic as the
    GLR of :func:`naive.glr_ref` over the projections since the last restart,
    and the decision with its reset.

    ``mon`` a :class:`~ftc_mc.core.sixdof.monitor.SideMonitor`, ``k_fault``
    the switch step.  :meth:`step` takes the step ``k``, the commands ``u``
    (3,), the 17 measurements ``z`` of ``k + 1`` and whether the lane is
    alive; the attributes ``X``, ``P``, ``side_k``, ``side_block``,
    ``side_pre``, ``side_n``, ``b`` (9,) hold the lane's state and record,
    ``side`` the first elevon named (its block code) and ``pos`` its
    estimated position ``b0 + (1 - b1)(u + u0)`` (``core/sixdof/lockturn.py``).

    With ``mon.nonlinear`` the prediction flies the airframe's equations
    (``ftc_mc.model.sixdof.derivatives``, classical RK4 written here,
    ``mon.n_sub`` steps, commands ``b0 + (1 - b1)(u + u0)``) from ``x0 + X``,
    the gust states linear, and each innovation is ``z - h(X_pred) - c (X -
    X_pred)`` with ``h`` the airframe's outputs less the trim's
    (``ftc_mc.model.sixdof.outputs``); ``plant`` the truth (``p``, ``x0``,
    ``y0``, ``dt``).
    """

    def __init__(self, mon, k_fault, plant=None, thresholds=(30.0, 30.0, 30.0)):
        self.mon, self.kf, self.plant = mon, k_fault, plant
        self.thresholds = np.asarray(thresholds, dtype=float)  # the design's, per direction
        n = mon.P0.shape[0]
        self.X, self.P = np.zeros(n), np.zeros((n, n))
        self.hist = []  # direction projections since the last restart, oldest first
        self.side_k, self.side_block, self.side_pre, self.side_n = -1, 0, 0, 0
        self.b = np.zeros(9)
        self.side, self.pos = 0, 0.0  # the first elevon named and its position estimate
        self.last = 0  # its latest decision
        self.now = 0  # its decision at this step
        self.turn_k = -1  # the step from which the lock-turn law may fly (k + 1 of that decision)

    def step(self, k, u, z, alive):
        from naive import glr_ref

        mon = self.mon
        ns, nu = mon.B.shape
        n = ns + 2 * nu
        if k == 0:
            self.X, self.P = np.zeros(n), mon.P0.copy()
        g = -(u + mon.u0)
        F = np.eye(n)
        F[:ns, :ns] = mon.A
        F[:ns, ns:ns + nu] = mon.B
        F[:ns, ns + nu:] = mon.B @ np.diag(g)
        X = F @ self.X
        X[:ns] += mon.B @ (u - mon.u_ff)
        off = np.zeros(mon.C.shape[0])
        Cm = mon.C
        if mon.nonlinear == EXTENDED:
            F, X, Cm, off = self._extended(u)
        elif mon.nonlinear:
            X[:ns], off = self._nonlinear(u)
        P = F @ self.P @ F.T + mon.Q
        S = np.zeros((n, nu))
        S[:ns] = F[:ns, ns:ns + nu]
        num, den = np.zeros(nu), np.zeros(nu)
        for r in range(mon.C.shape[0]):
            c = np.zeros(n)
            c[:ns] = Cm[r]
            s = c @ P @ c + mon.r[r]
            innov = z[r] - c @ X - off[r]
            mu = (c @ S) / np.sqrt(s)
            num += mu * innov / np.sqrt(s)
            den += mu ** 2
            K = P @ c / s
            S = S - np.outer(K, c @ S)
            X = X + K * innov
            P = P - np.outer(P @ c, P @ c) / s
            P = np.triu(P) + np.triu(P, 1).T
        X[ns:ns + nu] = np.clip(X[ns:ns + nu], mon.lo, mon.hi)
        X[ns + nu:] = np.clip(X[ns + nu:], 0.0, 1.0)
        self.X, self.P = X, P
        kn = k + 1
        self.now = 0
        if kn <= mon.startup:
            self.hist = []
            return
        d = np.where(den > 0, num / np.sqrt(np.where(den > 0, den, 1.0)), 0.0)
        self.hist = (self.hist + [d])[-mon.window:]
        stat = glr_ref(self.hist[::-1], mon.min_window)  # three directions
        block = 0
        passing = stat > self.thresholds  # then the largest factor above its threshold
        if passing.any():
            block = int(np.argmax(np.where(passing, stat / self.thresholds, 0.0))) + 1
            for i in (ns + block - 1, ns + nu + block - 1):
                self.P[i, :] = 0.0
                self.P[:, i] = 0.0
                self.P[i, i] = mon.reset_var[i - ns]
            self.last = self.now = block
            if block > 1 and self.side == 0:
                self.side, self.turn_k = block, kn
            if alive:
                self.side_n += 1
                if kn >= self.kf:
                    if self.side_k < 0:
                        self.side_k, self.side_block = kn, block
                else:
                    self.side_pre += 1
            self.hist = []
        if self.side:
            a = self.side - 1
            self.pos = self.X[ns + a] + (1 - self.X[ns + nu + a]) * (u[a] + mon.u0[a])
        if alive and (self.side_k < 0 or kn <= self.side_k + mon.snap):
            self.b = np.concatenate([X[ns:], X[ns:ns + nu] + (1 - X[ns + nu:]) * (u + mon.u0)])


    def _extended(self, u):
        """The extended filter's ``F`` (n, n), prediction ``X_pred`` (n,),
        output Jacobian ``C`` (m, ns) and ``h(X_pred) - C X_pred`` (m,): the
        equations with the gust states' wind ``mon.wind g`` held over the
        period, their Jacobians by forward differences of step
        ``JACOBIAN_STEP`` at the estimate."""
        from ftc_mc.core.sixdof.monitor import JACOBIAN_STEP as eps

        mon, pl = self.mon, self.plant
        ns, nu = mon.B.shape
        nx = len(mon.states)
        n = ns + 2 * nu
        X = self.X
        cmd = X[ns:ns + nu] + (1 - X[ns + nu:]) * (u + mon.u0)
        wind = mon.wind @ X[nx:ns]

        def fly(xr, c, w):
            return rk4_ref(_on_trim(pl, mon.states, xr), c, pl.p, w, pl.dt,
                           mon.n_sub)[mon.states] - pl.x0[mon.states]

        def out(xr, w):
            return outputs_ref(_on_trim(pl, mon.states, xr), pl.p, w)[mon.outs] - pl.y0[mon.outs]

        def forward(f, x0):
            f0 = f(x0)
            return np.stack([(f(x0 + eps * e) - f0) / eps for e in np.eye(x0.size)], axis=1)

        xr = X[:nx]
        F = np.eye(n)
        F[:nx, :nx] = forward(lambda v: fly(v, cmd, wind), xr)
        Bl = forward(lambda c: fly(xr, c, wind), cmd)
        F[:nx, ns:ns + nu] = Bl
        F[:nx, ns + nu:] = Bl @ np.diag(-(u + mon.u0))
        F[:nx, nx:ns] = forward(lambda w: fly(xr, cmd, w), wind) @ mon.wind
        F[nx:ns, :nx] = 0.0
        F[nx:ns, nx:ns] = mon.A[nx:, nx:]
        Xp = X.copy()
        Xp[:nx] = fly(xr, cmd, wind)
        Xp[nx:ns] = mon.A[nx:, nx:] @ X[nx:ns]
        wp = mon.wind @ Xp[nx:ns]
        C = np.zeros((mon.C.shape[0], ns))
        C[:, :nx] = forward(lambda v: out(v, wp), Xp[:nx])
        C[:, nx:] = forward(lambda w: out(Xp[:nx], w), wp) @ mon.wind
        return F, Xp, C, out(Xp[:nx], wp) - C @ Xp[:ns]

    def _nonlinear(self, u):
        """The nonlinear prediction of the monitor's states (ns,) and each
        measurement's ``h(X_pred) - C X_pred`` (m,)."""
        mon, pl = self.mon, self.plant
        ns, nu = mon.B.shape
        nx = len(mon.states)
        cmd = self.X[ns:ns + nu] + (1 - self.X[ns + nu:]) * (u + mon.u0)
        pred = np.zeros(ns)
        pred[:nx] = (fly_equations(pl, mon.states, self.X[:nx], cmd, mon.n_sub)
                     + mon.A[:nx, nx:] @ self.X[nx:ns])
        pred[nx:] = mon.A[nx:, nx:] @ self.X[nx:ns]
        off = equation_outputs(pl, mon.states, mon.outs, pred[:nx]) - mon.C[:, :nx] @ pred[:nx]
        return pred, off


def _on_trim(pl, states, x_dev):
    """The absolute 6-DOF state: the trim ``pl.x0`` plus ``x_dev`` on the rows ``states``."""
    x = pl.x0.copy()
    x[states] += x_dev
    return x


def fly_equations(pl, states, x_dev, cmd, n_sub, wind=None):
    """One period ``pl.dt`` of the 6-DOF airframe's equations
    (``ftc_mc.model.sixdof.derivatives``, classical RK4 in ``n_sub`` steps,
    the ``wind`` (6,) held, default still air) from the trim ``pl.x0`` plus
    ``x_dev`` on the rows ``states``, under the absolute commands ``cmd``;
    returns the deviation on those rows."""
    from ftc_mc.model.sixdof import derivatives

    x = _on_trim(pl, states, x_dev)
    h = pl.dt / n_sub
    for _ in range(n_sub):
        k1 = derivatives(x, cmd, pl.p, wind)
        k2 = derivatives(x + h / 2 * k1, cmd, pl.p, wind)
        k3 = derivatives(x + h / 2 * k2, cmd, pl.p, wind)
        k4 = derivatives(x + h * k3, cmd, pl.p, wind)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x[states] - pl.x0[states]


def equation_outputs(pl, states, outs, x_dev, wind=None):
    """The airframe's outputs ``outs`` less the trim's
    (``ftc_mc.model.sixdof.outputs``, in the ``wind`` (6,), default still air)
    at the trim plus ``x_dev`` on the rows ``states``."""
    from ftc_mc.model.sixdof import outputs

    return outputs(_on_trim(pl, states, x_dev), pl.p, wind)[outs] - pl.y0[outs]


def turn_probe_ref(tab, t, b1, var):
    """The lock-turn law's probe and hand-back ``t`` steps after it took over
    (``ftc_mc/core/sixdof/lockturn.py``, written from that module's docstring):
    the 3211 of Fig. 4 (``+A`` for 3 units, ``-A`` for 2, ``+A``, ``-A``) on the
    named elevon, and whether a lane whose monitor estimates its ``b1`` with
    variance ``var`` hands back.  Returns ``(addition [rad], hands back)``."""
    if tab.probe == 0.0:
        return 0.0, False
    units = t // tab.probe_unit if t >= 0 else -1
    signs = [1.0] * 3 + [-1.0] * 2 + [1.0, -1.0]
    value = tab.probe * signs[units] if 0 <= units < len(signs) else 0.0
    upper = b1 + tab.hand_back_sd * np.sqrt(max(var, 0.0))
    return value, bool(t == tab.check and upper < tab.hand_back)


def lock_turn_law_ref(tab, s, p, xhat, lo_dev, hi_dev):
    """The lock-turn law of one lane (``ftc_mc/core/sixdof/lockturn.py``),
    written from that module's docstring: every table entry interpolated with
    ``np.interp`` over the side's lock grid at the position ``p`` (clamped to
    its ends), ``u* - K (x_hat - x*) - k`` on the throttle and the healthy
    elevon, the locked elevon at its trim command ``hold``, each clipped;
    the trim commands ``hold`` instead where neither grid point bracketing
    ``p`` is steady.
    ``xhat`` (n_f,) the fed-back states.  Returns the commands (3,) less the
    longitudinal trim."""
    n = tab.x.shape[1]
    grid = tab.lo[s] + tab.step * np.arange(n)
    out = np.zeros(3)
    out[tab.locked[s]] = tab.hold[tab.locked[s]]
    i = min(int(np.searchsorted(grid, np.clip(p, grid[0], grid[-1]), side="right")) - 1,
            n - 2)  # the bracketing pair i, i + 1 (the last two beyond the end)
    if not tab.steady[s, [i, i + 1]].any():  # no steady flight either side: trim held
        out[tab.cmd[s]] = tab.hold[tab.cmd[s]]
        return np.clip(out, lo_dev, hi_dev)

    def at(a):  # entry-wise interpolation of a (n, ...) table
        flat = a.reshape(n, -1)
        return np.array([np.interp(p, grid, flat[:, j]) for j in range(flat.shape[1])]
                        ).reshape(a.shape[1:])

    x, u, K, k = at(tab.x[s]), at(tab.u[s]), at(tab.K[s]), at(tab.k[s])
    out[tab.cmd[s]] = u[tab.cmd[s]] - K @ (xhat - x) - k
    return np.clip(out, lo_dev, hi_dev)


def envelope_excess_ref(env, xs):
    """The envelope's excess at the absolute 6-DOF state ``xs``, in m/s and
    degrees, from ``u, v, w`` and ``phi`` (``core/sixdof/lockturn.py``'s
    module docstring): the largest of ``env[0] - Va``, ``Va - env[1]``,
    ``env[2] - alpha``, ``alpha - env[3]``, ``|phi| - env[4]``; inf where not
    finite."""
    u, v, w = (xs[LAYOUT.states.index(n)] for n in ("u", "v", "w"))
    va = np.sqrt(u * u + v * v + w * w)
    alpha = np.degrees(np.arctan2(w, u))
    bank = np.degrees(abs(xs[LAYOUT.states.index("phi")]))
    e = max(env[0] - va, va - env[1], env[2] - alpha, alpha - env[3], bank - env[4])
    return e if np.isfinite([va, alpha, bank]).all() else np.inf


def rollout_step_ref(tab, pl, xs, cmd):
    """One period of a rollout from the absolute 6-DOF state ``xs`` under the
    absolute commands ``cmd``, still air, and the envelope's excess after it
    (``core/sixdof/lockturn.py``'s module docstring): on the linear plant
    (``pl.kind``) its model ``x+ = A x + B u`` in deviations from the trim
    ``x0``, ``u0``, the airspeed and angle of attack from its output map
    ``y0 + C dx``; else :func:`rk4_ref` (``ro_sub`` sub-steps) and
    :func:`envelope_excess_ref`.  Returns ``(state, excess)``."""
    from ftc_mc.core.sixdof.layout import OUTPUT, SIXDOF_LINEAR

    if pl.kind != SIXDOF_LINEAR:
        xs = rk4_ref(xs, cmd, pl.p, np.zeros(6), pl.dt, tab.ro_sub)
        return xs, envelope_excess_ref(tab.ro_env, xs)
    xs = pl.x0 + pl.A @ (xs - pl.x0) + pl.B @ (cmd - pl.u0)
    y = pl.y0 + pl.C @ (xs - pl.x0)
    va, alpha = y[OUTPUT["Va"]], np.degrees(y[OUTPUT["alpha"]])
    bank = np.degrees(abs(xs[LAYOUT.states.index("phi")]))
    env = tab.ro_env
    e = max(env[0] - va, va - env[1], env[2] - alpha, alpha - env[3], bank - env[4])
    return xs, (e if np.isfinite([va, alpha, bank]).all() else np.inf)


def rocking_scores_ref(tab, pl, s, p, x):
    """``(periods inside, -largest excess before leaving)`` of every rocking
    candidate (its first pair for ``ro_first`` periods, its second after, the
    named elevon at ``p``) flown ``ro_steps`` periods of
    :func:`rollout_step_ref` (still air) from the absolute state ``x``."""
    scores = []
    for c in range(len(tab.ro_first)):
        xs = np.array(x, dtype=float)
        excess = []
        for k in range(tab.ro_steps):
            pair = tab.ro_u[s, c, 0 if k < tab.ro_first[c] else 1]
            cmd = np.zeros(3)
            cmd[tab.cmd[s]] = pl.monitor.u0[tab.cmd[s]] + pair
            cmd[tab.locked[s]] = p
            xs, e = rollout_step_ref(tab, pl, xs, cmd)
            excess.append(e)
        out = next((k for k, e in enumerate(excess) if e > 0), tab.ro_steps)
        scores.append((out, -max(excess[:out], default=-np.inf)))
    return scores


def rocking_law_ref(tab, pl, s, p, x, lo_dev, hi_dev):
    """The rocking law of one lane (``ftc_mc/core/sixdof/lockturn.py``), written
    from that module's docstring: from the absolute 6-DOF state ``x`` (15,),
    every candidate history (its first pair for ``ro_first`` periods, its
    second after, the named elevon at ``p``) flies ``ro_steps`` periods of
    :func:`rollout_step_ref` (still air), with the envelope's excess after
    each, in m/s and degrees; the
    candidate that stays in longest, then the one with the least largest
    excess before it leaves, the first on a tie; the trim commands ``hold``
    when every candidate leaves within the first period.  Returns the
    commands of the throttle and the healthy elevon (2,) less the
    longitudinal trim ``pl.monitor.u0``, and the chosen candidate's index
    (-1: the trim held)."""
    scores = rocking_scores_ref(tab, pl, s, p, x)
    best = max(range(len(scores)), key=lambda c: (scores[c], -c))
    if scores[best][0] == 0:
        return np.clip(tab.hold[tab.cmd[s]], lo_dev[tab.cmd[s]], hi_dev[tab.cmd[s]]), -1
    cmd = np.clip(tab.ro_u[s, best, 0], lo_dev[tab.cmd[s]], hi_dev[tab.cmd[s]])
    return cmd, best


def guarded_law_ref(tab, pl, s, p, x, lo_dev, hi_dev):
    """The rollout guard on the lock-turn LQR of one lane
    (``ftc_mc/core/sixdof/lockturn.py``), written from that module's
    docstring: the LQR of :func:`lock_turn_law_ref` (at ``p``), its fed-back
    states read from the flown absolute state by name (:func:`turn_states`
    less the 6-DOF trim ``pl.x0``), flies ``ro_steps`` periods of
    :func:`rollout_step_ref` from ``x`` (15,), the named elevon at ``p``; if that stays
    in the envelope the LQR flies.  Else each candidate (one of the first
    ``gd_pairs`` held pairs of ``ro_u`` for ``gd_holds`` periods, then the
    LQR) flies too; the longest stay, then the least largest excess, wins,
    the LQR's own flight first and the candidates pair-major on a tie.
    Returns ``None`` when the LQR flies, else the winning pair's commands
    (2,) less ``pl.monitor.u0`` and ``(pair, hold)``."""
    from ftc_mc.design.lock_turn import SIDES, turn_states

    idx = [LAYOUT.states.index(n) for n in turn_states(SIDES[s])]

    def lqr(xs):
        full = lock_turn_law_ref(tab, s, p, xs[idx] - pl.x0[idx], lo_dev, hi_dev)
        return full[tab.cmd[s]]

    def fly(pair, hold):
        xs = np.array(x, dtype=float)
        excess = []
        for k in range(tab.ro_steps):
            cmd = np.zeros(3)
            cmd[tab.cmd[s]] = pl.monitor.u0[tab.cmd[s]] + (pair if k < hold else lqr(xs))
            cmd[tab.locked[s]] = p
            xs, e = rollout_step_ref(tab, pl, xs, cmd)
            excess.append(e)
        out = next((k for k, e in enumerate(excess) if e > 0), tab.ro_steps)
        return out, -max(excess[:out], default=-np.inf)

    own = fly(None, 0)
    if own[0] == tab.ro_steps:
        return None
    scores = [(own, None)]
    for c in range(tab.gd_pairs):
        for h in tab.gd_holds:
            scores.append((fly(tab.ro_u[s, c, 0], h), (c, int(h))))
    best = max(range(len(scores)), key=lambda i: (scores[i][0], -i))
    if scores[best][1] is None:
        return None
    c, h = scores[best][1]
    return np.clip(tab.ro_u[s, c, 0], lo_dev[tab.cmd[s]], hi_dev[tab.cmd[s]]), (c, h)


def side_blocks_ref(kind, mside, mlast, block, source=0, mnow=None):
    """Twin of ``core/sixdof/lockturn.side_blocks``, from its docstring: in a
    ``lock_turn`` or ``lock_turn_selected`` design (``kind`` 2 or 3) each lane's Table 1 reset (``block`` 1
    thrust or 2 elevons) goes to the block of the elevon the lane flies the
    law about (``mside`` > 0), else of the monitor's latest decision
    (``mlast``: 1 the throttle, 2 and 3 the elevons; 0 none: Table 1's
    stays).  With resets from the monitor (``source`` 1) every lane resets
    the block of the monitor's decision at this step (``mnow``; 0: none),
    whatever Table 1 and the kind; with ``source`` 2 (either) the lanes
    where it decided nothing keep the rule above.  Returns the new blocks."""
    out = np.array(block, copy=True)
    if source in (1, 2):
        monitor = np.array([0 if m == 0 else 1 if m == 1 else 2 for m in mnow], dtype=np.int64)
        if source == 1:
            return monitor
        rest = side_blocks_ref(kind, mside, mlast, block)
        return np.where(monitor != 0, monitor, rest)
    if kind < 2:  # lock_turn (2) and lock_turn_selected (3) only
        return out
    for l in range(len(out)):
        named = mside[l] if mside[l] > 0 else mlast[l]
        if out[l] != 0 and named != 0:
            out[l] = 1 if named == 1 else 2
    return out



def action_cost_ref(pl, ctl, tables, rc, a, x6, mlr, bhat, btrue, n_steps):
    """Eq. (45) for one of the four 6-DOF controllers
    (``ftc_mc/core/sixdof/selection.py``), written from that module's
    docstring with whole vectors: the plant's model (:func:`rollout_step_ref`)
    flown ``n_steps`` periods from the absolute state ``x6`` with the faults
    ``btrue`` (eq. 2 per actuator, ``[b0 (3), b1 (3)]``); c0 and c1 the
    paper's laws on the longitudinal states of the same names and the faults
    ``bhat`` (the elevons' ``b0`` summed), clipped, plus ``u_ff`` and the
    lateral loop's aileron (or the coupled law's terms), clipped again; c2 and
    c3 :func:`lock_turn_law_ref` at the lock position ``b0 + (1 - b1)(hold +
    u0)`` of the locked elevon, on the fed-back states read by name; the
    lateral loop's elevon model advanced; cost ``sum alpha^k (x' Q x + (u -
    u_ff)' R (u - u_ff))`` on the flown 6-DOF states less the trim.  ``inf``
    when not finite."""
    from ftc_mc.conventions import LONGITUDINAL
    from ftc_mc.design.lock_turn import SIDES, turn_states
    from naive import B0_E, B0_T, B1_L, B1_R, B1_T, C0, C1, controller_command_ref, engine_gain_ref

    mon = pl.monitor
    tab = mon.turn
    lon = [LAYOUT.states.index(LONGITUDINAL_AS_SIXDOF.get(m, m)) for m in LONGITUDINAL.states]
    lat = [LAYOUT.states.index(m) for m in LATERAL_MEASURED]
    left, right = LAYOUT.commands.index("left"), LAYOUT.commands.index("right")
    X = np.zeros(14)
    X[B0_T], X[B0_E], X[B1_T], X[B1_L], X[B1_R] = (bhat[0], bhat[1] + bhat[2], bhat[3],
                                                   bhat[4], bhat[5])
    xs = np.array(x6, dtype=float)
    m = np.array(mlr, dtype=float)
    if a >= 2:
        s = a - 2
        j = tab.locked[s]
        p = bhat[j] + (1.0 - bhat[3 + j]) * (tab.hold[j] + mon.u0[j])
        fed = [LAYOUT.states.index(name) for name in turn_states(SIDES[s])]
    cost, disc = 0.0, 1.0
    with np.errstate(all="ignore"):
        for _ in range(n_steps):
            dev = xs - pl.x0
            if a < 2:
                X[:9] = dev[lon]
                U = np.clip(controller_command_ref(a, X, ctl.K, tables, mon.u0), ctl.lo_dev,
                            ctl.hi_dev)
                state = np.concatenate([X[:9], dev[lat], m])
                if pl.coupled and a == C0:
                    extra = -pl.G0 @ state
                elif pl.coupled and a == C1:
                    G, g = engine_gain_ref(pl.G1, X[B0_T], X[B1_T])
                    extra = -G @ state - g
                else:
                    da = -pl.K_lat @ state[9:]
                    extra = np.zeros(3)
                    extra[left], extra[right] = da, -da
                u = np.clip(U + pl.u_ff + extra, ctl.lo_dev, ctl.hi_dev)
            else:
                u = lock_turn_law_ref(tab, s, p, dev[fed], ctl.lo_dev, ctl.hi_dev)
            m = pl.a_act * m + (1.0 - pl.a_act) * (u[[left, right]] - pl.u_ff[[left, right]])
            cmd = btrue[:3] + (1.0 - btrue[3:]) * (u + mon.u0)
            xs, _ = rollout_step_ref(tab, pl, xs, cmd)
            disc *= rc.alpha
            cost += disc * (rc.r_lqr @ (u - mon.u_ff) ** 2 + rc.q_lqr @ (xs - pl.x0) ** 2)
    return cost if np.isfinite(cost) else np.inf


def sixdof_select_ref(pl, scheme, kn, st, u, horizon_cost=action_cost_ref):
    """The belief and the selection of a ``lock_turn_selected`` design at a
    period's end (``ftc_mc/core/sixdof/selection.py``), written from that
    module's docstring: every lane's belief by eqs. (12)-(14) in log space on
    the side monitor's six fault parameters and their variances; on each live
    lane the controller minimising ``I^H(a) + sum_m b(m) (J^N(m, a) + P(c, a))``
    (the first on a tie), its side and start step when it is c2 or c3 and new,
    and the lock position of that elevon.  Returns a dict of ``belief``,
    ``cur``, ``mside``, ``mturn``, ``mpos``."""
    from naive import belief_update_log_ref

    mon = pl.monitor
    ns = mon.A.shape[0]
    bs, rc = scheme.belief, scheme.reconfig
    out = dict(belief=st.belief.copy(), cur=st.cur.copy(), mside=st.mside.copy(),
               mturn=st.mturn.copy(), mpos=st.mpos.copy())
    for l in range(st.mx.shape[1]):
        bh = st.mx[ns:ns + 6, l]
        var = np.diag(st.mP[:, :, l])[ns:ns + 6]
        b, _ = belief_update_log_ref(st.belief[:, l], bs.TM, bs.lo, bs.hi, bh, var)
        out["belief"][:, l] = b
        if not st.alive[l]:
            continue
        cur = int(st.cur[l])
        mlr = st.lat[[5, 6], l]
        x6 = pl.x0.copy()  # the monitor's estimate on its rows, the trim elsewhere
        x6[mon.states] += st.mx[:len(mon.states), l]
        obj = [horizon_cost(pl, scheme.controller, scheme.engine, rc, a, x6, mlr, bh, bh,
                            rc.horizon) + b @ (rc.JN[:, a] + rc.penalty[cur, a])
               for a in range(4)]
        obj = np.array(obj)
        obj[~np.isfinite(obj)] = np.inf  # never chosen; none finite: the one in use stays
        best = int(np.argmin(obj)) if np.isfinite(obj).any() else cur
        out["cur"][l] = best
        if best < 2:
            out["mside"][l] = 0
        elif st.mside[l] != best:
            out["mside"][l], out["mturn"][l] = best, kn
            j = best - 1
            out["mpos"][l] = bh[j] + (1.0 - bh[3 + j]) * (u[j, l] + mon.u0[j])
    return out
