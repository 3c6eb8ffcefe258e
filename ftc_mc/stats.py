"""Statistics shared by the campaign summary, the threshold sweep and the report.

The one home of the intervals, tests and quantiles the tables and the report
print, so a rate in ``summary.parquet``, in ``sweep.parquet`` and in a report
come from the same formula:

* :func:`wilson`: score interval of a binomial proportion (Tables 2-3 rates);
* :func:`poisson_ci`, :func:`poisson_rate`: exact interval of a Poisson rate
  (false resets per flight hour);
* :func:`poisson_upper`, :func:`hours_to_show`: one-sided upper bound of a
  Poisson rate, and the exposure a rate target needs (endurance runs);
* :func:`mcnemar_exact`: paired comparison of the two signature variants;
* :func:`two_proportion_p`, :func:`agrees`: unpaired comparison of two
  counts, e.g. our rate of a Tables 2-3 row against the paper's count
  (``docs/findings/paper-tables.md``, "How agreement is judged");
* :func:`finite`, :func:`finite_median`, :func:`median_p95`: delay and
  detection-time quantiles over the trials that have one.
"""

from __future__ import annotations

import numpy as np


def _scipy_stats():
    """``scipy.stats``, imported on first use: it takes 0.33 s, and the processes
    that import this module through the trial code (the parallel workers, the
    scenario) mostly never call it (measured)."""
    import scipy.stats

    return scipy.stats


def wilson(k: int, n: int, confidence: float = 0.95):
    """Wilson score interval of a binomial proportion ``k / n``.

    With ``z`` the ``(1 + confidence) / 2`` quantile of the standard normal,
    the bounds are ``(k + z²/2 ± z sqrt(k (n - k) / n + z²/4)) / (n + z²)``
    (Wilson 1927; Newcombe 1998, method 3).  They stay inside [0, 1] and are
    not degenerate at ``k = 0`` or ``k = n``.

    Parameters
    ----------
    k : int
        Successes (``0 <= k <= n``).
    n : int
        Trials (``n >= 1``).
    confidence : float
        Coverage of the interval (0.95: a 95 % interval).

    Returns
    -------
    (float, float)
        Lower and upper bound of the proportion [-].

    References
    ----------
    E. B. Wilson, "Probable inference, the law of succession, and statistical
    inference", J. Am. Stat. Assoc. 22 (1927) 209-212.
    R. G. Newcombe, "Two-sided confidence intervals for the single proportion:
    comparison of seven methods", Stat. Med. 17 (1998) 857-872.
    """
    ci = _scipy_stats().binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence,
                                                                method="wilson")
    return float(ci.low), float(ci.high)


def poisson_ci(k: int, exposure: float):
    """Exact (Garwood) 95 % interval of a Poisson rate ``k / exposure``.

    The bounds on the mean count are ``chi2(0.025; 2k) / 2`` (0 for ``k = 0``)
    and ``chi2(0.975; 2k + 2) / 2``, with ``chi2(p; d)`` the ``p`` quantile of
    the chi-square distribution with ``d`` degrees of freedom (Garwood 1936);
    they are the means for which observing at most (at least) ``k`` events has
    probability 0.025.  Both are divided by ``exposure``.

    Parameters
    ----------
    k : int
        Observed events (``k >= 0``).
    exposure : float
        Exposure the events were counted over (``> 0``), e.g. flight hours [h].

    Returns
    -------
    (float, float)
        Lower and upper bound of the rate [events per unit of ``exposure``].

    References
    ----------
    F. Garwood, "Fiducial limits for the Poisson distribution", Biometrika 28
    (1936) 437-442.
    """
    lo = 0.0 if k == 0 else _scipy_stats().chi2.ppf(0.025, 2 * k) / 2
    hi = _scipy_stats().chi2.ppf(0.975, 2 * k + 2) / 2
    return lo / exposure, hi / exposure


