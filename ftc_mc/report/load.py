"""Reading one result directory (run, scenario or sweep) from its Parquet files.

:func:`load_result_dir` is the report's only reader: it refuses a directory a
live ``ftc-mc`` process is writing, one without results, one missing a table
and one whose files disagree on their kind, and returns a :class:`ResultDir`.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from ..errors import UserError
from ..io.chunks import FOLDER as CHUNKS_FOLDER
from ..io.lock import holder
from ..campaign.side import SIDE_COLUMNS
from ..campaign.summary import SUMMARY_COLUMNS
from ..io.results import read_metadata

RUN_TABLES = ("trials.parquet", "summary.parquet")
"""Parquet files a run directory must hold (``resets.parquet`` is optional)."""
SCENARIO_TABLES = ("segments.parquet", "events.parquet")
"""Parquet files a scenario directory must hold (``timeseries.parquet`` optional)."""
SWEEP_TABLES = ("sweep.parquet",)
"""Parquet file of a sweep directory."""
ENDURANCE_TABLES = ("false_resets.parquet", "endurance.parquet")
"""Parquet files of an endurance directory (``ftc-mc endurance``)."""
TRIAL_COLUMNS = ("transition", "variant", "trial_id", "correct", "inappropriate",
                 "no_reset", "first_reset_s", "false_resets", "detection_s", "mode_changed",
                 "detected", "small_b1", "lock_near_trim", "resets_truncated", "judged",
                 "status", "stop_s", "sensor_output", "sensor_kind", "sensor_size",
                 "lock_offset", "height_lost_m", "lock_position", "loss_b1",
                 *SIDE_COLUMNS, *SUMMARY_COLUMNS)
"""The ``trials.parquet`` columns the report reads (its sections, figures, the
summary function and the side monitor's table); only these are loaded, so the
report of a run of millions of trials fits in memory.  The others (draws, final estimates, the
first reset's block, reset counts) are left on disk."""


@dataclasses.dataclass
class ResultDir:
    """One input directory, as read from its Parquet files.

    Attributes
    ----------
    path : Path
        The directory as given.
    kind : str
        ``"run"``, ``"scenario"``, ``"sweep"`` or ``"endurance"``.
    meta : dict
        ``ftc_mc`` metadata of the main table (summary, events or sweep).
    file_meta : dict of str to dict
        Metadata of every Parquet file in the directory, by file name.
    tables : dict of str to DataFrame
        The tables the report uses, by file stem.
    """

    path: Path
    kind: str
    meta: dict
    file_meta: dict
    tables: dict


def _kind_from_files(path: Path) -> str | None:
    """``"run"``, ``"scenario"``, ``"sweep"`` or None, from the Parquet files present."""
    found = [k for k, files in (("run", RUN_TABLES), ("scenario", SCENARIO_TABLES),
                                ("sweep", SWEEP_TABLES), ("endurance", ENDURANCE_TABLES[1:]))
             if any((path / f).is_file() for f in files)]
    if len(found) > 1:
        raise UserError(f"{path}: holds {' and '.join(found)} files; give one "
                        "directory per result")
    return found[0] if found else None


def _file_metadata(path: Path) -> dict:
    """Metadata of every Parquet file of ``path``, by file name."""
    metas = {}
    for f in sorted(path.glob("*.parquet")):
        try:
            metas[f.name] = read_metadata(f)
        except Exception as exc:  # pyarrow raises several types for a bad file
            raise UserError(f"{f}: not a readable Parquet file ({exc})") from None
        if not metas[f.name]:
            raise UserError(f"{f}: has no ftc_mc metadata; not an ftc-mc result file")
    return metas


def _check_not_busy(path: Path) -> None:
    """Refuse a directory that a live ``ftc-mc run``/``scenario`` is writing."""
    owner = holder(path)
    if owner is not None:
        raise UserError(f"{path}: being written by `{owner.get('command')}` (pid "
                        f"{owner.get('pid')}); build the report when it has finished")


def _read(file: Path) -> pd.DataFrame:
    """A result table; of ``trials.parquet`` only :data:`TRIAL_COLUMNS`."""
    if file.name != "trials.parquet":
        return pd.read_parquet(file)
    names = pq.read_schema(file).names
    return pd.read_parquet(file, columns=[c for c in names
                                          if c in set(TRIAL_COLUMNS)])


def _with_detectors(path: Path, summary: pd.DataFrame) -> pd.DataFrame:
    """A run's summary with the rows of the detectors scored on its recorded
    signals (``ftc-mc score``: ``detectors/<name>/summary.parquet``), each after
    the built-in designs' rows of its transition."""
    extra = [pd.read_parquet(f) for f in sorted((path / "detectors").glob("*/summary.parquet"))]
    if not extra:
        return summary
    both = pd.concat([summary, *extra], ignore_index=True)
    order = {t: i for i, t in enumerate(dict.fromkeys(summary["transition"]))}
    key = both["transition"].map(order).fillna(len(order)).to_numpy()
    return both.iloc[np.argsort(key, kind="stable")].reset_index(drop=True)


def load_result_dir(path) -> ResultDir:
    """Read one run, scenario or sweep directory.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    ResultDir

    Raises
    ------
    UserError
        If ``path`` is not a directory, is being written by a live ``ftc-mc``
        process, holds no results, misses a table, or its files disagree on
        their kind.
    """
    path = Path(path)
    if not path.is_dir():
        raise UserError(f"{path}: not a directory")
    _check_not_busy(path)
    kind = _kind_from_files(path)
    if kind is None:
        unfinished = (" (only the chunks of an unfinished run: finish it with "
                      "`ftc-mc run CONFIG --resume --out DIR`)"
                      if (path / CHUNKS_FOLDER).is_dir() else "")
        raise UserError(f"{path}: no ftc-mc results{unfinished} (expected trials.parquet "
                        "and summary.parquet of a run, or segments.parquet and "
                        "events.parquet of a scenario)")
    needed = {"run": RUN_TABLES, "scenario": SCENARIO_TABLES, "sweep": SWEEP_TABLES,
              "endurance": ENDURANCE_TABLES}[kind]
    missing = [f for f in needed if not (path / f).is_file()]
    if missing:
        raise UserError(f"{path}: incomplete {kind} results, missing {', '.join(missing)}")
    file_meta = _file_metadata(path)
    kinds = {m.get("kind") for m in file_meta.values()}
    if kinds != {kind}:
        raise UserError(f"{path}: metadata kind {sorted(map(str, kinds))} does not match "
                        f"the {kind} files it holds")
    tables = {f[:-len(".parquet")]: _read(path / f) for f in needed}
    if kind == "run":
        tables["summary"] = _with_detectors(path, tables["summary"])
    elif kind == "endurance":  # detectors scored on recorded flights (ftc-mc score)
        extra = [pd.read_parquet(f)
                 for f in sorted((path / "detectors").glob("*/endurance.parquet"))]
        if extra:
            tables["endurance"] = pd.concat([tables["endurance"], *extra], ignore_index=True)
    return ResultDir(path=path, kind=kind, meta=file_meta[needed[-1]],
                     file_meta=file_meta, tables=tables)


def unique_dirs(dirs) -> list:
    """``dirs`` as Paths, duplicates (same resolved directory) dropped.

    Parameters
    ----------
    dirs : iterable of str or Path

    Returns
    -------
    list of Path
        In the given order, each directory once.
    """
    seen, out = set(), []
    for d in dirs:
        key = Path(d).resolve()
        if key not in seen:
            seen.add(key)
            out.append(Path(d))
    return out
