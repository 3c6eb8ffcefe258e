"""Provenance of the report's inputs: the version check and the closing section.

Inputs whose files carry different package versions or git revisions are
refused (:func:`check_provenance`) unless mixing is allowed; the report ends
with the kind, version, revision, seed and config of every input
(:func:`provenance_section`).
"""

from __future__ import annotations

import pandas as pd
import yaml

from ..errors import UserError


def _stamp(meta: dict) -> tuple:
    return (str(meta.get("version")), str(meta.get("git_revision")))


def provenance_groups(inputs: list) -> dict:
    """Inputs grouped by (version, git revision).

    Parameters
    ----------
    inputs : list of ResultDir

    Returns
    -------
    dict of (str, str) to list of str
        Each distinct stamp and where it occurs: a directory when all its files
        carry the stamp, ``dir/file`` otherwise.
    """
    groups = {}
    for r in inputs:
        stamps = {name: _stamp(m) for name, m in r.file_meta.items()}
        for s in dict.fromkeys(stamps.values()):
            names = [n for n, v in stamps.items() if v == s]
            where = ([str(r.path)] if len(set(stamps.values())) == 1
                     else [str(r.path / n) for n in names])
            groups.setdefault(s, []).extend(where)
    return groups


def mixed_message(groups: dict) -> str:
    """One line saying which inputs differ in version or git revision.

    Parameters
    ----------
    groups : dict
        :func:`provenance_groups`.

    Returns
    -------
    str
    """
    parts = [f"version {v}, git revision {g}: {', '.join(w)}"
             for (v, g), w in groups.items()]
    return "inputs come from different versions or git revisions (" + "; ".join(parts) + ")"


def check_provenance(inputs: list, allow_mixed: bool) -> str | None:
    """Refuse inputs of different versions or git revisions.

    Parameters
    ----------
    inputs : list of ResultDir
    allow_mixed : bool
        Return a warning instead of raising.

    Returns
    -------
    str or None
        The warning (mixed inputs allowed), or None if all inputs agree.

    Raises
    ------
    UserError
        If the inputs differ and ``allow_mixed`` is false.
    """
    groups = provenance_groups(inputs)
    if len(groups) <= 1:
        return None
    msg = mixed_message(groups)
    if not allow_mixed:
        raise UserError(f"{msg}; pass --allow-mixed (allow_mixed=True) to build the "
                        "report anyway")
    return msg


def provenance_section(inputs: list, warning: str | None) -> list:
    """Markdown lines: kind, version, revision, seed and config of every input.

    Parameters
    ----------
    inputs : list of ResultDir
    warning : str or None
        :func:`check_provenance`'s warning, repeated at the top of the section.

    Returns
    -------
    list of str
    """
    rows = [{"directory": str(r.path), "kind": r.kind, "version": r.meta.get("version"),
             "git revision": r.meta.get("git_revision") or "-", "seed": r.meta.get("seed"),
             "files": ", ".join(r.file_meta)} for r in inputs]
    lines = ["## Provenance", ""]
    if warning:
        lines += [f"> **Warning: mixed inputs.** {warning}.", ""]
    lines += [pd.DataFrame(rows).to_markdown(index=False), ""]
    for r in inputs:
        cfg = yaml.safe_dump(r.meta.get("config", {}), sort_keys=False,
                             default_flow_style=None, width=100).rstrip()
        lines += [f"<details><summary>config of <code>{r.path}</code></summary>", "",
                  "```yaml", cfg, "```", "", "</details>", ""]
    return lines