def poisson_rate(k: int, exposure: float):
    """A Poisson rate ``k / exposure`` and its exact 95 % interval.

    The false-reset rate per flight hour of a run or of a sweep point.

    Parameters
    ----------
    k : int
        Observed events (``k >= 0``).
    exposure : float
        Exposure (``>= 0``), e.g. flight hours [h].

    Returns
    -------
    (float, float, float)
        Rate, lower and upper bound (:func:`poisson_ci`) [events per unit of
        ``exposure``]; all NaN when ``exposure`` is 0 (nothing was observed).
    """
    if not exposure:
        return np.nan, np.nan, np.nan
    lo, hi = poisson_ci(k, exposure)
    return k / exposure, lo, hi


def poisson_upper(k: int, exposure: float, confidence: float = 0.95) -> float:
    """One-sided exact upper confidence bound of a Poisson rate ``k / exposure``.

    ``chi2(confidence; 2k + 2) / 2 / exposure`` (Garwood 1936): the rate whose
    chance of giving at most ``k`` events in ``exposure`` is ``1 - confidence``.
    For ``k = 0`` it is ``-ln(1 - confidence) / exposure`` (3.0 / exposure at
    95 %, the "rule of three").  This is the bound a false-alarm target is
    checked against ("shown at 95 % confidence"); the two-sided interval of
    :func:`poisson_ci` has the larger 97.5 % upper end (3.69 / exposure at
    ``k = 0``).

    Parameters
    ----------
    k : int
        Observed events (``k >= 0``).
    exposure : float
        Exposure (``> 0``), e.g. flight hours [h].
    confidence : float
        One-sided confidence level.

    Returns
    -------
    float
        Upper bound [events per unit of ``exposure``]; NaN when ``exposure`` is 0.
    """
    if not exposure:
        return np.nan
    return float(_scipy_stats().chi2.ppf(confidence, 2 * int(k) + 2) / 2 / exposure)


def hours_to_show(k: int, target: float, confidence: float = 0.95) -> float:
    """Exposure at which ``k`` events give a one-sided upper bound of ``target``.

    ``chi2(confidence; 2k + 2) / 2 / target``: with ``k = 0`` events,
    ``-ln(1 - confidence) / target`` (3.0 / target at 95 %).  For ``k > 0`` it
    is the exposure needed if no further event occurred (a lower bound on what
    a longer run needs).

    Parameters
    ----------
    k : int
        Events seen so far.
    target : float
        Largest acceptable rate [events per unit of exposure], ``> 0``.
    confidence : float
        One-sided confidence level.

    Returns
    -------
    float
        Exposure [unit of ``1 / target``, e.g. h].
    """
    return float(_scipy_stats().chi2.ppf(confidence, 2 * int(k) + 2) / 2 / target)


def mcnemar_exact(only_a: int, only_b: int) -> float:
    """Two-sided exact McNemar test of paired binary outcomes.

    Under the null hypothesis (both variants equally likely to give the
    outcome), the discordant pairs split as Binomial(``only_a + only_b``, 1/2);
    the p-value is that of the exact two-sided binomial test of ``only_a``
    (McNemar 1947 for the test; the exact conditional form as in Fagerland
    et al. 2013): ``min(1, 2 P(X <= min(only_a, only_b)))``.

    Parameters
    ----------
    only_a, only_b : int
        Pairs where only variant ``a`` (only ``b``) had the outcome.

    Returns
    -------
    float
        The p-value; 1.0 when there are no discordant pairs.

    References
    ----------
    Q. McNemar, "Note on the sampling error of the difference between correlated
    proportions or percentages", Psychometrika 12 (1947) 153-157.
    M. W. Fagerland, S. Lydersen, P. Laake, "The McNemar test for binary
    matched-pairs data: mid-p and asymptotic are better than exact
    conditional", BMC Med. Res. Methodol. 13 (2013) 91.
    """
    if not only_a + only_b:
        return 1.0
    return _scipy_stats().binomtest(only_a, only_a + only_b).pvalue


AGREEMENT_LEVEL = 0.05
"""Level of :func:`agrees`: two counts agree unless the two-sided exact test
of :func:`two_proportion_p` rejects equal proportions at 5 %."""


