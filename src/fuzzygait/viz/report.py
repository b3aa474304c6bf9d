"""Clinicians' batch report: one HTML page per trial plus an ``index.html``.

Layout of the output folder::

    OUT/index.html                     every trial: status, key numbers, error line
    OUT/<trial>.html                   one page per successful trial
    OUT/<trial>_files/cycles.png|svg   angles over the gait cycle with fuzzy α-bands
    OUT/<trial>_files/time_series.png|svg   the whole trial with its α-bands

The pages are plain HTML5 with inline CSS: no JavaScript, no external resources; the
figures are referenced by relative paths, so the folder can be zipped, mailed or opened
from a USB stick.

Gait-cycle bands
----------------
The fuzzy analysis gives, for every α-level, a lower and an upper hull of each angle at
every frame.  Each hull is time-normalised with the *same* gait cycles as the angle
(:func:`fuzzygait.gait.cycles.normalise_cycles`), and the band drawn is the **mean
over cycles** of the normalised lower hulls and of the normalised upper hulls, around
the mean over cycles of the measured angle.  Because the mean is linear and every
cycle's hulls enclose every angle curve the marker errors allow, this band encloses
every *mean* curve the marker errors allow: it is the uncertainty of the curve that is
drawn, and it keeps the α-levels nested.  Min/max over cycles would mix the stride-to-
stride variability (the SD of the classic report) into the measurement uncertainty.  At
each percentage only cycles where the angle and every hull are available are used.

Atomicity
---------
Everything is written into a hidden staging folder beside ``OUT`` and moved into place
when the report is complete: pages first, ``index.html`` last.  On an error (or Ctrl-C)
the staging folder is removed and ``OUT`` is untouched.  Pages of trials from earlier
runs that are not part of this batch stay in ``OUT`` but are not linked.
"""

from __future__ import annotations

import datetime as _dt
import html
import math
import os
import re
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING
from urllib.parse import quote

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from fuzzygait import __version__  # noqa: E402
from fuzzygait.core.errors import FuzzyGaitError  # noqa: E402
from fuzzygait.gait.cycles import GaitCycle, gait_cycles, normalise_cycles, percent_points  # noqa: E402
from fuzzygait.mocap.gaps import methods_used  # noqa: E402
from fuzzygait.viz.layout import ANGLE_ROWS, PLANES, SIDE_STYLE  # noqa: E402

if TYPE_CHECKING:
    import xarray as xr

    from fuzzygait.markererror.analysis import MarkerErrorAnalysis
    from fuzzygait.workflows.angles import AnglesRun

__all__ = [
    "ReportItem",
    "ReportWriter",
    "TrialEntry",
    "component_label",
    "cycle_bands",
    "write_report",
]

#: Samples per normalised gait cycle (0, 1, ..., 100 %).
N_POINTS = 101
#: Figure resolution; the figures are 11 in wide -> 1100 px PNGs.
DPI = 100
FIG_SIZE = (11.0, 12.6)
SIDE_NAMES = {"L": "Left", "R": "Right"}
#: Readable names of the marker error sources (``fuzzygait.markererror.sources``).
SOURCE_NAMES = {"measurement": "measurement system", "placement": "marker placement",
                "sta": "soft-tissue artefact"}  # fmt: skip
_ROW_TITLES = dict(ANGLE_ROWS)
_PLANE_INFO = {axis: (plane, meaning) for axis, plane, meaning in PLANES}


@dataclass
class ReportItem:
    """One trial of the batch: its analysis, or the one-line error that stopped it."""

    source: Path
    analysis: MarkerErrorAnalysis | None = None
    error: str | None = None


@dataclass
class TrialEntry:
    """What the index shows about one trial (kept after its page has been written)."""

    source: Path
    page: str | None  # href relative to the index, None when failed
    error: str | None = None
    n_frames: int | None = None
    rate: float | None = None
    cycles: dict[str, int] = field(default_factory=dict)
    gaps_filled: int = 0
    gaps_left: int = 0
    max_delta_phi: tuple[float, str, float] | None = None  # (value %, component, alpha)
    widest_band: tuple[float, str, float] | None = None  # (deg, component, alpha)

    @property
    def ok(self) -> bool:
        return self.error is None


# ============================================================================ helpers
def component_label(name: str) -> str:
    """Clinical label of an angle component: ``"LKneeAngles_X"`` -> ``"Left knee,
    sagittal (+ flexion)"``; unknown names are returned unchanged."""
    parsed = _parse_component(name)
    if parsed is None:
        return name
    side, base, axis = parsed
    row = _ROW_TITLES.get(base)
    plane, meaning = _PLANE_INFO[axis]
    if row is None:
        return f"{SIDE_NAMES[side]} {base}, {plane}"
    positive = meaning.get(row, "")
    label = f"{SIDE_NAMES[side]} {row.lower()}, {plane}"
    return label + (f" (+ {positive})" if positive else "")


def _parse_component(name: str) -> tuple[str, str, str] | None:
    match = re.fullmatch(r"([LR])(\w+?)_([XYZ])", name)
    return (match[1], match[2], match[3]) if match else None


def _component_order(name: str) -> tuple[int, int, int, str]:
    """Sort key: joint rows of the report, then plane, then side."""
    parsed = _parse_component(name)
    rows = [base for base, _ in ANGLE_ROWS]
    if parsed is None or parsed[1] not in rows:
        return (len(rows), 0, 0, name)
    side, base, axis = parsed
    return (rows.index(base), "XYZ".index(axis), "LR".index(side), name)


def _esc(value: object) -> str:
    return html.escape(str(value), quote=True)


def _fmt(value: float, digits: int = 1) -> str:
    if value is None or not np.isfinite(value):
        return "–"
    return f"{value:.{digits}f}"


