"""Excitation signals and the saturation with excitation headroom (eqs. 15-16).

Signals are functions of the step count ``k`` since the request (``k = 0`` is the
first step of the signal); outside their support they are zero.
"""

from __future__ import annotations

from ...conventions import S3211_UNITS  # noqa: F401  (3, 2, 1, 1): Fig. 4
from ..jit import kernel


@kernel(internal=True)
def doublet_length(half_steps):
    """Steps a doublet lasts: two halves."""
    return 2 * half_steps


@kernel(internal=True)
def signal_3211_length(unit_steps):
    """Steps a 3211 lasts: 3 + 2 + 1 + 1 units."""
    total = 0
    for n in S3211_UNITS:
        total += n
    return total * unit_steps


@kernel
def running(k, start, length):
    """Whether a signal started at step ``start`` and lasting ``length`` steps
    is on at step ``k``."""
    return 0 <= k - start < length


@kernel
def doublet(k, half_steps, amplitude):
    """Doublet: ``+A`` for ``half_steps`` steps, then ``-A`` for as many (Fig. 4).

    Parameters
    ----------
    k : int
        Steps since the start of the signal.
    half_steps : int
        Length of each half [steps], >= 1.
    amplitude : float
        ``A`` [command unit].

    Returns
    -------
    float
    """
    if k < 0:
        return 0.0
    if k < half_steps:
        return amplitude
    if k < 2 * half_steps:
        return -amplitude
    return 0.0


@kernel(internal=True)
def signal_3211(k, unit_steps, amplitude):
    """3211 input: ``+A, -A, +A, -A`` lasting 3, 2, 1, 1 units (Fig. 4).

    Parameters
    ----------
    k : int
        Steps since the start of the signal.
    unit_steps : int
        One unit [steps], >= 1.
    amplitude : float
        ``A`` [command unit].

    Returns
    -------
    float
    """
    if k < 0:
        return 0.0
    n = k // unit_steps
    if n < 3:
        return amplitude
    if n < 5:
        return -amplitude
    if n < 6:
        return amplitude
    if n < 7:
        return -amplitude
    return 0.0


@kernel(internal=True)
def saturate(U, s, A, lo, hi):
    """Command saturation that keeps room for the excitation (eq. 15).

    ``f(U, s, A) = min(hi, max(lo, min(hi - A, max(lo + A, U)) + s))``; with no
    excitation (``A = 0``, ``s = 0``) this is eq. (16), ``min(hi, max(lo, U))``.

    Parameters
    ----------
    U : float
        Controller output (deviation from trim).
    s : float
        Excitation signal value.
    A : float
        Excitation amplitude while a signal is active, else 0.
    lo, hi : float
        Command limits as deviations from trim.

    Returns
    -------
    float
    """
    inner = min(hi - A, max(lo + A, U)) + s
    return min(hi, max(lo, inner))
