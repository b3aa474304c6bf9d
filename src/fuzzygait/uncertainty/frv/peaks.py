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
(:meth:`fuzzygait.uncertainty.frv.FRVMultiStudy.create`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from fuzzygait.uncertainty.frv.grouping import Grid
from fuzzygait.uncertainty.frv.hulls import hermite_cells

#: Finest lattice: ``h / RESOLUTION`` (a power of two; the refinement factors are its divisors).
RESOLUTION = 8


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
