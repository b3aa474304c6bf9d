"""Atomic file-system output: a result file or folder appears complete or not at all,
and what a killed process leaves behind is cleared by the next writer.

Temporary names carry the writing process's id (``.NAME.tmp-PID-XXXX``), so a later
writer can tell a killed process's leftovers (removed) from a running one's (kept).
"""

from __future__ import annotations

import ctypes
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError

_AT_FDCWD, _RENAME_EXCHANGE = -100, 2  # <fcntl.h>, <linux/fs.h>

#: Kinds of temporary entries beside a target (``.NAME.KIND-PID-XXXX``).
TEMPORARY_KINDS = ("tmp", "creating")


@contextmanager
def atomic_output(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; move it onto ``path`` on success.

    The temporary file (``.NAME.tmp-PID-XXXX.SUFFIX``) keeps ``path``'s suffix (some
    writers insist on it). On any exception it is removed and nothing is left at
    ``path``; one left by a killed process is removed by the next write to ``path``.

    Raises:
        FuzzyGaitError: when the folder of ``path`` does not exist.
    """
    path = Path(path)
    if not path.parent.exists():
        raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
    remove_stale(path.parent, f".{path.name}.tmp-")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.tmp-{os.getpid()}-", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; give normal rights
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def temporary_folder(target: Path, kind: str = "tmp") -> Path:
    """A new empty folder ``.NAME.KIND-PID-XXXX`` beside ``target`` (``kind`` one of
    :data:`TEMPORARY_KINDS`), after :func:`tidy_beside`."""
    tidy_beside(target)
    return Path(tempfile.mkdtemp(prefix=f".{target.name}.{kind}-{os.getpid()}-", dir=target.parent))


def replace_path(new: Path, target: Path) -> None:
    """Move ``new`` onto ``target`` (a file or a folder), replacing it; ``target`` is at
    every moment the complete old or the complete new one (:func:`replace_folder`)."""
    if new.is_dir() and not new.is_symlink():
        replace_folder(new, target)
    else:
        os.replace(new, target)


def replace_folder(new: Path, target: Path) -> None:
    """Move the complete folder ``new`` onto ``target``, replacing whatever is there.

    Where the system allows, the two are exchanged atomically and the old one removed
    afterwards, so ``target`` is at every moment the complete old or the complete new
    folder. Elsewhere the old one is renamed aside (``.NAME.old-PID``) first: nothing is
    deleted before the new folder is in place, and :func:`tidy_beside` puts it back if
    the process is killed between the two renames.
    """
    if not os.path.lexists(target):
        os.rename(new, target)
        return
    if exchange(new, target):
        remove_path(new)  # now the old folder
        return
    aside = target.with_name(f".{target.name}.old-{os.getpid()}")
    os.rename(target, aside)
    os.rename(new, target)
    remove_path(aside)


def exchange(a: Path, b: Path) -> bool:
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


def remove_path(path: Path) -> None:
    """Remove a file, a link or a whole folder; nothing if it is not there."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def tidy_beside(target: Path) -> None:
    """Clear what killed processes left beside ``target``: their temporary entries
    (:func:`temporary_folder`, :func:`atomic_output`) are removed, an old folder renamed
    aside is put back when nothing is at ``target`` (else removed)."""
    for kind in TEMPORARY_KINDS:
        remove_stale(target.parent, f".{target.name}.{kind}-")
    prefix = f".{target.name}.old-"
    for entry in target.parent.glob(f"{_glob_escape(prefix)}*"):
        pid = entry.name[len(prefix) :]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            if os.path.lexists(target):
                remove_path(entry)
            else:
                os.rename(entry, target)


def remove_stale(folder: Path, prefix: str) -> None:
    """Remove ``folder/PREFIX<pid>-…`` entries whose writing process ``<pid>`` is gone
    (what a killed process leaves behind); entries of running processes are kept."""
    if not folder.is_dir():
        return
    for entry in folder.glob(f"{_glob_escape(prefix)}*"):
        pid = entry.name[len(prefix) :].split("-", 1)[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            remove_path(entry)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def _glob_escape(text: str) -> str:
    """``text`` as a literal in a glob pattern."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)
