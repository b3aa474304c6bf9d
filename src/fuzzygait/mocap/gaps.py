"""Gap filling of marker trajectories: local cubic splines and inter-marker patterns.

A marker sample is *missing* when any of its x, y, z coordinates is not finite (the three
coordinates are always treated together).  A *gap* is a maximal run of missing samples of
one marker.  :func:`fill_gaps` fills a gap only when

* it is *interior*: valid samples exist both before and after it (never extrapolate, so
  gaps touching the first or last sample stay missing);
* it lasts at most ``max_gap`` frames;
* at least :data:`~fuzzygait.mocap.gap_plan.MIN_VALID_EACH_SIDE` (= 2) valid samples lie
  on each side of it, counted up to the nearest gap that is not fillable (start/end gap
  or longer than ``max_gap``).

Methods (``method=``):

``"spline"``
    A not-a-knot cubic spline (:class:`scipy.interpolate.CubicSpline`) with the sample
    index as abscissa, fitted to x, y and z together through the valid samples of a
    *window* around the gap: up to :data:`~fuzzygait.mocap.gap_plan.WINDOW_VALID_SAMPLES`
    (= 30) valid samples on each side, never reaching past a non-fillable gap.
``"pattern"``
    A linear regression of the marker on nearby markers visible throughout the gap and
    its window (:mod:`fuzzygait.mocap.pattern_fill`), plus the same windowed spline
    through the regression's residual, so that the fill meets the data at the gap
    edges.  It follows movement inside the gap that the marker's own samples cannot
    show (a foot's swing).  Where no regression is possible (fewer than 3 other markers
    visible over the gap and its window, or too few training frames) the gap is filled
    by the spline and the report says why.
``"auto"`` (default)
    Per gap, whichever of the two refills :data:`~fuzzygait.mocap.pattern_gaps.PSEUDO_GAPS`
    (= 4) pseudo-gaps better: runs of the same length cut into the marker's own valid samples within the
    regression's training range (about +-100 frames around the gap), refilled by both
    methods from the remaining samples (the regression retrained without them); ties
    go to the spline.  On the Vicon walking trials, one marker gapped at a time, auto
    was at most 8 % (and 0.1 mm) worse than the better method for every gap length of
    1-10 frames and better than both in 6 of 18 cases (``benchmarks/RESULTS.md``): it
    keeps the spline for 1-2 frame gaps at 50 Hz and on noisy unprocessed data, the
    pattern for longer gaps and at 120 Hz.

Every fill passes through the valid samples, so valid samples are returned bit-identical;
only samples inside filled gaps change.  Donors are measured samples only, never fills.

Why a window, and why neighbouring gaps share one spline: :mod:`fuzzygait.mocap.gap_plan`
(where the gaps and their windows are found).  The pattern's residual spline uses each
gap's own window, as its donors may differ from gap to gap
(:mod:`fuzzygait.mocap.pattern_gaps`).

Samples that stay missing are returned NaN in all three coordinates.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import pandas as pd

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Trial
from fuzzygait.mocap.gap_plan import WINDOW_VALID_SAMPLES as WINDOW_VALID_SAMPLES  # re-exported: read here by tests
from fuzzygait.mocap.gap_plan import plan_gaps, spline_fills
from fuzzygait.mocap.pattern_fill import PatternUnavailable
from fuzzygait.mocap.pattern_gaps import auto_choice, fit_for_gap, pattern_gap_fill

#: Labels of unlabelled trajectories: Vicon ``*12``, ``C_12``, ``Unlabeled 12``.
_UNLABELLED = re.compile(r"\*\d+|C_\d+|Unlabell?ed[ _]?\d*", re.IGNORECASE)
Method = Literal["auto", "spline", "pattern"]
#: Gap-filling methods accepted by :func:`fill_gaps`.
METHODS: tuple[Method, ...] = ("auto", "spline", "pattern")


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
        method: ``"spline"`` or ``"pattern"``: what filled the gap (``""`` if unfilled).
        note: why that method, when there is something to say (free text, left out of
            ``==``): the pattern could not be
            used (e.g. ``"pattern not possible: 2 other markers visible over the gap and
            its window (pattern needs 3)"``) or, for ``method="auto"``, the pseudo-gap
            errors (``"auto: 4 pseudo-gaps, RMS spline 2.1 mm, pattern 0.4 mm"``).
    """

    marker: str
    start: int
    length: int
    filled: bool
    reason: str = ""
    method: str = ""
    note: str = field(default="", compare=False)


