"""Fuzzy parameter sets the engine propagates: vectors of independent fuzzy numbers
(α-cut boxes) and fuzzy balls (spatial deviations whose norm is a triangular fuzzy
number, thesis §3.7)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.fuzzy import FuzzyNumber


@dataclass(frozen=True)
class FuzzyVector:
    """Independent fuzzy parameters; the α-level set is the box of their α-cuts."""

    numbers: tuple[FuzzyNumber, ...]

    def __init__(self, numbers: Sequence[FuzzyNumber]) -> None:
        if isinstance(numbers, FuzzyNumber):
            raise ParameterError(f"give the fuzzy parameters as a list, e.g. [{numbers.name or 'p'}]; got one "
                                 "fuzzy number")  # fmt: skip
        if not numbers:
            raise ParameterError("at least one fuzzy parameter is needed")
        wrong = [f"{i}: {n!r}" for i, n in enumerate(numbers) if not isinstance(n, FuzzyNumber)]
        if wrong:
            raise ParameterError(f"fuzzy parameters must be FuzzyNumber (e.g. triangular(0.9, 1.0, 1.1, 'k')); got "
                                 f"{', '.join(wrong)} (position: value)")  # fmt: skip
        object.__setattr__(self, "numbers", tuple(numbers))
        names = self.names
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise ParameterError(f"fuzzy parameter names must differ; {', '.join(repeated)} given more than once")

    @property
    def names(self) -> list[str]:
        return [n.name or f"p{i}" for i, n in enumerate(self.numbers)]

    @property
    def named(self) -> list[bool]:
        """Whether each parameter was given a name (the others are called ``p<i>``)."""
        return [bool(n.name) for n in self.numbers]

    @property
    def dim(self) -> int:
        return len(self.numbers)

    @property
    def deterministic(self) -> np.ndarray:
        """The peak values (α = 1)."""
        return np.array([n.peak for n in self.numbers])

    @property
    def scale(self) -> np.ndarray:
        """Per-parameter scale for relative tolerances: |peak|, or the support width
        where the peak is 0."""
        peak = np.abs(self.deterministic)
        width = np.array([n.support[1] - n.support[0] for n in self.numbers])
        return np.where(peak > 0, peak, np.where(width > 0, width, 1.0))

    def domain(self, alpha: float) -> BoxDomain:
        cuts = np.array([n.alpha_cut(alpha) for n in self.numbers])
        return BoxDomain(cuts[:, 0], cuts[:, 1])


@dataclass(frozen=True)
class FuzzyBalls:
    """Fuzzy spatial deviations: block ``k`` of the parameter vector lies within a ball
    around ``centres[k]`` whose radius is the triangular fuzzy number
    ``(0, 0, support_radii[k])`` — at level α the radius is ``(1 − α)·support_radii[k]``.

    Attributes:
        centres: ``(n_balls, block)`` deterministic positions (e.g. zero deviation).
        support_radii: ``(n_balls,)`` radius at α = 0 (same unit as the centres).
        names: one name per ball (e.g. marker labels).
    """

    centres: np.ndarray
    support_radii: np.ndarray
    names_: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        centres = np.asarray(self.centres, dtype=float)
        radii = np.asarray(self.support_radii, dtype=float)
        if centres.ndim != 2 or centres.shape[0] < 1 or centres.shape[1] < 1:
            raise ParameterError(f"centres must be an (n_balls, block) array with at least one ball, e.g. "
                                 f"np.zeros((2, 3)); got shape {centres.shape}")  # fmt: skip
        names = tuple(self.names_)
        if names and len(names) != centres.shape[0]:
            raise ParameterError(f"one name per ball needed (or none): {centres.shape[0]} balls, {len(names)} names "
                                 f"{list(names)}")  # fmt: skip
        unfinite = [names[k] if names else f"ball{k}" for k in np.flatnonzero(~np.all(np.isfinite(centres), axis=1))]
        if unfinite:
            raise ParameterError(f"ball centres must be finite; {', '.join(unfinite)} not")
        if radii.shape != (centres.shape[0],):
            raise ParameterError(f"one radius per ball needed (shape ({centres.shape[0]},)): {centres.shape[0]} "
                                 f"balls, radii of shape {radii.shape}")  # fmt: skip
        if np.any(radii < 0) or not np.all(np.isfinite(radii)):
            raise ParameterError(f"ball radii must be finite and >= 0; got {radii.tolist()}")
        object.__setattr__(self, "centres", centres)
        object.__setattr__(self, "support_radii", radii)
        object.__setattr__(self, "names_", names)

    @property
    def names(self) -> list[str]:
        base = list(self.names_) or [f"ball{k}" for k in range(self.centres.shape[0])]
        axes = "xyz" if self.centres.shape[1] <= 3 else [str(i) for i in range(self.centres.shape[1])]
        return [f"{b}_{axes[i]}" for b in base for i in range(self.centres.shape[1])]

    @property
    def named(self) -> list[bool]:
        """Whether each coordinate's ball was given a name."""
        return [bool(self.names_)] * (self.centres.shape[0] * self.centres.shape[1])

    @property
    def dim(self) -> int:
        return int(self.centres.size)

    @property
    def deterministic(self) -> np.ndarray:
        return self.centres.ravel().copy()

    @property
    def scale(self) -> np.ndarray:
        """Support radius of each coordinate's ball (the deterministic deviation is 0)."""
        return np.repeat(np.where(self.support_radii > 0, self.support_radii, 1.0), self.centres.shape[1])

    def domain(self, alpha: float) -> BallsDomain:
        if not 0.0 <= alpha <= 1.0:
            raise ParameterError(f"alpha must lie in [0, 1]; got {alpha}")
        return BallsDomain(self.centres, (1.0 - alpha) * self.support_radii)


FuzzyParameters = FuzzyVector | FuzzyBalls
