"""Atomic file output: a result file appears complete or not at all."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError


@contextmanager
def atomic_output(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; move it onto ``path`` on success.

    The temporary file keeps ``path``'s suffix (some writers insist on it). On any
    exception it is removed and nothing is left at ``path``.

    Raises:
        FuzzyGaitError: when the folder of ``path`` does not exist.
    """
    path = Path(path)
    if not path.parent.exists():
        raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=f".tmp{path.suffix}", dir=path.parent)
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


def replace_path(new: Path, target: Path) -> None:
    """Move ``new`` onto ``target`` (a file or a folder), replacing it: a folder is renamed
    aside first and removed after the move, so ``target`` is never half-written."""
    if target.is_dir() and not target.is_symlink():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.rename(target, old)
        os.rename(new, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(new, target)