def _check_max_gap(max_gap: object) -> int:
    if isinstance(max_gap, bool) or not isinstance(max_gap, int | np.integer) or max_gap < 0:
        raise ParameterError(
            f"max_gap must be a whole number of frames >= 0 (0 fills nothing); got {max_gap!r}"
        )
    return int(max_gap)


def _check_method(method: object) -> Method:
    """``method`` if it is one of :data:`METHODS`, else a ParameterError naming them."""
    if method not in METHODS:
        choices = ", ".join(repr(m) for m in METHODS)
        raise ParameterError(f"method must be one of {choices}; got {method!r}")
    return method


def _fill_marker(
    markers: np.ndarray,
    missing: np.ndarray,
    target: int,
    labels: Sequence[str],
    max_gap: int,
    method: Method,
) -> tuple[np.ndarray | None, np.ndarray | None, list[Gap]]:
    """Fill the gaps of column ``target`` of ``markers`` (NaN where ``missing``).

    Returns the sample indices filled, their ``(k, 3)`` values (mm) and the gap reports.
    """
    plan = plan_gaps(missing[:, target], max_gap)
    if not plan.runs:
        return None, None, []
    fills = spline_fills(plan, markers[:, target], plan.groups())
    used = dict.fromkeys(fills, ("spline", ""))
    for i in plan.fillable if method != "spline" else []:
        try:
            model = fit_for_gap(markers, missing, target, plan, i)
        except PatternUnavailable as why:
            used[i] = ("spline", f"pattern not possible: {why}")
            continue
        chosen, note = "pattern", ""
        if method == "auto":
            chosen, note = auto_choice(markers, missing, model, plan.runs[i].length, max_gap)
        if chosen == "pattern":
            fills[i] = pattern_gap_fill(markers, model, plan, i)
            donors = ", ".join(labels[d] for d in model.donors)
            note = "; ".join(filter(None, [note, f"donors {donors}"]))
        used[i] = (chosen, note)

    gaps = [
        Gap(labels[target], run.start, run.length, not reason, reason, *used.get(i, ("", "")))
        for i, (run, reason) in enumerate(zip(plan.runs, plan.reasons, strict=True))
    ]
    if not fills:
        return None, None, gaps
    order = sorted(fills)
    where = np.concatenate([np.arange(plan.runs[i].start, plan.runs[i].stop) for i in order])
    return where, np.concatenate([fills[i] for i in order]), gaps


def fill_gaps(
    markers: np.ndarray, labels: Sequence[str], max_gap: int = 10, method: Method = "auto"
) -> tuple[np.ndarray, list[Gap]]:
    """Fill short interior gaps of marker trajectories.

    See the module docstring for the gaps filled and the methods.  The input is never
    modified; valid samples are returned bit-identical.

    Args:
        markers: ``(n_frames, n_markers, 3)`` positions in mm; a sample is missing when
            any coordinate is NaN (or infinite).
        labels: one marker label per column, used in the report.
        max_gap: longest gap to fill, in frames (samples); ``0`` fills nothing.
        method: ``"spline"`` (cubic spline through the marker's own samples),
            ``"pattern"`` (regression on the other markers + residual spline; spline
            where that is not possible) or ``"auto"`` (per gap, whichever of the two
            refills pseudo-gaps next to it better).

    Returns:
        The filled copy of ``markers`` (mm; samples left missing are NaN in x, y and z)
        and one :class:`Gap` per gap, ordered by marker column then start.

    Raises:
        ParameterError: for a ``max_gap`` that is not an integer >= 0, an unknown
            ``method``, a wrongly shaped array, or a label count that does not match the
            marker columns.
    """
    max_gap = _check_max_gap(max_gap)
    method = _check_method(method)
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
    fills = []  # written after the loop: donors are measured samples, never fills
    for m in np.flatnonzero(missing.any(axis=0)).tolist():
        where, values, marker_gaps = _fill_marker(out, missing, m, labels, max_gap, method)
        gaps.extend(marker_gaps)
        if where is not None:
            fills.append((where, m, values))
    for where, m, values in fills:
        out[where, m] = values
    return out, gaps


