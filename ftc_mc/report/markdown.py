"""Formatting helpers shared by the report's sections.

Numbers and counts as the report prints them, relative links to figures,
file-name stems per input, transition labels, and the truth plant of a
result's config.
"""

from __future__ import annotations

import os
from pathlib import Path
from urllib.parse import quote

import numpy as np

from ..campaign.transitions import TRANSITION_TABLE
from ..stats import wilson

DEFAULT_PLANT = ("linear", "none")
LEGACY_AIRFRAME = "x8-gryte2018"
"""Airframe of results written before ``model.airframe`` existed."""
AIRFRAME_FILE_SUFFIXES = (".yaml", ".yml", ".npz", ".mat")
"""Truth plant of results written before the ``plant`` section existed; the
reference condition of the plant comparison."""

LABELS = {name: t.label for name, t in TRANSITION_TABLE.items()}
"""Display label of each transition name (e.g. ``Engine nominal → Engine locked``)."""


def label(name: str) -> str:
    """The display label of a transition (the name itself if unknown)."""
    return LABELS.get(name, name)


def rel_link(target: Path, report: Path) -> str:
    """URL-quoted POSIX path of ``target`` relative to the report's folder."""
    rel = os.path.relpath(Path(target).resolve(), Path(report).resolve().parent)
    return quote(Path(rel).as_posix())


def num(x, fmt="{:.1f}") -> str:
    """``x`` formatted with ``fmt``, ``-`` if it is None or not finite."""
    return "-" if x is None or not np.isfinite(x) else fmt.format(x)


def count(k: int, n: int, ci: bool = True) -> str:
    """``k/n (rate %, CI low-high)``, with the 95 % Wilson interval if ``ci``."""
    if not n:
        return f"{k}/0"
    text = f"{k}/{n} ({100 * k / n:.1f} %"
    if ci:
        lo, hi = wilson(k, n)
        text += f", {100 * lo:.1f}-{100 * hi:.1f}"
    return text + ")"


def slugs(inputs: list) -> list:
    """A distinct file-name stem per input (its directory name, made unique).

    Parameters
    ----------
    inputs : list of ResultDir

    Returns
    -------
    list of str
    """
    out, used = [], set()
    for r in inputs:
        base = "".join(c if c.isalnum() or c in "-_." else "_"
                       for c in r.path.resolve().name) or "input"
        slug, n = base, 1
        while slug in used:
            n += 1
            slug = f"{base}-{n}"
        used.add(slug)
        out.append(slug)
    return out


def plant_condition(cfg: dict) -> tuple:
    """The truth plant of a config: ``(plant.kind, plant.turbulence)``.

    Parameters
    ----------
    cfg : dict
        The config stored in a result's metadata.

    Returns
    -------
    (str, str)
        :data:`DEFAULT_PLANT` for results written before the ``plant`` section
        existed (or a field missing from it).
    """
    plant = cfg.get("plant") or {}
    return (str(plant.get("kind", DEFAULT_PLANT[0])),
            str(plant.get("turbulence", DEFAULT_PLANT[1])))


def airframe_of(cfg: dict) -> str:
    """The airframe of a config: a preset name or a file's stem.

    Results written before ``model.airframe`` existed flew the X8 of the
    authors' simulator (:data:`LEGACY_AIRFRAME`, to four digits).
    """
    spec = str((cfg.get("model") or {}).get("airframe", LEGACY_AIRFRAME))
    return Path(spec).stem if Path(spec).suffix.lower() in AIRFRAME_FILE_SUFFIXES else spec


def controller_of(cfg: dict, design: str | None) -> str:
    """The controller kind the design ``design`` flies in a stored config: its
    own ``controller``, else the ``controller`` section's ``kind``
    (``Config.controller_of``)."""
    own = (cfg.get("designs", {}).get(design) or {}).get("controller") if design else None
    return own or cfg.get("controller", {}).get("kind", "?")


def weights_of(cfg: dict, design: str | None) -> str:
    """The LQR weights the design ``design`` flies in a stored config: its own
    ``weights``, else the ``controller`` section's (``paper`` in results written
    before either existed)."""
    own = (cfg.get("designs", {}).get(design) or {}).get("weights") if design else None
    return own or cfg.get("controller", {}).get("weights") or "paper"


def plant_text(cfg: dict) -> str:
    """``airframe `name`, truth plant `kind`, turbulence `level``` of a config."""
    kind, turbulence = plant_condition(cfg)
    return (f"airframe `{airframe_of(cfg)}`, truth plant `{kind}`, "
            f"turbulence `{turbulence}`")
