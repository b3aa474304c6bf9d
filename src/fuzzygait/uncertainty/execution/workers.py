"""Worker-side machinery of the :class:`~fuzzygait.uncertainty.execution.Evaluator`:
model recipes, shared read-only arrays, the per-process model cache and the task
functions that evaluate parameter rows into memory-mapped result files.

Workers receive a small picklable *recipe* (``build()`` and a hashable ``key``, see
:class:`ModelRecipe`) and build the model once per process; the built model is cached
here by ``recipe.key``. Compiled simulators therefore load their shared library from the
on-disk cache instead of receiving pickled JIT-compiled CasADi functions. Large inputs a
recipe needs belong in a :class:`SharedArray`: a ``.npy`` file every worker
memory-maps read-only.
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import threading
import time
from collections.abc import Hashable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.protocol import SENSITIVITIES

#: Environment of the local cluster's worker processes: one BLAS/OpenMP thread each (the
#: workers are the parallelism; nested threads only oversubscribe the cores).
WORKER_ENV = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

#: Dask settings of the local cluster's workers (a nanny hands its worker the settings in
#: force when the nanny is made). Dask's statistical profiler is off: it samples every
#: worker's stack every 10 ms and keeps the last 1,000 one-second profiles, which grew a
#: worker by about 2 MB per trial page over a long batch report
#: (``benchmarks/report_load.py``) and costs time no-one looks at without a dashboard.
WORKER_SETTINGS = {"distributed.worker.profile.enabled": False}

#: The Dask preload of the local cluster's workers (:func:`dask_setup` runs in each).
WORKER_PRELOAD = __name__


#: Loggers of a worker process whose shutdown noise :class:`_ShutdownNoise` drops.
_NOISY_LOGGERS = ("distributed.worker", "distributed.core", "distributed.comm", "distributed.batched",
                  "distributed.nanny", "distributed.worker.state_machine",
                  "distributed.diskutils")  # fmt: skip  # its scratch directory: the evaluator removes it


class _ShutdownNoise(logging.Filter):
    """Drops a worker's log records once it is closing, and its tracebacks of a lost
    connection to the scheduler (the driver going away): neither tells the user anything
    the command does not say in one line."""

    def __init__(self, worker: object) -> None:
        super().__init__()
        self.worker = worker

    def filter(self, record: logging.LogRecord) -> bool:
        status = str(getattr(self.worker, "status", ""))
        if "clos" in status or "stopp" in status:
            return False
        return not str(record.msg).startswith(("Failed to communicate with scheduler", "Connection to"))


def dask_setup(worker: object) -> None:
    """Run by Dask in every worker process of the local cluster as it starts: the worker
    computes with one BLAS/OpenMP thread, ignores SIGINT, and logs nothing about its own
    shutdown.

    One thread: :data:`WORKER_ENV` says so to a spawned worker before it loads the
    libraries; a forked one (:func:`~.teardown.start_method`) has them loaded already,
    with the driver's thread counts, so they are set here (``threadpoolctl``).

    SIGINT: a Ctrl-C in a terminal goes to the whole process group; the driver (the
    ``fuzzygait`` command) then shuts the pool down itself, so a worker has nothing to do
    with it but print a traceback of the task it was running.  (The worker was born with
    SIGINT and SIGTERM blocked, before this runs:
    :func:`fuzzygait.uncertainty.execution.teardown.start_loop`; ignoring SIGINT keeps it
    so should anything unblock it.)"""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1)  # kept for the process's life (not used as a context)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    noise = _ShutdownNoise(worker)
    for name in _NOISY_LOGGERS:
        logging.getLogger(name).addFilter(noise)


@runtime_checkable
class ModelRecipe(Protocol):
    """What a worker needs to build a model: a picklable object with a stable, hashable
    ``key`` (equal keys ⇒ equal models; the built model is cached per process by it) and
    ``build() -> model`` (a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`). Keep recipes small:
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
    def create(cls, array: np.ndarray, path: str | os.PathLike[str]) -> SharedArray:
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


_MODELS: dict[Hashable, Any] = {}
_MODEL_LOCKS: dict[Hashable, threading.Lock] = {}
_BUILD_LOCK = threading.Lock()


def model_for(recipe: ModelRecipe) -> tuple[Any, threading.Lock, float]:
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


def fresh_after_fork() -> None:
    """In a forked copy of this process: new locks for the model cache and new file objects
    for the streams it writes to (:func:`_fresh_streams`).  Registered for every fork of a
    process that imported this module (``os.register_at_fork``), so in a local cluster's
    forked worker (:func:`~.teardown.start_method`) and in any other forked child alike,
    where the new objects write to the same descriptors as before.  The models the copy
    inherits are used as they are (they are the same models); a lock another thread of
    the original held at the moment of the copy would be held for ever in it."""
    global _BUILD_LOCK
    _BUILD_LOCK = threading.Lock()
    for key in list(_MODEL_LOCKS):
        _MODEL_LOCKS[key] = threading.Lock()
    _fresh_streams()


#: The copy's inherited stream objects, replaced by :func:`_fresh_streams` and kept so
#: that none is ever closed (its close would flush through its inherited lock).
_INHERITED_STREAMS: list[object] = []


def _fresh_streams() -> None:
    """``sys.stdout``, ``sys.stderr`` and every logging handler's stream replaced by a new
    file object on a duplicate of the same descriptor, buffer empty.

    A buffered file's lock is taken by whichever thread writes through it: another thread
    of the original (Dask's event loop logging, a progress bar) writing at the moment of
    the copy left it held for ever in the copy, whose first log line or warning then
    waited for ever (seen in the test suite: a worker stuck in its Dask preload's log line
    through pytest's log file handler).  Streams without a descriptor (``StringIO``, a
    capture) hold no such lock and are kept."""
    import sys

    made: dict[int, object] = {}

    def fresh(stream: Any) -> Any:
        if id(stream) in made:
            return made[id(stream)]
        try:
            descriptor = stream.fileno()
            lines = bool(getattr(stream, "line_buffering", False))
            copy = os.fdopen(os.dup(descriptor), "w", buffering=1 if lines else -1, encoding=stream.encoding,
                             errors=stream.errors)  # fmt: skip
        except (AttributeError, OSError, ValueError):  # no descriptor, or not a text stream
            return stream
        _INHERITED_STREAMS.append(stream)
        made[id(stream)] = copy
        return copy

    sys.stdout, sys.stderr = fresh(sys.stdout), fresh(sys.stderr)
    for reference in list(logging._handlerList):  # type: ignore[attr-defined]  # weak references to every handler
        handler = reference()
        if isinstance(handler, logging.StreamHandler) and handler.stream is not None:
            try:
                handler.stream = fresh(handler.stream)  # not setStream: it flushes the old one
            except AttributeError:  # a handler whose stream is looked up (logging's last resort: sys.stderr)
                continue


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=fresh_after_fork)


def clear_model_cache() -> None:
    """Forget the models built in this process (they are rebuilt on next use)."""
    with _BUILD_LOCK:
        _MODELS.clear()
        _MODEL_LOCKS.clear()
        _SHARED_ARRAYS.clear()


@dataclass(frozen=True)
class Slot:
    """Where a task writes its rows: a ``.npy`` file, its data offset and its row size."""

    path: str
    offset: int
    row_shape: tuple[int, ...]

    @classmethod
    def allocate(cls, path: Path, shape: tuple[int, ...]) -> Slot:
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


def probe(recipe: ModelRecipe, sensitivities: bool) -> dict[str, Any]:
    """Build (or fetch) the model and describe it: its times and whether it has
    sensitivities. Errors are returned, not raised."""
    try:
        model, _, seconds = model_for(recipe)
        times = np.asarray(model.times, dtype=float).ravel()
        has_sens = SENSITIVITIES in model.capabilities
        output = model.output
    except Exception as err:  # noqa: BLE001 - reported as one error in the driver
        return {"error": f"{type(err).__name__}: {err}", "error_type": type(err).__name__}
    return {"times": times, "sensitivities": has_sens, "build_seconds": seconds, "pid": os.getpid(),
            "host": socket.gethostname(), "parameter_names": tuple(model.parameter_names),
            "output": (output.name, output.units, output.description)}


def evaluate_rows(
    recipe: ModelRecipe, start: int, P: np.ndarray, values: Slot, sens: Slot | None
) -> dict[str, Any]:
    """Evaluate rows ``start, start+1, …`` (``P``) and write them into the store.

    Returns a small status: rows, process, build and run seconds; the rows themselves only
    when the store is not visible here; the failing row and message instead on error.
    """
    status: dict[str, Any] = {"start": start, "stop": start + len(P), "pid": os.getpid(),
                              "host": socket.gethostname(), "build_seconds": 0.0}  # fmt: skip
    row = start
    try:
        model, lock, status["build_seconds"] = model_for(recipe)
        tic = time.perf_counter()
        n_time = values.row_shape[0]
        out = np.empty((len(P), n_time))
        out_sens = np.empty((len(P), *sens.row_shape)) if sens is not None else None
        with lock:
            for i, p in enumerate(np.asarray(P, dtype=float)):
                row = start + i
                if out_sens is not None and sens is not None:
                    evaluation = model.evaluate(p.copy(), sensitivities=True)
                    f, jac = evaluation.values, np.asarray(evaluation.jacobian, dtype=float)
                    if jac.size != out_sens[i].size:
                        raise ParameterError(
                            f"the model returned sensitivities of shape {jac.shape}, expected {sens.row_shape}"
                        )
                    out_sens[i] = jac.reshape(sens.row_shape)
                else:
                    f = model.evaluate(p.copy()).values
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
        if sens is not None and out_sens is not None:
            sens.write(start, out_sens)
    else:
        status["values"] = out
        status["sensitivities"] = out_sens
    return status


# ------------------------------------------------------------------------ the driver


def map_task(function: Any, index: int, item: Any) -> dict[str, Any]:
    """Run ``function(item)`` in a worker; errors come back as a status, not raised."""
    try:
        return {"index": index, "value": function(item)}
    except Exception as err:  # noqa: BLE001 - reported as one error in the driver
        return {"index": index, "error": f"{type(err).__name__}: {err}", "error_type": type(err).__name__}
