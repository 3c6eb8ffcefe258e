"""Slow plain-NumPy reference twins of the :mod:`ftc_mc.core` kernels.

STUMPY style: every jitted kernel has a twin here, written from the paper's
equations in their textbook form (full matrices, explicit inverses, ``scipy``
normal CDF), deliberately *not* by transcribing the kernels.  The kernels exploit
structure (no ``A_aug`` is ever formed, sequential scalar updates, logarithms,
in-place work arrays); the twins do none of that, so an agreement to round-off
is evidence that the structure was exploited correctly.

Twins here: the filter (predict, residuals, Table 1, reset, update, projection,
one step), the belief, the excitation signals and saturation, the X8 equations
and RK4, the controllers and their selection (``controller_command_ref``,
``horizon_cost_ref``, ``controller_objectives_ref``, ``select_controller_ref``),
each stage of a trial step (``commands_ref``, ``truth_step_ref``,
``filter_update_ref``, ``check_validity_ref``, ``handle_resets_ref`` with
``policy_signals_ref``, ``record_cost_ref``, ``record_step_ref``,
``reconfigure_ref``) and the trial loop chaining them
(``advance_ref``).

Paper: "Reconfiguration control method for non-redundant actuator faults on UAV"
(``docs/reference/paper-map.md`` maps it to the code), sections 2-5.

Conventions (``ftc_mc.model.faults``): augmented state
``X = [x (9), b0 (2), b1 (3)]`` with ``b0 = [thrust, elevon sum]`` and
``b1 = [thrust, left, right]``; indices of the measured outputs are 0-based, so
the paper's outputs 3, 7, 8 (q, n_x, n_z) are 2, 6, 7 here.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.stats import norm

from ftc_mc.model.faults import augmented

NO_RESET, RESET_THRUST, RESET_ELEVONS = 0, 1, 2

N_X = 9
N_AUG = 14
OUT_Q, OUT_NX, OUT_NZ = 2, 6, 7  # paper's mu_3, mu_7, mu_8 (eqs. 9-11)
OUT_ALPHA, OUT_VA = 8, 11

# fault-parameter indices in the augmented state
B0_T, B0_E, B1_T, B1_L, B1_R = 9, 10, 11, 12, 13
BLOCKS = {RESET_THRUST: (B0_T, B1_T), RESET_ELEVONS: (B0_E, B1_L, B1_R)}


# --------------------------------------------------------------------- model
@dataclasses.dataclass
class RefModel:
    """Everything the reference filter needs, as plain arrays and numbers.

    Attributes
    ----------
    A, B, C : ndarray
        Plant matrices of eq. (1), shapes (9, 9), (9, 3), (12, 9).
    u0 : ndarray, shape (3,)
        Trim commands (absolute).
    q, r : ndarray
        Diagonals of Q (14,) and R (12,) (section 5.1).
    lo, hi : ndarray, shape (5,)
        Bounds of the fault parameters (eq. 6).
    t_q, t_nx : float
        Thresholds of Table 1.
    variant : str
        ``"paper"`` or ``"swapped"`` (``docs/reference/paper-map.md``).
    reset_var : ndarray, shape (5,)
        Variances after a reset (section 3.2.2).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    u0: np.ndarray
    q: np.ndarray
    r: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    t_q: float
    t_nx: float
    variant: str
    reset_var: np.ndarray
    G: np.ndarray | None = None
    Ad: np.ndarray | None = None
    Dg: np.ndarray | None = None
    Qg: np.ndarray | None = None
    test: str = "one_step"
    window: int = 1
    min_window: int = 1
    clip: float = np.inf
    settle: int = 0
    startup: int = 0
    nl: int = 0
    p: np.ndarray | None = None
    x0: np.ndarray | None = None
    y0: np.ndarray | None = None
    Cg: np.ndarray | None = None
    n_sub: int = 2
    dt: float = 0.1
    relin: int = 0
    Dz: np.ndarray | None = None
    reset_g: np.ndarray | None = None

    @property
    def ng(self) -> int:
        """Gust states carried after the fault parameters (0: the paper's filter)."""
        return 0 if self.G is None else self.G.shape[1]


def paper_q(dt, sigma_qx=0.01, sigma_qb=0.001):
    """Diagonal of Q: ``Q^x = sigma_qx^2 dt I_9``, ``Q^b = sigma_qb^2 dt I_5`` (5.1)."""
    return np.concatenate([np.full(9, sigma_qx ** 2 * dt), np.full(5, sigma_qb ** 2 * dt)])


def fault_bounds_ref(u_lower, u_upper):
    """Box of eq. (6): b0 within the command range, b1 in [0, 1] (section 2.4).

    The elevon entry of b0 is the *sum* of two elevon biases, so its range is
    twice one elevon's (``ftc_mc.model.faults`` docstring).
    """
    lo = np.array([u_lower[0], u_lower[1] + u_lower[2], 0.0, 0.0, 0.0])
    hi = np.array([u_upper[0], u_upper[1] + u_upper[2], 1.0, 1.0, 1.0])
    return lo, hi


def reset_variances_ref(t_q, t_nx, u_lower, u_upper):
    """Section 3.2.2: thrust ``((u1max-u1min)/t_nx)^2``, ``1/t_nx^2``; elevons the
    same with ``u2`` and ``t_q`` (b0 of the elevon sum, b1 of each elevon)."""
    v = np.zeros(5)
    v[0] = ((u_upper[0] - u_lower[0]) / t_nx) ** 2  # b0 thrust
    v[2] = 1.0 / t_nx ** 2                          # b1 thrust
    v[1] = ((u_upper[1] - u_lower[1]) / t_q) ** 2   # b0 elevons
    v[3] = 1.0 / t_q ** 2                           # b1 left
    v[4] = 1.0 / t_q ** 2                           # b1 right
    return v


def ref_model(plant, settings):
    """Reference model built from the plant and ``EstimatorSettings`` directly.

    Uses the settings' scalars only, never the kernels' namedtuples, so the
    builders of :mod:`ftc_mc.sim.estimator` are checked too.
    """
    lo, hi = fault_bounds_ref(plant.u_lower, plant.u_upper)
    return RefModel(
        A=np.array(plant.A), B=np.array(plant.B), C=np.array(plant.C),
        u0=np.array(plant.u0), q=paper_q(plant.dt, settings.sigma_qx, settings.sigma_qb),
        r=np.array(settings.r_diag, dtype=float), lo=lo, hi=hi,
        t_q=float(settings.t_q), t_nx=float(settings.t_nx), variant=settings.signature,
        reset_var=reset_variances_ref(settings.t_q, settings.t_nx,
                                      plant.u_lower, plant.u_upper))


def aug(model, u):
    """``A_aug(u)``, ``B_aug``, ``C_aug`` of eq. (5), formed explicitly; with gust
    states ``F = [[A, B_b0, D(u), G], [0, I, 0], [0, 0, A_d]]``,
    ``[B; 0; 0]`` and ``[C, 0, D_g]``."""
    A_aug, B_aug, C_aug = augmented(model.A, model.B, model.C, u, model.u0)
    ng = model.ng
    if ng == 0:
        return A_aug, B_aug, C_aug
    n0 = A_aug.shape[0]
    F = np.zeros((n0 + ng, n0 + ng))
    F[:n0, :n0] = A_aug
    F[:N_X, n0:] = model.G
    F[n0:, n0:] = model.Ad
    Bf = np.vstack([B_aug, np.zeros((ng, B_aug.shape[1]))])
    Cf = np.hstack([C_aug, model.Dg])
    return F, Bf, Cf


