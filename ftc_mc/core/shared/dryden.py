"""Numba kernels that advance the discrete Dryden gust model.

The matrices come from :func:`ftc_mc.model.turbulence.dryden_model` (Python
side, scipy); these kernels only run the exact discrete recursion::

    gust_k      = Cd s_k                       (u_g, w_g, q_g over period k)
    s_{k+1}     = Ad s_k + Bd eta_k,   eta_k ~ N(0, I_4)

The gust state has ``N_GUST_STATE = 4`` entries (u filter, two w filter states,
the q_g lag) and is driven by ``N_GUST_NOISE = 4`` standard normal draws per
step (``Bd`` is the Cholesky factor of the exact discrete noise covariance, see
:mod:`ftc_mc.model.turbulence`).  The state size is fixed so that the update is
done on local scalars, without allocation.
"""

from __future__ import annotations

from ..jit import kernel

N_GUST_STATE = 4
N_GUST_NOISE = 4
N_GUST_OUT = 3


@kernel
def gust_step(state, eta, Ad, Bd, Cd, out):
    """Write the current gust into ``out`` and advance ``state`` by one period.

    Parameters
    ----------
    state : ndarray, shape (4,)
        Gust filter state ``s_k``, overwritten with ``s_{k+1}``.
    eta : ndarray, shape (4,)
        Standard normal draws for this step.
    Ad, Bd : ndarray, shape (4, 4)
        Discrete transition and noise matrices.
    Cd : ndarray, shape (3, 4)
        Output matrix (``u_g``, ``w_g`` [m/s], ``q_g`` [rad/s]).
    out : ndarray, shape (3,)
        Written with ``Cd s_k`` (the gust held over period k).
    """
    s0 = state[0]
    s1 = state[1]
    s2 = state[2]
    s3 = state[3]
    for i in range(N_GUST_OUT):
        out[i] = Cd[i, 0] * s0 + Cd[i, 1] * s1 + Cd[i, 2] * s2 + Cd[i, 3] * s3
    e0 = eta[0]
    e1 = eta[1]
    e2 = eta[2]
    e3 = eta[3]
    for i in range(N_GUST_STATE):
        state[i] = (Ad[i, 0] * s0 + Ad[i, 1] * s1 + Ad[i, 2] * s2 + Ad[i, 3] * s3
                    + Bd[i, 0] * e0 + Bd[i, 1] * e1 + Bd[i, 2] * e2 + Bd[i, 3] * e3)


@kernel
def gust_record(state, etas, Ad, Bd, Cd, rec):
    """Run :func:`gust_step` over ``etas`` (shape (n, 4)); writes ``rec`` (n, 3)."""
    for k in range(etas.shape[0]):
        gust_step(state, etas[k], Ad, Bd, Cd, rec[k])
