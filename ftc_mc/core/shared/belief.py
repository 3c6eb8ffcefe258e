"""Mode observation likelihood (eq. 12) and Bayes belief update (eqs. 13-14).

Modes: 0 nominal, 1 engine faulty, 2 left elevon faulty, 3 right elevon faulty
(:data:`ftc_mc.conventions.MODE_NAMES`).
Each mode's prior ``f_m`` over the five fault parameters is uniform on a box
``[lo[m], hi[m]]`` (independent parameters, section 3.3.2), and the filter's
estimate is Gaussian with mean ``b_hat`` and the marginal variances of ``P``.
Eq. (12) is then a product of normal-CDF differences::

    p(omega | m) = prod_j (Phi((hi_mj - b_j)/s_j) - Phi((lo_mj - b_j)/s_j)) / (hi_mj - lo_mj)

computed in logarithms, with complementary error functions in the tails, and
beyond them (an interval whose probability is below the smallest normal
float64, about 37.5 standard deviations out) with the asymptotic series of the
normal tail's logarithm (:func:`log_upper_tail`), so a mode many standard
deviations away still gets a finite likelihood in the right order: a mode
1000 standard deviations out is less likely than one 40 out.  (A floor at the
smallest subnormal's logarithm instead made every such factor equal, and an
estimate far from every box then ranked a mode with one parameter far out
as likely as one with two.)
"""

from __future__ import annotations

import math

from ...conventions import N_MODES  # noqa: F401
from ..jit import kernel

LOG_TINY = -745.0  # log of the smallest subnormal float64

TINY_P = 2.2250738585072014e-308
"""The smallest normal float64: an interval probability below it (subnormal,
few significant digits, or zero) is computed from the tails' logarithms."""

TAIL_MIN = 20.0
"""Where :func:`log_upper_tail`'s series is used (scipy's ``log_ndtr`` switches
to its series at the same point); below it an interval's probability is far
above :data:`TINY_P` unless its bounds coincide."""

LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)


@kernel(internal=True)
def log_normal_interval(a, b):
    """``log(Phi(b) - Phi(a))`` for standard-normal bounds ``a <= b``, tail-safe.

    Parameters
    ----------
    a, b : float
        Standardised lower and upper bounds.

    Returns
    -------
    float
        The log-probability: from complementary error functions, or, when
        that probability is below :data:`TINY_P`, from the tails' logarithms
        (:func:`log_tail_interval`).
    """
    r2 = math.sqrt(2.0)
    if a > 0.0:
        p = 0.5 * (math.erfc(a / r2) - math.erfc(b / r2))
    elif b < 0.0:
        p = 0.5 * (math.erfc(-b / r2) - math.erfc(-a / r2))
    else:
        p = 1.0 - 0.5 * (math.erfc(b / r2) + math.erfc(-a / r2))
    if p < TINY_P:
        return log_tail_interval(a, b)
    return math.log(p)


@kernel(internal=True)
def log_upper_tail(u):
    """``log(1 - Phi(u))`` for ``u >= TAIL_MIN``: the asymptotic series
    ``-u^2/2 - log(u) - log(sqrt(2 pi)) + log(1 - 1/u^2 + 3/u^4 - 15/u^6 + ...)``
    summed until its terms stop mattering (under 1e-17; at ``u = 20`` after
    10 terms, at ``u = 40`` after 6).  ``-inf`` at ``u = inf``.
    """
    r = 1.0 / (u * u)
    term = 1.0
    s = 1.0
    for n in range(1, 40):
        term *= -(2 * n - 1) * r
        s += term
        if abs(term) < 1e-17:
            break
    return -0.5 * u * u - math.log(u) - LOG_SQRT_2PI + math.log(s)


@kernel(internal=True)
def log_tail_interval(a, b):
    """``log(Phi(b) - Phi(a))`` for an interval ``a < b`` in one tail, at
    least ``TAIL_MIN`` standard deviations out (mirrored to the upper tail:
    ``log(Q(u) - Q(v)) = log Q(u) + log(1 - Q(v)/Q(u))``, ``Q = 1 - Phi``,
    ``u < v`` the near and far bounds); ``LOG_TINY`` for any other interval
    whose probability is below :data:`TINY_P` (bounds that coincide, or a
    near bound beyond 1e154 standard deviations, whose square overflows)."""
    if a > 0.0:
        u = a
        v = b
    elif b < 0.0:
        u = -b
        v = -a
    else:
        return LOG_TINY
    if not (u >= TAIL_MIN and v > u):
        return LOG_TINY
    lu = log_upper_tail(u)
    d = log_upper_tail(v) - lu
    if not d < 0.0:
        return LOG_TINY
    if d > -0.6931471805599453:  # log(-expm1(d)) is exact where 1 - e^d cancels
        return lu + math.log(-math.expm1(d))
    return lu + math.log1p(-math.exp(d))


