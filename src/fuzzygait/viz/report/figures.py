"""The report's figures: the gait-report grid (joints x planes) with fuzzy α-bands, over
the gait cycle and over the whole trial (written as PNG and SVG by
:mod:`fuzzygait.workflows.report_folder`; nothing here writes a file).

Where an α-level's band is undetermined (the segment frame can flip within its balls)
the band is not drawn; a hatched strip in the side's colour along the top of the panel
marks those points (darker where higher α-levels are undetermined too).  The y-limits
come from the measured curves and the determined bands only."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from fuzzygait.gait.cycles import percent_points  # noqa: E402
from fuzzygait.gait.normative import NormativeData  # noqa: E402
from fuzzygait.kinematics.labels import SIDE_NAMES  # noqa: E402
from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE  # noqa: E402
from fuzzygait.viz.report.bands import TrialData, alpha_text  # noqa: E402
from fuzzygait.viz.report.clinical import ClinicalData  # noqa: E402
from fuzzygait.viz.report.grid import ANGLE_GRID, GridMargins, place_grid  # noqa: E402
from fuzzygait.viz.report.normalised_bands import N_POINTS, band_undetermined, cycle_bands  # noqa: E402

__all__ = ["cycle_figure", "time_series_figure"]

#: Figure resolution (dots per inch) the figures are written at; 11 in wide -> 1100 px PNGs.
DPI = 100
FIG_SIZE = (11.0, 12.6)


def _band_opacity(n_levels: int) -> float:
    """Opacity of one band layer: the innermost band (all layers stacked) reaches ~0.4."""
    return min(0.25, 1.0 - 0.6 ** (1.0 / max(n_levels, 1)))


#: Height (axes fraction) of one side's undetermined strip at the top of a panel.
STRIP = 0.045
#: Hatching of the undetermined strips.
HATCH = "////"


#: Line style per side (greyscale: left solid, right dashed).
SIDE_LINE = {"L": "-", "R": "--"}
#: Hatching of the right side's α-bands, widest (α = 0) first; denser for higher α.
RIGHT_HATCHES = ("/", "//", "///", "////", "/////")
#: Line width (points) of hatching.
HATCH_WIDTH = 0.6
#: Normative band colour (grey, drawn below everything).
NORMATIVE_COLOUR = "0.82"


def _right_hatch(k: int) -> str:
    return RIGHT_HATCHES[min(k, len(RIGHT_HATCHES) - 1)]


def _blank() -> Artist:
    """An invisible legend entry (keeps the legend's columns one per group)."""
    return Patch(facecolor="none", edgecolor="none", label=" ")


def _legend_handles(alphas: np.ndarray, n_cycles: dict[str, int] | None,
                    undetermined: set[int] | None = None, extras: Sequence[Artist] = ()) -> list[Artist]:  # fmt: skip
    """Legend entries, one column per group (matplotlib fills legends column by column):
    per side a line (with its number of cycles) and one swatch per α-level in the side's
    style (left: filled in its colour, darker for higher α; right: hatched in its colour,
    denser for higher α), then ``extras`` (foot off, stride-to-stride SD, normative band)
    and one hatched patch per α-level (index) undetermined in some panel.  Use with
    :func:`legend_columns`."""
    handles: list[Artist] = []
    layer = _band_opacity(len(alphas))
    for side, (side_name, colour) in SIDE_STYLE.items():
        label = side_name
        if n_cycles is not None:
            n = n_cycles.get(side, 0)
            label += f" (mean of {n} cycle{'s' if n != 1 else ''})"
        group: list[Artist] = [Line2D([], [], color=colour, lw=1.6, ls=SIDE_LINE[side], label=label)]
        for k, alpha in enumerate(alphas):
            tag = " (worst case)" if k == 0 and alpha == 0 else ""
            text = f"{side_name} α = {alpha_text(alpha)}{tag}"
            if side == "L":
                opacity = 1.0 - (1.0 - layer) ** (k + 1)
                group.append(Patch(facecolor=to_rgba(colour, opacity), edgecolor=colour, lw=0.5, label=text))
            else:
                group.append(Patch(facecolor="white", edgecolor=colour, hatch=_right_hatch(k), lw=0.5, label=text))
        handles += group + [_blank() for _ in range(max(1 + len(alphas), 3) - len(group))]
    rest = list(extras)
    for n, k in enumerate(sorted(undetermined or ())):
        what = "undetermined: no band" if n == 0 else "undetermined too"
        rest.append(Patch(facecolor=(0.25, 0.25, 0.25, 1.0 - 0.75 * 0.7**n), edgecolor="0.3", hatch=HATCH,
                          lw=0, label=f"α = {alpha_text(alphas[k])} {what}"))  # fmt: skip
    rows = max(1 + len(alphas), 3)
    return handles + rest + [_blank() for _ in range(-len(rest) % rows)]


def legend_columns(handles: Sequence[Artist], n_alphas: int) -> int:
    """Columns of the legend of :func:`_legend_handles`: one per side (a line and its
    α-swatches), then the rest in columns of the same height."""
    rows = max(1 + n_alphas, 3)
    return max(1, -(-len(handles) // rows))


def _panel_grid(title: str, rows: Sequence[tuple[str, str]] = ANGLE_ROWS) -> tuple[Figure, np.ndarray]:
    """An empty joints x planes grid with axis labels and plane titles (``rows``: the
    joint rows, default :data:`~fuzzygait.viz.layout.ANGLE_ROWS`)."""
    height = FIG_SIZE[1] * (len(rows) + 0.6) / (len(ANGLE_ROWS) + 0.6)
    fig, axes = plt.subplots(len(rows), 3, figsize=(FIG_SIZE[0], height), sharex=True, squeeze=False)
    fig.suptitle(title, fontsize=13)
    for r, (_, row_title) in enumerate(rows):
        for c, (_, plane, meaning) in enumerate(PLANES):
            ax = axes[r, c]
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=8)
            label = meaning.get(row_title, "")
            ax.set_ylabel(f"{row_title} (deg)" + (f"\n+ {label}" if label else ""), fontsize=8)
            if r == 0:
                ax.set_title(plane, fontsize=11)
    return fig, axes


def _add_legend(fig: Figure, handles: list[Artist], ncol: int = 7, margins: GridMargins = ANGLE_GRID) -> Figure:
    """Add the legend above the grid and lay the figure out (room for its rows; the grid's
    ``margins`` in inches, :mod:`.grid`)."""
    ncol = min(len(handles), ncol)
    rows = -(-len(handles) // max(ncol, 1))
    height = fig.get_size_inches()[1]
    legend_top = 1.0 - 0.42 / height
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, legend_top),
               ncol=ncol, fontsize=8, frameon=False)  # fmt: skip
    place_grid(fig, legend_top - (0.16 * rows + 0.05) / height, margins)
    return fig


@dataclass(frozen=True)
class _BandStyle:
    """How one side's curve and α-bands are drawn: its ``colour``, the opacity of one
    filled band layer (``layer``, :func:`_band_opacity`), the ``side`` (``"L"`` filled
    and solid, ``"R"`` hatched and dashed) and whether the bands are ``rasterized`` (the
    whole-trial grid: thousands of frames)."""

    colour: str
    layer: float
    side: str = "L"
    rasterized: bool = False


def _draw_bands(ax: Axes, x: np.ndarray, curve: np.ndarray, alphas: np.ndarray, band: np.ndarray | None,
                style: _BandStyle) -> None:  # fmt: skip
    """α-bands (nested, widest first) in the side's style — left filled in its colour,
    right hatched in its colour (so overlapping bands never mix into a third colour and
    stay apart in greyscale) — the widest band's edges as thin lines, and the curve on top
    (left solid, right dashed).  NaN bounds (undetermined or missing) leave the band out
    there."""
    colour, rasterized = style.colour, style.rasterized
    line = SIDE_LINE.get(style.side, "-")
    if band is not None and len(alphas):
        for k in range(len(alphas)):
            if style.side == "R":
                hatched = ax.fill_between(x, band[k, 0], band[k, 1], facecolor="none", edgecolor=colour,
                                          hatch=_right_hatch(k), lw=0, rasterized=rasterized)  # fmt: skip
                hatched.set_hatch_linewidth(HATCH_WIDTH)
            else:
                ax.fill_between(x, band[k, 0], band[k, 1], color=colour, alpha=style.layer, lw=0,
                                rasterized=rasterized)  # fmt: skip
        for bound in (0, 1):
            ax.plot(x, band[0, bound], color=colour, lw=0.6, ls=line, alpha=0.9, rasterized=rasterized)
    ax.plot(x, curve, color=colour, lw=1.5, ls=line)


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


def time_limits(t: np.ndarray) -> tuple[float, float]:
    """x-axis limits (s) of a whole-trial plot: the first and last sample, widened by
    5 ms each way for a trial of one frame (matplotlib refuses equal limits)."""
    lo, hi = float(t[0]), float(t[-1])
    return (lo - 0.005, hi + 0.005) if hi <= lo else (lo, hi)


def _not_computed(ax: Axes, text: str = "not computed") -> None:
    """A grey note in the middle of an empty panel."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize=8, color="0.45")  # fmt: skip



def _normative(ax: Axes, x: np.ndarray, clinical: ClinicalData | None, base: str, axis: str) -> bool:
    """:func:`draw_normative` of the angle component ``base``/``axis``."""
    return draw_normative(ax, x, None if clinical is None else clinical.normative, f"{base}_{axis}")


def draw_normative(ax: Axes, x: np.ndarray, normative: NormativeData | None, variable: str) -> bool:
    """The normative mean ± 1 SD band of ``variable`` (named without side, e.g.
    ``KneeAngles_X``; grey, below everything) over ``x`` (% gait cycle); per side when the
    file has sided curves (drawn once when both sides share the pooled one). Whether a
    band was drawn."""
    if normative is None:
        return False
    drawn: list[int] = []
    for side in SIDE_STYLE:
        found = normative.curve(side + variable)
        if found is None or id(found) in drawn:
            continue
        drawn.append(id(found))
        mean, sd = found
        ax.fill_between(x, mean - sd, mean + sd, color=NORMATIVE_COLOUR, lw=0, zorder=0)
        ax.plot(x, mean, color="0.6", lw=0.8, zorder=0.5)
    return bool(drawn)


def _stride_sd(ax: Axes, x: np.ndarray, clinical: ClinicalData | None, name: str, colour: str) -> bool:
    """Mean ± 1 SD over the side's cycles as thin dotted lines in the side's colour."""
    if clinical is None or name not in clinical.curves:
        return False
    mean, sd = clinical.curves[name]
    if not np.isfinite(sd).any():
        return False
    for sign in (-1.0, 1.0):
        ax.plot(x, mean + sign * sd, color=colour, lw=0.9, ls=":", zorder=2.5)
    return True


def foot_off_lines(ax: Axes, clinical: ClinicalData | None) -> None:
    """A vertical line at each side's mean Foot Off (% of the cycle) in its colour and
    line style."""
    if clinical is None:
        return
    for side, percent in clinical.foot_off.items():
        colour = SIDE_STYLE[side][1]
        ax.axvline(percent, color=colour, lw=1.0, ls=SIDE_LINE[side], alpha=0.85, zorder=1)


def clinical_handles(clinical: ClinicalData | None, sd: bool, normative: bool) -> list[Artist]:
    """Legend entries of foot off, stride-to-stride SD and the normative band."""
    if clinical is None:
        return []
    handles: list[Artist] = []
    if clinical.foot_off:
        handles.append(Line2D([], [], color="0.2", lw=1.0, ls="-", label="foot off (vertical, per side)"))
    if sd:
        handles.append(Line2D([], [], color="0.2", lw=0.9, ls=":", label="mean ± 1 SD over cycles"))
    if normative and clinical.normative is not None:
        handles.append(Patch(facecolor=NORMATIVE_COLOUR, edgecolor="0.6", lw=0.5, label="normative mean ± 1 SD"))
    return handles


def cycle_figure(data: TrialData, title: str, clinical: ClinicalData | None = None) -> Figure:
    """The gait-report grid (joints x planes) over the gait cycle with α-bands (and, with
    ``clinical``, foot-off lines, stride-to-stride SD and the normative band).  Axes
    ``fig.axes``: row-major, rows as :func:`~fuzzygait.viz.report.clinical.grid_rows` (the
    forefoot last with CGM 2.4), columns sagittal, frontal, transverse."""
    x = percent_points(N_POINTS)
    layer = _band_opacity(len(data.alphas))
    rows = clinical.rows if clinical is not None and clinical.rows else list(ANGLE_ROWS)
    fig, axes = _panel_grid(title, rows)
    seen: set[int] = set()
    any_sd = any_norm = False
    for r, (base, _) in enumerate(rows):
        for c, (axis, _, _) in enumerate(PLANES):
            ax = axes[r, c]
            drawn, banded, notes, uncut = False, False, [], False
            strips: list[tuple[int, str, np.ndarray]] = []
            any_norm = _normative(ax, x, clinical, base, axis) or any_norm
            foot_off_lines(ax, clinical)
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
                _draw_bands(ax, x, curve, data.alphas, band, _BandStyle(colour, layer, side))
                any_sd = _stride_sd(ax, x, clinical, name, colour) or any_sd
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
            elif not banded and len(data.alphas):
                notes.append("no bands (not analysed)")
            _draw_undetermined(ax, x, strips)
            if notes:
                ax.text(0.01, 0.02, "; ".join(notes), transform=ax.transAxes, fontsize=6.5,
                        color="0.3", va="bottom")  # fmt: skip
            ax.set_xlim(0, 100)
            if r == len(rows) - 1:
                ax.set_xlabel("gait cycle (%)  [0 and 100 % = foot strike]", fontsize=8)
    handles = _legend_handles(data.alphas, data.n_cycles(), seen, clinical_handles(clinical, any_sd, any_norm))
    return _add_legend(fig, handles, legend_columns(handles, len(data.alphas)))


def time_series_figure(data: TrialData, title: str, clinical: ClinicalData | None = None) -> Figure:
    """The whole trial with α-bands (joints x planes, time in s; bands rasterised in an
    SVG) and foot strikes as dotted lines (axes as :func:`cycle_figure`)."""
    trial = data.run.trial
    t = trial.times
    layer = _band_opacity(len(data.alphas))
    rows = clinical.rows if clinical is not None and clinical.rows else list(ANGLE_ROWS)
    fig, axes = _panel_grid(title, rows)
    strikes = {side: [e.time for e in data.run.events
                      if e.label == "Foot Strike" and e.context == SIDE_NAMES[side]]
               for side in SIDE_STYLE}  # fmt: skip
    seen: set[int] = set()
    for r, (base, _) in enumerate(rows):
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
                _draw_bands(ax, t, signal, data.alphas, data.determined_hull(name),
                            _BandStyle(colour, layer, side, rasterized=True))  # fmt: skip
                drawn = True
                flags = data.undetermined(name)
                if flags is not None and flags.any():
                    flags = flags & np.isfinite(signal)[None, :]
                    strips.append((slot, colour, flags))
                    seen.update(int(k) for k in np.flatnonzero(flags.any(axis=1)))
            if not drawn:
                _not_computed(ax)
            _draw_undetermined(ax, t, strips)
            ax.set_xlim(*time_limits(t))
            if r == len(rows) - 1:
                ax.set_xlabel("time (s)   [dotted lines: foot strikes]", fontsize=8)
    handles = _legend_handles(data.alphas, None, seen)
    return _add_legend(fig, handles, legend_columns(handles, len(data.alphas)))
