"""The persistent FRV-GFA study (thesis §2.7.4 steps 1–7): :class:`FRVStudy` runs the
steps into a chunked zarr store, block by block, and extends it by samples; every write
commits atomically (:mod:`fuzzygait.uncertainty.frv.store`)."""

from __future__ import annotations

import os
import shutil
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Self

import numpy as np
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.schema import BOUNDS
from fuzzygait.io.atomic import replace_folder, temporary_folder, tidy_beside
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.frv.evaluation import BatchFunction, _run_evaluator, declared_bounds, serial_evaluator
from fuzzygait.uncertainty.frv.grouping import Grid, _decode, _encode, _interval_keys, group
from fuzzygait.uncertainty.frv.hulls import HULLS, _hermite_rows, interval_hulls
from fuzzygait.uncertainty.frv.options import StudyOptions
from fuzzygait.uncertainty.frv.samples import BLOCK, FRVSpec, _whole, generate_samples
from fuzzygait.uncertainty.frv.store import STORE_FORMAT, check, commit, new_store, open_group, read_meta
from fuzzygait.uncertainty.frv.store import append as _append
from fuzzygait.uncertainty.gfa import optimisation_nodes
from fuzzygait.uncertainty.postprocess import repair_nesting
from fuzzygait.uncertainty.protocol import FuzzyModel, Output

__all__ = ["STORE_FORMAT", "FRVStudy"]


def _single_spec(spec: FRVSpec | Sequence[FRVSpec]) -> FRVSpec:
    if isinstance(spec, FRVSpec):
        return spec
    specs = list(spec)
    if len(specs) == 1 and isinstance(specs[0], FRVSpec):
        return specs[0]
    raise ParameterError(
        f"FRVStudy takes one FRV parameter; got {len(specs)}. For several use FRVMultiStudy "
        "(fuzzygait.uncertainty.frv.multi: tensor grids, boxes of per-parameter intervals)"
    )