def is_unlabelled(label: str) -> bool:
    """Whether ``label`` names an unlabelled trajectory (Vicon's ``*127``, also ``C_12``
    and ``Unlabeled 3`` as other systems write them): no model reads such a marker."""
    return bool(_UNLABELLED.fullmatch(label.strip()))


def labelled_markers(labels: Sequence[str]) -> list[str]:
    """``labels`` without the unlabelled trajectories (:func:`is_unlabelled`), in order."""
    return [label for label in labels if not is_unlabelled(label)]


def fill_trial_gaps(
    trial: Trial, max_gap: int = 10, method: Method = "auto", markers: Sequence[str] | None = None
) -> tuple[Trial, list[Gap]]:
    """:func:`fill_gaps` applied to a trial's markers.

    Args:
        trial: the trial (not modified).
        max_gap: longest gap to fill, in frames; ``0`` fills nothing.
        method: ``"auto"``, ``"spline"`` or ``"pattern"`` (see :func:`fill_gaps`).
        markers: fill (and report) only these markers, which are also the only ones the
            pattern fill regresses on; the others are kept as they are.  None: every
            marker.  Labels the trial does not hold are ignored.

    Returns:
        A new trial whose notes end with a :attr:`~fuzzygait.core.findings.FindingKind.GAP_FILLING`
        finding (``max_gap`` and ``method`` as given) whose message reads e.g.
        ``"gap filling: 5 of 7 gaps filled (max_gap=10 frames, method=auto: 3 pattern,
        2 spline)"``, and the gap report.
    """
    if markers is None:
        columns = list(range(trial.n_markers))
    else:
        wanted = set(markers)
        columns = [k for k, label in enumerate(trial.marker_labels) if label in wanted]
    labels = [trial.marker_labels[k] for k in columns]
    filled_part, gaps = fill_gaps(trial.markers[:, columns, :], labels, max_gap, method)
    out = np.array(trial.markers, dtype=float)
    out[:, columns, :] = filled_part
    n_filled = sum(gap.filled for gap in gaps)
    used = methods_used(gaps)
    which = "" if markers is None else f", {len(columns)} of {trial.n_markers} markers"
    message = (
        f"gap filling: {n_filled} of {len(gaps)} gaps filled "
        f"(max_gap={max_gap} frames, method={method}{': ' + used if used else ''}{which})"
    )
    note = Finding(FindingKind.GAP_FILLING, message, max_gap=max_gap, method=method)
    return trial.with_markers(out, note=note), gaps


def methods_used(gaps: Sequence[Gap]) -> str:
    """How many gaps each method filled, e.g. ``"3 pattern, 2 spline"`` (``""``: none)."""
    counts = {name: sum(gap.method == name for gap in gaps) for name in ("pattern", "spline")}
    return ", ".join(f"{count} {name}" for name, count in counts.items() if count)


def gap_report_table(gaps: Sequence[Gap]) -> pd.DataFrame:
    """The gap report as a table: marker, start, length, filled, reason, method, note."""
    return pd.DataFrame(
        {
            "marker": pd.Series([g.marker for g in gaps], dtype=object),
            "start": pd.Series([g.start for g in gaps], dtype="int64"),
            "length": pd.Series([g.length for g in gaps], dtype="int64"),
            "filled": pd.Series([g.filled for g in gaps], dtype=bool),
            "reason": pd.Series([g.reason for g in gaps], dtype=object),
            "method": pd.Series([g.method for g in gaps], dtype=object),
            "note": pd.Series([g.note for g in gaps], dtype=object),
        }
    )
