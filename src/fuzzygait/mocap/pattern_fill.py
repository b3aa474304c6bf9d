"""Inter-marker ("pattern") prediction of one marker from other markers.

Used by :func:`fuzzygait.mocap.fill_gaps` (``method="pattern"`` or ``"auto"``) to fill a
gap of a *target* marker while other markers -- the *donors* -- stay visible.  This module
only fits and evaluates the predictor; gap finding and the windows belong to
:mod:`fuzzygait.mocap.gap_plan`, the residual spline that joins the prediction to the data
to :mod:`fuzzygait.mocap.pattern_gaps`.

The model, for one gap:

1. *Donors*: the other markers that are valid at every *support* frame (the frames of the
   gap and the valid samples of the target's spline window around it), at most
   :data:`MAX_DONORS` of them, the ones nearest to the target (mean distance over the
   window's valid samples); at least :data:`MIN_DONORS` are needed.
2. *Training frames*: frames within :data:`TRAIN_HALF_WIDTH` frames of the support where
   the target and every donor are valid (minus any frames the caller excludes); at least
   ``max(MIN_TRAIN_FRAMES, TRAIN_FRAMES_PER_PREDICTOR * 3 * n_donors)`` are needed.
3. *Regression*: the donors' x, y, z coordinates (3 per donor, the *predictors*) are
   standardised (zero mean, unit standard deviation over the training frames) and the
   target's x, y, z are regressed on them by ridge regression, ``coef = V diag(1 / (s^2
   + RIDGE)) V^T A^T (y - mean y)`` with ``A = U S V^T`` the SVD of the standardised
   predictors, and a tiny ridge (:data:`RIDGE` = 1e-6): enough to keep collinear donors
   (markers of one rigid segment) from blowing up the coefficients; it shrinks a
   direction of the fit by the factor ``s^2 / (s^2 + RIDGE)``, i.e. by ~1e-8 where a
   direction varies as much as a whole predictor (``s^2`` ~ number of training frames).

The prediction is a linear (affine) function of the donor positions in the same frame, so
it follows the gap's fast movement (the swing of a foot) that a spline through the
target's own samples cannot know about.  Its error is a smooth function of time when the
relation between target and donors drifts slowly; the residual spline in
:mod:`~fuzzygait.mocap.pattern_gaps` removes the part of it seen at the gap edges.

How the constants were chosen (``benchmarks/preprocess.py``, protocol "one marker at a
time": gaps of 1-10 frames cut into one complete marker of the Vicon trials
Movement_trial (120 Hz, 74 complete markers), gait-pig and gait-raw (50 Hz, 8 and 7)):

* :data:`MAX_DONORS` 3, 4, 6, 8, 12 and all: 8 is best or within a few per cent at 50 Hz
  (gait-pig, 10 frames: 3 donors 4.1 mm, 8 donors 3.0 mm); all 73 donors of
  Movement_trial would need 657 training frames, more than the trial has.
* :data:`TRAIN_HALF_WIDTH` 50, 100, 250 frames: the same on the short 50 Hz trials,
  100 best at 120 Hz (10 frames: 0.060 mm vs 0.080 mm with 250); local and cheap.
* :data:`RIDGE` 1e-12 ... 1: 1e-6 is best or within 2 %; 1e-9 and 1e-12 are as good at
  50 Hz and 5-10 % worse at 120 Hz; 1e-3 loses at 5 frames (gait-pig 0.91 vs 0.68 mm)
  and 1e-1 everywhere (gait-pig, 10 frames: 6.5 vs 3.0 mm).
* Donor velocities as extra predictors (central differences) helped 10-frame gaps
  (gait-raw 10.3 -> 7.1 mm) but hurt 5-frame gaps (gait-pig 0.68 -> 0.95 mm) and double
  the training frames needed, so the short 50 Hz trials fell back to the spline; not used.

The regression's ``V`` and ``s^2`` are computed from the eigendecomposition of the small
Gram matrix ``A^T A`` (predictors x predictors) rather than by LAPACK's SVD of the tall
``A``: the same ridge solution, but LAPACK's threaded SVD took 6-13 ms per call instead
of ~0.1 ms on a busy 2-core machine (hundreds of rows), which made ``method="auto"``
20 times slower.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Fewest donor markers a pattern fit needs.
MIN_DONORS = 3
#: Most donor markers used (the nearest ones to the target).
MAX_DONORS = 8
#: Ridge parameter on standardised predictors (dimensionless).
RIDGE = 1e-6
#: Training frames are taken within this many frames before and after the support.
TRAIN_HALF_WIDTH = 100
#: Fewest training frames, in absolute terms ...
MIN_TRAIN_FRAMES = 20
#: ... and per predictor (3 predictors per donor).
TRAIN_FRAMES_PER_PREDICTOR = 3


class PatternUnavailable(Exception):
    """No pattern fit is possible for this gap; the message says why (one line)."""


@dataclass(frozen=True)
class PatternModel:
    """A fitted linear predictor of one marker from donor markers.

    Attributes:
        target: column of the predicted marker.
        donors: columns of the donor markers, nearest first.
        n_train: number of training frames.
        train_range: ``(lo, hi)``: training frames were taken from ``lo <= frame < hi``.
    """

    target: int
    donors: tuple[int, ...]
    n_train: int
    train_range: tuple[int, int]
    _centre: np.ndarray
    _scale: np.ndarray
    _coef: np.ndarray
    _offset: np.ndarray

    def predict(self, markers: np.ndarray, frames: np.ndarray) -> np.ndarray:
        """Predicted target positions ``(len(frames), 3)`` in mm.

        Args:
            markers: ``(n_frames, n_markers, 3)`` positions in mm; the donors must be
                valid at ``frames``.
            frames: 0-based frame indices.
        """
        features = _features(markers, self.donors, frames)
        return ((features - self._centre) / self._scale) @ self._coef + self._offset


def donors_visible(missing: np.ndarray, frames: np.ndarray, donors: tuple[int, ...]) -> np.ndarray:
    """``(len(frames),)`` True where every donor's features exist (the model can predict)."""
    return ~missing[np.asarray(frames)][:, list(donors)].any(axis=1)


