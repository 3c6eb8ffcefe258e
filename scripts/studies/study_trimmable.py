"""Which elevon locks admit a steady flight: the trimmable set, per airframe and model.

Feeds ``docs/findings/sixdof.md`` (the set, per airframe).  A lock offset from
trim is *trimmable* when some steady flight exists with it inside the validity
envelope (airspeed 12-30 m/s, angle of attack -8 to 12 deg, bank up to 60
deg), with the healthy elevon and the throttle within the airframe's limits:

* ``nonlinear``: a steady flight of the airframe's equations
  (``ftc_mc.model.trimmable.steady_flight``: least squares from the trim and
  random starts; slow, about a second per lock);
* ``linear``: a steady flight of the 6-DOF linear model at the nominal glide,
  which the linear plant flies (``ftc_mc.model.trimmable.linear_steady_flight``:
  a linear programme; milliseconds per lock).

Prints, per airframe, model and side, the band of trimmable offsets on the
grid and whether it is one interval; for the linear model also the set's
exact ends (``ftc_mc.model.trimmable.linear_trimmable_set``: the set is one
interval, whose ends two linear programmes find).

    python scripts/studies/study_trimmable.py [--airframe x8-pyfly,x8-gryte2018]
        [--models linear,nonlinear] [--offsets=-12:12:0.25]
"""

from __future__ import annotations

import argparse
import math
import time

import ftc_mc  # noqa: F401 -- the package first (its numba settings)
import numpy as np

from ftc_mc.core.sixdof.layout import COMMAND
from ftc_mc.model.presets import resolve_airframe
from ftc_mc.model.sixdof import build_sixdof_plant
from ftc_mc.model.trimmable import linear_steady_flight, linear_trimmable_set, steady_flight

SIDES = ("left", "right")


def trimmable(name: str, model: str, side: str, offsets_deg) -> list:
    """Whether each offset [deg] of ``side`` is trimmable on ``model``."""
    af = resolve_airframe(name)
    plant = build_sixdof_plant(af)
    trim = plant.u0[COMMAND[side]]
    locks = [trim + math.radians(o) for o in offsets_deg]
    if model == "linear":
        return [linear_steady_flight(plant, side, lock) for lock in locks]
    return [steady_flight(af, side, lock).steady for lock in locks]


def exact(name: str, side: str) -> str:
    """The linear model's trimmable set of ``side`` as offsets from trim [deg]."""
    plant = build_sixdof_plant(resolve_airframe(name))
    ends = linear_trimmable_set(plant, side)
    if ends is None:
        return "none"
    trim = plant.u0[COMMAND[side]]
    return " to ".join(f"{math.degrees(e - trim):+.2f}" for e in ends) + " deg"


def band(offsets_deg, ok) -> str:
    """``lo to hi deg`` of the trimmable offsets, and whether they are one interval."""
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return "none"
    whole = idx[-1] - idx[0] + 1 == idx.size
    return (f"{offsets_deg[idx[0]]:+g} to {offsets_deg[idx[-1]]:+g} deg "
            f"({idx.size} of {len(ok)} on the grid{'' if whole else ', not one interval'})")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--airframe", default="x8-pyfly,x8-gryte2018")
    ap.add_argument("--models", default="linear,nonlinear")
    ap.add_argument("--offsets", default="-12:12:0.25",
                    help="lo:hi:step [deg]; --offsets=-30:6:0.25 (an equals sign before a minus)")
    a = ap.parse_args(argv)
    lo, hi, step = (float(v) for v in a.offsets.split(":"))
    offsets = np.round(np.arange(lo, hi + step / 2, step), 9)
    for name in a.airframe.split(","):
        for model in a.models.split(","):
            for side in SIDES:
                t0 = time.perf_counter()
                ok = trimmable(name, model, side, offsets)
                print(f"{name} {model:9s} {side:5s}: {band(offsets, ok)}"
                      + (f"; exact {exact(name, side)}" if model == "linear" else "")
                      + f" [{time.perf_counter() - t0:.1f} s]", flush=True)


if __name__ == "__main__":
    main()
