"""Figure of an endurance run: when in a flight the false resets come."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from .figure import plt, save


def endurance_figure(resets: pd.DataFrame, flight_s: float, path: Path) -> Path:
    """Histogram (1 s bins, log count) of the false resets' times from the flight's
    start, one line per design.

    Parameters
    ----------
    resets : DataFrame
        ``false_resets.parquet`` (``variant``, ``time_s`` [s]).
    flight_s : float
        Flight length [s].
    path : Path
        PNG to write.
    """
    fig, ax = plt.subplots(figsize=(7, 3.5))
    bins = np.arange(0.0, flight_s + 1.0, 1.0)
    for v, g in resets.groupby("variant", sort=False):
        ax.hist(g["time_s"], bins=bins, histtype="step", label=str(v))
    ax.set_yscale("log")
    ax.set_xlabel("time of the false reset from the flight's start [s]")
    ax.set_ylabel("false resets per 1 s bin")
    ax.set_title("False resets of the fault-free flights (first 64 of a flight stored)")
    ax.legend()
    return save(fig, path)
