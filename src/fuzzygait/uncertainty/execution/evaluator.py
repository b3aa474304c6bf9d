"""The engine's one ``Evaluator``: serial, a local Dask process pool, or a Dask scheduler.

    with Evaluator(workers=2) as evaluator:                 # local pool of 2 processes
        outputs = evaluator.map(task, items)                # any picklable function, in order
        batch = evaluator.batch(recipe)                     # parameter rows of a model
        trajectories = batch(P)                             # (k, n_time)
        model = evaluator.model(recipe)                     # a FuzzyModel evaluated on the pool

    Evaluator(scheduler="tcp://10.0.0.5:8786")              # an existing cluster

* **No set-up.** ``workers=1`` (the default) runs everything in this process through the
  *same* task functions. Otherwise a local Dask cluster of ``workers`` single-threaded
  processes is started on first use, reused by every later call and shut down by
  :meth:`Evaluator.close`, the ``with`` block, or at interpreter exit. ``scheduler`` may
  be the address of a running scheduler or a ``distributed.Client`` you already have.
* **Recipes, not models** for parameter rows (:mod:`.workers`): each process builds the
  model once from a small recipe.
* **Results through a memory-mapped store.** Each row task writes its rows at their
  byte offset in a ``.npy`` file and returns a small status, so trajectories never travel
  through the scheduler; rows come back in input order whatever the completion order. A
  worker that cannot see the store (a remote machine without a shared file system)
  returns its rows with the status instead.
* **Deterministic.** Each row or item is computed independently by the same function, so
  1 worker and N workers give bit-identical results, as long as the processes use the
  same BLAS threading (the local cluster's workers run with one BLAS thread; set the
  same in the driver for the serial path — the test suite does).
* **One error.** A failing row or item is one :class:`ParallelEvaluationError` naming it
  and the original error type and message — no remote traceback. An unreachable
  scheduler address is one such error too.
"""

from __future__ import annotations

import logging
import os
import shutil
import sys
import tempfile
import threading
import uuid
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.execution.batches import EvaluatedModel, RecipeBatch
from fuzzygait.uncertainty.execution.errors import ParallelEvaluationError
from fuzzygait.uncertainty.execution.teardown import (
    CLOSE_TIMEOUT,
    allow_threaded_fork,
    clear_pool_variable,
    interrupts_held,
    new_loop,
    pre_spawn_environ,
    release_at_exit,
    start_loop,
    start_method,
    started_clusters,
    tear_down,
)
from fuzzygait.uncertainty.execution.workers import (
    WORKER_ENV,
    WORKER_PRELOAD,
    WORKER_SETTINGS,
    ModelRecipe,
    map_task,
)

T = TypeVar("T")
R = TypeVar("R")


#: Prefix of an evaluator's temporary directory (``fuzzygait-parallel-<pid>-<random>``
#: in the system's temporary folder; the Dask workers' scratch space is inside it).
TMPDIR_PREFIX = "fuzzygait-parallel-"

@dataclass(eq=False)
class _Resources:
    """What an evaluator owns and must release (kept apart so ``weakref.finalize`` does not
    hold the evaluator alive)."""

    client: Any = None
    cluster: Any = None
    loop: Any = None  # the local cluster's event loop (teardown.start_loop), a distributed LoopRunner
    owns_client: bool = False
    closing: bool = False  # released (or being released): its loop's late error reports are dropped
    token: str | None = None  # marks the local cluster's worker processes (teardown.POOL_VARIABLE)
    settings: Any = None  # the Dask settings of the local cluster's start, while in force
    tmpdir: str | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)

    def make_tmpdir(self) -> str:
        """The temporary directory (created on first call; the caller holds ``lock``)."""
        if self.tmpdir is None:
            remove_stale_tmpdirs()
            self.tmpdir = tempfile.mkdtemp(prefix=f"{TMPDIR_PREFIX}{os.getpid()}-")
        return self.tmpdir

    def release(self, interrupted: bool = False) -> None:
        """Close the client and the cluster, kill any process of the cluster left (a
        worker, one still starting, or a process a worker started) and remove the
        temporary directory; ``interrupted`` (or after :func:`stop_quickly`): the workers
        are frozen and killed at once, their running tasks abandoned.  No process of the
        cluster is running when this returns (:func:`.teardown.tear_down`)."""
        with self.lock, interrupts_held():  # a Ctrl-C now is raised once all is released
            client, cluster, loop, tmpdir = self.client, self.cluster, self.loop, self.tmpdir
            self.client = self.cluster = self.loop = self.tmpdir = None
            self.closing = cluster is not None or self.closing
            _LIVE.discard(self)

            def close() -> None:
                for owned, thing in ((self.owns_client, client), (True, cluster)):
                    if thing is not None and owned:
                        try:
                            thing.close(timeout=CLOSE_TIMEOUT)
                        except Exception:  # noqa: BLE001 - best effort at shutdown
                            pass

            try:
                tear_down(cluster, self.token, loop, close, quickly=_QUICKLY.is_set() or interrupted)
            finally:  # even when the close fails: no file left
                self.restore_settings()
                clear_pool_variable()
                if tmpdir is not None:
                    shutil.rmtree(tmpdir, ignore_errors=True)

    def restore_settings(self) -> None:
        """End the Dask settings of the cluster's start (if still in force)."""
        settings, self.settings = self.settings, None
        if settings is not None:
            settings.__exit__(None, None, None)


