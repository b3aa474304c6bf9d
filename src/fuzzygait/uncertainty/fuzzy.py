"""Convex fuzzy numbers (thesis §2.5).

A fuzzy number is stored by its α-discretisation (Eq. 2.14–2.19): an increasing list of
α-levels ``0 = α_1 < … < α_N = 1`` with nested intervals ``[l_α, r_α]``. Between the
levels the membership function is taken piecewise linear, so a triangular number is
represented exactly by the two levels 0 and 1.

The :math:`l_α r_α`-discretisation (Eq. 2.20) describes the same number by its peak and
the non-negative increments from one level to the next lower one; convexity is exactly
the non-negativity of the increments (Eq. 2.21).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fuzzygait.core.errors import ParameterError


def _as_levels(alphas: Sequence[float] | np.ndarray) -> np.ndarray:
    levels = np.asarray(alphas, dtype=float)
    if levels.ndim != 1 or levels.size < 1:
        raise ParameterError("alphas must be a non-empty 1-D sequence")
    if not np.all((levels >= 0) & (levels <= 1)):
        raise ParameterError(f"alphas must lie in [0, 1]; got {levels.tolist()}")
    if np.any(np.diff(levels) <= 0):
        raise ParameterError(f"alphas must be strictly increasing; got {levels.tolist()}")
    return levels


@dataclass(frozen=True)
class FuzzyNumber:
    """A convex fuzzy number given by α-cuts.

    Attributes:
        alphas: strictly increasing α-levels, first 0, last 1.
        lower: left ends ``l_α`` of the α-cuts (non-decreasing with α).
        upper: right ends ``r_α`` of the α-cuts (non-increasing with α).
        name: optional label (parameter name).
    """

    alphas: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    name: str = ""

    def __post_init__(self) -> None:
        alphas = _as_levels(self.alphas)
        lower = np.asarray(self.lower, dtype=float)
        upper = np.asarray(self.upper, dtype=float)
        label = f"fuzzy number {self.name!r}" if self.name else "fuzzy number"
        if alphas[0] != 0.0 or alphas[-1] != 1.0:
            raise ParameterError(f"{label}: α-levels must run from 0 to 1; got {alphas.tolist()}")
        if lower.shape != alphas.shape or upper.shape != alphas.shape:
            raise ParameterError(f"{label}: one lower and one upper bound per α-level needed")
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise ParameterError(f"{label}: α-cut bounds must be finite")
        if np.any(lower > upper):
            raise ParameterError(f"{label}: an α-cut has lower > upper")
        if np.any(np.diff(lower) < 0) or np.any(np.diff(upper) > 0):
            raise ParameterError(
                f"{label}: not convex: higher α-cuts must lie inside lower ones (Eq. 2.19)"
            )
        object.__setattr__(self, "alphas", alphas)
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    # ------------------------------------------------------------------ views
    @property
    def peak(self) -> float:
        """The α = 1 value (midpoint of the α = 1 cut if it is an interval)."""
        return float(0.5 * (self.lower[-1] + self.upper[-1]))

    @property
    def support(self) -> tuple[float, float]:
        """The α = 0 interval ``(l_0, r_0)``."""
        return float(self.lower[0]), float(self.upper[0])

    def alpha_cut(self, alpha: float) -> tuple[float, float]:
        """The interval ``[l_α, r_α]`` (linear between stored levels)."""
        if not 0.0 <= alpha <= 1.0:
            raise ParameterError(f"alpha must lie in [0, 1]; got {alpha}")
        return (
            float(np.interp(alpha, self.alphas, self.lower)),
            float(np.interp(alpha, self.alphas, self.upper)),
        )

    def membership(self, x: np.ndarray | float) -> np.ndarray:
        """Membership μ(x) in [0, 1], piecewise linear between the α-cut ends; NaN where
        ``x`` is NaN."""
        x = np.asarray(x, dtype=float)
        left = _branch(x, self.lower, self.alphas)
        right = _branch(x, self.upper[::-1], self.alphas[::-1])
        mu = np.where(x < self.lower[-1], left, np.where(x > self.upper[-1], right, 1.0))
        return np.where(np.isnan(x), np.nan, np.where((x < self.lower[0]) | (x > self.upper[0]), 0.0, mu))

    def increments(self) -> tuple[np.ndarray, np.ndarray]:
        """The l_α r_α-increments (Eq. 2.20), from the lowest level up.

        Returns:
            ``(dl, dr)``: ``dl[i] = l_{α_{i+1}} − l_{α_i}`` for ``i < N−1``, and
            ``dr[i] = r_{α_i} − r_{α_{i+1}}`` for ``i < N−1`` plus ``dr[N−1]`` the
            width of the α = 1 cut (0 for a fuzzy number with a single peak).
        """
        dl = np.diff(self.lower)
        dr = np.append(-np.diff(self.upper), self.upper[-1] - self.lower[-1])
        return dl, dr

    def rescaled(self, alphas: Sequence[float]) -> FuzzyNumber:
        """The same number described on other α-levels (0 and 1 must be included)."""
        levels = _as_levels(alphas)
        return FuzzyNumber(
            levels,
            np.interp(levels, self.alphas, self.lower),
            np.interp(levels, self.alphas, self.upper),
            self.name,
        )


def _branch(x: np.ndarray, xs: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Linear interpolation of α over one flank given by increasing ``xs``; where several
    levels share one abscissa (a vertical edge) the highest α counts."""
    order = np.argsort(xs, kind="stable")
    xs, levels = xs[order], levels[order]
    unique, first = np.unique(xs, return_index=True)
    highest = np.maximum.reduceat(levels, first)
    if unique.size == 1:
        return np.where(x == unique[0], highest[0], 0.0)
    return np.interp(x, unique, highest, left=0.0, right=0.0)


