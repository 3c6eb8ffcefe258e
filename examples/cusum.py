"""A CUSUM on the recorded normalised innovations: a detector of your own, in NumPy.

Score it on a run recorded with ``--record signals``::

    ftc-mc run configs/paper_tables.yaml --trials 200 --record signals --out results/rec
    ftc-mc score results/rec --detector examples.cusum:cusum
    ftc-mc report results/rec -o report.md      # its rows beside the built-in designs

Two-sided CUSUM (Page 1954) of each innovation ``x`` (unit variance when the
filter's model holds): ``g+ = max(0, g+ + x - k)``, ``g- = max(0, g- - x - k)``;
an alarm when either exceeds ``h``.  The channel that fires names the block the
way Table 1 does: ``n_x`` the thrust, ``q`` the elevons.

Its score (``configs/paper_tables.yaml``, 100 trials per row, seed 2026, the
paper design's loop; docs/guides/your-detector.md): correct 100 % of the elevon
and engine locks (the paper's design: 24 % of elevon locks by its first reset),
82 % of elevon losses, 94 % of engine losses, 76-77 % of the recoveries, no
inappropriate alarm and no false alarm; mean delay 0.1-0.4 s.
"""

import numpy as np

K = 0.75
"""Drift allowance [innovation standard deviations per step]."""
H = 12.0
"""Alarm threshold of the cumulative sums."""
ARMED_S = 2.0
"""The filter's start-up: no alarm before this time [s]."""

CHANNELS = {"innov_nx": "thrust", "innov_q": "elevons"}


def cusum(signals, names, dt):
    """First alarm time [s] (NaN: none) and the block it names, per trial."""
    n, steps, _ = signals.shape
    cols = [names.index(c) for c in CHANNELS]
    x = np.nan_to_num(signals[:, :, cols].astype(np.float64))  # NaN after a trial stopped
    g_hi = np.zeros((n, len(cols)))
    g_lo = np.zeros((n, len(cols)))
    alarm = np.full(n, np.nan)
    block = np.full(n, "", dtype=object)
    armed = int(round(ARMED_S / dt))
    for j in range(steps):
        g_hi = np.maximum(0.0, g_hi + x[:, j] - K)
        g_lo = np.maximum(0.0, g_lo - x[:, j] - K)
        if j + 1 < armed:
            g_hi[:] = 0.0
            g_lo[:] = 0.0
            continue
        g = np.maximum(g_hi, g_lo)
        fire = (g > H).any(axis=1) & np.isnan(alarm)
        if fire.any():
            alarm[fire] = (j + 1) * dt
            which = np.argmax(g[fire], axis=1)
            block[fire] = np.array(list(CHANNELS.values()), dtype=object)[which]
    return alarm, block


cusum.columns = tuple(CHANNELS)
