"""Measurement noise of the 6-DOF lateral loop's measured states.

The paper's filter knows the noise of the 12 longitudinal outputs only; each
measured lateral state of the 6-DOF loop takes that of the longitudinal sensor
of the same kind.  The truth draws its lateral noise so
(:func:`ftc_mc.sim.setup.build_setup`), and the side monitor's ``R`` assumes it
(:mod:`ftc_mc.sim.monitor`).
"""

from __future__ import annotations

import numpy as np


LATERAL_NOISE_AS = {"phi": "theta", "v": "w", "p": "q", "r": "q", "psi": "theta"}
"""The longitudinal output whose measurement noise each measured lateral state
of the 6-DOF loop takes (same kind of sensor: attitude, body velocity, rate)."""


def lateral_noise(r_std: np.ndarray) -> np.ndarray:
    """Noise standard deviations (5,) of the lateral loop's measured states
    (``core/sixdof/truth.LATERAL_LOOP``), from the longitudinal outputs' (12,)
    by :data:`LATERAL_NOISE_AS`."""
    from ..conventions import LONGITUDINAL
    from ..core.sixdof.truth import LATERAL_LOOP, N_LAT_MEASURED

    return np.array([r_std[LONGITUDINAL.output(LATERAL_NOISE_AS[n])]
                     for n in LATERAL_LOOP[:N_LAT_MEASURED]])