def triangular(left: float, peak: float, right: float, name: str = "") -> FuzzyNumber:
    """Triangular fuzzy number with support ``[left, right]`` and peak ``peak``."""
    if not left <= peak <= right:
        raise ParameterError(
            f"triangular fuzzy number {name!r}: need left <= peak <= right; got {left}, {peak}, {right}"
        )
    return FuzzyNumber(np.array([0.0, 1.0]), np.array([left, peak]), np.array([right, peak]), name)


def triangular_relative(peak: float, spread: float, name: str = "") -> FuzzyNumber:
    """Symmetric triangular number ``peak ± spread·|peak|`` (e.g. spread 0.1 = ±10 %)."""
    if spread < 0:
        raise ParameterError(f"spread of {name or 'fuzzy number'} must be >= 0; got {spread}")
    width = spread * abs(peak)
    return triangular(peak - width, peak, peak + width, name)


def from_increments(
    peak: float,
    left_increments: Sequence[float],
    right_increments: Sequence[float],
    alphas: Sequence[float],
    name: str = "",
) -> FuzzyNumber:
    """Build a fuzzy number from its peak and l_α r_α-increments (Eq. 2.20).

    Args:
        peak: left end of the α = 1 cut.
        left_increments: ``N−1`` values ``Δp_{α_i,l}``, from α_1 = 0 up to α_{N−1}.
        right_increments: ``N`` values ``Δp_{α_i,r}``; the last is the width of the
            α = 1 cut (0 for a single peak).
        alphas: the ``N`` increasing α-levels, 0 first and 1 last.

    Raises:
        ParameterError: when an increment is negative (convexity, Eq. 2.21), naming it.
    """
    levels = _as_levels(alphas)
    dl = np.asarray(left_increments, dtype=float)
    dr = np.asarray(right_increments, dtype=float)
    n = levels.size
    if dl.shape != (n - 1,) or dr.shape != (n,):
        raise ParameterError(
            f"need {n - 1} left and {n} right increments for {n} α-levels; got {dl.size} and {dr.size}"
        )
    bad = [f"left increment at α={levels[i]:g} is {v:g}" for i, v in enumerate(dl) if v < 0]
    bad += [f"right increment at α={levels[i]:g} is {v:g}" for i, v in enumerate(dr) if v < 0]
    if bad:
        raise ParameterError(
            f"fuzzy number {name!r} would not be convex (Eq. 2.21): {'; '.join(bad)}; "
            "increments must be >= 0"
        )
    lower = peak - np.concatenate([np.cumsum(dl[::-1])[::-1], [0.0]])
    upper_top = peak + dr[-1]
    upper = upper_top + np.concatenate([np.cumsum(dr[:-1][::-1])[::-1], [0.0]])
    return FuzzyNumber(levels, lower, upper, name)
