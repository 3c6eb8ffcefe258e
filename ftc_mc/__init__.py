"""ftc-mc: Monte Carlo fault injection for indirect active fault-tolerant control.

Implements "Reconfiguration control method for non-redundant actuator faults on
UAV" on a Skywalker X8 model; see ``docs/reference/paper-map.md``.  The Python API, one
function per command (see :mod:`ftc_mc.api`)::

    import ftc_mc
    res = ftc_mc.run_campaign("configs/elevon_lock.yaml", trials=200, jobs=2)
    res.summary
"""

from .blas import pin_openblas

pin_openblas()  # before numpy loads OpenBLAS (ftc_mc/blas.py)

from .api import (build_report, load_config, run_campaign, run_endurance,  # noqa: E402
                  run_scenario, run_sweep, score_detector)

__all__ = ["run_campaign", "run_sweep", "run_endurance", "run_scenario", "build_report",
           "load_config", "score_detector"]
