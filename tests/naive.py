"""Slow plain-NumPy reference twins of the :mod:`ftc_mc.core` kernels.

STUMPY style: every jitted kernel has a twin here, written from the paper's
equations in their textbook form (full matrices, explicit inverses, ``scipy``
normal CDF), deliberately *not* by transcribing the kernels.  The kernels exploit
structure (no ``A_aug`` is ever formed, sequential scalar updates, logarithms,
in-place work arrays); the twins do none of that, so an agreement to round-off
is evidence that the structure was exploited correctly.

Paper: "Reconfiguration control method for non-redundant actuator faults on UAV"
(``../shared/seeds/000_6d7db61963b544ed.txt``), sections 2-3 and 5.1.

Conventions (DESIGN.md section 3, ``ftc_mc.model.faults``): augmented state
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
        ``"paper"`` or ``"swapped"`` (DESIGN.md section 4).
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
    builders of :mod:`ftc_mc.estimator` are checked too.
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
    """``A_aug(u)``, ``B_aug``, ``C_aug`` of eq. (5), formed explicitly."""
    return augmented(model.A, model.B, model.C, u, model.u0)


# ------------------------------------------------------------------ filter
def predict_ref(X, P, u, model):
    """Eq. (5) time update: ``X = A_aug X + B_aug u``, ``P = A_aug P A_aug^T + Q``."""
    A_aug, B_aug, _ = aug(model, u)
    X = A_aug @ X + B_aug @ u
    P = A_aug @ P @ A_aug.T + np.diag(model.q)
    return X, P


def innovation_ref(X, P, z, model):
    """Full innovation ``mu = z - C_aug X`` and ``S = C_aug P C_aug^T + R``."""
    _, _, C_aug = aug(model, np.zeros(3))
    mu = z - C_aug @ X
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


def update_ref(X, P, z, model):
    """Batch update ``K = P C^T S^-1`` with the Joseph form of the covariance."""
    _, _, C = aug(model, np.zeros(3))
    R = np.diag(model.r)
    S = C @ P @ C.T + R
    K = np.linalg.solve(S, C @ P).T  # = P C^T S^-1 (S and P symmetric)
    X = X + K @ (z - C @ X)
    I_KC = np.eye(P.shape[0]) - K @ C
    P = I_KC @ P @ I_KC.T + K @ R @ K.T
    return X, P


def constraints_ref(lo, hi):
    """``D X <= d`` of eq. (6): two rows (upper, lower) per fault parameter."""
    D = np.zeros((10, N_AUG))
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
    D, d = constraints_ref(lo, hi)
    violated = D @ X > d
    if not violated.any():
        return np.array(X, dtype=float, copy=True), 0
    E = D[violated]
    e = d[violated]
    L = E.T @ np.linalg.inv(E @ E.T)
    return X + L @ (e - E @ X), int(violated.sum())


def filter_step_ref(X, P, u, z, model):
    """One estimator step in ``ftc_mc.core.step.filter_step``'s order:
    predict, residuals, Table 1; on a reset, reset the block of ``P_{k|k}`` and
    predict again; update, projection.

    Returns
    -------
    X, P, block, residuals
    """
    Xp, Pp = predict_ref(X, P, u, model)
    res = residuals_ref(Xp, Pp, z, model)
    block = signature_ref(res[0], res[1], res[2], model.t_q, model.t_nx, model.variant)
    if block:
        Xp, Pp = predict_ref(X, reset_ref(P, block, model.reset_var), u, model)
    X, P = update_ref(Xp, Pp, z, model)
    X, _ = project_ref(X, model.lo, model.hi)
    return X, P, block, res


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
    ``alpha`` [rad], ``Va`` [m/s] of the X8 (DESIGN.md section 2), air-relative.

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
