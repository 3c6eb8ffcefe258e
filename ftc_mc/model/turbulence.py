"""MIL-F-8785C Dryden turbulence, discretised exactly.

Builds the matrices of the discrete gust models run by
:func:`ftc_mc.core.shared.dryden.gust_step`: the longitudinal ``u_g, w_g, q_g``
(:func:`dryden_model`, below) and, for the 6-DOF plant, the lateral
``v_g, p_g, r_g`` (:func:`dryden_lateral_model`, at the end of the module).

Spectra (MIL-F-8785C section 3.7.2; one-sided in angular frequency ``omega``
[rad/s], i.e. ``int_0^inf Phi d omega = sigma^2``; ``V`` airspeed)::

    Phi_u(w) = sigma_u^2 (2 L_u / (pi V)) / (1 + (L_u w / V)^2)
    Phi_w(w) = sigma_w^2 (L_w / (pi V)) (1 + 3 (L_w w / V)^2) / (1 + (L_w w / V)^2)^2
    Phi_q(w) = (w / V)^2 / (1 + (4 b w / (pi V))^2) * Phi_w(w)

with ``b`` the wing span.  Shaping filters driven by unit-intensity white noise
``eta`` (``E eta(t) eta(s) = delta(t - s)``, one-sided angular PSD ``1/pi``, so
``|H|^2 = pi Phi``)::

    H_u(s) = sigma_u sqrt(2 L_u / V) / (1 + (L_u/V) s)
    H_w(s) = sigma_w sqrt(L_w / V) (1 + sqrt(3) (L_w/V) s) / (1 + (L_w/V) s)^2
    q_g    = -(s / V) / (1 + T_q s) w_g,     T_q = 4 b / (pi V)

The pitch gust is the rotation of the air seen by the wing, ``q_g = -dw_g/dx``
(frozen field, ``d/dx = (1/V) d/dt``) with the first-order lag of the span
(``T_q``); its sign makes a uniform rotation of the air equivalent to ``-q`` of
the aircraft, which is how :mod:`ftc_mc.core.longitudinal.nonlinear` uses it (the
aerodynamics see ``q - q_g``).  The spectrum fixes only ``|H_q|``; the sign
follows this definition (MIL-F-8785C and MIL-HDBK-1797 differ in sign).  It is
realised without feed-through as ``q_g = -(w_g - s_q) / (V T_q)`` with the lag
state ``s_q' = (w_g - s_q) / T_q``.

Low-altitude scales (MIL-F-8785C, 10 ft < h < 1000 ft; ``h`` in ft)::

    L_w = h,   L_u = h / (0.177 + 0.000823 h)^1.2         [ft]
    sigma_w = 0.1 W20,   sigma_u = sigma_w / (0.177 + 0.000823 h)^0.4

with the wind speed at 20 ft ``W20`` = 15, 30, 45 kt for light, moderate and
severe turbulence.  Defaults for this landing approach: altitude 100 m (328 ft),
airspeed 20 m/s, X8 span b = 2.1 m (Gryte et al., ICUAS 2018).  At these values
``L_u`` = 263 m, ``L_w`` = 100 m, and for moderate turbulence ``sigma_w`` =
1.54 m/s, ``sigma_u`` = 2.13 m/s.

Discretisation is exact for white-noise-driven systems: ``Ad = expm(Ac dt)``
and the discrete noise covariance ``Qd = int_0^dt expm(Ac t) Bc Bc^T
expm(Ac^T t) dt`` by Van Loan's matrix exponential; ``Bd`` is the (lower)
Cholesky factor of ``Qd``, so the sampled gust state has exactly the
statistics of the continuous process at the sample instants (a zero-order hold
of the noise would not: with ``T_q`` = 0.13 s and dt = 0.1 s its variance error
would be large).  The gust is then held over each control period.
"""

from __future__ import annotations

import collections
import math

import numpy as np
import scipy.linalg

