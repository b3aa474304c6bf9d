"""The persistent FRV-GFA study (thesis §2.7.4 steps 1–7) of one or several FRV
parameters: :class:`FRVStudy` runs the steps into a chunked zarr store, block by block,
and extends it by samples; every write commits atomically
(:mod:`fuzzygait.uncertainty.frv.store`). What differs between one parameter and several
is the study's :class:`~fuzzygait.uncertainty.frv.method.Method`."""

from __future__ import annotations

import os
import shutil
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.schema import BOUNDS
from fuzzygait.io.atomic import replace_folder, temporary_folder, tidy_beside
from fuzzygait.uncertainty.frv.evaluation import BatchFunction, declared_bounds, serial_evaluator
from fuzzygait.uncertainty.frv.grouping import Grid, possible_boxes
from fuzzygait.uncertainty.frv.hulls import HULLS
from fuzzygait.uncertainty.frv.method import Method, _blocks, sample_ranges
from fuzzygait.uncertainty.frv.multi import SeveralParameters
from fuzzygait.uncertainty.frv.options import MultiStudyOptions, StudyOptions
from fuzzygait.uncertainty.frv.samples import FRVSpec, _whole, check_specs
from fuzzygait.uncertainty.frv.single import OneParameter
from fuzzygait.uncertainty.frv.store import STORE_FORMAT, check, commit, new_store, open_group, read_meta
from fuzzygait.uncertainty.frv.store import append as _append
from fuzzygait.uncertainty.gfa import optimisation_nodes
from fuzzygait.uncertainty.protocol import FuzzyModel, Output

__all__ = ["STORE_FORMAT", "FRVStudy"]


def _new_counts() -> dict[str, Any]:
    return {"samples": 0, "forward_simulations": 0, "interval_optimisations": 0, "occurring_intervals": 0,
            "occurring_proper_intervals": 0, "possible_intervals": 0, "worst_case_optimisations": 0,
            "time_nodes": 0, "repaired_values": 0, "wall_time": 0.0, "last_forward_simulations": 0,
            "last_new_intervals": 0, "last_wall_time": 0.0}  # fmt: skip


def _method_of(meta: dict[str, Any]) -> type[Method]:
    """The study's method from its commit record: several parameters' record holds a list
    of ``spec`` (also with one parameter, a study made with :class:`MultiStudyOptions`)."""
    return SeveralParameters if isinstance(meta["spec"], list) else OneParameter


