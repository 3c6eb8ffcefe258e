"""Rows of the actuator fault kinds beyond the paper's lock and loss.

A row ``<prefix>_<kind>`` (:data:`~ftc_mc.conventions.KIND_TRANSITIONS`;
``elevon_*`` the left elevon as the paper's rows, ``right_elevon_*``,
``engine_*``) starts nominal and switches at the fault step to one actuator
with the fault ``kind``, a setting of the generic fault model the truth reads
each step (``b0``, ``b1`` and ``TrialInputs.fp``;
``ftc_mc/core/longitudinal/plant.py``, ``actuator_effect``):

============  ==========================================  =========================
kind          parameters (per trial)                      model
============  ==========================================  =========================
hardover      side (either stop, equal odds)              lock at a travel limit:
                                                          ``b1 = 1``, ``b0`` the stop
float         floating angle ``delta_f0`` and gain        the surface trails at
              ``k_f`` (elevons only)                      ``delta_f0 + k_f alpha``
slow          rate limit ``R``                            ``|dc/dt| <= R``
delayed       delay ``d`` [steps]                         ``c_k = u_{k-d}``
oscillatory   amplitude ``A``, frequency ``f``, phase     ``c = u + A sin(2 pi f t + phi)``
runaway       drift rate ``r`` (either sign)              ``c = u + r t`` to the stop
intermittent  lock position ``p``, on and off spells      stuck at ``p`` during spells
============  ==========================================  =========================

Draws.  A row's trials draw the first value of their main stream as every
other row does (uniform over [0, 1], ignored), so their noise and gusts are
those of the paper's rows (common random numbers); the kind's own parameters
come from a stream of their own, ``default_rng([trial_id, root_seed,
KIND_STREAM])``, in the order of :func:`draw_kind_lane`.  The ranges are the
config's ``kind_draws`` section (``docs/guides/fault-kinds.md`` gives their
sources).

Scoring.  Every kind is a fault of one actuator, so a row is judged as the
paper's rows are: the faulty actuator's block is the correct reset, the other
block's is inappropriate, and the final (truth) mode is the faulty actuator's
mode, which the belief should find (``detected``).  The scheme models only
``b0`` and ``b1``; what a kind it cannot represent is mistaken for shows in
the first reset's block and the belief's mode (``docs/guides/fault-kinds.md``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..conventions import (ACTUATOR_FAULT_KINDS, ACTUATOR_NAMES, FP_DELAY, FP_FLOAT,
                           FP_FLOAT_ANGLE, FP_FLOAT_GAIN, FP_OSC_AMP, FP_OSC_FREQ,
                           FP_OSC_PHASE, FP_RATE, FP_RUNAWAY, KIND_NONE, KIND_PREFIXES,
                           KIND_TRANSITIONS, LONGITUDINAL, MODE_NAMES, MODE_NOMINAL)
from ..sim.inputs import Schedule, neutral_params

KIND_STREAM = 7
"""Third key of a lane's fault-kind stream (module docstring)."""

DEG = math.pi / 180.0

KIND_LABELS = {
    "hardover": "hard-over", "float": "floating", "slow": "slow", "delayed": "delayed",
    "oscillatory": "oscillating", "runaway": "running away",
    "intermittent": "intermittently stuck"}
"""How a row's label names its kind."""

PARAM_COLUMNS = {
    "hardover": ("lock_position", None),
    "float": ("float_gain", "float_angle_rad"),
    "slow": ("rate_limit_per_s", None),
    "delayed": ("delay_s", None),
    "oscillatory": ("osc_amp", "osc_freq_hz"),
    "runaway": ("runaway_rate_per_s", None),
    "intermittent": ("lock_position", "stuck_fraction"),
}
"""What a row's ``fault_param`` and ``fault_param2`` columns hold (units: the
actuator's command unit, rad for an elevon, throttle for the engine)."""


