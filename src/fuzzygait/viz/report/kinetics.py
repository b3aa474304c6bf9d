"""The report's kinetics figures: Plug-in Gait joint moments and powers over the gait cycle
and the ground reaction over stance, computed by fuzzygait from the force plates
(:mod:`fuzzygait.kinetics`; nothing here writes a file: :mod:`fuzzygait.workflows.
report_folder` writes them as PNG and SVG).

Units: moments N·m per kg body mass (internal moments, Plug-in Gait's X sagittal, Y
frontal, Z transverse), powers W/kg (positive = generated), ground reaction % body
weight (forward, medial, up).  Sides as the angle pages draw them: left red and solid,
right green and dashed.  A trial's figure draws each counted cycle thin and their mean
thick; a session's figure the mean ± 1 SD over every counted cycle of its trials.  Only
cycles whose stance was on a force plate count
(:func:`fuzzygait.gait.normative.kinetic_cycles`); the normative mean ± 1 SD is grey
where a normative file has the variable (``KneeMoment_X``, ``KneePower_Z``,
``NormalisedGRF_Z``).

When the trial's marker-error analysis carries fuzzy kinetics
(:attr:`~fuzzygait.markererror.result.MarkerErrorResult.kinetics`), a trial's figure draws
their α-bands around each side's mean as the angle figures draw theirs (left filled, right
hatched, widest first; :func:`kinetic_bands`: the mean over the counted cycles of each
α-level's bounds), leaves a band out where a cycle's band is undetermined and marks those
points with the hatched strip along the top of the panel; nothing where the analysis did
not cover every counted cycle.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from fuzzygait.gait.cycles import GaitCycle, cycle_statistics, normalise_cycles, percent_points  # noqa: E402
from fuzzygait.gait.normative import N_POINTS, STANCE_OUTPUT, NormativeData, kinetic_cycles, loaded_cycles  # noqa: E402
from fuzzygait.viz.layout import SIDE_STYLE  # noqa: E402
from fuzzygait.viz.report.bands import alpha_text  # noqa: E402
from fuzzygait.viz.report.figures import (  # noqa: E402
    HATCH,
    HATCH_WIDTH,
    NORMATIVE_COLOUR,
    SIDE_LINE,
    _add_legend,
    _band_opacity,
    _draw_undetermined,
    _right_hatch,
    draw_normative,
)
from fuzzygait.viz.report.grid import GridMargins  # noqa: E402
from fuzzygait.viz.report.normalised_bands import (  # noqa: E402
    _cycle_flags,
    band_undetermined,
    component_levels,
    cycle_bands,
)

if TYPE_CHECKING:
    import xarray as xr

__all__ = [
    "GRF_COLUMNS",
    "KINETIC_COLUMNS",
    "KINETIC_ROWS",
    "KineticBands",
    "KineticCycles",
    "dataset_components",
    "kinetic_bands",
    "grf_figure",
    "kinetics_figure",
    "session_kinetics_figure",
]

#: Rows of the kinetics grid (Plug-in Gait's joint names).
KINETIC_ROWS = ("Hip", "Knee", "Ankle")
#: Columns: (output, axis, title, unit).
KINETIC_COLUMNS = (
    ("Moment", "X", "Moment, sagittal", "N·m/kg"),
    ("Moment", "Y", "Moment, frontal", "N·m/kg"),
    ("Moment", "Z", "Moment, transverse", "N·m/kg"),
    ("Power", "Z", "Power", "W/kg"),
)
#: What a positive value is, per (joint, output, axis) (internal moments; checked on
#: Movement_trial: hip and knee extensor moments and abductor moments in stance positive,
#: the ankle's plantarflexor moment positive at push-off); Plug-in Gait's own sign elsewhere.
MEANING = {
    ("Hip", "Moment", "X"): "+ extensor", ("Knee", "Moment", "X"): "+ extensor",
    ("Ankle", "Moment", "X"): "+ plantarflexor", ("Hip", "Moment", "Y"): "+ abductor",
    ("Knee", "Moment", "Y"): "+ abductor",
}  # fmt: skip
#: The ground reaction's columns: (axis, title, meaning of positive values).
GRF_COLUMNS = (("X", "Anterior–posterior", "+ forward"), ("Y", "Medial–lateral", "+ medial"),
               ("Z", "Vertical", "+ up"))  # fmt: skip
#: Line widths (points): the mean, one cycle.
MEAN_WIDTH, CYCLE_WIDTH = 1.7, 0.6
#: Size (inches) of the kinetics grid and of the ground-reaction row.
KINETICS_SIZE, GRF_SIZE = (11.0, 8.2), (11.0, 3.6)
#: Margins (inches) of the two grids: two-line y-labels before every column.
KINETIC_GRID = GridMargins(left=0.85, right=0.3, wgap=1.0, hgap=0.22)
GRF_GRID = GridMargins(left=0.85, right=0.3, wgap=0.9, hgap=0.2, bottom=0.6)


def _meaning(joint: str, output: str, axis: str) -> str:
    return MEANING.get((joint, output, axis), "Plug-in Gait sign" if output == "Moment" else "+ generated")


def dataset_components(kinetics: xr.Dataset) -> dict[str, dict[str, np.ndarray]]:
    """Side -> component without side (``"KneeMoment_X"`` N·m/kg, ``"KneePower_Z"`` W/kg,
    ``"NormalisedGRF_Z"`` % BW) -> ``(n_frames,)`` of a kinetics dataset with variables
    ``moment (side, joint, axis, frame)``, ``power (side, joint, frame)`` and ``grf (side,
    axis, frame)``."""
    out: dict[str, dict[str, np.ndarray]] = {}
    for side in (str(s) for s in kinetics["side"].values):
        parts: dict[str, np.ndarray] = {}
        if "moment" in kinetics:
            moment = kinetics["moment"].sel(side=side).transpose("joint", "axis", "frame")
            for joint in (str(j) for j in moment["joint"].values):
                for axis in (str(a) for a in moment["axis"].values):
                    parts[f"{joint}Moment_{axis}"] = np.asarray(moment.sel(joint=joint, axis=axis).values, dtype=float)
        if "power" in kinetics:
            power = kinetics["power"].sel(side=side).transpose("joint", "frame")
            for joint in (str(j) for j in power["joint"].values):
                parts[f"{joint}Power_Z"] = np.asarray(power.sel(joint=joint).values, dtype=float)
        if "grf" in kinetics:
            grf = kinetics["grf"].sel(side=side).transpose("axis", "frame")
            for axis in (str(a) for a in grf["axis"].values):
                parts[f"{STANCE_OUTPUT}_{axis}"] = np.asarray(grf.sel(axis=axis).values, dtype=float)
        out[side] = parts
    return out


def _counted(cycles: Mapping[str, np.ndarray], side: str) -> int:
    """The most cycles of ``side`` any joint moment or power of ``cycles`` has."""
    return max((len(cycles.get(f"{side}{joint}{output}_{axis}", ())) for joint in KINETIC_ROWS
                for output, axis, _, _ in KINETIC_COLUMNS), default=0)  # fmt: skip


@dataclass(frozen=True)
class KineticBands:
    """The fuzzy kinetics' α-bands over the gait cycle of a trial's counted cycles.

    Attributes:
        alphas: α-levels < 1, ascending (the widest band first).
        bands: sided component (``"LKneeMoment_X"``) -> ``(n_alpha, 2 [lower, upper],
            101)`` N·m/kg or W/kg: the mean over the side's counted cycles of each bound;
            NaN where undetermined in some cycle or not analysed in every one.
        undetermined: sided component -> ``(n_alpha, 101)`` True where the band is left
            out as undetermined (a segment frame can flip inside the balls).
        allowable: the moments' allowable-error sentences
            (:func:`~fuzzygait.markererror.fuzzy_kinetics.allowable_kinetic_error`).
        cop_error_mm: the centre-of-pressure ball's radius at α = 0, mm.
        delta_phi: per analysed component ``(label, units, cells)``: ΔΦ (Eq. 5.3, % of the
            largest |value|, over the determined frames) at each α-level < 1 from the
            highest down, "undetermined" where a frame is, "–" where none has a band.
    """

    alphas: np.ndarray
    bands: dict[str, np.ndarray]
    undetermined: dict[str, np.ndarray]
    allowable: tuple[str, ...] = ()
    cop_error_mm: float = float("nan")
    delta_phi: tuple[tuple[str, str, tuple[str, ...]], ...] = ()


def _counted_cycles(signal: np.ndarray, vertical: np.ndarray, cycles: Sequence[GaitCycle]) -> list[GaitCycle]:
    """The cycles :func:`~fuzzygait.gait.normative.kinetic_cycles` counts for ``signal``:
    on a plate in mid-stance and with a value on every point of the cycle."""
    kept = loaded_cycles(cycles, vertical)
    return [c for c in kept if np.isfinite(normalise_cycles(signal, [c], N_POINTS)).all()]


def kinetic_bands(fuzzy: xr.Dataset, components: Mapping[str, Mapping[str, np.ndarray]],
                  cycles: Mapping[str, Sequence[GaitCycle]], frames: np.ndarray) -> KineticBands | None:  # fmt: skip
    """The α-bands of every fuzzy kinetic component of ``fuzzy`` (a kinetics group) over
    the cycles the figures count (``components``: :func:`dataset_components` of the
    trial's kinetics; ``frames``: its C3D frame numbers); None without a level < 1."""
    from fuzzygait.markererror.fuzzy_kinetics import allowable_kinetic_error
    from fuzzygait.markererror.result import UNITS_COORD, kinetic_part

    alphas: np.ndarray | None = None
    bands, flags = {}, {}
    for name in (str(c) for c in fuzzy["component"].to_numpy()):
        side, base = name[:1], name[1:]
        signal, vertical = components.get(side, {}).get(base), components.get(side, {}).get(f"{STANCE_OUTPUT}_Z")
        levels = component_levels(fuzzy, name, frames)
        if signal is None or vertical is None or levels is None:
            continue
        alphas, hull, mask = levels
        kept = _counted_cycles(signal, vertical, cycles.get(side, ()))
        if not kept:
            continue
        # frames not analysed (a partial analysis) hold the measured value, so a cycle's
        # spline runs through them; the points next to them are left out below
        analysed = np.isfinite(hull).all(axis=(0, 1))
        filled = np.where(analysed, hull, np.asarray(signal, dtype=float))
        curve, band, _ = cycle_bands(signal, filled, kept, undetermined=mask & analysed)
        covered = ~_cycle_flags(~analysed[:, None], kept, N_POINTS)[..., 0].any(axis=0)
        undetermined = band_undetermined(curve, band)
        assert undetermined is not None
        band[:, :, ~covered] = np.nan
        bands[name], flags[name] = band, undetermined & covered
    if alphas is None:
        return None
    units = fuzzy[UNITS_COORD].to_numpy().astype(str)
    tolerance = float(fuzzy.attrs.get("kinetic_tolerance", 0.1))
    allowable: tuple[str, ...] = ()
    if "N·m/kg" in units:
        moments = kinetic_part(fuzzy, "N·m/kg")
        allowable = tuple(allowable_kinetic_error(moments, str(c), tolerance).sentence
                          for c in moments["component"].to_numpy())  # fmt: skip
    return KineticBands(alphas, bands, flags, allowable, float(fuzzy.attrs.get("cop_error_mm", np.nan)),
                        _delta_phi_rows(fuzzy))  # fmt: skip


def _delta_phi_rows(fuzzy: xr.Dataset) -> tuple[tuple[str, str, tuple[str, ...]], ...]:
    """:attr:`KineticBands.delta_phi` of a kinetics group."""
    from fuzzygait.markererror.analysis import relative_envelope_width, undetermined_levels
    from fuzzygait.markererror.result import UNITS_COORD, kinetic_part

    rows = []
    for units in dict.fromkeys(fuzzy[UNITS_COORD].to_numpy().astype(str)):
        part = kinetic_part(fuzzy, str(units))
        table, flags = relative_envelope_width(part), undetermined_levels(part)
        labels = dict(zip(part["component"].to_numpy().astype(str), part["label"].to_numpy().astype(str), strict=True))
        for name in table.index:
            cells = tuple("undetermined" if flags.loc[name, a] else f"{table.loc[name, a]:.0f}"
                          if np.isfinite(table.loc[name, a]) else "–" for a in table.columns)  # fmt: skip
            rows.append((labels[str(name)], str(units), cells))
    return tuple(rows)


@dataclass(frozen=True)
class KineticCycles:
    """A trial's kinetics cut into its gait cycles.

    Attributes:
        cycles: sided component (``"LKneeMoment_X"``) -> ``(n, 101)``: N·m/kg, W/kg over
            the gait cycle, % body weight over stance (:func:`~fuzzygait.gait.normative.
            kinetic_cycles`).
        counted: side -> its cycles with force-plate data; ``total`` -> all its cycles.
        foot_off: side -> mean foot off (% of the cycle) of its counted cycles.
        fuzzy: the fuzzy kinetics' bands over those cycles, None without them.
    """

    cycles: dict[str, np.ndarray]
    counted: dict[str, int] = field(default_factory=dict)
    total: dict[str, int] = field(default_factory=dict)
    foot_off: dict[str, float] = field(default_factory=dict)
    fuzzy: KineticBands | None = None

    @classmethod
    def of(cls, components: Mapping[str, Mapping[str, np.ndarray]],
           cycles: Mapping[str, Sequence[GaitCycle]]) -> KineticCycles:  # fmt: skip
        """Cut ``components`` (:func:`dataset_components`) into ``cycles`` (per side);
        the fuzzy bands are added with :func:`dataclasses.replace` and
        :func:`kinetic_bands`."""
        stacks = kinetic_cycles(components, cycles)
        counted = {side: _counted(stacks, side) for side in SIDE_STYLE}
        foot_off = {}
        for side, side_cycles in cycles.items():
            offs = [c.foot_off_percent for c in side_cycles if c.foot_off_percent is not None]
            if offs and counted.get(side):
                foot_off[side] = float(np.mean(offs))
        return cls(stacks, counted, {s: len(c) for s, c in cycles.items()}, foot_off)

    def any(self) -> bool:
        """Whether some cycle has kinetics."""
        return bool(self.cycles)


def _draw_side(ax: Axes, x: np.ndarray, stack: np.ndarray, side: str, spread: str) -> None:
    """One side's curves: ``spread`` ``"cycles"`` each cycle thin, ``"sd"`` the mean ±
    1 SD (left filled, right hatched), and the mean thick on top."""
    colour = SIDE_STYLE[side][1]
    mean, sd = cycle_statistics(stack)
    if spread == "cycles":
        for row in stack:
            ax.plot(x, row, color=colour, lw=CYCLE_WIDTH, alpha=0.55, zorder=2)
    elif np.isfinite(sd).any():
        if side == "R":
            ax.fill_between(x, mean - sd, mean + sd, facecolor="none", edgecolor=colour, hatch=_right_hatch(3), lw=0)
        else:
            ax.fill_between(x, mean - sd, mean + sd, color=colour, alpha=0.2, lw=0)
    ax.plot(x, mean, color=colour, lw=MEAN_WIDTH, ls=SIDE_LINE[side], zorder=3, gid=f"mean-{side}")


def _draw_fuzzy(ax: Axes, x: np.ndarray, band: np.ndarray, side: str, layer: float) -> None:
    """α-bands of one side (``(n_alpha, 2, n_points)``, widest first) as the angle figures
    draw them: left filled in its colour (each level one more layer; where a wider level is
    left out, its layer is added, so a level's shade is its legend swatch's), right hatched,
    the widest band's edges thin."""
    colour = SIDE_STYLE[side][1]
    for k in range(band.shape[0]):
        if side == "R":
            hatched = ax.fill_between(x, band[k, 0], band[k, 1], facecolor="none", edgecolor=colour,
                                      hatch=_right_hatch(k), lw=0, zorder=1.5)  # fmt: skip
            hatched.set_hatch_linewidth(HATCH_WIDTH)
        else:
            ax.fill_between(x, band[k, 0], band[k, 1], color=colour, alpha=layer, lw=0, zorder=1.5)
            for wider in range(k):  # a wider level left out (undetermined): its layer too, so the
                gap = ~np.isfinite(band[wider]).all(axis=0)  # shade stays the legend's of level k
                if gap.any():
                    ax.fill_between(x, np.where(gap, band[k, 0], np.nan), np.where(gap, band[k, 1], np.nan),
                                    color=colour, alpha=layer, lw=0, zorder=1.5)  # fmt: skip
    for bound in (0, 1):
        ax.plot(x, band[0, bound], color=colour, lw=0.6, ls=SIDE_LINE[side], alpha=0.9, zorder=1.6)


def _band_handles(fuzzy: KineticBands, undetermined: set[int]) -> list[Artist]:
    """Legend entries of the α-bands (per side and level) and of the undetermined strips."""
    from matplotlib.colors import to_rgba

    handles: list[Artist] = []
    layer = _band_opacity(len(fuzzy.alphas))
    for side, (name, colour) in SIDE_STYLE.items():
        if not any(c.startswith(side) and np.isfinite(b).any() for c, b in fuzzy.bands.items()):
            continue  # no band of this side drawn
        for k, alpha in enumerate(fuzzy.alphas):
            text = f"{name} α = {alpha_text(alpha)}" + (" (worst case)" if k == 0 and alpha == 0 else "")
            face = ({"facecolor": "white", "hatch": _right_hatch(k)} if side == "R"
                    else {"facecolor": to_rgba(colour, 1.0 - (1.0 - layer) ** (k + 1))})  # fmt: skip
            handles.append(Patch(edgecolor=colour, lw=0.5, label=text, **face))
    for n, k in enumerate(sorted(undetermined)):
        what = "undetermined: no band" if n == 0 else "undetermined too"
        handles.append(Patch(facecolor=(0.25, 0.25, 0.25, 1.0 - 0.75 * 0.7**n), edgecolor="0.3", hatch=HATCH, lw=0,
                             label=f"α = {alpha_text(fuzzy.alphas[k])} {what}"))  # fmt: skip
    return handles


def _panel(ax: Axes, title: str | None, ylabel: str) -> None:
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.grid(alpha=0.3)
    ax.tick_params(labelsize=8)
    ax.set_ylabel(ylabel, fontsize=7.5)
    if title:
        ax.set_title(title, fontsize=10.5)


def _empty(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=8, color="0.45")


def _handles(counts: Mapping[str, int], spread: str, normative: bool, foot_off: bool) -> list[Artist]:
    """Legend entries: per side its mean (with the cycles counted) and its spread, then
    foot off and the normative band."""
    handles: list[Artist] = []
    for side, (name, colour) in SIDE_STYLE.items():
        n = counts.get(side, 0)
        if not n:
            continue
        cycles = f"{n} cycle{'s' if n != 1 else ''} on a force plate"
        handles.append(Line2D([], [], color=colour, lw=MEAN_WIDTH, ls=SIDE_LINE[side],
                              label=f"{name}: mean of {cycles}"))  # fmt: skip
        if spread == "cycles":
            handles.append(Line2D([], [], color=colour, lw=CYCLE_WIDTH, alpha=0.55, label=f"{name}: each cycle"))
        elif n > 1:  # one cycle has no SD
            face = ({"facecolor": "white", "hatch": _right_hatch(3)} if side == "R"
                    else {"facecolor": colour, "alpha": 0.2})  # fmt: skip
            handles.append(Patch(edgecolor=colour, lw=0.5, label=f"{name}: ± 1 SD over cycles", **face))
    if foot_off:
        handles.append(Line2D([], [], color="0.2", lw=1.0, label="foot off (vertical, per side)"))
    if normative:
        handles.append(Patch(facecolor=NORMATIVE_COLOUR, edgecolor="0.6", lw=0.5, label="normative mean ± 1 SD"))
    return handles


def _kinetics_grid(cycles: Mapping[str, np.ndarray], title: str, normative: NormativeData | None, spread: str,
                   foot_off: Mapping[str, float], fuzzy: KineticBands | None = None) -> Figure:  # fmt: skip
    """Hip, knee and ankle (rows) moments in three planes and power (columns) over the
    gait cycle (axes row-major in ``fig.axes``), with ``fuzzy``'s α-bands where given."""
    x = percent_points(N_POINTS)
    fig, axes = plt.subplots(len(KINETIC_ROWS), len(KINETIC_COLUMNS), figsize=KINETICS_SIZE, sharex=True,
                             squeeze=False)  # fmt: skip
    fig.suptitle(title, fontsize=13)
    counts: dict[str, int] = {}
    seen: set[int] = set()
    any_norm = False
    for r, joint in enumerate(KINETIC_ROWS):
        for c, (output, axis, column, unit) in enumerate(KINETIC_COLUMNS):
            ax = axes[r, c]
            label = f"{joint} {output.lower()} ({unit})\n{_meaning(joint, output, axis)}"
            _panel(ax, column if r == 0 else None, label)
            any_norm = draw_normative(ax, x, normative, f"{joint}{output}_{axis}") or any_norm
            for side, percent in foot_off.items():
                ax.axvline(percent, color=SIDE_STYLE[side][1], lw=1.0, ls=SIDE_LINE[side], alpha=0.85, zorder=1)
            drawn = False
            strips: list[tuple[int, str, np.ndarray]] = []
            for slot, side in enumerate(SIDE_STYLE):
                stack = cycles.get(f"{side}{joint}{output}_{axis}")
                if stack is None or not len(stack):
                    continue
                if fuzzy is not None and (band := fuzzy.bands.get(f"{side}{joint}{output}_{axis}")) is not None:
                    _draw_fuzzy(ax, x, band, side, _band_opacity(len(fuzzy.alphas)))
                    flags = fuzzy.undetermined[f"{side}{joint}{output}_{axis}"]
                    if flags.any():
                        strips.append((slot, SIDE_STYLE[side][1], flags))
                        seen.update(int(k) for k in np.flatnonzero(flags.any(axis=1)))
                _draw_side(ax, x, stack, side, spread)
                counts[side] = max(counts.get(side, 0), len(stack))
                drawn = True
            _draw_undetermined(ax, x, strips)
            if not drawn:
                _empty(ax, "no cycle on a force plate")
            ax.set_xlim(0, 100)
            if r == len(KINETIC_ROWS) - 1:
                ax.set_xlabel("gait cycle (%)", fontsize=8)
    handles = _handles(counts, spread, any_norm, bool(foot_off))
    if fuzzy is not None and fuzzy.bands:
        handles += _band_handles(fuzzy, seen)
    return _add_legend(fig, handles, ncol=3, margins=KINETIC_GRID)


def kinetics_figure(kinetics: KineticCycles, title: str, normative: NormativeData | None = None) -> Figure:
    """A trial's joint moments and powers over the gait cycle: per side every cycle on a
    force plate (thin) and their mean (thick; left solid, right dashed), the sides' mean
    foot off, the normative band where given, the fuzzy kinetics' α-bands where analysed
    (:attr:`KineticCycles.fuzzy`).  Axes ``fig.axes`` row-major (rows
    :data:`KINETIC_ROWS`, columns :data:`KINETIC_COLUMNS`); each mean line carries the
    gid ``"mean-L"``/``"mean-R"``."""
    return _kinetics_grid(kinetics.cycles, title, normative, "cycles", kinetics.foot_off, kinetics.fuzzy)


def session_kinetics_figure(cycles: Mapping[str, np.ndarray], title: str,
                            normative: NormativeData | None = None) -> Figure | None:  # fmt: skip
    """A session's joint moments and powers: per side the mean ± 1 SD over ``cycles``
    (sided component -> ``(n_cycles, 101)``, every counted cycle of every trial stacked);
    None when no cycle has kinetics."""
    if not any(_counted(cycles, side) for side in SIDE_STYLE):
        return None
    return _kinetics_grid(cycles, title, normative, "sd", {})


def grf_figure(cycles: Mapping[str, np.ndarray], title: str, normative: NormativeData | None = None,
               spread: str = "cycles") -> Figure | None:  # fmt: skip
    """The ground reaction over stance (0 and 100 %: the first and last frame of the foot's
    load on the plate), % body weight,
    one panel per component (:data:`GRF_COLUMNS`): per side each cycle thin and the mean
    (``spread`` ``"sd"``: mean ± 1 SD, the session's); None without a cycle on a plate."""
    if not any(f"{s}{STANCE_OUTPUT}_Z" in cycles for s in SIDE_STYLE):
        return None
    x = percent_points(N_POINTS)
    fig, axes = plt.subplots(1, len(GRF_COLUMNS), figsize=GRF_SIZE, squeeze=False)
    fig.suptitle(title, fontsize=13)
    counts: dict[str, int] = {}
    any_norm = False
    for c, (axis, column, meaning) in enumerate(GRF_COLUMNS):
        ax = axes[0, c]
        _panel(ax, column, f"ground reaction (% body weight)\n{meaning}")
        any_norm = draw_normative(ax, x, normative, f"{STANCE_OUTPUT}_{axis}") or any_norm
        for side in SIDE_STYLE:
            stack = cycles.get(f"{side}{STANCE_OUTPUT}_{axis}")
            if stack is not None and len(stack):
                _draw_side(ax, x, stack, side, spread)
                counts[side] = max(counts.get(side, 0), len(stack))
        ax.set_xlim(0, 100)
        ax.set_xlabel("stance on the plate (%)", fontsize=8)
    return _add_legend(fig, _handles(counts, spread, any_norm, False), ncol=3, margins=GRF_GRID)
