"""Figure files: any object with a matplotlib-style ``savefig(fname, *, dpi, format)``
written to disk, and closed afterwards.

The figures themselves are built by :mod:`fuzzygait.viz` (which writes nothing); this
module only writes them: :func:`save_figure` one file atomically (a result the user
named), :func:`save_figure_files` the same figure in several formats side by side (the
report's ``stem.png`` / ``stem.svg``, written into a staging folder that is moved into
place as a whole).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.paths import FIGURE_SUFFIXES
from fuzzygait.io.atomic import atomic_output

__all__ = ["FIGURE_SUFFIXES", "SavableFigure", "save_figure", "save_figure_files"]


class SavableFigure(Protocol):
    """What a figure must offer to be written: ``savefig`` as matplotlib's
    :class:`~matplotlib.figure.Figure` has it."""

    def savefig(self, fname: str | os.PathLike[str], *, dpi: float, format: str) -> None:  # noqa: A002
        """Write the figure to ``fname`` in ``format`` at ``dpi`` dots per inch."""


def _close(fig: object) -> None:
    """Release ``fig`` from pyplot's figure manager.  A figure made through pyplot means
    pyplot is imported already; without it there is nothing to release (and importing it
    here could pick a display backend)."""
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close(fig)


def save_figure(fig: SavableFigure, path: str | os.PathLike[str], dpi: int = 110) -> Path:
    """Write ``fig`` atomically as PNG, SVG or PDF (by the suffix of ``path``) and close it.

    Args:
        fig: the figure (e.g. from :mod:`fuzzygait.viz`).
        path: the file; its folder must exist.  A temporary file beside it is renamed
            onto it once complete.
        dpi: resolution of a PNG, dots per inch.

    Returns:
        ``path``.

    Raises:
        ParameterError: another suffix than :data:`FIGURE_SUFFIXES`.
        FuzzyGaitError: ``path`` cannot be written (names it); nothing is left at
            ``path`` then.
    """
    path = Path(path)
    kind = path.suffix.lower().lstrip(".")
    try:
        if kind not in FIGURE_SUFFIXES:
            raise ParameterError(f"{path}: a plot must end in .png, .svg or .pdf")
        with atomic_output(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=kind)
    except OSError as exc:
        raise FuzzyGaitError(f"{path}: cannot write the plot ({exc.strerror or exc})") from exc
    finally:
        _close(fig)
    return path


def save_figure_files(fig: SavableFigure, stem: Path, suffixes: Sequence[str] = ("png", "svg"), *,
                      dpi: int) -> list[Path]:  # fmt: skip
    """Write ``fig`` as ``stem.<suffix>`` for every suffix (its format), ``dpi`` dots per
    inch, and close it (also when writing fails).  Not atomic: meant for a staging folder
    that is moved into place whole.  Returns the files written."""
    written = []
    try:
        for suffix in suffixes:
            path = stem.with_suffix(f".{suffix}")
            fig.savefig(path, dpi=dpi, format=suffix)
            written.append(path)
    finally:
        _close(fig)
    return written
