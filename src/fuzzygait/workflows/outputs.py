"""Output files of the workflows: their suffixes checked before any work, and
all of them written or none."""

from __future__ import annotations

import shutil
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Option
from fuzzygait.core.paths import DATASET_SUFFIXES, FIGURE_SUFFIXES

__all__ = ["check_output_suffixes", "write_all_or_none"]

#: A file to write: its path (None: not asked for) and the function that writes it.
Writer = tuple[Path | None, Callable[[Path], object]]


def check_output_suffixes(out_file: Path, rrd: Path | None, plots: Mapping[str, Path | None]) -> None:
    """One clear error, before any work (and before the imports of the libraries that
    write the files), for an output path with the wrong suffix (``plots`` maps the option
    name to its path)."""
    if out_file.suffix.lower() not in DATASET_SUFFIXES:
        raise FuzzyGaitError(f"{out_file}: {Option.OUT} must end in {' or '.join(DATASET_SUFFIXES)}")
    if rrd is not None and rrd.suffix.lower() != ".rrd":
        raise FuzzyGaitError(f"{rrd}: {Option.RRD} must end in .rrd")
    for option, plot in plots.items():
        if plot is not None and plot.suffix.lower().lstrip(".") not in FIGURE_SUFFIXES:
            raise FuzzyGaitError(f"{plot}: {option} must end in .png, .svg or .pdf")


def _remove_output(path: Path) -> None:
    """Remove a written file or folder (zarr stores are folders)."""
    if path.is_dir():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def write_all_or_none(writers: Sequence[Writer]) -> list[Path]:
    """Run ``writer(path)`` for every given path (folders created first); on any failure
    remove what was already written and re-raise: all outputs or none."""
    written: list[Path] = []
    try:
        for path, _ in writers:
            if path is not None:
                try:
                    path.parent.mkdir(parents=True, exist_ok=True)
                except OSError as exc:
                    raise FuzzyGaitError(f"{path}: cannot create its folder ({exc.strerror or exc})") from None
        for path, write in writers:
            if path is not None:
                write(path)
                written.append(path)
    except BaseException:
        for path in written:
            _remove_output(path)
        raise
    return written
