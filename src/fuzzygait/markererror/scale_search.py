"""The bracketing search of the allowable marker error: the largest scale of the error
table whose band stays within a tolerance, for one angle component
(:func:`~fuzzygait.markererror.allowable.allowable_errors` runs it)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class ScaleSearch:
    """Bracketing search of the largest error scale ``s`` (fraction of Σ) whose excursion
    ``E(s)`` (degrees) is at most ``tolerance``, for one component.

    ``points`` maps every evaluated scale to its excursion (``inf``: undetermined); ``s = 0``
    (the measured angle) passes. :meth:`propose` gives the next scale to evaluate (None when
    the bracket is narrower than ``step`` or nothing fails); :meth:`record` adds a result.
    """

    tolerance: float
    step: float
    points: dict[float, float] = field(default_factory=dict)
    history: list[bool] = field(default_factory=list)
    widths: list[float] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.points.setdefault(0.0, 0.0)

    def excursions(self) -> dict[float, float]:
        """The excursions made monotone in the scale (ascending): the band at a scale
        contains the bands of all smaller scales (nested balls), so ``E(s)`` is at least
        every ``E(s')`` with ``s' < s`` — the hulls' nesting repair, in one number."""
        out, running = {}, 0.0
        for scale in sorted(self.points):
            running = max(running, self.points[scale])
            out[scale] = running
        return out

    def bracket(self) -> tuple[float, float | None]:
        """(largest passing scale, smallest failing scale or None)."""
        excursions = self.excursions()
        passing = max(s for s, e in excursions.items() if e <= self.tolerance)
        failing = [s for s, e in excursions.items() if not e <= self.tolerance]
        return passing, (min(failing) if failing else None)

    def done(self) -> bool:
        lo, hi = self.bracket()
        return hi is None or hi - lo <= self.step

    def remaining(self) -> int:
        """Runs still expected (at most): the bisection steps from the bracket's width to
        ``step`` (the interpolation usually needs fewer); 0 when done."""
        lo, hi = self.bracket()
        if hi is None or hi - lo <= self.step:
            return 0
        return max(1, math.ceil(math.log2((hi - lo) / self.step)))

    def record(self, scale: float, excursion: float) -> None:
        self.points[scale] = excursion
        self.history.append(excursion <= self.tolerance)

    def propose(self) -> float | None:
        lo, hi = self.bracket()
        if hi is None or hi - lo <= self.step:
            return None
        self.widths.append(hi - lo)
        if len(self.widths) >= 3 and self.widths[-1] > 0.5 * self.widths[-3]:
            scale = 0.5 * (lo + hi)  # interpolation stalls: bisect
        else:
            estimate = self._interpolate(lo, hi)
            scale = 0.5 * (lo + hi) if estimate is None else estimate
            if estimate is not None and self.history:  # a little past the estimate, towards the side not moved last
                scale += 0.5 * self.step if self.history[-1] else -0.5 * self.step
        half = 0.5 * self.step
        return float(min(max(scale, lo + half), hi - half))

    def _interpolate(self, lo: float, hi: float) -> float | None:
        """Scale where the excursion reaches the tolerance: the quadratic through the
        bracket's ends and the nearest other evaluated scale when it has one root inside
        the bracket, else the chord; None when the failing end is undetermined."""
        excursions = self.excursions()
        e_lo, e_hi = excursions[lo], excursions[hi]
        if not math.isfinite(e_hi) or e_hi <= e_lo:
            return None
        others = [s for s, e in excursions.items() if s not in (lo, hi) and math.isfinite(e)]
        if others:
            third = min(others, key=lambda s: min(abs(s - lo), abs(s - hi)))
            coefficients = np.polyfit([lo, hi, third], [e_lo, e_hi, excursions[third]], 2)
            coefficients[-1] -= self.tolerance
            roots = [r.real for r in np.roots(coefficients) if abs(r.imag) < 1e-12 and lo < r.real < hi]
            if len(roots) == 1:
                return float(roots[0])
        return lo + (self.tolerance - e_lo) / (e_hi - e_lo) * (hi - lo)
