"""The FRV-GFA of several independent fuzzy random parameters (thesis §2.7.4, the
multi-parameter case after Eq. 2.33): :class:`SeveralParameters`, the
:class:`~fuzzygait.uncertainty.frv.method.Method` of an
:class:`~fuzzygait.uncertainty.frv.FRVStudy` whose record holds a list of ``spec``.

Each parameter has its own :class:`~fuzzygait.uncertainty.frv.FRVSpec` (one set of
α-levels for all), its own sample stream (:func:`generate_box_samples`: parameter 0 is
the one-parameter stream) and its own :class:`Grid` of ``N_p-disc`` points. A sample's
α-cut is a *box*, one grouped interval per parameter; its key is the tuple of the
per-parameter ``(left bin, right bin)`` pairs (:func:`box_rows`) and only occurring boxes
get an entry, out of the ``∏_d N_d(N_d+1)/2`` possible ones (:func:`possible_boxes`).

The library holds one forward simulation per *grid point* (a tuple of bin centres, one
per parameter) that lies inside at least one occurring box — exactly the points the
hulls read. A box's hull is the extreme library value over its grid points
(:func:`~fuzzygait.uncertainty.frv.hulls.box_extrema`: direct reduction along the
trailing parameters, sparse table along the first), and the hulls are nesting-repaired
as for one parameter.

α = 1 without sensitivities is the library value at the sample's grouped peak point
(with one parameter this is exactly the one-parameter study,
:class:`~fuzzygait.uncertainty.frv.single.OneParameter`, with ``refine=False``). When
the evaluator returns sensitivities (``refine``), α = 1 is the model at the sample's
*own* peak by cubic Hermite interpolation in every parameter
(:func:`~fuzzygait.uncertainty.frv.hulls.hermite_values`, from the values and gradients
at the ``2^D`` lattice points around the peak, which the library then also holds), kept
within those ``2^D`` values (``bounded``). The grouped peak alone misses where the
output changes quickly within a bin (the stance blade's energy changes by up to 50 %
within 4 % of E, its vibration phase turning over), and the α = 1 outputs would then not
follow the peak distribution. Box hulls and α = 1 values stay within the simulations
they are made from and within the model's declared bounds
(:attr:`~fuzzygait.uncertainty.protocol.Output.bounds`); the interpolant's extrema
between grid points are not stored (:mod:`fuzzygait.uncertainty.frv.hulls`).

The α = 1 lattice (:mod:`fuzzygait.uncertainty.frv.peaks`) is the grouping grid, or
finer along a parameter where the grid cannot follow the model: ``peak_refine`` gives
the factors, or (default) they are chosen on the first batch -- per parameter, the
interpolant is checked against simulations at :data:`PEAK_CHECKS` test peaks (each
moved onto its cell's lower corner in the other parameters) and the lattice halved
until the median error is at most ``peak_tolerance`` of the output's spread (the checks are recorded in
``counts["peak_checks"]``, the factors chosen in ``counts["peak_refine"]``). The boxes,
their keys and hulls stay on the grouping grid.

The store is the one-parameter layout of :mod:`fuzzygait.uncertainty.frv.store` (same
commit protocol) with a parameter axis: root ``spec``, ``grid`` and ``n_disc`` are
lists (one entry per parameter); ``library``: ``value (bin, time)`` at ``point (bin,
parameter)`` grid bins plus ``offset (bin, parameter)`` in eighths of a bin (α = 1
lattice points between the grid's; absent in older stores), ``centre (bin,
parameter)``, with ``refine`` also ``slope (bin, time, parameter)`` = ∂value/∂p; root
``peak_refine`` and ``peak_tolerance``; ``intervals`` (the box dictionary):
``left``, ``right (interval, parameter)``, ``lower``, ``upper (interval, time)``;
``samples``: ``hull (sample, alpha, bound, time)`` as for one parameter, ``cut`` and
``bin (sample, parameter, alpha, bound)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.uncertainty.frv.evaluation import _run_evaluator
from fuzzygait.uncertainty.frv.grouping import Grid, box_rows, group
from fuzzygait.uncertainty.frv.hulls import box_extrema
from fuzzygait.uncertainty.frv.method import Method, _blocks
from fuzzygait.uncertainty.frv.options import PEAK_FACTORS, PEAK_TOLERANCE, MultiStudyOptions, StudyOptions
from fuzzygait.uncertainty.frv.peaks import PEAK_CHECKS, RESOLUTION, PeakLattice, _peak_factors, key_centres
from fuzzygait.uncertainty.frv.samples import generate_box_samples
from fuzzygait.uncertainty.frv.store import append as _append
from fuzzygait.uncertainty.frv.store import open_group
from fuzzygait.uncertainty.postprocess import repair_nesting

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv.study import FRVStudy

__all__ = ["PEAK_CHECKS", "PEAK_FACTORS", "PEAK_TOLERANCE", "SeveralParameters"]


def _group_boxes(cuts: np.ndarray, grids: Sequence[Grid]) -> np.ndarray:
    """Bins ``(n, n_params, n_alpha, 2)`` of box samples, parameter ``d`` on ``grids[d]``."""
    return np.stack([group(cuts[:, d], g) for d, g in enumerate(grids)], axis=1)


class SeveralParameters(PeakLattice, Method):
    """Boxes of several independent FRV parameters over a library of grid points, α = 1
    on the peak lattice (module docstring). The study's counts are the one-parameter ones
    with boxes for intervals (``occurring_intervals`` = occurring boxes,
    ``possible_intervals`` = possible boxes, ``interval_optimisations`` = 2 × time nodes ×
    occurring boxes wider than one point) plus ``possible_intervals_per_parameter``."""

    axes = ("parameter",)
    default_disc = 30

    def __init__(self, study: FRVStudy, meta: dict[str, Any]) -> None:
        super().__init__(study, meta)
        n_params, nodes = len(study.specs), study.nodes.size
        # α = 1 lattice factors: None until chosen; older stores have the grid's
        factors = meta.get("peak_refine", [1] * n_params)
        self.peak_refine = None if factors is None else [int(f) for f in factors]
        self.peak_tolerance = float(meta.get("peak_tolerance", PEAK_TOLERANCE))
        self._offsets = "peak_refine" in meta  # the library stores lattice offsets
        # library rows in order of computation, the row of each grid point and of each
        # lattice key (grid points included, key = RESOLUTION · bin)
        self._points: dict[tuple[int, ...], int] = {}
        self._keys: dict[tuple[int, ...], int] = {}
        self._lib_values = np.empty((0, nodes))
        self._lib_slopes = np.empty((0, nodes, n_params))
        # box dictionary: key (l_1, r_1, …, l_D, r_D) -> row
        self._boxes: dict[tuple[int, ...], int] = {}
        self._box_lower = np.empty((0, nodes))
        self._box_upper = np.empty((0, nodes))
        self._n_params = n_params

    # ------------------------------------------------------------------ the record
    @staticmethod
    def listed(value: Any) -> list[Any]:
        return list(value)

    @staticmethod
    def recorded(values: Sequence[Any]) -> Any:
        return list(values)

    @classmethod
    def settings(cls, options: StudyOptions, n_params: int) -> tuple[dict[str, Any], Sequence[Grid] | None]:
        """``peak_refine`` (one factor per parameter, or None: chosen on the first batch)
        and ``peak_tolerance`` of :class:`MultiStudyOptions` (a
        :class:`~fuzzygait.uncertainty.frv.StudyOptions` takes their defaults), and their
        ``grids`` (one per parameter)."""
        several = MultiStudyOptions.of(options)
        factors = None if several.peak_refine is None else _peak_factors(several.peak_refine, n_params)
        grids = several.grids
        if grids is not None and (len(grids) != n_params or not all(isinstance(g, Grid) for g in grids)):
            raise ParameterError(f"grids: give one Grid per parameter ({n_params})")
        return {"peak_refine": factors, "peak_tolerance": float(several.peak_tolerance)}, grids

    def commit_entries(self) -> dict[str, Any]:
        self.study.counts["possible_intervals_per_parameter"] = [g.possible_intervals for g in self.study.grids]
        return {"peak_refine": self.peak_refine} if self._offsets else {}

    # ------------------------------------------------------------------ samples
    def draw(self, start: int, n: int) -> np.ndarray:
        return generate_box_samples(self.study.specs, n, self.study.seed, start)

    def group(self, cuts: np.ndarray) -> np.ndarray:
        return _group_boxes(cuts, self.study.grids)

    def parameter_coords(self) -> dict[str, Any]:
        return {"parameter": [s.name for s in self.study.specs]}

    # ------------------------------------------------------------------ library and dictionary
    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` at grid ``point`` / ``centre (bin, parameter)``,
        rows in order of computation."""
        return open_group(self.study.path, "library", self.study.library_rows)

    def load(self) -> None:
        study = self.study
        if study.library_rows:
            lib = self.library()
            self._lib_values = lib["value"].to_numpy()
            if "slope" in lib:
                self._lib_slopes = lib["slope"].to_numpy()
            points = lib["point"].to_numpy()
            offsets = lib["offset"].to_numpy() if "offset" in lib else np.zeros_like(points)
            keys = points * RESOLUTION + offsets
            self._keys = {tuple(k): i for i, k in enumerate(keys.tolist())}
            self._points = {tuple(p): i for i, (p, o) in enumerate(zip(points.tolist(), offsets.tolist()))
                            if not any(o)}  # fmt: skip
        if study.interval_rows:
            table = study.intervals()
            pairs = np.stack([table["left"].to_numpy(), table["right"].to_numpy()], axis=2)
            keys = pairs.reshape(study.interval_rows, -1)
            self._boxes = {tuple(k): i for i, k in enumerate(keys.tolist())}
            if study.stored_hulls:
                self._box_lower, self._box_upper = table["lower"].to_numpy(), table["upper"].to_numpy()
            else:  # an older store: its hulls held the Hermite extrema; new samples use the library's
                self._box_lower, self._box_upper = self._box_hulls(keys[:, 0::2], keys[:, 1::2])

    def complete(self, start: int, stop: int) -> tuple[int, int]:
        """Pass 2: the samples' occurring boxes (and, refining, their peaks' Hermite
        cells); the library (grid points inside new boxes, cell corners, the α = 1
        lattice when it is chosen now) and the box dictionary are completed."""
        study, width = self.study, 2 * self._n_params
        found = np.empty((0, width), dtype=np.int64)
        for a, b in _blocks(start, stop, study.chunk):
            rows = box_rows(self.group(self.draw(a, b - a)))
            found = np.unique(np.concatenate([found, rows.reshape(-1, width)]), axis=0)
        corners = self._peak_corners(start, stop) if study.refine is not False else None
        new = np.array([k for k in found.tolist() if tuple(k) not in self._boxes], dtype=np.int64).reshape(-1, width)
        keys = _box_points(new) * RESOLUTION
        if study.refine and corners is not None:
            keys = np.unique(np.concatenate([keys, corners]), axis=0)
        simulations = self._extend_library(keys)
        if study.refine and corners is not None:  # decided by the first evaluator call when not given
            simulations += self._extend_library(corners)
        if study.refine and self.peak_refine is None:  # choose the α = 1 lattice, then fill it
            simulations += self._choose_peak_refine(start, stop)
            if any(f > 1 for f in self._factors()):
                simulations += self._extend_library(self._peak_corners(start, stop))
        self._add_boxes(new)
        return simulations, int(new.shape[0])

    def _extend_library(self, keys: np.ndarray) -> int:
        """Simulate the lattice ``keys (k, n_params)`` (units of a bin / RESOLUTION) not
        yet in the library, in the given order (one evaluator call); returns their number."""
        study = self.study
        missing = np.array([p for p in keys.tolist() if tuple(p) not in self._keys], dtype=np.int64)
        missing = missing.reshape(-1, self._n_params)
        if not missing.shape[0]:
            return 0
        centres = key_centres(study.grids, missing)
        points, offsets = missing // RESOLUTION, missing % RESOLUTION
        F, J = _run_evaluator(study.evaluator, centres, study.n_time)
        if study.refine is None:
            study.refine = J is not None
        if study.refine and J is None:
            raise ParameterError("this study refines hulls with sensitivities; the evaluator returned none")
        values = F[:, study.nodes]
        names = [s.name for s in study.specs]
        ds = xr.Dataset({"value": (("bin", "time"), values)},
                        coords={"point": (("bin", "parameter"), points), "centre": (("bin", "parameter"), centres),
                                "time": study.times, "parameter": names})  # fmt: skip
        if self._offsets:
            ds = ds.assign_coords(offset=(("bin", "parameter"), offsets))
        elif np.any(offsets):
            raise FuzzyGaitError("internal: a store without lattice offsets cannot hold α = 1 lattice points")
        if study.refine and J is not None:
            slopes = J[:, study.nodes]
            ds["slope"] = (("bin", "time", "parameter"), slopes)
            self._lib_slopes = np.concatenate([self._lib_slopes, slopes])
        _append(study.path, "library", ds, "bin")
        first = self._lib_values.shape[0]
        self._keys.update({tuple(k): first + i for i, k in enumerate(missing.tolist())})
        on_grid = ~np.any(offsets, axis=1)
        self._points.update({tuple(p): first + i for i, p in enumerate(points.tolist()) if on_grid[i]})
        self._lib_values = np.concatenate([self._lib_values, values])
        study.library_rows += int(missing.shape[0])
        study.counts["forward_simulations"] += int(missing.shape[0])
        study._write_meta()
        return int(missing.shape[0])

    def _add_boxes(self, boxes: np.ndarray) -> None:
        """Hulls of new ``boxes`` (keys ``(k, 2·n_params)``) from the library; store them."""
        if not boxes.shape[0]:
            return
        study = self.study
        lefts, rights = boxes[:, 0::2], boxes[:, 1::2]
        lower, upper = self._box_hulls(lefts, rights)
        ds = xr.Dataset({"left": (("interval", "parameter"), lefts), "right": (("interval", "parameter"), rights),
                         "lower": (("interval", "time"), lower), "upper": (("interval", "time"), upper)},
                        coords={"time": study.times, "parameter": [s.name for s in study.specs]})  # fmt: skip
        _append(study.path, "intervals", ds, "interval")
        first = self._box_lower.shape[0]
        self._boxes.update({tuple(k): first + i for i, k in enumerate(boxes.tolist())})
        self._box_lower = np.concatenate([self._box_lower, lower])
        self._box_upper = np.concatenate([self._box_upper, upper])
        study.interval_rows += int(boxes.shape[0])
        proper = int(np.count_nonzero(np.any(rights > lefts, axis=1)))
        study.counts["occurring_intervals"] = len(self._boxes)
        study.counts["occurring_proper_intervals"] += proper
        study.counts["interval_optimisations"] += 2 * proper * int(study.nodes.size)
        study._write_meta()

    def _box_hulls(self, lefts: np.ndarray, rights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper hulls of the boxes of grid bins ``lefts … rights`` (``(k,
        n_params)`` each): the extreme library values over their grid points, within the
        model's declared bounds."""
        origin = lefts.min(axis=0)
        shape = tuple(rights.max(axis=0) - origin + 1)
        dense = np.full((*shape, self.study.nodes.size), np.nan)  # the library on the boxes' bounding grid
        points = np.array(list(self._points), dtype=np.int64).reshape(-1, self._n_params) - origin
        rows = np.fromiter(self._points.values(), dtype=np.int64, count=len(self._points))
        inside = np.all((points >= 0) & (points < np.array(shape)), axis=1)
        dense[tuple(points[inside].T)] = self._lib_values[rows[inside]]
        lower, upper = box_extrema(dense, dense, lefts - origin, rights - origin)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise FuzzyGaitError("internal: a box reaches a grid point without a library entry")
        return np.clip(lower, *self.study.bounds), np.clip(upper, *self.study.bounds)

    def assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped box samples ``(nb, n_params,
        n_alpha, 2)`` with raw peaks ``(nb, n_params)``, nesting-repaired; α = 1 is the
        model at the raw peak (refining) or the library value at the grouped peak."""
        rows = box_rows(bins)
        nb, levels, width = rows.shape
        idx = np.array([self._boxes[tuple(k)] for k in rows.reshape(-1, width).tolist()], dtype=np.int64)
        idx = idx.reshape(nb, levels)
        hull = np.empty((nb, levels + 1, 2, self.study.nodes.size))
        hull[:, :-1, 0] = self._box_lower[idx]
        hull[:, :-1, 1] = self._box_upper[idx]
        if self.study.refine:
            hull[:, -1, :] = self._peak_values(peaks)[:, None, :]
        else:
            grouped = np.array([self._points[tuple(p)] for p in bins[:, :, -1, 0].tolist()], dtype=np.int64)
            hull[:, -1, :] = self._lib_values[grouped][:, None, :]
        hull[:, -1] = np.clip(hull[:, -1], *self.study.bounds)
        repaired = np.moveaxis(repair_nesting(np.moveaxis(hull, 0, 2)), 2, 0)
        return repaired, int(np.count_nonzero(repaired != hull))


def _box_points(boxes: np.ndarray) -> np.ndarray:
    """The grid points ``(k, n_params)`` inside any of ``boxes`` (keys ``(m,
    2·n_params)``), in C order of their bins."""
    n_params = boxes.shape[1] // 2
    if not boxes.shape[0]:
        return np.empty((0, n_params), dtype=np.int64)
    lefts, rights = boxes[:, 0::2], boxes[:, 1::2]
    origin = lefts.min(axis=0)
    covered = np.zeros(tuple(rights.max(axis=0) - origin + 1), dtype=bool)
    for lo, hi in zip((lefts - origin).tolist(), (rights - origin + 1).tolist(), strict=True):
        covered[tuple(slice(a, b) for a, b in zip(lo, hi, strict=True))] = True
    return np.argwhere(covered) + origin
