"""Matplotlib figures for clinicians: gait-cycle-normalised joint angles (built here,
written by :func:`fuzzygait.io.figure_files.save_figure`)."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE  # noqa: E402


def gait_cycles_figure(
    stats: pd.DataFrame,
    *,
    title: str = "",
    rows: Sequence[tuple[str, str]] = ANGLE_ROWS,
) -> Figure:
    """The classic gait-report grid (joints x planes; mean ± 1 SD per side); write it
    with :func:`fuzzygait.io.figure_files.save_figure` (PNG, SVG or PDF by suffix).

    Args:
        stats: output of :func:`fuzzygait.gait.cycles.mean_sd_table` (columns
            ``angle`` like ``LKneeAngles_X``, ``percent``, ``mean``, ``sd``,
            ``n_cycles``); degrees.
        title: figure title.
        rows: which angles to show.

    Returns:
        The figure.
    """
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
    return fig