def process_noise(model):
    """``Q``: the diagonal of eq. (5) on ``x`` and ``b``, ``Qg`` on the gust states."""
    Q = np.diag(model.q)
    if model.ng:
        Q = np.block([[Q, np.zeros((len(model.q), model.ng))],
                      [np.zeros((model.ng, len(model.q))), model.Qg]])
    return Q


# ------------------------------------------------------------------ filter
def predict_ref(X, P, u, model):
    """Eq. (5) time update: ``X = A_aug X + B_aug u``, ``P = A_aug P A_aug^T + Q``."""
    A_aug, B_aug, _ = aug(model, u)
    Xn = A_aug @ X + B_aug @ u
    if model.nl:  # extended filter: the airframe predicts the plant states
        b0, b1 = X[N_X:N_X + 2], X[N_X + 2:N_AUG]
        effect = u + np.array([b0[0], b0[1] / 2, b0[1] / 2]) - b1 * (u + model.u0)
        Xn[:N_X] = rk4_ref(model.x0 + X[:N_X], model.u0 + effect, model.p,
                           gust_wind(X, model), model.dt, model.n_sub) - model.x0
    P = A_aug @ P @ A_aug.T + process_noise(model)
    return Xn, P


def gust_wind(X, model):
    """The estimated gust ``C_d g`` (zero without gust states)."""
    return model.Cg @ X[N_AUG:] if model.ng else np.zeros(3)


def predicted_outputs(X, model):
    """``C_aug X``, or with the extended filter ``h(x0 + x, C_d g) - y0 + D_z g``
    (``D_z``: the output biases of a sensor-aware design)."""
    if model.nl:
        bias = model.Dz @ X[N_AUG:] if model.Dz is not None else 0.0
        return (x8_outputs_ref(model.x0 + X[:N_X], model.p, gust_wind(X, model)) - model.y0
                + bias)
    return aug(model, np.zeros(3))[2] @ X


def x8_jacobian_ref(x, cmd, p, wind):
    """``[df/dx, df/dcmd, df/dwind]`` (9 x 15) of :func:`x8_derivatives_ref` by
    central differences (steps ``1e-5 max(1, |v|)``: errors near 1e-10
    relative, far below the forward differences the filter once used)."""
    v = np.concatenate([x, cmd, wind]).astype(float)
    J = np.zeros((N_X, v.size))
    for j in range(v.size):
        step = 1e-5 * max(1.0, abs(v[j]))
        vp, vm = v.copy(), v.copy()
        vp[j] += step
        vm[j] -= step
        fp = x8_derivatives_ref(vp[:N_X], vp[N_X:N_X + 3], p, vp[N_X + 3:])
        fm_ = x8_derivatives_ref(vm[:N_X], vm[N_X:N_X + 3], p, vm[N_X + 3:])
        J[:, j] = (fp - fm_) / (vp[j] - vm[j])
    return J


def rk4_jacobian_ref(x, cmd, p, wind, dt, n_sub):
    """The derivative of :func:`rk4_ref`'s map in ``[x, cmd, wind]`` (9 x 15),
    carried through the RK4 stages: ``K_s = J_f(x_s) [S_s; E]`` with the stage
    tangents ``S_s`` formed as the stage points are and ``E`` the held
    commands' and wind's unit columns."""
    def f(s):
        return x8_derivatives_ref(s, cmd, p, wind)

    def slope(s, S):
        return x8_jacobian_ref(s, cmd, p, wind) @ np.vstack([S, np.eye(6, 15, N_X)])

    h = dt / n_sub
    x = np.array(x, dtype=float)
    S = np.eye(N_X, 15)
    for _ in range(n_sub):
        k1, K1 = f(x), slope(x, S)
        x2, S2 = x + h / 2 * k1, S + h / 2 * K1
        k2, K2 = f(x2), slope(x2, S2)
        x3, S3 = x + h / 2 * k2, S + h / 2 * K2
        k3, K3 = f(x3), slope(x3, S3)
        x4, S4 = x + h * k3, S + h * K3
        k4, K4 = f(x4), slope(x4, S4)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        S = S + h / 6 * (K1 + 2 * K2 + 2 * K3 + K4)
    return S


def jacobians_ref(X, u, model, exact=True):
    """The extended filter's Jacobians at the estimate ``X`` with the command
    ``u`` (``core/gustfilter.relinearise_lanes``, ``relinearise_outputs_lanes``):
    of the one-period map ``x_{k+1} = rk4(x0 + x, u0 + e, C_d g)``, its
    derivative carried through the RK4 stages (:func:`rk4_jacobian_ref`), and
    of the outputs ``h(x0 + x, C_d g)`` by central differences (steps ``1e-5
    max(1, |v|)``); with ``exact=False`` the forward differences the kernels
    took before: steps ``1e-6 max(1, |x0_i + x_i|)`` in the states, ``1e-6`` in
    the effects and the wind, each divided by the step actually represented.
    Returns ``JA, JB, JW, JC, JHW``."""
    b0, b1 = X[N_X:N_X + 2], X[N_X + 2:N_AUG]
    cmd = model.u0 + u + np.array([b0[0], b0[1] / 2, b0[1] / 2]) - b1 * (u + model.u0)
    xs = model.x0 + X[:N_X]
    w = gust_wind(X, model)

    def f(x, c, wind):
        return rk4_ref(x, c, model.p, wind, model.dt, model.n_sub)

    def h(x, wind):
        return x8_outputs_ref(x, model.p, wind)

    fb, yb = f(xs, cmd, w), h(xs, w)
    JA, JB, JW = np.zeros((N_X, N_X)), np.zeros((N_X, 3)), np.zeros((N_X, 3))
    JC, JHW = np.zeros((len(yb), N_X)), np.zeros((len(yb), 3))
    for j in range(N_X):
        xp = xs.copy()
        xp[j] = xs[j] + 1e-6 * max(1.0, abs(xs[j]))
        d = xp[j] - xs[j]
        JA[:, j] = (f(xp, cmd, w) - fb) / d
        JC[:, j] = (h(xp, w) - yb) / d
    for j in range(3):
        cp = cmd.copy()
        cp[j] = cmd[j] + 1e-6
        JB[:, j] = (f(xs, cp, w) - fb) / (cp[j] - cmd[j])
        wp = w.copy()
        wp[j] = w[j] + 1e-6
        JW[:, j] = (f(xs, cmd, wp) - fb) / (wp[j] - w[j])
        JHW[:, j] = (h(xs, wp) - yb) / (wp[j] - w[j])
    if exact:
        S = rk4_jacobian_ref(xs, cmd, model.p, w, model.dt, model.n_sub)
        JA, JB, JW = S[:, :N_X], S[:, N_X:N_X + 3], S[:, N_X + 3:]
        v = np.concatenate([xs, w])
        for j in range(v.size):
            step = 1e-5 * max(1.0, abs(v[j]))
            vp, vm = v.copy(), v.copy()
            vp[j] += step
            vm[j] -= step
            col = ((h(vp[:N_X], vp[N_X:]) - h(vm[:N_X], vm[N_X:])) / (vp[j] - vm[j]))
            if j < N_X:
                JC[:, j] = col
            else:
                JHW[:, j - N_X] = col
    return JA, JB, JW, JC, JHW


JACOBIANS = ("JA", "JB", "JW", "JC", "JHW")
"""The per-lane Jacobian fields of a ``LaneState``."""