class FRVStudy:
    """An FRV-GFA study of one or several independent FRV parameters, persisted in a zarr
    store (directory) and extendable by samples.

    One parameter (the thesis' Table 5.3 case,
    :class:`~fuzzygait.uncertainty.frv.single.OneParameter`): a dictionary of occurring
    intervals, α = 1 by the cubic Hermite interpolant of the library on the grouping grid.
    Several (:class:`~fuzzygait.uncertainty.frv.multi.SeveralParameters`): boxes of
    per-parameter intervals on tensor grids, α = 1 on the peak lattice. A study of one
    parameter made with :class:`~fuzzygait.uncertainty.frv.MultiStudyOptions` is made
    the second way (its store has the several-parameter layout).

    Store layout (zarr v2 groups, written through xarray):

    * root attributes, the commit record: ``spec``, ``seed``, ``grid``, ``n_disc``,
      ``time_stride``, ``refine``, ``chunk``, ``n_time`` (the model's), ``n_samples``,
      ``counts``, the valid rows ``library_rows`` and ``interval_rows``, ``hulls``
      (``"simulated"``: the interval hulls are library extremes; absent in stores made
      before, whose stored ones are recomputed on :meth:`open`), and the caller's
      ``options`` (what the study was made with, e.g. the command's options); with
      several parameters ``spec``, ``grid`` and ``n_disc`` are lists and
      ``peak_refine``, ``peak_tolerance`` describe the α = 1 lattice;
    * ``library``: ``value (bin, time)`` the model at each bin centre or grid point
      (``slope`` = df/dp when refining), rows in order of computation;
    * ``intervals``: the dictionary of occurring intervals (boxes): their bins
      ``left``, ``right`` and ``lower``, ``upper (interval, time)`` hulls — the extreme
      library values over their bins (thesis §2.7.4, post-processing);
    * ``samples``: ``hull (sample, alpha, bound, time)`` chunked ``(chunk, all, 2, all)``
      with the raw α-cuts ``cut`` and their ``bin`` (``(sample, alpha, bound)``, with
      several parameters ``(sample, parameter, alpha, bound)``), written block by block
      (one append along ``sample`` per block of ``chunk`` samples).

    The method modules (:mod:`~fuzzygait.uncertainty.frv.single`,
    :mod:`~fuzzygait.uncertainty.frv.multi`) describe their entries. Only the output
    time nodes ``optimisation_nodes(n_time, time_stride)`` are kept (the library too).
    Each write phase (library, intervals, all samples of one call) commits atomically;
    rows a killed write left beyond the commit record are discarded on :meth:`open`, and
    a study is created in a folder beside its store and moved into place when complete.
    Use :meth:`create`, :meth:`open`, :meth:`add_samples`; read with :meth:`hulls`,
    :meth:`samples`, :meth:`library`, :meth:`intervals`, :attr:`counts`.
    """

    def __init__(self, path: Path, model: FuzzyModel, specs: tuple[FRVSpec, ...], meta: dict[str, Any],
                 evaluator: BatchFunction | None) -> None:  # fmt: skip
        kind = _method_of(meta)
        self.path, self.model, self.specs = path, model, specs
        self.grids: tuple[Grid, ...] = tuple(Grid(**g) for g in kind.listed(meta["grid"]))
        self.n_disc: list[int] = [int(n) for n in kind.listed(meta["n_disc"])]
        self.refine: bool | None = meta["refine"]
        self.seed = int(meta["seed"])
        self.time_stride = int(meta["time_stride"])
        self.chunk = int(meta["chunk"])
        self.n_time = int(meta["n_time"])
        self.n_samples = int(meta["n_samples"])
        self.library_rows = int(meta["library_rows"])
        self.interval_rows = int(meta["interval_rows"])
        self.options: dict[str, Any] = dict(meta.get("options") or {})
        self.counts: dict[str, Any] = dict(meta["counts"])
        self.evaluator: BatchFunction = evaluator if evaluator is not None else serial_evaluator(model)
        times = np.asarray(model.times, dtype=float)
        if times.ndim != 1 or times.size != self.n_time:
            raise ParameterError(f"{path}: the study has {self.n_time} time nodes; the model has {times.size}")
        self.nodes = optimisation_nodes(self.n_time, self.time_stride)
        self.times = times[self.nodes]
        self.bounds = declared_bounds(model)
        self.output: Output = model.output  # what the hulls are, and their units
        # the stored interval hulls are the library extremes (older stores: Hermite extrema)
        self.stored_hulls = meta.get("hulls") == HULLS
        self._method: Method = kind(self, meta)

    # ------------------------------------------------------------------ the parameters
    @property
    def n_params(self) -> int:
        """The number of FRV parameters."""
        return len(self.specs)

    @property
    def several(self) -> bool:
        """Whether the study has the several-parameter layout (boxes, α = 1 lattice)."""
        return isinstance(self._method, SeveralParameters)

    @property
    def spec(self) -> FRVSpec:
        """The FRV parameter of a study of one (:attr:`specs`: all of them).

        Raises:
            ParameterError: the study has several.
        """
        return self.specs[self._only("spec")]

    @property
    def grid(self) -> Grid:
        """The grid of a study of one FRV parameter (:attr:`grids`: all of them)."""
        return self.grids[self._only("grid")]

    def _only(self, what: str) -> int:
        if len(self.specs) != 1:
            names = ", ".join(s.name for s in self.specs)
            raise ParameterError(f"{self.path}: a study of {len(self.specs)} FRV parameters ({names}) has one "
                                 f"{what} each; use {what}s")  # fmt: skip
        return 0

    @property
    def alphas(self) -> tuple[float, ...]:
        """The α-levels (the same for every parameter)."""
        return self.specs[0].alphas

    @property
    def peak_refine(self) -> list[int] | None:
        """The α = 1 lattice per parameter (1: the grouping grid; None: not yet chosen)."""
        return self._method.peak_refine

    @property
    def peak_tolerance(self) -> float | None:
        """The α = 1 lattice's tolerance (several parameters; None for one)."""
        return self._method.peak_tolerance

    # ------------------------------------------------------------------ create / open
    @classmethod
    def create(cls, model: FuzzyModel, spec: FRVSpec | Sequence[FRVSpec], n_samples: int,
               options: StudyOptions | None = None, *, store: str | os.PathLike[str] | None = None,
               evaluator: BatchFunction | None = None) -> FRVStudy:  # fmt: skip
        """Run the FRV-GFA for ``n_samples`` samples into a new store.

        Args:
            model: a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel` of the FRV
                parameters (``p`` in ``spec`` order, SI); sensitivities used when declared.
            spec: the FRV parameter, or several (one :class:`FRVSpec` each, all with the
                same α-levels).
            n_samples: ``N_s``.
            options: the study's :class:`~fuzzygait.uncertainty.frv.StudyOptions`:
                ``n_disc`` grid points over the first batch's range (one number for all
                parameters or one per parameter; default 100 for one parameter, 30 per
                parameter for several), seed (parameter ``k`` is stream ``k``), time
                stride, refinement, chunk, overwrite and the ``record`` stored as the
                ``options`` attribute; a
                :class:`~fuzzygait.uncertainty.frv.MultiStudyOptions` adds the ``grids``
                to group on and the α = 1 lattice (``peak_refine``, ``peak_tolerance``)
                and makes the several-parameter study even of one parameter.
            store: the zarr directory to create.
            evaluator: batch evaluator ``P (k, n_params) -> (k, n_time)`` or ``(F, J (k,
                n_time, n_params))`` with sensitivities; default :func:`serial_evaluator`.

        The study is built in a temporary folder beside ``store`` and moved onto it when
        complete: on any failure (or a kill) nothing is left at ``store``.
        """
        t0 = time.perf_counter()
        specs = check_specs(spec)
        n_samples = _whole(n_samples, "n_samples", 1)
        options = StudyOptions() if options is None else options
        if not isinstance(options, StudyOptions):
            raise ParameterError(f"options: give a StudyOptions (or MultiStudyOptions); got {type(options).__name__}")
        kind = SeveralParameters if len(specs) > 1 or isinstance(options, MultiStudyOptions) else OneParameter
        discs = options.discs(len(specs), kind.default_disc)
        settings, grids = kind.settings(options, len(specs))
        if store is None:
            raise ParameterError("store: give the path of the zarr directory to create")
        path = Path(store)
        if path.exists() and not options.overwrite:
            raise FuzzyGaitError(f"{path}: already exists; open it with FRVStudy.open or pass overwrite=True")
        if not path.parent.exists():
            raise FuzzyGaitError(f"{path}: folder {path.parent} does not exist; create it first")
        if grids is None:
            ranges = sample_ranges(specs, options.seed, 0, n_samples)
            grids = [Grid.from_range(lo, hi, n) for (lo, hi), n in zip(ranges, discs, strict=True)]
        else:
            discs = [g.n_points for g in grids]
        record: dict[str, Any] = {"spec": kind.recorded([s.to_dict() for s in specs]), "seed": options.seed,
                "grid": kind.recorded([g.to_dict() for g in grids]), "n_disc": kind.recorded(discs),
                "time_stride": options.time_stride, "refine": options.refine, "hulls": HULLS, **settings,
                "chunk": options.chunk, "n_time": int(np.asarray(model.times).size), "n_samples": 0,
                "library_rows": 0, "interval_rows": 0, "counts": _new_counts(),
                "options": dict(options.record or {})}  # fmt: skip
        staging = temporary_folder(path, "creating")
        try:
            new_store(staging, record)
            study = cls(staging, model, specs, record, evaluator)
            study._ingest(0, n_samples, t0)
            replace_folder(staging, path)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        study.path = path
        return study

    @classmethod
    def open(cls, path: str | os.PathLike[str], model: FuzzyModel, evaluator: BatchFunction | None = None) -> FRVStudy:
        """Open a study written by :meth:`create`, of one FRV parameter or several (the
        model must be the same one)."""
        path = Path(path)
        meta = read_meta(path)
        specs = tuple(FRVSpec.from_dict(s) for s in _method_of(meta).listed(meta["spec"]))
        study = cls(path, model, specs, meta, evaluator)
        tidy_beside(path)
        check(path, meta, repair=True)
        study._method.load()
        return study

    # ------------------------------------------------------------------ public
    def add_samples(self, n: int) -> FRVStudy:
        """Add samples ``n_samples … n_samples + n − 1``: group them on the stored grids
        (each extended by whole bins if they leave it), simulate only bin centres (grid
        points) not yet in the library, compute only intervals (boxes) not yet in the
        dictionary, and append the new samples' hulls. Earlier samples' hulls are not
        touched."""
        t0 = time.perf_counter()
        n = _whole(n, "n")
        if n:
            check(self.path, read_meta(self.path), repair=True)
            ranges = sample_ranges(self.specs, self.seed, self.n_samples, n)
            self.grids = tuple(g.extended(r) for g, r in zip(self.grids, ranges, strict=True))
            self._write_meta()
            self._ingest(self.n_samples, n, t0)
        return self

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

    def library(self) -> xr.Dataset:
        """The library: ``value (bin, time)`` (and ``slope``); one parameter: at bin
        ``centre``, sorted by bin; several: at grid ``point`` / ``centre (bin,
        parameter)``, rows in order of computation."""
        return self._method.library()

    def intervals(self) -> xr.Dataset:
        """The interval (box) dictionary: ``left``, ``right`` bins (``(interval,
        parameter)`` with several parameters), ``lower``, ``upper (interval, time)``
        hulls, rows in order of computation."""
        return open_group(self.path, "intervals", self.interval_rows)

    boxes = intervals

    # ------------------------------------------------------------------ internals
    def _write_meta(self) -> None:
        """Commit: the record of the grids, counts and valid rows, rewritten in one file."""
        possible = possible_boxes(self.grids)
        self.counts["possible_intervals"] = possible
        entries = self._method.commit_entries()
        self.counts["time_nodes"] = int(self.nodes.size)
        self.counts["worst_case_optimisations"] = 2 * int(self.nodes.size) * possible  # Eq. 2.33, product form
        commit(self.path, {"grid": self._method.recorded([g.to_dict() for g in self.grids]), "refine": self.refine,
                           **entries, "n_samples": self.n_samples, "library_rows": self.library_rows,
                           "interval_rows": self.interval_rows, "counts": self.counts})  # fmt: skip

    def _ingest(self, start: int, n: int, t0: float) -> None:
        """Steps 2–7 for samples ``start … start+n−1`` on the current grids: pass 2
        completes the library and the dictionary for them (the method's); pass 3 draws
        and groups the samples again (a pure function of the sample index) and appends
        their hulls block by block."""
        stop = start + n
        simulations, new_entries = self._method.complete(start, stop)
        repaired, n_alpha, axes = 0, len(self.alphas), self._method.axes
        chunks = {"chunks": (self.chunk, *[self.n_params for _ in axes], n_alpha, 2)}
        encoding = {"hull": {"chunks": (self.chunk, n_alpha, 2, self.nodes.size)}, "cut": chunks, "bin": chunks}
        dims = ("sample", *axes, "alpha", "bound")
        for a, b in _blocks(start, stop, self.chunk):  # pass 3
            cuts = self._method.draw(a, b - a)
            bins = self._method.group(cuts)
            hull, changed = self._assemble(bins, cuts[..., -1, 0])
            repaired += changed
            ds = xr.Dataset({"hull": (("sample", "alpha", "bound", "time"), hull), "cut": (dims, cuts),
                             "bin": (dims, bins)}, coords={"sample": np.arange(a, b)})  # fmt: skip
            if a == 0:  # the creating write carries the other coordinates
                ds = ds.assign_coords(**self._method.parameter_coords(), alpha=list(self.alphas), bound=list(BOUNDS),
                                      time=self.times)  # fmt: skip
            _append(self.path, "samples", ds, "sample", encoding)
        elapsed = time.perf_counter() - t0
        self.n_samples = stop
        self.counts.update(samples=stop, repaired_values=self.counts["repaired_values"] + repaired,
                           wall_time=self.counts["wall_time"] + elapsed, last_forward_simulations=simulations,
                           last_new_intervals=new_entries, last_wall_time=elapsed)  # fmt: skip
        self._write_meta()

    def _assemble(self, bins: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, int]:
        """Hulls ``(nb, n_alpha, 2, n_nodes)`` of grouped samples with raw ``peaks``,
        nesting-repaired, and the number of values repaired (the method's)."""
        return self._method.assemble(bins, peaks)