FT = 0.3048            # [m]
KT = 1852.0 / 3600.0   # [m/s]

#: wind speed at 20 ft [kt] per turbulence level (MIL-F-8785C)
W20_KT = {"none": 0.0, "light": 15.0, "moderate": 30.0, "severe": 45.0}

X8_SPAN = 2.1  # [m] Gryte et al., ICUAS 2018

DrydenModel = collections.namedtuple(
    "DrydenModel",
    ["Ad", "Bd", "Cd", "P0", "P0_chol", "Ac", "Bc", "Cc", "sigma_u", "sigma_w",
     "sigma_q", "L_u", "L_w", "T_q", "V", "dt", "level", "altitude_m", "span"])
DrydenModel.__doc__ = """Discrete Dryden gust model (see :func:`dryden_model`).

Ad, Bd (4, 4), Cd (3, 4): discrete recursion of :func:`ftc_mc.core.shared.dryden.gust_step`.
P0 (4, 4), P0_chol: stationary state covariance and its Cholesky factor (start a
record in stationary turbulence with ``s_0 = P0_chol @ randn(4)``).
Ac, Bc (4, 2), Cc: continuous shaping filters (noise inputs eta_u, eta_w).
sigma_u, sigma_w [m/s], sigma_q [rad/s]: standard deviations of the gusts.
L_u, L_w [m], T_q [s]: scale lengths and pitch-gust lag; V [m/s], dt [s],
level, altitude_m [m], span [m]: the arguments."""


def dryden_scales(level: str, altitude_m: float = 100.0):
    """MIL-F-8785C low-altitude intensities and scale lengths.

    Parameters
    ----------
    level : {"none", "light", "moderate", "severe"}
    altitude_m : float
        Altitude above ground [m], between 10 ft and 1000 ft.

    Returns
    -------
    sigma_u, sigma_w : float
        [m/s]
    L_u, L_w : float
        [m]
    """
    if level not in W20_KT:
        raise ValueError(f"turbulence parameter 'level' must be one of "
                         f"{sorted(W20_KT)}, got {level!r}")
    h = altitude_m / FT
    if not (math.isfinite(h) and 10.0 <= h <= 1000.0):
        raise ValueError("turbulence parameter 'altitude_m' must be within the "
                         f"low-altitude range 3.048 .. 304.8 m, got {altitude_m!r}")
    k = 0.177 + 0.000823 * h
    sigma_w = 0.1 * W20_KT[level] * KT
    sigma_u = sigma_w / k ** 0.4
    return sigma_u, sigma_w, h / k ** 1.2 * FT, h * FT


