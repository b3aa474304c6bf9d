"""The FRV-GFA of several independent fuzzy random parameters (thesis §2.7.4, the
multi-parameter case after Eq. 2.33): :class:`FRVMultiStudy`.

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
(with one parameter this is exactly :class:`~fuzzygait.uncertainty.frv.FRVStudy` with
``refine=False``). When the evaluator returns sensitivities (``refine``), α = 1 is the
model at the sample's *own* peak by cubic Hermite interpolation in every parameter
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

import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.schema import BOUNDS
from fuzzygait.io.atomic import tidy_beside
from fuzzygait.uncertainty.frv.evaluation import BatchFunction, _run_evaluator
from fuzzygait.uncertainty.frv.grouping import Grid, box_rows, group, possible_boxes
from fuzzygait.uncertainty.frv.hulls import HULLS, box_extrema
from fuzzygait.uncertainty.frv.options import PEAK_FACTORS, PEAK_TOLERANCE, MultiStudyOptions, StudyOptions
from fuzzygait.uncertainty.frv.peaks import (
    PEAK_CHECKS,
    RESOLUTION,
    PeakLattice,
    _peak_factors,
    key_centres,
)
from fuzzygait.uncertainty.frv.samples import BLOCK, FRVSpec, _whole, check_specs, generate_box_samples
from fuzzygait.uncertainty.frv.store import append as _append
from fuzzygait.uncertainty.frv.store import check, commit, open_group, read_meta
from fuzzygait.uncertainty.frv.study import FRVStudy, StudyState, _blocks, _new_counts
from fuzzygait.uncertainty.postprocess import repair_nesting
from fuzzygait.uncertainty.protocol import FuzzyModel

__all__ = ["PEAK_CHECKS", "PEAK_FACTORS", "PEAK_TOLERANCE", "FRVMultiStudy", "is_multi_store", "open_study"]


def is_multi_store(meta: Mapping[str, Any]) -> bool:
    """Whether a commit record (:func:`~fuzzygait.uncertainty.frv.store.read_meta`) is an
    :class:`FRVMultiStudy`'s (its ``spec`` is a list, one entry per parameter)."""
    return isinstance(meta.get("spec"), list)


def _group_boxes(cuts: np.ndarray, grids: Sequence[Grid]) -> np.ndarray:
    """Bins ``(n, n_params, n_alpha, 2)`` of box samples, parameter ``d`` on ``grids[d]``."""
    return np.stack([group(cuts[:, d], g) for d, g in enumerate(grids)], axis=1)


def _sample_ranges(specs: Sequence[FRVSpec], seed: int, start: int, n: int) -> np.ndarray:
    """``(n_params, 2)``: per parameter the smallest and largest α-cut end of samples
    ``start … start+n−1`` (pass 1)."""
    out = np.array([[np.inf, -np.inf]] * len(specs))
    for a, b in _blocks(start, start + n, BLOCK):
        cuts = generate_box_samples(specs, b - a, seed, a)
        out[:, 0] = np.minimum(out[:, 0], cuts[:, :, 0, 0].min(axis=0))
        out[:, 1] = np.maximum(out[:, 1], cuts[:, :, 0, 1].max(axis=0))
    return out


