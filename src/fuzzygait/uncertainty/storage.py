"""Saving and loading fuzzy results (netCDF ``.nc`` or zarr ``.zarr``), atomically.

A zarr result is a folder: it is written complete beside its target and then swapped
into place (:func:`fuzzygait.io.atomic.replace_folder`), so a process killed at any moment
leaves the previous result or the new one at the target, never a mixture and never
nothing. Temporary files and folders carry the writing process's id; one left by a
killed process is removed by the next save to the same target.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.atomic import atomic_output, replace_folder, temporary_folder

SUFFIXES = (".nc", ".zarr")


def _kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise FuzzyGaitError(f"{path}: results are saved as .nc (netCDF) or .zarr")
    return suffix


def save_result(result: xr.Dataset, path: str | os.PathLike[str]) -> Path:
    """Write ``result`` to ``path``; on failure nothing new is left and a previous result
    at ``path`` is untouched (a .zarr folder is written beside and swapped into place)."""
    path = Path(path)
    if _kind(path) == ".nc":
        with atomic_output(path) as tmp:
            result.to_netcdf(tmp, engine="h5netcdf")
        return path
    if not path.parent.exists():
        raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
    tmp = temporary_folder(path)
    try:
        result.to_zarr(tmp, mode="w", zarr_format=2, consolidated=True)  # widest compatibility
        replace_folder(tmp, path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return path


def load_result(path: str | os.PathLike[str]) -> xr.Dataset:
    """Read a result written by :func:`save_result` (fully into memory)."""
    path = Path(path)
    kind = _kind(path)
    if not path.exists():
        raise FuzzyGaitError(f"{path}: no such result; check the path")
    if kind == ".nc":
        with xr.open_dataset(path, engine="h5netcdf") as ds:
            return ds.load()
    return xr.open_zarr(path).load()