def dryden_model(level: str = "moderate", V: float = 20.0, altitude_m: float = 100.0,
                 dt: float = 0.1, span: float = X8_SPAN) -> DrydenModel:
    """Exact discrete Dryden model for the longitudinal gusts ``u_g, w_g, q_g``.

    Parameters
    ----------
    level : {"none", "light", "moderate", "severe"}
        Turbulence intensity (W20 = 0, 15, 30, 45 kt).
    V : float
        Airspeed [m/s] (approach: 20 m/s).
    altitude_m : float
        Altitude [m] for the scale lengths (approach: 100 m = 328 ft).
    dt : float
        Sampling period [s].
    span : float
        Wing span [m] for the pitch gust (X8: 2.1 m).

    Returns
    -------
    DrydenModel
    """
    for name, val in (("V", V), ("dt", dt), ("span", span)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise ValueError(f"turbulence parameter {name!r} must be a finite "
                             f"number > 0, got {val!r}")
    sigma_u, sigma_w, L_u, L_w = dryden_scales(level, altitude_m)
    tu = L_u / V
    tw = L_w / V
    T_q = 4.0 * span / (math.pi * V)
    Ku = sigma_u * math.sqrt(2.0 * L_u / V)
    Kw = sigma_w * math.sqrt(L_w / V)
    # states: [s_u, s_w1, s_w2, s_q]; w_g = Cw s_w (controllable canonical form)
    Cw = np.array([1.0 / tw ** 2, math.sqrt(3.0) / tw])
    Ac = np.zeros((4, 4))
    Bc = np.zeros((4, 2))
    Cc = np.zeros((3, 4))
    Ac[0, 0] = -1.0 / tu
    Bc[0, 0] = Ku / tu
    Ac[1, 2] = 1.0
    Ac[2, 1] = -1.0 / tw ** 2
    Ac[2, 2] = -2.0 / tw
    Bc[2, 1] = Kw
    Ac[3, 1:3] = Cw / T_q
    Ac[3, 3] = -1.0 / T_q
    Cc[0, 0] = 1.0
    Cc[1, 1:3] = Cw
    Cc[2, 1:3] = -Cw / (V * T_q)
    Cc[2, 3] = 1.0 / (V * T_q)

    Ad, Bd, P0 = _discretise(Ac, Bc, dt)
    P0_chol = _psd_sqrt(P0)
    sigma_q = math.sqrt(max(float(Cc[2] @ P0 @ Cc[2]), 0.0))
    return DrydenModel(Ad=Ad, Bd=Bd, Cd=Cc.copy(), P0=P0, P0_chol=P0_chol, Ac=Ac,
                       Bc=Bc, Cc=Cc, sigma_u=sigma_u, sigma_w=sigma_w,
                       sigma_q=sigma_q, L_u=L_u, L_w=L_w, T_q=T_q, V=float(V),
                       dt=float(dt), level=level, altitude_m=float(altitude_m),
                       span=float(span))


def _discretise(Ac: np.ndarray, Bc: np.ndarray, dt: float):
    """Exact discretisation of a shaping filter ``ds = Ac s dt + Bc dW`` over ``dt``.

    Van Loan: ``expm([[-A, B B^T], [0, A^T]] dt) = [[., F12], [0, F22]]`` gives
    ``Ad = F22^T`` and the discrete noise covariance ``Qd = Ad F12``.

    Returns
    -------
    Ad : ndarray
        Discrete transition.
    Bd : ndarray
        Symmetric square root of ``Qd`` (the noise input of a standard normal draw).
    P0 : ndarray
        Stationary state covariance (continuous Lyapunov equation).
    """
    n = Ac.shape[0]
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -Ac
    M[:n, n:] = Bc @ Bc.T
    M[n:, n:] = Ac.T
    F = scipy.linalg.expm(M * dt)
    Ad = F[n:, n:].T
    Qd = Ad @ F[:n, n:]
    Qd = 0.5 * (Qd + Qd.T)
    P0 = scipy.linalg.solve_continuous_lyapunov(Ac, -Bc @ Bc.T)
    return Ad, _psd_sqrt(Qd), 0.5 * (P0 + P0.T)


def _psd_sqrt(Q: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor of a positive semidefinite matrix (zero if Q = 0)."""
    if not np.any(Q):
        return np.zeros_like(Q)
    try:
        return np.linalg.cholesky(Q)
    except np.linalg.LinAlgError:
        # semidefinite: symmetric square root (any factor with L L^T = Q works)
        w, V = np.linalg.eigh(Q)
        return (V * np.sqrt(np.clip(w, 0.0, None))) @ V.T


def psd_u(omega, m: DrydenModel):
    """Analytic one-sided Phi_u(omega) [(m/s)^2 / (rad/s)]."""
    a = m.L_u / m.V
    return m.sigma_u ** 2 * 2.0 * a / math.pi / (1.0 + (a * omega) ** 2)


def psd_w(omega, m: DrydenModel):
    """Analytic one-sided Phi_w(omega) [(m/s)^2 / (rad/s)]."""
    a = m.L_w / m.V
    x2 = (a * omega) ** 2
    return m.sigma_w ** 2 * a / math.pi * (1.0 + 3.0 * x2) / (1.0 + x2) ** 2


def psd_q(omega, m: DrydenModel):
    """Analytic one-sided Phi_q(omega) [(rad/s)^2 / (rad/s)]."""
    return (omega / m.V) ** 2 / (1.0 + (m.T_q * omega) ** 2) * psd_w(omega, m)


# ----------------------------------------------------------------------------
# lateral components (6-DOF plant)

DrydenLateralModel = collections.namedtuple(
    "DrydenLateralModel",
    ["Ad", "Bd", "Cd", "P0", "P0_chol", "Ac", "Bc", "Cc", "sigma_v", "sigma_p",
     "sigma_r", "L_v", "L_w", "T_p", "T_r", "V", "dt", "level", "altitude_m", "span"])
DrydenLateralModel.__doc__ = """Discrete lateral Dryden gust model (see
:func:`dryden_lateral_model`).

Ad, Bd (4, 4), Cd (3, 4): the same recursion as the longitudinal model
(:func:`ftc_mc.core.shared.dryden.gust_step` runs both), outputs ``v_g`` [m/s],
``p_g``, ``r_g`` [rad/s]; states ``[s_v1, s_v2, s_r, s_p]``.
P0, P0_chol: stationary state covariance and its Cholesky factor.
Ac, Bc (4, 2), Cc: continuous shaping filters (noise inputs eta_v, eta_p).
sigma_v [m/s], sigma_p, sigma_r [rad/s]: standard deviations of the gusts.
L_v, L_w [m]: scale lengths; T_p, T_r [s]: the roll-gust filter's and the
yaw-gust lag's time constants; V [m/s], dt [s], level, altitude_m [m], span [m]:
the arguments."""


def dryden_lateral_model(level: str = "moderate", V: float = 20.0,
                         altitude_m: float = 100.0, dt: float = 0.1,
                         span: float = X8_SPAN) -> DrydenLateralModel:
    """Exact discrete Dryden model for the lateral gusts ``v_g, p_g, r_g``.

    Spectra (MIL-F-8785C section 3.7.2, one-sided in ``omega`` as the module
    docstring; at low altitude ``L_v = L_u``, ``sigma_v = sigma_u``)::

        Phi_v(w) = sigma_v^2 (L_v / (pi V)) (1 + 3 (L_v w / V)^2) / (1 + (L_v w / V)^2)^2
        Phi_p(w) = sigma_w^2 / (L_w V) 0.8 (pi L_w / (4 b))^(1/3) / (1 + (4 b w / (pi V))^2)
        Phi_r(w) = (w / V)^2 / (1 + (3 b w / (pi V))^2) Phi_v(w)

    Shaping filters (unit-intensity white noise, ``|H|^2 = pi Phi``)::

        H_v(s) = sigma_v sqrt(L_v / V) (1 + sqrt(3) (L_v/V) s) / (1 + (L_v/V) s)^2
        H_p(s) = sigma_w sqrt(0.8 pi (pi L_w / (4 b))^(1/3) / (L_w V)) / (1 + T_p s),
                 T_p = 4 b / (pi V)
        r_g    = +(s / V) / (1 + T_r s) v_g,     T_r = 3 b / (pi V)

    The yaw gust is the rotation of the air ``r_g = +dv_g/dx`` (frozen field)
    with the span's lag: a lateral gust growing toward the nose is seen by the
    aerodynamics as the aircraft yawing left, so they see ``r - r_g`` (as
    ``q - q_g``; the opposite sign convention of ``q_g = -dw_g/dx`` follows from
    the axes).  The roll gust is an independent process (``p_g = dw_g/dy``,
    the spanwise gradient of the vertical gust, uncorrelated with ``w_g`` at
    the centre of gravity in the Dryden model).  Discretised exactly as
    :func:`dryden_model` (Van Loan).

    Parameters
    ----------
    level : {"none", "light", "moderate", "severe"}
    V : float
        Airspeed [m/s].
    altitude_m : float
        Altitude [m] for the scale lengths.
    dt : float
        Sampling period [s].
    span : float
        Wing span [m].

    Returns
    -------
    DrydenLateralModel
    """
    for name, val in (("V", V), ("dt", dt), ("span", span)):
        if not (isinstance(val, (int, float)) and math.isfinite(val) and val > 0):
            raise ValueError(f"turbulence parameter {name!r} must be a finite "
                             f"number > 0, got {val!r}")
    sigma_u, sigma_w, L_u, L_w = dryden_scales(level, altitude_m)
    sigma_v, L_v = sigma_u, L_u
    tv = L_v / V
    T_r = 3.0 * span / (math.pi * V)
    T_p = 4.0 * span / (math.pi * V)
    Kv = sigma_v * math.sqrt(L_v / V)
    Kp = sigma_w * math.sqrt(0.8 * math.pi * (math.pi * L_w / (4.0 * span)) ** (1.0 / 3.0)
                             / (L_w * V))
    # states [s_v1, s_v2, s_r, s_p]; v_g = Cv s_v (controllable canonical form)
    Cv = np.array([1.0 / tv ** 2, math.sqrt(3.0) / tv])
    Ac = np.zeros((4, 4))
    Bc = np.zeros((4, 2))
    Cc = np.zeros((3, 4))
    Ac[0, 1] = 1.0
    Ac[1, 0] = -1.0 / tv ** 2
    Ac[1, 1] = -2.0 / tv
    Bc[1, 0] = Kv
    Ac[2, 0:2] = Cv / T_r
    Ac[2, 2] = -1.0 / T_r
    Ac[3, 3] = -1.0 / T_p
    Bc[3, 1] = Kp / T_p
    Cc[0, 0:2] = Cv                      # v_g
    Cc[1, 3] = 1.0                       # p_g
    Cc[2, 0:2] = Cv / (V * T_r)          # r_g = (v_g - s_r) / (V T_r)
    Cc[2, 2] = -1.0 / (V * T_r)
    Ad, Bd, P0 = _discretise(Ac, Bc, dt)
    var = np.diag(Cc @ P0 @ Cc.T)
    return DrydenLateralModel(
        Ad=Ad, Bd=Bd, Cd=Cc.copy(), P0=P0, P0_chol=_psd_sqrt(P0), Ac=Ac, Bc=Bc, Cc=Cc,
        sigma_v=sigma_v, sigma_p=math.sqrt(max(float(var[1]), 0.0)),
        sigma_r=math.sqrt(max(float(var[2]), 0.0)), L_v=L_v, L_w=L_w, T_p=T_p,
        T_r=T_r, V=float(V), dt=float(dt), level=level, altitude_m=float(altitude_m),
        span=float(span))


def psd_v(omega, m: DrydenLateralModel):
    """Analytic one-sided Phi_v(omega) [(m/s)^2 / (rad/s)]."""
    a = m.L_v / m.V
    x2 = (a * omega) ** 2
    return m.sigma_v ** 2 * a / math.pi * (1.0 + 3.0 * x2) / (1.0 + x2) ** 2


def psd_p(omega, m: DrydenLateralModel):
    """Analytic one-sided Phi_p(omega) [(rad/s)^2 / (rad/s)]."""
    _, sigma_w, _, L_w = dryden_scales(m.level, m.altitude_m)
    return (sigma_w ** 2 / (L_w * m.V) * 0.8
            * (math.pi * L_w / (4.0 * m.span)) ** (1.0 / 3.0)
            / (1.0 + (m.T_p * omega) ** 2))


def psd_r(omega, m: DrydenLateralModel):
    """Analytic one-sided Phi_r(omega) [(rad/s)^2 / (rad/s)]."""
    return (omega / m.V) ** 2 / (1.0 + (m.T_r * omega) ** 2) * psd_v(omega, m)
