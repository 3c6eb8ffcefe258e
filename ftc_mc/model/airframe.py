"""Skywalker X8 longitudinal airframe parameters.

Source of every aerodynamic number below: K. Gryte, R. Hann, M. Alam, J. Rohac,
T. A. Johansen, T. I. Fossen, "Aerodynamic modeling of the Skywalker X8 Fixed-Wing
Unmanned Aerial Vehicle", ICUAS 2018, as transcribed in DESIGN.md section 2.
Second sources checked: the authors' own simulator README (github krisgry/x8)
states Cm_alpha = -0.4629, Cm_0 = 0.0227, Cm_delta_e = -0.2292 and that the thrust
model is the Aerosonde one of Beard & McLain, "Small Unmanned Aircraft" (2012);
a public Python transcription of ``x8_param.mat`` gives mass 3.364 kg and
Jy 0.1702 kg m^2.  The drag polar is the quadratic fit
``CD = 0.0197 + 0.0791 a + 1.0555 a**2 + 0.0633 de**2`` of DESIGN.md.

Choices that are ours, not Gryte's (see ``docs/model.md``):

* actuator time constants: engine 0.3 s (same order as the short-period mode,
  paper section 2.4), elevons 0.05 s;
* command limits: throttle [0, 1] (absolute), each elevon [-30 deg, +30 deg]
  (absolute, symmetric range in rad);
* sea-level air, so calibrated airspeed equals true airspeed.
"""

from __future__ import annotations

import dataclasses
import math

from ..errors import UserError

G0 = 9.81
"""Gravitational acceleration [m/s^2]."""


@dataclasses.dataclass(frozen=True)
class Airframe:
    """Longitudinal Skywalker X8 parameters (SI units, angles in rad).

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

    @property
    def command_lower(self):
        """Absolute lower command limits (throttle, left, right elevon)."""
        return (self.throttle_limits[0], self.elevon_limits[0], self.elevon_limits[0])

    @property
    def command_upper(self):
        """Absolute upper command limits (throttle, left, right elevon)."""
        return (self.throttle_limits[1], self.elevon_limits[1], self.elevon_limits[1])


X8 = Airframe()
"""The default Skywalker X8 airframe."""
