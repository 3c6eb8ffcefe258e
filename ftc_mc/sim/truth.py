"""The truth plant a trial simulates (:class:`~ftc_mc.core.longitudinal.settings.TruthPlant`).

The estimator and the controllers always use the linear model of eq. (1); the
truth they act on can be that same linear model (the paper's setting) or the
nonlinear X8 of :mod:`ftc_mc.core.longitudinal.nonlinear`, each in still air or in
MIL-F-8785C Dryden turbulence (:mod:`ftc_mc.model.turbulence`).

The linear plant in turbulence needs the gust's input matrices
(:func:`ftc_mc.model.wind.plant_wind_matrices`): those of a linear-model file,
or the Jacobians of the nonlinear equations with respect to the wind at trim.
"""

from __future__ import annotations

import numpy as np

from ..conventions import PLANT_KINDS, TURBULENCE_LEVELS
from ..core.longitudinal.settings import TruthPlant
from ..model.linear import LinearPlant
from ..model.turbulence import DrydenModel, dryden_model
from ..model.wind import plant_wind_matrices


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
            Bw, Dw = plant_wind_matrices(plant)
    pl = TruthPlant(kind=PLANT_KINDS.index(kind), n_sub=int(substeps), dt=float(plant.dt),
                    p=np.ascontiguousarray(tp.params, dtype=np.float64),
                    x0=np.ascontiguousarray(tp.x0, dtype=np.float64),
                    y0=np.ascontiguousarray(tp.y0, dtype=np.float64),
                    turb=0 if gust is None else 1, Ad=Ad, Bd=Bd, Cd=Cd, Bw=Bw, Dw=Dw)
    return pl, gust
