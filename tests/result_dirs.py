"""Helpers of the report tests that handle result directories."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd

from ftc_mc.io.results import read_metadata, write_parquet


def same_stamp(src: Path, dst: Path) -> None:
    """Give ``dst``'s files the version and git revision of ``src``.

    Other engineers commit and edit tracked files while the suite runs, so the
    revision (and its ``+dirty`` suffix) can change between two CLI calls.
    """
    ref = read_metadata(src / "summary.parquet")
    for path in dst.glob("*.parquet"):
        meta = read_metadata(path)
        if (meta["version"], meta["git_revision"]) != (ref["version"], ref["git_revision"]):
            meta.update(version=ref["version"], git_revision=ref["git_revision"])
            write_parquet(pd.read_parquet(path), path, meta)


def copy_dir(src: Path, dst: Path) -> Path:
    """A copy of the result directory ``src`` at ``dst``."""
    shutil.copytree(src, dst)
    return dst
