"""The α = 1 lattice of a refined FRV study: the model at each sample's own peak by cubic
Hermite interpolation on a lattice finer than the grouping grid where the grid is too
coarse for it (the thesis' novelty check, §2.7.4 "Interaction between GFA novelty check
and FRV-GFA sample grouping": a new forward simulation is added to the library where the
library cannot answer within a tolerance, independently of the grouping).

The grouping grid of parameter ``d`` (``N_p-disc`` points, bin centres ``origin + (i +
½)·h``) fixes the boxes and their keys. The α = 1 values are interpolated on the lattice
of refinement ``r_d`` (1, 2, 4 or :data:`RESOLUTION`): centres ``origin + (i + ½)·h`` at
spacing ``h / r_d``, so every grid centre is a lattice point and ``r = 1`` is the grid
itself. Library points are keyed in units of ``h / RESOLUTION`` (``key = RESOLUTION·i``
for grid centre ``i``), so the points of every level share one dictionary.

How fine: the interpolant's error against the simulated model at test peaks
(:func:`interpolation_error`) decides whether a parameter's lattice is halved
(:meth:`fuzzygait.uncertainty.frv.FRVStudy.create` of several parameters);
:class:`PeakLattice` is the part of
:class:`~fuzzygait.uncertainty.frv.multi.SeveralParameters` that chooses, fills and
interpolates it.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.frv.evaluation import _run_evaluator
from fuzzygait.uncertainty.frv.grouping import Grid
from fuzzygait.uncertainty.frv.hulls import hermite_cells, hermite_values
from fuzzygait.uncertainty.frv.method import _blocks
from fuzzygait.uncertainty.frv.options import PEAK_FACTORS
from fuzzygait.uncertainty.frv.samples import generate_box_samples

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv.study import FRVStudy

#: Finest lattice: ``h / RESOLUTION`` (a power of two; the refinement factors are its divisors).
RESOLUTION = 8
#: Test peaks per parameter and lattice level when the α = 1 lattice is chosen.
PEAK_CHECKS = 16


def lattice(grids: Sequence[Grid], factors: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(origins, spacings, first, last)`` of the lattice of refinement ``factors`` in the
    form :func:`~fuzzygait.uncertainty.frv.hulls.hermite_cells` takes (lattice point ``j``
    of parameter ``d`` at ``origins[d] + (j + ½)·spacings[d]``)."""
    r = np.asarray(factors, dtype=np.int64)
    h = np.array([g.spacing for g in grids])
    origins = np.array([g.origin for g in grids]) + 0.5 * h - 0.5 * h / r
    first = np.array([g.first_bin for g in grids], dtype=np.int64) * r
    last = np.array([g.last_bin for g in grids], dtype=np.int64) * r
    return origins, h / r, first, last


