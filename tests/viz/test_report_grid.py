"""The report grids' fixed layout (viz/report/grid.py): with the widest labels a page
meets (three-digit negative ticks, two-line y-labels), no panel's labels reach into its
neighbour's or off the figure, and the legend stays clear of the panels — measured with
the renderer, the check tight_layout used to make on every page."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.viz.report.figures import _add_legend, _panel_grid, plt
from fuzzygait.viz.report.grid import place_grid


def _boxes(fig):
    renderer = fig.canvas.get_renderer()
    return renderer, [ax.get_tightbbox(renderer) for ax in fig.axes]


def _overlap(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


@pytest.mark.parametrize("span", [(-180.0, 180.0), (-0.25, 1.25), (0.0, 9.0)])
def test_angle_grid_labels_stay_apart_and_inside(span):
    fig, axes = _panel_grid("a title as long as a trial's: walk01.c3d: joint angles (mean over gait cycles)")
    x = np.linspace(0, 100, 101)
    for ax in axes.flat:
        ax.plot(x, np.linspace(*span, x.size))
    axes[-1, 0].set_xlabel("gait cycle (%)  [0 and 100 % = foot strike]", fontsize=8)
    handles = [plt.Line2D([], [], label=f"entry {k}") for k in range(9)]
    _add_legend(fig, handles, ncol=3)
    renderer, boxes = _boxes(fig)
    width, height = fig.bbox.width, fig.bbox.height
    for i, box in enumerate(boxes):
        assert box.x0 >= 0 and box.y0 >= 0 and box.x1 <= width and box.y1 <= height, (i, box)
        for j in range(i + 1, len(boxes)):
            assert not _overlap(box, boxes[j]), (i, j)
    legend = fig.legends[0].get_window_extent(renderer)
    assert not any(_overlap(legend, box) for box in boxes)
    plt.close(fig)


def test_a_grid_without_room_is_refused():
    fig, _ = plt.subplots(5, 3, figsize=(2.0, 2.0))
    with pytest.raises(ValueError, match="no room for a 5 x 3 grid"):
        place_grid(fig, 0.9)
    plt.close(fig)
