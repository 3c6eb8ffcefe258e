"""Namedtuples of arrays that carry settings into the kernels.

Built from the linear plant and the configuration by :mod:`ftc_mc.estimator`;
the kernels only read them.
"""

from __future__ import annotations

from collections import namedtuple

FilterModel = namedtuple("FilterModel", [
    "A",        # (9, 9)  discrete state matrix (eq. 1)
    "B",        # (9, 3)  discrete input matrix (eq. 1)
    "Bb0",      # (9, 2)  input matrix of b0 (thrust, elevon sum), eq. (4)
    "C",        # (12, 9) output matrix (eq. 1)
    "c_ident",  # (12,) int64: state index when row r of C is a unit row, else -1
    "u0",       # (3,)  trim commands, absolute
    "q_diag",   # (14,) diagonal of Q (eq. 5; paper section 5.1)
    "r_diag",   # (12,) diagonal of R (paper section 5.1)
    "lo",       # (5,)  lower bounds of b0, b1 (eq. 6)
    "hi",       # (5,)  upper bounds of b0, b1 (eq. 6)
])
"""The augmented Kalman filter's model (paper eqs. 4-6)."""

Detection = namedtuple("Detection", [
    "t_q",        # threshold on r_q (Table 1), > 0
    "t_nx",       # threshold on r_nx (Table 1), > 0
    "swapped",    # 0: Table 1 as printed; 1: third clause's r_nz test swapped
    "reset_var",  # (5,) variance of each fault parameter after its block's reset
])
"""Residual signature and covariance reset (paper section 3.2.2, Table 1)."""

Belief = namedtuple("Belief", [
    "TM",  # (4, 4) column-stochastic mode transition matrix (eq. 13)
    "lo",  # (4, 5) lower edge of each mode's box of (b0, b1) (eq. 12)
    "hi",  # (4, 5) upper edge of each mode's box
])
"""Four-mode belief: nominal, engine, left elevon, right elevon (section 3.3)."""
