"""The report's figures: the gait-report grid (joints x planes) with fuzzy α-bands, over
the gait cycle and over the whole trial, as PNG and SVG.

Where an α-level's band is undetermined (the segment frame can flip within its balls)
the band is not drawn; a hatched strip in the side's colour along the top of the panel
marks those points (darker where higher α-levels are undetermined too).  The y-limits
come from the measured curves and the determined bands only."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from fuzzygait.gait.cycles import percent_points  # noqa: E402
from fuzzygait.kinematics.labels import SIDE_NAMES  # noqa: E402
from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE  # noqa: E402
from fuzzygait.viz.report.bands import (  # noqa: E402
    N_POINTS,
    TrialData,
    alpha_text,
    band_undetermined,
    cycle_bands,
)

__all__ = ["cycle_figure", "plot_cycle_bands", "plot_time_series", "time_series_figure"]

#: Figure resolution; the figures are 11 in wide -> 1100 px PNGs.
DPI = 100
FIG_SIZE = (11.0, 12.6)


def _band_opacity(n_levels: int) -> float:
    """Opacity of one band layer: the innermost band (all layers stacked) reaches ~0.4."""
    return min(0.25, 1.0 - 0.6 ** (1.0 / max(n_levels, 1)))


#: Height (axes fraction) of one side's undetermined strip at the top of a panel.
STRIP = 0.045
#: Hatching of the undetermined strips.
HATCH = "////"


def _legend_handles(alphas: np.ndarray, n_cycles: dict[str, int] | None,
                    undetermined: set[int] | None = None) -> list[Artist]:  # fmt: skip
    """Legend entries: one line per side (with its number of cycles), one patch per
    α-level, and one hatched patch per α-level (index) undetermined in some panel."""
    handles: list[Artist] = []
    for side, (side_name, colour) in SIDE_STYLE.items():
        label = side_name
        if n_cycles is not None:
            n = n_cycles.get(side, 0)
            label += f" (mean of {n} cycle{'s' if n != 1 else ''})"
        handles.append(Line2D([], [], color=colour, lw=1.6, label=label))
    layer = _band_opacity(len(alphas))
    for k, alpha in enumerate(alphas):
        opacity = 1.0 - (1.0 - layer) ** (k + 1)
        tag = " worst case" if k == 0 and alpha == 0 else ""
        edge: dict[str, Any] = {"edgecolor": "0.25", "lw": 0.5} if k == 0 else {"lw": 0}
        handles.append(Patch(facecolor=(0.25, 0.25, 0.25, opacity), label=f"α = {alpha_text(alpha)}{tag}", **edge))
    for n, k in enumerate(sorted(undetermined or ())):
        what = "undetermined: no band" if n == 0 else "undetermined too"
        handles.append(Patch(facecolor=(0.25, 0.25, 0.25, 1.0 - 0.75 * 0.7**n), edgecolor="0.3", hatch=HATCH,
                             lw=0, label=f"α = {alpha_text(alphas[k])} {what}"))  # fmt: skip
    return handles


def _panel_grid(title: str) -> tuple[Figure, np.ndarray]:
    """An empty joints x planes grid with axis labels and plane titles."""
    fig, axes = plt.subplots(len(ANGLE_ROWS), 3, figsize=FIG_SIZE, sharex=True, squeeze=False)
    fig.suptitle(title, fontsize=13)
    for r, (_, row_title) in enumerate(ANGLE_ROWS):
        for c, (_, plane, meaning) in enumerate(PLANES):
            ax = axes[r, c]
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=8)
            label = meaning[row_title]
            ax.set_ylabel(f"{row_title} (deg)" + (f"\n+ {label}" if label else ""), fontsize=8)
            if r == 0:
                ax.set_title(plane, fontsize=11)
    return fig, axes


def _add_legend(fig: Figure, handles: list[Artist]) -> Figure:
    """Add the legend above the grid and lay the figure out."""
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.968),
               ncol=min(len(handles), 7), fontsize=8.5, frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.945))
    return fig


def _save(fig: Figure, stem: Path) -> None:
    """Write ``stem.png`` and ``stem.svg`` and close the figure."""
    try:
        for suffix in ("png", "svg"):
            fig.savefig(stem.with_suffix(f".{suffix}"), dpi=DPI, format=suffix)
    finally:
        plt.close(fig)


def _draw_bands(ax: Axes, x: np.ndarray, curve: np.ndarray, alphas: np.ndarray, band: np.ndarray | None,
                colour: str, layer: float, rasterized: bool = False) -> None:  # fmt: skip
    """α-bands (nested, widest first) in the side's colour, the widest band's edges as
    thin lines (so overlapping left/right bands stay apart), and the curve on top.  NaN
    bounds (undetermined or missing) leave the band out there."""
    if band is not None and len(alphas):
        for k in range(len(alphas)):
            ax.fill_between(x, band[k, 0], band[k, 1], color=colour, alpha=layer, lw=0,
                            rasterized=rasterized)  # fmt: skip
        for bound in (0, 1):
            ax.plot(x, band[0, bound], color=colour, lw=0.5, alpha=0.8, rasterized=rasterized)
    ax.plot(x, curve, color=colour, lw=1.4)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[(first, last), ...]`` index runs where ``mask`` holds."""
    padded = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    edges = np.flatnonzero(np.diff(padded.astype(np.int8)))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _draw_undetermined(ax: Axes, x: np.ndarray, strips: list[tuple[int, str, np.ndarray]],
                       n_slots: int = len(SIDE_STYLE)) -> None:  # fmt: skip
    """Hatched strips along the top of the panel, one per side (``slot`` 0, 1, ... of
    ``n_slots``), where ``mask (n_alpha, n_points)`` is undetermined; each α-level adds a
    layer, so the strip is darker where higher α-levels are undetermined too.  The
    y-limits are frozen first (with headroom for the strips): the strips never stretch the
    axis."""
    if not strips:
        return
    ax.autoscale_view()
    bottom, top = ax.get_ylim()
    ax.set_ylim(bottom, top + (top - bottom) * (n_slots * STRIP + 0.02) / (1.0 - n_slots * STRIP))
    step = float(np.median(np.diff(x))) if x.size > 1 else 1.0
    half = max(step / 2, 0.004 * float(x[-1] - x[0]))  # a single frame stays visible
    for slot, colour, mask in strips:
        high, low = 1.0 - slot * STRIP, 1.0 - (slot + 1) * STRIP + 0.006
        for k in range(mask.shape[0]):
            for first, last in _runs(mask[k]):
                ax.axvspan(x[first] - half, x[last] + half, ymin=low, ymax=high, facecolor=colour,
                           alpha=0.25 if k == 0 else 0.3, edgecolor=colour, hatch=HATCH, lw=0)  # fmt: skip


