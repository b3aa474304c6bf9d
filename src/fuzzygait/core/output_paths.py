"""Output paths checked before any work: the suffixes of the files the commands write and
one clear line for a path with another, known without importing the libraries that write
them, so a mistyped path is answered at once (xarray, pandas and scipy alone take about
1.5 s to import)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Option

__all__ = ["DATASET_SUFFIXES", "FIGURE_SUFFIXES", "SUBJECT_SUFFIXES", "TABLE_SUFFIXES", "check_c3d_path",
           "check_subject_path", "check_table_path"]  # fmt: skip

#: Fuzzy results: netCDF files or zarr stores (:mod:`fuzzygait.uncertainty.storage`).
DATASET_SUFFIXES = (".nc", ".zarr")
#: Figures (formats, without the dot) :func:`fuzzygait.io.figure_files.save_figure` writes.
FIGURE_SUFFIXES = ("png", "svg", "pdf")
#: Tables (:func:`fuzzygait.io.tables.write_table`).
TABLE_SUFFIXES = (".csv", ".parquet")
#: Subject files ``calibrate`` writes.
SUBJECT_SUFFIXES = (".toml", ".vsk")


def _check(path: str | os.PathLike[str], suffixes: Sequence[str], message: str) -> Path:
    path = Path(path)
    if path.suffix.lower() not in suffixes:
        raise FuzzyGaitError(f"{path}: {message}")
    return path


def check_table_path(path: str | os.PathLike[str], option: Option | str = Option.OUT) -> Path:
    """``path`` if its suffix is a table format, else a clear error naming ``option``."""
    return _check(path, TABLE_SUFFIXES, f"{option} must end in .csv or .parquet")


def check_subject_path(path: str | os.PathLike[str], option: Option | str = Option.OUT) -> Path:
    """``path`` if it names a ``.toml`` or ``.vsk`` subject file, else a clear error."""
    return _check(path, SUBJECT_SUFFIXES, f"{option} must name a .toml or .vsk subject file")


def check_c3d_path(path: str | os.PathLike[str], option: Option | str = Option.OUT) -> Path:
    """``path`` if it names a ``.c3d`` file, else a clear error naming ``option``."""
    return _check(path, (".c3d",), f"{option} must name a .c3d file")
