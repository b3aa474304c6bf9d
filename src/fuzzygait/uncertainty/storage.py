"""Saving and loading fuzzy results (netCDF ``.nc`` or zarr ``.zarr``), atomically: one
dataset (:func:`save_result`, :func:`load_result`) or several as the root and groups of
one file (:func:`save_groups`, :func:`load_groups`; each group with its own dimensions,
so not an :class:`xarray.DataTree`, whose groups must align with their parents).

A zarr result is a folder: it is written complete beside its target and then swapped
into place (:func:`fuzzygait.io.atomic.replace_folder`), so a process killed at any moment
leaves the previous result or the new one at the target, never a mixture and never
nothing. Temporary files and folders carry the writing process's id; one left by a
killed process is removed by the next save to the same target.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.paths import DATASET_SUFFIXES
from fuzzygait.io.atomic import atomic_output, replace_folder, temporary_folder


def _kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in DATASET_SUFFIXES:
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
    """Read a result written by :func:`save_result` (fully into memory).

    Raises:
        FuzzyGaitError: no such file, it cannot be read, or it is not a result dataset.
    """
    path = Path(path)
    kind = _kind(path)
    if not path.exists():
        raise FuzzyGaitError(f"{path}: no such result; check the path")
    with _reading(path):
        if kind == ".nc":
            with xr.open_dataset(path, engine="h5netcdf") as ds:
                return ds.load()
        return xr.open_zarr(path).load()


@contextmanager
def _reading(path: Path) -> Iterator[None]:
    """Turn the error of reading ``path`` as a result into one line naming the file: it
    cannot be read, or it is not a result (not netCDF, an empty or foreign zarr folder)."""
    try:
        yield
    except PermissionError as exc:
        raise FuzzyGaitError(f"{path}: cannot be read ({exc.strerror or exc}); check its permissions") from exc
    except (OSError, ValueError) as exc:
        raise FuzzyGaitError(f"{path}: not a fuzzygait result dataset (a .nc or .zarr written by fuzzygait): "
                             f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}") from exc  # fmt: skip


def _write_groups(groups: Mapping[str, xr.Dataset], target: Path, kind: str) -> None:
    """Write the root (``"/"``) and then each group into ``target`` (a new file or folder)."""
    for name, dataset in groups.items():
        group = None if name == "/" else name.strip("/")
        if kind == ".nc":
            dataset.to_netcdf(target, engine="h5netcdf", mode="w" if group is None else "a", group=group)
        else:
            dataset.to_zarr(target, mode="w" if group is None else "a", group=group, zarr_format=2,
                            consolidated=False)  # fmt: skip
    if kind == ".zarr":
        import zarr

        zarr.consolidate_metadata(str(target))  # widest compatibility, as save_result


def save_groups(groups: Mapping[str, xr.Dataset], path: str | os.PathLike[str]) -> Path:
    """Write ``groups`` (``"/"``: the root, first; ``"/name"``: a group) to ``path``,
    atomically as :func:`save_result`."""
    path = Path(path)
    kind = _kind(path)
    if next(iter(groups), None) != "/" or any(not k.startswith("/") or k.count("/") != 1 for k in groups):
        raise FuzzyGaitError(f"{path}: groups must start with the root '/' and be named '/name'; got {list(groups)}")
    if kind == ".nc":
        with atomic_output(path) as tmp:
            _write_groups(groups, tmp, kind)
        return path
    if not path.parent.exists():
        raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
    tmp = temporary_folder(path)
    try:
        _write_groups(groups, tmp, kind)
        replace_folder(tmp, path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return path


def load_groups(path: str | os.PathLike[str]) -> dict[str, xr.Dataset]:
    """Read every group of a file written by :func:`save_groups` (or :func:`save_result`:
    the root only), fully into memory: ``{"/": root, "/name": group, ...}``.

    Raises:
        FuzzyGaitError: no such file, it cannot be read, or it is not a result dataset.
    """
    path = Path(path)
    kind = _kind(path)
    if not path.exists():
        raise FuzzyGaitError(f"{path}: no such result; check the path")
    with _reading(path):
        groups = xr.open_groups(path, engine="h5netcdf" if kind == ".nc" else "zarr")
        try:
            return {name: dataset.load() for name, dataset in groups.items()}
        finally:
            for dataset in groups.values():
                dataset.close()
