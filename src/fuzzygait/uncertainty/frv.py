"""Fuzzy random variables and the FRV Graph Follower algorithm (thesis §2.7, §5.7).

A fuzzy random variable (FRV) is a random variable whose realisations are convex fuzzy
numbers (Eq. 2.25). Propagating one through a model ``f(p) -> (n_time,)`` takes the nested
steps of the FRV-GFA (thesis §2.7.4, "FRV-GFA steps"):

1. **Sample generation** (:func:`generate_samples`, Eqs. 2.26–2.30): ``N_s`` fuzzy-number
   samples of the FRV parameter, each described by ``N_α`` α-cuts.
2. **Grouping** (:class:`Grid`, :func:`group`, Eqs. 2.31–2.32): the sample range is
   discretised into ``N_p-disc`` equidistant points; every α-cut end is mapped to the
   centre of the bin between two neighbouring points. The α-cuts become intervals between
   bin centres, most of which recur across the samples.
3.–4. **Keys and dictionaries**: an interval is keyed by its ``(left bin, right bin)``
   pair; only *occurring* intervals (present in at least one sample) get an entry.
5. **Hulls** (:func:`interval_hulls`): the model is evaluated once per bin centre (the
   library ``f_lib``, one forward simulation each, through an injectable batch
   ``evaluator``). Because every interval end is a bin centre and the GFA's novelty check
   maps optima onto library entries, the α-level optimisation of an interval returns the
   extreme library value over the bins inside it; all occurring intervals are answered
   at once by sparse-table range-max/min queries. With sensitivities the thesis'
   linearisation between neighbouring library entries is used as a cubic Hermite
   interpolant per sub-interval, whose interior extremum is taken in closed form
   (``refine``).
6.–7. **Assembly**: each sample's output fuzzy number at every time node is its
   intervals' hulls (α = 1: the library value at the peak bin), passed through
   :func:`~fuzzygait.uncertainty.postprocess.repair_nesting` (Fig. 2.11).
8.–9. **Increments and fitting** (:func:`fit_distributions`).

:class:`FRVStudy` runs steps 1–7 into a chunked zarr store, block by block (the
``(n_samples, n_alpha, 2, n_time)`` hull array is never held in memory), and can add
samples later, simulating only new bin centres and computing only new intervals
(the extension the thesis describes as "not yet implemented", §2.7.4).

Only one FRV parameter is supported (the Table 5.3 case); see :class:`FRVStudy`.
"""

from __future__ import annotations

import math
import os
import shutil
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
import zarr
from scipy import stats

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.uncertainty.fuzzy import _as_levels
from fuzzygait.uncertainty.gfa import BOUNDS, optimisation_nodes
from fuzzygait.uncertainty.model import CountedModel, has_sensitivities
from fuzzygait.uncertainty.postprocess import repair_nesting

#: Samples per random stream: sample ``i`` is drawn from ``default_rng([seed, i // BLOCK])``
#: so it is the same whatever blocks the samples are requested in.
BLOCK = 1024
#: A value within this fraction of a spacing above the grid's top point belongs to the
#: last bin (the largest sample of the first batch lies exactly on the top point).
EDGE_TOL = 1e-9
#: Interval keys: ``(left + KEY_BIAS) * KEY_BASE + (right + KEY_BIAS)`` (bins in ±2^30).
KEY_BIAS, KEY_BASE = 1 << 30, 1 << 31
DISTRIBUTIONS = ("normal", "beta")
STORE_FORMAT = "fuzzygait-frv-1"

Evaluator = Callable[[np.ndarray], "np.ndarray | tuple[np.ndarray, np.ndarray]"]


# =========================================================================== samples
@dataclass(frozen=True)
class FRVSpec:
    """A fuzzy random parameter (thesis §2.7.1, Table 5.3).

    Attributes:
        name: parameter name.
        deterministic: ``p_det``, the deterministic value (non-zero: it sets the scale).
        relative_scale: the 0.1 of Eqs. 2.28–2.29; increments scale with
            ``relative_scale·|p_det|``.
        alphas: increasing α-levels, the last one 1 (at least two levels).
        distribution: ``"normal"`` (thesis §2.7.2, increments redrawn while ≤ 0) or
            ``"beta"`` (§5.7.2: beta-distributed increments, normal peak).
        mean, std: the normal distribution ``N(mean, std)`` of the peak draw (both
            distributions) and of the increments (``"normal"``); the thesis uses N(1, 1).
        beta_a, beta_b: shape parameters of the increments' beta distribution.
    """

    name: str
    deterministic: float
    relative_scale: float = 0.1
    alphas: tuple[float, ...] = (0.0, 0.5, 1.0)
    distribution: str = "normal"
    mean: float = 1.0
    std: float = 1.0
    beta_a: float = 2.0
    beta_b: float = 2.0

    def __post_init__(self) -> None:
        label = f"FRV {self.name!r}"
        levels = _as_levels(self.alphas)
        if levels[-1] != 1.0 or levels.size < 2:
            raise ParameterError(f"{label}: alphas must end with 1 and have a level below it; got {levels.tolist()}")
        object.__setattr__(self, "alphas", tuple(float(a) for a in levels))
        values = {k: float(getattr(self, k)) for k in ("deterministic", "relative_scale", "mean", "std", "beta_a", "beta_b")}
        if not all(math.isfinite(v) for v in values.values()):
            raise ParameterError(f"{label}: parameters must be finite; got {values}")
        if values["deterministic"] == 0.0:
            raise ParameterError(f"{label}: deterministic value must be non-zero (it sets the increments' scale, Eq. 2.28)")
        if values["relative_scale"] <= 0 or values["std"] <= 0:
            raise ParameterError(f"{label}: relative_scale and std must be > 0; got {values['relative_scale']}, {values['std']}")
        if self.distribution not in DISTRIBUTIONS:
            raise ParameterError(f"{label}: distribution must be 'normal' or 'beta'; got {self.distribution!r}")
        if values["beta_a"] <= 0 or values["beta_b"] <= 0:
            raise ParameterError(f"{label}: beta_a and beta_b must be > 0")
        if self.distribution == "normal" and values["mean"] / values["std"] < -3.0:
            raise ParameterError(
                f"{label}: increments N({values['mean']}, {values['std']}) are positive in under 0.2 % of draws; "
                "the redraw (Eq. 2.21) would hardly terminate — use mean/std >= -3"
            )
        for key, value in values.items():
            object.__setattr__(self, key, value)

    @property
    def scale(self) -> float:
        """``relative_scale·|p_det|``: the Δp of one unit of the drawn value (Eq. 2.28)."""
        return self.relative_scale * abs(self.deterministic)

    @property
    def n_alpha_divisor(self) -> int:
        """``N_α`` of Eq. 2.29: the number of α-levels below 1 (= increments per side)."""
        return len(self.alphas) - 1

    @property
    def increment_scale(self) -> float:
        """``relative_scale·|p_det|/N_α`` (Eq. 2.29)."""
        return self.scale / self.n_alpha_divisor

    def peak_distribution(self) -> Any:
        """The peak's distribution ``N(p_det + mean·s, (std·s)²)``, ``s`` = :attr:`scale`."""
        return stats.norm(self.deterministic + self.mean * self.scale, self.std * self.scale)

    def increment_distribution(self) -> Any:
        """The distribution of every increment ``Δp_{l/r, α<1}``: the normal truncated to
        positive values (what redrawing yields) or the scaled beta."""
        c = self.increment_scale
        if self.distribution == "beta":
            return stats.beta(self.beta_a, self.beta_b, loc=0.0, scale=c)
        return stats.truncnorm(-self.mean / self.std, np.inf, loc=self.mean * c, scale=self.std * c)

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["alphas"] = list(self.alphas)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> FRVSpec:
        return cls(**{**data, "alphas": tuple(data["alphas"])})


