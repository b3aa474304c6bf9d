"""Starting and tearing down a local Dask cluster's processes so that no signal meant for
the command reaches them, nothing they print reaches the user, and nothing of them
outlives the evaluator.

* **Workers born deaf to SIGINT and SIGTERM.**  A Ctrl-C in a terminal goes to every
  process of the foreground process group, and the worker processes are in it (they
  should be: ``ps -g PGID`` after the command ended is how one checks none is left).  A
  worker that received it while importing (before Dask runs its preload,
  :func:`~fuzzygait.uncertainty.execution.workers.dask_setup`) printed a
  ``KeyboardInterrupt`` traceback and its nanny "failed to start".  The cluster's event
  loop therefore runs in a thread started with both signals blocked
  (:func:`start_loop`): the processes the cluster starts from that loop inherit the
  blocked mask through ``fork``/``exec``, so they never see either signal, from their
  first instruction on, nor do the processes they start; their parent stops them.
* **Forked, on Linux** (:func:`start_method`): a worker is a copy of this process, with
  its imports and compiled models, instead of a new interpreter importing them again.
* **Known from birth**: each worker is given :data:`POOL_VARIABLE` set to its cluster's
  token in its environment (:func:`pre_spawn_environ`), which its nanny keeps from its
  making on, so that a worker still starting — of a cluster cut short while starting,
  whose close closes nothing — is found as surely as a running one
  (:func:`worker_processes`).  The nanny's record is read, not the worker's environment
  as the system shows it: a forked worker's is this process's at its own start.
* **Stopped at once when interrupted** (:func:`tear_down`): the worker processes and
  everything they started (a C compiler building a simulator, a C3D reader child) are
  frozen and listed, so that none can escape as an orphan, then killed, then the nannies
  and the cluster closed; after a plain close whatever is left is killed.  Either way
  the killed processes are waited for: none is left running when the evaluator's
  close returns.  At interpreter exit, any worker still running is killed before
  multiprocessing would wait for it for ever (:func:`release_at_exit`).
* **Quiet**: the cluster's loop drops its reports of errors nobody waited for once the
  teardown has begun (a start or a close cut short: "Task exception was never
  retrieved ... Nanny failed to start").
* **Forgotten by distributed** (:func:`forget_cluster`) once closed or killed, so that its
  close at interpreter exit does not run a second time.
* **Not cut short**: an interrupt arriving while an evaluator releases its cluster is
  held until the release is complete (:func:`interrupts_held`; the ``fuzzygait``
  command's handler honours it), so that a Ctrl-C at the end of a run cannot leave a
  worker or the temporary directory behind.

Used by :mod:`fuzzygait.uncertainty.execution.evaluator` when an evaluator closes, is
interrupted or fails to start its cluster.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from typing import Any

#: Seconds the close of a cluster may take before its workers are killed.
CLOSE_TIMEOUT = 10.0
#: Seconds a worker is given to stop by itself when its evaluator stops quickly.
QUICK_STOP_SECONDS = 0.5
#: Seconds to wait for killed processes to be gone.
KILL_WAIT_SECONDS = 5.0
#: The signals the local cluster's processes never receive (the command's to handle).
BLOCKED = frozenset({signal.SIGINT, signal.SIGTERM})


_holding = 0
_held: list[BaseException] = []


@contextlib.contextmanager
def interrupts_held() -> Iterator[None]:
    """While inside (in the main thread), an interrupt is held, not raised, by a signal
    handler that honours it (:func:`holding_interrupts`, :func:`hold`); the outermost
    block raises the held exception as it ends.  Elsewhere it does nothing."""
    global _holding
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _holding += 1
    try:
        yield
    finally:
        _holding -= 1
        if _holding == 0 and _held:
            error = _held[0]
            _held.clear()
            raise error


def holding_interrupts() -> bool:
    """Whether the main thread is inside :func:`interrupts_held`."""
    return _holding > 0


def hold(error: BaseException) -> None:
    """Hold ``error`` (an interrupt) until the outermost :func:`interrupts_held` ends."""
    _held.append(error)


def _psutil() -> Any:
    """psutil (untyped; it comes with distributed), or None."""
    try:
        return importlib.import_module("psutil")
    except ImportError:  # pragma: no cover - a dependency of distributed
        return None


@contextlib.contextmanager
def signals_blocked() -> Iterator[None]:
    """SIGINT and SIGTERM blocked in the calling thread while inside (held pending, not
    lost: delivered when the block ends).  A thread started inside inherits the block,
    and so does every process that thread starts."""
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, BLOCKED)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def new_loop() -> Any:
    """A distributed ``LoopRunner`` to start with :func:`start_loop` (separate, so that
    its owner holds it before it starts and can stop it whatever happens next)."""
    from distributed.utils import LoopRunner

    return LoopRunner()


def start_loop(runner: Any, quiet: Callable[[], bool]) -> None:
    """Start ``runner``'s event-loop thread with SIGINT and SIGTERM blocked: the local
    cluster run on that loop starts its worker processes from it, so they inherit the
    block (see the module docstring).  Once ``quiet()`` is true (the cluster is being
    torn down), the loop's reports of errors nobody waited for are dropped: the tasks of
    a start or a close cut short by the teardown ("Task exception was never retrieved
    ... Nanny failed to start", written by asyncio's default handler straight to
    stderr).  Before that they are reported as usual.

    The multiprocessing resource tracker is started first, from the calling thread: the
    thread that starts it has both signals *unblocked* afterwards (CPython blocks them
    around the tracker's start and unblocks them, not restores them), which, in the
    loop's thread, let the workers be born with the terminal's SIGINT again."""
    if os.name == "posix":
        from multiprocessing import resource_tracker

        resource_tracker.ensure_running()
    with signals_blocked():
        runner.start()

    def report(loop: Any, context: dict[str, Any]) -> None:
        if not quiet():
            loop.default_exception_handler(context)

    runner.loop.asyncio_loop.set_exception_handler(report)


def stop_loop(runner: Any) -> None:
    """Stop the event loop of :func:`start_loop` (None: nothing to do)."""
    if runner is None:
        return
    try:
        runner.stop(timeout=CLOSE_TIMEOUT)
    except Exception:  # noqa: BLE001 - best effort at shutdown
        pass


def start_method() -> str:
    """How a local cluster starts its worker processes (Dask's
    ``distributed.worker.multiprocessing-method``): ``fork`` on Linux in place of Dask's
    default ``spawn``; any other setting, and every setting elsewhere, as configured.

    A spawned worker is a new interpreter that imports ``distributed``, numpy, scipy,
    CasADi and the engine's modules again and loads the compiled models: about 2 s of CPU
    per worker, paid on the same two cores as the work.  A forked one is a copy of this
    process, which has them all already.  Measured (``benchmarks/RESULTS.md``, issue 40,
    sixth round): ``fuzzygait uncertainty`` on the sample trial 9.4 → 8.1 s wall; a
    ``fuzzygait report`` of 10 trials on 2 workers 1.41× → 1.63× one.  The answers are
    bit-identical: a worker
    computes with one BLAS thread either way (:func:`~.workers.dask_setup`).  The copy is
    made while this process's other threads run; what a worker uses of this process's
    state with a lock another thread may hold at that moment (the model cache, the
    standard streams and the logging handlers' streams) is made afresh in the copy
    (:func:`~.workers.fresh_after_fork`), and a worker never uses the rest (the scheduler,
    the client).  Elsewhere ``spawn`` is kept: Windows has no ``fork``, and
    macOS's system libraries are not safe to use in a forked copy."""
    import dask

    configured = str(dask.config.get("distributed.worker.multiprocessing-method", default="spawn"))
    if configured != "spawn" or not sys.platform.startswith("linux"):
        return configured
    return "fork"


def allow_threaded_fork() -> None:
    """Silence Python's (≥ 3.12) warning at every fork of a process with threads, for a
    local cluster whose workers are forked: :func:`start_method` says why that is safe."""
    warnings.filterwarnings("ignore", message=r"This process \(pid=\d+\) is multi-threaded, use of fork\(\)",
                            category=DeprecationWarning)  # fmt: skip


#: The environment variable marking a local cluster's worker processes: its value is the
#: cluster's token, set by Dask in the environment each worker starts with.
POOL_VARIABLE = "FUZZYGAIT_POOL"


def pre_spawn_environ(token: str) -> dict[str, object]:
    """Dask's environment for new worker processes, with :data:`POOL_VARIABLE` set to
    ``token`` (so that a worker is known as the cluster's from the moment it is made,
    :func:`worker_processes`) and without Dask's ``MALLOC_TRIM_THRESHOLD_``.

    Dask sets glibc's trim threshold to 64 KiB in every worker so that memory goes back
    to the system at once; the engine's evaluations allocate and free many mid-sized
    arrays, and with that setting two workers ran the marker-error analysis no faster
    than one plain process (1.9× slower than without it, the extra time mostly system
    time; ``benchmarks/evaluator_overhead.py``). glibc's adaptive default is used instead."""
    import dask

    environ = dict(dask.config.get("distributed.nanny.pre-spawn-environ", default={}) or {})
    environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    environ[POOL_VARIABLE] = token
    return environ


def clear_pool_variable() -> None:
    """Take :data:`POOL_VARIABLE` out of this process's environment.

    A nanny copies its ``pre-spawn-environ`` into ``os.environ`` before it starts a
    worker, and reads that setting with ``os.environ`` taking precedence: left there, the
    token of a process's first cluster marked the workers of every later one (which were
    then not found by their own token when interrupted while starting), and any process
    this one starts later (a browser for a PDF) looked like a worker."""
    os.environ.pop(POOL_VARIABLE, None)


_AT_EXIT: list[Any] = []


def release_at_exit(release: Callable[[], None]) -> None:
    """Run ``release()`` (once per process, however often this is called), then kill
    every worker process of any local cluster still running, at interpreter exit
    *before* multiprocessing's own exit handler, which sends SIGTERM to the daemonic
    child processes still running and joins them without a timeout: a local cluster's
    workers never see SIGTERM (their parent stops them), so one left running would make
    that join wait for ever."""
    if _AT_EXIT:
        return
    from multiprocessing import util

    def at_exit() -> None:
        try:
            release()
        finally:
            kill_processes(_marked_children(None))

    _AT_EXIT.append(util.Finalize(None, at_exit, exitpriority=100))  # run by util._exit_function first


async def close_nannies(nannies: list[Any], timeout: float) -> None:
    import asyncio

    await asyncio.gather(*(nanny.close(timeout=timeout) for nanny in nannies), return_exceptions=True)


def _nannies(cluster: Any) -> list[Any]:
    """A local cluster's nannies: those running, and those still starting (a cluster
    cut short while starting has none running yet, and its close closes none)."""
    found = {id(n): n for n in [*getattr(cluster, "workers", {}).values(), *list(getattr(cluster, "_created", ()))]}
    return list(found.values())


def stop_workers_now(cluster: Any) -> None:
    """Close a local cluster's nannies with a short timeout: a worker busy with a task is
    killed after :data:`QUICK_STOP_SECONDS` instead of the close's usual 4 s; the wait
    here is bounded even for a nanny whose worker is still starting."""
    nannies = _nannies(cluster)
    try:
        cluster.sync(close_nannies, nannies, QUICK_STOP_SECONDS, callback_timeout=2 * QUICK_STOP_SECONDS + 1)
    except Exception:  # noqa: BLE001 - best effort: the close and the kill below follow
        pass


def _marked_nannies(token: str | None) -> list[Any]:
    """The nannies of this process whose worker environment carries :data:`POOL_VARIABLE`
    equal to ``token`` (None: any): every nanny is in ``Nanny._instances`` from its making
    on, whether or not its cluster has listed it, and its ``WorkerProcess`` keeps the
    environment it gives its worker (``env``)."""
    nanny_module = sys.modules.get("distributed.nanny")
    if nanny_module is None:  # no nanny was ever made here
        return []
    marked = []
    for nanny in list(nanny_module.Nanny._instances):
        environ = getattr(getattr(nanny, "process", None), "env", None)
        value = environ.get(POOL_VARIABLE) if isinstance(environ, dict) else None
        if value is not None and (token is None or value == token):
            marked.append(nanny)
    return marked


def _worker_children(nannies: list[Any]) -> list[Any]:
    """The worker processes of ``nannies`` (``psutil`` processes) that are children of this
    process: each nanny's multiprocessing process, whose pid is known as soon as its
    ``fork`` has returned (before distributed's own record of it)."""
    psutil = _psutil()
    if psutil is None:  # pragma: no cover
        return []
    found: dict[int, Any] = {}
    for nanny in nannies:
        process = getattr(getattr(getattr(nanny, "process", None), "process", None), "_process", None)  # AsyncProcess's
        pid = getattr(getattr(process, "_popen", None), "pid", None)
        if not pid or pid in found:
            continue
        try:
            child = psutil.Process(pid)
            if child.ppid() == os.getpid():  # a worker is a child of this process (not a pid reused since)
                found[pid] = child
        except psutil.Error:
            continue
    return list(found.values())


def _marked_children(token: str | None) -> list[Any]:
    """This process's children that are worker processes of the local cluster ``token``
    (None: of any), by the environment their nannies give them (:func:`_marked_nannies`)."""
    return _worker_children(_marked_nannies(token))


def _worker_roots(cluster: Any, token: str | None) -> list[Any]:
    """The worker processes of a local cluster: its nannies' (running or starting) and
    those of every nanny marked with ``token`` (a cluster distributed has not listed)."""
    nannies = {id(n): n for n in [*(_marked_nannies(token) if token else []),
                                  *(_nannies(cluster) if cluster is not None else [])]}  # fmt: skip
    return _worker_children(list(nannies.values()))


def worker_processes(cluster: Any, token: str | None = None, freeze: bool = False) -> list[Any]:
    """The worker processes of a local cluster and all their descendants (``psutil``
    processes); ``token``: the cluster's (:func:`pre_spawn_environ`).  ``freeze``: each
    is stopped (SIGSTOP) as it is found and the search runs until no new one turns up,
    so that the list is complete (a stopped process starts no other) — for a cluster
    about to be killed."""
    psutil = _psutil()
    if psutil is None or (cluster is None and token is None):
        return []
    found: dict[int, Any] = {}
    for _ in range(20):  # a tree of processes forking as it is frozen: settles in a round or two
        new = []
        for root in _worker_roots(cluster, token):
            try:
                tree = [root, *root.children(recursive=True)]
            except psutil.Error:
                tree = [root]
            new += [p for p in tree if p.pid not in found]
        if not new:
            break
        for process in new:
            found[process.pid] = process
            if freeze:
                try:
                    process.suspend()
                except psutil.Error:
                    pass
        if not freeze:
            break
    return list(found.values())


def tear_down(cluster: Any, token: str | None, loop: Any, close: Callable[[], object], quickly: bool) -> None:
    """Close a local cluster (``close()``: its client's and its own close) and stop its
    event loop; no process of the cluster is left running when this returns.

    ``quickly`` (interrupted, or a start that failed): the cluster's processes are
    frozen and listed first, the nannies told not to restart them, and they are killed
    at once; then the close (now quick).  Otherwise the close stops the workers, and
    anything of them left is killed after it.  ``cluster`` None with a ``token``: a
    local cluster interrupted before distributed listed it, whose workers (still being
    started by its loop) are found by the token alone; ``cluster`` and ``token`` None (a
    remote scheduler): only ``close()``.  An interrupt meanwhile is held until the end
    (:func:`interrupts_held`)."""
    with interrupts_held():
        listed = worker_processes(cluster, token, freeze=quickly)
        try:
            if quickly and cluster is not None:
                for nanny in _nannies(cluster):  # a worker dying now is not restarted
                    with contextlib.suppress(Exception):
                        nanny.close_gracefully(reason="fuzzygait-interrupted")
                kill_processes(listed)
                stop_workers_now(cluster)
            close()
        except Exception:  # noqa: BLE001 - best effort: the kill below follows
            pass
        finally:
            stop_loop(loop)  # no process can be started by the cluster any more
            # including any started meanwhile, and those of a cluster interrupted before distributed
            # listed it (``cluster`` None): its token still marks them
            kill_processes(listed + worker_processes(cluster, token))
            if cluster is not None:
                forget_cluster(cluster)


def kill_processes(processes: list[Any]) -> None:
    """SIGKILL ``processes`` (``psutil`` processes; the gone ones are skipped) and wait
    until each is gone: reaped, or a zombie waiting for its parent (a worker's parent is
    this process, whose multiprocessing thread reaps it; an orphan's is init)."""
    psutil = _psutil()
    if psutil is None or not processes:
        return
    for process in processes:
        try:
            process.kill()
        except psutil.Error:
            pass
    deadline = time.monotonic() + KILL_WAIT_SECONDS
    for process in processes:
        while time.monotonic() < deadline:
            try:
                if not process.is_running() or process.status() == psutil.STATUS_ZOMBIE:
                    break
            except psutil.Error:
                break
            time.sleep(0.005)
    _wait_reaped(processes, deadline)


def _wait_reaped(processes: list[Any], deadline: float) -> None:
    """Wait (until ``deadline``) for the dead children of this process among ``processes``
    to be reaped by whoever waits for them (multiprocessing's watch thread of each
    worker), so that none is left behind as a zombie; reap them after that."""
    children = [p for p in processes if _parent_is_me(p)]
    while children and time.monotonic() < deadline:
        children = [p for p in children if os.path.exists(f"/proc/{p.pid}") and _parent_is_me(p)]
        if children:
            time.sleep(0.005)
    for process in children:  # nobody reaped it in time: this process does
        try:
            os.waitpid(process.pid, os.WNOHANG)
        except OSError:
            pass


def _parent_is_me(process: Any) -> bool:
    try:
        return bool(process.ppid() == os.getpid())
    except Exception:  # noqa: BLE001 - gone
        return False


def forget_cluster(cluster: Any) -> None:
    """Take a closed (or killed) local cluster off distributed's list to close at exit,
    whose second close prints a traceback for a worker interrupted while starting."""
    try:
        from distributed.deploy.spec import SpecCluster

        SpecCluster._instances.discard(cluster)
    except Exception:  # noqa: BLE001 - best effort: an older or newer distributed
        pass


def started_clusters(before: set[int]) -> list[Any]:
    """Local clusters created in this process since ``before`` (ids of the clusters then)."""
    from distributed.deploy.spec import SpecCluster

    return [cluster for cluster in list(SpecCluster._instances) if id(cluster) not in before]
