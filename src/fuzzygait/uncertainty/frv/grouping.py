"""Grouping of FRV samples (thesis §2.7.4 steps 2–4, Eqs. 2.31–2.32): the parameter grid
:class:`Grid`, bin indices of α-cut ends, and the keys of the occurring intervals."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv.samples import _whole

#: A value within this fraction of a spacing above the grid's top point belongs to the
#: last bin (the largest sample of the first batch lies exactly on the top point).
EDGE_TOL = 1e-9
#: Interval keys: ``(left + KEY_BIAS) * KEY_BASE + (right + KEY_BIAS)`` (bins in ±2^30).
KEY_BIAS, KEY_BASE = 1 << 30, 1 << 31


@dataclass(frozen=True)
class Grid:
    """The discretisation of the parameter range used for grouping (Eq. 2.31–2.32).

    The first batch's range ``[min, max]`` of all α-cut ends is discretised into
    ``N_p-disc`` equidistant points ``x_j = origin + j·spacing``; the ``N_p-disc − 1``
    bins are the intervals between neighbouring points, bin ``b`` being
    ``[origin + b·spacing, origin + (b+1)·spacing)`` (the last bin closed) with centre
    ``origin + (b + ½)·spacing``. A value is grouped to its bin's centre.

    Bin indices are global integers anchored at ``origin``: when later samples fall
    outside, the grid is extended by whole bins of the same spacing (``offset`` bins
    below ``origin``: bins ``−offset … n_bins − offset − 1``) and no existing bin is
    renumbered.

    The first batch's largest value lies exactly on the top point and belongs to the bin
    below it (within ``EDGE_TOL`` spacings); that bin's upper edge stays closed when the
    grid is extended above it (``closed_top``), so a value is grouped to the same bin on
    the first grid and on every extension of it.

    Attributes:
        origin: the first batch's smallest value (bin 0's lower edge).
        spacing: distance between neighbouring points.
        n_points: discretisation points currently covered (bins = ``n_points − 1``).
        offset: bins added below ``origin``.
        closed_top: the bin whose upper edge is closed; None: the last bin.
    """

    origin: float
    spacing: float
    n_points: int
    offset: int = 0
    closed_top: int | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.origin) and math.isfinite(self.spacing) and self.spacing > 0):
            raise ParameterError(f"grid: origin must be finite and spacing > 0; got {self.origin}, {self.spacing}")
        _whole(self.n_points, "grid n_points", 2)
        _whole(self.offset, "grid offset", 0)

    @classmethod
    def from_range(cls, low: float, high: float, n_disc: int) -> Grid:
        """``n_disc`` points from ``low`` to ``high``."""
        n_disc = _whole(n_disc, "n_disc", 2)
        if not high > low:
            raise ParameterError(f"grid: all samples coincide ({low}); nothing to discretise")
        return cls(float(low), (float(high) - float(low)) / (n_disc - 1), n_disc)

    @classmethod
    def from_samples(cls, samples: np.ndarray, n_disc: int) -> Grid:
        samples = np.asarray(samples, dtype=float)
        return cls.from_range(float(samples.min()), float(samples.max()), n_disc)

    @property
    def n_bins(self) -> int:
        return self.n_points - 1

    @property
    def first_bin(self) -> int:
        return -self.offset

    @property
    def last_bin(self) -> int:
        return self.n_bins - self.offset - 1

    @property
    def possible_intervals(self) -> int:
        """Eq. 2.32: ``N(N+1)/2`` intervals ``[c_l, c_r]``, ``l ≤ r``, over ``N`` bins —
        equal to ``C(N_p-disc, 2)`` for ``N_p-disc = N + 1`` points (30 points → 435)."""
        return self.n_bins * (self.n_bins + 1) // 2

    def points(self) -> np.ndarray:
        """The discretisation points."""
        return self.origin + (np.arange(self.n_points) - self.offset) * self.spacing

    def centres(self, bins: np.ndarray | int | None = None) -> np.ndarray:
        """Centres of ``bins`` (default: all bins, lowest first)."""
        if bins is None:
            bins = np.arange(self.first_bin, self.last_bin + 1)
        return self.origin + (np.asarray(bins, dtype=float) + 0.5) * self.spacing

    def bins_of(self, values: np.ndarray) -> np.ndarray:
        """Bin index of each value (may lie outside the grid; see :meth:`extended`)."""
        u = (np.asarray(values, dtype=float) - self.origin) / self.spacing
        bins = np.floor(u).astype(np.int64)
        top = (self.last_bin if self.closed_top is None else self.closed_top) + 1
        return np.where((bins == top) & (u - top <= EDGE_TOL), top - 1, bins)

    def extended(self, values: np.ndarray) -> Grid:
        """The grid grown by whole bins until it covers ``values`` (self if it does)."""
        bins = self.bins_of(values)
        if bins.size == 0:
            return self
        first, last = min(self.first_bin, int(bins.min())), max(self.last_bin, int(bins.max()))
        if (first, last) == (self.first_bin, self.last_bin):
            return self
        closed = self.last_bin if self.closed_top is None else self.closed_top
        return Grid(self.origin, self.spacing, last - first + 2, -first, closed)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def group(samples: np.ndarray, grid: Grid) -> np.ndarray:
    """Group samples (thesis §2.7.4, "Grouping of samples").

    Args:
        samples: ``(..., n_alpha, 2)`` α-cuts (or any array of parameter values).
        grid: a grid covering them (see :meth:`Grid.extended`).

    Returns:
        Bin indices of the same shape; the grouped values are ``grid.centres(bins)``.
    """
    bins = grid.bins_of(samples)
    if bins.size and (bins.min() < grid.first_bin or bins.max() > grid.last_bin):
        raise ParameterError(
            f"samples reach bins {int(bins.min())}…{int(bins.max())} outside the grid's "
            f"{grid.first_bin}…{grid.last_bin}; group on grid.extended(samples)"
        )
    return bins


def _encode(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    return (np.asarray(left, dtype=np.int64) + KEY_BIAS) * KEY_BASE + (np.asarray(right, dtype=np.int64) + KEY_BIAS)


def _decode(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    keys = np.asarray(keys, dtype=np.int64)
    return keys // KEY_BASE - KEY_BIAS, keys % KEY_BASE - KEY_BIAS


def _interval_keys(bins: np.ndarray) -> np.ndarray:
    """Sorted unique keys of the α < 1 intervals of grouped samples ``(n, n_alpha, 2)``."""
    return np.unique(_encode(bins[:, :-1, 0], bins[:, :-1, 1]))


def occurring_intervals(bins: np.ndarray) -> np.ndarray:
    """The ``(left_bin, right_bin)`` pairs present in grouped samples ``(n, n_alpha, 2)``
    at α-levels below 1, sorted; α = 1 cuts are degenerate ``(b, b)`` (the library entry
    itself) and are not intervals to optimise."""
    return np.stack(_decode(_interval_keys(np.asarray(bins))), axis=1)


# ---------------------------------------------------------------------------- several FRVs
def possible_boxes(grids: Sequence[Grid]) -> int:
    """Possible α-cut boxes over per-parameter grids: the product of each parameter's
    possible intervals (Eq. 2.32) — the multi-parameter worst case the thesis states after
    Eq. 2.33 (grids of 4 and 3 points, 3 and 2 bins: ``6 · 3 = 18`` boxes)."""
    return math.prod(g.possible_intervals for g in grids)


def box_rows(bins: np.ndarray) -> np.ndarray:
    """The α < 1 boxes of grouped samples ``(n, n_params, n_alpha, 2)`` as rows
    ``(n, n_alpha − 1, 2·n_params)``: ``(left_1, right_1, left_2, right_2, …)`` — the key
    of a box, the tuple of its per-parameter ``(left bin, right bin)`` pairs."""
    bins = np.asarray(bins, dtype=np.int64)
    n, n_params, n_alpha, _ = bins.shape
    return np.moveaxis(bins[:, :, :-1, :], 1, 2).reshape(n, n_alpha - 1, 2 * n_params)


def occurring_boxes(bins: np.ndarray) -> np.ndarray:
    """The keys ``(k, 2·n_params)`` of the boxes present in grouped samples ``(n, n_params,
    n_alpha, 2)`` at α-levels below 1, unique and sorted lexicographically (for one
    parameter: :func:`occurring_intervals`)."""
    rows = box_rows(bins)
    return np.unique(rows.reshape(-1, rows.shape[-1]), axis=0)
