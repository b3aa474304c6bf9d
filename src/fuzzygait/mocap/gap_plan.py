"""Where one marker's gaps are and which samples a fill of each may use.

A marker sample is *missing* when any of its x, y, z coordinates is not finite; a *gap* is
a maximal run of missing samples (:func:`find_gaps`).  :func:`plan_gaps` decides which gaps
of one marker :func:`~fuzzygait.mocap.gaps.fill_gaps` may fill (interior, at most
``max_gap`` frames, :data:`MIN_VALID_EACH_SIDE` valid samples on each side up to the nearest
gap that is not fillable) and the *window* of valid samples around each: up to
:data:`WINDOW_VALID_SAMPLES` on each side, never reaching past a gap that is not fillable.
:func:`spline_fills` fits the windowed not-a-knot cubic splines.

Why a window: a cubic spline is local in effect -- the influence of a knot on the curve
decays by a factor of about 2 - sqrt(3) ~= 0.27 per knot -- so 30 samples on each side
gives the same values as a spline through the whole trajectory to far below 1e-12 of the
signal, while the cost and the dependence on distant (possibly mislabelled) data stay
bounded.  Neighbouring gaps whose windows overlap (fewer than 2 x 30 valid samples apart)
share one spline through the union of their windows (:meth:`GapPlan.groups`); for the
reason just given this differs from separate fits only at round-off level and keeps the
work linear in the trial length even when gaps are dense.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from fuzzygait.core.errors import ParameterError

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
class GapPlan:
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


def plan_gaps(missing: np.ndarray, max_gap: int) -> GapPlan:
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
    return GapPlan(runs, reasons, np.flatnonzero(~missing), n_valid_before, seg_lo, seg_hi)


def spline(knots: np.ndarray, values: np.ndarray, where: np.ndarray) -> np.ndarray:
    """Not-a-knot cubic spline through ``values`` (one row per knot) evaluated at ``where``."""
    return CubicSpline(knots, values, axis=0, bc_type="not-a-knot")(where)


def spline_fills(
    plan: GapPlan, values: np.ndarray, groups: Sequence[Sequence[int]]
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
        parts = np.split(spline(knots, values[knots], where), np.cumsum(lengths[:-1]))
        fills.update(zip(group, parts, strict=True))
    return fills
