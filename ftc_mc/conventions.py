"""Names and indices of states, outputs, parameters, modes, blocks and statuses.

The one home of every name list and index the rest of the package shares, so a
kernel, a table and a report agree on what "index 11" or "mode 2" means.  Pure
Python constants (Numba reads module-level ints and tuples as compile-time
constants).  See ``docs/reference/paper-map.md`` for the paper's symbols.

Plant and filter (docs/reference/airframes.md, paper eqs. 1-5)
------------------------------------------------------
The linear plant's state has ``N_X = 9`` entries (:data:`STATE_NAMES`), its
outputs ``N_Z = 12`` (:data:`OUTPUT_NAMES`, the paper's order), its commands
``N_U = 3`` (:data:`INPUT_NAMES`).  The paper's augmented filter state is
``[x (9), b0 (2), b1 (3)]`` (eq. 5, :data:`PARAM_NAMES` for the last five); a
filter design with more states (gusts, sensor biases) appends them after the
fault parameters, so kernels take the augmented dimension from their arrays'
shapes, never from a literal.
"""

from __future__ import annotations

import dataclasses

# ------------------------------------------------------------------ plant
STATE_NAMES = ("u", "w", "q", "x", "z", "theta", "thrust", "elevon_left", "elevon_right")
"""States of the linear plant (body velocities [m/s], pitch rate [rad/s],
position deviations [m], pitch [rad], then the three first-order actuators)."""

INPUT_NAMES = ("throttle", "elevon_left", "elevon_right")
"""Commands: throttle [-] and elevon deflections [rad]."""

OUTPUT_NAMES = ("u", "w", "q", "x", "z", "theta", "n_x", "n_z", "alpha", "gamma", "CAS",
                "Va")
"""The 12 outputs in the paper's order (section 5.1)."""

ACTUATOR_NAMES = ("engine", "left_elevon", "right_elevon")
"""Actuators in command order."""

N_X = len(STATE_NAMES)
N_U = len(INPUT_NAMES)
N_Z = len(OUTPUT_NAMES)

OUT_Q = OUTPUT_NAMES.index("q")
OUT_NX = OUTPUT_NAMES.index("n_x")
OUT_NZ = OUTPUT_NAMES.index("n_z")
OUT_ALPHA = OUTPUT_NAMES.index("alpha")
OUT_VA = OUTPUT_NAMES.index("Va")

# ------------------------------------------------------------------ fault parameters
PARAM_NAMES = ("b0_thrust", "b0_elevons", "b1_thrust", "b1_left", "b1_right")
"""The estimator's fault parameters (paper section 2.4): the thrust's bias, the
elevons' bias *sum*, and the three effectiveness losses."""

N_B0 = 2
N_B1 = 3
N_FAULT = N_B0 + N_B1
N_AUG = N_X + N_FAULT
"""Augmented dimension of the paper's filter (eq. 5)."""

I_B0_THRUST = N_X + PARAM_NAMES.index("b0_thrust")
I_B0_ELEVONS = N_X + PARAM_NAMES.index("b0_elevons")
I_B1_THRUST = N_X + PARAM_NAMES.index("b1_thrust")
I_B1_LEFT = N_X + PARAM_NAMES.index("b1_left")
I_B1_RIGHT = N_X + PARAM_NAMES.index("b1_right")

# ------------------------------------------------------------------ residuals, blocks
RESIDUAL_NAMES = ("r_q", "r_nx", "r_nz")
"""Normalised residuals of eqs. 9-11, on the outputs :data:`RESIDUAL_OUTPUTS`."""
RESIDUAL_OUTPUTS = (OUT_Q, OUT_NX, OUT_NZ)
BIASED_OUTPUTS = tuple(OUTPUT_NAMES[o] for o in RESIDUAL_OUTPUTS)
"""Outputs whose sensor bias a sensor-aware design may estimate."""

NO_RESET = 0
RESET_THRUST = 1
RESET_ELEVONS = 2
BLOCK_NAMES = ("none", "thrust", "elevons")
"""Covariance blocks of Table 1, indexed by the block code."""