def lane_jacobians_ref(scheme, st, u, k):
    """Every lane's Jacobians after step ``k``'s re-linearisation: when ``relin >
    0`` divides ``k``, those of the state map (``JA``, ``JB``, ``JW``) about the
    estimate ``st.xa`` and those of the outputs (``JC``, ``JHW``) about its
    prediction (:func:`predict_ref`), where the update linearises the outputs
    (:func:`jacobians_ref` at each point); else ``st``'s.  Returns a dict
    ``name -> (.., L)`` array."""
    model = ref_of(scheme)
    out = {f: np.array(getattr(st, f), copy=True) for f in JACOBIANS}
    if model.relin > 0 and k % model.relin == 0:
        n = st.xa.shape[0]
        for l in range(st.xa.shape[1]):
            Xp, _ = predict_ref(st.xa[:, l], np.zeros((n, n)), u[:, l], model)
            at_estimate = jacobians_ref(st.xa[:, l], u[:, l], model)
            at_prediction = jacobians_ref(Xp, u[:, l], model)
            for f, J, Jp in zip(JACOBIANS, at_estimate, at_prediction):
                out[f][:, :, l] = Jp if f in ("JC", "JHW") else J
    return out


def relinearised(model, jac, l):
    """``model`` with lane ``l``'s Jacobians: ``A = JA``, ``B = JB`` (so
    ``Phi(u)`` is built from it), ``G = JW C_d``, ``C = JC``,
    ``D_g = JHW C_d + D_z``."""
    if model.relin == 0:
        return model
    J = {f: jac[f][:, :, l] for f in JACOBIANS}
    gust = {} if not model.ng else dict(G=J["JW"] @ model.Cg,
                                        Dg=J["JHW"] @ model.Cg + model.Dz)
    return dataclasses.replace(model, A=J["JA"], B=J["JB"], C=J["JC"], **gust)


def innovation_ref(X, P, z, model):
    """Full innovation ``mu = z - C_aug X`` and ``S = C_aug P C_aug^T + R``."""
    _, _, C_aug = aug(model, np.zeros(3))
    mu = z - predicted_outputs(X, model)
    S = C_aug @ P @ C_aug.T + np.diag(model.r)
    return mu, S


def residuals_ref(X, P, z, model):
    """Eqs. (9)-(11): ``r_i = mu_i (C_i P C_i^T + R_ii)^-1 mu_i`` for q, n_x, n_z."""
    mu, S = innovation_ref(X, P, z, model)
    return np.array([mu[i] * mu[i] / S[i, i] for i in (OUT_Q, OUT_NX, OUT_NZ)])


def signature_ref(r_q, r_nx, r_nz, t_q, t_nx, variant):
    """Table 1, written clause by clause.

    ``variant="paper"`` is the table as printed; ``"swapped"`` exchanges the
    ``r_nz`` comparison of the third clause of both rows.
    """
    if variant == "paper":
        third_thrust, third_elevons = r_nz >= r_nx, r_nz < r_nx
    elif variant == "swapped":
        third_thrust, third_elevons = r_nz < r_nx, r_nz >= r_nx
    else:
        raise ValueError(variant)
    thrust = ((r_nx >= t_nx and r_q < t_q)
              or (r_nx >= t_nx and r_q >= t_q and third_thrust))
    elevons = ((r_nx < t_nx and r_q >= t_q)
               or (r_nx >= t_nx and r_q >= t_q and third_elevons))
    assert not (thrust and elevons), "Table 1 rows must be exclusive"
    if thrust:
        return RESET_THRUST
    if elevons:
        return RESET_ELEVONS
    return NO_RESET


def reset_ref(P, block, reset_var):
    """Section 3.2.2: zero the covariances of the block's fault parameters and set
    their variances; every other entry of ``P`` untouched."""
    P = np.array(P, dtype=float, copy=True)
    for i in BLOCKS.get(block, ()):
        P[i, :] = 0.0
        P[:, i] = 0.0
        P[i, i] = reset_var[i - N_X]
    return P


def reset_extra_ref(P, block, reset_g):
    """The extra states that go with a reset block (a sensor-aware design's
    output biases): each ``g`` with ``reset_g[block, g] > 0`` gets its
    row and column zeroed and that variance."""
    P = np.array(P, dtype=float, copy=True)
    if reset_g is None or not block:
        return P
    for g in np.flatnonzero(reset_g[block] > 0):
        i = N_AUG + g
        P[i, :] = 0.0
        P[:, i] = 0.0
        P[i, i] = reset_g[block, g]
    return P


def update_ref(X, P, z, model):
    """Batch update ``K = P C^T S^-1`` with the Joseph form of the covariance."""
    _, _, C = aug(model, np.zeros(3))
    R = np.diag(model.r)
    S = C @ P @ C.T + R
    K = np.linalg.solve(S, C @ P).T  # = P C^T S^-1 (S and P symmetric)
    X = X + K @ (z - predicted_outputs(X, model))
    I_KC = np.eye(P.shape[0]) - K @ C
    P = I_KC @ P @ I_KC.T + K @ R @ K.T
    return X, P


def constraints_ref(lo, hi, n=N_AUG):
    """``D X <= d`` of eq. (6): two rows (upper, lower) per fault parameter."""
    D = np.zeros((10, n))
    d = np.zeros(10)
    for j in range(5):
        D[2 * j, N_X + j] = 1.0
        d[2 * j] = hi[j]
        D[2 * j + 1, N_X + j] = -1.0
        d[2 * j + 1] = -lo[j]
    return D, d


def project_ref(X, lo, hi):
    """Active-set projection, eq. (8) literally: ``X + L (e - E X)``,
    ``L = E^T (E E^T)^-1`` over the violated rows of eq. (6)."""
    D, d = constraints_ref(lo, hi, len(X))
    violated = D @ X > d
    if not violated.any():
        return np.array(X, dtype=float, copy=True), 0
    E = D[violated]
    e = d[violated]
    L = E.T @ np.linalg.inv(E @ E.T)
    return X + L @ (e - E @ X), int(violated.sum())


def innovations_ref(X, P, z, model):
    """Signed normalised innovations ``mu_i / sqrt(S_ii)`` of q, n_x, n_z."""
    mu, S = innovation_ref(X, P, z, model)
    return np.array([mu[i] / np.sqrt(S[i, i]) for i in (OUT_Q, OUT_NX, OUT_NZ)])


def glr_ref(newest_first, m_min=1):
    """GLR of a mean shift over a window (``ftc_mc/core/shared/glr.py``), directly:
    ``max_{m >= m_min} (sum of the m newest e)^2 / m`` per channel;
    ``newest_first`` is (m, 3).  Zero while the window holds fewer than ``m_min``."""
    e = np.asarray(newest_first, dtype=float)
    if len(e) < m_min:
        return np.zeros(3)
    m = np.arange(1, len(e) + 1)[:, None]
    return np.max((np.cumsum(e, axis=0) ** 2 / m)[m_min - 1:], axis=0)


def filter_step_ref(X, P, u, z, model, stat=None, gate=None):
    """One estimator step in ``tests/single_trajectory.py::filter_step``'s order:
    predict, residuals, Table 1; on a reset, reset the block of ``P_{k|k}`` and
    predict again; update, projection.  ``stat``: a function of the signed
    innovations giving the decision statistics (the GLR test); ``None`` for
    the paper's one-step residuals.  ``gate``: a function of Table 1's block
    giving the block reset (the settling rule).

    Returns
    -------
    X, P, block, statistics, innovations
    """
    Xp, Pp = predict_ref(X, P, u, model)
    res = residuals_ref(Xp, Pp, z, model)
    e = innovations_ref(Xp, Pp, z, model)
    if stat is not None:
        res = stat(e)
    block = signature_ref(res[0], res[1], res[2], model.t_q, model.t_nx, model.variant)
    if gate is not None:
        block = gate(block)
    if block:
        P0 = reset_extra_ref(reset_ref(P, block, model.reset_var), block, model.reset_g)
        Xp, Pp = predict_ref(X, P0, u, model)
    X, P = update_ref(Xp, Pp, z, model)
    X, _ = project_ref(X, model.lo, model.hi)
    return X, P, block, res, e


