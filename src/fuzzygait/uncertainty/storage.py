"""Saving and loading fuzzy results (netCDF ``.nc`` or zarr ``.zarr``), atomically.

A zarr result is a folder: it is written complete beside its target and then swapped
into place (:func:`replace_folder`), so a process killed at any moment leaves the
previous result or the new one at the target, never a mixture and never nothing.
Temporary folders carry the writing process's id; one left by a killed process is
removed by the next save to the same target (:func:`remove_stale`).
"""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
from pathlib import Path

import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.atomic import atomic_output

SUFFIXES = (".nc", ".zarr")
_AT_FDCWD, _RENAME_EXCHANGE = -100, 2  # <fcntl.h>, <linux/fs.h>


def _kind(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise FuzzyGaitError(f"{path}: results are saved as .nc (netCDF) or .zarr")
    return suffix


def _exchange(a: Path, b: Path) -> bool:
    """Swap ``a`` and ``b`` in one atomic step (Linux ``renameat2(RENAME_EXCHANGE)``);
    False where the platform or the file system cannot (then nothing was changed)."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (AttributeError, OSError):
        return False
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    errno = ctypes.get_errno()
    if errno in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: not supported here
        return False
    raise OSError(errno, os.strerror(errno), str(b))


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def replace_folder(new: Path, target: Path) -> None:
    """Move the complete folder ``new`` onto ``target``, replacing whatever is there.

    Where the system allows, the two are exchanged atomically and the old one removed
    afterwards, so ``target`` is at every moment the complete old or the complete new
    folder. Elsewhere the old one is renamed aside (``.NAME.old-PID``) first: nothing is
    deleted before the new folder is in place.
    """
    if not os.path.lexists(target):
        os.rename(new, target)
        return
    if _exchange(new, target):
        _remove(new)  # now the old folder
        return
    aside = target.with_name(f".{target.name}.old-{os.getpid()}")
    os.rename(target, aside)
    os.rename(new, target)
    _remove(aside)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale(folder: Path, prefix: str) -> None:
    """Remove ``folder/PREFIX<pid>-…`` entries whose writing process ``<pid>`` is gone
    (what a killed process leaves behind); entries of running processes are kept."""
    if not folder.is_dir():
        return
    for entry in folder.glob(f"{_glob_escape(prefix)}*"):
        pid = entry.name[len(prefix) :].split("-", 1)[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            _remove(entry)


def _glob_escape(text: str) -> str:
    """``text`` as a literal in a glob pattern."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


def _restore_aside(target: Path) -> None:
    """Undo what a process killed inside :func:`replace_folder`'s fallback left: the old
    folder renamed aside and nothing at ``target`` — it goes back (else it is removed)."""
    prefix = f".{target.name}.old-"
    for entry in target.parent.glob(f"{_glob_escape(prefix)}*"):
        pid = entry.name[len(prefix) :]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            if os.path.lexists(target):
                _remove(entry)
            else:
                os.rename(entry, target)


TEMPORARY_KINDS = ("tmp", "creating")


def tidy_beside(target: Path) -> None:
    """Clear what killed processes left beside ``target``: their temporary folders
    (:func:`temporary_folder`) are removed, an old folder renamed aside is put back."""
    for kind in TEMPORARY_KINDS:
        remove_stale(target.parent, f".{target.name}.{kind}-")
    _restore_aside(target)


def temporary_folder(target: Path, kind: str = "tmp") -> Path:
    """A new empty folder ``.NAME.KIND-PID-XXXX`` beside ``target`` (``kind`` one of
    :data:`TEMPORARY_KINDS`), after :func:`tidy_beside`."""
    tidy_beside(target)
    return Path(tempfile.mkdtemp(prefix=f".{target.name}.{kind}-{os.getpid()}-", dir=target.parent))


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