def cell_keys(grids: Sequence[Grid], factors: Sequence[int], peaks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each peak's lattice cell: its ``2^D`` corner keys ``(n, 2^D, D)`` (in units of
    ``h / RESOLUTION``, the corner order of
    :func:`~fuzzygait.uncertainty.frv.hulls.hermite_values`) and positions ``t (n, D)``."""
    origins, spacings, first, last = lattice(grids, factors)
    k, t = hermite_cells(origins, spacings, first, last, np.asarray(peaks, dtype=float))
    bits = np.array(list(itertools.product((0, 1), repeat=len(grids))), dtype=np.int64)
    step = (last > first).astype(np.int64)  # a single-bin parameter has no upper corner
    scale = RESOLUTION // np.asarray(factors, dtype=np.int64)
    return (k[:, None, :] + bits[None] * step) * scale, t


def key_centres(grids: Sequence[Grid], keys: np.ndarray) -> np.ndarray:
    """Parameter values ``(k, D)`` of lattice ``keys (k, D)``."""
    keys = np.asarray(keys, dtype=np.int64).reshape(-1, len(grids))
    return np.stack([g.centres(keys[:, d] / RESOLUTION) for d, g in enumerate(grids)], axis=1)


def interpolation_error(predicted: np.ndarray, exact: np.ndarray, library: np.ndarray) -> float:
    """The interpolant's error at test points: per time node the median over the points
    of ``|predicted − exact|``, divided by the spread (max − min) of the ``library``
    values at that node, and the largest over the nodes (nodes where the library does
    not vary, e.g. the initial state, are left out).

    Args:
        predicted, exact: ``(n_points, n_time)``.
        library: ``(n_rows, n_time)`` the values that set the output's scale.
    """
    spread = np.ptp(library, axis=0)
    varies = spread > 1e-9 * max(float(spread.max(initial=0.0)), np.finfo(float).tiny)
    if not varies.any():
        return 0.0
    error = np.median(np.abs(np.asarray(predicted) - np.asarray(exact)), axis=0)
    return float(np.max(error[varies] / spread[varies]))


def _peak_factors(peak_refine: int | Sequence[int], n_params: int) -> list[int]:
    """``peak_refine`` as one factor per parameter, each one of :data:`PEAK_FACTORS`."""
    factors = [peak_refine] * n_params if isinstance(peak_refine, (int, np.integer)) else list(peak_refine)
    if len(factors) != n_params or not all(isinstance(f, (int, np.integer)) and f in PEAK_FACTORS for f in factors):
        raise ParameterError(f"peak_refine: give one factor or one per parameter ({n_params}), each of "
                             f"{', '.join(map(str, PEAK_FACTORS))}; got {peak_refine}")  # fmt: skip
    return [int(f) for f in factors]


class PeakLattice:
    """The α = 1 lattice of a study of several FRV parameters (a mixin of
    :class:`~fuzzygait.uncertainty.frv.multi.SeveralParameters`, whose attributes are the
    ones below): which lattice, its cells' corner keys, its choice on the first batch,
    and the bounded Hermite interpolant on it."""

    study: FRVStudy
    peak_refine: list[int] | None
    peak_tolerance: float | None
    _n_params: int
    _points: dict[tuple[int, ...], int]
    _keys: dict[tuple[int, ...], int]
    _lib_values: np.ndarray
    _lib_slopes: np.ndarray

    def _extend_library(self, keys: np.ndarray) -> int:
        raise NotImplementedError

    def _factors(self) -> list[int]:
        """The α = 1 lattice factors in use (the grid's until chosen)."""
        return self.peak_refine if self.peak_refine is not None else [1] * self._n_params

    def _peak_corners(self, start: int, stop: int) -> np.ndarray:
        """Lattice keys ``(k, n_params)`` of the Hermite cell corners of the raw peaks of
        samples ``start … stop−1`` on the α = 1 lattice in use."""
        study = self.study
        corners = np.empty((0, self._n_params), dtype=np.int64)
        for a, b in _blocks(start, stop, study.chunk):
            cuts = generate_box_samples(study.specs, b - a, study.seed, a)
            cells = cell_keys(study.grids, self._factors(), cuts[:, :, -1, 0])[0].reshape(-1, self._n_params)
            corners = np.unique(np.concatenate([corners, cells]), axis=0)
        return corners

    def _choose_peak_refine(self, start: int, stop: int) -> int:
        """Choose the α = 1 lattice on samples ``start … stop−1`` (module docstring).

        Per parameter ``d`` in turn, :data:`PEAK_CHECKS` test peaks are moved onto their
        lattice cell's lower corner in every other parameter (so only ``d`` is
        interpolated) and simulated; ``d``'s spacing is halved while the interpolant at
        those points misses the model by more than ``peak_tolerance`` of the output's
        spread (:func:`~fuzzygait.uncertainty.frv.peaks.interpolation_error`). Returns
        the simulations it ran (the test points' and the new lattice points')."""
        study = self.study
        assert self.peak_tolerance is not None  # a lattice to choose has a tolerance
        pick = np.unique(np.linspace(start, stop - 1, min(PEAK_CHECKS, stop - start)).round().astype(np.int64))
        peaks = np.concatenate([generate_box_samples(study.specs, 1, study.seed, int(i))[:, :, -1, 0] for i in pick])
        grid_rows = np.fromiter(self._points.values(), dtype=np.int64, count=len(self._points))
        factors, checks, simulations, tested = [1] * self._n_params, [], 0, 0
        for d, grid in enumerate(study.grids):
            if grid.n_bins < 2:
                continue
            corners = cell_keys(study.grids, factors, peaks)[0]
            tests = key_centres(study.grids, corners[:, 0])
            tests[:, d] = peaks[:, d]  # the peak along d, the cell's lower corner in the others
            exact, _ = _run_evaluator(study.evaluator, tests, study.n_time)
            tested += len(tests)
            while True:
                corners, t = cell_keys(study.grids, factors, peaks)
                simulations += self._extend_library(corners.reshape(-1, self._n_params))
                t_along = np.zeros_like(t)
                t_along[:, d] = t[:, d]
                predicted = self._hermite(corners, t_along, factors)
                error = interpolation_error(predicted, exact[:, study.nodes], self._lib_values[grid_rows])
                checks.append({"parameter": study.specs[d].name, "factor": factors[d], "error": error})
                if error <= self.peak_tolerance or factors[d] == PEAK_FACTORS[-1]:
                    break
                factors[d] *= 2
        self.peak_refine = factors
        study.counts["peak_checks"] = checks
        study.counts["peak_refine"] = {spec.name: factor for spec, factor in zip(study.specs, factors, strict=True)}
        study.counts["forward_simulations"] += tested  # the library's are counted as they are added
        study._write_meta()
        return simulations + tested

    def _peak_values(self, peaks: np.ndarray) -> np.ndarray:
        """The model at raw peaks ``(n, n_params)`` by Hermite interpolation of the library
        on the study's α = 1 lattice (within each cell's corner values)."""
        corners, t = cell_keys(self.study.grids, self._factors(), peaks)
        return self._hermite(corners, t, self._factors())

    def _hermite(self, corners: np.ndarray, t: np.ndarray, factors: Sequence[int]) -> np.ndarray:
        """The Hermite interpolant on the lattice of ``factors`` in cells of corner keys
        ``(n, 2^D, n_params)`` at positions ``t (n, n_params)``, each value within its
        cell's corner values."""
        rows = np.array([self._keys[tuple(p)] for p in corners.reshape(-1, self._n_params).tolist()],
                        dtype=np.int64).reshape(corners.shape[:2])  # fmt: skip
        spacings = np.array([g.spacing for g in self.study.grids]) / np.asarray(factors)
        return hermite_values(self._lib_values[rows], self._lib_slopes[rows], spacings, t, bounded=True)
