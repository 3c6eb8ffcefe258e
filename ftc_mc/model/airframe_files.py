"""A user's own aircraft from files: airframe YAML and linear models (.npz, .mat).

Airframe YAML (``docs/reference/airframes.md``): a flat mapping with every field of
:class:`~ftc_mc.model.airframe.Airframe`, SI units, angles in rad.  Every
longitudinal field is required and unknown fields are refused, so a typo cannot
silently fall back to a default; the lateral-directional fields are optional
(only the 6-DOF model needs them, and it names the missing ones); :func:`export_airframe` writes a complete, commented file to start
from.  YAML is read with ``yaml.safe_load`` only.

Linear model (``.npz`` as written by :func:`ftc_mc.model.summary.save_npz`, or
MATLAB ``.mat`` with the same variable names): everything a trial of the linear
plant uses, listed in :data:`LINEAR_MODEL_VARIABLES`.  It has no airframe, so it
flies only the linear truth plant.

Every problem is one :class:`~ftc_mc.errors.UserError` line naming the field or
variable, e.g. ``airframe.mass: must be > 0, got -1.0 (my_uav.yaml)``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
import reprlib
import zipfile
import zlib
from pathlib import Path

import numpy as np
import yaml

from ..errors import UserError
from ..io.yamlfile import read_yaml
from .airframe import LATERAL_FIELDS, Airframe
from .linear import LinearPlant, TrimPoint

_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = 60
_REPR.maxlist = _REPR.maxtuple = 4

# ----------------------------------------------------------------------------
# airframe YAML

AIRFRAME_FIELDS: dict[str, tuple[str, str, str]] = {
    "mass": ("positive", "[kg]", "vehicle mass"),
    "Jy": ("positive", "[kg m^2]", "pitch moment of inertia"),
    "S": ("positive", "[m^2]", "wing reference area"),
    "c": ("positive", "[m]", "mean aerodynamic chord"),
    "rho": ("positive", "[kg/m^3]", "air density"),
    "g": ("positive", "[m/s^2]", "gravitational acceleration"),
    "CL0": ("finite", "[-]", "lift coefficient at zero alpha"),
    "CLa": ("finite", "[1/rad]", "lift slope dCL/dalpha"),
    "CLq": ("finite", "[1/rad]", "lift due to pitch rate, per c q / (2 Va)"),
    "CLde": ("finite", "[1/rad]", "lift due to elevon (mean of both)"),
    "CD0": ("finite", "[-]", "drag coefficient at zero alpha"),
    "CDa": ("finite", "[1/rad]", "drag, linear term in alpha"),
    "CDa2": ("finite", "[1/rad^2]", "drag, quadratic term in alpha"),
    "CDde2": ("finite", "[1/rad^2]", "drag, quadratic term in elevon"),
    "Cm0": ("finite", "[-]", "pitch-moment coefficient at zero alpha"),
    "Cma": ("finite", "[1/rad]", "pitch-moment slope dCm/dalpha"),
    "Cmq": ("finite", "[1/rad]", "pitch damping, per c q / (2 Va)"),
    "Cmde": ("finite", "[1/rad]", "pitch moment due to elevon (mean of both)"),
    "S_prop": ("positive", "[m^2]", "propeller disc area"),
    "k_motor": ("positive", "[m/s]", "motor constant: discharge speed at full throttle"),
    "C_prop": ("positive", "[-]", "propeller efficiency coefficient"),
    "tau_thrust": ("positive", "[s]", "engine (throttle) first-order time constant"),
    "tau_elevon": ("positive", "[s]", "elevon first-order time constant"),
    "throttle_limits": ("throttle", "[-]",
                        "absolute throttle command range [lo, hi], 0 <= lo < hi <= 1"),
    "elevon_limits": ("elevon", "[rad]",
                      "absolute range of each elevon [-max, max], 0 < max <= pi/2"),
    # lateral-directional: optional, needed by the 6-DOF model only
    "b": ("positive", "[m]", "wing span (6-DOF)"),
    "Jx": ("positive", "[kg m^2]", "roll moment of inertia (6-DOF)"),
    "Jz": ("positive", "[kg m^2]", "yaw moment of inertia (6-DOF)"),
    "Jxz": ("finite", "[kg m^2]", "product of inertia, I = [[Jx,0,-Jxz],[0,Jy,0],"
                                   "[-Jxz,0,Jz]] (6-DOF)"),
    "C_D_beta1": ("finite", "[1/rad]", "drag, linear term in sideslip (6-DOF)"),
    "C_D_beta2": ("finite", "[1/rad^2]", "drag, quadratic term in sideslip (6-DOF)"),
    "C_Y_0": ("finite", "[-]", "side force at zero sideslip (6-DOF)"),
    "C_Y_beta": ("finite", "[1/rad]", "side force due to sideslip (6-DOF)"),
    "C_Y_p": ("finite", "[1/rad]", "side force due to roll rate, per b p / (2 Va) "
                                   "(6-DOF)"),
    "C_Y_r": ("finite", "[1/rad]", "side force due to yaw rate, per b r / (2 Va) "
                                   "(6-DOF)"),
    "C_Y_delta_a": ("finite", "[1/rad]", "side force due to aileron (left - "
                                         "right)/2 (6-DOF)"),
    "C_l_0": ("finite", "[-]", "roll moment at zero sideslip (6-DOF)"),
    "C_l_beta": ("finite", "[1/rad]", "roll moment due to sideslip (6-DOF)"),
    "C_l_p": ("finite", "[1/rad]", "roll damping, per b p / (2 Va) (6-DOF)"),
    "C_l_r": ("finite", "[1/rad]", "roll moment due to yaw rate, per b r / (2 Va) "
                                   "(6-DOF)"),
    "C_l_delta_a": ("finite", "[1/rad]", "roll moment due to aileron (left - "
                                         "right)/2 (6-DOF)"),
    "C_n_0": ("finite", "[-]", "yaw moment at zero sideslip (6-DOF)"),
    "C_n_beta": ("finite", "[1/rad]", "yaw moment due to sideslip (6-DOF)"),
    "C_n_p": ("finite", "[1/rad]", "yaw moment due to roll rate, per b p / (2 Va) "
                                   "(6-DOF)"),
    "C_n_r": ("finite", "[1/rad]", "yaw damping, per b r / (2 Va) (6-DOF)"),
    "C_n_delta_a": ("finite", "[1/rad]", "yaw moment due to aileron (left - "
                                         "right)/2 (6-DOF)"),
    "k_T_P": ("nonnegative", "[N m s^2/rad^2]", "propeller roll torque "
                                                 "-k_T_P (k_Omega throttle)^2 (6-DOF)"),
    "k_Omega": ("nonnegative", "[rad/s]", "propeller speed at full throttle, for "
                                          "k_T_P (6-DOF)"),
}
"""Airframe field -> (check, unit, meaning); the order of :class:`Airframe`.

