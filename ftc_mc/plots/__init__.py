"""Figures (matplotlib, Agg backend), written atomically as PNG.

* ``figure.py``: the backend and :func:`save`;
* ``scenario.py``: :func:`scenario_figures`, the paper's Figs. 6-12 for one
  scenario (``ftc-mc scenario``);
* ``campaign.py``: the report's figures of campaign results:
  :func:`delay_figure` (one run), :func:`sweep_figure` (one sweep) and
  :func:`plant_figure` (runs on different truth plants);
* ``operating.py``: :func:`operating_figure`, the operating characteristic of
  a sweep's detection designs.
"""

from __future__ import annotations

from .campaign import delay_figure, plant_figure, sweep_figure
from .figure import plt, save
from .operating import operating_figure
from .scenario import scenario_figures

__all__ = ["plt", "save", "scenario_figures", "delay_figure", "sweep_figure",
           "plant_figure", "operating_figure"]
