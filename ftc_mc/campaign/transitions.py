"""The fault transitions of Tables 2-3 and the ranges of their fault draws.

A transition names the actuator (the paper's eight rows fault the left elevon,
``docs/reference/paper-map.md``; the ``right_elevon_*`` rows, the same four
elevon rows on the right elevon), the fault kind (lock or loss of effectiveness) and the direction
(``onset``: nominal -> faulty; ``recovery``: faulty -> nominal).  Its trials fly
a two-entry schedule (:meth:`Transition.schedule`): the initial mode from the
start, the final mode from the fault step on.  Each trial's fault value (lock
position or effectiveness loss ``b1``) is the first draw of its stream, uniform
over :meth:`FaultRanges.of` (``ftc_mc/sim/inputs.py`` gives the order of all draws).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..config.schema import parse_sensor_transition
from ..conventions import (ACTUATOR_NAMES, LONGITUDINAL, MODE_LEFT_ELEVON, MODE_NAMES,
                           MODE_RIGHT_ELEVON, OUTPUT_NAMES, PAPER_TRANSITIONS,
                           RESET_ELEVONS, RESET_THRUST, SENSOR_FAULT_KINDS, SENSOR_PREFIX,
                           KIND_TRANSITIONS, TRANSITIONS)
from ..sim.inputs import Schedule
from .kinds import KindTransition, is_kind, kind_transition  # noqa: F401

ENGINE, LEFT, RIGHT = (ACTUATOR_NAMES.index(n) for n in ("engine", "left_elevon",
                                                         "right_elevon"))
ELEVONS = (LEFT, RIGHT)
"""Actuator indices (command order, :data:`~ftc_mc.conventions.ACTUATOR_NAMES`)."""
ELEVON_MODES = (MODE_LEFT_ELEVON, MODE_RIGHT_ELEVON)
"""The belief's elevon modes, whose argmax names the side (``correct_side``)."""


@dataclasses.dataclass(frozen=True)
class Transition:
    """One row of Tables 2-3.

    Attributes
    ----------
    name : str
    actuator : int
        Index into :data:`~ftc_mc.conventions.ACTUATOR_NAMES` (:data:`ENGINE`,
        :data:`LEFT`, :data:`RIGHT`).
    kind : str
        ``"lock"`` or ``"loss"``.
    onset : bool
        True for nominal -> faulty, False for faulty -> nominal.
    label : str
        The paper's row label.
    """

    name: str
    actuator: int
    kind: str
    onset: bool
    label: str

    @property
    def fault_mode(self) -> int:
        """The belief mode of the faulty actuator (:data:`~ftc_mc.conventions.MODE_NAMES`,
        named as the actuator): the final mode of an onset whose fault value lies
        outside the nominal box."""
        return MODE_NAMES.index(ACTUATOR_NAMES[self.actuator])

    @property
    def is_elevon(self) -> bool:
        """Whether the faulty actuator is an elevon (left or right)."""
        return self.actuator in ELEVONS

    @property
    def correct_block(self) -> int:
        """Covariance block that a reset should hit (Table 1's block code of the
        faulty actuator)."""
        return LONGITUDINAL.actuator_block[self.actuator]

    @property
    def other_block(self) -> int:
        """The block whose reset is inappropriate (the other one)."""
        return RESET_ELEVONS if self.correct_block == RESET_THRUST else RESET_THRUST

    def schedule(self, values: np.ndarray, k_fault: int) -> Schedule:
        """The two-entry schedule of trials with the fault values ``values``.

        Parameters
        ----------
        values : ndarray, shape (L,)
            Each lane's lock position (absolute) or effectiveness loss ``b1``.
        k_fault : int
            Step of the switch to the final mode.

        Returns
        -------
        Schedule
            Entry 0 the initial mode, entry 1 the final one: nominal then faulty
            for an onset, faulty then nominal for a recovery.
        """
        L = len(values)
        n_a = len(LONGITUDINAL.actuators)
        nominal = np.zeros((2, n_a, L))
        b0, b1 = np.zeros((n_a, L)), np.zeros((n_a, L))
        if self.kind == "lock":
            b1[self.actuator] = 1.0
            b0[self.actuator] = values
        else:
            b1[self.actuator] = values
        faulty = 1 if self.onset else 0
        b0s, b1s = nominal, nominal.copy()
        b0s[faulty], b1s[faulty] = b0, b1
        return Schedule(k_switch=np.array([0, k_fault], dtype=np.int64), b0=b0s, b1=b1s)


TRANSITION_TABLE = {
    t.name: t for t in [
        Transition("elevon_lock", LEFT, "lock", True, "Elevon nominal → Elevon locked"),
        Transition("elevon_unlock", LEFT, "lock", False, "Elevon locked → Elevon nominal"),
        Transition("elevon_loss", LEFT, "loss", True,
                   "Elevon nominal → Elevon less efficient"),
        Transition("elevon_loss_recover", LEFT, "loss", False,
                   "Elevon less efficient → Elevon nominal"),
        Transition("engine_lock", ENGINE, "lock", True, "Engine nominal → Engine locked"),
        Transition("engine_unlock", ENGINE, "lock", False, "Engine locked → Engine nominal"),
        Transition("engine_loss", ENGINE, "loss", True,
                   "Engine nominal → Engine less efficient"),
        Transition("engine_loss_recover", ENGINE, "loss", False,
                   "Engine less efficient → Engine nominal"),
    ]
}
# the elevon rows again on the right elevon (not in the paper)
TRANSITION_TABLE.update(
    (f"right_{t.name}", dataclasses.replace(t, name=f"right_{t.name}", actuator=RIGHT,
                                            label=t.label.replace("Elevon", "Right elevon")))
    for t in list(TRANSITION_TABLE.values()) if t.actuator == LEFT)