def _not_computed(ax: Axes, text: str = "not computed") -> None:
    """A grey note in the middle of an empty panel."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize=8, color="0.45")  # fmt: skip



def plot_cycle_bands(data: TrialData, stem: Path, title: str) -> dict[str, int]:
    """The gait-report grid (joints x planes) over the gait cycle with α-bands; writes
    ``stem.png`` and ``stem.svg``.  Returns the number of cycles per side."""
    _save(cycle_figure(data, title), stem)
    return data.n_cycles()


def plot_time_series(data: TrialData, stem: Path, title: str) -> None:
    """The whole trial with α-bands (joints x planes, time in s) and foot strikes as
    dotted lines; writes ``stem.png`` and ``stem.svg`` (bands rasterised in the SVG)."""
    _save(time_series_figure(data, title), stem)


def cycle_figure(data: TrialData, title: str) -> Figure:
    """The gait-cycle grid of :func:`plot_cycle_bands` (axes ``fig.axes``: row-major,
    rows as :data:`~fuzzygait.viz.layout.ANGLE_ROWS`, columns sagittal, frontal,
    transverse)."""
    x = percent_points(N_POINTS)
    layer = _band_opacity(len(data.alphas))
    fig, axes = _panel_grid(title)
    seen: set[int] = set()
    for r, (base, _) in enumerate(ANGLE_ROWS):
        for c, (axis, _, _) in enumerate(PLANES):
            ax = axes[r, c]
            drawn, banded, notes, uncut = False, False, [], False
            strips: list[tuple[int, str, np.ndarray]] = []
            for slot, (side, (_, colour)) in enumerate(SIDE_STYLE.items()):
                name = f"{side}{base}_{axis}"
                signal = data.angle(name)
                cycles = data.cycles[side]
                uncut = uncut or (signal is not None and not cycles)
                if signal is None:
                    notes.append(f"{side}: not computed")
                if signal is None or not cycles:
                    continue
                hull = data.hull(name)
                if hull is None:  # not analysed: the mean curve alone
                    curve, _, used = cycle_bands(signal, np.empty((0, 2, signal.size)), cycles)
                    band = None
                else:
                    curve, band, used = cycle_bands(signal, hull, cycles, undetermined=data.undetermined(name))
                if not np.isfinite(curve).any():
                    continue
                _draw_bands(ax, x, curve, data.alphas, band, colour, layer)
                flags = band_undetermined(curve, band)
                if flags is not None and flags.any():
                    strips.append((slot, colour, flags))
                    seen.update(int(k) for k in np.flatnonzero(flags.any(axis=1)))
                drawn, banded = True, banded or band is not None
                if used < len(cycles):
                    notes.append(f"{side}: {used} of {len(cycles)} cycles")
            if not drawn:
                _not_computed(ax, "no gait cycles (see the whole trial)" if uncut else "not computed")
                notes = []
            elif not banded:
                notes.append("no bands (not analysed)")
            _draw_undetermined(ax, x, strips)
            if notes:
                ax.text(0.01, 0.02, "; ".join(notes), transform=ax.transAxes, fontsize=6.5,
                        color="0.3", va="bottom")  # fmt: skip
            ax.set_xlim(0, 100)
            if r == len(ANGLE_ROWS) - 1:
                ax.set_xlabel("gait cycle (%)  [0 and 100 % = foot strike]", fontsize=8)
    return _add_legend(fig, _legend_handles(data.alphas, data.n_cycles(), seen))


def time_series_figure(data: TrialData, title: str) -> Figure:
    """The whole-trial grid of :func:`plot_time_series` (axes as :func:`cycle_figure`)."""
    trial = data.run.trial
    t = trial.times
    layer = _band_opacity(len(data.alphas))
    fig, axes = _panel_grid(title)
    strikes = {side: [e.time for e in data.run.events
                      if e.label == "Foot Strike" and e.context == SIDE_NAMES[side]]
               for side in SIDE_STYLE}  # fmt: skip
    seen: set[int] = set()
    for r, (base, _) in enumerate(ANGLE_ROWS):
        for c, (axis, _, _) in enumerate(PLANES):
            ax = axes[r, c]
            drawn = False
            strips: list[tuple[int, str, np.ndarray]] = []
            for slot, (side, (_, colour)) in enumerate(SIDE_STYLE.items()):
                for when in strikes[side]:
                    ax.axvline(when, color=colour, lw=0.7, ls=":", alpha=0.7)
                name = f"{side}{base}_{axis}"
                signal = data.angle(name)
                if signal is None:
                    continue
                _draw_bands(ax, t, signal, data.alphas, data.determined_hull(name), colour, layer, rasterized=True)
                drawn = True
                flags = data.undetermined(name)
                if flags is not None and flags.any():
                    flags = flags & np.isfinite(signal)[None, :]
                    strips.append((slot, colour, flags))
                    seen.update(int(k) for k in np.flatnonzero(flags.any(axis=1)))
            if not drawn:
                _not_computed(ax)
            _draw_undetermined(ax, t, strips)
            ax.set_xlim(t[0], t[-1])
            if r == len(ANGLE_ROWS) - 1:
                ax.set_xlabel("time (s)   [dotted lines: foot strikes]", fontsize=8)
    return _add_legend(fig, _legend_handles(data.alphas, None, seen))

