"""Parallel and distributed forward simulations through Dask.

A :class:`BatchEvaluator` evaluates a model for many parameter vectors at once — the
rows of ``P (k, n_p)`` — on a pool of processes::

    with BatchEvaluator(recipe, workers=4) as evaluate:     # local process pool
        trajectories = evaluate(P)                          # (k, n_time)

    evaluate = BatchEvaluator(recipe, scheduler="tcp://10.0.0.5:8786")   # existing cluster

* **No set-up.** Without ``scheduler`` a local Dask cluster of ``workers`` single-threaded
  processes (default: one per CPU) is started on first use, reused by every later call and
  shut down by :meth:`BatchEvaluator.close`, the ``with`` block, or at interpreter exit.
  ``workers=1`` runs serially in this process through the *same* task function.
  ``scheduler`` may be the address of a running scheduler (``distributed.Client`` is
  connected to it) or a ``distributed.Client`` you already have.
* **Recipes, not models.** Workers receive a small picklable *recipe* (``build()`` and a
  hashable ``key``, see :class:`ModelRecipe`) and build the model once per process; the
  built model is cached in this module by ``recipe.key``. Compiled simulators therefore
  load their shared library from the on-disk cache (:mod:`fuzzygait.mechanics.codegen`)
  instead of receiving pickled JIT-compiled CasADi functions, which would recompile on
  every unpickling. Large inputs a recipe needs (precomputed trajectories, marker data)
  belong in a :class:`SharedArray`: a ``.npy`` file every worker memory-maps read-only
  (one copy in the page cache, not one per worker and task).
* **Results through a memory-mapped store.** The driver allocates ``.npy`` files of the
  full result shape (in a private temporary directory, or in ``store``); each task writes
  its rows at their byte offset and returns only a small status, so trajectories never
  travel through the scheduler as pickles. The driver reads the rows back by index, so the
  order is the input order whatever the completion order. A worker that cannot see the
  store (a remote machine without a shared file system) returns its rows with the status
  instead — the same numbers, only more traffic.
* **Deterministic.** Each row is computed independently by the same function on a model
  built from the same recipe, so 1 worker and N workers give bit-identical results, as
  long as the processes use the same BLAS threading (the local cluster's workers run with
  ``OPENBLAS_NUM_THREADS=OMP_NUM_THREADS=MKL_NUM_THREADS=1``; set the same in the driver
  for the serial path — the test suite does).
* **One error.** A row whose evaluation raises is reported as one
  :class:`ParallelEvaluationError` (a :class:`~fuzzygait.core.errors.FuzzyGaitError`) naming the
  row, its parameters and the original error type and message — no remote traceback. An
  unreachable scheduler address is one such error too.

:class:`ParallelModel` wraps an evaluator as an uncertainty-engine model with
``evaluate_nodes``, so the all-nodes-at-once direct mode of
:func:`~fuzzygait.uncertainty.gfa.graph_follower` runs its α-level optimisations' forward
simulations in parallel.
"""

from __future__ import annotations

import math
import os
import shutil
import socket
import tempfile
import threading
import time
import uuid
import weakref
from collections.abc import Hashable, Sequence
from dataclasses import astuple, dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from fuzzygait.core.errors import FuzzyGaitError, ParameterError

#: Environment of the local cluster's worker processes: one BLAS/OpenMP thread each (the
#: workers are the parallelism; nested threads only oversubscribe the cores).
WORKER_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


class ParallelEvaluationError(FuzzyGaitError):
    """A parallel evaluation failed.

    Attributes:
        row: index of the failing parameter row (None when no row is to blame, e.g. an
            unreachable scheduler).
        parameters: that row's parameter vector (list of floats) or None.
        error_type: name of the original exception type (e.g. ``"SimulationError"``).
    """

    def __init__(self, message: str, row: int | None = None, parameters: list[float] | None = None,
                 error_type: str | None = None) -> None:  # fmt: skip
        super().__init__(message)
        self.row, self.parameters, self.error_type = row, parameters, error_type


