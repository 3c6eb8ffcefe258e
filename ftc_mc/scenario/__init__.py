"""The closed-loop scenario: one flight of the full loop with a fault schedule.

The paper's section 5 (Table 4) by default, or any schedule of a scenario config.

* :mod:`~ftc_mc.scenario.run`: :func:`run_scenario` and :class:`ScenarioResult`
  (time series, events, one row per schedule entry);
* :mod:`~ftc_mc.scenario.timeline`: the paper's timeline
  (:data:`PAPER_TIMELINE`) and :func:`summary_markdown`, ours beside it;
* :mod:`~ftc_mc.scenario.write`: :func:`write_scenario`, the Parquet files,
  Figs. 6-12 (:mod:`ftc_mc.plots`) and summary.md.
"""

from .run import ScenarioResult, run_scenario
from ..paper import PAPER_TIMELINE
from .timeline import summary_markdown
from .write import write_scenario

__all__ = ["PAPER_TIMELINE", "ScenarioResult", "run_scenario", "summary_markdown",
           "write_scenario"]
