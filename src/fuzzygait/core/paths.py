"""Paths checked before any work: the input files a command reads are there (a C3D trial,
a subject file) and the files it writes have a suffix it writes (the suffixes known
without importing the libraries that write them), so a mistyped path gets its one line
at once, not after the imports of xarray, pandas and scipy (about 1.5 s)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from fuzzygait.core.errors import C3DError, FuzzyGaitError, ParameterError
from fuzzygait.core.options import Option

__all__ = ["DATASET_SUFFIXES", "FIGURE_SUFFIXES", "SUBJECT_INPUT_KINDS", "SUBJECT_SUFFIXES", "TABLE_SUFFIXES",
           "check_c3d_input", "check_c3d_path", "check_not_input", "check_subject_input", "check_subject_path",
           "check_table_path"]  # fmt: skip

#: Fuzzy results: netCDF files or zarr stores (:mod:`fuzzygait.uncertainty.storage`).
DATASET_SUFFIXES = (".nc", ".zarr")
#: Figures (formats, without the dot) :func:`fuzzygait.io.figure_files.save_figure` writes.
FIGURE_SUFFIXES = ("png", "svg", "pdf")
#: Tables (:func:`fuzzygait.io.tables.write_table`).
TABLE_SUFFIXES = (".csv", ".parquet")
#: Subject files ``calibrate`` writes.
SUBJECT_SUFFIXES = (".toml", ".vsk")
#: Subject files read (:func:`fuzzygait.io.subject.read_subject`): suffix and what it is.
SUBJECT_INPUT_KINDS = {".toml": ".toml", ".vsk": ".vsk", ".mp": "a Vicon Nexus or pyCGM2 .mp",
                       ".xml": "a QTM session.xml"}  # fmt: skip
#: The smallest C3D file: one 512-byte block (the header).
C3D_BLOCK = 512


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


def check_not_input(path: str | os.PathLike[str], inputs: Sequence[str | os.PathLike[str] | None],
                    option: Option | str = Option.OUT) -> Path:  # fmt: skip
    """``path`` unless it is the same file as one of ``inputs`` by any name (``./x.c3d``,
    a hard or symbolic link): an output never replaces a file the command reads.  Else a
    clear error naming ``option`` and the input."""
    path = Path(path)
    if path.exists():
        for source in inputs:
            if source is not None and Path(source).exists() and os.path.samefile(path, source):
                raise FuzzyGaitError(f"{path}: {option} is the input file {source}; writing it would replace the "
                                     "input: choose another name")  # fmt: skip
    return path


def check_c3d_input(path: str | os.PathLike[str]) -> Path:
    """``path`` if it is a file that can be a C3D file (at least its 512-byte header);
    else the :class:`~fuzzygait.core.errors.C3DError` naming it and what to do."""
    path = Path(path)
    if not path.exists():
        raise C3DError(f"{path}: no such file; check the path")
    if not path.is_file():
        raise C3DError(f"{path}: is not a file; give a .c3d file")
    if path.stat().st_size < C3D_BLOCK:
        raise C3DError(f"{path}: too short to be a C3D file (under {C3D_BLOCK} bytes); the file is damaged")
    return path


def check_subject_input(path: str | os.PathLike[str]) -> Path:
    """``path`` if it is a subject file of a kind :data:`SUBJECT_INPUT_KINDS` names and
    is there; else the :class:`~fuzzygait.core.errors.ParameterError` naming it."""
    path = Path(path)
    *first, last = SUBJECT_INPUT_KINDS.values()
    kinds = f"{', '.join(first)} or {last}"
    if path.is_dir():
        raise ParameterError(f"{path}: is a folder, not a subject file; give the subject file itself ({kinds})")
    if path.suffix.lower() not in SUBJECT_INPUT_KINDS:
        raise ParameterError(f"{path}: unknown subject file type {path.suffix.lower()!r}; use {kinds}")
    if not path.exists():
        raise ParameterError(f"{path}: no such subject file; check the path")
    return path