@kernel(internal=True)
def mode_log_likelihood(bhat, var, lo, hi, out):
    """Log of eq. (12) for each mode.

    Parameters
    ----------
    bhat : ndarray, shape (5,)
        Estimated ``[b0_T, b0_e, b1_T, b1_L, b1_R]``.
    var : ndarray, shape (5,)
        Their marginal variances (diagonal of ``P``), > 0.
    lo, hi : ndarray, shape (4, 5)
        Box of each mode.
    out : ndarray, shape (4,)
        Written with ``log p(omega | m)``.
    """
    for m in range(lo.shape[0]):
        acc = 0.0
        for j in range(bhat.shape[0]):
            s = math.sqrt(var[j])
            acc += log_normal_interval((lo[m, j] - bhat[j]) / s,
                                       (hi[m, j] - bhat[j]) / s)
            acc -= math.log(hi[m, j] - lo[m, j])
        out[m] = acc


@kernel(internal=True)
def belief_update(belief, bs, bhat, var, work):
    """One reconfiguration-period belief update (eqs. 13-14), in place.

    Parameters
    ----------
    belief : ndarray, shape (4,)
        ``b_{n|n}`` on entry, ``b_{n+1|n+1}`` on exit; sums to one.
    bs : Belief
        Transition matrix and mode boxes.
    bhat, var : ndarray, shape (5,)
        Fault-parameter estimate and marginal variances.
    work : ndarray, shape (2 N_MODES,)
        Work array.

    Returns
    -------
    int
        Index of the most probable mode after the update.
    """
    nm = belief.shape[0]
    # prediction b_{n+1|n} = T_M b_{n|n} (eq. 13)
    for i in range(nm):
        acc = 0.0
        for j in range(nm):
            acc += bs.TM[i, j] * belief[j]
        work[i] = acc
    mode_log_likelihood(bhat, var, bs.lo, bs.hi, work[nm:])
    # Bayes rule (eq. 14) in logarithms
    top = -math.inf
    for i in range(nm):
        if work[i] > 0.0:
            v = math.log(work[i]) + work[nm + i]
        else:
            v = -math.inf
        work[nm + i] = v
        if v > top:
            top = v
    total = 0.0
    for i in range(nm):
        e = math.exp(work[nm + i] - top)
        work[nm + i] = e
        total += e
    for i in range(nm):
        belief[i] = work[nm + i] / total
    return most_probable(belief)


@kernel(inline="always")
def most_probable(belief):
    """Index of the most probable mode of ``belief`` (the first on a tie)."""
    best = 0
    for i in range(belief.shape[0]):
        if belief[i] > belief[best]:
            best = i
    return best


@kernel(inline="always")
def belief_update_lane(beliefs, l, bs, x, P, first, update, bl, bhat, var, work):
    """Lane ``l``'s belief (column ``l`` of ``beliefs``, (4, L)) updated in
    place by :func:`belief_update` from the fault-parameter estimate on rows
    ``first`` to ``first + n`` of ``x`` (n, L) (``n = bhat.shape[0]``) and
    their marginal variances, the diagonal of ``P`` (n, n, L); with
    ``update`` False left as it is.  ``bl``, ``bhat``, ``var`` hold the
    belief, the estimate and the variances after; ``work`` as
    :func:`belief_update`'s.  Returns the most probable mode."""
    for m in range(bl.shape[0]):
        bl[m] = beliefs[m, l]
    for j in range(bhat.shape[0]):
        bhat[j] = x[first + j, l]
        var[j] = P[first + j, first + j, l]
    if not update:
        return most_probable(bl)
    best = belief_update(bl, bs, bhat, var, work)
    for m in range(bl.shape[0]):
        beliefs[m, l] = bl[m]
    return best