# ------------------------------------------------------------------ belief
def normal_interval_ref(a, b):
    """``Phi(b) - Phi(a)`` with scipy's CDF; for ``a > 0`` the mirror identity
    ``Phi(-a) - Phi(-b)`` is used so the difference is not taken between two
    numbers close to one."""
    if a > 0:
        return norm.cdf(-a) - norm.cdf(-b)
    return norm.cdf(b) - norm.cdf(a)


def mode_likelihood_ref(bhat, var, lo, hi):
    """Eq. (12) with uniform ``f_m`` on each mode's box and independent Gaussian
    parameters: ``prod_j (Phi((hi-b)/s) - Phi((lo-b)/s)) / (hi - lo)``."""
    s = np.sqrt(var)
    out = np.ones(lo.shape[0])
    for m in range(lo.shape[0]):
        for j in range(len(bhat)):
            mass = normal_interval_ref((lo[m, j] - bhat[j]) / s[j], (hi[m, j] - bhat[j]) / s[j])
            out[m] *= mass / (hi[m, j] - lo[m, j])
    return out


def belief_update_ref(belief, TM, lo, hi, bhat, var):
    """Eqs. (13)-(14): ``b_pred = T_M b``; ``b_post = b_pred p / sum(b_pred p)``."""
    pred = TM @ belief
    lik = mode_likelihood_ref(bhat, var, lo, hi)
    post = pred * lik / np.sum(pred * lik)
    return post, int(np.argmax(post))


def log_normal_interval_ref(a, b):
    """``log(Phi(b) - Phi(a))`` for ``a <= b`` in log space: both bounds moved
    to the left tail by symmetry, then ``log Phi(b) + log1p(-Phi(a)/Phi(b))``
    with scipy's ``log_ndtr``; an interval across zero directly."""
    from scipy.special import log_ndtr, ndtr

    if a > 0:
        a, b = -b, -a
    if b <= 0:
        la, lb = log_ndtr(a), log_ndtr(b)
        return lb + np.log1p(-np.exp(la - lb))
    return np.log(ndtr(b) - ndtr(a))


def belief_update_log_ref(belief, TM, lo, hi, bhat, var):
    """Eqs. (12)-(14) as :func:`belief_update_ref`, in log space (the likelihoods
    of all four modes can underflow when the estimate is far from every box):
    ``log p(omega|m) = sum_j log(Phi(..) - Phi(..)) - log(hi - lo)``, posterior by
    log-sum-exp."""
    from scipy.special import logsumexp

    s = np.sqrt(var)
    loglik = np.array([sum(log_normal_interval_ref((lo[m, j] - bhat[j]) / s[j],
                                                   (hi[m, j] - bhat[j]) / s[j])
                           - np.log(hi[m, j] - lo[m, j]) for j in range(len(bhat)))
                       for m in range(lo.shape[0])])
    with np.errstate(divide="ignore"):
        logpost = np.log(TM @ belief) + loglik
    post = np.exp(logpost - logsumexp(logpost))
    return post, int(np.argmax(post))


# -------------------------------------------------------------- excitation
def doublet_ref(k, half_steps, amplitude):
    """Doublet of Fig. 4: two alternating steps ``+A`` then ``-A``."""
    seq = np.concatenate([np.full(half_steps, amplitude), np.full(half_steps, -amplitude)])
    return float(seq[k]) if 0 <= k < len(seq) else 0.0


def signal_3211_ref(k, unit_steps, amplitude):
    """3211 of Fig. 4: alternating steps of durations 3, 2, 1, 1 units."""
    seq = np.concatenate([np.full(n * unit_steps, sign * amplitude)
                          for n, sign in ((3, 1.0), (2, -1.0), (1, 1.0), (1, -1.0))])
    return float(seq[k]) if 0 <= k < len(seq) else 0.0


def saturate_ref(U, s, A, lo, hi):
    """Eq. (15): clip ``U`` to ``[lo + A, hi - A]``, add ``s``, clip to ``[lo, hi]``."""
    return float(np.clip(np.clip(U, lo + A, hi - A) + s, lo, hi))


# ------------------------------------------------------------- X8 nonlinear
X8_PARAMS = ("mass", "Jy", "S", "c", "rho", "g", "CL0", "CLa", "CLq", "CLde", "CD0",
             "CDa", "CDa2", "CDde2", "Cm0", "Cma", "Cmq", "Cmde", "S_prop", "k_motor",
             "C_prop", "tau_thrust", "tau_elevon", "V0", "gamma0")
"""Names of the packed parameter vector, in ``model.dynamics.pack_parameters``'s order."""


