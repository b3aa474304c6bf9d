"""Matplotlib figures for clinicians: gait-cycle-normalised joint angles."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from fuzzygait.core.errors import FuzzyGaitError, ParameterError  # noqa: E402
from fuzzygait.io.atomic import atomic_output  # noqa: E402
from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE  # noqa: E402


def plot_gait_cycles(
    stats: pd.DataFrame,
    path: str | os.PathLike[str],
    *,
    title: str = "",
    rows: Sequence[tuple[str, str]] = ANGLE_ROWS,
) -> Path:
    """Write the classic gait-report grid (joints x planes; mean ± 1 SD per side).

    Args:
        stats: output of :func:`fuzzygait.gait.cycles.mean_sd_table` (columns
            ``angle`` like ``LKneeAngles_X``, ``percent``, ``mean``, ``sd``,
            ``n_cycles``); degrees.
        path: PNG, SVG or PDF file, by suffix.
        title: figure title.
        rows: which angles to show.

    Returns:
        The written path.
    """
    path = Path(path)
    fig, axes = plt.subplots(len(rows), 3, figsize=(11, 2.3 * len(rows) + 0.8), sharex=True, squeeze=False)
    for r, (angle, row_title) in enumerate(rows):
        for c, (axis, plane, meaning) in enumerate(PLANES):
            ax = axes[r, c]
            for side, (side_name, colour) in SIDE_STYLE.items():
                sel = stats[stats["angle"] == f"{side}{angle}_{axis}"].sort_values("percent")
                if sel.empty or sel["mean"].isna().all():
                    continue
                n = int(sel["n_cycles"].max())
                ax.plot(sel["percent"], sel["mean"], color=colour, lw=1.5, label=f"{side_name} (n={n})")
                ax.fill_between(
                    sel["percent"], sel["mean"] - sel["sd"], sel["mean"] + sel["sd"],
                    color=colour, alpha=0.2, lw=0,
                )  # fmt: skip
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.grid(alpha=0.3)
            label = meaning[row_title]
            ax.set_ylabel(f"{row_title} (deg)" + (f"\n+ {label}" if label else ""), fontsize=8)
            if r == 0:
                ax.set_title(plane)
            if r == len(rows) - 1:
                ax.set_xlabel("gait cycle (%)")
            ax.set_xlim(0, 100)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="upper right", fontsize=8)
    fig.suptitle(title or "Joint angles over the gait cycle (mean ± 1 SD)")
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    return save_figure(fig, path)


FIGURE_SUFFIXES = ("png", "svg", "pdf")


def save_figure(fig, path: str | os.PathLike[str], dpi: int = 110) -> Path:
    """Write ``fig`` atomically as PNG, SVG or PDF (by the suffix of ``path``) and close it.

    Raises :class:`ParameterError` for another suffix and :class:`FuzzyGaitError` naming
    ``path`` when it cannot be written; nothing is left at ``path`` then.
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
        plt.close(fig)
    return path
