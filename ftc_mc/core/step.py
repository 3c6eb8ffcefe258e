"""One full estimator step of one trajectory (paper Fig. 2 and section 3.2).

Order within a step ``k -> k+1``:

1. predict ``X_{k+1|k}``, ``P_{k+1|k}`` with the command ``u_k`` (eq. 5);
2. residuals ``r_q, r_nx, r_nz`` on the prediction (eqs. 9-11);
3. Table 1 signature; if it fires, reset that block of ``P_{k+1|k}``
   (section 3.2.2), so the update can move the suspected fault parameters;
4. measurement update with ``z_{k+1}``;
5. active-set projection of the state (eqs. 6-8); ``P`` stays unconstrained
   (semi-closed loop).
"""

from __future__ import annotations

from .jit import kernel
from .kalman import predict, project, residuals, update
from .signature import reset_covariance, signature


@kernel
def filter_step(xa, P, u, z, fm, det, phi, T, h, res):
    """Advance the augmented filter by one sampling period.

    Parameters
    ----------
    xa : ndarray, shape (14,)
        Augmented estimate, updated in place.
    P : ndarray, shape (14, 14)
        Covariance, updated in place.
    u : ndarray, shape (3,)
        Command deviation applied during the step.
    z : ndarray, shape (12,)
        Measurement deviation from trim outputs at the end of the step.
    fm : FilterModel
    det : Detection
    phi, T, h : ndarray
        Work arrays of shapes (9, 5), (9, 14), (14,).
    res : ndarray, shape (3,)
        Written with ``[r_q, r_nx, r_nz]``.

    Returns
    -------
    int
        The block reset this step (``signature.NO_RESET`` if none).
    """
    predict(xa, P, u, fm, phi, T)
    residuals(xa, P, z, fm, res)
    block = signature(res[0], res[1], res[2], det.t_q, det.t_nx, det.swapped)
    reset_covariance(P, block, det.reset_var)
    update(xa, P, z, fm, h)
    project(xa, fm)
    return block
