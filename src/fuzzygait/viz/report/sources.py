"""The report's per-source part (thesis Fig. 5.9, "effect of the individual uncertainty
sources on the flexion angles"): per joint (hip, knee, ankle) and side the measured
flexion angle with the α = 0 band of each error source alone — measurement system, marker
placement, soft-tissue artefact — and of all together, over the gait cycle (over time for
a side without gait cycles), and the table "widest α = 0 band per source" naming the
source that dominates.

The bands are read from the result's per-source bands (``result.sources``,
:mod:`fuzzygait.markererror.per_source`); undetermined points are drawn as in the other
figures (:mod:`~fuzzygait.viz.report.figures`): no band, a hatched strip in the band's
colour along the top of the panel, the y-limits from the curve and the determined bands
only.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from fuzzygait.gait.cycles import percent_points
from fuzzygait.kinematics.labels import PLANES, SIDE_NAMES, component_label
from fuzzygait.markererror.per_source import (
    ALL,
    SourceWidths,
    has_source_bands,
    source_components,
    source_hull,
    source_names,
    source_title,
    source_undetermined,
    widest_source_bands,
)
from fuzzygait.markererror.result import MarkerErrorResult
from fuzzygait.viz.report.bands import TrialData, alpha_text
from fuzzygait.viz.report.clinical_html import footnote
from fuzzygait.viz.report.figures import HATCH, _draw_undetermined, _not_computed, plt, time_limits
from fuzzygait.viz.report.grid import SOURCES_GRID, place_grid
from fuzzygait.viz.report.markup import escape, html_table
from fuzzygait.viz.report.normalised_bands import N_POINTS, band_undetermined, cycle_bands

__all__ = ["SOURCE_STYLE", "source_figure", "sources_section"]

#: Band colour per source (:data:`~fuzzygait.markererror.per_source.ALL`: all together).
SOURCE_STYLE = {"measurement": "tab:blue", "placement": "tab:orange", "sta": "tab:purple", ALL: "0.55"}
#: The joints of the figure: (angle name without side, row title).
JOINTS = (("HipAngles", "Hip"), ("KneeAngles", "Knee"), ("AnkleAngles", "Ankle"))
FIG_SIZE = (11.0, 9.6)
_MEANING = PLANES[0][2]  # sagittal: row title -> positive direction


def _colour(source: str) -> str:
    return SOURCE_STYLE.get(source, "tab:brown")


def _tint(source: str, strength: float = 0.4) -> tuple[float, float, float]:
    """The source's colour mixed with white: the opaque fill of its band (so the ring a
    band adds around the narrower ones drawn on top of it shows its own colour)."""
    red, green, blue = to_rgb(_colour(source))
    return (1 - strength + strength * red, 1 - strength + strength * green, 1 - strength + strength * blue)


def _order(result: MarkerErrorResult) -> list[str]:
    """Sources drawn widest first: all together, then the sources alone by their mean
    widest band (the fills are opaque: each narrower band is drawn over the wider ones)."""
    widths = widest_source_bands(result)

    def mean_width(source: str) -> float:
        values = widths.widths[source].to_numpy(dtype=float)
        return float(np.nanmean(values)) if np.isfinite(values).any() else math.inf

    return [ALL, *sorted(source_names(result), key=mean_width, reverse=True)]


def _band(data: TrialData, source: str, component: str) -> tuple[np.ndarray, np.ndarray]:
    """α = 0 (the smallest per-source level) hull ``(1, 2, n_frames)`` deg and undetermined
    mask ``(1, n_frames)`` of ``component`` with ``source`` on the trial's frames."""
    frames = np.asarray(data.run.trial.frames)
    assert data.result is not None
    hull = source_hull(data.result, source, component).isel(alpha=[0]).reindex(frame=frames)
    flags = source_undetermined(data.result, source, component).isel(alpha=[0])
    flags = flags.reindex(frame=frames, fill_value=False)
    values = hull.sel(bound=["lower", "upper"]).transpose("alpha", "bound", "frame").to_numpy().astype(float)
    return values, flags.transpose("alpha", "frame").to_numpy().astype(bool)


