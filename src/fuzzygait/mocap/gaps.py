"""Gap filling of marker trajectories by local cubic splines.

A marker sample is *missing* when any of its x, y, z coordinates is not finite (the three
coordinates are always treated together).  A *gap* is a maximal run of missing samples of
one marker.  :func:`fill_gaps` fills a gap only when

* it is *interior*: valid samples exist both before and after it (never extrapolate, so
  gaps touching the first or last sample stay missing);
* it lasts at most ``max_gap`` frames;
* at least :data:`MIN_VALID_EACH_SIDE` (= 2) valid samples lie on each side of it, counted
  up to the nearest gap that is not fillable (start/end gap or longer than ``max_gap``).

The fill is a not-a-knot cubic spline (:class:`scipy.interpolate.CubicSpline`) with the
sample index as abscissa, fitted to x, y and z together through the valid samples of a
*window* around the gap: up to :data:`WINDOW_VALID_SAMPLES` (= 30) valid samples on each
side, never reaching past a non-fillable gap.  The spline passes through the valid samples,
so valid samples are returned bit-identical; only samples inside filled gaps change.

Why a window: a cubic spline is local in effect -- the influence of a knot on the curve
decays by a factor of about 2 - sqrt(3) ~= 0.27 per knot -- so 30 samples on each side
gives the same values as a spline through the whole trajectory to far below 1e-12 of the
signal, while the cost and the dependence on distant (possibly mislabelled) data stay
bounded.  Neighbouring gaps whose windows overlap (fewer than 2 x 30 valid samples apart)
share one spline through the union of their windows; for the reason just given this
differs from separate fits only at round-off level and keeps the work linear in the
trial length even when gaps are dense.

Samples that stay missing are returned NaN in all three coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline

from fuzzygait.errors import ParameterError
from fuzzygait.io.trial import Trial

#: Valid samples used on each side of a gap for the spline fit (at most).
WINDOW_VALID_SAMPLES = 30
#: Valid samples needed on each side of a gap to fill it.
MIN_VALID_EACH_SIDE = 2

Position = Literal["interior", "start", "end", "all"]


class GapRun(NamedTuple):
    """A contiguous run of missing samples found by :func:`find_gaps`.

    Attributes:
        start: 0-based index of the first missing sample.
        length: number of missing samples (frames).
        position: ``"interior"`` (valid samples on both sides), ``"start"`` (touches the
            first sample), ``"end"`` (touches the last sample) or ``"all"`` (every sample
            is missing).
    """

    start: int
    length: int
    position: Position

    @property
    def stop(self) -> int:
        """0-based index one past the last missing sample."""
        return self.start + self.length


@dataclass(frozen=True)
class Gap:
    """One gap of one marker, as reported by :func:`fill_gaps`.

    Attributes:
        marker: marker label.
        start: 0-based sample index of the first missing sample.
        length: number of missing samples (frames).
        filled: whether the gap was filled.
        reason: ``""`` when filled, else why not: ``"marker never visible"``,
            ``"at start of trial"``, ``"at end of trial"``, ``"longer than max_gap=N"`` or
            ``"too few valid samples (need 2 on each side)"``.
    """

    marker: str
    start: int
    length: int
    filled: bool
    reason: str = ""


def find_gaps(mask: np.ndarray) -> list[GapRun]:
    """Contiguous runs of ``True`` in a 1-D missing-sample mask.

    Args:
        mask: ``(n_frames,)`` boolean, True where the sample is missing.

    Returns:
        One :class:`GapRun` ``(start, length, position)`` per run, in time order.
    """
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim != 1:
        raise ParameterError(f"mask must be one-dimensional; got shape {mask.shape}")
    n = mask.size
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    stops = np.flatnonzero(edges == -1)
    runs = []
    for start, stop in zip(starts.tolist(), stops.tolist(), strict=True):
        if start == 0 and stop == n:
            position: Position = "all"
        elif start == 0:
            position = "start"
        elif stop == n:
            position = "end"
        else:
            position = "interior"
        runs.append(GapRun(start, stop - start, position))
    return runs


def _check_max_gap(max_gap: object) -> int:
    if isinstance(max_gap, bool) or not isinstance(max_gap, int | np.integer) or max_gap < 0:
        raise ParameterError(
            f"max_gap must be a whole number of frames >= 0 (0 fills nothing); got {max_gap!r}"
        )
    return int(max_gap)


def _unfillable_reason(run: GapRun, max_gap: int) -> str:
    """Reason a gap cannot be filled from its position and length alone ('' if it may be)."""
    if run.position == "all":
        return "marker never visible"
    if run.position == "start":
        return "at start of trial"
    if run.position == "end":
        return "at end of trial"
    if run.length > max_gap:
        return f"longer than max_gap={max_gap}"
    return ""


def _fill_marker(
    values: np.ndarray, missing: np.ndarray, label: str, max_gap: int
) -> tuple[np.ndarray | None, np.ndarray | None, list[Gap]]:
    """Fill one ``(n_frames, 3)`` trajectory.

    Returns the sample indices filled, their ``(k, 3)`` values and the gap reports.
    """
    runs = find_gaps(missing)
    if not runs:
        return None, None, []
    n = missing.size
    valid_index = np.flatnonzero(~missing)
    # n_valid_before[i] = number of valid samples in [0, i); also the position in
    # valid_index of the first valid sample at or after i.
    n_valid_before = np.concatenate(([0], np.cumsum(~missing)))

    reasons = [_unfillable_reason(run, max_gap) for run in runs]
    # Segment bounds: each run's window may not reach past the nearest unfillable gaps.
    seg_lo = np.zeros(len(runs), dtype=int)
    seg_hi = np.full(len(runs), n, dtype=int)
    lo = 0
    for i, run in enumerate(runs):
        seg_lo[i] = lo
        if reasons[i]:
            lo = run.stop
    hi = n
    for i in range(len(runs) - 1, -1, -1):
        seg_hi[i] = hi
        if reasons[i]:
            hi = runs[i].start

    fillable = []
    for i, run in enumerate(runs):
        if reasons[i]:
            continue
        left = n_valid_before[run.start] - n_valid_before[seg_lo[i]]
        right = n_valid_before[seg_hi[i]] - n_valid_before[run.stop]
        if min(left, right) < MIN_VALID_EACH_SIDE:
            reasons[i] = f"too few valid samples (need {MIN_VALID_EACH_SIDE} on each side)"
        else:
            fillable.append(i)

    # Group fillable gaps whose windows overlap; one spline per group.
    groups: list[list[int]] = []
    for i in fillable:
        if groups:
            prev = runs[groups[-1][-1]]
            between = n_valid_before[runs[i].start] - n_valid_before[prev.stop]
            if seg_lo[i] == seg_lo[groups[-1][-1]] and between < 2 * WINDOW_VALID_SAMPLES:
                groups[-1].append(i)
                continue
        groups.append([i])

    filled_index, filled_values = [], []
    for group in groups:
        first, last = runs[group[0]], runs[group[-1]]
        a = max(
            n_valid_before[first.start] - WINDOW_VALID_SAMPLES,
            n_valid_before[seg_lo[group[0]]],
        )
        b = min(
            n_valid_before[last.stop] + WINDOW_VALID_SAMPLES,
            n_valid_before[seg_hi[group[-1]]],
        )
        knots = valid_index[a:b]
        spline = CubicSpline(knots, values[knots], axis=0, bc_type="not-a-knot")
        where = np.concatenate([np.arange(runs[i].start, runs[i].stop) for i in group])
        filled_index.append(where)
        filled_values.append(spline(where))

    gaps = [
        Gap(label, run.start, run.length, filled=not reason, reason=reason)
        for run, reason in zip(runs, reasons, strict=True)
    ]
    if not filled_index:
        return None, None, gaps
    return np.concatenate(filled_index), np.concatenate(filled_values), gaps


def fill_gaps(
    markers: np.ndarray, labels: Sequence[str], max_gap: int = 10
) -> tuple[np.ndarray, list[Gap]]:
    """Fill short interior gaps of marker trajectories with local cubic splines.

    See the module docstring for the method.  The input is never modified.

    Args:
        markers: ``(n_frames, n_markers, 3)`` positions in mm; a sample is missing when
            any coordinate is NaN (or infinite).
        labels: one marker label per column, used in the report.
        max_gap: longest gap to fill, in frames (samples); ``0`` fills nothing.

    Returns:
        The filled copy of ``markers`` (mm; samples left missing are NaN in x, y and z)
        and one :class:`Gap` per gap, ordered by marker column then start.

    Raises:
        ParameterError: for a ``max_gap`` that is not an integer >= 0, a wrongly shaped
            array, or a label count that does not match the marker columns.
    """
    max_gap = _check_max_gap(max_gap)
    out = np.array(markers, dtype=float)  # always a copy
    if out.ndim != 3 or out.shape[2] != 3:
        raise ParameterError(
            f"markers must have shape (frames, markers, 3) in mm; got {out.shape}"
        )
    labels = list(labels)
    if len(labels) != out.shape[1]:
        raise ParameterError(
            f"labels: {len(labels)} labels for {out.shape[1]} marker columns; give one each"
        )
    missing = ~np.all(np.isfinite(out), axis=2)
    out[missing] = np.nan
    gaps: list[Gap] = []
    for m in np.flatnonzero(missing.any(axis=0)):
        where, values, marker_gaps = _fill_marker(out[:, m], missing[:, m], labels[m], max_gap)
        gaps.extend(marker_gaps)
        if where is not None:
            out[where, m] = values
    return out, gaps


def fill_trial_gaps(trial: Trial, max_gap: int = 10) -> tuple[Trial, list[Gap]]:
    """:func:`fill_gaps` applied to a trial's markers.

    Args:
        trial: the trial (not modified).
        max_gap: longest gap to fill, in frames; ``0`` fills nothing.

    Returns:
        A new trial whose notes end with a summary such as
        ``"gap filling: 5 of 7 gaps filled (max_gap=10 frames)"``, and the gap report.
    """
    markers, gaps = fill_gaps(trial.markers, trial.marker_labels, max_gap)
    n_filled = sum(gap.filled for gap in gaps)
    note = f"gap filling: {n_filled} of {len(gaps)} gaps filled (max_gap={max_gap} frames)"
    return trial.with_markers(markers, note=note), gaps


def gap_report_table(gaps: Sequence[Gap]) -> pd.DataFrame:
    """The gap report as a table with columns marker, start, length, filled, reason."""
    return pd.DataFrame(
        {
            "marker": pd.Series([g.marker for g in gaps], dtype=object),
            "start": pd.Series([g.start for g in gaps], dtype="int64"),
            "length": pd.Series([g.length for g in gaps], dtype="int64"),
            "filled": pd.Series([g.filled for g in gaps], dtype=bool),
            "reason": pd.Series([g.reason for g in gaps], dtype=object),
        }
    )
