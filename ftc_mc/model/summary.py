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
        f"  {'mode':<20} {'continuous [1/s]':>26} {'discrete':>24}"
        f" {'wn [rad/s]':>10} {'zeta':>6}",
    ]
    for e in s["eigenvalues"]:
        lc = complex(*e["continuous"])
        ld = complex(*e["discrete"])
        wn = abs(lc)
        zeta = -lc.real / wn if wn > 1e-12 else float("nan")
        lines.append(f"  {e['mode']:<20} {lc.real:12.4f} {lc.imag:+12.4f}j "
                     f"{ld.real:10.5f} {ld.imag:+10.5f}j {wn:10.4f} {zeta:6.3f}")
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


def save_npz(plant: LinearPlant, f) -> None:
    """Write A, B, C, u0, command limits and dt to an open binary file (.npz)."""
    np.savez(f, A=plant.A, B=plant.B, C=plant.C, u0=plant.u0, u_lower=plant.u_lower,
             u_upper=plant.u_upper, dt=np.float64(plant.dt), x0=plant.trim.x0,
             y0=plant.trim.y0)
