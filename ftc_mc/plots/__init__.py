"""Figures (matplotlib, Agg backend), written atomically as PNG.

* ``figure.py``: the backend and :func:`save`;
* ``scenario.py``: :func:`scenario_figures`, the paper's Figs. 6-12 for one
  scenario (``ftc-mc scenario``).
"""

from __future__ import annotations

from .figure import plt, save
from .scenario import scenario_figures

__all__ = ["plt", "save", "scenario_figures"]
