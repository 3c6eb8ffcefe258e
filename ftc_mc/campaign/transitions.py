"""The eight fault transitions of Tables 2-3 and the per-trial draws.

A transition names the actuator (the faulty elevon is the left one, DESIGN.md
section 6), the fault kind (lock or loss of effectiveness) and the direction
(``onset``: nominal -> faulty; ``recovery``: faulty -> nominal).

Draws per trial, from ``numpy.random.default_rng([trial_id, root_seed])`` in this
order: the fault parameter (lock position uniform over the lock range, or
effectiveness loss ``b1`` uniform over its range), then the process noise
(``n_steps x 9``), then the measurement noise (``n_steps x 12``).  Trial ``i`` of
every transition uses the same stream (common random numbers), and the two
signature variants run on identical draws and noise.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..conventions import BLOCK_NAMES, MODE_ENGINE, MODE_NOMINAL  # noqa: F401
from ..conventions import MODE_LEFT_ELEVON as MODE_LEFT
from ..conventions import MODE_RIGHT_ELEVON as MODE_RIGHT

ENGINE, LEFT, RIGHT = 0, 1, 2


@dataclasses.dataclass(frozen=True)
class Transition:
    """One row of Tables 2-3.

    Attributes
    ----------
    name : str
    actuator : int
        0 engine, 1 left elevon.
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
    def correct_block(self) -> int:
        """Covariance block that a reset should hit (1 thrust, 2 elevons)."""
        return 1 if self.actuator == ENGINE else 2

    @property
    def other_block(self) -> int:
        """The block whose reset is inappropriate."""
        return 2 if self.actuator == ENGINE else 1


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
"""The paper's own Monte Carlo counts, for side-by-side reports."""


def faulty_params(tr: Transition, value: float):
    """Per-actuator truth ``(b0, b1)`` of the faulty mode.

    Parameters
    ----------
    tr : Transition
    value : float
        Lock position (absolute) or effectiveness loss ``b1``.

    Returns
    -------
    b0, b1 : ndarray, shape (3,)
    """
    b0 = np.zeros(3)
    b1 = np.zeros(3)
    if tr.kind == "lock":
        b1[tr.actuator] = 1.0
        b0[tr.actuator] = value
    else:
        b1[tr.actuator] = value
    return b0, b1


def mode_of(b1: np.ndarray, beta_engine: float, beta_elevon: float) -> int:
    """The mode whose box holds the truth ``b1`` (single fault at a time)."""
    if b1[ENGINE] > beta_engine:
        return MODE_ENGINE
    if b1[LEFT] > beta_elevon:
        return MODE_LEFT
    if b1[RIGHT] > beta_elevon:
        return MODE_RIGHT
    return MODE_NOMINAL


def estimator_params(b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
    """Estimator parameters ``[b0_T, b0_L + b0_R, b1_T, b1_L, b1_R]`` of a truth."""
    return np.array([b0[0], b0[1] + b0[2], b1[0], b1[1], b1[2]])


def draw_trial(trial_id: int, seed: int, tr: Transition, lock_range, loss_range,
               n_steps: int, q_std: np.ndarray, r_std: np.ndarray, gust_chol=None):
    """All random draws of one trial.

    Parameters
    ----------
    trial_id, seed : int
        The stream is ``default_rng([trial_id, seed])``.
    tr : Transition
    lock_range, loss_range : tuple of float
        Uniform ranges of the lock position and of ``b1``.
    n_steps : int
    q_std : ndarray, shape (9,)
        Process-noise standard deviations.
    r_std : ndarray, shape (12,)
        Measurement-noise standard deviations.
    gust_chol : ndarray, shape (4, 4), optional
        Cholesky factor of the stationary Dryden state covariance
        (:class:`~ftc_mc.model.turbulence.DrydenModel`); ``None`` in still air.

    Returns
    -------
    value : float
        The fault draw (lock position or ``b1``).
    w : ndarray, shape (n_steps, 9)
    v : ndarray, shape (n_steps, 12)
    gust : tuple or None
        ``(eta, g0)``: the gust draws, shape (n_steps, 4), and the initial gust
        state, shape (4,), drawn after everything else so that the still-air
        draws of a trial are the same with and without turbulence.
    """
    rng = np.random.default_rng([trial_id, seed])
    lo, hi = lock_range if tr.kind == "lock" else loss_range
    value = rng.uniform(lo, hi)
    w = rng.standard_normal((n_steps, 9)) * q_std
    v = rng.standard_normal((n_steps, 12)) * r_std
    return value, w, v, draw_gusts(rng, n_steps, gust_chol)


def draw_gusts(rng: np.random.Generator, n_steps: int, gust_chol):
    """Gust draws ``(eta, g0)`` from ``rng`` (see :func:`draw_trial`), or None.

    The initial state is stationary: ``g0 = gust_chol @ N(0, I_4)``.
    """
    if gust_chol is None:
        return None
    eta = rng.standard_normal((n_steps, 4))
    g0 = gust_chol @ rng.standard_normal(4)
    return eta, g0


def gust_lanes(n_steps: int, L: int, turbulent: bool):
    """Empty lane arrays ``eta`` (n_steps or 0, 4, L) and ``g0`` (4, L) of TrialInputs."""
    return np.zeros((n_steps if turbulent else 0, 4, L)), np.zeros((4, L))