THRUST_BLOCK = (PARAM_NAMES.index("b0_thrust"), PARAM_NAMES.index("b1_thrust"))
ELEVON_BLOCK = (PARAM_NAMES.index("b0_elevons"), PARAM_NAMES.index("b1_left"),
                PARAM_NAMES.index("b1_right"))
"""Fault parameters (indices into :data:`PARAM_NAMES`) reset with each block."""

VARIANTS = ("paper", "swapped")
"""Table 1 as printed, and with its third clause's r_nz comparison swapped."""

THRESHOLDED = ("r_q", "r_nx")
"""Table 1's thresholded residual channels (``t_q``, ``t_nx``); the others
(``r_nz``) are only compared with another channel."""

NO_COMPARE = -1
"""``cmp_a`` of a decision-table row that compares no channels."""


def _table1(variant: str) -> tuple:
    """Table 1 as a decision table (module docstring of
    ``core/longitudinal/signature.py``): one row per hit pattern of the residual
    channels (bit ``i`` set when channel ``i`` of :data:`RESIDUAL_NAMES` reaches its
    threshold), each ``(block_if, block_else, cmp_a, cmp_b)``: ``block_if``
    when ``cmp_a`` is :data:`NO_COMPARE` or ``r[cmp_a] >= r[cmp_b]``, else
    ``block_else``."""
    q, nx, nz = (RESIDUAL_NAMES.index(n) for n in ("r_q", "r_nx", "r_nz"))
    both = ((RESET_THRUST, RESET_ELEVONS) if variant == "paper"
            else (RESET_ELEVONS, RESET_THRUST))  # swapped: the r_nz test reversed
    rows = []
    for pattern in range(1 << len(RESIDUAL_NAMES)):
        q_hit, nx_hit = bool(pattern >> q & 1), bool(pattern >> nx & 1)
        if q_hit and nx_hit:
            rows.append((*both, nz, nx))
        elif q_hit:
            rows.append((RESET_ELEVONS, RESET_ELEVONS, NO_COMPARE, NO_COMPARE))
        elif nx_hit:
            rows.append((RESET_THRUST, RESET_THRUST, NO_COMPARE, NO_COMPARE))
        else:  # r_nz alone is never a hit of Table 1
            rows.append((NO_RESET, NO_RESET, NO_COMPARE, NO_COMPARE))
    return tuple(rows)


TABLE1 = {v: _table1(v) for v in VARIANTS}
"""Table 1's decision table of each variant (:func:`_table1`), the data the
kernel reads (``Detection.table``)."""

TEST_ONE_STEP, TEST_GLR = 0, 1
"""Residual tests of a design (``Detection.test``): the paper's one-step test of
the normalised residuals (eqs. 9-11), or the GLR of a persistent change of their
mean over a sliding window (``ftc_mc/core/shared/glr.py``)."""
TEST_NAMES = ("one_step", "glr")

RESETS_TABLE1, RESETS_SIDE_MONITOR, RESETS_EITHER = 0, 1, 2
"""What decides a design's covariance resets (``Detection.source``): Table 1 on
its residual test's statistics (the paper's section 3.2.2); on the 6-DOF plant,
the side monitor's per-actuator GLR decisions
(``ftc_mc/core/sixdof/monitor.py``; ``docs/findings/sixdof-monitor-resets.md``);
or either, the monitor's decision where it makes one, else Table 1's."""
RESETS_NAMES = ("table1", "side_monitor", "either")

S3211_UNITS = (3, 2, 1, 1)
"""Durations of the elevon 3211's alternating steps, in units (the paper's Fig. 4)."""

EXCITATION_POLICIES = ("none", "periodic", "ambiguous")
"""When a design sends excitation beyond the paper's requests on resets
(``Excitation.policy``): ``none`` only those (the paper); ``periodic``
the doublet and the 3211 every period, staggered by half a period; ``ambiguous``
one of them when the belief is unsure or a residual is high."""
EXCITE_NONE, EXCITE_PERIODIC, EXCITE_AMBIGUOUS = range(len(EXCITATION_POLICIES))

