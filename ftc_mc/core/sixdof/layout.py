"""Names and indices of the 6-DOF plant family: the one layout object.

Every size and index of the 6-DOF kernels (:mod:`ftc_mc.core.sixdof.plant`), of
the 6-DOF model layer (:mod:`ftc_mc.model.sixdof`) and of their tests comes from
:data:`LAYOUT` (or the module constants derived from it below, which Numba
freezes into the kernels at compile time).  Nothing here is longitudinal: the
longitudinal family keeps :mod:`ftc_mc.conventions`, and no longitudinal module
imports this package (``docs/reference/airframes.md``, "Six degrees of freedom").

State (15): the 12 rigid-body states of the authors' simulator (krisgry/x8
``dynamics.m``: position, Euler angles, body velocity, body rates) followed by
the three first-order actuators::

     0 x      north position error        [m]  (along the reference track)
     1 y      east position error         [m]
     2 z      down position error         [m]
     3 phi    roll angle                  [rad]
     4 theta  pitch angle                 [rad]
     5 psi    yaw angle                   [rad]
     6 u      body forward velocity       [m/s]
     7 v      body lateral velocity       [m/s]  (right wing positive)
     8 w      body downward velocity      [m/s]
     9 p      roll rate                   [rad/s]
    10 q      pitch rate                  [rad/s]
    11 r      yaw rate                    [rad/s]
    12 throttle  engine state             [-]
    13 left   left elevon deflection      [rad]
    14 right  right elevon deflection     [rad]

Positions are measured from a reference point that flies the straight glide
path north at ``V0`` and ``gamma0`` (as the longitudinal ``x``, ``z``).
Commands (3): absolute throttle [-], left and right elevon [rad].  Elevon
mixing as in PyFly (``docs/reference/airframes.md``): elevator = (left + right)/2,
aileron = (left - right)/2.

Outputs (19): the 12 rigid-body states, then the specific forces ``n_x``,
``n_y``, ``n_z`` [g] (aerodynamic plus thrust over m g; ``n_z`` positive up,
about 1 in level flight), ``alpha``, ``beta`` [rad], the air-path angle
``gamma`` [rad] and the airspeed ``Va`` [m/s].

Wind (6): body-axis gust velocities ``u_g, v_g, w_g`` [m/s] and gust rates
``p_g, q_g, r_g`` [rad/s].
"""

from __future__ import annotations

import collections

Layout = collections.namedtuple(
    "Layout", ["states", "commands", "outputs", "wind", "params", "rigid",
               "actuators", "longitudinal", "lateral"])
Layout.__doc__ = """Names of the 6-DOF family (see the module docstring).

states, commands, outputs, wind, params : tuple of str
    Names in index order.
rigid : tuple of str
    The 12 rigid-body states (the first entries of ``states``).
actuators : tuple of str
    The actuator states, in the order of ``commands``.
longitudinal, lateral : tuple of str
    The rigid-body states of each motion (for naming modes by their
    eigenvectors: ``ftc_mc.model.sixdof.named_modes``)."""

PARAM_NAMES = (
    "mass", "Jx", "Jy", "Jz", "Jxz", "S", "c", "b", "rho", "g",
    "CL0", "CLa", "CLq", "CLde",
    "CD0", "CDa", "CDa2", "CDde2", "C_D_beta1", "C_D_beta2",
    "Cm0", "Cma", "Cmq", "Cmde",
    "C_Y_0", "C_Y_beta", "C_Y_p", "C_Y_r", "C_Y_delta_a",
    "C_l_0", "C_l_beta", "C_l_p", "C_l_r", "C_l_delta_a",
    "C_n_0", "C_n_beta", "C_n_p", "C_n_r", "C_n_delta_a",
    "S_prop", "k_motor", "C_prop", "k_T_P", "k_Omega",
    "tau_thrust", "tau_elevon", "V0", "gamma0",
)
"""Packed parameter vector (``ftc_mc.model.sixdof.pack_parameters``): airframe
fields by their :class:`ftc_mc.model.airframe.Airframe` names, then the
reference glide path ``V0`` [m/s], ``gamma0`` [rad]."""

LAYOUT = Layout(
    states=("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r",
            "throttle", "left", "right"),
    commands=("throttle", "left", "right"),
    outputs=("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r",
             "n_x", "n_y", "n_z", "alpha", "beta", "gamma", "Va"),
    wind=("u_g", "v_g", "w_g", "p_g", "q_g", "r_g"),
    params=PARAM_NAMES,
    rigid=("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r"),
    actuators=("throttle", "left", "right"),
    longitudinal=("theta", "u", "w", "q"),
    lateral=("phi", "v", "p", "r"),
)
"""The 6-DOF layout."""