def _blocks(start: int, stop: int, chunk: int) -> Iterator[tuple[int, int]]:
    """Sample ranges aligned to multiples of ``chunk`` (so appends fill zarr chunks)."""
    a = start
    while a < stop:
        b = min(stop, (a // chunk + 1) * chunk)
        yield a, b
        a = b


def _new_counts() -> dict[str, Any]:
    return {"samples": 0, "forward_simulations": 0, "interval_optimisations": 0, "occurring_intervals": 0,
            "occurring_proper_intervals": 0, "possible_intervals": 0, "worst_case_optimisations": 0,
            "time_nodes": 0, "repaired_values": 0, "wall_time": 0.0, "last_forward_simulations": 0,
            "last_new_intervals": 0, "last_wall_time": 0.0}  # fmt: skip


class StudyState:
    """What every FRV study (one parameter or several) reads from its commit record:
    seed, time stride and optimisation nodes, chunk, sizes, options, counts, evaluator —
    and how a new study is built into place (:meth:`_build`)."""

    path: Path
    seed: int
    time_stride: int
    chunk: int
    n_time: int
    n_samples: int
    library_rows: int
    interval_rows: int
    options: dict[str, Any]
    counts: dict[str, Any]
    evaluator: BatchFunction
    nodes: np.ndarray
    times: np.ndarray
    bounds: tuple[float, float]
    output: Output
    stored_hulls: bool

    def _read_common_meta(self, path: Path, model: FuzzyModel, meta: dict[str, Any],
                          evaluator: BatchFunction | None) -> None:  # fmt: skip
        """Set the attributes above from ``meta``.

        Raises:
            ParameterError: the model's time nodes are not the study's.
        """
        self.seed = int(meta["seed"])
        self.time_stride = int(meta["time_stride"])
        self.chunk = int(meta["chunk"])
        self.n_time = int(meta["n_time"])
        self.n_samples = int(meta["n_samples"])
        self.library_rows = int(meta["library_rows"])
        self.interval_rows = int(meta["interval_rows"])
        self.options = dict(meta.get("options") or {})
        self.counts = dict(meta["counts"])
        self.evaluator = evaluator if evaluator is not None else serial_evaluator(model)
        times = np.asarray(model.times, dtype=float)
        if times.ndim != 1 or times.size != self.n_time:
            raise ParameterError(f"{path}: the study has {self.n_time} time nodes; the model has {times.size}")
        self.nodes = optimisation_nodes(self.n_time, self.time_stride)
        self.times = times[self.nodes]
        self.bounds = declared_bounds(model)
        self.output = model.output  # what the hulls are, and their units
        # the stored interval hulls are the library extremes (older stores: Hermite extrema)
        self.stored_hulls = meta.get("hulls") == HULLS

    def hulls(self) -> xr.Dataset:
        """The output ``hull (sample, alpha, bound, time)``, lazily (nothing loaded),
        in the model output's units, with the counts as attributes (a fuzzy result:
        ``hulls().fuzzy``)."""
        ds = open_group(self.path, "samples", self.n_samples)[["hull"]]
        ds["hull"].attrs["units"] = self.output.units
        ds.attrs.update(self.counts, output=self.output.name, units=self.output.units)
        return ds

    def samples(self) -> xr.Dataset:
        """The raw α-cuts ``cut`` and their ``bin`` (lazily; with several parameters
        ``(sample, parameter, alpha, bound)``)."""
        return open_group(self.path, "samples", self.n_samples)[["cut", "bin"]]

    def _ingest(self, start: int, n: int, t0: float) -> None:
        """Process samples ``start … start+n−1`` (each study kind's own steps)."""
        raise NotImplementedError

    @classmethod
    def _build(cls, path: Path, record: dict[str, Any], make: Callable[[Path], Self], n_samples: int,
               t0: float) -> Self:  # fmt: skip
        """A new study of ``n_samples`` samples: its store (commit record ``record``) built
        in a temporary folder beside ``path`` by the study ``make(folder)`` returns, and
        moved into place only when complete; the temporary folder is removed either way."""
        staging = temporary_folder(path, "creating")
        try:
            new_store(staging, record)
            study = make(staging)
            study._ingest(0, n_samples, t0)
            replace_folder(staging, path)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        study.path = path
        return study


class FRVStudy(StudyState):
    """An FRV-GFA study persisted in a zarr store (directory), extendable by samples.

    Store layout (zarr v2 groups, written through xarray):

    * root attributes, the commit record: ``spec``, ``seed``, ``grid``, ``n_disc``,
      ``time_stride``, ``refine``, ``chunk``, ``n_time`` (the model's), ``n_samples``,
      ``counts``, the valid rows ``library_rows`` and ``interval_rows``, ``hulls``
      (``"simulated"``: the interval hulls are library extremes; absent in stores made
      before, whose stored ones are recomputed on :meth:`open`), and the caller's
      ``options`` (what the study was made with, e.g. the command's options);
    * ``library``: ``value (bin, time)`` the model at each bin centre (``slope`` = df/dp
      when refining), ``centre (bin)``; rows in order of computation;
    * ``intervals``: ``left``, ``right (interval)`` bins and ``lower``, ``upper
      (interval, time)`` hulls — the dictionary of occurring intervals: the extreme
      library values over the interval's bins (thesis §2.7.4, post-processing);
    * ``samples``: ``hull (sample, alpha, bound, time)`` chunked ``(chunk, all, 2, all)``
      with the raw α-cuts ``cut (sample, alpha, bound)`` and their ``bin``, written block
      by block (one append along ``sample`` per block of ``chunk`` samples).

    Only the output time nodes ``optimisation_nodes(n_time, time_stride)`` are kept (the
    library too). Each write phase (library, intervals, all samples of one call) commits
    atomically; rows a killed write left beyond the commit record are discarded on
    :meth:`open`, and a study is created in a folder beside its store and moved into place
    when complete (see :mod:`fuzzygait.uncertainty.frv.store`). Use :meth:`create`,
    :meth:`open`, :meth:`add_samples`; read with :meth:`hulls`, :meth:`samples`,
    :meth:`library`, :meth:`intervals`, :attr:`counts`.
    """

    def __init__(self, path: Path, model: FuzzyModel, spec: FRVSpec, meta: dict[str, Any],
                 evaluator: BatchFunction | None) -> None:  # fmt: skip
        self.path, self.model, self.spec = path, model, spec
        self.grid = Grid(**meta["grid"])
        self.n_disc: int = meta["n_disc"]
        self.refine: bool | None = meta["refine"]
        self._read_common_meta(path, model, meta, evaluator)
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
    def create(cls, model: FuzzyModel, spec: FRVSpec | Sequence[FRVSpec], n_samples: int,
               options: StudyOptions | None = None, *, store: str | os.PathLike[str] | None = None,
               evaluator: BatchFunction | None = None) -> FRVStudy:  # fmt: skip
        """Run the FRV-GFA for ``n_samples`` samples into a new store.

        Args:
            model: a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel` of one
                parameter (``p`` of shape ``(1,)``); sensitivities used when declared.
            spec: the FRV parameter (one; a sequence of several raises ParameterError).
            n_samples: ``N_s``.
            options: the study's :class:`~fuzzygait.uncertainty.frv.StudyOptions`
                (``n_disc`` one number, default 100; seed, time stride, refinement,
                chunk, overwrite and the ``record`` stored as the ``options`` attribute).
            store: the zarr directory to create.
            evaluator: batch evaluator ``P (k, 1) -> (k, n_time)`` or ``((k, n_time),
                (k, n_time, 1))`` with sensitivities; default :func:`serial_evaluator`.

        The study is built in a temporary folder beside ``store`` and moved onto it when
        complete: on any failure (or a kill) nothing is left at ``store``.
        """
        t0 = time.perf_counter()
        spec = _single_spec(spec)
        n_samples = _whole(n_samples, "n_samples", 1)
        options = StudyOptions() if options is None else options
        if not isinstance(options, StudyOptions):
            raise ParameterError(f"options: give a StudyOptions; got {type(options).__name__}")
        (n_disc,) = options.discs(1, 100)
        seed, chunk, time_stride = options.seed, options.chunk, options.time_stride
        if store is None:
            raise ParameterError("store: give the path of the zarr directory to create")
        path = Path(store)
        if path.exists() and not options.overwrite:
            raise FuzzyGaitError(f"{path}: already exists; open it with FRVStudy.open or pass overwrite=True")
        if not path.parent.exists():
            raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
        n_time = CountedModel(model, scale=np.ones(1)).n_time
        low, high = _sample_range(spec, seed, 0, n_samples, chunk)
        meta: dict[str, Any] = {"seed": seed, "grid": Grid.from_range(low, high, n_disc).to_dict(), "n_disc": n_disc,
                "time_stride": time_stride, "refine": options.refine, "hulls": HULLS, "chunk": chunk,
                "n_time": n_time, "n_samples": 0, "library_rows": 0, "interval_rows": 0, "counts": _new_counts(),
                "options": dict(options.record or {})}  # fmt: skip
        record = {"spec": spec.to_dict(), **meta}
        return cls._build(path, record, lambda folder: cls(folder, model, spec, meta, evaluator), n_samples, t0)

    @classmethod
    def open(cls, path: str | os.PathLike[str], model: FuzzyModel, evaluator: BatchFunction | None = None) -> FRVStudy:
        """Open a study written by :meth:`create` (the model must be the same one)."""
        path = Path(path)
        meta = read_meta(path)
        if isinstance(meta["spec"], list):
            raise FuzzyGaitError(f"{path}: an FRV study of several parameters; open it with FRVMultiStudy.open "
                                 "(or fuzzygait.uncertainty.frv.open_study)")  # fmt: skip
        study = cls(path, model, FRVSpec.from_dict(meta["spec"]), meta, evaluator)
        tidy_beside(path)
        check(path, meta, repair=True)
        if study.library_rows:
            lib = study.library()
            study._lib_first = int(lib["bin"][0])
            study._lib_values = lib["value"].to_numpy()
            study._lib_slopes = lib["slope"].to_numpy() if "slope" in lib else None
        if study.interval_rows:
            table = study.intervals()
            left, right = table["left"].to_numpy(), table["right"].to_numpy()
            keys = _encode(left, right)
            order = np.argsort(keys)
            study._keys = keys[order]
            if study.stored_hulls:
                study._int_lower = table["lower"].to_numpy()[order]
                study._int_upper = table["upper"].to_numpy()[order]
            else:  # an older store: its hulls held the Hermite extrema; new samples use the library's
                study._int_lower, study._int_upper = study._interval_hulls(left[order], right[order])
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
            check(self.path, read_meta(self.path), repair=True)
            low, high = _sample_range(self.spec, self.seed, self.n_samples, n, self.chunk)
            self.grid = self.grid.extended(np.array([low, high]))
            self._write_meta()
            self._ingest(self.n_samples, n, t0)
        return self

    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` at bin ``centre`` (and ``slope``), sorted."""
        return open_group(self.path, "library", self.library_rows).sortby("bin")

    def intervals(self) -> xr.Dataset:
        """The interval dictionary: ``left``, ``right`` bins, ``lower``, ``upper`` hulls."""
        return open_group(self.path, "intervals", self.interval_rows)

    # ------------------------------------------------------------------ internals
    def _write_meta(self) -> None:
        """Commit: the record of the grid, counts and valid rows, rewritten in one file."""
        self.counts["possible_intervals"] = self.grid.possible_intervals
        self.counts["time_nodes"] = int(self.nodes.size)
        self.counts["worst_case_optimisations"] = 2 * int(self.nodes.size) * self.grid.possible_intervals  # Eq. 2.33
        commit(self.path, {"grid": self.grid.to_dict(), "refine": self.refine, "n_samples": self.n_samples,
                           "library_rows": self.library_rows, "interval_rows": self.interval_rows,
                           "counts": self.counts})  # fmt: skip

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
        """The model at raw ``peaks``: the Hermite interpolant of the library, each value
        within its cell's two library values."""
        assert self._lib_slopes is not None  # only called when refining with a library of slopes
        slopes = self._lib_slopes[..., 0] if self._lib_slopes.ndim == 3 else self._lib_slopes
        first = float(self.grid.centres(self._lib_first))
        return _hermite_rows(self._lib_values, slopes, first, self.grid.spacing, peaks, bounded=True)

    def _interval_hulls(self, left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper hulls of the intervals of bins ``left … right``: the extreme
        library values over their bins, within the model's declared bounds."""
        lower, upper = interval_hulls(self._lib_values, left - self._lib_first, right - self._lib_first)
        return np.clip(lower, *self.bounds), np.clip(upper, *self.bounds)

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
            raise ParameterError("this study interpolates α = 1 with sensitivities; the evaluator returned none")
        values = F[:, self.nodes]
        slopes = J[:, self.nodes, 0] if self.refine and J is not None else None
        ds = xr.Dataset({"value": (("bin", "time"), values)},
                        coords={"bin": missing, "centre": ("bin", centres), "time": self.times})
        if slopes is not None:
            ds["slope"] = (("bin", "time"), slopes)
        _append(self.path, "library", ds, "bin")
        self.library_rows += int(missing.size)
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
        lower, upper = self._interval_hulls(left, right)
        ds = xr.Dataset({"left": ("interval", left), "right": ("interval", right),
                         "lower": (("interval", "time"), lower), "upper": (("interval", "time"), upper)},
                        coords={"time": self.times})  # fmt: skip
        _append(self.path, "intervals", ds, "interval")
        self.interval_rows += int(keys.size)
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
        O(spacing⁴)) kept within those two values — so the α = 1 output keeps the peak
        distribution instead of the grid's staircase, and never leaves what the
        simulations produced; without sensitivities, the value at the peak's bin centre.
        Every value lies within the model's declared bounds."""
        idx = np.searchsorted(self._keys, _encode(bins[:, :-1, 0], bins[:, :-1, 1]))
        hull = np.empty((bins.shape[0], bins.shape[1], 2, self.nodes.size))
        hull[:, :-1, 0] = self._int_lower[idx]
        hull[:, :-1, 1] = self._int_upper[idx]
        if self.refine and self._lib_slopes is not None and self._lib_values.shape[0] >= 2:
            hull[:, -1, :] = self._peak_values(peaks)[:, None, :]
        else:
            hull[:, -1, :] = self._lib_values[bins[:, -1, 0] - self._lib_first][:, None, :]
        hull[:, -1] = np.clip(hull[:, -1], *self.bounds)
        repaired = np.moveaxis(repair_nesting(np.moveaxis(hull, 0, 2)), 2, 0)
        return repaired, int(np.count_nonzero(repaired != hull))


def _sample_range(spec: FRVSpec, seed: int, start: int, n: int, chunk: int) -> tuple[float, float]:
    """Smallest and largest α-cut end of samples ``start … start+n−1`` (pass 1)."""
    low, high = np.inf, -np.inf
    for a, b in _blocks(start, start + n, max(chunk, BLOCK)):
        cuts = generate_samples(spec, b - a, seed, a)
        low, high = min(low, float(cuts[:, 0, 0].min())), max(high, float(cuts[:, 0, 1].max()))
    return low, high


