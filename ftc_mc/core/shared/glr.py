"""Windowed GLR test of the residuals for a persistent change.

The paper tests one step: ``r_i = mu_i^2 / S_ii`` against its threshold (eqs.
9-11, Table 1).  A fault that shifts an innovation by less than its standard
deviation at each step is lost in one step but not over many.  With the signed
normalised innovations ``e_j = mu_j / sqrt(S_jj)`` (standard normal and white
under no fault), the generalised likelihood ratio of a constant shift ``nu`` in
their mean from an unknown step ``j`` on, over the last ``W`` steps, is

    g_k = max_{k-W < j <= k} (sum_{i=j}^{k} e_i)^2 / (k - j + 1)

(Willsky & Jones, IEEE TAC 1976; Basseville & Nikiforov, *Detection of Abrupt
Changes*, 1993, section 2.4 with a known variance), over changes at least
``m_min`` steps old (``Detection.min_window``; 1: any): for each ``j`` the
statistic is chi-square with one degree of freedom under no fault, and a shift
``nu`` grows it as ``m nu^2`` with the ``m`` steps since the change.  It
replaces ``r_q``, ``r_nx``, ``r_nz`` in Table 1, each channel on its own window.
After a reset the window restarts (the innovations before it belong to the
fault the reset answered).  ``W = 1`` gives the one-step test back.

Each innovation may enter the window clipped to ``[-c, c]``
(``Detection.clip``; ``inf``: not clipped), a Huber-type limit (Huber, *Robust
Statistics*, 1981, section 4.5): the sum then grows by at most ``c`` per step,
so one step's outlier of many standard deviations (the n_x spike of a sharp
vertical gust, whose alpha^2 term the filter's linearisation does not see;
docs/findings/turbulence-designs.md) no longer passes a threshold alone, while a persistent shift
``nu < c`` is summed unchanged.

Plain-NumPy twin: ``tests/naive.py::glr_ref``.
"""

from __future__ import annotations

from ..jit import kernel


@kernel(inline="always")
def glr_lanes(innov, ebuf, ecount, k, m_min, clip, stat):
    """Append step ``k``'s innovations to each lane's window and form the GLR.

    Parameters
    ----------
    innov : ndarray, shape (c, L)
        Signed normalised innovations of this step (``c = 3``: q, n_x, n_z).
    ebuf : ndarray, shape (W, c, L)
        Ring buffer of the window: step ``k`` goes to row ``k % W``.
    ecount : ndarray of int64, shape (L,)
        Innovations in each lane's window, updated (at most ``W``).
    k : int
        Step (any counter that advances by one per call).
    m_min : int
        Shortest change tested, ``1 <= m_min <= W``: the maximum runs over
        ``m_min <= k - j + 1``, so an outlier of one step does not count as a
        persistent change; 0 until the window holds ``m_min`` innovations.
    clip : float
        Each innovation is stored clipped to ``[-clip, clip]`` (``inf``: as is).
    stat : ndarray, shape (c, L)
        Written with ``g_k`` per channel and lane.
    """
    W = ebuf.shape[0]
    nc = innov.shape[0]
    L = innov.shape[1]
    p = k % W
    for c in range(nc):
        for l in range(L):
            e = innov[c, l]
            ebuf[p, c, l] = clip if e > clip else (-clip if e < -clip else e)
    for l in range(L):
        m = ecount[l] + 1
        ecount[l] = m if m < W else W
    for c in range(nc):
        for l in range(L):
            acc = 0.0
            best = 0.0
            row = p
            for m in range(1, ecount[l] + 1):
                acc += ebuf[row, c, l]
                g = acc * acc / m
                if g > best and m >= m_min:
                    best = g
                row = row - 1 if row > 0 else W - 1
            stat[c, l] = best


@kernel(inline="always")
def glr_restart(block, ecount):
    """Empty the window of every lane that reset a block (``block != 0``)."""
    for l in range(block.shape[0]):
        if block[l] != 0:
            ecount[l] = 0