def index(names: tuple) -> dict:
    """Name -> index of a tuple of names."""
    return {n: i for i, n in enumerate(names)}


STATE = index(LAYOUT.states)
"""State name -> index."""
OUTPUT = index(LAYOUT.outputs)
"""Output name -> index."""
COMMAND = index(LAYOUT.commands)
"""Command name -> index."""
WIND = index(LAYOUT.wind)
"""Wind component name -> index."""
PARAM = index(LAYOUT.params)
"""Parameter name -> index."""

AS_SIXDOF = {"thrust": "throttle", "elevon_left": "left", "elevon_right": "right",
             "CAS": "Va"}
"""6-DOF names of the longitudinal family's states, commands and outputs
(:mod:`ftc_mc.conventions`) where they differ; the others keep their names
(``CAS`` is the airspeed)."""


def sixdof_name(name: str) -> str:
    """The 6-DOF state, command or output named ``name`` in the longitudinal family."""
    return AS_SIXDOF.get(name, name)


N_STATE = len(LAYOUT.states)
N_RIGID = len(LAYOUT.rigid)
N_COMMAND = len(LAYOUT.commands)
N_OUTPUT = len(LAYOUT.outputs)
N_WIND = len(LAYOUT.wind)
N_PARAM = len(LAYOUT.params)

# Module constants for the kernels (Numba freezes globals at compile time).
X_X, X_Y, X_Z = STATE["x"], STATE["y"], STATE["z"]
X_PHI, X_THETA, X_PSI = STATE["phi"], STATE["theta"], STATE["psi"]
X_U, X_V, X_W = STATE["u"], STATE["v"], STATE["w"]
X_P, X_Q, X_R = STATE["p"], STATE["q"], STATE["r"]
X_THR, X_LEFT, X_RIGHT = STATE["throttle"], STATE["left"], STATE["right"]
U_THR, U_LEFT, U_RIGHT = COMMAND["throttle"], COMMAND["left"], COMMAND["right"]
W_U, W_V, W_W = WIND["u_g"], WIND["v_g"], WIND["w_g"]
W_P, W_Q, W_R = WIND["p_g"], WIND["q_g"], WIND["r_g"]
Y_NX, Y_NY, Y_NZ = OUTPUT["n_x"], OUTPUT["n_y"], OUTPUT["n_z"]
Y_ALPHA, Y_BETA, Y_GAMMA, Y_VA = (OUTPUT["alpha"], OUTPUT["beta"], OUTPUT["gamma"],
                                  OUTPUT["Va"])

SIXDOF_NONLINEAR, SIXDOF_LINEAR = 2, 3
"""``SixDofTruth.kind`` (after the longitudinal ``TruthPlant.kind`` 0 and 1): the
airframe's equations, or the 6-DOF linear model (``plant.kind``)."""

assert LAYOUT.states[:N_RIGID] == LAYOUT.rigid
assert LAYOUT.outputs[:N_RIGID] == LAYOUT.rigid
assert tuple(LAYOUT.states[N_RIGID:]) == LAYOUT.actuators

# The side monitor's augmented filter (core/sixdof/monitor.py)
MONITOR_STATES = tuple(n for n in LAYOUT.states if n != "y")
"""States of the side monitor's filter: the 6-DOF states but the cross-track
position, which no row of the linear model reads and no sensor measures (the
along-track ``x`` is one of the longitudinal outputs)."""
MONITOR_GUST_STATES = tuple(f"gust_lon_{i}" for i in range(4)) + tuple(
    f"gust_lat_{i}" for i in range(4))
"""States a gust-aware monitor appends to :data:`MONITOR_STATES`: those of the
longitudinal (``u_g, w_g, q_g``) and lateral (``v_g, p_g, r_g``) Dryden models
(``model/turbulence.py``), in their own order."""
MONITOR_PARAMS = tuple(f"b0_{a}" for a in LAYOUT.commands) + tuple(
    f"b1_{a}" for a in LAYOUT.commands)
"""Its fault parameters after the states: a lock offset ``b0`` [throttle, rad]
and an effectiveness loss ``b1`` [-] of each actuator (eq. 2 per actuator)."""
MONITOR_LATERAL = ("phi", "v", "p", "r", "psi")
"""The lateral outputs it measures after the 12 longitudinal ones: the lateral
loop's sensors (core/sixdof/truth.LATERAL_LOOP), with their noise."""
MONITOR_DIRECTIONS = LAYOUT.commands
"""Its fault directions, one GLR each: the throttle, the left and the right
elevon.  A decision's block code is the direction's index plus one."""