@dataclasses.dataclass(frozen=True)
class KindTransition:
    """A fault-kind row: one actuator from nominal to the fault ``kind``.

    Attributes
    ----------
    name : str
    actuator : int
        Index into :data:`~ftc_mc.conventions.ACTUATOR_NAMES`.
    kind : str
        One of :data:`~ftc_mc.conventions.KINDS_BEYOND`.
    """

    name: str
    actuator: int
    kind: str
    onset = True

    @property
    def label(self) -> str:
        act = ACTUATOR_NAMES[self.actuator].replace("_", " ")
        return f"{act.capitalize()} nominal → {act} {KIND_LABELS[self.kind]}"

    @property
    def kind_code(self) -> int:
        return ACTUATOR_FAULT_KINDS.index(self.kind)

    @property
    def fault_mode(self) -> int:
        """The belief mode of the faulty actuator: the truth mode from the fault on."""
        return MODE_NAMES.index(ACTUATOR_NAMES[self.actuator])

    @property
    def is_elevon(self) -> bool:
        return ACTUATOR_NAMES[self.actuator] != "engine"

    @property
    def correct_block(self) -> int:
        """The faulty actuator's covariance block (Table 1's block code)."""
        return LONGITUDINAL.actuator_block[self.actuator]

    @property
    def other_block(self) -> int:
        blocks = set(LONGITUDINAL.actuator_block)
        return next(b for b in sorted(blocks) if b != self.correct_block)


def kind_transition(name: str) -> KindTransition:
    """The :class:`KindTransition` named ``name`` (one of ``KIND_TRANSITIONS``)."""
    assert name in KIND_TRANSITIONS, name
    for prefix in sorted(KIND_PREFIXES, key=len, reverse=True):
        if name.startswith(prefix + "_"):
            return KindTransition(name, ACTUATOR_NAMES.index(KIND_PREFIXES[prefix]),
                                  name[len(prefix) + 1:])
    raise AssertionError(name)


def is_kind(name: str) -> bool:
    """Whether ``name`` is a fault-kind row."""
    return name in KIND_TRANSITIONS


def _lerp(r, x):
    return r[0] + x * (r[1] - r[0])


@dataclasses.dataclass(frozen=True)
class KindRanges:
    """The ranges of a row's draws in the actuator's command unit (from the
    config's ``kind_draws``, elevon degrees in radians), with the actuator's
    travel and lock range, the control period and the fault step."""

    kd: object
    lo: tuple
    hi: tuple
    lock: dict
    dt: float

    def of(self, tr: KindTransition, name: str):
        """The range ``name`` (rate_limit, osc_amp, runaway) of ``tr``'s actuator."""
        kd = self.kd
        elevon = tr.is_elevon
        return {
            "rate_limit": (tuple(v * DEG for v in kd.elevon_rate_limit_deg_s) if elevon
                           else tuple(kd.engine_rate_limit_per_s)),
            "osc_amp": (tuple(v * DEG for v in kd.elevon_osc_amp_deg) if elevon
                        else tuple(kd.engine_osc_amp)),
            "runaway": (tuple(v * DEG for v in kd.elevon_runaway_deg_s) if elevon
                        else tuple(kd.engine_runaway_per_s)),
        }[name]


def kind_ranges(cfg, setup, lock: dict) -> KindRanges:
    """The :class:`KindRanges` of a validated config."""
    plant = setup.plant
    return KindRanges(kd=cfg.kind_draws, lo=tuple(map(float, plant.u_lower)),
                      hi=tuple(map(float, plant.u_upper)), lock=dict(lock), dt=float(plant.dt))


