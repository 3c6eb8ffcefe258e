"""Airframe parameters, and today's rounded Skywalker X8 (``X8``).

:class:`Airframe` holds the coefficient set of the longitudinal model of
``ftc_mc/model/dynamics.py`` and, optionally (:data:`LATERAL_FIELDS`), the
lateral-directional data of the 6-DOF model (``ftc_mc/model/sixdof.py``).  The cited, full-precision copies of the two public
X8 parameter files are the presets of ``ftc_mc/model/presets.py``
(``x8-gryte2018``, ``x8-pyfly``; ``docs/reference/airframes.md`` compares them); a user's
own aircraft comes from a YAML file (``ftc_mc/model/airframe_files.py``).

:data:`X8` (the defaults of :class:`Airframe`) is the airframe the tool has flown
so far: the values of ``x8-gryte2018`` rounded to about 4 digits (c 0.3571 for
0.35714285714285715, CL0 0.0867, CLde 0.2781, CDa 0.0791, CDa2 1.0555, CDde2
0.0633, Cmq -1.3012, S_prop 0.1018, ...).  It stays unchanged because the golden
results of ``tests/test_golden.py`` pin it; its trim at 20 m/s, -3 deg differs
from the preset's in the fourth digit of alpha (1.0737 against 1.0731 deg).

Choices that are ours, not the parameter files' (the same in ``X8`` and both
presets; ``docs/reference/airframes.md``):

* actuator time constants: engine 0.3 s (same order as the short-period mode,
  paper section 2.4), elevons 0.05 s;
* command limits: throttle [0, 1] (absolute), each elevon [-30 deg, +30 deg]
  (absolute, symmetric range in rad);
* sea-level air (rho 1.225 kg/m^3, g 9.81 m/s^2), so calibrated airspeed equals
  true airspeed.
"""

from __future__ import annotations

import dataclasses
import math

from ..errors import UserError

G0 = 9.81
"""Gravitational acceleration [m/s^2]."""


