"""Fixed layout of the report's subplot grids (joints x planes).

``Figure.tight_layout`` measures every tick label and axis title of the grid, which costs
as much as drawing the figure once more (without it an angles-only report takes half the
time: ``benchmarks/report_figures.py``).  The
report grids have the same labels on every page, so their margins and gaps are fixed here
in inches instead — the values ``tight_layout`` gave on the report figures (the widest of
the sample and Vicon trials, rounded up), so the pages look as they did.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class GridMargins:
    """Margins and gaps of a subplot grid, in inches.

    ``titles`` is the room above the top row (plane titles and padding) below the area the
    caller keeps free for the suptitle and the legend; ``wgap`` / ``hgap`` the gaps between
    columns (room for the next column's y-label and tick labels) and rows."""

    left: float = 0.9
    right: float = 0.26
    bottom: float = 0.55
    titles: float = 0.68
    wgap: float = 0.93
    hgap: float = 0.24


#: The joint-angle grids: cycles, time series, per-source figure.
ANGLE_GRID = GridMargins()
#: The kinetics grid (moment and power labels are longer, two lines each).
KINETICS_GRID = GridMargins(wgap=1.4, hgap=0.2)
#: The per-source figure (a row of tick labels under every panel).
SOURCES_GRID = GridMargins(wgap=0.85, hgap=0.55)
#: The session page's grid (one-line y-labels, only in the first column).
SESSION_GRID = GridMargins(left=0.78, right=0.2, titles=0.65, wgap=0.55, hgap=0.24)


def place_grid(fig: Figure, top: float, margins: GridMargins = ANGLE_GRID) -> None:
    """Lay ``fig``'s subplot grid out below ``top`` (figure fraction, 0-1: what is above is
    the suptitle's and legend's) with ``margins`` (inches)."""
    width, height = (float(v) for v in fig.get_size_inches())
    spec = fig.axes[0].get_subplotspec()
    if spec is None:
        raise ValueError("place_grid needs a figure of subplots")
    rows, cols = spec.get_gridspec().get_geometry()
    top_in = (1.0 - top) * height + margins.titles
    axis_width = (width - margins.left - margins.right - (cols - 1) * margins.wgap) / cols
    axis_height = (height - top_in - margins.bottom - (rows - 1) * margins.hgap) / rows
    if axis_width <= 0 or axis_height <= 0:
        raise ValueError(f"a {width:g} x {height:g} in figure has no room for a {rows} x {cols} grid")
    fig.subplots_adjust(left=margins.left / width, right=1.0 - margins.right / width, bottom=margins.bottom / height,
                        top=1.0 - top_in / height, wspace=margins.wgap / axis_width,
                        hspace=margins.hgap / axis_height)  # fmt: skip