def source_figure(data: TrialData, title: str) -> Figure:
    """The per-source grid: rows hip, knee, ankle flexion; columns left, right (axes
    ``fig.axes`` row-major)."""
    result = data.result
    assert result is not None and result.sources is not None, "the per-source figure needs per-source bands"
    order = _order(result)
    analysed = set(source_components(result))
    alpha = float(result.sources["alpha"].to_numpy().min())
    fig, axes = plt.subplots(len(JOINTS), 2, figsize=FIG_SIZE, squeeze=False)
    fig.suptitle(title, fontsize=13)
    hatched = False
    for r, (base, row_title) in enumerate(JOINTS):
        for c, side in enumerate("LR"):
            ax = axes[r, c]
            ax.axhline(0.0, color="0.6", lw=0.6)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=8)
            ax.set_ylabel(f"{row_title} (deg)\n+ {_MEANING[row_title]}", fontsize=8)
            if r == 0:
                ax.set_title(SIDE_NAMES[side], fontsize=11)
            name = f"{side}{base}_X"
            signal = data.angle(name)
            cycles = data.cycles[side]
            if signal is None or name not in analysed:
                _not_computed(ax, "not computed" if signal is None else "not analysed per source")
                ax.set_xlabel("gait cycle (%)", fontsize=8)
                continue
            strips: list[tuple[int, str, np.ndarray]] = []
            curve: np.ndarray | None = None
            drawn: dict[str, np.ndarray] = {}
            x = percent_points(N_POINTS) if cycles else np.asarray(data.run.trial.times, dtype=float)
            for slot, source in enumerate(order):
                hull, mask = _band(data, source, name)
                if cycles:
                    curve, band, _ = cycle_bands(signal, hull, cycles, undetermined=mask)
                    flags = band_undetermined(curve, band)
                else:
                    curve, band = signal, np.where(mask[:, None, :], np.nan, hull)
                    flags = mask & np.isfinite(signal)[None, :]
                colour = _colour(source)
                drawn[source] = band[0]
                ax.fill_between(x, band[0, 0], band[0, 1], color=_tint(source), lw=0)
                for bound in (0, 1):
                    ax.plot(x, band[0, bound], color=colour, lw=0.8, alpha=0.9)
                if flags is not None and flags.any():
                    strips.append((slot, colour, flags))
                    hatched = True
            if curve is not None:
                ax.plot(x, curve, color="black", lw=1.3)
                _limit(ax, curve, drawn)
            _draw_undetermined(ax, x, strips, n_slots=len(order))
            if cycles:
                ax.set_xlim(0, 100)
                if r == len(JOINTS) - 1:
                    ax.set_xlabel("gait cycle (%)  [0 and 100 % = foot strike]", fontsize=8)
            else:
                ax.set_xlim(*time_limits(x))
                ax.set_xlabel("time (s)  [no gait cycles on this side: the whole trial]", fontsize=8)
    n_cycles = data.n_cycles()
    handles: list[Artist] = [Line2D([], [], color="black", lw=1.3, label="measured (mean over cycles: L "
                                    f"{n_cycles['L']}, R {n_cycles['R']})")]  # fmt: skip
    for source in reversed(order):
        handles.append(Patch(facecolor=_tint(source), edgecolor=_colour(source),
                             label=f"{source_title(source)}{'' if source == ALL else ' alone'}"))  # fmt: skip
    if hatched:
        handles.append(Patch(facecolor="0.85", edgecolor="0.3", hatch=HATCH, lw=0,
                             label="undetermined: no band (strip in the band's colour)"))  # fmt: skip
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.962), ncol=3, fontsize=8.5,
               frameon=False, title=f"α = {alpha_text(alpha)} bands (worst case of each)",
               title_fontsize=8.5)  # fmt: skip
    place_grid(fig, 0.9, SOURCES_GRID)
    return fig


#: How far (fraction of the sources' range) the band of all together may widen the y-axis.
ALL_HEADROOM = 0.5


def _limit(ax: Axes, curve: np.ndarray, bands: dict[str, np.ndarray]) -> None:
    """y-limits from the curve and the bands of the sources alone, widened by the band of
    all together by at most :data:`ALL_HEADROOM` of that range each way (where it is far
    wider, e.g. a bound near the 90° of "undetermined", it leaves the panel and a note
    says how far it reaches): the sources stay readable."""
    inner = np.concatenate([curve, *(b.ravel() for s, b in bands.items() if s != ALL)])
    inner = inner[np.isfinite(inner)]
    if inner.size == 0:
        return
    low, high = float(inner.min()), float(inner.max())
    span = max(high - low, 1.0)
    outer = bands.get(ALL)
    outer = outer[np.isfinite(outer)] if outer is not None else np.array([])
    reach = (float(outer.min()), float(outer.max())) if outer.size else (low, high)
    bottom = max(min(low, reach[0]), low - ALL_HEADROOM * span)
    top = min(max(high, reach[1]), high + ALL_HEADROOM * span)
    pad = 0.05 * (top - bottom)
    ax.set_ylim(bottom - pad, top + pad)
    if reach[0] < bottom - pad or reach[1] > top + pad:
        ax.text(0.99, 0.02, f"all together reaches {reach[0]:.0f}° to {reach[1]:.0f}° (beyond the axis)",
                transform=ax.transAxes, ha="right", va="bottom", fontsize=6.5, color="0.3")  # fmt: skip


# ============================================================================ HTML
def _radius_text(result: MarkerErrorResult, source: str) -> str:
    """The α = 0 radii of one source alone over the markers, e.g. "2 mm" or "5–15 mm"."""
    assert result.sources is not None
    radius = result.sources["ball_radius"].sel(source=source).to_numpy().astype(float)
    radius = radius[np.isfinite(radius)]
    if radius.size == 0:
        return ""
    low, high = float(radius.min()), float(radius.max())
    return f"{low:g} mm" if math.isclose(low, high) else f"{low:g}–{high:g} mm"