def _whole(value: object, name: str, minimum: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < minimum:
        raise ParameterError(f"{name} must be a whole number >= {minimum}; got {value!r}")
    return int(value)


def _sample_block(spec: FRVSpec, seed: int, block: int) -> np.ndarray:
    """The ``BLOCK`` samples of block ``block`` (see :func:`generate_samples`)."""
    rng = np.random.default_rng([seed, block])
    peak = spec.deterministic + rng.normal(spec.mean, spec.std, BLOCK) * spec.scale  # Eq. 2.28
    shape = (BLOCK, spec.n_alpha_divisor, 2)
    if spec.distribution == "beta":
        drawn = rng.beta(spec.beta_a, spec.beta_b, shape)
    else:
        drawn = rng.normal(spec.mean, spec.std, shape)
        while True:  # redraw non-positive increments (convexity, Eq. 2.21); terminates (mean/std >= -3)
            bad = drawn <= 0.0
            count = int(np.count_nonzero(bad))
            if not count:
                break
            drawn[bad] = rng.normal(spec.mean, spec.std, count)
    delta = drawn * spec.increment_scale  # Eq. 2.29; delta[:, 0] is the step below α = 1
    n_alpha = len(spec.alphas)
    cuts = np.empty((BLOCK, n_alpha, 2))
    cuts[:, -1, :] = peak[:, None]
    for step, k in enumerate(range(n_alpha - 2, -1, -1)):  # Eq. 2.30, from α = 1 downwards
        cuts[:, k, 0] = cuts[:, k + 1, 0] - delta[:, step, 0]
        cuts[:, k, 1] = cuts[:, k + 1, 1] + delta[:, step, 1]
    return cuts


def generate_samples(spec: FRVSpec, n: int, seed: int = 0, start: int = 0) -> np.ndarray:
    """Samples ``start … start+n−1`` of the FRV (thesis Eqs. 2.26–2.30).

    Each sample is a fuzzy number built from its peak downwards:

    * peak (Eq. 2.28, implemented as printed): ``p_peak = p_det + X·s`` with
      ``X ~ N(mean, std)`` and ``s = relative_scale·|p_det|``. With the thesis' N(1, 1)
      the peak is *shifted* by one ``s`` on average: ``p_peak ~ N(p_det + mean·s, (std·s)²)``.
      (``|p_det|`` makes the scale a magnitude; the thesis' ``p_det`` is positive.)
    * increments (Eq. 2.29): ``Δ = X·s/N_α`` for every α-level below 1 and each side, with
      ``N_α`` the number of α-levels *below 1* (the number of increments per side), so
      the expected α = 0 half-width ``E[X]·s`` does not depend on how many α-levels are
      used — the purpose the thesis gives for the division. ``"normal"``: ``X ~ N(mean,
      std)`` redrawn while ``X ≤ 0`` (the truncation of §2.7.2); ``"beta"``:
      ``X ~ Beta(a, b)`` in [0, 1], no redraw needed (§5.7.2).
    * α-cuts (Eq. 2.30): ``p_{l,k−1} = p_{l,k} − Δ_l``, ``p_{r,k−1} = p_{r,k} + Δ_r``.

    Sample ``i`` is a function of ``(spec, seed, i)`` only: it is taken from block
    ``i // BLOCK`` generated with ``np.random.default_rng([seed, i // BLOCK])``, so two
    calls ``(start=0, n=a)`` and ``(start=a, n=b)`` give the samples of one call ``n=a+b``.

    Returns:
        ``(n, n_alpha, 2)``: per sample and α-level (in ``spec.alphas`` order) the α-cut
        ``[left, right]``; the α = 1 cut is ``[peak, peak]``.
    """
    n, start, seed = _whole(n, "n"), _whole(start, "start"), _whole(seed, "seed")
    out = np.empty((n, len(spec.alphas), 2))
    stop = start + n
    for block in range(start // BLOCK, (stop - 1) // BLOCK + 1 if n else start // BLOCK):
        first = block * BLOCK
        a, b = max(start, first), min(stop, first + BLOCK)
        out[a - start : b - start] = _sample_block(spec, seed, block)[a - first : b - first]
    return out


def sample_increments(samples: np.ndarray) -> np.ndarray:
    """The l_α r_α-increments of fuzzy-number samples (Eq. 2.20).

    Args:
        samples: ``(..., n_alpha, 2)`` α-cuts ``[left, right]``, α increasing.

    Returns:
        ``(..., n_alpha, 2)``: for α_k < 1 ``left(α_{k+1}) − left(α_k)`` and
        ``right(α_k) − right(α_{k+1})`` (both ≥ 0 for a convex number); at α = 1 the peak
        (the α = 1 left end, both bounds) — the ``Δp_{α=1}`` entry of Eq. 2.26.
    """
    samples = np.asarray(samples, dtype=float)
    out = np.empty_like(samples)
    out[..., :-1, 0] = samples[..., 1:, 0] - samples[..., :-1, 0]
    out[..., :-1, 1] = samples[..., :-1, 1] - samples[..., 1:, 1]
    out[..., -1, :] = samples[..., -1, 0, None]
    return out


# =========================================================================== grouping
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

    Attributes:
        origin: the first batch's smallest value (bin 0's lower edge).
        spacing: distance between neighbouring points.
        n_points: discretisation points currently covered (bins = ``n_points − 1``).
        offset: bins added below ``origin``.
    """

    origin: float
    spacing: float
    n_points: int
    offset: int = 0

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
        top = self.last_bin + 1
        return np.where((bins == top) & (u - top <= EDGE_TOL), top - 1, bins)

    def extended(self, values: np.ndarray) -> Grid:
        """The grid grown by whole bins until it covers ``values`` (self if it does)."""
        bins = self.bins_of(values)
        if bins.size == 0:
            return self
        first, last = min(self.first_bin, int(bins.min())), max(self.last_bin, int(bins.max()))
        if (first, last) == (self.first_bin, self.last_bin):
            return self
        return Grid(self.origin, self.spacing, last - first + 2, -first)

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


# =========================================================================== hulls
def range_extrema(low_values: np.ndarray, high_values: np.ndarray, first: np.ndarray,
                  last: np.ndarray, time_block: int = 256) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Minimum of ``low_values`` and maximum of ``high_values`` over the rows
    ``first[q] … last[q]`` (inclusive) of every query ``q``, for all columns at once.

    A sparse table (row ranges of length 2^j) answers each query with two look-ups; it
    is built per block of ``time_block`` columns to bound memory.

    Returns:
        ``(minimum, maximum)``, each ``(n_queries, n_columns)``.
    """
    low_values, high_values = np.asarray(low_values, dtype=float), np.asarray(high_values, dtype=float)
    first, last = np.asarray(first, dtype=np.int64), np.asarray(last, dtype=np.int64)
    m, n_col = low_values.shape
    if first.size and (first.min() < 0 or last.max() >= m or np.any(first > last)):
        raise ParameterError("range query outside the rows or with first > last")
    length = last - first + 1
    powers = 1 << np.arange(max(1, int(m).bit_length()), dtype=np.int64)
    level = np.searchsorted(powers, length, side="right") - 1  # floor(log2(length))
    minimum, maximum = np.empty((first.size, n_col)), np.empty((first.size, n_col))
    levels = np.unique(level)
    for c0 in range(0, n_col, time_block):
        cols = slice(c0, c0 + time_block)
        lo, hi = low_values[:, cols], high_values[:, cols]
        for j in range(int(levels.max()) + 1 if levels.size else 0):
            if j:
                half = 1 << (j - 1)
                lo, hi = np.minimum(lo[:-half], lo[half:]), np.maximum(hi[:-half], hi[half:])
            sel = np.flatnonzero(level == j)
            if sel.size:
                a, b = first[sel], last[sel] - (1 << j) + 1
                minimum[sel, cols] = np.minimum(lo[a], lo[b])
                maximum[sel, cols] = np.maximum(hi[a], hi[b])
    return minimum, maximum


def hermite_segment_extrema(values: np.ndarray, slopes: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Extrema of the cubic Hermite interpolant between neighbouring library entries.

    Args:
        values: ``(m, n_time)`` library values at equidistant parameters.
        slopes: ``(m, n_time)`` their derivatives ``df/dp``.
        spacing: the parameter distance ``h`` between neighbouring entries.

    Returns:
        ``(minimum, maximum)``, each ``(m − 1, n_time)``: per sub-interval the extremes of
        its ends and of the interpolant's interior stationary points (roots of the
        quadratic derivative, in closed form). The interpolant's error is at most
        ``h⁴/384·max|∂⁴f/∂p⁴|``, which bounds the error of these extrema too.
    """
    f0, f1 = values[:-1], values[1:]
    m0, m1 = spacing * slopes[:-1], spacing * slopes[1:]
    a = 2.0 * f0 + m0 - 2.0 * f1 + m1  # H(s) = a s³ + b s² + m0 s + f0, s ∈ [0, 1]
    b = -3.0 * f0 - 2.0 * m0 + 3.0 * f1 - m1
    lo, hi = np.minimum(f0, f1), np.maximum(f0, f1)
    qa, qb = 3.0 * a, 2.0 * b  # H'(s) = qa s² + qb s + m0
    disc = qb * qb - 4.0 * qa * m0
    real = disc >= 0.0
    q = -0.5 * (qb + np.copysign(np.sqrt(np.where(real, disc, 0.0)), qb))  # stable roots q/qa, m0/q
    with np.errstate(divide="ignore", invalid="ignore"):
        for s in (q / qa, m0 / q):
            inside = real & (s > 0.0) & (s < 1.0)
            s = np.where(inside, s, 0.0)
            h = ((a * s + b) * s + m0) * s + f0
            lo = np.where(inside, np.minimum(lo, h), lo)
            hi = np.where(inside, np.maximum(hi, h), hi)
    return lo, hi


def interval_hulls(values: np.ndarray, left: np.ndarray, right: np.ndarray, *,
                   slopes: np.ndarray | None = None, spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Lower and upper hull of the output over parameter intervals of a library.

    Args:
        values: ``(m, n_time)`` model outputs at ``m`` consecutive bin centres.
        left, right: ``(k,)`` row indices (into ``values``) of each interval's ends.
        slopes: optional ``(m, n_time)`` ``df/dp``; given, the hull also takes the
            extrema of the cubic Hermite interpolant between neighbouring rows inside the
            interval (the linearised refinement); otherwise it is exactly the extreme
            library value over rows ``left … right``.
        spacing: parameter distance between rows (needed with ``slopes``).

    Returns:
        ``(lower, upper)``, each ``(k, n_time)``.
    """
    values = np.asarray(values, dtype=float)
    left, right = np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)
    if slopes is None:
        return range_extrema(values, values, left, right)
    if spacing is None:
        raise ParameterError("interval_hulls: spacing is needed with slopes")
    lower, upper = values[left], values[left].copy()
    proper = np.flatnonzero(right > left)
    if proper.size:
        seg_lo, seg_hi = hermite_segment_extrema(values, np.asarray(slopes, dtype=float), float(spacing))
        lower[proper], upper[proper] = range_extrema(seg_lo, seg_hi, left[proper], right[proper] - 1)
    return lower, upper