COST_NAMES = ("track_sq", "track_max") + tuple(f"u2_{n}" for n in INPUT_NAMES)
"""Rows of ``TrialRecord.cost``, summed over the steps a trial flew:
the squared glide-path cross-track error [m^2], its largest magnitude [m], then
each command's squared deviation from trim [throttle^2, rad^2]."""
N_COST = len(COST_NAMES)
COST_TRACK_SQ = COST_NAMES.index("track_sq")
COST_TRACK_MAX = COST_NAMES.index("track_max")
COST_U2 = COST_NAMES.index(f"u2_{INPUT_NAMES[0]}")
"""First of the ``N_U`` command rows, in command order."""

N_GUST_EST = 4
"""Gust states in a gust-aware filter (the Dryden shaping filter, ``core/shared/dryden.py``),
appended after the fault parameters: ``[x (9), b (5), g (4)]``."""

# ------------------------------------------------------------------ modes, controllers
MODE_NAMES = ("nominal", "engine", "left_elevon", "right_elevon")
"""The belief's four modes (section 3.3)."""
N_MODES = len(MODE_NAMES)
MODE_NOMINAL, MODE_ENGINE, MODE_LEFT_ELEVON, MODE_RIGHT_ELEVON = range(N_MODES)

CONTROLLER_NAMES = ("c0 nominal", "c1 engine fault", "c2 elevon fault")
"""Controllers of section 4, indexed by their code."""
N_CONTROLLERS = len(CONTROLLER_NAMES)
C_NOMINAL, C_ENGINE, C_ELEVON = range(N_CONTROLLERS)
SELECTED_CONTROLLER_NAMES = ("c0 nominal", "c1 engine fault", "c2 left elevon fault",
                             "c3 right elevon fault")
"""The four controllers a ``lock_turn_selected`` design chooses among on the
6-DOF plant, indexed by their code (``ftc_mc/core/sixdof/selection.py``: c2
and c3 the lock-turn controllers of the left and right elevon)."""

# ------------------------------------------------------------------ trial status
STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_NOT_PSD = 2
STATUS_AIRSPEED = 3
STATUS_ALPHA = 4
STATUS_BANK = 5
STATUS_NAMES = ("ok", "nonfinite", "covariance_not_psd", "airspeed_out_of_bounds",
                "alpha_out_of_bounds", "bank_out_of_bounds")
"""Why a trial stopped being trusted (``ok``: it ran to its end)."""

# ------------------------------------------------------------------ campaigns, plants
PAPER_TRANSITIONS = ("elevon_lock", "elevon_unlock", "elevon_loss", "elevon_loss_recover",
                     "engine_lock", "engine_unlock", "engine_loss", "engine_loss_recover")
"""The eight transitions of Tables 2-3 (docs/reference/paper-map.md); their faulty elevon is
the left one, as in the paper."""
RIGHT_ELEVON_TRANSITIONS = ("right_elevon_lock", "right_elevon_unlock", "right_elevon_loss",
                            "right_elevon_loss_recover")
"""The four elevon rows with the right elevon faulty (not in the paper)."""
TRANSITIONS = PAPER_TRANSITIONS + RIGHT_ELEVON_TRANSITIONS
"""Every actuator transition: the paper's eight, then the right elevon's four."""

AIRFRAME_PRESETS = ("x8-pyfly", "x8-gryte2018")
"""Airframe presets (:mod:`ftc_mc.model.presets`), the default first."""
DEFAULT_AIRFRAME = AIRFRAME_PRESETS[0]
"""Airframe flown when a config names none (``docs/reference/airframes.md``: why)."""

PLANT_KINDS = ("linear", "nonlinear")
TURBULENCE_LEVELS = ("none", "light", "moderate", "severe")
"""Truth plants and MIL-F-8785C turbulence levels (W20 = 0, 15, 30, 45 kt)."""

