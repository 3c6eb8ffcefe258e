"""One full estimator step of one trajectory (paper Fig. 2 and section 3.2).

Order within a step ``k -> k+1``:

1. predict ``X_{k+1|k}``, ``P_{k+1|k}`` with the command ``u_k`` (eq. 5);
2. residuals ``r_q, r_nx, r_nz`` on the prediction (eqs. 9-11);
3. Table 1 signature; if it fires, the suspected block is reset in ``P_{k|k}``
   (section 3.2.2) and ``P_{k+1|k}`` is predicted again from it;
4. measurement update with ``z_{k+1}``;
5. active-set projection of the state (eqs. 6-8); ``P`` stays unconstrained
   (semi-closed loop).

Why step 3 resets ``P_{k|k}`` and predicts again rather than zeroing the block of
``P_{k+1|k}`` directly: zeroing the block's rows and columns in ``P_{k+1|k}``
also zeroes its covariance with the plant state, so the update's gain for the
suspected parameters is exactly zero on that step.  While the residuals stay
above threshold the reset repeats every step and the parameters never move
(measured on elevon locks 0.2 rad from trim: in 6 of 8 seeds the elevon
parameters stayed frozen for the whole 60 s).  Predicting from the reset
``P_{k|k}`` gives ``P_{k+1|k}`` the block's reset variances (plus ``Q^b``) and the
cross-covariances ``Phi(u) P_bb`` through which the update can move them; the
printed reset variances and the zeroed correlations are kept.
"""

from __future__ import annotations

from ..jit import kernel
from .kalman import predict, project, residuals, update
from .signature import NO_RESET, reset_covariance, signature


@kernel
def filter_step(xa, P, u, z, fm, det, phi, T, h, res, x_prev, P_prev):
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
    x_prev, P_prev : ndarray
        Work arrays of shapes (14,) and (14, 14): ``X_{k|k}`` and ``P_{k|k}``.

    Returns
    -------
    int
        The block reset this step (``signature.NO_RESET`` if none).
    """
    n = xa.shape[0]
    for i in range(n):
        x_prev[i] = xa[i]
        for j in range(n):
            P_prev[i, j] = P[i, j]
    predict(xa, P, u, fm, phi, T)
    residuals(xa, P, z, fm, res)
    block = signature(res[0], res[1], res[2], det.t_q, det.t_nx, det.swapped)
    if block != NO_RESET:
        reset_covariance(P_prev, block, det.reset_var)
        for i in range(n):
            xa[i] = x_prev[i]
            for j in range(n):
                P[i, j] = P_prev[i, j]
        predict(xa, P, u, fm, phi, T)
    update(xa, P, z, fm, h)
    project(xa, fm)
    return block