Checks: ``positive`` finite > 0; ``nonnegative`` finite >= 0; ``finite`` any
finite number; ``throttle`` and ``elevon`` the two-number ranges described in
the meaning.  The lateral-directional fields
(:data:`~ftc_mc.model.airframe.LATERAL_FIELDS`) are optional: a file without
them flies longitudinal runs; the 6-DOF model names the missing ones."""

_NUMBER_TEXT = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)$")
"""Scientific notation without a dot (``1e-5``), which YAML 1.1 reads as text."""


def _yaml_number(value: float) -> str:
    """A float as YAML text that ``yaml.safe_load`` reads back to the same bits."""
    return yaml.safe_dump(float(value)).splitlines()[0]


def export_airframe(airframe: Airframe, path_or_stream, name: str = "",
                    source: str = "") -> None:
    """Write an airframe as a commented YAML file, every field with its unit.

    Parameters
    ----------
    airframe : Airframe
        The parameters to write.
    path_or_stream : str, Path or text stream
        Destination file (overwritten) or an open text stream.
    name : str
        Written as a comment (e.g. the preset name); not read back.
    source : str
        Written as a comment (where the numbers come from); not read back.

    Notes
    -----
    Numbers are written so that :func:`load_airframe_yaml` reads back an equal
    :class:`Airframe` (every float to the bit).
    """
    lines = ["# Airframe for ftc-mc (docs/reference/airframes.md): every field is required,",
             "# SI units, angles in rad; unknown fields are refused."]
    for label, text in (("name", name), ("source", source)):
        for i, part in enumerate(str(text).splitlines() if text else []):
            lines.append(f"# {label + ':' if i == 0 else ' ' * (len(label) + 1)} {part}")
    rows = []
    for field in dataclasses.fields(Airframe):
        value = getattr(airframe, field.name)
        if value is None:  # a lateral-directional field not given
            continue
        if isinstance(value, tuple):
            text = "[" + ", ".join(_yaml_number(v) for v in value) + "]"
        else:
            text = _yaml_number(value)
        rows.append((field.name, text))
    width = max(len(text) for _, text in rows)
    for name, text in rows:
        _, unit, meaning = AIRFRAME_FIELDS[name]
        lines.append(f"{name + ':':<16} {text:<{width}}  # {unit} {meaning}")
    out = "\n".join(lines) + "\n"
    if hasattr(path_or_stream, "write"):
        path_or_stream.write(out)
    else:
        Path(path_or_stream).write_text(out, encoding="utf-8")


def _number(value, where: str) -> float:
    """A finite float from a YAML scalar, or UserError naming ``where``."""
    if isinstance(value, str) and _NUMBER_TEXT.match(value.strip()):
        value = float(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise UserError(f"{where}: must be a number, got {_REPR.repr(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise UserError(f"{where}: must be finite, got {value!r}")
    return value


def _field_value(name: str, raw, source: str):
    check = AIRFRAME_FIELDS[name][0]
    where = f"airframe.{name}"
    tail = f" ({source})"
    try:
        if check in ("throttle", "elevon"):
            if not isinstance(raw, (list, tuple)) or len(raw) != 2:
                raise UserError(f"{where}: must be a list of two numbers [lo, hi], "
                                f"got {_REPR.repr(raw)}")
            lo = _number(raw[0], f"{where}[0]")
            hi = _number(raw[1], f"{where}[1]")
            if check == "throttle" and not 0.0 <= lo < hi <= 1.0:
                raise UserError(f"{where}: must satisfy 0 <= lo < hi <= 1, "
                                f"got [{lo!r}, {hi!r}]")
            if check == "elevon" and not (lo == -hi and 0.0 < hi <= math.pi / 2):
                raise UserError(f"{where}: must be symmetric [-max, max] with "
                                f"0 < max <= pi/2 rad, got [{lo!r}, {hi!r}]")
            return (lo, hi)
        value = _number(raw, where)
        if check == "positive" and not value > 0:
            raise UserError(f"{where}: must be > 0, got {value!r}")
        if check == "nonnegative" and not value >= 0:
            raise UserError(f"{where}: must be >= 0, got {value!r}")
        return value
    except UserError as exc:
        raise UserError(f"{exc}{tail}") from None


def parse_airframe(data, source: str = "airframe") -> Airframe:
    """Validate a mapping of airframe fields (parsed YAML) as an :class:`Airframe`.

    Parameters
    ----------
    data : dict
        Every field of :data:`AIRFRAME_FIELDS`, nothing else.
    source : str
        Name of the origin (file name) for the error line.

    Returns
    -------
    Airframe

    Raises
    ------
    UserError
        One line: an unknown or missing field, or a value that is not a finite
        number or is out of its range, naming the field.
    """
    tail = f" ({source})"
    if data is None:
        raise UserError(f"airframe: the file is empty; expected a mapping of the "
                        f"airframe fields{tail}")
    if not isinstance(data, dict):
        raise UserError(f"airframe: expected a mapping of the airframe fields at the "
                        f"top level, got {type(data).__name__}{tail}")
    unknown = [k for k in data if k not in AIRFRAME_FIELDS]
    if unknown:
        key = unknown[0]
        close = difflib.get_close_matches(str(key), AIRFRAME_FIELDS, n=1)
        hint = (f"did you mean {close[0]!r}?" if close
                else f"the fields are {', '.join(AIRFRAME_FIELDS)}")
        more = f" [and {len(unknown) - 1} more]" if len(unknown) > 1 else ""
        raise UserError(f"airframe.{str(key)[:40]}: unknown field "
                        f"({hint}){more}{tail}")
    missing = [k for k in AIRFRAME_FIELDS if k not in data and k not in LATERAL_FIELDS]
    if missing:
        raise UserError(f"airframe: missing field{'s' if len(missing) > 1 else ''} "
                        f"{', '.join(missing)} (every longitudinal field is "
                        f"required){tail}")
    values = {name: _field_value(name, data[name], source)
              for name in AIRFRAME_FIELDS if name in data}
    try:
        return Airframe(**values)
    except ValueError as exc:  # the dataclass's own checks; ours are stricter
        raise UserError(f"airframe: {exc}{tail}") from None


def load_airframe_yaml(path) -> Airframe:
    """Read an airframe YAML file (as written by :func:`export_airframe`).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Airframe

    Raises
    ------
    UserError
        One line: missing, unreadable, empty or malformed file, a top level that
        is not a mapping, or a field problem (:func:`parse_airframe`).
    """
    path = Path(path)
    return parse_airframe(read_yaml(path), str(path))


# ----------------------------------------------------------------------------
# linear models

LINEAR_MODEL_VARIABLES: dict[str, tuple[tuple[int, ...], str]] = {
    "A": ((9, 9), "discrete state matrix, x[k+1] = A x[k] + B u[k] (deviations "
                  "from trim)"),
    "B": ((9, 3), "discrete input matrix (throttle [-], left, right elevon [rad])"),
    "C": ((12, 9), "output matrix, z[k] = C x[k] (deviations from trim)"),
    "u0": ((3,), "trim commands, absolute: throttle [-], left, right elevon [rad]"),
    "u_lower": ((3,), "absolute lower command limits: throttle [-], elevons [rad]"),
    "u_upper": ((3,), "absolute upper command limits: throttle [-], elevons [rad]"),
    "dt": ((), "sampling period [s] of the zero-order hold"),
    "x0": ((9,), "trim state, absolute: u, w [m/s], q [rad/s], x, z [m], "
                 "theta [rad], throttle [-], left, right elevon [rad]"),
    "y0": ((12,), "trim outputs, absolute: u, w [m/s], q [rad/s], x, z [m], "
                  "theta [rad], n_x, n_z [g], alpha, gamma [rad], CAS, Va [m/s]"),
    "alpha": ((), "trim angle of attack [rad]"),
    "V0": ((), "trim airspeed [m/s]"),
    "gamma0": ((), "trim flight-path angle [rad], negative when descending"),
    "Bw": ((9, 3), "discrete gust input matrix, gust [u_g, w_g [m/s], q_g [rad/s]] "
                   "held over dt"),
    "Dw": ((12, 3), "gust feed-through into the 12 outputs"),
}
"""Variable -> (shape, meaning with unit) of a linear-model file; all required."""


def _load_npz(path: Path) -> dict:
    if not zipfile.is_zipfile(path):  # np.load would try it as .npy or a pickle
        raise ValueError("not a zip archive")
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def _load_mat(path: Path) -> dict:
    import scipy.io  # here, not at the top: only .mat files need it (0.2 s per run)
    try:
        data = scipy.io.loadmat(path, squeeze_me=True)
    except scipy.io.matlab.MatReadError as exc:
        raise ValueError(str(exc) or type(exc).__name__) from None
    return {k: v for k, v in data.items() if not k.startswith("__")}


def load_linear_model(path) -> LinearPlant:
    """Read a linear model from ``.npz`` or MATLAB ``.mat``.

    The file holds the variables of :data:`LINEAR_MODEL_VARIABLES` (as written by
    :func:`ftc_mc.model.summary.save_npz`), all required, nothing else, every
    entry a finite real number.  Singleton dimensions are dropped (a MATLAB
    ``3x1`` vector is a vector of 3, a ``1x1`` a scalar).

    Parameters
    ----------
    path : str or Path
        A ``.npz`` or ``.mat`` file.

    Returns
    -------
    LinearPlant
        ``airframe``, ``Ac``, ``Bc``, ``Cc`` and ``trim.params`` are ``None``
        (no nonlinear model: it flies only the linear truth plant); ``Bw`` and
        ``Dw`` are the file's.

    Raises
    ------
    UserError
        One line: unknown suffix, missing, empty, truncated or unreadable file;
        a missing or unknown variable, a wrong shape, a non-numeric or
        non-finite entry, ``dt`` or ``V0`` not > 0, ``u_lower`` not below
        ``u_upper``, or ``u0`` outside the limits, naming the variable.
    """
    path = Path(path)
    tail = f" ({path})"
    suffix = path.suffix.lower()
    if suffix not in (".npz", ".mat"):
        raise UserError(f"linear model: expected a .npz or .mat file, got "
                        f"{path.suffix or 'no suffix'!r}{tail}")
    if not path.exists():
        raise UserError(f"linear model: no such file{tail}")
    if not path.is_file():
        raise UserError(f"linear model: not a regular file{tail}")
    if path.stat().st_size == 0:
        raise UserError(f"linear model: the file is empty{tail}")
    try:
        raw = _load_npz(path) if suffix == ".npz" else _load_mat(path)
    except (OSError, ValueError, EOFError, TypeError, KeyError, NotImplementedError,
            zipfile.BadZipFile, zlib.error) as exc:
        first = (str(exc).splitlines() or [type(exc).__name__])[0]
        if isinstance(exc, NotImplementedError):  # scipy's words for v7.3 files
            first = "MATLAB v7.3 (HDF5) files are not read; save with -v7"
        kind = "NumPy .npz" if suffix == ".npz" else "MATLAB .mat"
        raise UserError(f"linear model: not a readable {kind} file "
                        f"({_REPR.repr(first)[1:-1]}){tail}") from None
    unknown = sorted(k for k in raw if k not in LINEAR_MODEL_VARIABLES)
    if unknown:
        raise UserError(f"linear model: unknown variable{'s' if len(unknown) > 1 else ''}"
                        f" {', '.join(unknown)} (the variables are "
                        f"{', '.join(LINEAR_MODEL_VARIABLES)}){tail}")
    missing = [k for k in LINEAR_MODEL_VARIABLES if k not in raw]
    if missing:
        raise UserError(f"linear model: missing variable{'s' if len(missing) > 1 else ''}"
                        f" {', '.join(missing)}{tail}")
    v = {}
    for name, (shape, _) in LINEAR_MODEL_VARIABLES.items():
        a = np.asarray(raw[name])
        if a.dtype.kind not in "fiu":
            raise UserError(f"linear model: {name}: must hold real numbers, got "
                            f"dtype {a.dtype}{tail}")
        a = np.squeeze(a)
        if a.shape != shape:
            want = "a scalar" if shape == () else f"shape {shape}"
            raise UserError(f"linear model: {name}: must be {want}, got shape "
                            f"{a.shape}{tail}")
        a = np.array(a, dtype=np.float64, order="C")  # a copy; keeps 0-d scalars
        if not np.all(np.isfinite(a)):
            at = np.argwhere(~np.isfinite(a))[0]
            raise UserError(f"linear model: {name}: must be finite, got "
                            f"{float(a[tuple(at)])!r} at index {at.tolist()}{tail}")
        v[name] = a
    for name in ("dt", "V0"):
        if not v[name] > 0:
            raise UserError(f"linear model: {name}: must be > 0, got {float(v[name])!r}"
                            f"{tail}")
    if not np.all(v["u_lower"] < v["u_upper"]):
        raise UserError(f"linear model: u_lower: must be below u_upper, got "
                        f"{v['u_lower'].tolist()} and {v['u_upper'].tolist()}{tail}")
    if not np.all((v["u_lower"] <= v["u0"]) & (v["u0"] <= v["u_upper"])):
        raise UserError(f"linear model: u0: must lie within [u_lower, u_upper], got "
                        f"{v['u0'].tolist()}{tail}")
    tp = TrimPoint(x0=v["x0"], u0=v["u0"], y0=v["y0"], alpha=float(v["alpha"]),
                   V0=float(v["V0"]), gamma0=float(v["gamma0"]), params=None)
    return LinearPlant(A=v["A"], B=v["B"], C=v["C"], Ac=None, Bc=None, Cc=None,
                       dt=float(v["dt"]), trim=tp, u_lower=v["u_lower"],
                       u_upper=v["u_upper"], airframe=None, Bw=v["Bw"], Dw=v["Dw"])
