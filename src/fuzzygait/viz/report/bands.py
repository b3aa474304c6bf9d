"""The report's numbers: gait-cycle bands, the ΔΦ table and the summary numbers of a
trial, and the clinical labels of the angle components.

The fuzzy marker-error dataset is read only through :mod:`fuzzygait.markererror.result`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
import pandas as pd

from fuzzygait.gait.cycles import GaitCycle, gait_cycles, normalise_cycles
from fuzzygait.kinematics.labels import parse_component
from fuzzygait.markererror.result import angle_components, component_hull
from fuzzygait.viz.layout import ANGLE_ROWS, SIDE_STYLE

if TYPE_CHECKING:
    import xarray as xr

    from fuzzygait.core.trial import Event, Trial
    from fuzzygait.io.subject import SubjectParameters
    from fuzzygait.kinematics import CGMResult
    from fuzzygait.mocap.gaps import Gap

#: Samples per normalised gait cycle (0, 1, ..., 100 %).
N_POINTS = 101
#: α-levels closer to 1 than this count as the measured curve.
_ALPHA_ONE = 1.0 - 1e-9


class ReportRun(Protocol):
    """What the report reads of a trial's joint-angle run
    (:class:`fuzzygait.workflows.angles.AnglesRun`)."""

    @property
    def raw(self) -> Trial: ...
    @property
    def trial(self) -> Trial: ...
    @property
    def subject(self) -> SubjectParameters: ...
    @property
    def result(self) -> CGMResult: ...
    @property
    def gaps(self) -> list[Gap]: ...
    @property
    def events(self) -> list[Event]: ...
    @property
    def event_source(self) -> str: ...
    @property
    def notes(self) -> list[str]: ...


class TrialAnalysis(Protocol):
    """What the report reads of a trial's marker-error analysis
    (:class:`fuzzygait.workflows.marker_uncertainty.MarkerErrorAnalysis`)."""

    @property
    def run(self) -> ReportRun: ...
    @property
    def fuzzy(self) -> xr.Dataset: ...
    @property
    def delta_phi(self) -> pd.DataFrame: ...
    @property
    def notes(self) -> list[str]: ...


# ============================================================================ labels
def alpha_text(alpha: float) -> str:
    """An α-level as written in the report (``0.25``, ``0``)."""
    return f"{alpha:g}"


def component_order(name: str) -> tuple[int, int, int, str]:
    """Sort key: joint rows of the report, then plane, then side."""
    parsed = parse_component(name)
    rows = [base for base, _ in ANGLE_ROWS]
    if parsed is None or parsed[1] not in rows:
        return (len(rows), 0, 0, name)
    side, base, axis = parsed
    return (rows.index(base), "XYZ".index(axis), "LR".index(side), name)


def grid_components() -> list[str]:
    """Every angle component of the report grid (joint rows x planes x sides)."""
    return [f"{side}{base}_{axis}" for base, _ in ANGLE_ROWS for axis in "XYZ" for side in "LR"]


# ============================================================================ bands
def _hulls(fuzzy: xr.Dataset, name: str, frames: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(alphas < 1 ascending, hull (n_alpha, 2 [lower, upper], n_frames) deg)`` of one
    angle component on ``frames``, or None when the analysis did not cover it."""
    if name not in angle_components(fuzzy):
        return None
    data = component_hull(fuzzy, name)
    if "frame" in data.dims and "frame" in fuzzy.coords:
        data = data.reindex(frame=np.asarray(frames))
    data = data.sel(bound=["lower", "upper"]).transpose("alpha", "bound", "frame")
    alphas = np.asarray(data["alpha"].values, dtype=float)
    keep = alphas < _ALPHA_ONE
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


@dataclass
class TrialData:
    """Angles, hulls and cycles of one trial, aligned on the trial's frames."""

    run: ReportRun
    fuzzy: xr.Dataset
    alphas: np.ndarray
    cycles: dict[str, list[GaitCycle]]

    @classmethod
    def of(cls, analysis: TrialAnalysis) -> TrialData:
        """The report data of one analysed trial (α-levels below 1, cycles per side)."""
        run = analysis.run
        alphas = np.asarray(analysis.fuzzy["alpha"].values, dtype=float)
        alphas = np.sort(alphas[alphas < _ALPHA_ONE])
        cycles = {side: gait_cycles(run.trial, run.events, side) for side in SIDE_STYLE}
        return cls(run, analysis.fuzzy, alphas, cycles)

    def angle(self, name: str) -> np.ndarray | None:
        """The measured angle component ``name`` (deg), or None when not computed."""
        parsed = parse_component(name)
        if parsed is None:
            return None
        side, base, axis = parsed
        values = self.run.result.angles.get(f"{side}{base}")
        if values is None or f"{side}{base}" in self.run.result.unavailable:
            return None
        column = np.asarray(values, dtype=float)[:, "XYZ".index(axis)]
        return None if not np.isfinite(column).any() else column

    def hull(self, name: str) -> np.ndarray | None:
        """``(n_alpha, 2, n_frames)`` hull of ``name`` at the report's α-levels, or None
        when it was not analysed."""
        found = _hulls(self.fuzzy, name, self.run.trial.frames)
        if found is None:
            return None
        alphas, values = found
        if alphas.shape != self.alphas.shape or not np.allclose(alphas, self.alphas):
            # only the α-levels common to the whole report
            index = [int(np.argmin(abs(alphas - a))) for a in self.alphas]
            values = values[index]
        return values

    def n_cycles(self) -> dict[str, int]:
        """Gait cycles per side."""
        return {side: len(c) for side, c in self.cycles.items()}


# ============================================================================ numbers
def delta_phi_table(analysis: TrialAnalysis, data: TrialData) -> pd.DataFrame:
    """ΔΦ rows in report order, α columns descending (as Table 5.2), plus the reference
    max |Φ| of the measured angle and the widest band at the smallest α."""
    table = analysis.delta_phi.copy()
    table.columns = [float(c) for c in table.columns]
    table = table[sorted(table.columns, reverse=True)]
    table = table.loc[sorted(table.index, key=component_order)]
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


#: A summary number: (value, component, α-level).
Summary = tuple[float, str, float]


def summary_numbers(table: pd.DataFrame) -> tuple[Summary | None, Summary | None]:
    """Largest ΔΦ at the smallest α (sagittal hip/knee/ankle when present, as in
    Table 5.2, else any angle) and the widest band (deg) at the smallest α."""
    alpha_columns = [c for c in table.columns if isinstance(c, float)]
    if not alpha_columns or table.empty:
        return None, None
    lowest = float(min(alpha_columns))
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
    max_delta_phi: Summary | None = None  # (value %, component, alpha)
    widest_band: Summary | None = None  # (deg, component, alpha)

    @property
    def ok(self) -> bool:
        """Whether the trial has a page (no error)."""
        return self.error is None

    @classmethod
    def of(cls, source: Path, page: str, data: TrialData, table: pd.DataFrame) -> TrialEntry:
        """The index entry of a trial drawn on ``page`` from ``data`` and its ΔΦ table."""
        run = data.run
        largest, widest = summary_numbers(table)
        filled = sum(g.filled for g in run.gaps)
        return cls(
            source=source,
            page=page,
            n_frames=run.trial.n_frames,
            rate=run.trial.rate,
            cycles=data.n_cycles(),
            gaps_filled=filled,
            gaps_left=len(run.gaps) - filled,
            max_delta_phi=largest,
            widest_band=widest,
        )
