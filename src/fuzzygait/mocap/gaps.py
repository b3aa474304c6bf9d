"""Gap filling of marker trajectories: local cubic splines and inter-marker patterns.

A marker sample is *missing* when any of its x, y, z coordinates is not finite (the three
coordinates are always treated together).  A *gap* is a maximal run of missing samples of
one marker.  :func:`fill_gaps` fills a gap only when

* it is *interior*: valid samples exist both before and after it (never extrapolate, so
  gaps touching the first or last sample stay missing);
* it lasts at most ``max_gap`` frames;
* at least :data:`MIN_VALID_EACH_SIDE` (= 2) valid samples lie on each side of it, counted
  up to the nearest gap that is not fillable (start/end gap or longer than ``max_gap``).

Methods (``method=``):

``"spline"``
    A not-a-knot cubic spline (:class:`scipy.interpolate.CubicSpline`) with the sample
    index as abscissa, fitted to x, y and z together through the valid samples of a
    *window* around the gap: up to :data:`WINDOW_VALID_SAMPLES` (= 30) valid samples on
    each side, never reaching past a non-fillable gap.
``"pattern"``
    A linear regression of the marker on nearby markers visible throughout the gap and
    its window (:mod:`fuzzygait.mocap.pattern_fill`), plus the same windowed spline
    through the regression's residual, so that the fill meets the data at the gap
    edges.  It follows movement inside the gap that the marker's own samples cannot
    show (a foot's swing).  Where no regression is possible (fewer than 3 other markers
    visible over the gap and its window, or too few training frames) the gap is filled
    by the spline and the report says why.
``"auto"`` (default)
    Per gap, whichever of the two refills :data:`PSEUDO_GAPS` (= 4) pseudo-gaps better:
    runs of the same length cut into the marker's own valid samples within the
    regression's training range (about +-100 frames around the gap), refilled by both
    methods from the remaining samples (the regression retrained without them); ties
    go to the spline.  On the Vicon walking trials, one marker gapped at a time, auto
    was at most 8 % (and 0.1 mm) worse than the better method for every gap length of
    1-10 frames and better than both in 6 of 18 cases (``benchmarks/RESULTS.md``): it
    keeps the spline for 1-2 frame gaps at 50 Hz and on noisy unprocessed data, the
    pattern for longer gaps and at 120 Hz.

Every fill passes through the valid samples, so valid samples are returned bit-identical;
only samples inside filled gaps change.  Donors are measured samples only, never fills.

Why a window: a cubic spline is local in effect -- the influence of a knot on the curve
decays by a factor of about 2 - sqrt(3) ~= 0.27 per knot -- so 30 samples on each side
gives the same values as a spline through the whole trajectory to far below 1e-12 of the
signal, while the cost and the dependence on distant (possibly mislabelled) data stay
bounded.  Neighbouring gaps whose windows overlap (fewer than 2 x 30 valid samples apart)
share one spline through the union of their windows; for the reason just given this
differs from separate fits only at round-off level and keeps the work linear in the
trial length even when gaps are dense.  The pattern's residual spline uses each gap's
own window (:meth:`_GapPlan.knots`), as its donors may differ from gap to gap.

Samples that stay missing are returned NaN in all three coordinates.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal, NamedTuple

import numpy as np
import pandas as pd
from scipy.interpolate import CubicSpline

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind
from fuzzygait.core.trial import Trial
from fuzzygait.mocap.pattern_fill import (
    PatternModel,
    PatternUnavailable,
    donors_visible,
    fit_pattern,
)

#: Valid samples used on each side of a gap for the spline fit (at most).
#: Labels of unlabelled trajectories: Vicon ``*12``, ``C_12``, ``Unlabeled 12``.
_UNLABELLED = re.compile(r"\*\d+|C_\d+|Unlabell?ed[ _]?\d*", re.IGNORECASE)
WINDOW_VALID_SAMPLES = 30
#: Valid samples needed on each side of a gap to fill it.
MIN_VALID_EACH_SIDE = 2

#: Pseudo-gaps cut per gap to choose the method when ``method="auto"`` (2, 4 and 6 were
#: measured: 2 decides less reliably, 6 leaves the short 50 Hz trials too few training
#: frames for the retrained regression).
PSEUDO_GAPS = 4

Position = Literal["interior", "start", "end", "all"]
Method = Literal["auto", "spline", "pattern"]
#: Gap-filling methods accepted by :func:`fill_gaps`.
METHODS: tuple[Method, ...] = ("auto", "spline", "pattern")


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


@dataclass(frozen=True)
class _GapPlan:
    """Which gaps of one marker can be filled and the valid samples each fill may use.

    This is the one place that owns the windowing rule of the module docstring: a fit for
    gaps ``runs[first..last]`` may use up to :data:`WINDOW_VALID_SAMPLES` valid samples
    before the first and after the last, never past a gap that cannot be filled.
    """

    runs: list[GapRun]
    reasons: list[str]  # "" for a fillable gap, else why not (see Gap.reason)
    valid_index: np.ndarray  # 0-based indices of the valid samples
    n_valid_before: np.ndarray  # [i] = valid samples in [0, i)
    seg_lo: np.ndarray  # per run: the window may not start before this sample
    seg_hi: np.ndarray  # per run: ... nor end after it

    @property
    def fillable(self) -> list[int]:
        """Indices (into ``runs``) of the gaps that may be filled."""
        return [i for i, reason in enumerate(self.reasons) if not reason]

    def knots(self, first: int, last: int) -> np.ndarray:
        """Valid sample indices of the window around gaps ``runs[first..last]``."""
        a = max(
            self.n_valid_before[self.runs[first].start] - WINDOW_VALID_SAMPLES,
            self.n_valid_before[self.seg_lo[first]],
        )
        b = min(
            self.n_valid_before[self.runs[last].stop] + WINDOW_VALID_SAMPLES,
            self.n_valid_before[self.seg_hi[last]],
        )
        return self.valid_index[a:b]

    def groups(self) -> list[list[int]]:
        """Fillable gaps in runs whose windows overlap; one spline serves each group."""
        groups: list[list[int]] = []
        for i in self.fillable:
            if groups:
                last = groups[-1][-1]
                before = self.n_valid_before
                between = before[self.runs[i].start] - before[self.runs[last].stop]
                if self.seg_lo[i] == self.seg_lo[last] and between < 2 * WINDOW_VALID_SAMPLES:
                    groups[-1].append(i)
                    continue
            groups.append([i])
        return groups


def _plan_gaps(missing: np.ndarray, max_gap: int) -> _GapPlan:
    """Find one marker's gaps and decide which are fillable (see the module docstring)."""
    runs = find_gaps(missing)
    n = missing.size
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

    for i, run in enumerate(runs):
        if reasons[i]:
            continue
        left = n_valid_before[run.start] - n_valid_before[seg_lo[i]]
        right = n_valid_before[seg_hi[i]] - n_valid_before[run.stop]
        if min(left, right) < MIN_VALID_EACH_SIDE:
            reasons[i] = f"too few valid samples (need {MIN_VALID_EACH_SIDE} on each side)"
    return _GapPlan(runs, reasons, np.flatnonzero(~missing), n_valid_before, seg_lo, seg_hi)