# ------------------------------------------------------------------------------ recipes
@runtime_checkable
class ModelRecipe(Protocol):
    """What a worker needs to build a model: a picklable object with a stable, hashable
    ``key`` (equal keys ⇒ equal models; the built model is cached per process by it) and
    ``build() -> model`` (see :mod:`fuzzygait.uncertainty.model`). Keep recipes small:
    put big arrays in a :class:`SharedArray`."""

    @property
    def key(self) -> Hashable: ...

    def build(self) -> Any: ...


_SHARED_ARRAYS: dict[str, np.ndarray] = {}


@dataclass(frozen=True)
class SharedArray:
    """A read-only array that every worker memory-maps from one ``.npy`` file.

    Pass a ``SharedArray`` (a path, a shape and a dtype: a few bytes) in a recipe instead of
    the array itself; :meth:`load` maps the file once per process. The file must be visible
    to the workers (local cluster: always; remote cluster: a shared file system).
    """

    path: str
    shape: tuple[int, ...]
    dtype: str

    @classmethod
    def create(cls, array: np.ndarray, path: str | os.PathLike[str]) -> "SharedArray":
        """Write ``array`` to ``path`` (``.npy``) and return its handle."""
        array = np.ascontiguousarray(array)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, array)
        return cls(str(path.resolve()), tuple(int(n) for n in array.shape), array.dtype.str)

    def load(self) -> np.ndarray:
        """The array, memory-mapped read-only (mapped once per process)."""
        array = _SHARED_ARRAYS.get(self.path)
        if array is None:
            try:
                array = np.load(self.path, mmap_mode="r")
            except OSError as err:
                raise ParameterError(f"shared array {self.path} cannot be read: {err}") from None
            if array.shape != self.shape or array.dtype.str != self.dtype:
                raise ParameterError(
                    f"shared array {self.path} holds {array.dtype.str}{list(array.shape)}, "
                    f"expected {self.dtype}{list(self.shape)} (was the file replaced?)"
                )
            _SHARED_ARRAYS[self.path] = array
        return array


@dataclass(frozen=True)
class LegModelRecipe:
    """Recipe of :class:`~fuzzygait.mechanics.targets.LegTargetModel`: one target output of
    a leg scenario as a function of the named parameters.

    Args:
        scenario: "swing" or "stance".
        target: see :data:`fuzzygait.mechanics.targets.TARGETS`.
        names: the varying parameters, in the order of the columns of ``P``.
        base: the full leg parameter vector the others are fixed at (None: the scenario's).
        nodes: blade nodes.
        dt, duration: time step and simulated time (s; None: the scenario's).
        scheme: time stepping scheme ("variational" for sensitivities).
        foot: "beam", "rigid" or "none".
    """

    scenario: str = "swing"
    target: str = "total_deformation_energy"
    names: tuple[str, ...] = ("E",)
    base: tuple[float, ...] | None = None
    nodes: int = 20
    dt: float | None = None
    duration: float | None = None
    scheme: str = "variational"
    foot: str = "beam"

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))
        if self.base is not None:
            object.__setattr__(self, "base", tuple(float(v) for v in np.asarray(self.base, float).ravel()))
        object.__setattr__(self, "nodes", int(self.nodes))
        for name in ("dt", "duration"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))

    @property
    def key(self) -> Hashable:
        return ("LegModelRecipe", *astuple(self))

    def build(self) -> Any:
        # Imported here so that the engine does not import the simulator (CasADi) unless used.
        from fuzzygait.mechanics.scenarios import LegSimulator
        from fuzzygait.mechanics.targets import LegTargetModel

        simulator = LegSimulator(self.scenario, nodes=self.nodes, foot=self.foot)  # type: ignore[arg-type]
        base = None if self.base is None else np.asarray(self.base, dtype=float)
        return LegTargetModel(simulator, self.target, self.names, base, self.dt, self.duration, self.scheme)


