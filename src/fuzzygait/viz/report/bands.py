"""The report's numbers: a trial's angles and hulls on its frames (:class:`TrialData`),
the ΔΦ table and the key numbers of a trial (determined bands first), its index entry,
and the order of the angle components.  The gait-cycle bands (undetermined points left
out): :mod:`fuzzygait.viz.report.normalised_bands`.

The fuzzy marker-error dataset is read only through :mod:`fuzzygait.markererror.result`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
import pandas as pd

from fuzzygait.core.findings import Finding
from fuzzygait.core.names import is_flexion
from fuzzygait.gait.cycles import GaitCycle, gait_cycles
from fuzzygait.kinematics.labels import parse_component
from fuzzygait.markererror.analysis import undetermined_levels
from fuzzygait.markererror.result import MarkerErrorResult
from fuzzygait.mocap.marker_placement import moved_angles, moved_segments
from fuzzygait.viz.layout import ANGLE_ROWS, SIDE_STYLE
from fuzzygait.viz.report.normalised_bands import ALPHA_ONE, component_levels

if TYPE_CHECKING:
    import xarray as xr

    from fuzzygait.core.trial import Event, Trial
    from fuzzygait.io.subject import SubjectParameters
    from fuzzygait.kinematics import CGMResult
    from fuzzygait.mocap.gaps import Gap
    from fuzzygait.viz.report.allowable import AllowableSummary


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
    def notes(self) -> list[Finding]: ...
    @property
    def warnings(self) -> list[str]: ...


class TrialAnalysis(Protocol):
    """What the report reads of a trial's marker-error analysis
    (:class:`fuzzygait.workflows.marker_uncertainty.MarkerErrorAnalysis`)."""

    @property
    def run(self) -> ReportRun: ...
    @property
    def fuzzy(self) -> xr.Dataset | None: ...  # None: angles only (no uncertainty analysis)
    @property
    def delta_phi(self) -> pd.DataFrame: ...
    @property
    def notes(self) -> list[Finding]: ...
    @property
    def result(self) -> MarkerErrorResult | None: ...  # the bands, allowable error and per-source bands


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


@dataclass
class TrialData:
    """Angles, hulls and cycles of one trial, aligned on the trial's frames."""

    run: ReportRun
    fuzzy: xr.Dataset | None  # None: angles only, no bands
    alphas: np.ndarray
    cycles: dict[str, list[GaitCycle]]
    result: MarkerErrorResult | None = None  # the whole result (per-source bands, allowable error)

    @classmethod
    def of(cls, analysis: TrialAnalysis) -> TrialData:
        """The report data of one analysed trial (α-levels below 1, cycles per side)."""
        run = analysis.run
        alphas = np.zeros(0) if analysis.fuzzy is None else np.asarray(analysis.fuzzy["alpha"].values, dtype=float)
        alphas = np.sort(alphas[alphas < ALPHA_ONE])
        cycles = {side: gait_cycles(run.trial, run.events, side) for side in SIDE_STYLE}
        return cls(run, analysis.fuzzy, alphas, cycles, analysis.result if analysis.fuzzy is not None else None)

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

    def _report_levels(self, name: str) -> tuple[np.ndarray, np.ndarray] | None:
        """Hull and undetermined mask of ``name`` at the report's α-levels."""
        if self.fuzzy is None:
            return None
        found = component_levels(self.fuzzy, name, self.run.trial.frames)
        if found is None:
            return None
        alphas, values, mask = found
        if alphas.shape != self.alphas.shape or not np.allclose(alphas, self.alphas):
            # only the α-levels common to the whole report
            index = [int(np.argmin(abs(alphas - a))) for a in self.alphas]
            values, mask = values[index], mask[index]
        return values, mask

    def hull(self, name: str) -> np.ndarray | None:
        """``(n_alpha, 2, n_frames)`` hull of ``name`` at the report's α-levels (as
        computed, undetermined bounds included), or None when it was not analysed."""
        found = self._report_levels(name)
        return None if found is None else found[0]

    def undetermined(self, name: str) -> np.ndarray | None:
        """``(n_alpha, n_frames)`` True where the band of ``name`` is undetermined (the
        segment frame can flip within the α-level's balls), or None when not analysed."""
        found = self._report_levels(name)
        return None if found is None else found[1]

    def determined_hull(self, name: str) -> np.ndarray | None:
        """:meth:`hull` with NaN where the band is undetermined: what is drawn."""
        found = self._report_levels(name)
        if found is None:
            return None
        values, mask = found
        return np.where(mask[:, None, :], np.nan, values)

    def n_cycles(self) -> dict[str, int]:
        """Gait cycles per side."""
        return {side: len(c) for side, c in self.cycles.items()}