def two_proportion_p(k_a: int, n_a: int, k_b: int, n_b: int) -> float:
    """Two-sided p-value of Fisher's exact test of two binomial proportions.

    Tests whether ``k_a`` of ``n_a`` and ``k_b`` of ``n_b`` can come from the
    same proportion, on the 2x2 table ``[[k_a, n_a - k_a], [k_b, n_b - k_b]]``
    (``scipy.stats.fisher_exact``, two-sided: the probability, under the
    hypergeometric distribution of the table with its margins fixed, of the
    tables no more probable than the one observed; Fisher 1935, Agresti 1992).
    Both counts are treated as samples: the test is the one for two
    independent Monte Carlo estimates.  It is exact, so never too liberal
    (conditioning on both margins makes it conservative), and costs
    microseconds at any ``n`` (Boschloo's unconditional test, more powerful,
    takes 1-30 s per table at ``n = 1000``, measured with ``scipy.stats.
    boschloo_exact`` on scipy 1.17).

    Parameters
    ----------
    k_a, n_a : int
        Successes and trials of the first sample (``0 <= k_a <= n_a``).
    k_b, n_b : int
        The same of the second sample.

    Returns
    -------
    float
        The p-value; NaN if either sample is empty (nothing to compare).

    References
    ----------
    R. A. Fisher, "The logic of inductive inference", J. R. Stat. Soc. 98
    (1935) 39-82.
    A. Agresti, "A survey of exact inference for contingency tables", Stat.
    Sci. 7 (1992) 131-153.
    """
    k_a, n_a, k_b, n_b = (int(x) for x in (k_a, n_a, k_b, n_b))
    if not (n_a and n_b):
        return np.nan
    if not (0 <= k_a <= n_a and 0 <= k_b <= n_b):
        raise ValueError(f"counts out of range: {k_a}/{n_a}, {k_b}/{n_b}")
    table = [[k_a, n_a - k_a], [k_b, n_b - k_b]]
    return float(_scipy_stats().fisher_exact(table, alternative="two-sided").pvalue)


def agrees(p: float, level: float = AGREEMENT_LEVEL):
    """Whether a comparison with p-value ``p`` finds agreement.

    Agreement means the test does not reject equal proportions (``p >= level``);
    it does not show that they are equal, only that the data cannot tell them
    apart at that level.

    Parameters
    ----------
    p : float
        A p-value (:func:`two_proportion_p`), NaN when nothing was compared.
    level : float
        Significance level of the test.

    Returns
    -------
    bool or None
        None when ``p`` is NaN (no verdict).
    """
    if not np.isfinite(p):
        return None
    return bool(p >= level)


def finite(values) -> np.ndarray:
    """The finite entries of ``values`` as floats (NaN and ±inf dropped).

    Parameters
    ----------
    values : array_like
        E.g. first-reset delays [s], NaN where a trial had none.

    Returns
    -------
    ndarray of float
    """
    v = np.asarray(values, dtype=float)
    return v[np.isfinite(v)]


def finite_median(values) -> float:
    """Median of the finite entries of ``values`` (NaN if there are none).

    Parameters
    ----------
    values : array_like
        Same unit as the result, e.g. [s].

    Returns
    -------
    float
    """
    v = finite(values)
    return float(np.median(v)) if len(v) else np.nan


def median_p95(values):
    """Median and 95th percentile of the finite entries of ``values``.

    The percentile interpolates linearly between order statistics (numpy's
    default, type 7 of Hyndman and Fan 1996).

    Parameters
    ----------
    values : array_like
        Same unit as the results, e.g. [s].

    Returns
    -------
    (float, float)
        Both NaN if no entry is finite.

    References
    ----------
    R. J. Hyndman, Y. Fan, "Sample quantiles in statistical packages", Am.
    Stat. 50 (1996) 361-365.
    """
    v = finite(values)
    if len(v) == 0:
        return np.nan, np.nan
    return float(np.median(v)), float(np.quantile(v, 0.95))
