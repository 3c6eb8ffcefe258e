"""The final tables of a run or sweep, assembled from its chunk store one chunk at a
time: memory bounded by a chunk and a row group, not by the run.

A run's rows are ordered by transition (as configured), design (as run) and
trial id, and each chunk holds a range of trial ids of one transition, its
rows design by design (:func:`ftc_mc.campaign.runner.sort_rows`).  So
``trials.parquet`` and ``resets.parquet`` are written (``io/stream.py``)
transition by transition and design by design, reading every chunk of the
transition in chunk order and keeping the rows of that design: the same rows
in the same order as the table sorted in memory, whatever order the chunks
finished in.  Each chunk is read once per design.

The summary is a chunked scan, exact: while a (transition, design) group is
written, the columns the summary reads (:data:`~.summary.SUMMARY_COLUMNS`,
about 60 bytes per trial) are kept for that group alone, and its row is
computed from them by the same function as in memory
(:func:`~.summary.summary_row`); rates, intervals, and the medians and 95th
percentiles of the delays are therefore the same to the bit.  The memory it
takes grows with the trials of one transition (about 60 MB per million), not
with the run.

The file schema is that of the table concatenated in memory: the column union
in order of first appearance and each column's type, found from one row of
each distinct chunk schema (a chunk without resets stores its text columns
with Arrow's null type; a run mixing actuator and sensor transitions has
columns only some chunks hold, filled with nulls).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc

from ..io.results import META_KEY
from ..io.stream import ParquetStream, with_meta
from .summary import SUMMARY_COLUMNS, summary_frame, summary_row


def _starts(units) -> dict:
    """Chunk starts of each name, in chunk order."""
    out = {}
    for name, ids in units:
        out.setdefault(name, []).append(int(ids[0]))
    return out


def file_schema(store, units, table: str) -> pa.Schema:
    """The Arrow schema (pandas metadata included) ``table`` of the chunks has
    when the chunks are concatenated in memory and written by
    ``pa.Table.from_pandas``."""
    samples, seen = [], []
    for name, ids in units:
        schema = store.schema(name, int(ids[0]), table)
        if any(schema.equals(s) for s in seen):
            continue
        seen.append(schema)
        samples.append(store.arrow(name, int(ids[0]), table).slice(0, 1).to_pandas())
    return pa.Table.from_pandas(pd.concat(samples, ignore_index=True),
                                preserve_index=False).schema


def conform(table: pa.Table, schema: pa.Schema) -> pa.Table:
    """``table`` with the columns of ``schema`` in its order and types (missing
    columns as nulls), as a concatenation in memory would give it."""
    cols = []
    for field in schema:
        if field.name in table.column_names:
            col = table[field.name]
            cols.append(col if col.type == field.type else col.cast(field.type))
        else:
            cols.append(pa.nulls(table.num_rows, field.type))
    return pa.Table.from_arrays(cols, schema=schema)


def _of_variant(table: pa.Table, variant: str) -> pa.Table:
    return table.filter(pc.equal(table["variant"], variant))


def write_run_tables(store, units, variants, out_dir, meta: dict) -> pd.DataFrame:
    """Write ``trials.parquet`` and ``resets.parquet`` of a run from its chunk store,
    and return its summary.

    Parameters
    ----------
    store : ChunkStore
        Every chunk of ``units`` finished.
    units : list of (str, ndarray)
        The run's chunks (``runner.plan_chunks``), transitions in config order.
    variants : sequence of str
        The designs, in the order they were run.
    out_dir : Path
    meta : dict
        Provenance stored under ``ftc_mc`` in both files.

    Returns
    -------
    DataFrame
        The summary (:func:`~.summary.summarize` of the trials table).
    """
    starts = _starts(units)
    schemas = {t: with_meta(file_schema(store, units, t), META_KEY, meta)
               for t in ("trials", "resets")}
    rows = []
    with ParquetStream(out_dir / "trials.parquet", schemas["trials"]) as trials, \
            ParquetStream(out_dir / "resets.parquet", schemas["resets"]) as resets:
        for name, chunk_starts in starts.items():
            for variant in variants:
                keep = []
                for start in chunk_starts:
                    t = _of_variant(store.arrow(name, start, "trials"), variant)
                    t = conform(t, schemas["trials"])
                    trials.write(t)
                    keep.append(t.select([c for c in SUMMARY_COLUMNS if c in t.column_names]))
                    del t
                    r = _of_variant(store.arrow(name, start, "resets"), variant)
                    resets.write(conform(r, schemas["resets"]))
                    del r
                g = pa.concat_tables(keep).to_pandas()
                del keep
                if len(g):
                    rows.append(summary_row(name, variant, g))
                del g
    return summary_frame(rows, list(starts), variants)


def sweep_rows(store, units, variants, points, flight_name: str):
    """The per-point summary rows and the fault-free flight counts of a sweep, from
    its chunk store.

    Reads every chunk of a transition once per threshold point, keeping the
    summary columns of that (transition, point) for every design.

    Parameters
    ----------
    store : ChunkStore
    units : list of (str, ndarray)
        The sweep's chunks: transitions in config order, then the flights.
    variants : sequence of str
    points : list of (float, float)
        The threshold points.
    flight_name : str
        Chunk name of the fault-free flights.

    Returns
    -------
    tables : list of (float, float, DataFrame)
        ``(t_q, t_nx, summary)`` of every point, in point order.
    flights : DataFrame
        The fault-free flights' counts, one row per chunk, point and design.
    steps : (int, int)
        Trial steps simulated, and what the points would cost one by one.
    """
    starts = _starts(units)
    sim = alone = 0
    for name, chunk_starts in starts.items():
        for start in chunk_starts:
            st = store.arrow(name, start, "steps").to_pandas()
            sim += int(st["simulated"].iloc[0])
            alone += int(st["alone"].iloc[0])
    flights = pd.concat([store.arrow(flight_name, s, "trials").to_pandas()
                         for s in starts.get(flight_name, [])], ignore_index=True)
    names = [n for n in starts if n != flight_name]
    points = sorted(set(map(tuple, points)))
    per_point = {}
    for name in names:
        for tq, tnx in points:
            parts = []
            for start in starts[name]:
                t = store.arrow(name, start, "trials")
                t = t.filter(pc.and_(pc.equal(t["t_q"], tq), pc.equal(t["t_nx"], tnx)))
                parts.append(t.select([c for c in SUMMARY_COLUMNS if c in t.column_names]))
            g = pa.concat_tables(parts, promote_options="default").to_pandas()
            for variant in variants:
                gv = g[g["variant"] == variant]
                if len(gv):
                    per_point.setdefault((tq, tnx), []).append(summary_row(name, variant, gv))
    tables = [(tq, tnx, summary_frame(per_point.get((tq, tnx), []), names, variants))
              for tq, tnx in points]
    return tables, flights, (sim, alone)
