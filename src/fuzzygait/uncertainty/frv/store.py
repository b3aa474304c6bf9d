"""The crash-consistent zarr store of an FRV study (:class:`~fuzzygait.uncertainty.frv.FRVStudy`).

Commit protocol. Every file of the store is written whole or not at all (zarr's local
store writes a file beside and renames it). The root attributes are the *commit
record*: the study's settings, its counts and how many rows of each group are valid
(``library_rows``, ``interval_rows``, ``n_samples``). A write phase appends its rows
first and then rewrites the commit record (one file), so rows beyond the record are
a killed write's leftovers: :func:`check` cuts them off (or, reading only, ignores
them) and removes a group that no commit has counted. A group holding fewer rows than
its record says is damage no kill can cause; the study is refused in one line.

A new study is built in a temporary folder beside its target and moved into place
when complete (:func:`~fuzzygait.io.atomic.replace_folder`), so a failed or
killed first run leaves nothing at the target.
"""

from __future__ import annotations

import shutil
from collections.abc import Mapping
from pathlib import Path
from typing import Any, cast

import xarray as xr
import zarr

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Advice, Option

STORE_FORMAT = "fuzzygait-frv-2"
#: the format before the commit record (its valid rows are inferred from its counts)
LEGACY_FORMAT = "fuzzygait-frv-1"
#: group → (its row dimension, the commit-record key of its valid rows, its variables)
GROUPS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "library": ("bin", "library_rows", ("value",)),
    "intervals": ("interval", "interval_rows", ("left", "right", "lower", "upper")),
    "samples": ("sample", "n_samples", ("hull", "cut", "bin")),
}
_KEYS = ("spec", "seed", "grid", "n_disc", "time_stride", "refine", "chunk", "n_time", "n_samples", "counts")
FIX = Advice("start a new study (frv-sim: another {out}, or {overwrite})", out=Option.OUT, overwrite=Option.OVERWRITE)


class StudyError(FuzzyGaitError):
    """A store that is not a usable FRV study (names the store and what to do)."""


def read_meta(path: Path) -> dict[str, Any]:
    """The commit record of the study at ``path`` (legacy stores: rows from the counts)."""
    if not path.is_dir():
        raise StudyError(f"{path}: no such FRV study; check the path")
    try:
        attrs: dict[str, Any] = dict(zarr.open_group(path, mode="r").attrs)
    except Exception as exc:  # noqa: BLE001 - anything unreadable is "not a study"
        raise StudyError(f"{path}: not an FRV study (no readable zarr group: {exc}); {FIX}") from None
    fmt = attrs.get("format")
    if fmt == LEGACY_FORMAT and isinstance(attrs.get("counts"), dict):
        counts = attrs["counts"]
        attrs.setdefault("library_rows", int(counts.get("forward_simulations", 0)))
        attrs.setdefault("interval_rows", int(counts.get("occurring_intervals", 0)))
    elif fmt != STORE_FORMAT:
        raise StudyError(f"{path}: not an FRV study store (format {fmt!r}); {FIX}")
    missing = [key for key in (*_KEYS, "library_rows", "interval_rows") if key not in attrs]
    if missing:
        raise StudyError(f"{path}: the study's record lacks {', '.join(missing)}; {FIX}")
    return attrs


def commit(path: Path, attrs: Mapping[str, Any]) -> None:
    """Rewrite the commit record with ``attrs`` merged in: one atomic write of ``.zattrs``
    (``Group.update_attributes``; ``attrs.update`` would write the file once per key)."""
    zarr.open_group(path, mode="r+", zarr_format=2).update_attributes(dict(attrs))


def new_store(path: Path, attrs: Mapping[str, Any]) -> None:
    """An empty study (its first commit record) in the empty folder ``path``."""
    zarr.open_group(path, mode="w", zarr_format=2).update_attributes({"format": STORE_FORMAT, **attrs})


def check(path: Path, meta: Mapping[str, Any], repair: bool = False) -> None:
    """Compare every group with the commit record ``meta``.

    With ``repair`` rows beyond the record are cut off, groups no commit counted and
    zarr's ``*.partial`` temporaries are removed (all left by a killed write).

    Raises:
        StudyError: a group lacks rows or variables the record counts.
    """
    if repair:  # before zarr lists the folder (it warns about them)
        for leftover in path.rglob("*.partial"):
            leftover.unlink(missing_ok=True)
    root = zarr.open_group(path, mode="a" if repair else "r", zarr_format=2)
    for name, (dim, key, variables) in GROUPS.items():
        rows = int(meta[key])
        if rows == 0:
            if repair and (path / name).exists():
                shutil.rmtree(path / name, ignore_errors=True)
            continue
        if name not in root:
            raise StudyError(f"{path}: the study is damaged: its {name} group is missing; {FIX}")
        group = cast("zarr.Group", root[name])
        arrays = dict(group.arrays())
        absent = [v for v in variables if v not in arrays]
        if absent:
            raise StudyError(f"{path}: the study is damaged: {name} lacks {', '.join(absent)}; {FIX}")
        for array_name, array in arrays.items():
            dims = cast("list[str]", array.attrs.get("_ARRAY_DIMENSIONS", []))
            if not dims or dims[0] != dim:
                continue
            if array.shape[0] < rows:
                raise StudyError(f"{path}: the study is damaged: {name}/{array_name} has {array.shape[0]} of "
                                 f"its {rows} rows; {FIX}")  # fmt: skip
            if repair and array.shape[0] > rows:
                array.resize((rows, *array.shape[1:]))


def open_group(path: Path, name: str, rows: int) -> xr.Dataset:
    """The first ``rows`` rows of group ``name``, lazily (slices read on access, nothing
    cached)."""
    dim = GROUPS[name][0]
    try:
        ds = xr.open_dataset(path, engine="zarr", group=name, consolidated=False, chunks=None, cache=False)
    except (ValueError, KeyError, OSError) as exc:
        raise StudyError(f"{path}: its {name} cannot be read ({exc}); opening the study to extend it (frv-sim "
                         f"{Option.SAMPLES} 0) discards an interrupted write, else {FIX}") from None  # fmt: skip
    return ds.isel({dim: slice(0, rows)})


def read_group(path: Path, name: str) -> xr.Dataset:
    """The committed rows of group ``name`` of the study at ``path``, lazily, after
    :func:`check` (a reader does not repair)."""
    meta = read_meta(path)
    check(path, meta)
    return open_group(path, name, int(meta[GROUPS[name][1]]))


def append(path: Path, name: str, ds: xr.Dataset, dim: str, encoding: dict[str, Any] | None = None) -> None:
    """Write ``ds`` to group ``name``: create it, or append along ``dim``."""
    root = zarr.open_group(path, mode="r")
    if name in root:
        ds.to_zarr(path, group=name, append_dim=dim, consolidated=False, zarr_format=2)
    else:
        ds.to_zarr(path, group=name, mode="w-", consolidated=False, zarr_format=2, encoding=encoding)