# ============================================================================ numbers


@dataclass
class DeltaPhiTable:
    """The ΔΦ table of a trial: rows in report order, α columns descending (as Table
    5.2).

    Attributes:
        values: ΔΦ (%) over the determined frames (NaN: not available).
        undetermined: True where the α-level is undetermined at some frame
            (:func:`~fuzzygait.markererror.analysis.undetermined_levels`): the cell reads
            "undetermined", whatever ``values`` holds.
        widest: widest band (deg) over the determined frames per α-level (NaN: none).
        undetermined_frames: frames undetermined per α-level.
        peak: reference max |Φ| (deg) of the measured angle per row.
        n_frames: frames of the trial.
    """

    values: pd.DataFrame
    undetermined: pd.DataFrame
    widest: pd.DataFrame
    undetermined_frames: pd.DataFrame
    peak: pd.Series
    n_frames: int

    @property
    def alphas(self) -> list[float]:
        """The α-levels of the columns (descending)."""
        return [float(a) for a in self.values.columns]

    @property
    def components(self) -> list[str]:
        """The rows (angle components, report order)."""
        return [str(n) for n in self.values.index]

    def is_undetermined(self, name: str, alpha: float) -> bool:
        """Whether ``name``'s band at ``alpha`` is undetermined at some frame."""
        return bool(self.undetermined[alpha][name])

    def value(self, name: str, alpha: float) -> float:
        """ΔΦ (%) of ``name`` at ``alpha`` over the determined frames (NaN: none)."""
        return float(self.values[alpha][name])

    def widest_band(self, name: str, alpha: float) -> float:
        """Widest band (deg) of ``name`` at ``alpha`` over the determined frames."""
        return float(self.widest[alpha][name])

    def frames_undetermined(self, name: str, alpha: float) -> int:
        """Frames where ``name``'s band at ``alpha`` is undetermined."""
        return int(self.undetermined_frames[alpha][name])

    def determined(self, alpha: float) -> pd.Series:
        """ΔΦ at ``alpha`` of the rows determined at every frame with a finite value."""
        column = self.values[alpha].astype(float)
        keep = ~self.undetermined[alpha].astype(bool) & np.isfinite(column)
        return column[keep]


def delta_phi_table(analysis: TrialAnalysis, data: TrialData) -> DeltaPhiTable:
    """The ΔΦ table of a trial (:class:`DeltaPhiTable`) from its analysis' ΔΦ (Eq. 5.3,
    over determined frames) and undetermined α-levels."""
    values = analysis.delta_phi.copy()
    alphas = sorted((float(c) for c in values.columns), reverse=True)
    values.columns = pd.Index([float(c) for c in values.columns])
    names = sorted((str(n) for n in values.index), key=component_order)
    values = values.reindex(index=names, columns=alphas)
    levels = undetermined_levels(analysis.fuzzy) if analysis.fuzzy is not None else pd.DataFrame()
    level_alphas = [float(c) for c in levels.columns]
    flags = np.zeros((len(names), len(alphas)), dtype=bool)
    widest = np.full((len(names), len(alphas)), np.nan)
    frames = np.zeros((len(names), len(alphas)), dtype=int)
    peak = np.full(len(names), np.nan)
    for i, name in enumerate(names):
        for j, alpha in enumerate(alphas):
            match = [k for k, c in enumerate(level_alphas) if abs(c - alpha) <= 1e-9]
            if name in levels.index and match:
                flags[i, j] = bool(levels.loc[name].iloc[match[0]])
        signal = data.angle(name)
        if signal is not None:
            peak[i] = float(np.nanmax(np.abs(signal)))
        hull, mask = data.determined_hull(name), data.undetermined(name)
        if hull is None or mask is None:
            continue
        for k, alpha in enumerate(data.alphas):
            column = [j for j, c in enumerate(alphas) if abs(c - alpha) <= 1e-9]
            if not column:
                continue
            j = column[0]
            width = hull[k, 1] - hull[k, 0]
            if np.isfinite(width).any():
                widest[i, j] = float(np.nanmax(width))
            frames[i, j] = int(mask[k].sum())
            flags[i, j] = flags[i, j] or bool(mask[k].any())
    return DeltaPhiTable(
        values,
        pd.DataFrame(flags, index=names, columns=alphas),
        pd.DataFrame(widest, index=names, columns=alphas),
        pd.DataFrame(frames, index=names, columns=alphas),
        pd.Series(peak, index=names, dtype=float),
        data.run.trial.n_frames,
    )


