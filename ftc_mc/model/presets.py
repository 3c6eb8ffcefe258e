"""Airframe presets: each a faithful copy of one cited parameter file.

Two public parameter files of the Skywalker X8 exist, both from the NTNU group
(``docs/reference/airframes.md`` compares them):

* ``x8-gryte2018``: ``x8_param.mat`` of the authors' simulator for K. Gryte,
  R. Hann, M. Alam, J. Rohac, T. A. Johansen, T. I. Fossen, "Aerodynamic modeling
  of the Skywalker X8 Fixed-Wing Unmanned Aerial Vehicle", ICUAS 2018;
* ``x8-pyfly``: ``pyfly/x8_param.mat`` of the PyFly simulator.

Every number of a preset is the float64 of its file, written as its ``repr``
(full precision) next to the file's variable name.  The file names each source
by repository, path and commit.  What is ours, not the files' (the same in both
presets and in :data:`ftc_mc.model.airframe.X8`): air density 1.225 kg/m^3,
g = 9.81 m/s^2, actuator time constants (engine 0.3 s, elevons 0.05 s) and the
command limits (throttle [0, 1], each elevon +-30 deg).

The longitudinal model without stall (``ftc_mc/model/dynamics.py``) uses 19 of
a file's entries; the 6-DOF model (``ftc_mc/model/sixdof.py``) 23 more, the
lateral-directional ones (:data:`ftc_mc.model.airframe.LATERAL_FIELDS`, the
propeller torque included); the others are listed in each preset's ``unused``
text.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from ..errors import UserError
from .airframe import Airframe
from .linear import trim


@dataclasses.dataclass(frozen=True)
class Source:
    """Where a preset's numbers come from.

    Attributes
    ----------
    repo : str
        Public GitHub repository, ``owner/name``.
    path : str
        The parameter file inside the repository.
    commit : str
        Full commit hash of the copied version.
    date : str
        Commit date (ISO 8601).
    reference : str
        The publication or project the file belongs to.
    """

    repo: str
    path: str
    commit: str
    date: str
    reference: str

    def __str__(self) -> str:
        return f"github.com/{self.repo} {self.path} @ {self.commit[:12]} ({self.date})"


@dataclasses.dataclass(frozen=True)
class Preset:
    """A named airframe with its source.

    Attributes
    ----------
    name : str
        Registry name, e.g. ``"x8-gryte2018"``.
    airframe : Airframe
        The parameters.
    source : Source
        The cited file.
    note : str
        One line: what distinguishes this preset.
    unused : str
        Entries present in the source file but used by neither the
        longitudinal nor the 6-DOF model.
    """

    name: str
    airframe: Airframe
    source: Source
    note: str
    unused: str


_LATERAL = dict(
    b=2.1,                           # b
    Jx=1.229,                        # Jx
    Jz=0.8808,                       # Jz
    Jxz=0.9343,                      # Jxz
    C_D_beta1=-0.005842980345415388,  # C_D_beta1
    C_D_beta2=0.14781193079241584,   # C_D_beta2
    C_Y_0=0.0,                       # C_Y_0 (stored as the integer 0)
    C_Y_beta=-0.22387215700254048,   # C_Y_beta
    C_Y_p=-0.13735505263157893,      # C_Y_p
    C_Y_r=0.08386876842105263,       # C_Y_r
    C_Y_delta_a=0.043276402502774876,  # C_Y_delta_a
    C_l_0=0.0,                       # C_l_0 (stored as the integer 0)
    C_l_beta=-0.08489628639662417,   # C_l_beta
    C_l_p=-0.40419799999999995,      # C_l_p
    C_l_r=0.055520599999999996,      # C_l_r
    C_l_delta_a=0.12018814125782745,  # C_l_delta_a
    C_n_0=0.0,                       # C_n_0 (stored as the integer 0)
    C_n_beta=0.0283,                 # C_n_beta
    C_n_p=0.004365511578947368,      # C_n_p
    C_n_r=-0.07200000000000001,      # C_n_r (XFLR's value times 6, README)
    C_n_delta_a=-0.00339,            # C_n_delta_a
)
"""The lateral-directional data (6-DOF only), identical in both cited files."""


_GRYTE2018 = Source(
    repo="krisgry/x8", path="x8_param.mat",
    commit="8bfb2d945dbff9abdfda6431b8f1d962c9d45b30", date="2018-06-14",
    reference=("K. Gryte, R. Hann, M. Alam, J. Rohac, T. A. Johansen, T. I. Fossen, "
               "'Aerodynamic modeling of the Skywalker X8 Fixed-Wing Unmanned Aerial "
               "Vehicle', ICUAS 2018 (the authors' simulator)"))

_PYFLY = Source(
    repo="eivindeb/pyfly", path="pyfly/x8_param.mat",
    commit="8451687b8df4a7bc6f78f3a1cdcfd503b76bf596", date="2020-04-25",
    reference="PyFly - Python Fixed Wing Flight Simulator (its X8 parameter file)")

# Values: github.com/krisgry/x8, x8_param.mat, commit 8bfb2d945dbf (2018-06-14).
X8_GRYTE2018 = Airframe(
    mass=3.364,                      # mass
    Jy=0.1702,                       # Jy
    S=0.75,                          # S_wing
    c=0.35714285714285715,           # c
    CL0=0.08673556671610734,         # C_L_0
    CLa=4.020328244000679,           # C_L_alpha
    CLq=3.87,                        # C_L_q
    CLde=0.2780736201734713,         # C_L_delta_e
    CD0=0.01970001181915082,         # C_D_0
    CDa=0.07909146315766297,         # C_D_alpha1
    CDa2=1.0554699867680841,         # C_D_alpha2
    CDde2=0.06334739678180232,       # C_D_delta_e
    Cm0=0.02275,                     # C_m_0
    Cma=-0.4629,                     # C_m_alpha
    Cmq=-1.3012370370370372,         # C_m_q
    Cmde=-0.2292,                    # C_m_delta_e
    S_prop=0.10178760197630929,      # S_prop
    k_motor=40.0,                    # k_motor (stored as the integer 40)
    C_prop=1.0,                      # C_prop (stored as the integer 1)
    **_LATERAL,  # lateral-directional (6-DOF only; identical in both files)
    k_T_P=0.0,                       # k_T_P (stored as the integer 0)
    k_Omega=0.0,                     # k_Omega (stored as the integer 0)
    # ours, not the file's (module docstring):
    rho=1.225, g=9.81, tau_thrust=0.3, tau_elevon=0.05,
    throttle_limits=(0.0, 1.0),
    elevon_limits=(-math.radians(30.0), math.radians(30.0)),
)

# Values: github.com/eivindeb/pyfly, pyfly/x8_param.mat, commit 8451687b8df4
# (2020-04-25).
X8_PYFLY = Airframe(
    mass=3.364,                      # mass
    Jy=0.1702,                       # Jy
    S=0.75,                          # S_wing
    c=0.35714285714285715,           # c
    CL0=0.08673556671610734,         # C_L_0
    CLa=4.020328244000679,           # C_L_alpha
    CLq=3.87,                        # C_L_q
    CLde=0.2780736201734713,         # C_L_delta_e
    CD0=0.01970001181915082,         # C_D_0
    CDa=0.07909146315766297,         # C_D_alpha1
    CDa2=1.0554699867680841,         # C_D_alpha2
    CDde2=0.06334739678180232,       # C_D_delta_e
    Cm0=0.018,                       # C_m_0
    Cma=-0.2524,                     # C_m_alpha
    Cmq=-1.3012370370370372,         # C_m_q
    Cmde=-0.2292,                    # C_m_delta_e
    S_prop=0.10178760197630929,      # S_prop
    k_motor=37.42,                   # k_motor
    C_prop=0.248,                    # C_prop
    **_LATERAL,  # lateral-directional (6-DOF only; identical in both files)
    k_T_P=1.1871e-06,                # k_T_P
    k_Omega=797.1268,                # k_Omega
    # ours, not the file's (module docstring):
    rho=1.225, g=9.81, tau_thrust=0.3, tau_elevon=0.05,
    throttle_limits=(0.0, 1.0),
    elevon_limits=(-math.radians(30.0), math.radians(30.0)),
)

_UNUSED_COMMON = (
    "rudder terms C_Y_delta_r, C_l_delta_r, C_n_delta_r 0 (no rudder); C_D_q 0; "
    "r_cg [0, 0, 0]")

PRESETS: dict[str, Preset] = {
    "x8-gryte2018": Preset(
        name="x8-gryte2018", airframe=X8_GRYTE2018, source=_GRYTE2018,
        note=("the authors' simulator: C_m fitted to flight tests; strong engine "
              "(C_prop 1, k_motor 40 m/s)"),
        unused=_UNUSED_COMMON),
    "x8-pyfly": Preset(
        name="x8-pyfly", airframe=X8_PYFLY, source=_PYFLY,
        note=("PyFly's file: C_m 0.018 - 0.2524 a; weaker engine (C_prop 0.248, "
              "k_motor 37.42 m/s)"),
        unused=(f"{_UNUSED_COMMON}; PyFly's stall model M 50, a_0 0.267, C_m_fp "
                "-0.2168 and its drag polar C_D_p 0.0102 with Oswald e 0.9935")),
}
"""The registry: preset name -> :class:`Preset`."""


def get_preset(name: str) -> Preset:
    """The preset of a name.

    Parameters
    ----------
    name : str
        A key of :data:`PRESETS`.

    Returns
    -------
    Preset

    Raises
    ------
    UserError
        Unknown name; the line lists the known ones.
    """
    try:
        return PRESETS[name]
    except (KeyError, TypeError):
        raise UserError(f"airframe: unknown preset {name!r}; known presets: "
                        f"{', '.join(PRESETS)} (or the path of an airframe .yaml "
                        "file)") from None


def resolve_airframe(spec) -> Airframe:
    """The airframe named by a preset name or given by a YAML file path.

    Parameters
    ----------
    spec : str or Path
        A preset name (:data:`PRESETS`), or the path of an airframe YAML file
        (:func:`ftc_mc.model.airframe_files.load_airframe_yaml`).  A string is a
        path when it ends in ``.yaml`` or ``.yml``, contains a path separator, or
        names an existing file.

    Returns
    -------
    Airframe

    Raises
    ------
    UserError
        Unknown preset (the line lists the known ones), a linear-model file
        (``.npz``/``.mat``, which is not an airframe), or any problem of the
        YAML file.
    """
    from .airframe_files import load_airframe_yaml

    if isinstance(spec, str) and spec in PRESETS:
        return PRESETS[spec].airframe
    if not isinstance(spec, (str, Path)):
        raise UserError(f"airframe: expected a preset name or a file path, got "
                        f"{type(spec).__name__}")
    path = Path(spec)
    suffix = path.suffix.lower()
    if suffix in (".npz", ".mat"):
        raise UserError(f"airframe: {str(spec)!r} is a linear-model file, not an "
                        "airframe (.yaml); a linear model flies only the linear "
                        "truth plant")
    text = str(spec)
    if (isinstance(spec, Path) or suffix in (".yaml", ".yml") or "/" in text
            or "\\" in text or path.is_file()):
        return load_airframe_yaml(path)
    return get_preset(text).airframe


def list_airframes(V0: float = 20.0, gamma_deg: float = -3.0) -> list[dict]:
    """Rows describing every preset, with its trim (for ``ftc-mc airframes``).

    Parameters
    ----------
    V0 : float
        Trim airspeed [m/s].
    gamma_deg : float
        Trim flight-path angle [deg].

    Returns
    -------
    list of dict
        One per preset, in registry order: ``name``, ``source`` (repository,
        path, commit and date), ``reference``, ``note``, ``throttle`` [-],
        ``alpha_deg`` [deg], ``elevon_rad`` [rad] (``None`` when the preset
        cannot fly the condition) and ``refused`` (the reason, or ``None``).
    """
    rows = []
    for p in PRESETS.values():
        row = {"name": p.name, "source": str(p.source), "reference": p.source.reference,
               "note": p.note, "throttle": None, "alpha_deg": None,
               "elevon_rad": None, "refused": None}
        try:
            tp = trim(p.airframe, V0, gamma_deg)
        except UserError as exc:
            row["refused"] = str(exc)
        else:
            row.update(throttle=float(tp.u0[0]), alpha_deg=math.degrees(tp.alpha),
                       elevon_rad=float(tp.u0[1]))
        rows.append(row)
    return rows