def _alpha_text(alpha: float) -> str:
    return f"{alpha:g}"


def _one_line(text: str) -> str:
    lines = [line.strip() for line in str(text).splitlines() if line.strip()]
    return " ".join(lines) if lines else "unknown error"


def _sources_text(fuzzy: xr.Dataset) -> str:
    """``"measurement,sta"`` attribute -> ``"measurement system, soft-tissue artefact"``."""
    sources = fuzzy.attrs.get("sources", "")
    names = sources.split(",") if isinstance(sources, str) else list(np.atleast_1d(sources))
    return ", ".join(SOURCE_NAMES.get(str(n).strip(), str(n).strip()) for n in names if str(n).strip())


def _slug(stem: str) -> str:
    slug = re.sub(r"[^A-Za-z0-9._-]+", "_", stem).strip("._-")
    return slug or "trial"


# ============================================================================ bands
def _hulls(fuzzy: xr.Dataset, name: str, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(alphas < 1 ascending, hull (n_alpha, 2 [lower, upper], n_frames) deg)`` of one
    angle component on ``frames``, or None when the analysis did not cover it."""
    if name not in fuzzy.data_vars:
        return None
    data = fuzzy[name]
    if "frame" in data.dims and "frame" in fuzzy.coords:
        data = data.reindex(frame=np.asarray(frames))
    data = data.sel(bound=["lower", "upper"]).transpose("alpha", "bound", "frame")
    alphas = np.asarray(data["alpha"].values, dtype=float)
    keep = alphas < 1.0 - 1e-9
    if not keep.any():
        return None
    order = np.argsort(alphas[keep])
    values = np.asarray(data.values, dtype=float)[keep][order]
    return alphas[keep][order], values


def cycle_bands(
    signal: np.ndarray, hull: np.ndarray, cycles: Sequence[GaitCycle], n_points: int = N_POINTS
) -> tuple[np.ndarray, np.ndarray, int]:
    """Gait-cycle-normalised mean curve and fuzzy bands of one angle component.

    Args:
        signal: ``(n_frames,)`` measured angle (deg).
        hull: ``(n_alpha, 2, n_frames)`` lower/upper hull per α-level (deg).
        cycles: the side's gait cycles (:func:`gait_cycles`).

    Returns:
        ``(mean (n_points,), band (n_alpha, 2, n_points), n_cycles)``: the mean over
        cycles of the normalised angle and of the normalised lower and upper hulls,
        using at each percentage only the cycles where the angle and all hulls are
        finite; ``n_cycles`` is the largest number of cycles used.
    """
    n_alpha = hull.shape[0]
    if not cycles:
        return np.full(n_points, np.nan), np.full((n_alpha, 2, n_points), np.nan), 0
    curve = normalise_cycles(np.asarray(signal, dtype=float), cycles, n_points)  # (c, p)
    hulls = normalise_cycles(np.moveaxis(np.asarray(hull, dtype=float), -1, 0), cycles, n_points)
    valid = np.isfinite(curve) & np.isfinite(hulls).all(axis=(2, 3))  # (c, p)
    count = valid.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(valid, curve, 0.0).sum(axis=0) / count
        band = np.where(valid[:, :, None, None], hulls, 0.0).sum(axis=0) / count[:, None, None]
    mean[count == 0] = np.nan
    band[count == 0] = np.nan
    return mean, np.moveaxis(band, 0, -1), int(count.max())


# ============================================================================ figures
def _band_opacity(n_levels: int) -> float:
    """Opacity of one band layer: the innermost band (all layers stacked) reaches ~0.4."""
    return min(0.25, 1.0 - 0.6 ** (1.0 / max(n_levels, 1)))


def _legend_handles(alphas: np.ndarray, n_cycles: dict[str, int] | None) -> list:
    handles: list = []
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
        edge = {"edgecolor": "0.25", "lw": 0.5} if k == 0 else {"lw": 0}
        handles.append(Patch(facecolor=(0.25, 0.25, 0.25, opacity), label=f"α = {_alpha_text(alpha)}{tag}", **edge))
    return handles


def _panel_grid(title: str) -> tuple[plt.Figure, np.ndarray]:
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


def _finish_figure(fig: plt.Figure, axes: np.ndarray, handles: list, stem: Path) -> None:
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.968),
               ncol=min(len(handles), 7), fontsize=8.5, frameon=False)  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.945))
    for suffix in ("png", "svg"):
        fig.savefig(stem.with_suffix(f".{suffix}"), dpi=DPI, format=suffix)
    plt.close(fig)


def _draw_bands(ax, x, curve, alphas, band, colour, layer, rasterized=False) -> None:  # noqa: ANN001
    """α-bands (nested, widest first) in the side's colour, the widest band's edges as
    thin lines (so overlapping left/right bands stay apart), and the curve on top."""
    if band is not None and len(alphas):
        for k in range(len(alphas)):
            ax.fill_between(x, band[k, 0], band[k, 1], color=colour, alpha=layer, lw=0,
                            rasterized=rasterized)  # fmt: skip
        for bound in (0, 1):
            ax.plot(x, band[0, bound], color=colour, lw=0.5, alpha=0.8, rasterized=rasterized)
    ax.plot(x, curve, color=colour, lw=1.4)


def _not_computed(ax, text: str = "not computed") -> None:  # noqa: ANN001
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center",
            fontsize=8, color="0.45")  # fmt: skip


@dataclass
class _TrialData:
    """Angles, hulls and cycles of one trial, aligned on the trial's frames."""

    run: AnglesRun
    fuzzy: xr.Dataset
    alphas: np.ndarray
    cycles: dict[str, list[GaitCycle]]

    @classmethod
    def of(cls, analysis: MarkerErrorAnalysis) -> _TrialData:
        run = analysis.run
        alphas = np.asarray(analysis.fuzzy["alpha"].values, dtype=float)
        alphas = np.sort(alphas[alphas < 1.0 - 1e-9])
        cycles = {side: gait_cycles(run.trial, run.events, side) for side in SIDE_STYLE}
        return cls(run, analysis.fuzzy, alphas, cycles)

    def angle(self, name: str) -> np.ndarray | None:
        parsed = _parse_component(name)
        if parsed is None:
            return None
        side, base, axis = parsed
        values = self.run.result.angles.get(f"{side}{base}")
        if values is None or f"{side}{base}" in self.run.result.unavailable:
            return None
        column = np.asarray(values, dtype=float)[:, "XYZ".index(axis)]
        return None if not np.isfinite(column).any() else column

    def hull(self, name: str) -> np.ndarray | None:
        found = _hulls(self.fuzzy, name, self.run.trial.frames)
        if found is None:
            return None
        alphas, values = found
        if alphas.shape != self.alphas.shape or not np.allclose(alphas, self.alphas):
            # only the α-levels common to the whole report
            index = [int(np.argmin(abs(alphas - a))) for a in self.alphas]
            values = values[index]
        return values


def plot_cycle_bands(data: _TrialData, stem: Path, title: str) -> dict[str, int]:
    """The gait-report grid (joints x planes) over the gait cycle with α-bands; writes
    ``stem.png`` and ``stem.svg``.  Returns the number of cycles per side."""
    x = percent_points(N_POINTS)
    layer = _band_opacity(len(data.alphas))
    fig, axes = _panel_grid(title)
    for r, (base, _) in enumerate(ANGLE_ROWS):
        for c, (axis, _, _) in enumerate(PLANES):
            ax = axes[r, c]
            drawn, banded, notes, uncut = False, False, [], False
            for side, (_, colour) in SIDE_STYLE.items():
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
                    curve, band, used = cycle_bands(signal, hull, cycles)
                if not np.isfinite(curve).any():
                    continue
                _draw_bands(ax, x, curve, data.alphas, band, colour, layer)
                drawn, banded = True, banded or band is not None
                if used < len(cycles):
                    notes.append(f"{side}: {used} of {len(cycles)} cycles")
            if not drawn:
                _not_computed(ax, "no gait cycles (see the whole trial)" if uncut else "not computed")
                notes = []
            elif not banded:
                notes.append("no bands (not analysed)")
            if notes:
                ax.text(0.01, 0.02, "; ".join(notes), transform=ax.transAxes, fontsize=6.5,
                        color="0.3", va="bottom")  # fmt: skip
            ax.set_xlim(0, 100)
            if r == len(ANGLE_ROWS) - 1:
                ax.set_xlabel("gait cycle (%)  [0 and 100 % = foot strike]", fontsize=8)
    n_cycles = {side: len(cycles) for side, cycles in data.cycles.items()}
    _finish_figure(fig, axes, _legend_handles(data.alphas, n_cycles), stem)
    return n_cycles


def plot_time_series(data: _TrialData, stem: Path, title: str) -> None:
    """The whole trial with α-bands (joints x planes, time in s) and foot strikes as
    dotted lines; writes ``stem.png`` and ``stem.svg`` (bands rasterised in the SVG)."""
    trial = data.run.trial
    t = trial.times
    layer = _band_opacity(len(data.alphas))
    fig, axes = _panel_grid(title)
    strikes = {side: [e.time for e in data.run.events
                      if e.label == "Foot Strike" and e.context == SIDE_NAMES[side]]
               for side in SIDE_STYLE}  # fmt: skip
    for r, (base, _) in enumerate(ANGLE_ROWS):
        for c, (axis, _, _) in enumerate(PLANES):
            ax = axes[r, c]
            drawn = False
            for side, (_, colour) in SIDE_STYLE.items():
                for when in strikes[side]:
                    ax.axvline(when, color=colour, lw=0.7, ls=":", alpha=0.7)
                name = f"{side}{base}_{axis}"
                signal = data.angle(name)
                if signal is None:
                    continue
                _draw_bands(ax, t, signal, data.alphas, data.hull(name), colour, layer, rasterized=True)
                drawn = True
            if not drawn:
                _not_computed(ax)
            ax.set_xlim(t[0], t[-1])
            if r == len(ANGLE_ROWS) - 1:
                ax.set_xlabel("time (s)   [dotted lines: foot strikes]", fontsize=8)
    _finish_figure(fig, axes, _legend_handles(data.alphas, None), stem)


# ============================================================================ numbers
def _delta_phi_table(analysis: MarkerErrorAnalysis, data: _TrialData) -> pd.DataFrame:
    """ΔΦ rows in report order, α columns descending (as Table 5.2), plus the reference
    max |Φ| of the measured angle and the widest band at the smallest α."""
    table = analysis.delta_phi.copy()
    table.columns = [float(c) for c in table.columns]
    table = table[sorted(table.columns, reverse=True)]
    table = table.loc[sorted(table.index, key=_component_order)]
    peak, widest = [], []
    lowest = data.alphas[0] if data.alphas.size else None
    for name in table.index:
        signal = data.angle(name)
        peak.append(float(np.nanmax(np.abs(signal))) if signal is not None else math.nan)
        hull = data.hull(name)
        if hull is None or lowest is None:
            widest.append(math.nan)
        else:
            width = hull[0, 1] - hull[0, 0]
            widest.append(float(np.nanmax(width)) if np.isfinite(width).any() else math.nan)
    table["peak"] = peak
    table["widest"] = widest
    return table


def _summary_numbers(table: pd.DataFrame) -> tuple[tuple | None, tuple | None]:
    """Largest ΔΦ at the smallest α (sagittal hip/knee/ankle when present, as in
    Table 5.2, else any angle) and the widest band (deg) at the smallest α."""
    alpha_columns = [c for c in table.columns if isinstance(c, float)]
    if not alpha_columns or table.empty:
        return None, None
    lowest = min(alpha_columns)
    column = table[lowest].astype(float)
    flexion = [n for n in table.index if re.fullmatch(r"[LR](Hip|Knee|Ankle)Angles_X", n)]
    candidates = column.loc[flexion] if flexion else column
    candidates = candidates[np.isfinite(candidates)]
    largest = None
    if not candidates.empty:
        name = str(candidates.idxmax())
        largest = (float(candidates[name]), name, lowest)
    widths = table["widest"].astype(float)
    widths = widths[np.isfinite(widths)]
    widest = None
    if not widths.empty:
        name = str(widths.idxmax())
        widest = (float(widths[name]), name, lowest)
    return largest, widest


# ============================================================================ HTML
CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, Arial, sans-serif;
       margin: 0 auto; max-width: 1180px; padding: 0 1.2rem 2rem; color: #1d1d1f;
       line-height: 1.45; background: #fff; }
nav { padding: .7rem 0; border-bottom: 1px solid #ddd; margin-bottom: .6rem; font-size: .95rem; }
a { color: #0b57b0; }
h1 { font-size: 1.6rem; margin: .6rem 0 .2rem; word-break: break-all; }
h2 { font-size: 1.2rem; margin: 1.8rem 0 .5rem; border-bottom: 2px solid #e4e4e4; padding-bottom: .2rem; }
h3 { font-size: 1rem; margin: 1rem 0 .3rem; }
p.lead { color: #555; margin-top: 0; }
table { border-collapse: collapse; margin: .4rem 0 1rem; font-size: .92rem; }
th, td { border: 1px solid #d5d5d5; padding: .25rem .55rem; text-align: left; vertical-align: top; }
thead th { background: #f2f4f7; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.kv th { background: #f7f7f7; font-weight: 600; white-space: nowrap; }
.cols { display: flex; flex-wrap: wrap; gap: 0 2.5rem; align-items: flex-start; }
.box { background: #f5f8fc; border: 1px solid #cfdcec; border-radius: 6px; padding: .7rem 1rem; margin: .8rem 0; }
.ok { color: #17692e; font-weight: 700; }
.failed { color: #b3261e; font-weight: 700; }
tr.failed-row td { background: #fff4f3; }
code, .mono { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: .88em; }
span.error { display: inline-block; max-width: 24rem; overflow-wrap: anywhere; color: #7a1c16; font-size: .85em; }
figure { margin: .6rem 0 1rem; }
figure img { max-width: 100%; height: auto; border: 1px solid #e2e2e2; }
figcaption { font-size: .9rem; color: #444; margin-top: .3rem; }
.small { font-size: .85rem; color: #555; }
ul.notes li { margin: .15rem 0; }
footer { margin-top: 2.5rem; border-top: 1px solid #ddd; padding-top: .6rem; font-size: .85rem; color: #666; }
"""

ALPHA_SENTENCE = (
    "Each shaded band shows how far the joint angle could be off if every marker were "
    "displaced by up to (1 − α) times its assumed maximum error: the lightest, widest "
    "band (α = 0) is the worst case with all error sources at their maximum, darker "
    "bands (higher α) assume smaller errors, and the line (α = 1) is the angle as "
    "measured."
)
DELTA_PHI_SENTENCE = (
    "ΔΦ<sub>α</sub> = max<sub>t</sub>(Φ<sup>u</sup><sub>α</sub>(t) − "
    "Φ<sup>l</sup><sub>α</sub>(t)) / max<sub>t</sub> |Φ(t)| × 100 %: the widest the "
    "α-band gets anywhere in the trial, relative to the largest measured magnitude of the "
    "angle (thesis Eq. 5.3 and Table 5.2; the magnitude keeps angles that stay negative "
    "comparable)."
)


def _page(title: str, body: str) -> str:
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta name=\"generator\" content=\"fuzzygait " + _esc(__version__) + "\">\n"
        f"<title>{_esc(title)}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}\n"
        "</body>\n</html>\n"
    )


def _footer() -> str:
    stamp = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z").strip()
    return (
        f"<footer>Generated by fuzzygait {_esc(__version__)} on {_esc(stamp)}. "
        "Angles: Plug-in Gait lower body; uncertainty: fuzzy marker-position errors "
        "propagated with the Graph Follower algorithm (α-level optimisation).</footer>"
    )


def _kv_table(rows: Sequence[tuple[str, str]], caption: str | None = None) -> str:
    cap = f"<caption class=\"small\">{_esc(caption)}</caption>" if caption else ""
    body = "".join(f"<tr><th scope=\"row\">{_esc(k)}</th><td>{v}</td></tr>" for k, v in rows)
    return f"<table class=\"kv\">{cap}<tbody>{body}</tbody></table>"


def _table(header: Sequence[tuple[str, bool]], rows: Iterable[Sequence[tuple[str, bool]]],
           row_classes: Sequence[str] | None = None) -> str:  # fmt: skip
    """``header``/cells are (html, numeric) pairs; the html must already be escaped."""
    num = ' class="num"'
    head = "".join(f'<th scope="col"{num if n else ""}>{h}</th>' for h, n in header)
    lines = []
    for i, row in enumerate(rows):
        rc = f' class="{row_classes[i]}"' if row_classes and row_classes[i] else ""
        cells = "".join(f"<td{num if n else ''}>{v}</td>" for v, n in row)
        lines.append(f"<tr{rc}>{cells}</tr>")
    return f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(lines)}</tbody></table>"


def _deg(rad: float) -> str:
    text = f"{math.degrees(rad):.2f}"
    return "0.00" if text == "-0.00" else text


def _static_text(run: AnglesRun) -> str:
    """Where the static offsets come from (a sentence)."""
    static = [n for n in run.notes if n.startswith("static offsets")]
    if static:
        return static[0][0].upper() + static[0][1:] + "."
    return "No static trial given: the static offsets are used as stored in the subject parameters."


def _subject_section(run: AnglesRun) -> str:
    subject = run.subject
    rows = [
        ("Leg length", "mm", "leg_length", lambda v: f"{v:.1f}"),
        ("Knee width", "mm", "knee_width", lambda v: f"{v:.1f}"),
        ("Ankle width", "mm", "ankle_width", lambda v: f"{v:.1f}"),
        ("ASIS–trochanter distance", "mm", "asis_trochanter", lambda v: f"{v:.1f}"),
        ("Tibial torsion", "deg", "tibial_torsion", _deg),
        ("Thigh rotation offset", "deg", "thigh_rotation", _deg),
        ("Shank rotation offset", "deg", "shank_rotation", _deg),
        ("Ankle ab/adduction offset", "deg", "ankle_abadd", _deg),
        ("Sole delta", "mm", "sole_delta", lambda v: f"{v:.1f}"),
        ("<b>Static plantarflexion offset</b>", "deg", "static_plant_flex", _deg),
        ("<b>Static rotation offset</b>", "deg", "static_rot_off", _deg),
    ]
    side_rows = [
        [(label, False), (unit, False), (_esc(fmt(getattr(subject.left, attr))), True),
         (_esc(fmt(getattr(subject.right, attr))), True)]
        for label, unit, attr, fmt in rows
    ]  # fmt: skip
    sides = _table([("Parameter", False), ("Unit", False), ("Left", True), ("Right", True)], side_rows)
    general = [
        ("Body mass", f"{subject.body_mass:g} kg" if subject.body_mass else "not given"),
        ("Height", f"{subject.height:g} mm" if subject.height else "not given"),
        ("Marker diameter", f"{subject.marker_diameter:g} mm"),
        ("Inter-ASIS distance", f"{subject.inter_asis_distance:g} mm"
         if subject.inter_asis_distance else "measured from the markers"),
        ("Source", _esc(subject.source or "trial file")),
    ]  # fmt: skip
    return (
        "<h2 id=\"subject\">Subject parameters used</h2>"
        f"<p class=\"small\">{_esc(_static_text(run))}</p>"
        f"<div class=\"cols\">{sides}{_kv_table(general)}</div>"
    )


def _quality_section(analysis: MarkerErrorAnalysis, data: _TrialData) -> str:
    run = analysis.run
    trial = run.trial
    parts = ["<h2 id=\"quality\">Data quality</h2>"]
    # events and cycles
    counts = []
    for side, side_name in SIDE_NAMES.items():
        strikes = sum(1 for e in run.events if e.context == side_name and e.label == "Foot Strike")
        offs = sum(1 for e in run.events if e.context == side_name and e.label == "Foot Off")
        counts.append([(side_name, False), (str(strikes), True), (str(offs), True),
                       (str(len(data.cycles[side])), True)])  # fmt: skip
    source = "read from the file" if run.event_source == "file" else run.event_source
    parts.append(f"<h3>Gait events</h3><p>Events {_esc(source)}.</p>")
    parts.append(_table([("Side", False), ("Foot strikes", True), ("Foot offs", True),
                         ("Gait cycles", True)], counts))  # fmt: skip
    # gaps
    parts.append("<h3>Gaps in the marker trajectories</h3>")
    if not run.gaps:
        parts.append("<p>None: every marker was visible in every frame.</p>")
    else:
        filled = sum(g.filled for g in run.gaps)
        parts.append(
            f"<p>{filled} of {len(run.gaps)} gaps filled ({_esc(methods_used(run.gaps)) or 'none'}); frames of gaps "
            "left open have no angle (and no band) for the joints that use the marker.</p>"
        )
        rows = []
        classes = []
        for gap in sorted(run.gaps, key=lambda g: (g.marker, g.start)):
            first = trial.first_frame + gap.start
            status = f"filled by {gap.method}" if gap.filled else f"not filled: {gap.reason}"
            span = f"{first}–{first + gap.length - 1}" if gap.length > 1 else f"{first}"
            rows.append([(_esc(gap.marker), False), (span, True),
                         (str(gap.length), True), (_esc(status), False)])  # fmt: skip
            classes.append("" if gap.filled else "failed-row")
        parts.append(_table([("Marker", False), ("C3D frames", True), ("Frames", True),
                             ("Result", False)], rows, row_classes=classes))  # fmt: skip
    # missing markers / angles not computed
    parts.append("<h3>Missing markers and angles not computed</h3>")
    never = sorted({g.marker for g in run.gaps if "never visible" in g.reason})
    missing = []
    if never:
        missing.append(f"Markers never visible: {_esc(', '.join(never))}.")
    missing += [f"{_esc(name)} not computed: {_esc(why)}" for name, why in run.result.unavailable.items()]
    for name, values in run.result.angles.items():
        if name in run.result.unavailable:
            continue
        empty = int((~np.isfinite(np.asarray(values, dtype=float)).all(axis=1)).sum())
        if 0 < empty < trial.n_frames:
            missing.append(f"{_esc(name)}: no value on {empty} of {trial.n_frames} frames "
                           "(a marker it needs is missing there).")  # fmt: skip
    no_band = [n for n in _all_components(data) if data.angle(n) is not None and data.hull(n) is None]
    if no_band:
        angles = list(dict.fromkeys(n.rsplit("_", 1)[0] for n in no_band))
        missing.append("No uncertainty band (not analysed): " + _esc(", ".join(angles)) + ".")
    if missing:
        parts.append("<ul class=\"notes\">" + "".join(f"<li>{m}</li>" for m in missing) + "</ul>")
    else:
        parts.append("<p>None: every marker was recorded and every angle computed on every frame.</p>")
    # notes
    notes = list(dict.fromkeys([*run.notes, *analysis.notes]))
    if notes:
        parts.append("<h3>Processing notes</h3><ul class=\"notes\">"
                     + "".join(f"<li>{_esc(n)}</li>" for n in notes) + "</ul>")  # fmt: skip
    return "".join(parts)


def _all_components(data: _TrialData) -> list[str]:
    return [f"{side}{base}_{axis}" for base, _ in ANGLE_ROWS for axis in "XYZ" for side in "LR"]


def _assumptions_section(analysis: MarkerErrorAnalysis, data: _TrialData) -> str:
    fuzzy = analysis.fuzzy
    sources = _sources_text(fuzzy)
    parts = ["<h2 id=\"assumptions\">Assumed marker errors</h2>",
             "<p>The true position of every marker is taken to lie within a ball around "
             "its measured position; at α = 0 the ball has the radius below (the sum of the "
             f"selected error sources: {_esc(sources or 'see notes')}), at level α the radius "
             "is (1 − α) times that.</p>"]  # fmt: skip
    if "ball_radius" in fuzzy.data_vars and "marker" in fuzzy["ball_radius"].dims:
        radius = fuzzy["ball_radius"]
        rows = [[(_esc(m), False), (_fmt(float(r), 1), True)]
                for m, r in zip(radius["marker"].values, radius.values, strict=True)]  # fmt: skip
        half = (len(rows) + 1) // 2
        tables = [_table([("Marker", False), ("Radius at α = 0 (mm)", True)], chunk)
                  for chunk in (rows[:half], rows[half:]) if chunk]  # fmt: skip
        parts.append(f"<div class=\"cols\">{''.join(tables)}</div>")
    return "".join(parts)


def _delta_phi_section(table: pd.DataFrame, data: _TrialData) -> str:
    alpha_columns = [c for c in table.columns if isinstance(c, float)]
    lowest = data.alphas[0] if data.alphas.size else None
    header = [("Angle", False)] + [(f"α = {_alpha_text(a)}", True) for a in alpha_columns]
    header += [("Reference<br>max |Φ| (deg)", True)]
    if lowest is not None:
        header += [(f"Widest band<br>α = {_alpha_text(lowest)} (deg)", True)]
    rows = []
    for name, row in table.iterrows():
        cells = [(f"{_esc(component_label(name))} <span class=\"small mono\">{_esc(name)}</span>", False)]
        cells += [(_fmt(float(row[a]), 0), True) for a in alpha_columns]
        cells += [(_fmt(float(row["peak"]), 1), True)]
        if lowest is not None:
            cells += [(_fmt(float(row["widest"]), 1), True)]
        rows.append(cells)
    return (
        "<h2 id=\"delta-phi\">Relative envelope width ΔΦ (%)</h2>"
        f"<p>{DELTA_PHI_SENTENCE} Values are large for angles whose largest value is "
        "small or near zero (e.g. frontal and transverse planes); read them together with "
        "the band width in degrees. “–”: not available.</p>"
        + _table(header, rows)
    )


def _trial_page(analysis: MarkerErrorAnalysis, data: _TrialData, entry: TrialEntry,
                table: pd.DataFrame, files: str, source: Path) -> str:  # fmt: skip
    run = analysis.run
    trial = run.trial
    last = trial.first_frame + trial.n_frames - 1
    n_cycles = {side: len(c) for side, c in data.cycles.items()}
    facts = [
        ("File", f"<span class=\"mono\">{_esc(source)}</span>"),
        ("Subject", _esc(trial.subject or run.raw.subject or "not named in the file")),
        ("Frames", f"{trial.n_frames} (C3D frames {trial.first_frame}–{last})"),
        ("Sampling rate", f"{trial.rate:g} Hz"),
        ("Duration", f"{trial.n_frames / trial.rate:.2f} s"),
        ("Gait cycles", f"left {n_cycles['L']}, right {n_cycles['R']}"),
        ("Static offsets",
         f"plantarflexion L {_deg(run.subject.left.static_plant_flex)}°, R {_deg(run.subject.right.static_plant_flex)}°; "
         f"rotation L {_deg(run.subject.left.static_rot_off)}°, R {_deg(run.subject.right.static_rot_off)}°"
         f"<br><span class=\"small\">{_esc(_static_text(run))} "
         "<a href=\"#subject\">All subject parameters</a></span>"),
        ("α-levels", ", ".join(_alpha_text(a) for a in data.alphas) + ", 1 (measured)"),
    ]  # fmt: skip
    if _sources_text(analysis.fuzzy):
        facts.append(("Error sources", _esc(_sources_text(analysis.fuzzy))))
    key = []
    if entry.max_delta_phi is not None:
        value, name, alpha = entry.max_delta_phi
        key.append(f"Largest ΔΦ at α = {_alpha_text(alpha)}: <b>{_fmt(value, 0)} %</b> "
                   f"– {_esc(component_label(name))}")  # fmt: skip
    if entry.widest_band is not None:
        value, name, alpha = entry.widest_band
        key.append(f"Widest band at α = {_alpha_text(alpha)}: <b>{_fmt(value, 1)}°</b> "
                   f"– {_esc(component_label(name))}")  # fmt: skip
    filled = sum(g.filled for g in run.gaps)
    key.append(f"Gaps: {filled} filled, {len(run.gaps) - filled} left open; "
               f"{len(run.result.unavailable)} angle(s) not computed.")  # fmt: skip
    figs = quote(files)
    body = f"""
<nav><a href="index.html">← All trials (index)</a> · <a href="#cycles">Gait cycle</a> ·
<a href="#delta-phi">ΔΦ table</a> · <a href="#time-series">Whole trial</a> ·
<a href="#quality">Data quality</a> · <a href="#subject">Subject</a></nav>
<header>
<h1>{_esc(source.name)}</h1>
<p class="lead">Joint angles with their uncertainty from marker position errors</p>
</header>
<main>
<div class="cols">{_kv_table(facts)}<div class="box">{'<br>'.join(key)}</div></div>
<h2 id="cycles">Joint angles over the gait cycle</h2>
<p>{ALPHA_SENTENCE} Left side red, right side green; all angles in degrees, positive
direction as labelled on each axis.</p>
<p class="small">How the bands are normalised: each α-level's lower and upper bound is
cut into the same gait cycles (foot strike to next foot strike of that side) and
time-normalised like the angle; the band shown is the mean over cycles of the lower and of
the upper bounds, around the mean angle curve. It is therefore the uncertainty of the
mean curve drawn; the stride-to-stride variability is not included. A note such as
“L: 3 of 4 cycles” means some cycles had missing data there.</p>
<figure>
<a href="{figs}/cycles.svg"><img src="{figs}/cycles.png" width="1100" height="1260"
alt="Grid of joint angles (pelvis, hip, knee, ankle, foot progression; sagittal, frontal, transverse) over the gait cycle, left and right, with uncertainty bands per alpha-level"></a>
<figcaption>Mean over gait cycles with α-bands. Click for the scalable version
(<a href="{figs}/cycles.svg">SVG</a>, <a href="{figs}/cycles.png">PNG</a>).</figcaption>
</figure>
{_delta_phi_section(table, data)}
<h2 id="time-series">Whole trial</h2>
<p>The same angles over the whole recording (not normalised), with the α-bands frame by
frame. Dotted vertical lines mark foot strikes (red left, green right).</p>
<figure>
<a href="{figs}/time_series.svg"><img src="{figs}/time_series.png" width="1100" height="1260"
alt="Grid of joint angles over time for the whole trial with uncertainty bands per alpha-level"></a>
<figcaption>Joint angles over time with α-bands
(<a href="{figs}/time_series.svg">SVG</a>, <a href="{figs}/time_series.png">PNG</a>).</figcaption>
</figure>
{_quality_section(analysis, data)}
{_assumptions_section(analysis, data)}
{_subject_section(run)}
<p><a href="index.html">← Back to all trials</a></p>
</main>
{_footer()}"""
    return _page(f"{source.name} – fuzzygait report", body)


def _index_page(entries: Sequence[TrialEntry], alphas: Sequence[float]) -> str:
    n_ok = sum(e.ok for e in entries)
    n_failed = len(entries) - n_ok
    rows, classes = [], []
    for i, e in enumerate(entries, 1):
        if e.ok:
            name = f"<a href=\"{quote(e.page or '')}\">{_esc(e.source.name)}</a>"
            status = "<span class=\"ok\">OK</span>"
            frames = f"{e.n_frames} @ {e.rate:g} Hz" if e.n_frames is not None and e.rate else "–"
            cycles = f"{e.cycles.get('L', 0)} / {e.cycles.get('R', 0)}"
            if e.max_delta_phi is not None:
                value, comp, alpha = e.max_delta_phi
                dphi = (f"{_fmt(value, 0)} %<br><span class=\"small\">"
                        f"{_esc(component_label(comp))}</span>")  # fmt: skip
            else:
                dphi = "–"
            widest = f"{_fmt(e.widest_band[0], 1)}°" if e.widest_band is not None else "–"
            gaps = f"{e.gaps_filled} filled" + (f", {e.gaps_left} open" if e.gaps_left else "")
            detail = (f"<a href=\"{quote(e.page or '')}\">report page</a><br>"
                      f"<span class=\"small\">gaps: {_esc(gaps)}</span>")  # fmt: skip
            rows.append([(str(i), True), (name, False), (status, False), (frames, True),
                         (cycles, True), (dphi, True), (widest, True), (detail, False)])  # fmt: skip
            classes.append("")
        else:
            rows.append([(str(i), True), (_esc(e.source.name), False),
                         ("<span class=\"failed\">failed</span>", False), ("–", True), ("–", True),
                         ("–", True), ("–", True),
                         (f'<span class="mono error">{_esc(e.error)}</span>', False)])  # fmt: skip
            classes.append("failed-row")
    alpha_text = _alpha_text(min(alphas)) if alphas else "0"
    header = [("#", True), ("Trial", False), ("Status", False), ("Frames", True),
              ("Gait cycles L / R", True), (f"Largest ΔΦ at α = {alpha_text}", True),
              (f"Widest band at α = {alpha_text}", True), ("Details / error", False)]  # fmt: skip
    table = _table(header, rows, row_classes=classes)
    failed_text = f', <span class="failed">{n_failed} failed</span>' if n_failed else ""
    sources = "".join(f"<li><span class=\"mono\">{_esc(e.source)}</span></li>" for e in entries)
    body = f"""
<header>
<h1>Gait report: joint angles and their uncertainty</h1>
<p class="lead">{len(entries)} trial{'s' if len(entries) != 1 else ''}:
<span class="ok">{n_ok} OK</span>{failed_text}</p>
</header>
<main>
<div class="box">
<p>Each trial page shows the Plug-in Gait joint angles over the gait cycle and over the
whole trial, with shaded bands for the uncertainty caused by marker position errors
(measurement system, marker placement, soft-tissue artefact). {ALPHA_SENTENCE}</p>
<p>{DELTA_PHI_SENTENCE} The index shows the largest ΔΦ among hip, knee and ankle
flexion (as in the thesis' Table 5.2), and the widest band in degrees among all
angles.</p>
</div>
<h2>Trials</h2>
{table}
<h2>Input files</h2>
<ol class="small">{sources}</ol>
</main>
{_footer()}"""
    return _page("fuzzygait report – all trials", body)


# ============================================================================ writer
class ReportWriter:
    """Writes the report trial by trial into a staging folder; :meth:`finish` moves it
    into ``out_dir`` (pages first, index last).  Use as a context manager: on an
    exception the staging folder is removed and ``out_dir`` is left as it was.

    Args:
        out_dir: the report folder (created; existing pages of the same names replaced).
        strict: re-raise errors while drawing a page instead of listing the trial as
            failed (for debugging).
    """

    def __init__(self, out_dir: str | os.PathLike[str], *, strict: bool = False) -> None:
        self.out_dir = Path(out_dir)
        self.strict = strict
        self.entries: list[TrialEntry] = []
        self._names: set[str] = {"index"}
        self._alphas: set[float] = set()
        if self.out_dir.exists() and not self.out_dir.is_dir():
            raise FuzzyGaitError(f"{self.out_dir}: --out must be a folder, not a file")
        parent = self.out_dir.resolve().parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
            self._staging = Path(tempfile.mkdtemp(prefix=f".{self.out_dir.name}.", suffix=".tmp", dir=parent))
        except OSError as exc:
            raise FuzzyGaitError(f"{self.out_dir}: cannot create the report folder ({exc.strerror})") from None
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self._staging, 0o777 & ~umask)

    # -- context manager
    def __enter__(self) -> ReportWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:  # noqa: ANN001
        self.abort()

    def abort(self) -> None:
        """Remove the staging folder (no-op after :meth:`finish`)."""
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None

    # -- trials
    def _unique_name(self, source: Path) -> str:
        base = _slug(source.stem)
        name, k = base, 2
        while name.lower() in self._names:
            name, k = f"{base}-{k}", k + 1
        self._names.add(name.lower())
        return name

    def add(self, item: ReportItem) -> TrialEntry:
        """Write the page of one trial (or record its failure); returns its index entry."""
        if self._staging is None:
            raise RuntimeError("the report is already finished")
        source = Path(item.source)
        if item.analysis is None or item.error is not None:
            entry = TrialEntry(source, None, _one_line(item.error or "no analysis result"))
            self.entries.append(entry)
            return entry
        name = self._unique_name(source)
        files = f"{name}_files"
        try:
            entry = self._write_trial(item.analysis, source, name, files)
        except Exception as exc:
            if self.strict:
                raise
            shutil.rmtree(self._staging / files, ignore_errors=True)
            (self._staging / f"{name}.html").unlink(missing_ok=True)
            message = str(exc) if isinstance(exc, FuzzyGaitError) else f"{type(exc).__name__}: {exc}"
            entry = TrialEntry(source, None, _one_line(f"could not draw the report page: {message}"))
        finally:
            plt.close("all")
        self.entries.append(entry)
        return entry

    def _write_trial(self, analysis: MarkerErrorAnalysis, source: Path, name: str, files: str) -> TrialEntry:
        run = analysis.run
        data = _TrialData.of(analysis)
        self._alphas.update(float(a) for a in data.alphas)
        folder = self._staging / files
        folder.mkdir()
        title = f"{source.name}: joint angles with fuzzy α-bands"
        plot_cycle_bands(data, folder / "cycles", title + " (mean over gait cycles)")
        plot_time_series(data, folder / "time_series", title + " (whole trial)")
        table = _delta_phi_table(analysis, data)
        largest, widest = _summary_numbers(table)
        filled = sum(g.filled for g in run.gaps)
        entry = TrialEntry(
            source=source,
            page=f"{name}.html",
            n_frames=run.trial.n_frames,
            rate=run.trial.rate,
            cycles={side: len(c) for side, c in data.cycles.items()},
            gaps_filled=filled,
            gaps_left=len(run.gaps) - filled,
            max_delta_phi=largest,
            widest_band=widest,
        )
        page = _trial_page(analysis, data, entry, table, files, source)
        (self._staging / f"{name}.html").write_text(page, encoding="utf-8")
        return entry

    # -- the end
    def finish(self) -> Path:
        """Write ``index.html`` and move everything into ``out_dir``; returns the index."""
        if self._staging is None:
            raise RuntimeError("the report is already finished")
        staging = self._staging
        index_html = _index_page(self.entries, sorted(self._alphas))
        (staging / "index.html").write_text(index_html, encoding="utf-8")
        try:
            if not self.out_dir.exists():
                os.rename(staging, self.out_dir)
            else:
                entries = sorted(staging.iterdir(), key=lambda p: p.name == "index.html")
                for path in entries:  # index.html last
                    _replace(path, self.out_dir / path.name)
                staging.rmdir()
        except OSError as exc:
            raise FuzzyGaitError(f"{self.out_dir}: cannot write the report ({exc.strerror or exc})") from None
        self._staging = None
        return self.out_dir / "index.html"


def _replace(new: Path, target: Path) -> None:
    """Move ``new`` onto ``target`` (a file or a folder), replacing it."""
    if target.is_dir() and not target.is_symlink():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.rename(target, old)
        os.rename(new, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(new, target)


def write_report(items: Iterable[ReportItem], out_dir: str | os.PathLike[str]) -> Path:
    """Write the batch report: one page per trial and ``index.html``.

    Args:
        items: the trials, in index order; may be a generator (each analysis is drawn
            and can be freed before the next one is computed).  An item with an
            ``error`` (or no analysis) is listed as failed with that one-line error.
        out_dir: report folder; created, or updated in place (same-named pages are
            replaced).  Nothing is changed in it if writing fails.

    Returns:
        Path of ``index.html``.  A trial whose page cannot be drawn is listed as failed
        with the reason; the other trials are still written.
    """
    with ReportWriter(out_dir) as writer:
        for item in items:
            writer.add(item)
        return writer.finish()