def draw_kind_lane(rng, tr: KindTransition, rg: KindRanges, k_fault: int, n_steps: int):
    """One lane's parameters of ``tr`` from its kind stream ``rng``.

    Draws, in order: a magnitude fraction ``m`` and a second fraction ``s``
    (uniform on [0, 1)), then for an oscillation its phase, for an
    intermittent fault its spells (on, off, on, ... durations, each uniform
    over its range and rounded to the grid, until the trial's end).

    Returns
    -------
    b0, b1 : float
        The faulty actuator's ``b0`` (absolute) and ``b1`` while the fault acts.
    fp : dict of int to float
        Its non-neutral fault-model parameters (``FP_*`` index -> value).
    values : (float, float)
        ``fault_param`` and ``fault_param2`` of the trials table (:data:`PARAM_COLUMNS`).
    on : ndarray of bool or None
        Intermittent only: whether the fault acts in each grid cell from the fault step.
    """
    from ..config.schema import INTERMITTENT_GRID_S

    a, kd = tr.actuator, rg.kd
    m, s = rng.uniform(), rng.uniform()
    b0, b1, fp, on = 0.0, 0.0, {}, None
    kind = tr.kind
    if kind == "hardover":
        b1, b0 = 1.0, float(rg.hi[a] if s < 0.5 else rg.lo[a])
        values = (b0, np.nan)
    elif kind == "float":
        gain = _lerp(kd.float_gain, m)
        angle = _lerp(kd.float_angle_deg, s) * DEG
        fp = {FP_FLOAT: 1.0, FP_FLOAT_ANGLE: angle, FP_FLOAT_GAIN: gain}
        values = (gain, angle)
    elif kind == "slow":
        rate = _lerp(rg.of(tr, "rate_limit"), m)
        fp = {FP_RATE: rate}
        values = (rate, np.nan)
    elif kind == "delayed":
        d = max(1, int(round(_lerp(kd.delay_s, m) / rg.dt)))
        fp = {FP_DELAY: float(d)}
        values = (d * rg.dt, np.nan)
    elif kind == "oscillatory":
        amp = _lerp(rg.of(tr, "osc_amp"), m)
        freq = _lerp(kd.osc_freq_hz, s)
        fp = {FP_OSC_AMP: amp, FP_OSC_FREQ: freq, FP_OSC_PHASE: rng.uniform(0.0, 2 * math.pi)}
        values = (amp, freq)
    elif kind == "runaway":
        rate = _lerp(rg.of(tr, "runaway"), m) * (1.0 if s < 0.5 else -1.0)
        fp = {FP_RUNAWAY: rate}
        values = (rate, np.nan)
    elif kind == "intermittent":
        b1, b0 = 1.0, _lerp(rg.lock[a], m)
        g = int(round(INTERMITTENT_GRID_S / rg.dt))
        n_cells = -(-(n_steps - k_fault) // g)
        on = np.zeros(n_cells, dtype=bool)
        i, acting = 0, True
        while i < n_cells:
            r = kd.intermittent_on_s if acting else kd.intermittent_off_s
            n = max(1, int(round(rng.uniform(*r) / INTERMITTENT_GRID_S)))
            on[i:i + n] = acting
            i += n
            acting = not acting
        values = (b0, float(on.mean()))
    else:
        raise AssertionError(kind)
    return b0, b1, fp, values, on


def kind_draws(tr: KindTransition, trial_ids, seed: int, rg: KindRanges, k_fault: int,
               n_steps: int):
    """Every lane's :func:`draw_kind_lane` (lane order of ``trial_ids``)."""
    return [draw_kind_lane(np.random.default_rng([int(t), seed, KIND_STREAM]), tr, rg,
                           k_fault, n_steps) for t in trial_ids]


def kind_schedule(tr: KindTransition, lanes, k_fault: int, dt: float) -> Schedule:
    """The schedule of a row's lanes (:func:`kind_draws`).

    Nominal from step 0; from ``k_fault`` the faulty actuator's ``b0``, ``b1``
    and fault-model parameters.  An intermittent row has an entry per grid
    cell from the fault step, the fault acting in a lane's on-cells (its
    spells, RflyMAD's start and duration on the grid) and the actuator
    healthy in its off-cells.  The truth mode is the faulty actuator's from
    the fault step on, also between spells (an intermittent actuator is a
    faulty one).
    """
    from ..config.schema import INTERMITTENT_GRID_S

    L, a = len(lanes), tr.actuator
    n_a = len(ACTUATOR_NAMES)
    if tr.kind == "intermittent":
        g = int(round(INTERMITTENT_GRID_S / dt))
        n_cells = len(lanes[0][4])
        k_switch = np.array([0] + [k_fault + j * g for j in range(n_cells)], dtype=np.int64)
        acting = np.zeros((len(k_switch), L), dtype=bool)
        for l, lane in enumerate(lanes):
            acting[1:, l] = lane[4]
    else:
        k_switch = np.array([0, k_fault], dtype=np.int64)
        acting = np.zeros((2, L), dtype=bool)
        acting[1] = True
    E = len(k_switch)
    b0, b1 = np.zeros((E, n_a, L)), np.zeros((E, n_a, L))
    fp = neutral_params(E, L)
    kind = np.full((E, n_a, L), KIND_NONE, dtype=np.int64)
    for l, (lb0, lb1, lfp, _, _) in enumerate(lanes):
        for e in np.nonzero(acting[:, l])[0]:
            b0[e, a, l], b1[e, a, l] = lb0, lb1
            for p, v in lfp.items():
                fp[e, p, a, l] = v
            kind[e, a, l] = tr.kind_code
    mode = np.full((E, L), tr.fault_mode, dtype=np.int64)
    mode[0] = MODE_NOMINAL
    return Schedule(k_switch=k_switch, b0=b0, b1=b1, fp=fp, kind=kind, mode=mode)
