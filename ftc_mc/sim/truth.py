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

from ..conventions import N_U, N_X, PLANT_KINDS, TURBULENCE_LEVELS
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
                       where: str = "model.airframe", monitor=None, paper=None):
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
    paper : tuple or None
        ``(K0, eng, Q, R, alpha)``: the paper's c0 gain, c1 tables, weights
        and discount, for c0 and c1 to fly the coupled 6-DOF laws
        (``controller.coupling: coupled``, :func:`coupled_controllers`);
        None: the separate loops.

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
    G0, G1 = coupled_controllers(six, lat, paper)
    c = np.ascontiguousarray
    pl = SixDofTruth(
        kind=SIXDOF_LINEAR if kind == "linear" else SIXDOF_NONLINEAR,
        n_sub=int(substeps), dt=float(plant.dt), p=c(six.trim.params, dtype=np.float64),
        x0=c(six.trim.x0, dtype=np.float64), y0=c(six.trim.y0, dtype=np.float64),
        u0=c(six.u0, dtype=np.float64), u_ff=c(six.u0 - plant.u0, dtype=np.float64),
        A=c(six.A), B=c(six.B), C=c(six.C), Bw=c(six.Bw), Dw=c(six.Dw),
        turb=lon.turb, Ad=lon.Ad, Bd=lon.Bd, Cd=lon.Cd, Adl=Adl, Bdl=Bdl, Cdl=Cdl,
        K_lat=c(lat.K[0], dtype=np.float64), coupled=int(paper is not None), G0=G0, G1=G1,
        a_act=elevon_lag(af.tau_elevon, plant.dt),
        lon_state=lon_state, lon_out=lon_out, lat_out=lat_out,
        monitor=side_monitor(six, six.u0 - plant.u0, plant.u_lower, plant.u_upper, lon_out,
                             monitor, af.b, af))
    return pl, gust, gust_lat


def kernel_gain(K: np.ndarray, K_paper: np.ndarray) -> np.ndarray:
    """A coupled gain in the kernel's form (``SixDofTruth.G0``, ``G1``).

    The kernel flies the paper's ``-K_paper xhat`` and adds ``-G s``, ``s =
    [xhat, lat]`` (``core/sixdof/truth.py``), so that the sum is ``-K`` on the
    estimate's longitudinal states and the lateral loop's states
    (:data:`ftc_mc.core.sixdof.truth.LATERAL_LOOP`).  Both hold the elevons:
    ``K``'s elevon columns are split into their mean, read from the estimate
    (the elevator, the longitudinal filter's), and their half difference,
    read from the loop's elevon model (the aileron, the lateral loop's), as
    the separate loops split them.

    Parameters
    ----------
    K : ndarray, shape (..., 3, 15)
        Coupled gains on the 6-DOF state.
    K_paper : ndarray, shape (..., 3, 9)
        The paper's gains they replace, on the longitudinal states.

    Returns
    -------
    G : ndarray, shape (..., 3, 16)
    """
    from ..conventions import STATE_NAMES
    from ..core.sixdof.layout import STATE, sixdof_name
    from ..core.sixdof.truth import LATERAL_LOOP

    left, right = K[..., STATE["left"]], K[..., STATE["right"]]
    mean, half_diff = (left + right) / 2.0, (left - right) / 2.0
    split = {"left": half_diff, "right": -half_diff}
    cols = [mean if sixdof_name(n) in ("left", "right") else K[..., STATE[sixdof_name(n)]]
            for n in STATE_NAMES]
    cols += [split[n] if n in split else K[..., STATE[n]] for n in LATERAL_LOOP]
    G = np.stack(cols, axis=-1)
    G[..., :len(STATE_NAMES)] -= K_paper
    return np.ascontiguousarray(G)


def coupled_controllers(six, lat, paper):
    """``(G0, G1)`` of :class:`SixDofTruth`: c0 and c1 as coupled 6-DOF laws
    less the paper's (:func:`kernel_gain`).

    Parameters
    ----------
    six : SixDofPlant
    lat : LateralDesign
    paper : tuple or None
        ``(K0, eng, Q, R, alpha)``: the paper's c0 gain, its c1 tables
        (``EngineTables``), weights and discount; None: zeros (the separate
        loops).
    """
    from ..core.shared.interp import EngineTables
    from ..core.sixdof.truth import LATERAL_LOOP
    from ..design.lateral import coupled_engine_tables, coupled_lqr

    n = N_X + len(LATERAL_LOOP)
    if paper is None:
        one = np.zeros(1)
        return np.zeros((N_U, n)), EngineTables(K=np.zeros((1, 1, N_U, n)),
                                                k=np.zeros((1, 1, N_U)), b0_grid=one,
                                                b1_grid=one)
    K0, eng, Q, R, alpha = paper
    d = coupled_lqr(six, K0, Q, R, alpha, lat)
    t6 = coupled_engine_tables(six, d, eng.b0_grid, eng.b1_grid)
    G1 = EngineTables(K=kernel_gain(t6.K, eng.K), k=np.ascontiguousarray(t6.k - eng.k),
                      b0_grid=eng.b0_grid, b1_grid=eng.b1_grid)
    return kernel_gain(d.K, K0), G1