@dataclasses.dataclass(frozen=True)
class Airframe:
    """Airframe parameters (SI units, angles in rad).

    The defaults are today's rounded X8 (:data:`X8`, module docstring), which
    has no lateral-directional data (longitudinal runs only).

    Parameters
    ----------
    mass : float
        Vehicle mass [kg].
    Jy : float
        Pitch moment of inertia [kg m^2].
    S : float
        Wing reference area [m^2].
    c : float
        Mean aerodynamic chord [m].
    rho : float
        Air density [kg/m^3].
    g : float
        Gravitational acceleration [m/s^2].
    CL0, CLa, CLq, CLde : float
        Lift coefficient: ``CL = CL0 + CLa a + CLq c q / (2 Va) + CLde de``.
    CD0, CDa, CDa2, CDde2 : float
        Drag coefficient: ``CD = CD0 + CDa a + CDa2 a^2 + CDde2 de^2``.
    Cm0, Cma, Cmq, Cmde : float
        Pitch-moment coefficient:
        ``Cm = Cm0 + Cma a + Cmq c q / (2 Va) + Cmde de``.
    S_prop : float
        Propeller disc area [m^2].
    k_motor : float
        Motor constant [m/s]: discharge speed at full throttle.
    C_prop : float
        Propeller efficiency coefficient [-].
    tau_thrust : float
        Engine (throttle) first-order time constant [s].
    tau_elevon : float
        Elevon first-order time constant [s].
    throttle_limits : tuple of float
        Absolute throttle command range [-].
    elevon_limits : tuple of float
        Absolute range of each elevon command [rad].
    b : float or None
        Wing span [m] (6-DOF only; so are the fields below, ``None``: not
        given, see :data:`LATERAL_FIELDS`).
    Jx, Jz, Jxz : float or None
        Roll and yaw moments of inertia and the product of inertia [kg m^2];
        the inertia matrix is ``[[Jx, 0, -Jxz], [0, Jy, 0], [-Jxz, 0, Jz]]``.
    C_D_beta1, C_D_beta2 : float or None
        Sideslip drag: ``+ C_D_beta1 beta + C_D_beta2 beta^2`` in ``CD``.
    C_Y_0, C_Y_beta, C_Y_p, C_Y_r, C_Y_delta_a : float or None
        Side force: ``CY = C_Y_0 + C_Y_beta beta + (C_Y_p p + C_Y_r r) b/(2 Va)
        + C_Y_delta_a da`` with aileron ``da = (left - right)/2``.
    C_l_0, C_l_beta, C_l_p, C_l_r, C_l_delta_a : float or None
        Roll moment, the same form (times ``qbar S b``).
    C_n_0, C_n_beta, C_n_p, C_n_r, C_n_delta_a : float or None
        Yaw moment, the same form (times ``qbar S b``).
    k_T_P, k_Omega : float or None
        Propeller roll torque ``-k_T_P (k_Omega throttle)^2`` [N m]: ``k_T_P``
        [N m s^2/rad^2], ``k_Omega`` [rad/s].

    Raises
    ------
    ValueError
        If a parameter is non-physical; the message names the parameter.
    """

    mass: float = 3.364
    Jy: float = 0.1702
    S: float = 0.75
    c: float = 0.3571
    rho: float = 1.225
    g: float = G0
    CL0: float = 0.0867
    CLa: float = 4.0203
    CLq: float = 3.87
    CLde: float = 0.2781
    CD0: float = 0.0197
    CDa: float = 0.0791
    CDa2: float = 1.0555
    CDde2: float = 0.0633
    Cm0: float = 0.02275
    Cma: float = -0.4629
    Cmq: float = -1.3012
    Cmde: float = -0.2292
    S_prop: float = 0.1018
    k_motor: float = 40.0
    C_prop: float = 1.0
    tau_thrust: float = 0.3
    tau_elevon: float = 0.05
    throttle_limits: tuple = (0.0, 1.0)
    elevon_limits: tuple = (-math.radians(30.0), math.radians(30.0))
    b: float | None = None
    Jx: float | None = None
    Jz: float | None = None
    Jxz: float | None = None
    C_D_beta1: float | None = None
    C_D_beta2: float | None = None
    C_Y_0: float | None = None
    C_Y_beta: float | None = None
    C_Y_p: float | None = None
    C_Y_r: float | None = None
    C_Y_delta_a: float | None = None
    C_l_0: float | None = None
    C_l_beta: float | None = None
    C_l_p: float | None = None
    C_l_r: float | None = None
    C_l_delta_a: float | None = None
    C_n_0: float | None = None
    C_n_beta: float | None = None
    C_n_p: float | None = None
    C_n_r: float | None = None
    C_n_delta_a: float | None = None
    k_T_P: float | None = None
    k_Omega: float | None = None

    def __post_init__(self):
        positive = ("mass", "Jy", "S", "c", "rho", "g", "S_prop", "k_motor",
                    "C_prop", "tau_thrust", "tau_elevon")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)
                    and value > 0):
                raise UserError(f"airframe parameter {name!r} must be a finite "
                                f"number > 0, got {value!r}")
        for name in ("CL0", "CLa", "CLq", "CLde", "CD0", "CDa", "CDa2", "CDde2",
                     "Cm0", "Cma", "Cmq", "Cmde"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise UserError(f"airframe parameter {name!r} must be finite, "
                                f"got {value!r}")
        for name in ("throttle_limits", "elevon_limits"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise UserError(f"airframe parameter {name!r} must be a finite "
                                f"range (lo < hi), got {(lo, hi)!r}")
        if self.elevon_limits[0] != -self.elevon_limits[1]:
            raise UserError("airframe parameter 'elevon_limits' must be "
                            f"symmetric, got {self.elevon_limits!r}")
        for name in LATERAL_FIELDS:
            value = getattr(self, name)
            if value is None:
                continue
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise UserError(f"airframe parameter {name!r} must be finite, "
                                f"got {value!r}")
            if name in ("b", "Jx", "Jz") and not value > 0:
                raise UserError(f"airframe parameter {name!r} must be > 0, "
                                f"got {value!r}")
            if name in ("k_T_P", "k_Omega") and value < 0:
                raise UserError(f"airframe parameter {name!r} must be >= 0, "
                                f"got {value!r}")
        if None not in (self.Jx, self.Jz, self.Jxz) and \
                not self.Jx * self.Jz - self.Jxz ** 2 > 0:
            raise UserError("airframe parameters 'Jx', 'Jz', 'Jxz': the inertia "
                            "matrix must be positive definite (Jx Jz > Jxz^2), got "
                            f"{self.Jx!r}, {self.Jz!r}, {self.Jxz!r}")

    @property
    def missing_lateral(self) -> tuple:
        """The lateral-directional fields (:data:`LATERAL_FIELDS`) not given."""
        return tuple(n for n in LATERAL_FIELDS if getattr(self, n) is None)

    @property
    def has_lateral(self) -> bool:
        """True when every lateral-directional field is given (6-DOF capable)."""
        return not self.missing_lateral

    @property
    def command_lower(self):
        """Absolute lower command limits (throttle, left, right elevon)."""
        return (self.throttle_limits[0], self.elevon_limits[0], self.elevon_limits[0])

    @property
    def command_upper(self):
        """Absolute upper command limits (throttle, left, right elevon)."""
        return (self.throttle_limits[1], self.elevon_limits[1], self.elevon_limits[1])


LATERAL_FIELDS = ("b", "Jx", "Jz", "Jxz", "C_D_beta1", "C_D_beta2",
                  "C_Y_0", "C_Y_beta", "C_Y_p", "C_Y_r", "C_Y_delta_a",
                  "C_l_0", "C_l_beta", "C_l_p", "C_l_r", "C_l_delta_a",
                  "C_n_0", "C_n_beta", "C_n_p", "C_n_r", "C_n_delta_a",
                  "k_T_P", "k_Omega")
"""The fields only the 6-DOF plant uses (optional: ``None`` when not given).

A longitudinal run ignores them; the 6-DOF model (``ftc_mc.model.sixdof``)
needs every one and names the missing ones.  The parameter files' rudder terms
(``C_*_delta_r``) and ``C_D_q`` are zero and not fields (the X8 has no rudder)."""

X8 = Airframe()
"""Today's Skywalker X8: the ``x8-gryte2018`` values rounded to about 4 digits.

Kept unchanged (golden results pin it); the cited full-precision copies are in
``ftc_mc/model/presets.py``."""
