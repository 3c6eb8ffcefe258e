"""``ftc_mc.stats`` against references that do not use the code under test.

* Wilson: the closed form of Newcombe (1998), method 3, with the normal
  quantile from the standard library (``statistics.NormalDist``), and the
  hand-evaluated 17/1000 interval;
* Garwood: the defining equations P(X >= k; lo) = P(X <= k; hi) = 0.025 of
  the Poisson distribution, solved by bisection on a plain-Python CDF, and the
  closed forms at k = 0 (hi = -ln 0.025) and k = 1 (lo = -ln 0.975);
* McNemar: the exact conditional p-value 2 P(X <= min(b, c)), X ~ Bin(b + c,
  1/2) (Fagerland et al. 2013), summed with ``math.comb``;
* Fisher's exact two-proportion test: the hypergeometric probabilities of
  the tables with the observed margins, summed with ``math.comb`` over those
  no more probable than the observed one (Agresti 1992, section 2.1), and
  Fisher's tea-tasting table 3/4 against 1/4, two-sided p = 34/70 (Fisher
  1935, Agresti 1992 Table 1);
* quantiles: linear interpolation between order statistics written out
  (Hyndman and Fan 1996, type 7).
"""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
import pytest

from ftc_mc.stats import (AGREEMENT_LEVEL, agrees, finite, finite_median, mcnemar_exact,
                          median_p95, poisson_ci, poisson_rate, two_proportion_p, wilson)


def _wilson_closed_form(k, n, confidence=0.95):
    """Newcombe (1998) method 3: (2k + z² ± z sqrt(z² + 4 k (n - k) / n)) / (2 (n + z²))."""
    z = NormalDist().inv_cdf((1 + confidence) / 2)
    centre = 2 * k + z * z
    half = z * math.sqrt(z * z + 4 * k * (n - k) / n)
    return (centre - half) / (2 * (n + z * z)), (centre + half) / (2 * (n + z * z))


@pytest.mark.parametrize("k,n", [(0, 1), (1, 1), (0, 20), (3, 20), (20, 20), (17, 1000),
                                 (500, 1000), (1, 7)])
@pytest.mark.parametrize("confidence", [0.95, 0.9])
def test_wilson_equals_its_closed_form(k, n, confidence):
    lo, hi = wilson(k, n, confidence)
    ref = _wilson_closed_form(k, n, confidence)
    assert lo == pytest.approx(ref[0], abs=1e-12)
    assert hi == pytest.approx(ref[1], abs=1e-12)
    assert 0.0 <= lo <= k / n <= hi <= 1.0


def test_wilson_hand_value():
    # Wilson's score interval for 17/1000, z = 1.959964, evaluated by hand:
    # centre 0.018848, half-width 0.0082075.
    lo, hi = wilson(17, 1000)
    assert lo == pytest.approx(0.018848 - 0.0082075, abs=2e-6)
    assert hi == pytest.approx(0.018848 + 0.0082075, abs=2e-6)


def _poisson_cdf(k, mu):
    """P(X <= k) for X ~ Poisson(mu), summed term by term."""
    term, total = math.exp(-mu), 0.0
    for i in range(k + 1):
        total += term
        term *= mu / (i + 1)
    return total