class FRVMultiStudy(PeakLattice, StudyState):
    """An FRV-GFA study of several independent FRV parameters in a zarr store,
    extendable by samples (see the module docstring for the method and the layout).

    Use :meth:`create`, :meth:`open`, :meth:`add_samples`; read with :meth:`hulls`,
    :meth:`samples`, :meth:`library`, :meth:`boxes`, :attr:`counts`. The counts are the
    one-parameter ones with boxes for intervals (``occurring_intervals`` = occurring
    boxes, ``possible_intervals`` = possible boxes, ``interval_optimisations`` = 2 × time
    nodes × occurring boxes wider than one point) plus ``possible_intervals_per_parameter``.
    """

    def __init__(self, path: Path, model: FuzzyModel, specs: tuple[FRVSpec, ...], meta: dict[str, Any],
                 evaluator: BatchFunction | None) -> None:  # fmt: skip
        self.path, self.model, self.specs = path, model, specs
        self.grids: tuple[Grid, ...] = tuple(Grid(**g) for g in meta["grid"])
        self.n_disc: list[int] = [int(n) for n in meta["n_disc"]]
        self.refine: bool | None = meta["refine"]
        self._read_common_meta(path, model, meta, evaluator)
        n_params = len(specs)
        # α = 1 lattice factors: None until chosen; older stores have the grid's
        factors = meta.get("peak_refine", [1] * n_params)
        self.peak_refine: list[int] | None = None if factors is None else [int(f) for f in factors]
        self.peak_tolerance = float(meta.get("peak_tolerance", PEAK_TOLERANCE))
        self._offsets = "peak_refine" in meta  # the library stores lattice offsets
        # library rows in order of computation, the row of each grid point and of each
        # lattice key (grid points included, key = RESOLUTION · bin)
        self._points: dict[tuple[int, ...], int] = {}
        self._keys: dict[tuple[int, ...], int] = {}
        self._lib_values = np.empty((0, self.nodes.size))
        self._lib_slopes = np.empty((0, self.nodes.size, n_params))
        # box dictionary: key (l_1, r_1, …, l_D, r_D) -> row
        self._boxes: dict[tuple[int, ...], int] = {}
        self._box_lower = np.empty((0, self.nodes.size))
        self._box_upper = np.empty((0, self.nodes.size))
        self._n_params = n_params

    @property
    def spec(self) -> tuple[FRVSpec, ...]:
        """The FRV parameters (as :attr:`specs`)."""
        return self.specs

    @property
    def alphas(self) -> tuple[float, ...]:
        return self.specs[0].alphas

    # ------------------------------------------------------------------ create / open
    @classmethod
    def create(cls, model: FuzzyModel, specs: Sequence[FRVSpec], n_samples: int,
               options: StudyOptions | None = None, *, store: str | os.PathLike[str] | None = None,
               evaluator: BatchFunction | None = None) -> FRVMultiStudy:  # fmt: skip
        """Run the FRV-GFA of several FRV parameters for ``n_samples`` samples into a new
        store (built beside it and moved into place when complete, as for one parameter).

        Args:
            model: a model of ``len(specs)`` parameters (``p`` in ``specs`` order, SI).
            specs: one :class:`FRVSpec` per parameter, all with the same α-levels.
            n_samples: ``N_s``.
            options: the study's :class:`~fuzzygait.uncertainty.frv.MultiStudyOptions`
                (a :class:`~fuzzygait.uncertainty.frv.StudyOptions` takes their defaults):
                ``n_disc`` grid points per parameter over the first batch's range (one
                number for all or one per parameter, default 30), seed (parameter ``k``
                is stream ``k``), time stride, refinement, chunk, overwrite, ``record``,
                and the ``grids`` to group on, the α = 1 lattice ``peak_refine`` (None:
                chosen on the first batch, module docstring) and ``peak_tolerance``.
            store: the zarr directory to create.
            evaluator: batch evaluator ``P (k, n_params) -> (k, n_time)`` or ``(F, J (k,
                n_time, n_params))``; default :func:`serial_evaluator`.
        """
        t0 = time.perf_counter()
        spec_tuple = check_specs(specs)
        n_params = len(spec_tuple)
        n_samples = _whole(n_samples, "n_samples", 1)
        if options is not None and not isinstance(options, StudyOptions):
            raise ParameterError(f"options: give a MultiStudyOptions; got {type(options).__name__}")
        options = MultiStudyOptions.of(options)
        seed, chunk, time_stride, grids = options.seed, options.chunk, options.time_stride, options.grids
        discs = options.discs(n_params, 30)
        peak_refine, peak_tolerance = options.peak_refine, options.peak_tolerance
        factors = None if peak_refine is None else _peak_factors(peak_refine, n_params)
        if store is None:
            raise ParameterError("store: give the path of the zarr directory to create")
        path = Path(store)
        if path.exists() and not options.overwrite:
            raise FuzzyGaitError(f"{path}: already exists; open it with FRVMultiStudy.open or pass overwrite=True")
        if not path.parent.exists():
            raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
        n_time = int(np.asarray(model.times).size)
        if grids is None:
            ranges = _sample_ranges(spec_tuple, seed, 0, n_samples)
            grid_list = [Grid.from_range(lo, hi, n) for (lo, hi), n in zip(ranges, discs, strict=True)]
        else:
            grid_list = list(grids)
            if len(grid_list) != n_params or not all(isinstance(g, Grid) for g in grid_list):
                raise ParameterError(f"grids: give one Grid per parameter ({n_params})")
            discs = [g.n_points for g in grid_list]
        meta: dict[str, Any] = {"seed": seed, "grid": [g.to_dict() for g in grid_list], "n_disc": discs,
                "time_stride": time_stride, "refine": options.refine, "hulls": HULLS, "peak_refine": factors,
                "peak_tolerance": float(peak_tolerance), "chunk": chunk, "n_time": n_time,
                "n_samples": 0, "library_rows": 0, "interval_rows": 0, "counts": _new_counts(),
                "options": dict(options.record or {})}  # fmt: skip
        record = {"spec": [s.to_dict() for s in spec_tuple], **meta}
        return cls._build(path, record, lambda folder: cls(folder, model, spec_tuple, meta, evaluator), n_samples,
                          t0)  # fmt: skip

    @classmethod
    def open(cls, path: str | os.PathLike[str], model: FuzzyModel,
             evaluator: BatchFunction | None = None) -> FRVMultiStudy:  # fmt: skip
        """Open a study written by :meth:`create` (the model must be the same one)."""
        path = Path(path)
        meta = read_meta(path)
        if not is_multi_store(meta):
            raise FuzzyGaitError(f"{path}: a one-parameter FRV study; open it with FRVStudy.open")
        specs = tuple(FRVSpec.from_dict(s) for s in meta["spec"])
        study = cls(path, model, specs, meta, evaluator)
        tidy_beside(path)
        check(path, meta, repair=True)
        if study.library_rows:
            lib = open_group(path, "library", study.library_rows)
            study._lib_values = lib["value"].to_numpy()
            if "slope" in lib:
                study._lib_slopes = lib["slope"].to_numpy()
            points = lib["point"].to_numpy()
            offsets = lib["offset"].to_numpy() if "offset" in lib else np.zeros_like(points)
            keys = points * RESOLUTION + offsets
            study._keys = {tuple(k): i for i, k in enumerate(keys.tolist())}
            study._points = {tuple(p): i for i, (p, o) in enumerate(zip(points.tolist(), offsets.tolist()))
                             if not any(o)}  # fmt: skip
        if study.interval_rows:
            table = study.boxes()
            pairs = np.stack([table["left"].to_numpy(), table["right"].to_numpy()], axis=2)
            keys = pairs.reshape(study.interval_rows, -1)
            study._boxes = {tuple(k): i for i, k in enumerate(keys.tolist())}
            if study.stored_hulls:
                study._box_lower, study._box_upper = table["lower"].to_numpy(), table["upper"].to_numpy()
            else:  # an older store: its hulls held the Hermite extrema; new samples use the library's
                study._box_lower, study._box_upper = study._box_hulls(keys[:, 0::2], keys[:, 1::2])
        return study

    # ------------------------------------------------------------------ public
    def add_samples(self, n: int) -> FRVMultiStudy:
        """Add samples ``n_samples … n_samples + n − 1``: group them on the stored grids
        (each extended by whole bins if they leave it), simulate only grid points not yet
        in the library, compute only boxes not yet in the dictionary, append the new
        samples' hulls. Earlier samples' hulls are not touched."""
        t0 = time.perf_counter()
        n = _whole(n, "n")
        if n:
            check(self.path, read_meta(self.path), repair=True)
            ranges = _sample_ranges(self.specs, self.seed, self.n_samples, n)
            self.grids = tuple(g.extended(r) for g, r in zip(self.grids, ranges, strict=True))
            self._write_meta()
            self._ingest(self.n_samples, n, t0)
        return self

    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` at grid ``point`` / ``centre (bin, parameter)``,
        rows in order of computation."""
        return open_group(self.path, "library", self.library_rows)

    def boxes(self) -> xr.Dataset:
        """The box dictionary: ``left``, ``right (interval, parameter)`` bins, ``lower``,
        ``upper (interval, time)`` hulls, rows in order of computation."""
        return open_group(self.path, "intervals", self.interval_rows)

    intervals = boxes

    # ------------------------------------------------------------------ internals
    def _write_meta(self) -> None:
        """Commit: the record of the grids, counts and valid rows, rewritten in one file."""
        possible = possible_boxes(self.grids)
        self.counts["possible_intervals"] = possible
        self.counts["possible_intervals_per_parameter"] = [g.possible_intervals for g in self.grids]
        self.counts["time_nodes"] = int(self.nodes.size)
        self.counts["worst_case_optimisations"] = 2 * int(self.nodes.size) * possible  # Eq. 2.33, product form
        commit(self.path, {"grid": [g.to_dict() for g in self.grids], "refine": self.refine,
                           **({"peak_refine": self.peak_refine} if self._offsets else {}),
                           "n_samples": self.n_samples, "library_rows": self.library_rows,
                           "interval_rows": self.interval_rows, "counts": self.counts})  # fmt: skip

    def _ingest(self, start: int, n: int, t0: float) -> None:
        """Steps 2–7 for samples ``start … start+n−1``: pass 2 collects their occurring
        boxes (and, refining, their peaks' Hermite cells); the library (grid points inside
        new boxes, cell corners) and the box dictionary are completed; pass 3 draws and
        groups the samples again and appends their hulls."""
        stop, width = start + n, 2 * self._n_params
        found = np.empty((0, width), dtype=np.int64)
        for a, b in _blocks(start, stop, self.chunk):  # pass 2
            cuts = generate_box_samples(self.specs, b - a, self.seed, a)
            rows = box_rows(_group_boxes(cuts, self.grids))
            found = np.unique(np.concatenate([found, rows.reshape(-1, width)]), axis=0)
        corners = self._peak_corners(start, stop) if self.refine is not False else None
        new = np.array([k for k in found.tolist() if tuple(k) not in self._boxes], dtype=np.int64).reshape(-1, width)
        keys = _box_points(new) * RESOLUTION
        if self.refine and corners is not None:
            keys = np.unique(np.concatenate([keys, corners]), axis=0)
        simulations = self._extend_library(keys)
        if self.refine and corners is not None:  # decided by the first evaluator call when not given
            simulations += self._extend_library(corners)
        if self.refine and self.peak_refine is None:  # choose the α = 1 lattice, then fill it
            simulations += self._choose_peak_refine(start, stop)
            if any(f > 1 for f in self._factors()):
                simulations += self._extend_library(self._peak_corners(start, stop))
        self._add_boxes(new)
        repaired, n_alpha = 0, len(self.alphas)
        chunks = {"chunks": (self.chunk, self._n_params, n_alpha, 2)}
        encoding = {"hull": {"chunks": (self.chunk, n_alpha, 2, self.nodes.size)}, "cut": chunks, "bin": chunks}
        names = [s.name for s in self.specs]
        for a, b in _blocks(start, stop, self.chunk):  # pass 3
            cuts = generate_box_samples(self.specs, b - a, self.seed, a)
            bins = _group_boxes(cuts, self.grids)
            hull, changed = self._assemble(bins, cuts[:, :, -1, 0])
            repaired += changed
            dims = ("sample", "parameter", "alpha", "bound")
            ds = xr.Dataset({"hull": (("sample", "alpha", "bound", "time"), hull), "cut": (dims, cuts),
                             "bin": (dims, bins)}, coords={"sample": np.arange(a, b)})  # fmt: skip
            if a == 0:  # the creating write carries the other coordinates
                ds = ds.assign_coords(parameter=names, alpha=list(self.alphas), bound=list(BOUNDS), time=self.times)
            _append(self.path, "samples", ds, "sample", encoding)
        elapsed = time.perf_counter() - t0
        self.n_samples = stop
        self.counts.update(samples=stop, repaired_values=self.counts["repaired_values"] + repaired,
                           wall_time=self.counts["wall_time"] + elapsed, last_forward_simulations=simulations,
                           last_new_intervals=int(new.shape[0]), last_wall_time=elapsed)  # fmt: skip
        self._write_meta()

    def _extend_library(self, keys: np.ndarray) -> int:
        """Simulate the lattice ``keys (k, n_params)`` (units of a bin / RESOLUTION) not
        yet in the library, in the given order (one evaluator call); returns their number."""
        missing = np.array([p for p in keys.tolist() if tuple(p) not in self._keys], dtype=np.int64)
        missing = missing.reshape(-1, self._n_params)
        if not missing.shape[0]:
            return 0
        centres = key_centres(self.grids, missing)
        points, offsets = missing // RESOLUTION, missing % RESOLUTION
        F, J = _run_evaluator(self.evaluator, centres, self.n_time)
        if self.refine is None:
            self.refine = J is not None
        if self.refine and J is None:
            raise ParameterError("this study refines hulls with sensitivities; the evaluator returned none")
        values = F[:, self.nodes]
        names = [s.name for s in self.specs]
        ds = xr.Dataset({"value": (("bin", "time"), values)},
                        coords={"point": (("bin", "parameter"), points), "centre": (("bin", "parameter"), centres),
                                "time": self.times, "parameter": names})  # fmt: skip
        if self._offsets:
            ds = ds.assign_coords(offset=(("bin", "parameter"), offsets))
        elif np.any(offsets):
            raise FuzzyGaitError("internal: a store without lattice offsets cannot hold α = 1 lattice points")
        if self.refine and J is not None:
            slopes = J[:, self.nodes]
            ds["slope"] = (("bin", "time", "parameter"), slopes)
            self._lib_slopes = np.concatenate([self._lib_slopes, slopes])
        _append(self.path, "library", ds, "bin")
        first = self._lib_values.shape[0]
        self._keys.update({tuple(k): first + i for i, k in enumerate(missing.tolist())})
        on_grid = ~np.any(offsets, axis=1)
        self._points.update({tuple(p): first + i for i, p in enumerate(points.tolist()) if on_grid[i]})
        self._lib_values = np.concatenate([self._lib_values, values])
        self.library_rows += int(missing.shape[0])
        self.counts["forward_simulations"] += int(missing.shape[0])
        self._write_meta()
        return int(missing.shape[0])

    def _add_boxes(self, boxes: np.ndarray) -> None:
        """Hulls of new ``boxes`` (keys ``(k, 2·n_params)``) from the library; store them."""
        if not boxes.shape[0]:
            return
        lefts, rights = boxes[:, 0::2], boxes[:, 1::2]
        lower, upper = self._box_hulls(lefts, rights)
        ds = xr.Dataset({"left": (("interval", "parameter"), lefts), "right": (("interval", "parameter"), rights),
                         "lower": (("interval", "time"), lower), "upper": (("interval", "time"), upper)},
                        coords={"time": self.times, "parameter": [s.name for s in self.specs]})  # fmt: skip
        _append(self.path, "intervals", ds, "interval")
        first = self._box_lower.shape[0]
        self._boxes.update({tuple(k): first + i for i, k in enumerate(boxes.tolist())})
        self._box_lower = np.concatenate([self._box_lower, lower])
        self._box_upper = np.concatenate([self._box_upper, upper])
        self.interval_rows += int(boxes.shape[0])
        proper = int(np.count_nonzero(np.any(rights > lefts, axis=1)))
        self.counts["occurring_intervals"] = len(self._boxes)
        self.counts["occurring_proper_intervals"] += proper
        self.counts["interval_optimisations"] += 2 * proper * int(self.nodes.size)
        self._write_meta()

    def _box_hulls(self, lefts: np.ndarray, rights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper hulls of the boxes of grid bins ``lefts … rights`` (``(k,
        n_params)`` each): the extreme library values over their grid points, within the
        model's declared bounds."""
        origin = lefts.min(axis=0)
        shape = tuple(rights.max(axis=0) - origin + 1)
        dense = np.full((*shape, self.nodes.size), np.nan)  # the library on the boxes' bounding grid
        points = np.array(list(self._points), dtype=np.int64).reshape(-1, self._n_params) - origin
        rows = np.fromiter(self._points.values(), dtype=np.int64, count=len(self._points))
        inside = np.all((points >= 0) & (points < np.array(shape)), axis=1)
        dense[tuple(points[inside].T)] = self._lib_values[rows[inside]]
        lower, upper = box_extrema(dense, dense, lefts - origin, rights - origin)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise FuzzyGaitError("internal: a box reaches a grid point without a library entry")
        return np.clip(lower, *self.bounds), np.clip(upper, *self.bounds)

    def _assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped box samples ``(nb, n_params,
        n_alpha, 2)`` with raw peaks ``(nb, n_params)``, nesting-repaired; α = 1 is the
        model at the raw peak (refining) or the library value at the grouped peak."""
        rows = box_rows(bins)
        nb, levels, width = rows.shape
        idx = np.array([self._boxes[tuple(k)] for k in rows.reshape(-1, width).tolist()], dtype=np.int64)
        idx = idx.reshape(nb, levels)
        hull = np.empty((nb, levels + 1, 2, self.nodes.size))
        hull[:, :-1, 0] = self._box_lower[idx]
        hull[:, :-1, 1] = self._box_upper[idx]
        if self.refine:
            hull[:, -1, :] = self._peak_values(peaks)[:, None, :]
        else:
            grouped = np.array([self._points[tuple(p)] for p in bins[:, :, -1, 0].tolist()], dtype=np.int64)
            hull[:, -1, :] = self._lib_values[grouped][:, None, :]
        hull[:, -1] = np.clip(hull[:, -1], *self.bounds)
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


def open_study(path: str | os.PathLike[str], model: FuzzyModel,
               evaluator: BatchFunction | None = None) -> FRVStudy | FRVMultiStudy:  # fmt: skip
    """Open a stored FRV study of one parameter (:class:`FRVStudy`) or of several
    (:class:`FRVMultiStudy`), whichever the store holds."""
    if is_multi_store(read_meta(Path(path))):
        return FRVMultiStudy.open(path, model, evaluator)
    return FRVStudy.open(path, model, evaluator)