#: A summary number: (value, component, α-level).
Summary = tuple[float, str, float]


@dataclass
class Headline:
    """The key numbers of a trial, determined bands first.

    Attributes:
        largest: largest ΔΦ (%) among the hip/knee/ankle flexion angles (as Table 5.2;
            any angle when none was analysed) whose band is determined at every frame,
            at the smallest α-level where one is.
        widest: widest band (deg) among the angles determined at every frame, at the
            smallest α-level where one is.
        alpha: the smallest α-level of the trial.
        undetermined: angle components undetermined at ``alpha`` (report order).
        n_components: angle components analysed.
        flexion_undetermined: the flexion angles among ``undetermined``.
    """

    largest: Summary | None = None
    widest: Summary | None = None
    alpha: float | None = None
    undetermined: list[str] = field(default_factory=list)
    n_components: int = 0
    flexion_undetermined: list[str] = field(default_factory=list)


def headline(table: DeltaPhiTable) -> Headline:
    """The key numbers of a trial (:class:`Headline`) from its ΔΦ table."""
    alphas = sorted(table.alphas)
    if not alphas or not table.components:
        return Headline()
    flexion = [n for n in table.components if is_flexion(n)]
    largest = widest = None
    for alpha in alphas:
        determined = table.determined(alpha)
        candidates = determined.loc[[n for n in flexion if n in determined.index]] if flexion else determined
        if largest is None and not candidates.empty:
            name = str(candidates.idxmax())
            largest = (float(candidates[name]), name, alpha)
        widths = table.widest[alpha].astype(float)
        widths = widths[~table.undetermined[alpha].astype(bool) & np.isfinite(widths)]
        if widest is None and not widths.empty:
            name = str(widths.idxmax())
            widest = (float(widths[name]), name, alpha)
    lowest = alphas[0]
    undetermined = [n for n in table.components if table.is_undetermined(n, lowest)]
    return Headline(largest, widest, lowest, undetermined, len(table.components),
                    [n for n in undetermined if n in flexion])  # fmt: skip


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
    headline: Headline = field(default_factory=Headline)
    allowable: AllowableSummary | None = None
    gps: float | None = None  # overall Gait Profile Score (deg), with normative data
    moved: tuple[str, ...] = ()  # segments whose markers moved since the static trial
    run_warnings: tuple[str, ...] = ()  # the angle run's warnings (a contradicted marker diameter, ...)

    @property
    def ok(self) -> bool:
        """Whether the trial has a page (no error)."""
        return self.error is None

    @property
    def data_warnings(self) -> list[str]:
        """Warnings about the trial's data for the index and session pages: the segments
        whose markers moved since the static trial (:func:`~fuzzygait.mocap.marker_placement.moved_markers`),
        then the angle run's own warnings (``AnglesRun.warnings``)."""
        if not self.moved:
            return list(self.run_warnings)
        moved = (f"markers moved since the static trial ({', '.join(self.moved)}): the {moved_angles(self.moved)} "
                 "are unreliable (the trial page's data quality notes say which markers)")  # fmt: skip
        return [moved, *self.run_warnings]

    @property
    def max_delta_phi(self) -> Summary | None:
        """Largest determined flexion ΔΦ: (value %, component, α)."""
        return self.headline.largest

    @property
    def widest_band(self) -> Summary | None:
        """Widest determined band: (deg, component, α)."""
        return self.headline.widest

    @classmethod
    def of(cls, source: Path, page: str, data: TrialData, table: DeltaPhiTable,
           allowable: AllowableSummary | None = None, gaps: Sequence[Gap] | None = None,
           gps: float | None = None) -> TrialEntry:  # fmt: skip
        """The index entry of a trial drawn on ``page`` from ``data``, its ΔΦ table and its
        allowable-marker-error table (:mod:`~fuzzygait.viz.report.allowable`); ``gaps``:
        the gaps counted (default every gap of the run; the report passes those of the
        markers the model uses), ``gps``: the overall Gait Profile Score (deg)."""
        run = data.run
        gaps = run.gaps if gaps is None else list(gaps)
        filled = sum(g.filled for g in gaps)
        return cls(
            source=source,
            page=page,
            n_frames=run.trial.n_frames,
            rate=run.trial.rate,
            cycles=data.n_cycles(),
            gaps_filled=filled,
            gaps_left=len(gaps) - filled,
            headline=headline(table),
            allowable=allowable,
            gps=gps,
            moved=tuple(moved_segments(run.notes)),
            run_warnings=tuple(run.warnings),
        )
