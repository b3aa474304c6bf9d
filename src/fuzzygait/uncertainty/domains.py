"""Feasible parameter sets of one α-level: boxes (independent fuzzy numbers) and
products of balls (fuzzy spatial deviations).

A domain answers what the α-level optimisation needs: membership tests, projection,
the maximiser of a linear function (the linearised model's optimum, in closed form),
random starting points and scipy bounds/constraints.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # scipy.optimize is imported where a constraint is made: 0.25 s a worker process otherwise
    from scipy.optimize import NonlinearConstraint


@dataclass(frozen=True)
class BoxDomain:
    """``lower <= p <= upper`` component-wise (the α-cut box)."""

    lower: np.ndarray
    upper: np.ndarray

    @property
    def dim(self) -> int:
        return int(self.lower.size)

    @property
    def centre(self) -> np.ndarray:
        return 0.5 * (self.lower + self.upper)

    def contains(self, p: np.ndarray, tol: float = 0.0) -> np.ndarray:
        """Whether each row of ``p`` (``(..., dim)``) lies in the box (+ ``tol`` slack)."""
        return np.all((p >= self.lower - tol) & (p <= self.upper + tol), axis=-1)

    def project(self, p: np.ndarray) -> np.ndarray:
        return np.clip(p, self.lower, self.upper)

    def linear_argmax(self, gradient: np.ndarray) -> np.ndarray:
        """Vertex maximising ``gradient · p`` (ties: the centre value)."""
        return np.where(gradient > 0, self.upper, np.where(gradient < 0, self.lower, self.centre))

    def sample(self, rng: np.random.Generator, n: int, surface: bool = False) -> np.ndarray:
        """Uniform points in the box (random vertices with ``surface=True``)."""
        if surface:
            return np.where(rng.random((n, self.dim)) < 0.5, self.lower, self.upper)
        return self.lower + (self.upper - self.lower) * rng.random((n, self.dim))

    def rescale_from(self, other: BoxDomain, p: np.ndarray) -> np.ndarray:
        """Map points of ``other`` to the same relative position in this box."""
        width = other.upper - other.lower
        relative = np.where(width > 0, (p - other.lower) / np.where(width > 0, width, 1.0), 0.5)
        return self.lower + relative * (self.upper - self.lower)

    def scipy_bounds(self) -> list[tuple[float, float]]:
        return list(zip(self.lower.tolist(), self.upper.tolist()))

    def scipy_constraints(self) -> list[NonlinearConstraint]:
        return []


@dataclass(frozen=True)
class BallsDomain:
    """Product of balls: ``|p_k − centre_k| <= radius_k`` for each block ``k`` of
    ``block`` coordinates (e.g. one 3-D ball per marker)."""

    centres: np.ndarray  # (n_balls, block)
    radii: np.ndarray  # (n_balls,)

    @property
    def block(self) -> int:
        return int(self.centres.shape[1])

    @property
    def dim(self) -> int:
        return int(self.centres.size)

    @property
    def centre(self) -> np.ndarray:
        return self.centres.ravel().copy()

    def _blocks(self, p: np.ndarray) -> np.ndarray:
        return np.asarray(p, dtype=float).reshape(*np.shape(p)[:-1], *self.centres.shape)

    @staticmethod
    def _lengths(blocks: np.ndarray) -> np.ndarray:
        """Euclidean length of each block (last axis), keeping it: the same numbers as
        ``np.linalg.norm(blocks, axis=-1, keepdims=True)`` (squares added in order) in
        about a third of the time for 3-vectors (no reduction over a short strided axis)."""
        squares = blocks[..., 0] ** 2
        for i in range(1, blocks.shape[-1]):
            squares = squares + blocks[..., i] ** 2
        return np.sqrt(squares)[..., None]

    def contains(self, p: np.ndarray, tol: float = 0.0) -> np.ndarray:
        d = self._lengths(self._blocks(p) - self.centres)[..., 0]
        return np.all(d <= self.radii + tol, axis=-1)

    def project(self, p: np.ndarray) -> np.ndarray:
        blocks = self._blocks(p) - self.centres
        norm = self._lengths(blocks)
        scale = np.where(norm > self.radii[:, None], self.radii[:, None] / np.maximum(norm, 1e-300), 1.0)
        return (self.centres + blocks * scale).reshape(np.shape(p))

    def linear_argmax(self, gradient: np.ndarray) -> np.ndarray:
        g = self._blocks(gradient)
        norm = self._lengths(g)
        direction = np.where(norm > 0, g / np.maximum(norm, 1e-300), 0.0)
        return (self.centres + self.radii[:, None] * direction).reshape(np.shape(gradient))

    def sample(self, rng: np.random.Generator, n: int, surface: bool = False) -> np.ndarray:
        """Uniform points in each ball (on each sphere with ``surface=True``)."""
        direction = rng.standard_normal((n, *self.centres.shape))
        direction /= self._lengths(direction)
        fraction = 1.0 if surface else rng.random((n, self.radii.size)) ** (1.0 / self.block)
        radius = self.radii * fraction
        return (self.centres + direction * radius[..., None]).reshape(n, self.dim)

    def rescale_from(self, other: BallsDomain, p: np.ndarray) -> np.ndarray:
        """Map points of ``other`` radially to the same relative position in these balls."""
        ratio = np.where(other.radii > 0, self.radii / np.where(other.radii > 0, other.radii, 1.0), 0.0)
        blocks = self._blocks(p) - other.centres
        return (self.centres + blocks * ratio[:, None]).reshape(np.shape(p))

    def scipy_bounds(self) -> list[tuple[float, float]]:
        lo = (self.centres - self.radii[:, None]).ravel()
        hi = (self.centres + self.radii[:, None]).ravel()
        return list(zip(lo.tolist(), hi.tolist()))

    def scipy_constraints(self) -> list[NonlinearConstraint]:
        """``|p_k − c_k|² <= r_k²`` for every ball (smooth form for SLSQP/trust-constr)."""

        def squared(p: np.ndarray) -> np.ndarray:
            return np.sum((self._blocks(p) - self.centres) ** 2, axis=-1)

        def jac(p: np.ndarray) -> np.ndarray:
            blocks = 2.0 * (self._blocks(p) - self.centres)
            out = np.zeros((self.radii.size, self.dim))
            for k in range(self.radii.size):
                out[k, k * self.block : (k + 1) * self.block] = blocks[k]
            return out

        from scipy.optimize import NonlinearConstraint

        return [NonlinearConstraint(squared, -np.inf, self.radii**2, jac=jac)]


Domain = BoxDomain | BallsDomain