def _spline(knots: np.ndarray, values: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Not-a-knot cubic spline through ``values`` (one row per knot) evaluated at ``where``."""
    return CubicSpline(knots, values, axis=0, bc_type="not-a-knot")(where)


def _spline_fills(
    plan: _GapPlan, values: np.ndarray, groups: Sequence[Sequence[int]]
) -> dict[int, np.ndarray]:
    """Spline fill of every gap in ``groups``, one spline per group through its window.

    Args:
        plan: the gaps and windows of one trajectory.
        values: ``(n_frames, k)`` samples, finite at the valid samples.
        groups: gap indices (into ``plan.runs``) sharing a spline, e.g. ``plan.groups()``.

    Returns:
        ``{gap index: (length, k) fill}``.
    """
    fills: dict[int, np.ndarray] = {}
    for group in groups:
        knots = plan.knots(group[0], group[-1])
        lengths = [plan.runs[i].length for i in group]
        where = np.concatenate([np.arange(plan.runs[i].start, plan.runs[i].stop) for i in group])
        parts = np.split(_spline(knots, values[knots], where), np.cumsum(lengths[:-1]))
        fills.update(zip(group, parts, strict=True))
    return fills


def _check_method(method: object) -> Method:
    """``method`` if it is one of :data:`METHODS`, else a ParameterError naming them."""
    if method not in METHODS:
        choices = ", ".join(repr(m) for m in METHODS)
        raise ParameterError(f"method must be one of {choices}; got {method!r}")
    return method


def _fit_for_gap(
    markers: np.ndarray, missing: np.ndarray, target: int, plan: _GapPlan, i: int
) -> PatternModel:
    """The regression for gap ``plan.runs[i]`` of column ``target``: donors visible over
    the gap and its window.  Raises :class:`PatternUnavailable`."""
    run = plan.runs[i]
    support = np.union1d(plan.knots(i, i), np.arange(run.start, run.stop))
    return fit_pattern(markers, missing, target, support)


def _pattern_fill(markers: np.ndarray, model: PatternModel, plan: _GapPlan, i: int) -> np.ndarray:
    """Pattern fill ``(length, 3)`` mm of gap ``plan.runs[i]``: the regression plus a
    spline of its residual through the gap's own window (:meth:`_GapPlan.knots`), so
    that the fill meets the data at the gap edges."""
    run = plan.runs[i]
    knots, where = plan.knots(i, i), np.arange(run.start, run.stop)
    residual = markers[knots, model.target] - model.predict(markers, knots)
    return model.predict(markers, where) + _spline(knots, residual, where)


def _pseudo_gap_starts(hidden: np.ndarray, length: int, count: int) -> list[int]:
    """Up to ``count`` starts of pseudo-gaps of ``length`` samples, spread over ``hidden``.

    A pseudo-gap lies on consecutive valid samples (``hidden`` False) with
    :data:`MIN_VALID_EACH_SIDE` valid samples before and after it, and pseudo-gaps do
    not touch each other.  Targets are evenly spaced; each takes the nearest free start.
    """
    pad = MIN_VALID_EACH_SIDE
    width = length + 2 * pad
    if hidden.size < width:
        return []
    run_valid = np.convolve(~hidden, np.ones(width, dtype=int), mode="valid") == width
    free = np.flatnonzero(run_valid) + pad  # starts whose padded run is valid
    starts: list[int] = []
    for target in np.linspace(0, hidden.size - length, count + 2)[1:-1]:
        if free.size:
            start = int(free[np.argmin(np.abs(free - target))])
            starts.append(start)
            free = free[np.abs(free - start) >= length + pad]
    return sorted(starts)


def _auto_choice(
    markers: np.ndarray, missing: np.ndarray, model: PatternModel, length: int, max_gap: int
) -> tuple[Method, str]:
    """Choose between spline and pattern for a gap of ``length`` frames by validation.

    :data:`PSEUDO_GAPS` pseudo-gaps of the same length are cut into the valid samples of
    ``model.target`` spread over the model's training range (where its donors are
    visible); both methods refill them from the remaining samples with the usual windows
    (the regression retrained on the same donors and range without them), and the method
    with the smaller sum of squared errors wins (ties and no room for pseudo-gaps:
    spline).  Returns the method and a note with the pseudo-gap RMS (mm) of both.
    """
    lo, hi = model.train_range
    target, frames = model.target, np.arange(lo, hi)
    seen = donors_visible(missing, frames, model.donors)
    hidden = missing[lo:hi, target] | ~seen
    starts = _pseudo_gap_starts(hidden, length, PSEUDO_GAPS)
    cut = hidden.copy()
    for start in starts:
        cut[start : start + length] = True
    plan = _plan_gaps(cut, max_gap)
    pseudo = [i for i, run in enumerate(plan.runs) if run.start in starts and not plan.reasons[i]]
    if not pseudo:
        return "spline", "auto: no room for pseudo-gaps"
    try:
        check = fit_pattern(
            markers, missing, target, frames[seen], exclude=lo + np.flatnonzero(cut & ~hidden),
            donors=model.donors, train_range=(lo, hi),
        )
    except PatternUnavailable as why:
        return "spline", f"auto: no validation possible ({why})"
    truth = markers[lo:hi, target]
    predicted = np.full_like(truth, np.nan)
    predicted[seen] = check.predict(markers, frames[seen])
    groups = [g for g in plan.groups() if set(pseudo).intersection(g)]
    fills = _spline_fills(plan, np.concatenate([truth, truth - predicted], axis=1), groups)
    errors = np.zeros(2)
    for i in pseudo:
        where = np.arange(plan.runs[i].start, plan.runs[i].stop)
        errors[0] += np.sum((fills[i][:, :3] - truth[where]) ** 2)
        errors[1] += np.sum((predicted[where] + fills[i][:, 3:] - truth[where]) ** 2)
    rms = np.sqrt(errors / (length * len(pseudo)))
    note = f"auto: {len(pseudo)} pseudo-gaps, RMS spline {rms[0]:.3g} mm, pattern {rms[1]:.3g} mm"
    return ("pattern" if errors[1] < errors[0] else "spline"), note


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
    plan = _plan_gaps(missing[:, target], max_gap)
    if not plan.runs:
        return None, None, []
    fills = _spline_fills(plan, markers[:, target], plan.groups())
    used = dict.fromkeys(fills, ("spline", ""))
    for i in plan.fillable if method != "spline" else []:
        try:
            model = _fit_for_gap(markers, missing, target, plan, i)
        except PatternUnavailable as why:
            used[i] = ("spline", f"pattern not possible: {why}")
            continue
        chosen, note = "pattern", ""
        if method == "auto":
            chosen, note = _auto_choice(markers, missing, model, plan.runs[i].length, max_gap)
        if chosen == "pattern":
            fills[i] = _pattern_fill(markers, model, plan, i)
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