@dataclass
class _AnalyticModel:
    kind: str
    times: np.ndarray
    fail_above: float | None
    offset: np.ndarray | None

    def _check(self, p: np.ndarray) -> None:
        if self.fail_above is not None and p[0] > self.fail_above:
            raise ParameterError(f"p[0] = {p[0]:g} exceeds fail_above = {self.fail_above:g}")

    def evaluate_with_sensitivities(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        p = np.asarray(p, dtype=float).ravel()
        self._check(p)
        t = self.times[:, None]
        omega = np.arange(1, p.size + 1, dtype=float)[None, :]
        if self.kind == "sin":
            terms, jac = np.sin(omega * t * p), omega * t * np.cos(omega * t * p)
        else:  # poly
            terms, jac = p**2 * t**omega, 2.0 * p * t**omega
        values = terms.sum(axis=1)
        if self.offset is not None:
            values = values + self.offset
        return values, jac

    def evaluate(self, p: np.ndarray) -> np.ndarray:
        return self.evaluate_with_sensitivities(p)[0]


@dataclass(frozen=True)
class AnalyticRecipe:
    """A cheap analytic model, for tests and examples of the parallel machinery.

    ``kind="sin"``: ``f(t) = Σ_i sin((i+1)·t·p_i)``; ``kind="poly"``:
    ``f(t) = Σ_i p_i²·t^(i+1)``, on ``n_time`` nodes of ``[0, t_end]``, with exact
    sensitivities. ``offset`` (a :class:`SharedArray` of shape ``(n_time,)``) is added to
    the output; ``fail_above`` makes evaluation raise
    :class:`~fuzzygait.core.errors.ParameterError` when ``p[0] > fail_above`` (to test errors).
    """

    kind: str = "sin"
    n_time: int = 101
    t_end: float = 1.0
    fail_above: float | None = None
    offset: SharedArray | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("sin", "poly"):
            raise ParameterError(f"unknown analytic model {self.kind!r}; choose 'sin' or 'poly'")
        if self.n_time < 1:
            raise ParameterError(f"n_time must be ≥ 1; got {self.n_time}")

    @property
    def key(self) -> Hashable:
        return ("AnalyticRecipe", self.kind, self.n_time, self.t_end, self.fail_above, self.offset)

    def build(self) -> _AnalyticModel:
        offset = None if self.offset is None else np.asarray(self.offset.load(), dtype=float)
        if offset is not None and offset.shape != (self.n_time,):
            raise ParameterError(f"offset must have shape ({self.n_time},); got {offset.shape}")
        times = np.linspace(0.0, self.t_end, self.n_time)
        return _AnalyticModel(self.kind, times, self.fail_above, offset)


# ------------------------------------------------------------------ worker-side state
_MODELS: dict[Hashable, Any] = {}
_MODEL_LOCKS: dict[Hashable, threading.Lock] = {}
_BUILD_LOCK = threading.Lock()


def _model_for(recipe: ModelRecipe) -> tuple[Any, threading.Lock, float]:
    """The model of ``recipe`` in this process (built on first use), its evaluation lock
    and the seconds spent building it now (0 when cached)."""
    key = recipe.key
    with _BUILD_LOCK:
        model = _MODELS.get(key)
        seconds = 0.0
        if model is None:
            start = time.perf_counter()
            model = recipe.build()
            seconds = time.perf_counter() - start
            _MODELS[key] = model
            _MODEL_LOCKS[key] = threading.Lock()
        return model, _MODEL_LOCKS[key], seconds


def clear_model_cache() -> None:
    """Forget the models built in this process (they are rebuilt on next use)."""
    with _BUILD_LOCK:
        _MODELS.clear()
        _MODEL_LOCKS.clear()
        _SHARED_ARRAYS.clear()


@dataclass(frozen=True)
class _Slot:
    """Where a task writes its rows: a ``.npy`` file, its data offset and its row size."""

    path: str
    offset: int
    row_shape: tuple[int, ...]

    @classmethod
    def allocate(cls, path: Path, shape: tuple[int, ...]) -> "_Slot":
        array = np.lib.format.open_memmap(path, mode="w+", dtype=np.float64, shape=shape)
        offset = int(array.offset)
        array.flush()
        del array
        return cls(str(path), offset, tuple(shape[1:]))

    @property
    def row_bytes(self) -> int:
        return 8 * int(np.prod(self.row_shape, dtype=np.int64))

    def visible(self, rows: int) -> bool:
        try:
            return os.path.getsize(self.path) >= self.offset + rows * self.row_bytes
        except OSError:
            return False

    def write(self, start: int, block: np.ndarray) -> None:
        # pwrite of the block's own byte range: disjoint writes never share a page, so this
        # is safe on shared network file systems too (concurrent mmap writes are not).
        data = np.ascontiguousarray(block, dtype="<f8").tobytes()
        fd = os.open(self.path, os.O_WRONLY)
        try:
            os.pwrite(fd, data, self.offset + start * self.row_bytes)
        finally:
            os.close(fd)


def _probe(recipe: ModelRecipe, sensitivities: bool) -> dict[str, Any]:
    """Build (or fetch) the model and describe it: its times and whether it has
    sensitivities. Errors are returned, not raised."""
    try:
        model, _, seconds = _model_for(recipe)
        times = np.asarray(model.times, dtype=float).ravel()
        has_sens = callable(getattr(model, "evaluate_with_sensitivities", None))
    except Exception as err:  # noqa: BLE001 - reported as one error in the driver
        return {"error": f"{type(err).__name__}: {err}", "error_type": type(err).__name__}
    return {"times": times, "sensitivities": has_sens, "build_seconds": seconds, "pid": os.getpid(),
            "host": socket.gethostname()}


def _evaluate_rows(
    recipe: ModelRecipe, start: int, P: np.ndarray, values: _Slot, sens: _Slot | None
) -> dict[str, Any]:
    """Evaluate rows ``start, start+1, …`` (``P``) and write them into the store.

    Returns a small status: rows, process, build and run seconds; the rows themselves only
    when the store is not visible here; the failing row and message instead on error.
    """
    status: dict[str, Any] = {"start": start, "stop": start + len(P), "pid": os.getpid(),
                              "host": socket.gethostname(), "build_seconds": 0.0}  # fmt: skip
    row = start
    try:
        model, lock, status["build_seconds"] = _model_for(recipe)
        tic = time.perf_counter()
        n_time = values.row_shape[0]
        out = np.empty((len(P), n_time))
        out_sens = np.empty((len(P), *sens.row_shape)) if sens is not None else None
        with lock:
            for i, p in enumerate(np.asarray(P, dtype=float)):
                row = start + i
                if out_sens is not None:
                    f, jac = model.evaluate_with_sensitivities(p.copy())
                    jac = np.asarray(jac, dtype=float)
                    if jac.size != out_sens[i].size:
                        raise ParameterError(
                            f"the model returned sensitivities of shape {jac.shape}, expected {sens.row_shape}"
                        )
                    out_sens[i] = jac.reshape(sens.row_shape)
                else:
                    f = model.evaluate(p.copy())
                f = np.asarray(f, dtype=float).ravel()
                if f.size != n_time:
                    raise ParameterError(f"the model returned {f.size} values for {n_time} time nodes")
                out[i] = f
        status["seconds"] = time.perf_counter() - tic
    except Exception as err:  # noqa: BLE001 - reported as one error in the driver
        status.update(error=f"{type(err).__name__}: {err}", error_type=type(err).__name__, row=row)
        return status
    if values.visible(status["stop"]) and (sens is None or sens.visible(status["stop"])):
        values.write(start, out)
        if sens is not None:
            sens.write(start, out_sens)
    else:
        status["values"] = out
        status["sensitivities"] = out_sens
    return status


# ------------------------------------------------------------------------ the driver
@dataclass
class _Resources:
    """What an evaluator owns and must release (kept apart so ``weakref.finalize`` does not
    hold the evaluator alive)."""

    client: Any = None
    cluster: Any = None
    owns_client: bool = False
    tmpdir: str | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def release(self) -> None:
        with self.lock:
            client, cluster, tmpdir = self.client, self.cluster, self.tmpdir
            self.client = self.cluster = self.tmpdir = None
            if client is not None and self.owns_client:
                try:
                    client.close()
                except Exception:  # noqa: BLE001 - best effort at shutdown
                    pass
            if cluster is not None:
                try:
                    cluster.close()
                except Exception:  # noqa: BLE001
                    pass
            if tmpdir is not None:
                shutil.rmtree(tmpdir, ignore_errors=True)


class BatchEvaluator:
    """Evaluate a model for many parameter vectors in parallel (see the module docstring).

    Args:
        recipe: a :class:`ModelRecipe` (e.g. :class:`LegModelRecipe`).
        scheduler: None (a local process pool), the address of a running Dask scheduler
            (``"tcp://host:8786"``), or a ``distributed.Client``.
        workers: size of the local pool (default: the CPU count; 1 = serial in this
            process). Ignored with ``scheduler``.
        sensitivities: return ``(values, sensitivities)`` — ``(k, n_time)`` and
            ``(k, n_time, n_p)`` — from the model's ``evaluate_with_sensitivities``.
        store: directory of the result files. None: a private temporary directory, and
            results are returned as in-memory arrays. A directory: each call's results stay
            there (``batch-NNNNN-values.npy``, ``…-sensitivities.npy``) and are returned as
            read-only memory maps of those files. For a remote cluster it must be on a file
            system the workers share (otherwise the rows come back with the statuses).
        chunk: parameter rows per task (None: about four tasks per worker).
        connect_timeout: seconds to wait for a scheduler address to answer.

    Call it with ``P (k, n_p)``. :attr:`last_statistics` lists, per task of the last call,
    the rows, the worker process and host, and the seconds spent building the model (0
    when the process had it cached) and evaluating; :attr:`builds` lists every model build
    this evaluator caused (process, host, seconds) — one per worker process at most.
    """

    def __init__(
        self,
        recipe: ModelRecipe,
        scheduler: str | Any | None = None,
        workers: int | None = None,
        sensitivities: bool = False,
        store: str | os.PathLike[str] | None = None,
        chunk: int | None = 1,
        connect_timeout: float = 10.0,
    ) -> None:
        if not callable(getattr(recipe, "build", None)) or not hasattr(recipe, "key"):
            raise ParameterError("recipe must have build() and a hashable key (see ModelRecipe)")
        try:
            hash(recipe.key)
        except TypeError:
            raise ParameterError(f"the recipe's key must be hashable; got {recipe.key!r}") from None
        if workers is not None and (int(workers) != workers or workers < 1):
            raise ParameterError(f"workers must be a positive integer; got {workers}")
        if chunk is not None and (int(chunk) != chunk or chunk < 1):
            raise ParameterError(f"chunk must be a positive integer or None; got {chunk}")
        self.recipe = recipe
        self.scheduler = scheduler
        self.workers = int(workers) if workers is not None else (os.cpu_count() or 1)
        self.sensitivities = bool(sensitivities)
        self.store = None if store is None else Path(store)
        self.chunk = None if chunk is None else int(chunk)
        self.connect_timeout = float(connect_timeout)
        self.last_statistics: list[dict[str, Any]] = []
        self.builds: list[dict[str, Any]] = []
        self._times: np.ndarray | None = None
        self._calls = 0
        self._resources = _Resources()
        self._finalizer = weakref.finalize(self, self._resources.release)

    # -- life cycle -----------------------------------------------------------------------
    @property
    def serial(self) -> bool:
        """Whether evaluation runs in this process (no scheduler and one worker)."""
        return self.scheduler is None and self.workers == 1

    @property
    def client(self) -> Any:
        """The ``distributed.Client`` (the local cluster is started, or the scheduler
        connected, on first use); None in serial mode."""
        if self.serial:
            return None
        res = self._resources
        with res.lock:
            if res.client is None:
                self._connect(res)
            return res.client

    def _connect(self, res: _Resources) -> None:
        import logging

        from distributed import Client, LocalCluster

        if self.scheduler is None:
            try:
                cluster = LocalCluster(
                    n_workers=self.workers, threads_per_worker=1, processes=True,
                    silence_logs=logging.ERROR, env=dict(WORKER_ENV), dashboard_address=None,
                    # no dashboard; the scheduler's health endpoint on a free local port
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                )  # fmt: skip
            except Exception as err:  # noqa: BLE001
                raise ParallelEvaluationError(f"cannot start a local Dask cluster: {err}") from None
            res.cluster, res.client, res.owns_client = cluster, Client(cluster, set_as_default=False), True
        elif isinstance(self.scheduler, str):
            try:
                res.client = Client(self.scheduler, timeout=self.connect_timeout, set_as_default=False)
            except Exception as err:  # noqa: BLE001
                raise ParallelEvaluationError(
                    f"cannot reach the Dask scheduler at {self.scheduler!r} within "
                    f"{self.connect_timeout:g} s ({type(err).__name__}: {err}); is it running "
                    "and is the address right?"
                ) from None
            res.owns_client = True
        else:
            res.client, res.owns_client = self.scheduler, False

    def _tmpdir(self) -> Path:
        if self.store is not None:
            self.store.mkdir(parents=True, exist_ok=True)
            return self.store
        res = self._resources
        with res.lock:
            if res.tmpdir is None:
                res.tmpdir = tempfile.mkdtemp(prefix="fuzzygait-parallel-")
            return Path(res.tmpdir)

    def close(self) -> None:
        """Shut down the local cluster (or disconnect from the scheduler) and remove the
        temporary store. The evaluator starts afresh if called again."""
        self._resources.release()

    def __enter__(self) -> "BatchEvaluator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- evaluation -----------------------------------------------------------------------
    @property
    def times(self) -> np.ndarray:
        """The model's time nodes (asks a worker to build the model on first access)."""
        if self._times is None:
            client = self.client
            if client is None:
                info = _probe(self.recipe, self.sensitivities)
            else:
                info = self._gather(client, [client.submit(_probe, self.recipe, self.sensitivities, pure=False)])[0]
            if "error" in info:
                raise ParallelEvaluationError(f"building the model failed: {info['error']}",
                                              error_type=info["error_type"])  # fmt: skip
            if info["build_seconds"]:
                self.builds.append({key: info[key] for key in ("pid", "host", "build_seconds")})
            if self.sensitivities and not info["sensitivities"]:
                raise ParameterError("the model has no evaluate_with_sensitivities; use sensitivities=False")
            self._times = info["times"]
        return self._times

    def _gather(self, client: Any, futures: list[Any]) -> list[Any]:
        try:
            return client.gather(futures)
        except Exception as err:  # noqa: BLE001 - worker death, lost connection
            raise ParallelEvaluationError(
                f"the Dask cluster failed while evaluating ({type(err).__name__}: {err})"
            ) from None
        finally:
            for future in futures:
                future.release()

    def _blocks(self, k: int) -> list[tuple[int, int]]:
        n_workers = 1
        if self.chunk is None and not self.serial:
            n_workers = max(1, len(self.client.scheduler_info().get("workers", {})) or self.workers)
        size = self.chunk if self.chunk is not None else max(1, math.ceil(k / (4 * n_workers)))
        return [(s, min(s + size, k)) for s in range(0, k, size)]

    def __call__(self, P: np.ndarray) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        P = np.asarray(P, dtype=float)
        if P.ndim != 2:
            raise ParameterError(f"P must be a 2-D array (rows = parameter vectors); got shape {P.shape}")
        if not np.all(np.isfinite(P)):
            bad = int(np.flatnonzero(~np.all(np.isfinite(P), axis=1))[0])
            raise ParameterError(f"parameter row {bad} is not finite: {P[bad].tolist()}")
        k, n_p = P.shape
        n_time = self.times.size
        directory = self._tmpdir()
        self._calls += 1
        stem = f"batch-{self._calls:05d}-{uuid.uuid4().hex[:8]}" if self.store is None else f"batch-{self._calls:05d}"
        values = _Slot.allocate(directory / f"{stem}-values.npy", (k, n_time))
        sens = _Slot.allocate(directory / f"{stem}-sensitivities.npy", (k, n_time, n_p)) if self.sensitivities else None
        try:
            statuses = self._run(P, values, sens)
            self._raise_first_error(statuses, P)
            out_values = self._read(values, statuses, "values")
            out_sens = self._read(sens, statuses, "sensitivities") if sens is not None else None
        finally:
            if self.store is None:
                for slot in (values, sens):
                    if slot is not None:
                        Path(slot.path).unlink(missing_ok=True)
        self.last_statistics = [
            {key: s[key] for key in ("start", "stop", "pid", "host", "build_seconds", "seconds")} for s in statuses
        ]
        self.builds += [
            {key: s[key] for key in ("pid", "host", "build_seconds")} for s in statuses if s["build_seconds"]
        ]
        return (out_values, out_sens) if self.sensitivities else out_values

    def _run(self, P: np.ndarray, values: _Slot, sens: _Slot | None) -> list[dict[str, Any]]:
        blocks = self._blocks(P.shape[0])
        client = self.client
        if client is None:
            return [_evaluate_rows(self.recipe, a, P[a:b], values, sens) for a, b in blocks]
        token = uuid.uuid4().hex[:12]
        futures = [
            client.submit(_evaluate_rows, self.recipe, a, P[a:b], values, sens,
                          key=f"fuzzygait-rows-{token}-{a}", pure=False)  # fmt: skip
            for a, b in blocks
        ]
        return sorted(self._gather(client, futures), key=lambda s: s["start"])

    @staticmethod
    def _raise_first_error(statuses: Sequence[dict[str, Any]], P: np.ndarray) -> None:
        failed = [s for s in statuses if "error" in s]
        if not failed:
            return
        first = min(failed, key=lambda s: s["row"])
        row = int(first["row"])
        others = len(failed) - 1
        more = f" ({others} other task(s) failed too)" if others else ""
        raise ParallelEvaluationError(
            f"evaluating parameter row {row} {P[row].tolist()} failed: {first['error']}{more}",
            row=row, parameters=P[row].tolist(), error_type=first["error_type"],
        )  # fmt: skip

    def _read(self, slot: _Slot, statuses: Sequence[dict[str, Any]], name: str) -> np.ndarray:
        stored = np.load(slot.path, mmap_mode="r+" if any(s.get(name) is not None for s in statuses) else "r")
        for s in statuses:
            if s.get(name) is not None:  # a worker that could not see the store
                stored[s["start"]:s["stop"]] = s[name]
        if isinstance(stored, np.memmap) and stored.mode == "r+":
            stored.flush()
        if self.store is not None:
            return np.load(slot.path, mmap_mode="r")
        return np.array(stored)


def parallel_map(
    recipe: ModelRecipe,
    P: np.ndarray,
    *,
    scheduler: str | Any | None = None,
    workers: int | None = None,
    sensitivities: bool = False,
    store: str | os.PathLike[str] | None = None,
    chunk: int | None = 1,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Evaluate ``recipe``'s model at every row of ``P`` once (a :class:`BatchEvaluator`
    that is closed afterwards; keep an evaluator to reuse its workers across calls)."""
    with BatchEvaluator(recipe, scheduler, workers, sensitivities, store, chunk) as evaluate:
        return evaluate(P)


class ParallelModel:
    """A :class:`BatchEvaluator` as an uncertainty-engine model.

    Offers ``times``, ``evaluate``, ``evaluate_many(P)`` and ``evaluate_nodes(P, nodes)``
    (so :func:`~fuzzygait.uncertainty.gfa.graph_follower` in direct mode evaluates each
    iteration's points in parallel; duplicate rows are simulated once), and
    ``evaluate_with_sensitivities`` when the evaluator computes sensitivities.
    """

    def __init__(self, evaluator: BatchEvaluator) -> None:
        self.evaluator = evaluator
        self.times = evaluator.times
        if evaluator.sensitivities:
            self.evaluate_with_sensitivities = self._evaluate_with_sensitivities

    def evaluate_many(self, P: np.ndarray) -> np.ndarray:
        out = self.evaluator(np.atleast_2d(np.asarray(P, dtype=float)))
        return out[0] if isinstance(out, tuple) else out

    def evaluate(self, p: np.ndarray) -> np.ndarray:
        return self.evaluate_many(np.asarray(p, dtype=float).reshape(1, -1))[0]

    def _evaluate_with_sensitivities(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        values, sens = self.evaluator(np.asarray(p, dtype=float).reshape(1, -1))
        return values[0], sens[0]

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        P = np.atleast_2d(np.asarray(P, dtype=float))
        unique, inverse = np.unique(P, axis=0, return_inverse=True)
        trajectories = self.evaluate_many(unique)
        return trajectories[inverse.ravel(), np.asarray(nodes, dtype=int).ravel()]
