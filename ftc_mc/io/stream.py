"""A Parquet file written piece by piece: memory bounded by a row group, not by
the file.

:class:`ParquetStream` writes Arrow tables of one schema as they come, buffered
into row groups of :data:`ROW_GROUP_ROWS` rows, to a temporary file beside the
target that is renamed onto it only when complete (``io/atomic.py``: a reader
never sees a half-written file, and it gets the umask's mode).  The schema
carries the ``ftc_mc`` provenance (``io/results.py``) like every result file.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from .atomic import commit, temp_path

ROW_GROUP_ROWS = 1 << 18
"""Rows per row group of a streamed file (262 144; a ``resets.parquet`` row
group of the paper's columns is about 25 MB in memory)."""


def with_meta(schema: pa.Schema, key: bytes, meta: dict) -> pa.Schema:
    """``schema`` with ``meta`` as JSON under ``key`` of its metadata."""
    merged = dict(schema.metadata or {})
    merged[key] = json.dumps(meta, sort_keys=True).encode()
    return schema.with_metadata(merged)


class ParquetStream:
    """Write one Parquet file from a sequence of Arrow tables (a context manager).

    Parameters
    ----------
    path : Path
        The final file; replaced only when the block ends without an error.
    schema : pa.Schema
        Schema of the file, metadata included; every table written is cast to it.
    row_group_rows : int, optional
        Rows buffered before a row group is written (:data:`ROW_GROUP_ROWS`).
    """

    def __init__(self, path, schema: pa.Schema, row_group_rows: int | None = None):
        self.path = Path(path)
        self.schema = schema
        self.row_group_rows = ROW_GROUP_ROWS if row_group_rows is None else row_group_rows
        self.buffer, self.buffered, self.rows = [], 0, 0
        self.tmp = None
        self.writer = None

    def __enter__(self):
        self.tmp = temp_path(self.path, ".parquet")
        self.writer = pq.ParquetWriter(self.tmp, self.schema)
        return self

    def write(self, table: pa.Table) -> None:
        """Append the rows of ``table`` (its columns in the file's order and types)."""
        if table.num_rows == 0:
            return
        self.buffer.append(table)
        self.buffered += table.num_rows
        if self.buffered >= self.row_group_rows:
            self._flush()

    def _flush(self) -> None:
        if self.buffered:
            table = pa.concat_tables(self.buffer)
            self.writer.write_table(table, row_group_size=self.row_group_rows)
            self.rows += table.num_rows
        self.buffer, self.buffered = [], 0

    def __exit__(self, exc_type, exc, tb):
        try:
            if exc_type is None:
                self._flush()
                if self.rows == 0:  # as pq.write_table writes an empty table
                    self.writer.write_table(self.schema.empty_table())
            self.writer.close()
            if exc_type is None:
                commit(self.tmp, self.path)
        finally:
            if self.tmp.exists():
                self.tmp.unlink()
        return False
