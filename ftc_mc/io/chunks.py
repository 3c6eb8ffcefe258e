"""Finished chunks of a campaign on disk, so a killed or interrupted run resumes.

Layout inside the output directory::

    .chunks/manifest.json                 the resolved config this run belongs to
    .chunks/<transition>-<first id>.resets.parquet
    .chunks/<transition>-<first id>.trials.parquet   written last: marks the chunk done

Every file is written atomically (temporary name, then rename), so a chunk is
either complete or absent whatever moment the process dies or is interrupted;
a temporary file left by a killed process is removed when the run resumes.
The final result files are assembled from the chunk files only, one chunk at a
time, so a resumed run and an uninterrupted one produce the same bytes of
result data.

Resuming looks at the folder once (:meth:`ChunkStore.finished`: one directory
listing, whatever the number of chunks), so a run of 15 000 chunks resumes in
time proportional to the chunks still to run (``scripts/benchmarks/bench_resume.py``).
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import UserError
from .atomic import atomic_path, write_text

FOLDER = ".chunks"


class ChunkStore:
    """Chunk files of one run directory.

    Parameters
    ----------
    out : Path
        The run's output directory.
    config_json : str
        Canonical JSON of the resolved configuration.
    """

    def __init__(self, out: Path, config_json: str):
        self.folder = Path(out) / FOLDER
        self.config_json = config_json

    def exists(self) -> bool:
        """Whether an unfinished run left chunks here."""
        return (self.folder / "manifest.json").exists()

    def open(self, resume: bool, resolve=None) -> None:
        """Start a new chunk folder, or check the one being resumed.

        ``resolve`` (optional) maps the identity the folder recorded to what it
        means under the current schema (fields added since then at their
        defaults), so a run recorded before a field existed still resumes.

        Raises
        ------
        UserError
            ``resume`` with chunks of another configuration, or without
            ``resume`` over chunks of an unfinished run.
        """
        manifest = self.folder / "manifest.json"
        if manifest.exists():
            if not resume:
                raise UserError(f"--out: {self.folder.parent} holds an unfinished run; pass "
                                "--resume to continue it or --overwrite to start again")
            try:
                theirs = json.loads(manifest.read_text(encoding="utf-8"))["config"]
            except (OSError, ValueError, KeyError):
                raise UserError(f"--resume: {manifest} is unreadable") from None
            if (theirs if resolve is None else resolve(theirs)) != json.loads(self.config_json):
                raise UserError(f"--resume: {self.folder.parent} was made by another "
                                "configuration (or other --trials/--seed/--signature)")
            self._remove_temporaries()
            return
        self.folder.mkdir(parents=True, exist_ok=True)
        write_text(manifest, json.dumps({"config": json.loads(self.config_json)},
                                        sort_keys=True))

    def _path(self, name: str, start: int, table: str) -> Path:
        return self.folder / f"{name}-{start:09d}.{table}.parquet"

    def finished(self) -> set:
        """``(name, start)`` of every finished chunk, from one listing of the folder."""
        out = set()
        if not self.folder.is_dir():
            return out
        tail = ".trials.parquet"
        with os.scandir(self.folder) as it:
            for entry in it:
                if entry.name.endswith(tail) and not entry.name.startswith("."):
                    name, _, start = entry.name[:-len(tail)].rpartition("-")
                    if start.isdigit():
                        out.add((name, int(start)))
        return out

    def _remove_temporaries(self) -> None:
        """Delete temporary files a killed process left (never under a final name)."""
        with os.scandir(self.folder) as it:
            for entry in it:
                if entry.name.startswith(".") and entry.name.endswith(".tmp"):
                    Path(entry.path).unlink(missing_ok=True)

    def write(self, name: str, start: int, trials: pd.DataFrame, **others: pd.DataFrame):
        """Store one finished chunk: the other tables first, then ``trials`` as the
        marker that the chunk is complete."""
        for table, df in [*others.items(), ("trials", trials)]:
            with atomic_path(self._path(name, start, table), suffix=".parquet") as tmp:
                pq.write_table(pa.Table.from_pandas(df, preserve_index=False), tmp)

    def read(self, name: str, start: int, tables=("trials", "resets")):
        """DataFrames of a finished chunk, one per name in ``tables``."""
        return tuple(pq.read_table(self._path(name, start, t)).to_pandas() for t in tables)

    def arrow(self, name: str, start: int, table: str, columns=None) -> pa.Table:
        """One table of a finished chunk as Arrow (only ``columns`` if given)."""
        return pq.read_table(self._path(name, start, table), columns=columns)

    def schema(self, name: str, start: int, table: str) -> pa.Schema:
        """The Arrow schema of one table of a finished chunk (its footer only)."""
        return pq.read_schema(self._path(name, start, table))

    def discard_if_empty(self) -> None:
        """Delete the chunk folder if no chunk in it was finished (a run refused
        before its first chunk leaves nothing behind)."""
        if not any(self.folder.glob("*.trials.parquet")):
            self.remove()

    def remove(self) -> None:
        """Delete the chunk folder (after the final files are written)."""
        shutil.rmtree(self.folder, ignore_errors=True)