def _cell(table: SourceWidths, component: str, source: str, strong: bool) -> str:
    width, flipped = table.width(component, source), table.frames_undetermined(component, source)
    if not math.isfinite(width):
        if not flipped:
            return "–"
        return '<b class="undet">undetermined</b>' if strong else '<span class="undet">undetermined</span>'
    text = f"<b>{width:.1f}</b>" if strong else f"{width:.1f}"
    if flipped:
        of = int(table.n_frames[component])
        text += f'<br><span class="small undet">undetermined on {flipped} of {of} frames</span>'
    return text


def sources_section(result: MarkerErrorResult | None, files: str | None) -> str:
    """The per-source section of the trial page: the figure (``files``: the trial's figure
    folder, href-quoted; None: no figure) and the widest-band table; "" without
    per-source bands (or without a result)."""
    if not has_source_bands(result):
        return ""
    assert result is not None
    table = widest_source_bands(result)
    alpha = alpha_text(table.alpha)
    columns = [*table.sources, ALL]
    header = [("Angle", False)]
    header += [(escape(source_title(s)).replace(" ", "<br>", 1) + ("" if s == ALL else " alone"), True)
               for s in columns]  # fmt: skip
    header += [("Dominates", False)]
    rows = []
    for component in (str(c) for c in table.widths.index):
        dominant = table.dominant(component)
        cells = [(f'<span class="nowrap" title="{escape(component)}">{escape(component_label(component))}</span>',
                  False)]  # fmt: skip
        cells += [(_cell(table, component, s, s == dominant), True) for s in columns]
        cells.append((escape(source_title(dominant)) if dominant else "–", False))
        rows.append(cells)
    radii = ", ".join(f"{escape(source_title(s))} {escape(_radius_text(result, s))}" for s in table.sources)
    figure = ""
    if files is not None:
        figure = (f'<figure><a href="{files}/sources.svg"><img src="{files}/sources.png" width="1100" height="960" '
                  'alt="Hip, knee and ankle flexion, left and right, over the gait cycle with the alpha = 0 band of '
                  'each marker error source alone and of all together"></a>'
                  f"<figcaption>Mean over gait cycles with the α = {alpha} band of each error source alone and of "
                  "all together; hatched strips along the top of a panel: that band is undetermined there (no band "
                  f'drawn). (<a href="{files}/sources.svg">SVG</a>, <a href="{files}/sources.png">PNG</a>)'
                  "</figcaption></figure>")  # fmt: skip
    return (
        '<h2 id="sources">Which error source dominates: flexion bands per source</h2>'
        f"<p>The flexion angles with the α = {alpha} band of each marker error source on its own and of all "
        f"together{footnote('sources')}. At α = {alpha} every marker lies within its source's error of where it was "
        f"measured ({radii}, by segment{footnote('bands')}); all together adds the three. Where the band of all "
        "together is determined, a source's band lies inside it, as its balls lie inside theirs; where it is "
        "undetermined (no band drawn), a source's own band can still be drawn and be wider than any band of all "
        "together in the table below. The widest one dominates the uncertainty — reducing that error helps "
        "most.</p>"
        + figure
        + f"<h3>Widest α = {alpha} band per source (deg)</h3>"
        "<p class=\"small\">The widest band anywhere in the trial (upper minus lower bound) over the frames where "
        "it is determined; “undetermined”: no frame is (a segment frame can flip). A source whose band is "
        "undetermined somewhere counts as dominating.</p>"
        + html_table(header, rows)
    )


def dominant_sentence(result: MarkerErrorResult | None, joint: str = "Knee") -> str | None:
    """One sentence naming the source that dominates ``joint`` flexion (left and right),
    e.g. "Knee flexion: soft-tissue artefact dominates (widest α = 0 band alone L 62.1°,
    R 60.3°; measurement system 4.3°/4.2°, marker placement 28.4°/27.9°; all together
    97.8°/95.0°)."; None without per-source bands for it (or without a result)."""
    if result is None or not has_source_bands(result):
        return None
    table = widest_source_bands(result)
    names = [f"{side}{joint}Angles_X" for side in "LR" if f"{side}{joint}Angles_X" in table.widths.index]
    if not names:
        return None
    dominants = list(dict.fromkeys(d for d in (table.dominant(n) for n in names) if d is not None))
    if not dominants:
        return None

    def widths(source: str) -> str:
        parts = []
        for name in names:
            width, flipped = table.width(name, source), table.frames_undetermined(name, source)
            text = f"{width:.1f}°" if math.isfinite(width) else "undetermined"
            parts.append(text + (f" ({flipped} frames undetermined)" if flipped and math.isfinite(width) else ""))
        return "/".join(parts)

    sides = "/".join(n[0] for n in names)
    lead = " and ".join(source_title(d) for d in dominants)
    others = "; ".join(f"{source_title(s)} {widths(s)}" for s in table.sources if s not in dominants)
    return (f"{joint} flexion: {lead} {'dominates' if len(dominants) == 1 else 'dominate'} (widest "
            f"α = {alpha_text(table.alpha)} band alone {sides} {'; '.join(widths(d) for d in dominants)}"
            + (f"; {others}" if others else "") + f"; all sources together {widths(ALL)}).")  # fmt: skip
