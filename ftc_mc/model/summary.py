"""What ``ftc-mc model`` prints: trim, named eigenvalues, redundancy check."""

from __future__ import annotations

import math

import numpy as np

from .linear import LinearPlant, named_eigenvalues, redundancy


def model_summary(plant: LinearPlant) -> dict:
    """JSON-ready description of the linear plant.

    Parameters
    ----------
    plant : LinearPlant

    Returns
    -------
    dict
        ``trim`` (``alpha_deg``, ``throttle``, ``elevon_rad``, ``airspeed_mps``,
        ``gamma_deg``, ``dt_s``), ``eigenvalues`` (list of ``mode``,
        ``continuous`` and ``discrete`` as ``[re, im]``) and ``redundancy``
        (:func:`ftc_mc.model.linear.redundancy`).
    """
    tp = plant.trim
    eig = [{"mode": e["mode"],
            "continuous": [e["continuous"].real, e["continuous"].imag],
            "discrete": [e["discrete"].real, e["discrete"].imag]}
           for e in named_eigenvalues(plant)]
    return {
        "trim": {"alpha_deg": math.degrees(tp.alpha), "throttle": float(tp.u0[0]),
                 "elevon_rad": float(tp.u0[1]), "airspeed_mps": tp.V0,
                 "gamma_deg": math.degrees(tp.gamma0), "dt_s": plant.dt},
        "eigenvalues": eig,
        "redundancy": redundancy(plant),
    }


def mode_table(eigenvalues) -> list:
    """Lines of the eigenvalue table of ``ftc-mc model`` (longitudinal and
    6-DOF): each mode's continuous and discrete eigenvalue, natural frequency
    and damping ratio.

    Parameters
    ----------
    eigenvalues : list of dict
        ``mode`` (name; ``_`` printed as a space), ``continuous`` and
        ``discrete`` as ``[real, imag]``.
    """
    lines = [f"  {'mode':<20} {'continuous [1/s]':>26} {'discrete':>24}"
             f" {'wn [rad/s]':>10} {'zeta':>6}"]
    for e in eigenvalues:
        lc = complex(*e["continuous"])
        ld = complex(*e["discrete"])
        wn = abs(lc)
        zeta = -lc.real / wn if wn > 1e-12 else float("nan")
        lines.append(f"  {e['mode'].replace('_', ' '):<20} {lc.real:12.4f} "
                     f"{lc.imag:+12.4f}j {ld.real:10.5f} {ld.imag:+10.5f}j "
                     f"{wn:10.4f} {zeta:6.3f}")
    return lines


def format_summary(s: dict) -> str:
    """Human-readable text of :func:`model_summary`."""
    t = s["trim"]
    lines = [
        f"Skywalker X8 trim at Va = {t['airspeed_mps']:g} m/s, "
        f"gamma = {t['gamma_deg']:g} deg, dt = {t['dt_s']:g} s",
        f"  angle of attack  {t['alpha_deg']:8.4f} deg",
        f"  throttle         {t['throttle']:8.4f}",
        f"  elevons (each)   {t['elevon_rad']:8.4f} rad "
        f"({math.degrees(t['elevon_rad']):.3f} deg)",
        "",
    ] + mode_table(s["eigenvalues"])
    r = s["redundancy"]
    lines += [
        "",
        "Redundancy (paper section 2.3: columns of G(z) linearly dependent):",
        f"  left/right elevons redundant: {r['elevons_redundant']} "
        f"(max sigma2/sigma1 = {r['elevon_sv_ratio_max']:.2e})",
        f"  thrust redundant with an elevon: {r['thrust_redundant']} "
        f"(min sigma2/sigma1 = {r['thrust_sv_ratio_min']:.2e})",
    ]
    return "\n".join(lines)


def save_npz(plant: LinearPlant, f, suffix: str = ".npz") -> None:
    """Write everything a trial of the linear plant uses to a ``.npz`` file (or,
    with ``suffix=".mat"``, a MATLAB ``.mat`` with the same variables).

    :func:`ftc_mc.model.airframe_files.load_linear_model` reads it back to a
    :class:`LinearPlant` whose arrays equal these to the bit.  Variables (all
    float64; ``docs/reference/airframes.md`` has the same table):

    ======== ======== ===========================================================
    name     shape    meaning [unit]
    ======== ======== ===========================================================
    A        (9, 9)   discrete state matrix, ``x[k+1] = A x[k] + B u[k]``
    B        (9, 3)   discrete input matrix (throttle [-], left, right elevon [rad])
    C        (12, 9)  output matrix, ``z[k] = C x[k]`` (deviations from trim)
    u0       (3,)     trim commands, absolute: throttle [-], elevons [rad]
    u_lower  (3,)     absolute lower command limits
    u_upper  (3,)     absolute upper command limits
    dt       ()       sampling period [s]
    x0       (9,)     trim state, absolute: u, w [m/s], q [rad/s], x, z [m],
                      theta [rad], throttle [-], left, right elevon [rad]
    y0       (12,)    trim outputs, absolute: u, w [m/s], q [rad/s], x, z [m],
                      theta [rad], n_x, n_z [g], alpha, gamma [rad], CAS, Va [m/s]
    alpha    ()       trim angle of attack [rad]
    V0       ()       trim airspeed [m/s]
    gamma0   ()       trim flight-path angle [rad]
    Bw       (9, 3)   discrete gust input matrix, gust ``[u_g, w_g, q_g]``
                      ([m/s], [m/s], [rad/s]) held over ``dt``
    Dw       (12, 3)  gust feed-through into the 12 outputs
    ======== ======== ===========================================================

    Parameters
    ----------
    plant : LinearPlant
        A plant built from an airframe (its ``Bw``, ``Dw`` are computed by
        :func:`ftc_mc.model.wind.wind_matrices`) or read from a file (its own).
    f : str, Path or binary file
        Destination, as for :func:`numpy.savez`.
    """
    from .wind import plant_wind_matrices  # compiles the Numba dynamics: only here

    Bw, Dw = plant_wind_matrices(plant)
    save_model_file(model_variables(plant, Bw, Dw), f, suffix)


def model_variables(plant: LinearPlant, Bw, Dw) -> dict:
    """The variables of :func:`save_npz` (its table), by name."""
    tp = plant.trim
    return dict(A=plant.A, B=plant.B, C=plant.C, u0=plant.u0, u_lower=plant.u_lower,
                u_upper=plant.u_upper, dt=np.float64(plant.dt), x0=tp.x0, y0=tp.y0,
                alpha=np.float64(tp.alpha), V0=np.float64(tp.V0),
                gamma0=np.float64(tp.gamma0), Bw=Bw, Dw=Dw)


def save_model_file(variables: dict, f, suffix: str) -> None:
    """Write a linear model's ``variables`` as ``.npz`` or as a MATLAB ``.mat``
    (level 5, the variables under the same names; MATLAB and
    :func:`ftc_mc.model.airframe_files.load_linear_model` read it).

    Parameters
    ----------
    variables : dict of str to array_like
    f : binary file
    suffix : {".npz", ".mat"}
    """
    if suffix == ".mat":
        import scipy.io

        scipy.io.savemat(f, variables, format="5", oned_as="column")
    else:
        np.savez(f, **variables)