def _bisect(f, lo, hi):
    """Root of the increasing-or-decreasing ``f`` on [lo, hi] (sign change)."""
    flo = f(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if (f(mid) > 0) == (flo > 0):
            lo, flo = mid, f(mid)
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _garwood(k):
    """Bounds on the mean: P(X >= k; lo) = 0.025 and P(X <= k; hi) = 0.025."""
    lo = 0.0 if k == 0 else _bisect(lambda m: (1 - _poisson_cdf(k - 1, m)) - 0.025,
                                    1e-12, 10.0 * k + 10)
    hi = _bisect(lambda m: _poisson_cdf(k, m) - 0.025, 1e-12, 10.0 * k + 20)
    return lo, hi


@pytest.mark.parametrize("k", [0, 1, 2, 5, 17, 60])
@pytest.mark.parametrize("exposure", [1.0, 0.37, 250.0])
def test_poisson_ci_solves_the_defining_equations(k, exposure):
    lo, hi = poisson_ci(k, exposure)
    ref_lo, ref_hi = _garwood(k)
    assert lo * exposure == pytest.approx(ref_lo, rel=1e-9, abs=1e-12)
    assert hi * exposure == pytest.approx(ref_hi, rel=1e-9)


def test_poisson_ci_closed_forms():
    # k = 0: P(X = 0; hi) = exp(-hi) = 0.025; k = 1: P(X >= 1; lo) = 1 - exp(-lo) = 0.025.
    assert poisson_ci(0, 1.0) == (0.0, pytest.approx(-math.log(0.025), rel=1e-12))
    assert poisson_ci(1, 2.0)[0] == pytest.approx(-math.log(0.975) / 2.0, rel=1e-12)


def test_poisson_rate():
    rate, lo, hi = poisson_rate(3, 0.5)
    assert rate == 6.0
    assert (lo, hi) == poisson_ci(3, 0.5)
    assert lo < rate < hi
    assert all(np.isnan(x) for x in poisson_rate(0, 0.0))
    assert all(np.isnan(x) for x in poisson_rate(0, np.float64(0.0)))


def _mcnemar_reference(b, c):
    n = b + c
    tail = sum(math.comb(n, i) for i in range(min(b, c) + 1)) / 2 ** n
    return min(1.0, 2 * tail)


@pytest.mark.parametrize("b,c", [(1, 9), (9, 1), (0, 5), (3, 3), (4, 7), (12, 30), (0, 1)])
def test_mcnemar_exact_equals_the_binomial_tail(b, c):
    assert mcnemar_exact(b, c) == pytest.approx(_mcnemar_reference(b, c), rel=1e-12)


def test_mcnemar_exact_values():
    assert mcnemar_exact(1, 9) == pytest.approx(2 * 11 / 1024, rel=1e-12)  # 0.0215
    assert mcnemar_exact(0, 0) == 1.0
    assert mcnemar_exact(2, 2) == 1.0


def _fisher_reference(k_a, n_a, k_b, n_b):
    """Two-sided Fisher p-value: the hypergeometric probabilities of the tables
    with the observed margins that are no more probable than the observed one
    (relative tolerance 1e-7 for ties, as scipy's), summed."""
    m = k_a + k_b  # the successes' margin

    def prob(x):  # x successes in the first sample
        return math.comb(n_a, x) * math.comb(n_b, m - x) / math.comb(n_a + n_b, m)

    observed = prob(k_a)
    xs = range(max(0, m - n_b), min(n_a, m) + 1)
    return min(1.0, sum(prob(x) for x in xs if prob(x) <= observed * (1 + 1e-7)))


@pytest.mark.parametrize("k_a,n_a,k_b,n_b", [(3, 4, 1, 4), (0, 20, 5, 20), (17, 1000, 0, 887),
                                             (74, 1000, 157, 1000), (1, 1000, 9, 1000),
                                             (5, 30, 5, 12), (70, 1000, 11, 1000)])
def test_two_proportion_p_equals_the_hypergeometric_sum(k_a, n_a, k_b, n_b):
    ref = _fisher_reference(k_a, n_a, k_b, n_b)
    assert two_proportion_p(k_a, n_a, k_b, n_b) == pytest.approx(ref, rel=1e-9)
    assert two_proportion_p(k_b, n_b, k_a, n_a) == pytest.approx(ref, rel=1e-9)  # symmetric


def test_two_proportion_p_known_values():
    # Fisher's lady tasting tea: 3 of 4 against 1 of 4; the tables with these margins
    # have 0-4 successes in the first row with probabilities (1, 16, 36, 16, 1) / 70,
    # and those no more probable than the observed 16 / 70 sum to 34 / 70
    assert two_proportion_p(3, 4, 1, 4) == pytest.approx(34 / 70, rel=1e-12)
    assert two_proportion_p(0, 1000, 0, 896) == 1.0  # equal (zero) counts
    assert two_proportion_p(74, 1000, 74, 1000) == 1.0  # the same count twice
    assert two_proportion_p(0, 1000, 999, 1000) < 1e-100  # as far apart as can be
    assert np.isnan(two_proportion_p(0, 1000, 0, 0))  # no trial judged: nothing to compare
    with pytest.raises(ValueError):
        two_proportion_p(5, 4, 1, 4)


def test_agreement_verdict():
    assert AGREEMENT_LEVEL == 0.05
    assert agrees(two_proportion_p(0, 1000, 0, 896)) is True
    assert agrees(two_proportion_p(74, 1000, 74, 1000)) is True
    assert agrees(two_proportion_p(0, 1000, 999, 1000)) is False
    assert agrees(two_proportion_p(17, 1000, 0, 887)) is False  # p = 2.2e-5
    assert agrees(np.nan) is None
    assert agrees(0.05) is True and agrees(0.0499) is False  # p >= level agrees
    assert agrees(0.2, level=0.25) is False


def _type7(x, p):
    """Hyndman and Fan (1996) type 7: x[j] + g (x[j+1] - x[j]), h = (n - 1) p."""
    x = sorted(x)
    h = (len(x) - 1) * p
    j = math.floor(h)
    return x[j] if j + 1 >= len(x) else x[j] + (h - j) * (x[j + 1] - x[j])


def test_quantiles_of_finite_values():
    values = [4.0, np.nan, 1.0, np.inf, 2.5, 10.0, -np.inf, 3.0, 0.5]
    kept = [4.0, 1.0, 2.5, 10.0, 3.0, 0.5]
    assert sorted(finite(values)) == sorted(kept)
    median, p95 = median_p95(values)
    assert median == _type7(kept, 0.5) == 2.75
    assert p95 == pytest.approx(_type7(kept, 0.95), rel=1e-15)
    assert finite_median(values) == median
    assert finite_median(np.array([1, 2, 3])) == 2.0  # integers are read as floats
    assert np.isnan(finite_median([np.nan]))
    assert all(np.isnan(x) for x in median_p95([]))
