"""Gust input matrices of the linear plant (Dryden turbulence on eq. 1).

The linear truth plant in turbulence is ``x+ = A x + B e + B_w g`` and
``z = C x + D_w g`` with the gust ``g = [u_g, w_g, q_g]`` ([m/s], [m/s],
[rad/s]) held over each control period.  ``B_w`` and ``D_w`` are the Jacobians
of the nonlinear derivatives and outputs (:mod:`ftc_mc.core.longitudinal.nonlinear`) with
respect to the wind at trim, the first discretised with the same zero-order hold
as ``A`` and ``B``; a linear model read from a file brings its own.
"""

from __future__ import annotations

import numpy as np

from ..conventions import LONGITUDINAL
from ..conventions import N_X as N_STATE
from ..conventions import N_Z as N_OUTPUT
from ..core.longitudinal.nonlinear import derivatives_nb, outputs_nb
from .linear import LinearPlant, jacobian, zoh


def wind_matrices(plant: LinearPlant):
    """Gust input matrices of the linear plant.

    Parameters
    ----------
    plant : LinearPlant

    Returns
    -------
    Bw : ndarray, shape (9, 3)
        Discrete (zero-order hold over ``plant.dt``) input matrix of the gust
        ``[u_g, w_g, q_g]`` ([m/s], [m/s], [rad/s]).
    Dw : ndarray, shape (12, 3)
        Feed-through of the gust into the 12 outputs.
    Ewc : ndarray, shape (9, 3)
        Continuous input matrix ``d f / d wind`` at trim.
    """
    tp = plant.trim

    def f_w(wind):
        dx = np.empty(N_STATE)
        derivatives_nb(tp.x0, tp.u0, tp.params, np.ascontiguousarray(wind), dx)
        return dx

    def h_w(wind):
        y = np.empty(N_OUTPUT)
        outputs_nb(tp.x0, tp.params, np.ascontiguousarray(wind), y)
        return y

    zero = np.zeros(3)
    Ewc = jacobian(f_w, zero)
    Dw = jacobian(h_w, zero)
    # structural zeros (the finite differences leave ~1e-12 there): the
    # kinematics, attitude and actuator rates and the first six outputs (the
    # states themselves) do not depend on the air's motion
    Ewc[LONGITUDINAL.state("x"):] = 0.0
    Dw[:LONGITUDINAL.output("n_x")] = 0.0
    _, Bw = zoh(plant.Ac, Ewc, plant.dt)
    return np.ascontiguousarray(Bw), np.ascontiguousarray(Dw), Ewc


def plant_wind_matrices(plant: LinearPlant):
    """``(Bw, Dw)`` of a plant: its own (a linear-model file) or :func:`wind_matrices`."""
    if plant.Bw is not None and plant.Dw is not None:
        return plant.Bw, plant.Dw
    Bw, Dw, _ = wind_matrices(plant)
    return Bw, Dw
