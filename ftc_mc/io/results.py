"""Parquet result files with provenance metadata, written atomically.

Each file carries, under the key ``ftc_mc`` of the Arrow schema metadata, a JSON
object with the resolved configuration, the package version, the git revision
(when the package runs from a git checkout) and the root seed.
"""

from __future__ import annotations

import json
import subprocess
from importlib import metadata
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import UserError
from .atomic import atomic_path, write_text

META_KEY = b"ftc_mc"
RUN_FILES = ("trials.parquet", "resets.parquet", "summary.parquet", "summary.md",
             "timeseries.parquet", "events.parquet", "sweep.parquet", "endurance.parquet")


def package_version() -> str:
    """Installed version of ftc-mc."""
    try:
        return metadata.version("ftc-mc")
    except metadata.PackageNotFoundError:
        return "unknown"


def git_revision() -> str | None:
    """Git revision of the source tree this package runs from, if any."""
    root = Path(__file__).resolve().parents[2]
    try:
        out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"],
                             capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    if out.returncode != 0:
        return None
    rev = out.stdout.strip()
    dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                            "--untracked-files=no"], capture_output=True, text=True,
                           timeout=5)
    return rev + ("+dirty" if dirty.returncode == 0 and dirty.stdout.strip() else "")


def provenance(config: dict, seed: int, kind: str) -> dict:
    """The metadata stored in every result file."""
    return {"kind": kind, "config": config, "version": package_version(),
            "git_revision": git_revision(), "seed": seed}


def write_parquet(df: pd.DataFrame, path, meta: dict) -> None:
    """Write ``df`` to ``path`` atomically with ``meta`` as JSON metadata."""
    table = pa.Table.from_pandas(df, preserve_index=False)
    merged = dict(table.schema.metadata or {})
    merged[META_KEY] = json.dumps(meta, sort_keys=True).encode()
    table = table.replace_schema_metadata(merged)
    with atomic_path(path, suffix=".parquet") as tmp:
        pq.write_table(table, tmp)


def read_metadata(path) -> dict:
    """The ``ftc_mc`` metadata of a result file (empty dict if absent)."""
    md = pq.read_schema(path).metadata or {}
    return json.loads(md[META_KEY]) if META_KEY in md else {}


def prepare_output_dir(out: Path, overwrite: bool = False) -> None:
    """Refuse to overwrite a finished run; create the directory otherwise.

    Raises
    ------
    UserError
        If ``out`` is a file, or already holds a finished run and ``overwrite``
        is false.
    """
    if out.exists() and not out.is_dir():
        raise UserError(f"--out: {out} exists and is not a directory")
    if not overwrite and out.is_dir() and any((out / f).exists() for f in RUN_FILES):
        raise UserError(f"--out: {out} already holds results; choose another "
                        "directory or pass --overwrite")


def write_summary(out: Path, summary: pd.DataFrame, summary_md: str, meta: dict) -> None:
    """Write ``summary.parquet`` and ``summary.md`` of a run, each atomically; the
    last files of a run (``trials.parquet`` and ``resets.parquet`` are streamed
    before them, ``campaign/assemble.py``)."""
    write_parquet(summary, out / "summary.parquet", meta)
    write_text(out / "summary.md", summary_md)
