"""Mode observation likelihood (eq. 12) and Bayes belief update (eqs. 13-14).

Modes: 0 nominal, 1 engine faulty, 2 left elevon faulty, 3 right elevon faulty
(:data:`ftc_mc.conventions.MODE_NAMES`).
Each mode's prior ``f_m`` over the five fault parameters is uniform on a box
``[lo[m], hi[m]]`` (independent parameters, section 3.3.2), and the filter's
estimate is Gaussian with mean ``b_hat`` and the marginal variances of ``P``.
Eq. (12) is then a product of normal-CDF differences::

    p(omega | m) = prod_j (Phi((hi_mj - b_j)/s_j) - Phi((lo_mj - b_j)/s_j)) / (hi_mj - lo_mj)

computed in logarithms, with complementary error functions in the tails so a
mode many standard deviations away still gets a finite, ordered likelihood.
"""

from __future__ import annotations

import math

from ...conventions import N_MODES  # noqa: F401
from ..jit import kernel

LOG_TINY = -745.0  # log of the smallest subnormal float64


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
        The log-probability; ``LOG_TINY`` when it underflows.
    """
    r2 = math.sqrt(2.0)
    if a > 0.0:
        p = 0.5 * (math.erfc(a / r2) - math.erfc(b / r2))
    elif b < 0.0:
        p = 0.5 * (math.erfc(-b / r2) - math.erfc(-a / r2))
    else:
        p = 1.0 - 0.5 * (math.erfc(b / r2) + math.erfc(-a / r2))
    if p <= 0.0:
        return LOG_TINY
    return math.log(p)


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