def rotation(angle):
    """2-D rotation by ``angle`` [rad]: ``[[cos, -sin], [sin, cos]]``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def x8_forces_ref(x, p, wind):
    """Body-axis force ``[X, Z]`` [N] (aerodynamic + thrust), moment ``M`` [N m],
    ``alpha`` [rad], ``Va`` [m/s] of the X8 (``ftc_mc/model/airframe.py``), air-relative.

    Lift and drag are formed in wind axes and rotated into body axes by the angle
    of attack: ``[X, Z]_aero = R(alpha) [-D, -L]``.
    """
    a = dict(zip(X8_PARAMS, p))
    v_air = np.asarray(x[:2]) - np.asarray(wind[:2])
    q_air = x[2] - wind[2]
    Va = float(np.hypot(v_air[0], v_air[1]))
    alpha = float(np.arctan2(v_air[1], v_air[0]))
    de = np.mean(x[7:9])
    qhat = a["c"] * q_air / (2.0 * Va)
    CL = a["CL0"] + a["CLa"] * alpha + a["CLq"] * qhat + a["CLde"] * de
    CD = np.polyval([a["CDa2"], a["CDa"], a["CD0"]], alpha) + a["CDde2"] * de ** 2
    Cm = a["Cm0"] + a["Cma"] * alpha + a["Cmq"] * qhat + a["Cmde"] * de
    qbar = 0.5 * a["rho"] * Va ** 2
    lift, drag = qbar * a["S"] * CL, qbar * a["S"] * CD
    Vd = Va + x[6] * (a["k_motor"] - Va)  # propeller discharge speed
    thrust = 0.5 * a["rho"] * a["S_prop"] * a["C_prop"] * Vd * (Vd - Va)
    F = rotation(alpha) @ np.array([-drag, -lift]) + np.array([thrust, 0.0])
    return F, qbar * a["S"] * a["c"] * Cm, alpha, Va


def x8_derivatives_ref(x, cmd, p, wind):
    """``dx/dt`` of the X8 (9 states): body-axis Newton-Euler with the Coriolis
    term ``q x [u, w]``, gravity rotated into body axes, the position error of the
    glide-path reference point and three first-order actuators."""
    a = dict(zip(X8_PARAMS, p))
    x = np.asarray(x, dtype=float)
    F, M, _, _ = x8_forces_ref(x, p, wind)
    vel = x[:2]
    q, theta = x[2], x[5]
    gravity = a["g"] * np.array([-np.sin(theta), np.cos(theta)])
    coriolis = q * np.array([-vel[1], vel[0]])
    accel = F / a["mass"] + gravity + coriolis
    # body -> (forward, down) earth axes: rotation by -theta
    pos_rate = rotation(-theta) @ vel - a["V0"] * np.array([np.cos(a["gamma0"]),
                                                            -np.sin(a["gamma0"])])
    tau = np.array([a["tau_thrust"], a["tau_elevon"], a["tau_elevon"]])
    act = (np.asarray(cmd) - x[6:9]) / tau
    return np.concatenate([accel, [M / a["Jy"]], pos_rate, [q], act])


def x8_outputs_ref(x, p, wind):
    """The 12 outputs: the first six states, specific forces over ``g``
    (``n_z`` up), ``alpha``, ``gamma = theta - alpha``, ``CAS = Va`` (sea level)
    and ``Va``."""
    a = dict(zip(X8_PARAMS, p))
    F, _, alpha, Va = x8_forces_ref(x, p, wind)
    mg = a["mass"] * a["g"]
    return np.concatenate([x[:6], [F[0] / mg, -F[1] / mg, alpha, x[5] - alpha, Va, Va]])


def rk4_ref(x, cmd, p, wind, dt, n_sub):
    """``n_sub`` classical RK4 steps over ``dt`` with commands and wind held."""
    def f(s):
        return x8_derivatives_ref(s, cmd, p, wind)

    h = dt / n_sub
    x = np.array(x, dtype=float)
    for _ in range(n_sub):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


# ----------------------------------------------------------------- control
# Controllers of section 4.1 and the selection of section 4.2; the commands are
# deviations from trim [throttle, rad, rad].
C0, C1, C2 = 0, 1, 2  # nominal, engine fault, elevon fault


def engine_gain_ref(tables, b0, b1):
    """Theorem 4.1's ``K(b0, b1)`` (3, 9) and ``k(b0, b1)`` (3,), bilinear in the
    offline tables (scipy's ``RegularGridInterpolator``), the coordinates clamped
    to the grid (section 4.1.5)."""
    from scipy.interpolate import RegularGridInterpolator

    g0, g1 = tables.b0_grid, tables.b1_grid
    point = [[np.clip(b0, g0[0], g0[-1]), np.clip(b1, g1[0], g1[-1])]]
    K = RegularGridInterpolator((g0, g1), tables.K)(point)[0]
    k = RegularGridInterpolator((g0, g1), tables.k)(point)[0]
    return K, k


def controller_command_ref(c, X, K, tables, u0):
    """Command of controller ``c`` from the augmented estimate ``X`` (no saturation).

    c0: ``-K x`` (eq. 19).  c1: ``-K(b0_T, b1_T) x - k(b0_T, b1_T)`` (eq. 44).
    c2: thrust ``-K_1 x``; elevons the minimum-norm ``U`` with
    ``Phi(U) = 2 K_2 x + b0_e - b1_L u0_L - b1_R u0_R + a . U = 0``,
    ``a = (1 - b1_L, 1 - b1_R)`` (eqs. 20-24), by the pseudo-inverse.
    """
    x = np.asarray(X[:N_X])
    if c == C1:
        Kc, kc = engine_gain_ref(tables, X[B0_T], X[B1_T])
        return -Kc @ x - kc
    U = -K @ x
    if c == C2:
        a = np.array([[1.0 - X[B1_L], 1.0 - X[B1_R]]])
        rhs = 2.0 * (K[1] @ x) + X[B0_E] - X[B1_L] * u0[1] - X[B1_R] * u0[2]
        U[1:] = (np.linalg.pinv(a) @ np.array([-rhs]))
    return U


def ref_of(scheme):
    """A :class:`RefModel` holding the arrays of ``scheme.filter`` and
    ``scheme.detection`` (the builders are checked in test_core_vs_naive)."""
    fm, det = scheme.filter, scheme.detection
    gust = fm.G.shape[1] > 0
    return RefModel(A=fm.A, B=fm.B, C=fm.C, u0=fm.u0, q=fm.q_diag, r=fm.r_diag, lo=fm.lo,
                    hi=fm.hi, t_q=det.t_q, t_nx=det.t_nx,
                    variant="swapped" if det.swapped else "paper", reset_var=det.reset_var,
                    G=fm.G if gust else None, Ad=fm.Ad if gust else None,
                    Dg=fm.Dg if gust else None, Qg=fm.Qg if gust else None,
                    test=("one_step", "glr")[det.test], window=int(det.window),
                    min_window=int(det.min_window), clip=float(det.clip),
                    settle=int(det.settle),
                    startup=int(det.startup),
                    nl=int(fm.nl), p=fm.p, x0=fm.x0, y0=fm.y0,
                    Cg=fm.Cg if gust else None, n_sub=int(fm.n_sub), dt=float(fm.dt),
                    relin=int(fm.relin), Dz=fm.Dz if gust else None,
                    reset_g=fm.reset_g if gust else None)


def horizon_cost_ref(c, X, P, scheme):
    """Eq. (45): ``I(c) = sum_{k'=1..H} alpha^k' (x' Q_lqr x + u' R_lqr u)`` along
    the prediction with controller ``c`` in the loop: saturated command (eq. 16),
    prediction (eq. 5), update with the predicted measurement (zero
    innovation), projection (eq. 8).  Returns ``I, X_{k+H}, P_{k+H|k+H}``."""
    # the selection predicts with the paper's model (a gust-aware filter's gust
    # states are left out, core/stages.reconfigure)
    model = dataclasses.replace(ref_of(scheme), G=None, Ad=None, Dg=None, Qg=None, nl=0)
    ctl, rc = scheme.controller, scheme.reconfig
    _, _, C_aug = aug(model, np.zeros(3))
    cost = 0.0
    for step in range(1, rc.horizon + 1):
        U = controller_command_ref(c, X, ctl.K, scheme.engine, model.u0)
        U = np.clip(U, ctl.lo_dev, ctl.hi_dev)
        X, P = predict_ref(X, P, U, model)
        X, P = update_ref(X, P, C_aug @ X, model)
        X, _ = project_ref(X, model.lo, model.hi)
        x = X[:N_X]
        cost += rc.alpha ** step * (x @ np.diag(rc.q_lqr) @ x + U @ np.diag(rc.r_lqr) @ U)
    return cost, X, P


def controller_objectives_ref(current, X, P, belief, scheme):
    """Eq. (47) for each controller ``a``: ``I(a) + sum_m b_{k+H}(m) (J^N(m, a) +
    P(c, a))`` with the belief updated on the predicted fault parameters."""
    bs, rc = scheme.belief, scheme.reconfig
    obj = np.zeros(3)
    for a in range(3):
        cost, Xh, Ph = horizon_cost_ref(a, X, P, scheme)
        b, _ = belief_update_log_ref(belief, bs.TM, bs.lo, bs.hi, Xh[N_X:],
                                     np.diag(Ph)[N_X:])
        obj[a] = cost + b @ (rc.JN[:, a] + rc.penalty[current, a])
    return obj


def select_controller_ref(current, X, P, belief, scheme):
    """The controller with the smallest objective (eq. 47); ``current`` if none is
    finite.  Returns the controller and the objectives."""
    obj = controller_objectives_ref(current, X, P, belief, scheme)
    if not np.any(np.isfinite(obj)):
        return current, obj
    return int(np.nanargmin(obj)), obj


# ------------------------------------------------------------ trial stages
# Twins of the stage kernels of ftc_mc.core.longitudinal.stages and ftc_mc.core.longitudinal.plant, on
# copies: each takes the lane state and returns what the stage writes.  Lane l
# of every array is one trial (lane index last).
NO_SIGNAL = -(1 << 40)
STATUS = {"ok": 0, "nonfinite": 1, "not_psd": 2, "airspeed": 3, "alpha": 4}


def running_ref(k, start, length):
    return start <= k < start + length


def commands_ref(scheme, st, k):
    """Commands ``u_k`` (3, L) and the excitation record (4, L): doublet value,
    3211 value, 1.0 where each starts at ``k`` (eqs. 15-25, 44)."""
    ctl, exc, fm = scheme.controller, scheme.excitation, scheme.filter
    L = st.xa.shape[1]
    u = np.zeros((3, L))
    out = np.zeros((4, L))
    d_len, s_len = 2 * exc.doublet_half, 7 * exc.s3211_unit
    for l in range(L):
        X = st.xa[:, l]
        if scheme.reconfig.kind == 0:
            U = -ctl.K @ X[:N_X]
        else:
            U = controller_command_ref(int(st.cur[l]), X, ctl.K, scheme.engine, fm.u0)
        sd, A_d = 0.0, 0.0
        if running_ref(k, st.d_start[l], d_len):
            sd = doublet_ref(k - st.d_start[l], exc.doublet_half, st.d_amp[l])
            A_d = st.d_amp[l]
        s, A_s = 0.0, 0.0
        if running_ref(k, st.s_start[l], s_len):
            s = signal_3211_ref(k - st.s_start[l], exc.s3211_unit, st.s_amp[l])
            if st.cur[l] == C2:  # eq. 23, with the design's floor
                g = 1.0 - X[B1_L]
                if exc.s3211_floor > 0.0:
                    g = max(g, exc.s3211_floor)
                s = g * s
            A_s = st.s_amp[l]
        sig, amp = (sd, s, -s), (A_d, A_s, A_s)
        for i in range(3):
            u[i, l] = saturate_ref(U[i], sig[i], amp[i], ctl.lo_dev[i], ctl.hi_dev[i])
        out[:, l] = [sd, s, float(k == st.d_start[l]), float(k == st.s_start[l])]
    return u, out


def dryden_ref(turb, Ad, Bd, Cd, state, eta):
    """One step of a discrete Dryden shaping filter on every lane: the gust held
    over the step ``Cd s_k``, the next state ``Ad s_k + Bd eta_k`` and the gust at
    the next sample; in still air (``turb`` 0) zero gusts and the state kept."""
    if not turb:
        L = state.shape[1]
        return np.zeros((Cd.shape[0], L)), state.copy(), np.zeros((Cd.shape[0], L))
    nxt = Ad @ state + Bd @ eta
    return Cd @ state, nxt, Cd @ nxt


def actuator_model_ref(u, u0, lo, hi, b0, b1, fp, k_on, k, dt, alpha, uhist, uprev):
    """The actuators' generic fault model and eq. (2) on every lane, vectorised
    over actuators and lanes (``docs/guides/fault-kinds.md``): the command
    ``d`` steps ago (trim before step 0), plus ``A sin(2 pi f t + phi) + r t``,
    blended toward the floating angle ``delta_f0 + k_f alpha`` with weight
    ``w`` and held in the travel when any of these acts, then within
    ``R dt`` of the last followed command.  Returns ``(e, uhist, uprev)``
    (updated copies)."""
    from ftc_mc.conventions import FAULT_PARAM_NAMES

    P = dict(zip(FAULT_PARAM_NAMES, fp))  # each (3, L)
    uhist = uhist.copy()
    H = uhist.shape[0]
    uhist[k % H] = u
    d = P["delay_steps"].astype(int)
    past = np.take_along_axis(uhist, ((k - d) % H)[None], axis=0)[0]
    c = np.where(d > 0, np.where(k - d >= 0, past, 0.0), u)
    t = (k - k_on) * dt
    amp, run, w = P["osc_amp"], P["runaway_rate"], P["float_weight"]
    acts = (amp != 0) | (run != 0) | (w != 0)
    moved = c + (amp * np.sin(2 * np.pi * P["osc_freq_hz"] * t + P["osc_phase"]) + run * t)
    floating = P["float_angle"] + P["float_gain"] * alpha[None, :] - u0[:, None]
    moved = np.where(w != 0, (1 - w) * moved + w * floating, moved)
    moved = np.clip(moved, lo[:, None], hi[:, None])
    c = np.where(acts, moved, c)
    step = P["rate_limit"] * dt
    c = np.where(c > uprev + step, uprev + step, np.where(c < uprev - step, uprev - step, c))
    e = b0 + (1.0 - b1) * c - b1 * u0[:, None]
    return e, uhist, c


def truth_step_ref(scheme, flight, inp, k, st, u, alpha_last=None):
    """The truth over step ``k``: effect (eq. 2), Dryden gust, linear (eq. 1) or
    nonlinear (RK4) plant, measurement and air data; ``alpha_last`` the true
    angle of attack of the last sample (zeros when omitted, as a fresh work
    area's).  Returns a dict with ``x``, ``gust``, ``e``, ``wind``,
    ``wind_next``, ``z``, ``va``, ``alpha``, ``zhold``, ``uhist``, ``uprev``."""
    from ftc_mc.model.faults import effect

    fm, pl, val = scheme.filter, flight.plant, flight.validity
    L = st.x.shape[1]
    ev = int(np.searchsorted(inp.k_switch, k, side="right")) - 1
    e, uhist, uprev = actuator_model_ref(
        u, fm.u0, scheme.controller.lo_dev, scheme.controller.hi_dev, inp.b0[ev],
        inp.b1[ev], inp.fp[ev], inp.k_switch[ev], k, pl.dt,
        np.zeros(L) if alpha_last is None else alpha_last, st.uhist,
        st.uprev)
    wind, gust, wind_next = dryden_ref(pl.turb, pl.Ad, pl.Bd, pl.Cd, st.gust,
                                       inp.eta[k] if pl.turb else None)
    if pl.kind == 0:
        x = fm.A @ st.x + fm.B @ e + pl.Bw @ wind + inp.w[k]
        z = fm.C @ x + pl.Dw @ wind_next + inp.v[k]
        va = val.va_trim + fm.C[OUT_VA] @ x + pl.Dw[OUT_VA] @ wind_next
        alpha = val.alpha_trim + fm.C[OUT_ALPHA] @ x + pl.Dw[OUT_ALPHA] @ wind_next
    else:
        x = np.zeros_like(st.x)
        z = np.zeros((12, L))
        va, alpha = np.zeros(L), np.zeros(L)
        for l in range(L):
            xabs = rk4_ref(pl.x0 + st.x[:, l], fm.u0 + e[:, l], pl.p, wind[:, l], pl.dt,
                           pl.n_sub) + inp.w[k][:, l]
            x[:, l] = xabs - pl.x0
            y = x8_outputs_ref(xabs, pl.p, wind_next[:, l])
            z[:, l] = y - pl.y0 + inp.v[k][:, l]
            va[l], alpha[l] = y[OUT_VA], y[OUT_ALPHA]
    zhold = st.zhold.copy()
    for l in range(L):
        z[:, l], zhold[l] = sensor_fault_ref(
            z[:, l], inp.v[k][:, l], zhold[l], k, pl.dt, int(inp.sensor_out[l]),
            int(inp.sensor_kind[l]), float(inp.sensor_size[l]), int(inp.sensor_k[l]))
    return dict(x=x, gust=gust, e=e, wind=wind, wind_next=wind_next, z=z, va=va,
                alpha=alpha, zhold=zhold, uhist=uhist, uprev=uprev)



def sensor_fault_ref(z, v, zhold, k, dt, out, kind, size, k_onset):
    """One lane's measurement ``z_{k+1}`` (12,) with its sensor fault on output
    ``out`` (-1: none), and the updated last healthy value: before the onset the
    output passes and is remembered; from it on, bias adds ``size``, drift
    ``size * (k + 1 - k_onset) * dt``, stuck holds the remembered value, noise
    scales the output's noise ``v`` by ``size``.  Returns ``(z, zhold)``."""
    z = np.array(z, dtype=float, copy=True)
    if out < 0:
        return z, zhold
    if k < k_onset:
        return z, float(z[out])
    name = ("bias", "stuck", "drift", "noise")[kind]
    if name == "bias":
        z[out] = z[out] + size
    elif name == "drift":
        z[out] = z[out] + size * (k + 1 - k_onset) * dt
    elif name == "stuck":
        z[out] = zhold
    else:
        z[out] = z[out] + (size - 1.0) * v[out]
    return z, zhold


def filter_update_ref(scheme, st, u, z, k=0, relinearised_already=False, with_innov=False):
    """Every lane's filter step (:func:`filter_step_ref`) and the running maxima
    of the decision statistics of ``r_q``, ``r_nx``; with the GLR test the
    window (``st.ebuf`` row ``k % W``, ``st.ecount``) takes this step's
    innovations and a reset empties it.  With ``relin > 0`` each lane's step
    uses its Jacobians (:func:`lane_jacobians_ref`, or ``st``'s as they are
    with ``relinearised_already``).  Returns ``xa, P, res, block, rmax,
    ebuf, ecount, last_k, last_block`` and, ``with_innov``, the signed normalised
    innovations (3, L)."""
    model = ref_of(scheme)
    jac = ({f: getattr(st, f) for f in JACOBIANS} if relinearised_already
           else lane_jacobians_ref(scheme, st, u, k))
    L = st.xa.shape[1]
    xa, P = st.xa.copy(), st.P.copy()
    ebuf, ecount = st.ebuf.copy(), st.ecount.copy()
    last_k, last_block = st.last_k.copy(), st.last_block.copy()
    res, block = np.zeros((3, L)), np.zeros(L, dtype=np.int64)
    innov = np.zeros((3, L))
    W = ebuf.shape[0]
    for l in range(L):
        stat = None
        if model.test == "glr":
            def stat(e, l=l):
                ebuf[k % W, :, l] = np.clip(e, -model.clip, model.clip)
                ecount[l] = min(ecount[l] + 1, W)
                return glr_ref(ebuf[(k - np.arange(ecount[l])) % W, :, l], model.min_window)
        gate = None
        if model.settle > 0 or k < model.startup:
            def gate(b, l=l):  # the other block, within `settle` steps of a reset;
                recent = k - last_k[l] < model.settle  # nothing before the start-up
                if k < model.startup:
                    return 0
                return 0 if (b and last_block[l] and b != last_block[l] and recent) else b
        xa[:, l], P[:, :, l], block[l], res[:, l], innov[:, l] = filter_step_ref(
            st.xa[:, l], st.P[:, :, l], u[:, l], z[:, l], relinearised(model, jac, l), stat,
            gate)
        if model.test == "glr" and block[l] or k < model.startup:
            ecount[l] = 0
        if model.settle > 0 and block[l]:
            last_k[l], last_block[l] = k, block[l]
    rmax = np.maximum(st.rmax, res[:2])
    if with_innov:
        return xa, P, res, block, rmax, ebuf, ecount, last_k, last_block, innov
    return xa, P, res, block, rmax, ebuf, ecount, last_k, last_block


def positive_definite_ref(P):
    """``P + 1e-12 max|diag| I`` has only positive eigenvalues (finite ``P``)."""
    M = P + 1e-12 * np.max(np.abs(np.diag(P))) * np.eye(P.shape[0])
    return bool(np.all(np.isfinite(M)) and np.linalg.eigvalsh(M).min() > 0.0)


def check_validity_ref(validity, st, kn, va, alpha, status, stop_k):
    """Which live lanes stop, and why (precedence: not finite, covariance not
    positive definite on a check step, airspeed, angle of attack).  Returns
    ``alive, status, stop_k``."""
    alive, status, stop_k = st.alive.copy(), status.copy(), stop_k.copy()
    for l in np.flatnonzero(st.alive):
        P = st.P[:, :, l]
        if not (np.all(np.isfinite(st.xa[:, l])) and np.all(np.isfinite(np.diag(P)))
                and np.isfinite(va[l]) and np.isfinite(alpha[l])):
            why = "nonfinite"
        elif kn % validity.psd_every == 0 and not positive_definite_ref(P):
            why = "not_psd"
        elif not validity.va_min <= va[l] <= validity.va_max:
            why = "airspeed"
        elif not validity.alpha_min <= alpha[l] <= validity.alpha_max:
            why = "alpha"
        else:
            continue
        alive[l], status[l], stop_k[l] = False, STATUS[why], kn
    return alive, status, stop_k


def handle_resets_ref(exc, st, kn, block, res, reset_k, reset_block, reset_res, n_resets):
    """Reset records and excitation requests (sections 3.2.3, 4.1.1).  Returns a
    dict of the updated ``d_start``, ``s_start``, ``d_amp``, ``s_amp``, ``recheck``
    and record arrays."""
    out = dict(d_start=st.d_start.copy(), s_start=st.s_start.copy(),
               d_amp=st.d_amp.copy(), s_amp=st.s_amp.copy(),
               recheck=st.recheck.copy(), reset_k=reset_k.copy(),
               reset_block=reset_block.copy(), reset_res=reset_res.copy(),
               n_resets=n_resets.copy())
    d_len, s_len = 2 * exc.doublet_half, 7 * exc.s3211_unit
    for l in range(st.xa.shape[1]):
        if st.alive[l] and block[l] in (RESET_THRUST, RESET_ELEVONS):
            m = out["n_resets"][l]
            if m < reset_k.shape[0]:
                out["reset_k"][m, l] = kn
                out["reset_block"][m, l] = block[l]
                out["reset_res"][m, :, l] = res[:, l]
            out["n_resets"][l] = m + 1
            if block[l] == RESET_THRUST:
                if not running_ref(kn, out["d_start"][l], d_len):
                    out["d_start"][l], out["d_amp"][l] = kn, exc.doublet_amp
                out["recheck"][l] = kn + exc.resend_delay
            elif not running_ref(kn, out["s_start"][l], s_len):
                out["s_start"][l], out["s_amp"][l] = kn, exc.s3211_amp
        if out["recheck"][l] == kn:
            out["recheck"][l] = -1
            if st.xa[B1_T, l] > exc.resend_b1 and not running_ref(kn, out["d_start"][l],
                                                                  d_len):
                out["d_start"][l], out["d_amp"][l] = kn, exc.doublet_amp
    if exc.policy != POLICY_NONE:
        policy_signals_ref(exc, st, kn, res, out)
    return out


POLICY_NONE, POLICY_PERIODIC, POLICY_AMBIGUOUS = 0, 1, 2
"""``Excitation.policy`` codes."""


def policy_signals_ref(exc, st, kn, res, out):
    """The design's excitation policy at step ``kn``, in place on ``out``'s
    ``d_start``, ``s_start``, ``d_amp`` and ``s_amp`` (those after the reset
    requests of the step), each signal at the policy's amplitude.

    On a live lane with no signal on, whose belief gives no fault mode
    (every mode but the first) ``pause_belief`` or more: periodic, the doublet when ``kn`` is the
    phase plus whole periods, the 3211 when it is half a period (rounded down)
    after such a step; ambiguous, when the last start of either signal lies at
    least a period back and the most probable mode is below ``belief_max`` or
    ``r_q`` or ``r_nx`` is at least ``suspect``: the 3211 after a doublet, else
    the doublet."""
    d_len, s_len = 2 * exc.doublet_half, 7 * exc.s3211_unit
    d_start, s_start = out["d_start"], out["s_start"]

    def send(signal, l):
        if signal == "d":
            d_start[l], out["d_amp"][l] = kn, exc.policy_doublet_amp
        else:
            s_start[l], out["s_amp"][l] = kn, exc.policy_s3211_amp

    for l in range(len(d_start)):
        on = running_ref(kn, d_start[l], d_len) or running_ref(kn, s_start[l], s_len)
        if not st.alive[l] or on or st.belief[1:, l].max() >= exc.pause_belief:
            continue
        if exc.policy == POLICY_PERIODIC:
            since = kn - exc.phase
            if since % exc.period == 0:
                send("d", l)
            elif (since - exc.period // 2) % exc.period == 0:
                send("s", l)
        elif exc.policy == POLICY_AMBIGUOUS:
            last = max(d_start[l], s_start[l])
            unsure = st.belief[:, l].max() < exc.belief_max
            high = res[0, l] >= exc.suspect or res[1, l] >= exc.suspect
            if kn - last >= exc.period and (unsure or high):
                send("s" if d_start[l] > s_start[l] else "d", l)


def record_cost_ref(track, k_switch, kn, x, u, alive, cost, marks):
    """The cost sums after a truth step: for each live lane, the
    glide path's cross-track error ``c = x sin(gamma0) + z cos(gamma0)`` of the
    true state ``x`` adds ``c^2`` to row 0 and raises row 1 to ``|c|``; each
    command adds its square to rows 2-4.  The height marks: a live
    lane's ``z`` goes to ``marks[1]``, and to ``marks[0]`` when the step reached
    ``kn`` is the switch ``k_switch``.  Returns updated copies of ``cost`` and
    ``marks``."""
    cost = cost.copy()
    marks = marks.copy()
    live = np.asarray(alive, dtype=bool)
    marks[1, live] = x[track.iz, live]
    if kn == k_switch:
        marks[0, live] = x[track.iz, live]
    c = x[track.ix] * track.sin_g + x[track.iz] * track.cos_g
    cost[0, live] += c[live] ** 2
    cost[1, live] = np.maximum(cost[1, live], np.abs(c[live]))
    cost[2:, live] += u[:, live] ** 2
    return cost, marks


def record_step_ref(k, st, u, res, exc, wind, block, hist, z, innov):
    """The history row ``k`` (only while ``k`` is below the history length)."""
    hist = {f: v.copy() for f, v in hist.items()}
    if k < hist["hist_x"].shape[0]:
        hist["hist_x"][k] = st.x
        hist["hist_xa"][k] = st.xa[:N_AUG]
        hist["hist_pdiag"][k] = np.diagonal(st.P)[:, N_X:N_AUG].T
        hist["hist_u"][k] = u
        hist["hist_res"][k] = res
        hist["hist_exc"][k] = exc
        hist["hist_wind"][k] = wind
        hist["hist_block"][k] = block
        hist["hist_z"][k] = z
        hist["hist_innov"][k] = innov
    return hist


def reconfigure_ref(scheme, timing, inp, st, kn, period, rec):
    """Belief update (eqs. 12-14), controller selection (eqs. 45-47) when
    reconfiguring, detection time.  Returns a dict of the new ``belief``,
    ``cur`` and the written record arrays."""
    bs = scheme.belief
    out = dict(belief=st.belief.copy(), cur=st.cur.copy(), rec_belief=rec.belief.copy(),
               rec_bhat=rec.bhat.copy(), controller=rec.controller.copy(),
               detect_k=rec.detect_k.copy())
    for l in range(st.xa.shape[1]):
        # the paper's 14 states (a gust-aware filter's gust states are not used here)
        X, P = st.xa[:N_AUG, l], st.P[:N_AUG, :N_AUG, l]
        if bs.lo.shape[1] != N_AUG - N_X:  # the 6-DOF selection's belief: updated by its stage
            b, best = st.belief[:, l].copy(), int(np.argmax(st.belief[:, l]))
        else:
            b, best = belief_update_log_ref(st.belief[:, l], bs.TM, bs.lo, bs.hi, X[N_X:],
                                            np.diag(P)[N_X:])
        out["belief"][:, l] = out["rec_belief"][period, :, l] = b
        out["rec_bhat"][period, :, l] = X[N_X:]
        if scheme.reconfig.kind != 0:
            out["cur"][l], _ = select_controller_ref(int(st.cur[l]), X, P, b, scheme)
        out["controller"][period, l] = out["cur"][l]
        mp = inp.mode_post[l]
        if (st.alive[l] and kn > timing.k_fault and out["detect_k"][l] < 0 and best == mp
                and b[mp] >= timing.detect_prob):
            out["detect_k"][l] = kn
    return out


def advance_ref(scheme, flight, inp, rec, st, k0, k1):
    """The trial loop from step ``k0`` to ``k1`` chaining the stage twins; ``rec``
    and ``st`` are namedtuples of arrays, returned as updated copies."""
    st = type(st)(*(np.array(a, copy=True) for a in st))
    rec = type(rec)(*(np.array(a, copy=True) for a in rec))
    every = flight.timing.reconf_every
    alpha_last = np.zeros(st.x.shape[1])  # a fresh work area's (the float reads it)
    for k in range(k0, k1):
        kn = k + 1
        u, exc = commands_ref(scheme, st, k)
        tr = truth_step_ref(scheme, flight, inp, k, st, u, alpha_last)
        alpha_last = tr["alpha"]
        st.x[:], st.gust[:], st.zhold[:] = tr["x"], tr["gust"], tr["zhold"]
        st.uhist[:], st.uprev[:] = tr["uhist"], tr["uprev"]
        rec.cost[:], rec.z_switch_last[:] = record_cost_ref(
            flight.track, flight.timing.k_fault, kn, st.x, u, st.alive, rec.cost,
            rec.z_switch_last)
        for f, J in lane_jacobians_ref(scheme, st, u, k).items():
            getattr(st, f)[:] = J
        xa, P, res, block, rmax, ebuf, ecount, last_k, last_block, innov = filter_update_ref(
            scheme, st, u, tr["z"], k, relinearised_already=True, with_innov=True)
        st.xa[:], st.P[:], st.rmax[:] = xa, P, rmax
        st.ebuf[:], st.ecount[:] = ebuf, ecount
        st.last_k[:], st.last_block[:] = last_k, last_block
        alive, status, stop_k = check_validity_ref(flight.validity, st, kn, tr["va"],
                                                   tr["alpha"], rec.status, rec.stop_k)
        st.alive[:], rec.status[:], rec.stop_k[:] = alive, status, stop_k
        out = handle_resets_ref(scheme.excitation, st, kn, block, res, rec.reset_k,
                                rec.reset_block, rec.reset_res, rec.n_resets)
        for f in ("d_start", "s_start", "d_amp", "s_amp", "recheck"):
            getattr(st, f)[:] = out[f]
        for f in ("reset_k", "reset_block", "reset_res", "n_resets"):
            getattr(rec, f)[:] = out[f]
        hist = record_step_ref(k, st, u, res, exc, tr["wind"], block,
                               {f: getattr(rec, f) for f in rec._fields
                                if f.startswith("hist_")}, tr["z"], innov)
        for f, v in hist.items():
            getattr(rec, f)[:] = v
        if kn % every == 0:
            period = kn // every - 1
            out = reconfigure_ref(scheme, flight.timing, inp, st, kn, period, rec)
            st.belief[:], st.cur[:] = out["belief"], out["cur"]
            rec.belief[:], rec.bhat[:] = out["rec_belief"], out["rec_bhat"]
            rec.controller[:], rec.detect_k[:] = out["controller"], out["detect_k"]
    rec.xa_end[:] = st.xa[:rec.xa_end.shape[0]]
    return rec, st