# ------------------------------------------------------------------ actuator fault kinds
ACTUATOR_FAULT_KINDS = ("lock", "loss", "hardover", "float", "slow", "delayed",
                        "oscillatory", "runaway", "intermittent")
"""Actuator fault kinds (``docs/guides/fault-kinds.md``): the paper's ``lock`` and
``loss`` (``b0``, ``b1`` of eq. 2), and the kinds beyond them, each a setting
of the per-actuator parameters :data:`FAULT_PARAM_NAMES` the truth reads each
step (``ftc_mc/core/longitudinal/plant.py``, ``actuator_effect``)."""
KIND_NONE = -1
"""The kind code of an actuator without a fault (signals' ``kind_*`` columns)."""

FAULT_PARAM_NAMES = ("delay_steps", "rate_limit", "osc_amp", "osc_freq_hz", "osc_phase",
                     "runaway_rate", "float_weight", "float_angle", "float_gain")
"""Per-actuator parameters of the generic fault model beside ``b0`` and ``b1``
(``TrialInputs.fp``): transport delay [steps]; rate limit [unit/s]; limit-cycle
amplitude [unit], frequency [Hz] and phase [rad]; runaway rate [unit/s]; the
weight of the floating angle in the surface's command [-], the floating angle
at zero angle of attack [rad] and its gain on the angle of attack [rad/rad].
The unit is the actuator's command unit (throttle [-], elevon [rad])."""
N_FAULT_PARAM = len(FAULT_PARAM_NAMES)
(FP_DELAY, FP_RATE, FP_OSC_AMP, FP_OSC_FREQ, FP_OSC_PHASE, FP_RUNAWAY, FP_FLOAT,
 FP_FLOAT_ANGLE, FP_FLOAT_GAIN) = range(N_FAULT_PARAM)
