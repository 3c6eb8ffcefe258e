"""Matplotlib on the Agg backend, and the atomic PNG writer of every figure."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..io.atomic import atomic_path  # noqa: E402


def save(fig, path: Path) -> Path:
    """Save ``fig`` to ``path`` (PNG, 110 dpi) atomically and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : Path
        PNG file; its folder is created if needed.

    Returns
    -------
    Path
        ``path``.
    """
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