# =========================================================================== evaluation
def serial_evaluator(model: object) -> Evaluator:
    """The default batch evaluator: ``P (k, n_p) -> F (k, n_time)`` by a loop over
    ``model.evaluate``, or ``(F, J (k, n_time, n_p))`` over
    ``model.evaluate_with_sensitivities`` when the model offers sensitivities."""
    counted = CountedModel(model, scale=np.ones(1))
    with_sensitivities = has_sensitivities(model)

    def evaluate(P: np.ndarray) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        P = np.atleast_2d(np.asarray(P, dtype=float))
        if with_sensitivities:
            pairs = [counted.trajectory_and_sensitivities(p) for p in P]
            return np.stack([f for f, _ in pairs]), np.stack([j for _, j in pairs])
        return np.stack([counted.trajectory(p) for p in P])

    return evaluate


def _run_evaluator(evaluator: Evaluator, P: np.ndarray, n_time: int) -> tuple[np.ndarray, np.ndarray | None]:
    out = evaluator(P)
    F, J = (out[0], out[1]) if isinstance(out, tuple) else (out, None)
    F = np.asarray(F, dtype=float)
    k = P.shape[0]
    if F.shape != (k, n_time):
        raise ParameterError(f"the evaluator returned shape {F.shape} for {k} parameters and {n_time} time nodes")
    if not np.all(np.isfinite(F)):
        bad = np.flatnonzero(~np.all(np.isfinite(F), axis=1))
        raise ParameterError(f"the model returned non-finite outputs for parameters {P[bad, 0].tolist()}")
    if J is not None:
        J = np.asarray(J, dtype=float).reshape(k, n_time, -1)[..., 0]
    return F, J