FAULT_PARAM_NEUTRAL = (0.0, float("inf"), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""The parameters of a healthy actuator (and of a lock or loss): the truth's
arithmetic is then eq. (2) exactly."""
MAX_DELAY_STEPS = 20
"""Longest transport delay the truth keeps commands for [steps] (2 s at 0.1 s)."""
N_CMD_HIST = MAX_DELAY_STEPS + 1
"""Length of each lane's command ring (``LaneState.uhist``)."""

KIND_PREFIXES = {"elevon": "left_elevon", "right_elevon": "right_elevon",
                 "engine": "engine"}
"""Name prefix of a fault-kind transition -> its actuator (``elevon_*`` is the
left one, as the paper's rows)."""
KINDS_BEYOND = ACTUATOR_FAULT_KINDS[2:]
"""The kinds beyond the paper's lock and loss."""
KIND_ACTUATORS = {"float": ("left_elevon", "right_elevon")}
"""Actuators a kind applies to when not all (a throttle cannot float)."""
KIND_TRANSITIONS = tuple(
    f"{prefix}_{kind}" for prefix, actuator in KIND_PREFIXES.items()
    for kind in KINDS_BEYOND if actuator in KIND_ACTUATORS.get(kind, ACTUATOR_NAMES))
"""Onset rows (nominal -> faulty) of the kinds beyond lock and loss, e.g.
``elevon_oscillatory``, ``right_elevon_runaway``, ``engine_slow``."""

# ------------------------------------------------------------------ sensor faults
OUTPUT_UNITS = ("m/s", "m/s", "rad/s", "m", "m", "rad", "g", "g", "rad", "rad", "m/s",
                "m/s")
"""Units of the outputs (:data:`OUTPUT_NAMES`) and so of a sensor bias on them
(a drift: the unit per second)."""

SENSOR_FAULT_KINDS = ("bias", "stuck", "drift", "noise")
"""Sensor faults on one output: ``bias`` a step of ``size``, ``stuck``
frozen at its last healthy value, ``drift`` a ramp of ``size`` per second,
``noise`` the measurement noise multiplied by ``size``."""
SENSOR_BIAS, SENSOR_STUCK, SENSOR_DRIFT, SENSOR_NOISE = range(len(SENSOR_FAULT_KINDS))
NO_SENSOR_FAULT = -1
"""``TrialInputs.sensor_out`` of a lane without a sensor fault."""
SENSOR_PREFIX = "sensor_"
"""Campaign transitions ``sensor_<kind>:<output>``, e.g. ``sensor_bias:q``."""


# ------------------------------------------------------------------ the family's layout
@dataclasses.dataclass(frozen=True)
class Layout:
    """Names and index maps of one plant family (a plant structure with its
    filter, residuals and blocks), for the code outside the kernels.

    The kernels of a family read the same numbers as module constants (Numba
    compiles them in); the rest of the package reads them here, never as
    literals.  Today's family is the longitudinal one (:data:`LONGITUDINAL`).

    Attributes
    ----------
    name : str
    states, outputs, inputs, actuators, params : tuple of str
        Plant states, outputs, commands, actuators (command order) and the
        filter's fault parameters.
    residuals : tuple of str
        Table 1's residual channels; ``residual_outputs`` the output each reads.
    residual_outputs : tuple of int
    blocks : tuple of str
        Table 1's covariance blocks by code (code 0: none).
    block_params : tuple of tuple of int
        Per block code, the fault parameters (indices into ``params``) it resets.
    actuator_block : tuple of int
        Per actuator, the block code of its fault parameters.
    b0_index, b1_index : tuple of int
        Per actuator, the index of its lock offset and effectiveness in the
        augmented estimate ``[x, b]``.
    thresholded : tuple of str
        Table 1's residual channels that have a threshold.
    decisions : tuple of (str, tuple)
        Per Table 1 variant, its decision table (:data:`TABLE1`).
    """

    name: str
    states: tuple
    outputs: tuple
    inputs: tuple
    actuators: tuple
    params: tuple
    residuals: tuple
    residual_outputs: tuple
    blocks: tuple
    block_params: tuple
    actuator_block: tuple
    b0_index: tuple
    b1_index: tuple
    thresholded: tuple = ()
    decisions: tuple = ()

    @property
    def n_x(self) -> int:
        """Plant states."""
        return len(self.states)

    @property
    def n_z(self) -> int:
        """Outputs."""
        return len(self.outputs)

    @property
    def n_u(self) -> int:
        """Commands."""
        return len(self.inputs)

    @property
    def n_aug(self) -> int:
        """The augmented estimate ``[x, b]`` of the family's own filter."""
        return len(self.states) + len(self.params)

    @property
    def faults(self) -> slice:
        """The fault parameters' rows of the augmented estimate."""
        return slice(self.n_x, self.n_aug)

    def output(self, name: str) -> int:
        """Index of the output ``name``."""
        return self.outputs.index(name)

    def state(self, name: str) -> int:
        """Index of the plant state ``name``."""
        return self.states.index(name)


LONGITUDINAL = Layout(
    name="longitudinal", states=STATE_NAMES, outputs=OUTPUT_NAMES, inputs=INPUT_NAMES,
    actuators=ACTUATOR_NAMES, params=PARAM_NAMES, residuals=RESIDUAL_NAMES,
    residual_outputs=RESIDUAL_OUTPUTS, blocks=BLOCK_NAMES,
    block_params=((), THRUST_BLOCK, ELEVON_BLOCK),
    actuator_block=(RESET_THRUST, RESET_ELEVONS, RESET_ELEVONS),
    b0_index=(I_B0_THRUST, I_B0_ELEVONS, I_B0_ELEVONS),
    b1_index=(I_B1_THRUST, I_B1_LEFT, I_B1_RIGHT), thresholded=THRESHOLDED,
    decisions=tuple(TABLE1.items()))
"""The longitudinal family: the paper's plant, filter and Table 1 (the elevons'
lock offsets enter as their sum, ``b0_elevons``)."""
