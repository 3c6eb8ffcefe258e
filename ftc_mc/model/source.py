"""Where a run's plant comes from: a preset, an airframe file or a linear-model file.

``model.airframe`` in a config (and ``--airframe`` on the command line) is one of

* a preset name (:data:`ftc_mc.model.presets.PRESETS`): its equations are flown
  by the nonlinear truth plant and trimmed and linearised for the filter;
* the path of an airframe YAML file (``ftc-mc model --airframe NAME --export``
  writes one; ``docs/reference/airframes.md`` lists its fields): the same;
* the path of a linear model (``.npz`` as written by ``ftc-mc model --save``, or
  a MATLAB ``.mat`` with the same variables): its own trim, matrices and gust
  input matrices; it has no equations, so it flies only the linear truth plant.

The default is :data:`DEFAULT_AIRFRAME`; ``docs/reference/airframes.md`` gives the
measurements it was chosen on.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..conventions import DEFAULT_AIRFRAME  # noqa: F401  (re-exported)
from ..errors import UserError
from .airframe_files import load_linear_model
from .linear import LinearPlant, build_plant, trim
from .presets import PRESETS, resolve_airframe


LINEAR_MODEL_SUFFIXES = (".npz", ".mat")


def is_linear_model(spec: str) -> bool:
    """Whether ``model.airframe`` names a linear-model file (``.npz``/``.mat``)."""
    return spec not in PRESETS and Path(spec).suffix.lower() in LINEAR_MODEL_SUFFIXES


def airframe_label(spec: str) -> str:
    """Short name of an airframe for output folders and tables: the preset's
    name, or the file's stem."""
    return spec if spec in PRESETS else Path(spec).stem


def check_airframe(spec: str) -> None:
    """Read the airframe or linear model ``spec`` names, or raise :class:`UserError`.

    Used by the config schema, so a bad preset name or file is refused before
    anything runs; the trim itself is checked when the plant is built.
    """
    if is_linear_model(spec):
        load_linear_model(spec)
    else:
        resolve_airframe(spec)


def check_condition(spec: str, V0: float, gamma_deg: float, dt: float,
                    alpha_range=None) -> tuple:
    """Refuse, as :func:`load_plant` would, a condition the airframe cannot fly
    (only the trim is computed, not the linearisation); return the absolute
    command limits ``(lower, upper)`` (throttle [-], elevons [rad])."""
    if is_linear_model(spec):
        plant = load_plant(spec, V0, gamma_deg, dt)
        return tuple(plant.u_lower), tuple(plant.u_upper)
    af = resolve_airframe(spec)
    trim(af, V0, gamma_deg, alpha_range)
    return af.command_lower, af.command_upper


def load_plant(spec: str, V0: float, gamma_deg: float, dt: float,
               alpha_range=None) -> LinearPlant:
    """The linear plant of a run (paper eq. 1).

    Parameters
    ----------
    spec : str
        ``model.airframe``: a preset name, an airframe YAML path or a linear-model
        path (module docstring).
    V0 : float
        Trim airspeed [m/s] (``model.airspeed_mps``).
    gamma_deg : float
        Trim flight-path angle [deg] (``model.gamma_deg``).
    dt : float
        Sampling period [s] (``model.dt_s``).
    alpha_range : (float, float), optional
        Validity range of the angle of attack [rad]: a trim outside it is refused.

    Returns
    -------
    LinearPlant

    Raises
    ------
    UserError
        The airframe cannot fly the condition, or a linear model's own trim
        airspeed, flight-path angle or sampling period differs from the config's
        (a linear model cannot be re-trimmed); the line names the field.
    """
    if not is_linear_model(spec):
        return build_plant(resolve_airframe(spec), V0, gamma_deg, dt, alpha_range)
    plant = load_linear_model(spec)
    tp = plant.trim
    for field, ours, theirs, unit in (("model.airspeed_mps", V0, tp.V0, "m/s"),
                                      ("model.gamma_deg", gamma_deg,
                                       math.degrees(tp.gamma0), "deg"),
                                      ("model.dt_s", dt, plant.dt, "s")):
        if not math.isclose(ours, theirs, rel_tol=1e-9, abs_tol=1e-12):
            raise UserError(f"{field}: {ours:g} {unit} differs from the linear model's "
                            f"{theirs:g} {unit} ({spec}); a linear model cannot be "
                            "re-trimmed: set the field to the model's value")
    return plant