#: Every evaluator's resources while it holds a cluster or a temporary directory.
_LIVE: set[_Resources] = set()


def _release_live() -> None:
    """Release every live evaluator (at exit: their workers never see SIGTERM)."""
    for res in list(_LIVE):
        res.release(interrupted=True)


#: Set by :func:`stop_quickly`: every evaluator closing from now on stops its workers at once.
_QUICKLY = threading.Event()


def stop_quickly() -> None:
    """From now on, an evaluator closing does not wait for its workers' running tasks (the
    command was interrupted: they are abandoned anyway), and Dask logs nothing in this
    process below CRITICAL (its reports of connections closed by the shutdown)."""
    _QUICKLY.set()
    logging.getLogger("distributed").setLevel(logging.CRITICAL)


def remove_temporary_directories() -> list[str]:
    """Remove the temporary directories of every live evaluator of this process without
    shutting anything down (the last resort of an interrupted command whose clean
    shutdown takes too long; its processes are killed separately). Returns them."""
    removed = []
    for res in list(_LIVE):
        if res.tmpdir is not None:
            shutil.rmtree(res.tmpdir, ignore_errors=True)
            removed.append(res.tmpdir)
    return removed


def remove_stale_tmpdirs(folder: str | None = None) -> list[str]:
    """Remove the temporary directories (``fuzzygait-parallel-<pid>-*``) that processes no
    longer running left behind (e.g. killed with SIGKILL) in ``folder`` (default: the
    system's temporary folder). Returns the removed paths."""
    removed = []
    root = Path(folder or tempfile.gettempdir())
    for path in root.glob(f"{TMPDIR_PREFIX}*-*"):
        pid = path.name.removeprefix(TMPDIR_PREFIX).split("-", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid() or _running(int(pid)):
            continue
        shutil.rmtree(path, ignore_errors=True)
        removed.append(str(path))
    return removed


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. another user's process
        return True
    return True


class _AbandonedWaits(logging.Filter):
    """Drops asyncio's "Task exception was never retrieved" reports of the client's
    ``AllExit``: the waits of a gather abandoned by an interrupt, ended by the close."""

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        return not (error is not None and type(error).__name__ == "AllExit")


_ABANDONED_WAITS = _AbandonedWaits()


def _script_hint() -> str:
    """Advice for the commonest reason a local pool does not start from a script: its
    worker processes are started by re-importing the script (``spawn``), and a script that
    runs its analysis at top level starts it again in every worker, which Python stops.
    Empty when the program is not a plain script (the ``fuzzygait`` command, a notebook),
    and when the workers are forked copies of this process, which import nothing again."""
    if start_method() == "fork":
        return ""
    main = sys.modules.get("__main__")
    guard = "`if __name__ == \"__main__\":`"
    script = sys.modules.get("__mp_main__")  # the same module as __main__, except in a spawned process
    if script is not None and script is not main:  # a spawned worker, importing the script
        return f" (this is a worker process re-importing the script: put the script's top-level code under {guard}, " \
               "or run with workers=1)"
    path = getattr(main, "__file__", None)
    spec = getattr(main, "__spec__", None)
    if not path or (spec is not None and spec.name.startswith("fuzzygait")):
        return ""
    return (f" (if the script {os.path.basename(path)} starts this run at its top level, put that code under {guard}: "
            "the workers re-import the script; or run with workers=1)")


class Evaluator:
    """Where the engine's work runs (see the module docstring).

    Args:
        workers: processes of the local pool (1, the default: serial in this process).
            Ignored with ``scheduler``.
        scheduler: None, the address of a running Dask scheduler (``"tcp://host:8786"``),
            or a ``distributed.Client``.
        connect_timeout: seconds to wait for a scheduler address to answer.
    """

    def __init__(self, workers: int = 1, scheduler: str | Any | None = None, connect_timeout: float = 10.0) -> None:
        if isinstance(workers, bool) or int(workers) != workers or workers < 1:
            raise ParameterError(f"workers must be a positive integer; got {workers}")
        self.workers = int(workers)
        self.scheduler = scheduler
        self.connect_timeout = float(connect_timeout)
        self._resources = _Resources()
        self._finalizer = weakref.finalize(self, self._resources.release)

    def __repr__(self) -> str:
        where = f"scheduler={self.scheduler!r}" if self.scheduler is not None else f"workers={self.workers}"
        return f"Evaluator({where})"

    # -- life cycle -----------------------------------------------------------------------
    @property
    def serial(self) -> bool:
        """Whether work runs in this process (no scheduler and one worker)."""
        return self.scheduler is None and self.workers == 1

    @property
    def client(self) -> Any:
        """The ``distributed.Client`` (the local cluster is started, or the scheduler
        connected, on first use); None when serial."""
        if self.serial:
            return None
        res = self._resources
        with res.lock:
            if res.client is None:
                self._connect(res)
            return res.client

    def _connect(self, res: _Resources) -> None:
        import dask
        from distributed import Client, LocalCluster
        from distributed.deploy.spec import SpecCluster

        logging.getLogger("asyncio").addFilter(_ABANDONED_WAITS)  # once: a filter is added only once
        if self.scheduler is None:
            _LIVE.add(res)
            scratch = os.path.join(res.make_tmpdir(), "dask")  # removed with the evaluator's directory
            before = {id(cluster) for cluster in list(SpecCluster._instances)}
            try:
                # the cluster's own event loop, in a thread that SIGINT and SIGTERM never reach:
                # the worker processes it starts inherit that (teardown.start_loop)
                res.closing, res.loop, res.token = False, new_loop(), uuid.uuid4().hex
                start_loop(res.loop, quiet=lambda: res.closing or _QUICKLY.is_set())
                release_at_exit(_release_live)
                # in force until the cluster has started or its loop is stopped (release): its nannies,
                # made on the loop, read them, also after an interrupt took this thread out of here
                clear_pool_variable()  # a former cluster's token must not mark this one's workers
                method = start_method()
                if method == "fork":
                    allow_threaded_fork()
                res.settings = dask.config.set({"distributed.nanny.pre-spawn-environ": pre_spawn_environ(res.token),
                                                "distributed.worker.multiprocessing-method": method,
                                                "temporary-directory": scratch,  # the scheduler's scratch too
                                                **WORKER_SETTINGS})  # fmt: skip
                cluster = LocalCluster(
                    n_workers=self.workers, threads_per_worker=1, processes=True, loop=res.loop.loop,
                    silence_logs=logging.ERROR, env=dict(WORKER_ENV), dashboard_address=None,
                    local_directory=scratch, preload=[WORKER_PRELOAD],
                    # no dashboard; the scheduler's health endpoint on a free local port
                    scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
                )  # fmt: skip
                res.restore_settings()
                clear_pool_variable()
            except BaseException as err:
                # a half-started cluster is the evaluator's: an interrupt's release closes it
                res.cluster = next(iter(started_clusters(before)), None)
                if not isinstance(err, Exception):
                    raise
                cut, res.cluster, loop, res.loop = res.cluster, None, res.loop, None
                tear_down(cut, res.token, loop, lambda: cut and cut.close(timeout=CLOSE_TIMEOUT), quickly=True)
                res.restore_settings()
                raise ParallelEvaluationError(f"cannot start a local Dask cluster: {err}{_script_hint()}") from None
            res.cluster = cluster
            res.client, res.owns_client = Client(cluster, set_as_default=False), True
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

    def n_workers(self) -> int:
        """Worker processes available (1 when serial)."""
        if self.serial:
            return 1
        return max(1, len(self.client.scheduler_info().get("workers", {})) or self.workers)

    def tmpdir(self) -> Path:
        """A private temporary directory, removed by :meth:`close`."""
        res = self._resources
        with res.lock:
            _LIVE.add(res)
            return Path(res.make_tmpdir())

    def close(self) -> None:
        """Shut down the local cluster (or disconnect from the scheduler) and remove the
        temporary store; a worker process still running after :data:`CLOSE_TIMEOUT`
        seconds is killed. The evaluator starts afresh if used again."""
        self._resources.release()

    def __enter__(self) -> Evaluator:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        self._resources.release(interrupted=exc_type is not None and issubclass(exc_type, KeyboardInterrupt))

    # -- generic tasks --------------------------------------------------------------------
    def submit_all(self, function: Callable[..., Any], argument_lists: Sequence[tuple[Any, ...]],
                   label: str = "task", progress: Callable[[int, int], None] | None = None) -> list[Any]:  # fmt: skip
        """``[function(*args) for args in argument_lists]``, in order, on the workers;
        ``progress(done, total)`` as each one finishes."""
        client = self.client
        if client is None:
            results = []
            for i, args in enumerate(argument_lists):
                results.append(function(*args))
                if progress is not None:
                    progress(i + 1, len(argument_lists))
            return results
        token = uuid.uuid4().hex[:12]
        futures = [client.submit(function, *args, key=f"fuzzygait-{label}-{token}-{i}", pure=False)
                   for i, args in enumerate(argument_lists)]  # fmt: skip
        try:
            if progress is not None:
                from distributed import as_completed

                for done, _ in enumerate(as_completed(futures, loop=client.loop), start=1):
                    progress(done, len(futures))
            return list(client.gather(futures))
        except Exception as err:  # noqa: BLE001 - worker death, lost connection
            raise ParallelEvaluationError(
                f"the Dask cluster failed while evaluating ({type(err).__name__}: {err})"
            ) from None
        finally:
            for future in futures:
                future.release()

    def map(self, function: Callable[[T], R], items: Sequence[T],
            progress: Callable[[int, int], None] | None = None) -> list[R]:  # fmt: skip
        """``[function(item) for item in items]`` in input order; ``function`` and the items
        must be picklable for a pool. A failing item is one
        :class:`ParallelEvaluationError` naming its index."""
        if self.serial:
            statuses = []
            for i, item in enumerate(items):
                statuses.append(map_task(function, i, item))
                if progress is not None:
                    progress(i + 1, len(items))
        else:
            statuses = self.submit_all(map_task, [(function, i, item) for i, item in enumerate(items)], "map",
                                       progress)  # fmt: skip
        failed = [s for s in statuses if "error" in s]
        if failed:
            first = failed[0]
            raise ParallelEvaluationError(f"item {first['index']} failed: {first['error']}", row=int(first["index"]),
                                          error_type=first["error_type"])  # fmt: skip
        return [s["value"] for s in statuses]

    # -- models -----------------------------------------------------------------------------
    def batch(self, recipe: ModelRecipe, *, sensitivities: bool = False,
              store: str | os.PathLike[str] | None = None, chunk: int | None = 1) -> RecipeBatch:  # fmt: skip
        """A callable ``P (k, n_p) -> (k, n_time)`` (and ``(k, n_time, n_p)``
        sensitivities) evaluating ``recipe``'s model on this evaluator's workers."""
        return RecipeBatch(self, recipe, sensitivities=sensitivities, store=store, chunk=chunk)

    def model(self, recipe: ModelRecipe, *, sensitivities: bool = False, chunk: int | None = 1) -> EvaluatedModel:
        """``recipe``'s model as a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`
        whose forward simulations run on this evaluator's workers."""
        return EvaluatedModel(self.batch(recipe, sensitivities=sensitivities, chunk=chunk))