# =========================================================================== study
def _single_spec(spec: FRVSpec | Sequence[FRVSpec]) -> FRVSpec:
    if isinstance(spec, FRVSpec):
        return spec
    specs = list(spec)
    if len(specs) == 1 and isinstance(specs[0], FRVSpec):
        return specs[0]
    raise ParameterError(
        f"FRV-GFA grouping supports one FRV parameter; got {len(specs)}. Several would need "
        "tensor grids (their worst case is the product of Eq. 2.33 per parameter) — not implemented"
    )


def _blocks(start: int, stop: int, chunk: int) -> Iterator[tuple[int, int]]:
    """Sample ranges aligned to multiples of ``chunk`` (so appends fill zarr chunks)."""
    a = start
    while a < stop:
        b = min(stop, (a // chunk + 1) * chunk)
        yield a, b
        a = b


def _open_group(path: Path, name: str) -> xr.Dataset:
    """Group ``name`` lazily: slices are read on access, nothing is cached."""
    return xr.open_dataset(path, engine="zarr", group=name, consolidated=False, chunks=None, cache=False)


def _append(path: Path, name: str, ds: xr.Dataset, dim: str, encoding: dict[str, Any] | None = None) -> None:
    """Write ``ds`` to group ``name``: create it, or append along ``dim``."""
    root = zarr.open_group(path, mode="r")
    if name in root:
        ds.to_zarr(path, group=name, append_dim=dim, consolidated=False, zarr_format=2)
    else:
        ds.to_zarr(path, group=name, mode="w-", consolidated=False, zarr_format=2, encoding=encoding)


def _new_counts() -> dict[str, Any]:
    return {"samples": 0, "forward_simulations": 0, "interval_optimisations": 0, "occurring_intervals": 0,
            "occurring_proper_intervals": 0, "possible_intervals": 0, "worst_case_optimisations": 0,
            "time_nodes": 0, "repaired_values": 0, "wall_time": 0.0, "last_forward_simulations": 0,
            "last_new_intervals": 0, "last_wall_time": 0.0}  # fmt: skip


class FRVStudy:
    """An FRV-GFA study persisted in a zarr store (directory), extendable by samples.

    Store layout (zarr v2 groups, written through xarray):

    * root attributes: ``spec``, ``seed``, ``grid``, ``n_disc``, ``time_stride``,
      ``refine``, ``chunk``, ``n_time`` (the model's), ``n_samples`` and ``counts``;
    * ``library``: ``value (bin, time)`` the model at each bin centre (``slope`` = df/dp
      when refining), ``centre (bin)``; rows in order of computation;
    * ``intervals``: ``left``, ``right (interval)`` bins and ``lower``, ``upper
      (interval, time)`` hulls — the dictionary of occurring intervals;
    * ``samples``: ``hull (sample, alpha, bound, time)`` chunked ``(chunk, all, 2, all)``
      with the raw α-cuts ``cut (sample, alpha, bound)`` and their ``bin``, written block
      by block (one append along ``sample`` per block of ``chunk`` samples).

    Only the output time nodes ``optimisation_nodes(n_time, time_stride)`` are kept (the
    library too). Use :meth:`create`, :meth:`open`, :meth:`add_samples`; read with
    :meth:`hulls`, :meth:`samples`, :meth:`library`, :meth:`intervals`, :attr:`counts`.
    """

    def __init__(self, path: Path, model: object, spec: FRVSpec, meta: dict[str, Any],
                 evaluator: Evaluator | None) -> None:  # fmt: skip
        self.path, self.model, self.spec = path, model, spec
        self.seed: int = meta["seed"]
        self.grid = Grid(**meta["grid"])
        self.n_disc: int = meta["n_disc"]
        self.time_stride: int = meta["time_stride"]
        self.refine: bool | None = meta["refine"]
        self.chunk: int = meta["chunk"]
        self.n_time: int = meta["n_time"]
        self.n_samples: int = meta["n_samples"]
        self.counts: dict[str, Any] = dict(meta["counts"])
        self.evaluator = evaluator if evaluator is not None else serial_evaluator(model)
        times = np.asarray(model.times, dtype=float)
        if times.ndim != 1 or times.size != self.n_time:
            raise ParameterError(f"{path}: the study has {self.n_time} time nodes; the model has {times.size}")
        self.nodes = optimisation_nodes(self.n_time, self.time_stride)
        self.times = times[self.nodes]
        # library: contiguous bins lib_first … lib_first + m − 1
        self._lib_first = 0
        self._lib_values = np.empty((0, self.nodes.size))
        self._lib_slopes: np.ndarray | None = None
        # interval dictionary, sorted by key
        self._keys = np.empty(0, dtype=np.int64)
        self._int_lower = np.empty((0, self.nodes.size))
        self._int_upper = np.empty((0, self.nodes.size))

    # ------------------------------------------------------------------ create / open
    @classmethod
    def create(cls, model: object, spec: FRVSpec | Sequence[FRVSpec], n_samples: int, n_disc: int = 100,
               seed: int = 0, store: str | os.PathLike[str] | None = None, evaluator: Evaluator | None = None,
               time_stride: int = 1, refine: bool | None = None, chunk: int = 256,
               overwrite: bool = False) -> FRVStudy:  # fmt: skip
        """Run the FRV-GFA for ``n_samples`` samples into a new store.

        Args:
            model: ``times`` and ``evaluate(p)`` (``p`` of shape ``(1,)``), optionally
                ``evaluate_with_sensitivities``.
            spec: the FRV parameter (one; a sequence of several raises ParameterError).
            n_samples: ``N_s``.
            n_disc: ``N_p-disc`` grid points over the first batch's range.
            seed: seed of the sample streams.
            store: the zarr directory to create.
            evaluator: batch evaluator ``P (k, 1) -> (k, n_time)`` or ``((k, n_time),
                (k, n_time, 1))`` with sensitivities; default :func:`serial_evaluator`.
            time_stride: keep every ``time_stride``-th time node (and the last).
            refine: Hermite refinement between library entries; default: when the
                evaluator returns sensitivities.
            chunk: samples per zarr chunk and per processing block.
            overwrite: replace an existing store.
        """
        t0 = time.perf_counter()
        spec = _single_spec(spec)
        n_samples = _whole(n_samples, "n_samples", 1)
        seed, chunk = _whole(seed, "seed"), _whole(chunk, "chunk", 1)
        time_stride, n_disc = _whole(time_stride, "time_stride", 1), _whole(n_disc, "n_disc", 2)
        if store is None:
            raise ParameterError("store: give the path of the zarr directory to create")
        path = Path(store)
        if path.exists():
            if not overwrite:
                raise FuzzyGaitError(f"{path}: already exists; open it with FRVStudy.open or pass overwrite=True")
            shutil.rmtree(path)
        if not path.parent.exists():
            raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
        n_time = CountedModel(model, scale=np.ones(1)).n_time
        low, high = _sample_range(spec, seed, 0, n_samples, chunk)
        meta = {"seed": seed, "grid": Grid.from_range(low, high, n_disc).to_dict(), "n_disc": n_disc,
                "time_stride": time_stride, "refine": refine, "chunk": chunk, "n_time": n_time,
                "n_samples": 0, "counts": _new_counts()}  # fmt: skip
        zarr.open_group(path, mode="w-", zarr_format=2).attrs.update({"format": STORE_FORMAT, "spec": spec.to_dict(), **meta})
        study = cls(path, model, spec, meta, evaluator)
        study._ingest(0, n_samples, t0)
        return study

    @classmethod
    def open(cls, path: str | os.PathLike[str], model: object, evaluator: Evaluator | None = None) -> FRVStudy:
        """Open a study written by :meth:`create` (the model must be the same one)."""
        path = Path(path)
        meta = _read_meta(path)
        study = cls(path, model, FRVSpec.from_dict(meta["spec"]), meta, evaluator)
        study._truncate()
        root = zarr.open_group(path, mode="r")
        if "library" in root:
            lib = _open_group(path, "library").sortby("bin")
            study._lib_first = int(lib["bin"][0]) if lib.sizes["bin"] else 0
            study._lib_values = lib["value"].to_numpy()
            study._lib_slopes = lib["slope"].to_numpy() if "slope" in lib else None
        if "intervals" in root:
            table = _open_group(path, "intervals")
            keys = _encode(table["left"].to_numpy(), table["right"].to_numpy())
            order = np.argsort(keys)
            study._keys = keys[order]
            study._int_lower = table["lower"].to_numpy()[order]
            study._int_upper = table["upper"].to_numpy()[order]
        return study

    # ------------------------------------------------------------------ public
    def add_samples(self, n: int) -> FRVStudy:
        """Add samples ``n_samples … n_samples + n − 1``: group them on the stored grid
        (extended by whole bins if they leave it), simulate only bin centres not yet in
        the library, compute only intervals not yet in the dictionary, and append the new
        samples' hulls. Earlier samples' hulls are not touched."""
        t0 = time.perf_counter()
        n = _whole(n, "n")
        if n:
            self._truncate()
            low, high = _sample_range(self.spec, self.seed, self.n_samples, n, self.chunk)
            self.grid = self.grid.extended(np.array([low, high]))
            self._write_meta()
            self._ingest(self.n_samples, n, t0)
        return self

    def hulls(self) -> xr.Dataset:
        """The output ``hull (sample, alpha, bound, time)``, lazily (nothing loaded),
        with the counts as attributes."""
        ds = _open_group(self.path, "samples")[["hull"]].isel(sample=slice(0, self.n_samples))
        ds.attrs.update(self.counts)
        return ds

    def samples(self) -> xr.Dataset:
        """The raw α-cuts ``cut`` and their ``bin`` (lazily)."""
        return _open_group(self.path, "samples")[["cut", "bin"]].isel(sample=slice(0, self.n_samples))

    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` at bin ``centre`` (and ``slope``), sorted."""
        return _open_group(self.path, "library").sortby("bin")

    def intervals(self) -> xr.Dataset:
        """The interval dictionary: ``left``, ``right`` bins, ``lower``, ``upper`` hulls."""
        return _open_group(self.path, "intervals")

    # ------------------------------------------------------------------ internals
    def _write_meta(self) -> None:
        self.counts["possible_intervals"] = self.grid.possible_intervals
        self.counts["time_nodes"] = int(self.nodes.size)
        self.counts["worst_case_optimisations"] = 2 * int(self.nodes.size) * self.grid.possible_intervals  # Eq. 2.33
        zarr.open_group(self.path, mode="a").attrs.update(
            {"grid": self.grid.to_dict(), "refine": self.refine, "n_samples": self.n_samples, "counts": self.counts}
        )

    def _truncate(self) -> None:
        """Drop sample rows beyond ``n_samples`` (left by an interrupted add)."""
        root = zarr.open_group(self.path, mode="a")
        if "samples" in root:
            for _, array in root["samples"].arrays():
                dims = array.attrs.get("_ARRAY_DIMENSIONS", [])
                if dims and dims[0] == "sample" and array.shape[0] > self.n_samples:
                    array.resize((self.n_samples, *array.shape[1:]))

    def _ingest(self, start: int, n: int, t0: float) -> None:
        """Steps 2–7 for samples ``start … start+n−1`` on the current grid: pass 2 finds
        their bins and occurring intervals; the library and the interval dictionary are
        completed; pass 3 draws and groups the samples again (a pure function of the
        sample index) and appends their hulls block by block."""
        stop = start + n
        keys = np.empty(0, dtype=np.int64)
        bin_lo, bin_hi = self.grid.last_bin, self.grid.first_bin
        for a, b in _blocks(start, stop, self.chunk):  # pass 2
            bins = group(generate_samples(self.spec, b - a, self.seed, a), self.grid)
            keys = np.union1d(keys, _interval_keys(bins))
            bin_lo, bin_hi = min(bin_lo, int(bins.min())), max(bin_hi, int(bins.max()))
        simulations = self._extend_library(bin_lo, bin_hi)
        new_keys = np.setdiff1d(keys, self._keys)
        self._add_intervals(new_keys)
        repaired, n_alpha = 0, len(self.spec.alphas)
        chunks = {"chunks": (self.chunk, n_alpha, 2)}
        encoding = {"hull": {"chunks": (self.chunk, n_alpha, 2, self.nodes.size)}, "cut": chunks, "bin": chunks}
        for a, b in _blocks(start, stop, self.chunk):  # pass 3
            cuts = generate_samples(self.spec, b - a, self.seed, a)
            bins = group(cuts, self.grid)
            hull, changed = self._assemble(bins, cuts[:, -1, 0])
            repaired += changed
            ds = xr.Dataset({"hull": (("sample", "alpha", "bound", "time"), hull),
                             "cut": (("sample", "alpha", "bound"), cuts), "bin": (("sample", "alpha", "bound"), bins)},
                            coords={"sample": np.arange(a, b)})  # fmt: skip
            if a == 0:  # the creating write carries the other coordinates
                ds = ds.assign_coords(alpha=list(self.spec.alphas), bound=list(BOUNDS), time=self.times)
            _append(self.path, "samples", ds, "sample", encoding)
        elapsed = time.perf_counter() - t0
        self.n_samples = stop
        self.counts.update(samples=stop, repaired_values=self.counts["repaired_values"] + repaired,
                           wall_time=self.counts["wall_time"] + elapsed, last_forward_simulations=simulations,
                           last_new_intervals=int(new_keys.size), last_wall_time=elapsed)  # fmt: skip
        self._write_meta()

    def _peak_values(self, peaks: np.ndarray) -> np.ndarray:
        slopes = self._lib_slopes[..., 0] if self._lib_slopes.ndim == 3 else self._lib_slopes
        first = float(self.grid.centres(self._lib_first))
        return _hermite_rows(self._lib_values, slopes, first, self.grid.spacing, peaks)

    def _extend_library(self, bin_lo: int, bin_hi: int) -> int:
        """Simulate the bin centres of ``bin_lo … bin_hi`` not yet in the library (one
        evaluator call); returns the number of forward simulations."""
        m = self._lib_values.shape[0]
        have_lo, have_hi = self._lib_first, self._lib_first + m - 1
        if m:
            bin_lo, bin_hi = min(bin_lo, have_lo), max(bin_hi, have_hi)
            missing = np.concatenate([np.arange(bin_lo, have_lo), np.arange(have_hi + 1, bin_hi + 1)])
        else:
            missing = np.arange(bin_lo, bin_hi + 1)
        if not missing.size:
            return 0
        centres = self.grid.centres(missing)
        F, J = _run_evaluator(self.evaluator, centres[:, None], self.n_time)
        if self.refine is None:
            self.refine = J is not None
        if self.refine and J is None:
            raise ParameterError("this study refines hulls with sensitivities; the evaluator returned none")
        values = F[:, self.nodes]
        slopes = J[:, self.nodes] if self.refine else None
        ds = xr.Dataset({"value": (("bin", "time"), values)}, coords={"bin": missing, "centre": ("bin", centres), "time": self.times})
        if slopes is not None:
            ds["slope"] = (("bin", "time"), slopes)
        _append(self.path, "library", ds, "bin")
        # merge into the contiguous in-memory library
        below = missing < have_lo if m else np.ones(missing.size, dtype=bool)
        self._lib_values = np.concatenate([values[below], self._lib_values, values[~below]])
        if slopes is not None:
            old = self._lib_slopes if self._lib_slopes is not None else np.empty((0, self.nodes.size))
            self._lib_slopes = np.concatenate([slopes[below], old, slopes[~below]])
        self._lib_first = bin_lo
        self.counts["forward_simulations"] += int(missing.size)
        self._write_meta()
        return int(missing.size)

    def _add_intervals(self, keys: np.ndarray) -> None:
        """Hulls of new intervals (sorted ``keys``) from the library; store them."""
        if not keys.size:
            return
        left, right = _decode(keys)
        rows_l, rows_r = left - self._lib_first, right - self._lib_first
        slopes = self._lib_slopes if self.refine else None
        lower, upper = interval_hulls(self._lib_values, rows_l, rows_r, slopes=slopes, spacing=self.grid.spacing)
        ds = xr.Dataset({"left": ("interval", left), "right": ("interval", right),
                         "lower": (("interval", "time"), lower), "upper": (("interval", "time"), upper)},
                        coords={"time": self.times})  # fmt: skip
        _append(self.path, "intervals", ds, "interval")
        all_keys = np.concatenate([self._keys, keys])
        order = np.argsort(all_keys, kind="stable")
        self._keys = all_keys[order]
        self._int_lower = np.concatenate([self._int_lower, lower])[order]
        self._int_upper = np.concatenate([self._int_upper, upper])[order]
        proper = int(np.count_nonzero(right > left))
        self.counts["occurring_intervals"] = int(self._keys.size)
        self.counts["occurring_proper_intervals"] += proper
        self.counts["interval_optimisations"] += 2 * proper * int(self.nodes.size)
        self._write_meta()

    def _assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped samples, nesting-repaired.

        α = 1 is the model at the sample's own peak: with sensitivities, the cubic Hermite
        interpolant of the library (values and slopes at the two neighbouring grid points,
        O(spacing⁴)) — so the α = 1 output keeps the peak distribution instead of the
        grid's staircase; without sensitivities, the value at the peak's bin centre."""
        idx = np.searchsorted(self._keys, _encode(bins[:, :-1, 0], bins[:, :-1, 1]))
        hull = np.empty((bins.shape[0], bins.shape[1], 2, self.nodes.size))
        hull[:, :-1, 0] = self._int_lower[idx]
        hull[:, :-1, 1] = self._int_upper[idx]
        if self.refine and self._lib_slopes is not None and self._lib_values.shape[0] >= 2:
            hull[:, -1, :] = self._peak_values(peaks)[:, None, :]
        else:
            hull[:, -1, :] = self._lib_values[bins[:, -1, 0] - self._lib_first][:, None, :]
        repaired = np.moveaxis(repair_nesting(np.moveaxis(hull, 0, 2)), 2, 0)
        return repaired, int(np.count_nonzero(repaired != hull))


def _hermite_rows(values: np.ndarray, slopes: np.ndarray, first_centre: float, spacing: float,
                  x: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation of library rows (grid points ``first_centre + k·spacing``)
    at the parameter values ``x``: ``(len(x), n_nodes)``."""
    u = (np.asarray(x, float) - first_centre) / spacing
    i = np.clip(np.floor(u).astype(np.int64), 0, values.shape[0] - 2)
    t = (u - i)[:, None]
    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
    return (h00 * values[i] + h10 * spacing * slopes[i]
            + h01 * values[i + 1] + h11 * spacing * slopes[i + 1])  # fmt: skip


def _sample_range(spec: FRVSpec, seed: int, start: int, n: int, chunk: int) -> tuple[float, float]:
    """Smallest and largest α-cut end of samples ``start … start+n−1`` (pass 1)."""
    low, high = np.inf, -np.inf
    for a, b in _blocks(start, start + n, max(chunk, BLOCK)):
        cuts = generate_samples(spec, b - a, seed, a)
        low, high = min(low, float(cuts[:, 0, 0].min())), max(high, float(cuts[:, 0, 1].max()))
    return low, high


def _read_meta(path: Path) -> dict[str, Any]:
    if not path.is_dir():
        raise FuzzyGaitError(f"{path}: no such FRV study; check the path")
    attrs = dict(zarr.open_group(path, mode="r").attrs)
    if attrs.get("format") != STORE_FORMAT:
        raise FuzzyGaitError(f"{path}: not an FRV study store (format {attrs.get('format')!r})")
    return attrs


# =========================================================================== fitting
def _store_path(store: FRVStudy | str | os.PathLike[str]) -> Path:
    return store.path if isinstance(store, FRVStudy) else Path(store)


def stored_samples(store: FRVStudy | str | os.PathLike[str]) -> int:
    """Number of samples in a stored study."""
    return int(_read_meta(_store_path(store))["n_samples"])


def iter_hull_blocks(store: FRVStudy | str | os.PathLike[str], data: str = "hulls") -> Iterator[np.ndarray]:
    """The stored output block by block (one zarr chunk of samples at a time):
    ``(nb, n_alpha, 2, n_time)`` hulls, or their l_α r_α-increments
    (:func:`sample_increments` per time node) with ``data="increments"``."""
    if data not in ("hulls", "increments"):
        raise ParameterError(f"data must be 'hulls' or 'increments'; got {data!r}")
    path = _store_path(store)
    meta = _read_meta(path)
    hull = _open_group(path, "samples")["hull"]
    for a, b in _blocks(0, meta["n_samples"], meta["chunk"]):
        block = hull.isel(sample=slice(a, b)).to_numpy()
        yield block if data == "hulls" else np.moveaxis(sample_increments(np.moveaxis(block, 3, 1)), 1, 3)


class _Moments:
    """Running count, mean and sum of squared deviations (Chan et al.'s merge)."""

    def __init__(self) -> None:
        self.n, self.mean, self.m2 = 0, 0.0, 0.0

    def add(self, block: np.ndarray) -> None:
        nb = block.shape[0]
        mean_b = block.mean(axis=0)
        m2_b = ((block - mean_b) ** 2).sum(axis=0)
        n = self.n + nb
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (nb / n)
        self.m2 = self.m2 + m2_b + delta**2 * (self.n * nb / n)
        self.n = n

    @property
    def variance(self) -> np.ndarray:
        return self.m2 / self.n


def fit_distributions(store: FRVStudy | str | os.PathLike[str], kind: str = "normal", data: str = "hulls",
                      exact_nodes: Sequence[int] = ()) -> xr.Dataset:  # fmt: skip
    """Fit a distribution per ``(alpha, bound, time)`` to the samples' output (step 9),
    streaming over the stored sample chunks.

    Args:
        store: a study or its store path.
        kind: ``"normal"``: ``mean`` and ``std`` (ddof 0 — the exact maximum-likelihood
            estimates, from running sums merged per block). ``"beta"``: each series is
            normalised to [0, 1] by its own min and max (``loc``, ``scale``; first pass —
            the thesis leaves the normalisation open, this is the per-(α, bound, time)
            choice), then method-of-moments ``a = m·c``, ``b = (1−m)·c`` with
            ``c = m(1−m)/v − 1`` (second pass); NaN where a series is constant.
        data: ``"hulls"`` (the α-cut values ``f_{α,l/r}``) or ``"increments"`` (the
            output's l_α r_α-increments; at α = 1 the peak value).
        exact_nodes: with ``kind="beta"``, output time-node indices at which
            ``scipy.stats.beta.fit`` (MLE, ``floc=0, fscale=1``) is also run on the
            normalised values compressed to ``(x(n−1) + ½)/n`` (Smithson & Verkuilen) —
            the min and max map to 0 and 1 exactly, where the likelihood is degenerate.

    Returns:
        Dataset over ``alpha``, ``bound``, ``time`` (``mean``, ``std`` or ``a``, ``b``,
        ``loc``, ``scale``; plus ``a_mle``, ``b_mle`` over ``exact_time``), attributes
        ``kind``, ``data``, ``n_samples``.
    """
    if kind not in DISTRIBUTIONS:
        raise ParameterError(f"kind must be 'normal' or 'beta'; got {kind!r}")
    path = _store_path(store)
    n_samples = _read_meta(path)["n_samples"]
    coords = _open_group(path, "samples").drop_dims("sample").coords
    dims = ("alpha", "bound", "time")
    attrs = {"kind": kind, "data": data, "n_samples": n_samples}
    if kind == "normal":
        moments = _Moments()
        for block in iter_hull_blocks(path, data):
            moments.add(block)
        return xr.Dataset({"mean": (dims, moments.mean), "std": (dims, np.sqrt(moments.variance))}, coords=coords, attrs=attrs)
    low, high = None, None
    for block in iter_hull_blocks(path, data):  # pass 1: normalisation
        b_lo, b_hi = block.min(axis=0), block.max(axis=0)
        low = b_lo if low is None else np.minimum(low, b_lo)
        high = b_hi if high is None else np.maximum(high, b_hi)
    scale = high - low
    safe = np.where(scale > 0, scale, 1.0)
    moments = _Moments()
    for block in iter_hull_blocks(path, data):  # pass 2: moments of the normalised values
        moments.add((block - low) / safe)
    m, v = moments.mean, moments.variance
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where((scale > 0) & (v > 0), m * (1.0 - m) / v - 1.0, np.nan)
    ds = xr.Dataset({"a": (dims, m * c), "b": (dims, (1.0 - m) * c), "loc": (dims, low), "scale": (dims, scale)},
                    coords=coords, attrs=attrs)  # fmt: skip
    nodes = [int(j) for j in exact_nodes]
    if nodes:
        n_alpha = ds.sizes["alpha"]
        columns = np.concatenate([block[..., nodes] for block in iter_hull_blocks(path, data)])  # (n, n_alpha, 2, k)
        a_mle = np.full((n_alpha, 2, len(nodes)), np.nan)
        b_mle = np.full_like(a_mle, np.nan)
        for index in np.ndindex(a_mle.shape):
            j = nodes[index[2]]
            if scale[index[0], index[1], j] <= 0:
                continue
            x = (columns[:, index[0], index[1], index[2]] - low[index[0], index[1], j]) / scale[index[0], index[1], j]
            x = (x * (x.size - 1) + 0.5) / x.size
            a_mle[index], b_mle[index], _, _ = stats.beta.fit(x, floc=0.0, fscale=1.0)
        ds["a_mle"] = (("alpha", "bound", "exact_time"), a_mle)
        ds["b_mle"] = (("alpha", "bound", "exact_time"), b_mle)
        ds = ds.assign_coords(exact_time=("exact_time", ds["time"].to_numpy()[nodes]), exact_node=("exact_time", nodes))
    return ds
