"""The pattern fill of one gap and ``method="auto"``'s choice between spline and pattern.

:func:`pattern_gap_fill` is the regression of :mod:`fuzzygait.mocap.pattern_fill` plus a
spline of its residual through the gap's own window (:meth:`~fuzzygait.mocap.gap_plan.GapPlan.knots`),
so that the fill meets the data at the gap edges; :func:`auto_choice` refills
:data:`PSEUDO_GAPS` pseudo-gaps cut next to the gap by both methods and keeps the better
(see :mod:`fuzzygait.mocap.gaps` for the methods).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.mocap.gap_plan import MIN_VALID_EACH_SIDE, GapPlan, plan_gaps, spline, spline_fills
from fuzzygait.mocap.pattern_fill import PatternModel, PatternUnavailable, donors_visible, fit_pattern

if TYPE_CHECKING:
    from fuzzygait.mocap.gaps import Method

#: Pseudo-gaps cut per gap to choose the method when ``method="auto"`` (2, 4 and 6 were
#: measured: 2 decides less reliably, 6 leaves the short 50 Hz trials too few training
#: frames for the retrained regression).
PSEUDO_GAPS = 4


def fit_for_gap(
    markers: np.ndarray, missing: np.ndarray, target: int, plan: GapPlan, i: int
) -> PatternModel:
    """The regression for gap ``plan.runs[i]`` of column ``target``: donors visible over
    the gap and its window.  Raises :class:`PatternUnavailable`."""
    run = plan.runs[i]
    support = np.union1d(plan.knots(i, i), np.arange(run.start, run.stop))
    return fit_pattern(markers, missing, target, support)


def pattern_gap_fill(markers: np.ndarray, model: PatternModel, plan: GapPlan, i: int) -> np.ndarray:
    """Pattern fill ``(length, 3)`` mm of gap ``plan.runs[i]``: the regression plus a
    spline of its residual through the gap's own window (:meth:`GapPlan.knots`), so
    that the fill meets the data at the gap edges."""
    run = plan.runs[i]
    knots, where = plan.knots(i, i), np.arange(run.start, run.stop)
    residual = markers[knots, model.target] - model.predict(markers, knots)
    return model.predict(markers, where) + spline(knots, residual, where)


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


def auto_choice(
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
    plan = plan_gaps(cut, max_gap)
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
    fills = spline_fills(plan, np.concatenate([truth, truth - predicted], axis=1), groups)
    errors = np.zeros(2)
    for i in pseudo:
        where = np.arange(plan.runs[i].start, plan.runs[i].stop)
        errors[0] += np.sum((fills[i][:, :3] - truth[where]) ** 2)
        errors[1] += np.sum((predicted[where] + fills[i][:, 3:] - truth[where]) ** 2)
    rms = np.sqrt(errors / (length * len(pseudo)))
    note = f"auto: {len(pseudo)} pseudo-gaps, RMS spline {rms[0]:.3g} mm, pattern {rms[1]:.3g} mm"
    return ("pattern" if errors[1] < errors[0] else "spline"), note