# the fault kinds beyond lock and loss, onsets on each actuator (ftc_mc/campaign/kinds.py)
TRANSITION_TABLE.update((name, kind_transition(name)) for name in KIND_TRANSITIONS)
"""Every actuator transition by name, the paper's eight rows first (their order in
tables), then the right elevon's (:data:`~ftc_mc.conventions.TRANSITIONS`), then the
fault kinds' (:data:`~ftc_mc.conventions.KIND_TRANSITIONS`, :class:`KindTransition`)."""
assert tuple(TRANSITION_TABLE) == TRANSITIONS + KIND_TRANSITIONS

PAPER_TABLES = {
    # name: (simulations, inappropriate resets, no reset) -- paper Tables 2 and 3
    "elevon_lock": (1000, 0, 0),
    "elevon_unlock": (1000, 17, 0),
    "elevon_loss": (1000, 0, 74),
    "elevon_loss_recover": (1000, 1, 83),
    "engine_lock": (1000, 0, 70),
    "engine_unlock": (1000, 0, 0),
    "engine_loss": (1000, 0, 165),
    "engine_loss_recover": (1000, 0, 179),
}
"""The paper's own Monte Carlo counts, for side-by-side reports (its eight rows
only: it ran no right-elevon fault)."""
assert tuple(PAPER_TABLES) == PAPER_TRANSITIONS


def paper_counts(name: str) -> tuple:
    """``(simulations, inappropriate, no reset)`` of the paper for transition
    ``name``; NaN for a row the paper did not run (the right elevon's)."""
    return PAPER_TABLES.get(name, (np.nan, np.nan, np.nan))


@dataclasses.dataclass(frozen=True)
class FaultRanges:
    """Uniform ranges of the trials' fault values (the config's ``draws`` section).

    Attributes
    ----------
    lock : dict of int to (float, float)
        Absolute lock position range per actuator index (:data:`ENGINE`,
        :data:`LEFT`, :data:`RIGHT`).
    loss : (float, float)
        Range of the effectiveness loss ``b1``.
    """

    lock: dict
    loss: tuple

    def of(self, tr: Transition) -> tuple:
        """The range of the fault values of ``tr``'s trials."""
        return self.lock[tr.actuator] if tr.kind == "lock" else self.loss


def fault_ranges(draws, u_lower, u_upper) -> FaultRanges:
    """The :class:`FaultRanges` of a validated ``draws`` section.

    A lock range left null is the actuator's whole command range
    ``[u_lower, u_upper]`` (the schema keeps a given range inside it).  Both
    elevons draw their locks over ``draws.elevon_lock_range_rad``, each within its
    own command limits when it is null.
    """
    lock = {ENGINE: tuple(draws.engine_lock_range or (u_lower[ENGINE], u_upper[ENGINE]))}
    for a in ELEVONS:
        lock[a] = tuple(draws.elevon_lock_range_rad or (u_lower[a], u_upper[a]))
    for a, (lo, hi) in lock.items():
        assert u_lower[a] <= lo < hi <= u_upper[a], (a, lo, hi)
    return FaultRanges(lock=lock, loss=tuple(draws.loss_b1_range))


@dataclasses.dataclass(frozen=True)
class SensorTransition:
    """A sensor fault from nominal: ``sensor_<kind>:<output>``.

    The actuators stay healthy throughout, so the correct covariance block is
    ``none``: any reset after the fault step is a misattribution.  The trial's
    first draw is the fault's size (:meth:`sizes`).

    Attributes
    ----------
    name : str
    kind : str
        One of :data:`~ftc_mc.conventions.SENSOR_FAULT_KINDS`.
    output : str
        One of :data:`~ftc_mc.conventions.OUTPUT_NAMES`.
    """

    name: str
    kind: str
    output: str

    @property
    def label(self) -> str:
        return f"{self.output} sensor {self.kind}"

    @property
    def out_index(self) -> int:
        return OUTPUT_NAMES.index(self.output)

    @property
    def kind_index(self) -> int:
        return SENSOR_FAULT_KINDS.index(self.kind)

    DRAW_RANGE = (-1.0, 1.0)
    """Range of the trial's first draw: its sign is the fault's, its magnitude
    places the size in the configured range (one uniform draw, as an actuator
    transition's)."""

    def sizes(self, draws: np.ndarray, size_range) -> np.ndarray:
        """Fault sizes from the first draws ``draws`` (uniform over
        :attr:`DRAW_RANGE`): bias and drift ``sign(d) (low + |d| (high - low))``;
        a noise factor ``low + |d| (high - low)``; stuck: NaN (no size)."""
        lo, hi = size_range
        mag = lo + np.abs(draws) * (hi - lo)
        if self.kind == "stuck":
            return np.full(len(draws), np.nan)
        if self.kind == "noise":
            return mag
        return np.where(draws < 0, -mag, mag)

    def schedule(self, values: np.ndarray, k_fault: int) -> Schedule:
        """Every actuator healthy throughout (one nominal entry)."""
        L = len(values)
        return Schedule(k_switch=np.zeros(1, dtype=np.int64), b0=np.zeros((1, 3, L)),
                        b1=np.zeros((1, 3, L)))


def transition_of(name: str):
    """The :class:`Transition`, :class:`KindTransition` or :class:`SensorTransition`
    named ``name`` (validated)."""
    if name in TRANSITION_TABLE:
        return TRANSITION_TABLE[name]
    kind, output = parse_sensor_transition(name)
    return SensorTransition(name, kind, output)


def is_sensor(name: str) -> bool:
    """Whether ``name`` is a sensor transition."""
    return name.startswith(SENSOR_PREFIX)
