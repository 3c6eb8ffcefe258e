"""The compile path of a scheme flying a flight (``ftc_mc/core/shared/paths.py``).

The one place where the settings decide which kernels a trial reaches: the
truth plant's kind, the filter (the paper's 14 states with a linear
prediction, any other estimate, or a prediction by the airframe's equations),
the residual test and the controller.
"""

from __future__ import annotations

from ..conventions import TEST_GLR
from ..core.shared.paths import (DENSE_FILTER, EXTENDED_FILTER, GLR_TEST, LINEAR_PLANT,
                                 NOMINAL_CONTROL, NONLINEAR_PLANT, ONE_STEP_TEST, PAPER_FILTER,
                                 RECONFIGURING, SELECT_FOUR, SIXDOF_EXTENDED_PLANT, SIXDOF_PLANT,
                                 Path)
from ..core.longitudinal.settings import Flight, Scheme


def path_of(scheme: Scheme, flight: Flight | None = None) -> Path:
    """The :class:`~ftc_mc.core.shared.paths.Path` of ``scheme`` flying ``flight``
    (``None``: the linear plant, for the stages that do not fly it).

    The filter is the paper's when its estimate has the paper's 14 states
    (``FilterModel.G`` has no column: no gust or bias states) and it predicts
    with the linear model; extended when it predicts with the airframe
    (``FilterModel.nl``); dense otherwise.  The plant is the 6-DOF family's
    for a ``SixDofTruth`` (``kind`` 2 or 3: nonlinear or linear, a run-time
    choice inside that family's kernel), with the extended side monitor its
    own path (``SIXDOF_EXTENDED_PLANT``).
    """
    fm = scheme.filter
    if fm.nl != 0:
        filt = EXTENDED_FILTER
    elif fm.G.shape[1] == 0:
        filt = PAPER_FILTER
    else:
        filt = DENSE_FILTER
    kind = 0 if flight is None else flight.plant.kind
    if kind < 2:
        plant = (LINEAR_PLANT, NONLINEAR_PLANT)[kind]
    else:
        from ..core.sixdof.monitor import EXTENDED  # the 6-DOF path only

        plant = SIXDOF_EXTENDED_PLANT if flight.plant.monitor.nonlinear == EXTENDED \
            else SIXDOF_PLANT
    control = NOMINAL_CONTROL if scheme.reconfig.kind == 0 else RECONFIGURING
    if scheme.reconfig.kind >= 2:
        from ..core.sixdof.lockturn import SELECTED_TURN  # the 6-DOF path only

        if scheme.reconfig.kind == SELECTED_TURN:
            control = SELECT_FOUR
    return Path(plant=plant,
                filter=filt,
                test=GLR_TEST if scheme.detection.test == TEST_GLR else ONE_STEP_TEST,
                control=control)