def _features(markers: np.ndarray, donors: tuple[int, ...], frames: np.ndarray) -> np.ndarray:
    """Predictor matrix ``(len(frames), 3 * len(donors))``: donor x, y, z in mm."""
    return markers[np.asarray(frames)][:, list(donors), :].reshape(len(frames), -1)


def choose_donors(
    markers: np.ndarray, missing: np.ndarray, target: int, support: np.ndarray
) -> tuple[int, ...]:
    """Donor columns for predicting ``target`` over the ``support`` frames.

    Args:
        markers: ``(n_frames, n_markers, 3)`` positions in mm.
        missing: ``(n_frames, n_markers)`` True where a sample is missing.
        target: column of the marker to predict.
        support: 0-based frames where every donor must be valid; the target must be
            valid at some of them (its distance to candidates is measured there).

    Returns:
        Up to :data:`MAX_DONORS` columns, nearest to the target first.

    Raises:
        PatternUnavailable: when fewer than :data:`MIN_DONORS` markers qualify.
    """
    candidates = np.flatnonzero(~missing[support].any(axis=0))
    candidates = candidates[candidates != target]
    if candidates.size < MIN_DONORS:
        raise PatternUnavailable(
            f"{candidates.size} other markers visible over the gap and its window "
            f"(pattern needs {MIN_DONORS})"
        )
    seen = support[~missing[support, target]]
    distance = np.linalg.norm(
        markers[seen][:, candidates] - markers[seen, target][:, None], axis=2
    ).mean(axis=0)
    nearest = candidates[np.argsort(distance, kind="stable")[:MAX_DONORS]]
    return tuple(int(d) for d in nearest)


def fit_pattern(
    markers: np.ndarray,
    missing: np.ndarray,
    target: int,
    support: np.ndarray,
    exclude: np.ndarray | None = None,
    donors: tuple[int, ...] | None = None,
    train_range: tuple[int, int] | None = None,
) -> PatternModel:
    """Fit the ridge predictor of ``target`` from its donors (see the module docstring).

    Args:
        markers: ``(n_frames, n_markers, 3)`` positions in mm (NaN where missing).
        missing: ``(n_frames, n_markers)`` True where a sample is missing.
        target: column of the marker to predict.
        support: sorted 0-based frames where the prediction will be evaluated (the gap
            and the valid samples of its spline window); donors must be valid there.
        exclude: frames never used for training (e.g. pseudo-gaps cut for validation).
        donors: donor columns to use (valid at ``support``) instead of choosing them
            with :func:`choose_donors`; e.g. to refit a model without some frames.
        train_range: ``(lo, hi)`` frames to train from instead of :data:`TRAIN_HALF_WIDTH`
            frames around the support.

    Returns:
        The fitted :class:`PatternModel`.

    Raises:
        PatternUnavailable: too few donors or training frames.
    """
    if donors is None:
        donors = choose_donors(markers, missing, target, support)
    if train_range is None:
        lo = max(0, int(support[0]) - TRAIN_HALF_WIDTH)
        hi = min(missing.shape[0], int(support[-1]) + 1 + TRAIN_HALF_WIDTH)
    else:
        lo, hi = train_range
    frames = np.arange(lo, hi)
    usable = ~missing[frames, target] & donors_visible(missing, frames, donors)
    if exclude is not None and len(exclude):
        inside = exclude[(exclude >= lo) & (exclude < hi)]
        usable[inside - lo] = False
    train = lo + np.flatnonzero(usable)
    n_predictors = 3 * len(donors)
    need = max(MIN_TRAIN_FRAMES, TRAIN_FRAMES_PER_PREDICTOR * n_predictors)
    if train.size < need:
        raise PatternUnavailable(
            f"{train.size} frames with the marker and its {len(donors)} donors all visible "
            f"(pattern needs {need})"
        )
    features = _features(markers, donors, train)
    centre = features.mean(axis=0)
    scale = features.std(axis=0)
    scale[scale == 0] = 1.0  # a motionless coordinate carries no information
    standardised = (features - centre) / scale
    y = markers[train, target]
    offset = y.mean(axis=0)
    # Ridge through the SVD A = U S V^T (module docstring): V and s^2 from A^T A.
    s2, v = np.linalg.eigh(standardised.T @ standardised)
    coef = v @ ((v.T @ (standardised.T @ (y - offset))) / (np.maximum(s2, 0.0) + RIDGE)[:, None])
    return PatternModel(target, donors, int(train.size), (lo, hi), centre, scale, coef, offset)
