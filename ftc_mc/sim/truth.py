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

import math

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


def sixdof_truth_plant(plant: LinearPlant, kind: str = "nonlinear", substeps: int = 10,
                       turbulence: str = "none", altitude_m: float = 100.0,
                       where: str = "model.airframe", monitor=None):
    """Kernel settings of the 6-DOF truth plant (``plant.dof: 6``), and its gust
    models.

    The airframe of the longitudinal ``plant`` is trimmed, linearised and
    discretised in six degrees of freedom (:func:`ftc_mc.model.sixdof.build_sixdof_plant`)
    at the same airspeed, flight-path angle and period, and the lateral loop
    is designed on that model (:func:`ftc_mc.design.lateral.lateral_lqr`).
    The 6-DOF modules are imported here, so a longitudinal run never loads them.

    Parameters
    ----------
    plant : LinearPlant
        The paper's longitudinal model (its airframe and trim point).
    kind : {"linear", "nonlinear"}
        The discrete 6-DOF linear model, or the 6-DOF equations by RK4.
    substeps, turbulence, altitude_m
        As :func:`truth_plant`.
    where : str
        The config field naming the airframe, for error lines.
    monitor : MonitorSpec or None
        The side monitor flown beside the scheme (:mod:`ftc_mc.sim.monitor`);
        None: off.

    Returns
    -------
    pl : SixDofTruth
    gust : DrydenModel or None
        The longitudinal gust model (``None`` in still air).
    gust_lat : DrydenLateralModel or None
        The lateral one.

    Raises
    ------
    UserError
        The airframe has no lateral-directional data (a linear-model file, or an
        airframe file without them), naming what is missing.
    """
    from ..core.sixdof.truth import (SIXDOF_LINEAR, SIXDOF_NONLINEAR, SixDofTruth,
                                     elevon_lag, index_maps)
    from ..design.lateral import lateral_lqr
    from ..errors import UserError
    from ..model.sixdof import build_sixdof_plant, require_lateral
    from ..model.turbulence import dryden_lateral_model
    from .monitor import side_monitor

    assert kind in PLANT_KINDS and turbulence in TURBULENCE_LEVELS, (kind, turbulence)
    af = plant.airframe
    if af is None:
        raise UserError(f"{where}: plant.dof 6 needs an airframe (a preset or an airframe "
                        "file with lateral-directional data); a linear-model file has "
                        "no 6-DOF model")
    require_lateral(af, where)
    tp = plant.trim
    six = build_sixdof_plant(af, tp.V0, math.degrees(tp.gamma0), plant.dt, where)
    lat = lateral_lqr(six)
    lon, gust = truth_plant(plant, "nonlinear", substeps, turbulence, altitude_m)
    gust_lat = None
    Adl, Bdl, Cdl = np.zeros((4, 4)), np.zeros((4, 2)), np.zeros((3, 4))
    if turbulence != "none":
        gust_lat = dryden_lateral_model(turbulence, V=tp.V0, altitude_m=altitude_m,
                                        dt=plant.dt, span=af.b)
        Adl, Bdl, Cdl = (np.ascontiguousarray(a) for a in (gust_lat.Ad, gust_lat.Bd,
                                                            gust_lat.Cd))
    lon_state, lon_out, lat_out = index_maps()
    c = np.ascontiguousarray
    pl = SixDofTruth(
        kind=SIXDOF_LINEAR if kind == "linear" else SIXDOF_NONLINEAR,
        n_sub=int(substeps), dt=float(plant.dt), p=c(six.trim.params, dtype=np.float64),
        x0=c(six.trim.x0, dtype=np.float64), y0=c(six.trim.y0, dtype=np.float64),
        u0=c(six.u0, dtype=np.float64), u_ff=c(six.u0 - plant.u0, dtype=np.float64),
        A=c(six.A), B=c(six.B), C=c(six.C), Bw=c(six.Bw), Dw=c(six.Dw),
        turb=lon.turb, Ad=lon.Ad, Bd=lon.Bd, Cd=lon.Cd, Adl=Adl, Bdl=Bdl, Cdl=Cdl,
        K_lat=c(lat.K[0], dtype=np.float64), a_act=elevon_lag(af.tau_elevon, plant.dt),
        lon_state=lon_state, lon_out=lon_out, lat_out=lat_out,
        monitor=side_monitor(six, six.u0 - plant.u0, plant.u_lower, plant.u_upper, lon_out,
                             monitor, af.b, af))
    return pl, gust, gust_lat


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
