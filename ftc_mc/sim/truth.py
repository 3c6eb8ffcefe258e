"""The truth plant a trial simulates (:class:`~ftc_mc.core.settings.TruthPlant`).

The estimator and the controllers always use the linear model of eq. (1); the
truth they act on can be that same linear model (the paper's setting) or the
nonlinear X8 of :mod:`ftc_mc.core.nonlinear`, each in still air or in
MIL-F-8785C Dryden turbulence (:mod:`ftc_mc.model.turbulence`).

The linear plant in turbulence needs the gust's input matrices: the Jacobians
of the nonlinear derivatives and outputs with respect to the wind
``[u_g, w_g, q_g]`` at trim, the first discretised with the same zero-order
hold as ``A`` and ``B`` (the gust is held over each control period).
"""

from __future__ import annotations

import numpy as np
import scipy.signal

from ..conventions import PLANT_KINDS, TURBULENCE_LEVELS
from ..core.nonlinear import derivatives_nb, outputs_nb
from ..core.settings import TruthPlant
from ..model.dynamics import N_OUTPUT, N_STATE
from ..model.linear import LinearPlant, jacobian
from ..model.turbulence import DrydenModel, dryden_model


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
    Ewc[3:] = 0.0
    Dw[:6] = 0.0
    _, Bw, _, _, _ = scipy.signal.cont2discrete(
        (plant.Ac, Ewc, plant.Cc, np.zeros((N_OUTPUT, 3))), plant.dt, method="zoh")
    return np.ascontiguousarray(Bw), np.ascontiguousarray(Dw), Ewc


def truth_plant(plant: LinearPlant, kind: str = "linear", substeps: int = 10,
                turbulence: str = "none", altitude_m: float = 100.0):
    """Kernel settings of the truth plant, and its gust model.

    Parameters
    ----------
    plant : LinearPlant
        The linear model (trim point, ``dt``, matrices).
    kind : {"linear", "nonlinear"}
    substeps : int
        RK4 sub-steps per control period of the nonlinear plant (>= 1).
        The choices are trusted: they come from a validated ``plant`` section.
    turbulence : {"none", "light", "moderate", "severe"}
        MIL-F-8785C level (W20 = 0, 15, 30, 45 kt).
    altitude_m : float
        Altitude for the Dryden scale lengths [m].

    Returns
    -------
    pl : TruthPlant
    gust : DrydenModel or None
        ``None`` in still air.
    """
    # the choices come from a validated config (config/schema.py: PlantConfig)
    assert kind in PLANT_KINDS and turbulence in TURBULENCE_LEVELS, (kind, turbulence)
    assert isinstance(substeps, int) and substeps >= 1, substeps
    tp = plant.trim
    gust: DrydenModel | None = None
    Ad = np.zeros((4, 4))
    Bd = np.zeros((4, 4))
    Cd = np.zeros((3, 4))
    Bw = np.zeros((9, 3))
    Dw = np.zeros((12, 3))
    if turbulence != "none":
        gust = dryden_model(turbulence, V=tp.V0, altitude_m=altitude_m, dt=plant.dt)
        Ad, Bd, Cd = (np.ascontiguousarray(a) for a in (gust.Ad, gust.Bd, gust.Cd))
        if kind == "linear":
            Bw, Dw, _ = wind_matrices(plant)
    pl = TruthPlant(kind=PLANT_KINDS.index(kind), n_sub=int(substeps), dt=float(plant.dt),
                    p=np.ascontiguousarray(tp.params, dtype=np.float64),
                    x0=np.ascontiguousarray(tp.x0, dtype=np.float64),
                    y0=np.ascontiguousarray(tp.y0, dtype=np.float64),
                    turb=0 if gust is None else 1, Ad=Ad, Bd=Bd, Cd=Cd, Bw=Bw, Dw=Dw)
    return pl, gust
