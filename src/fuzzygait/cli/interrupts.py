"""Clean interruption of a command by SIGINT (Ctrl-C) or SIGTERM, and no process left.

A signal can come at any moment of the ``fuzzygait`` process's life; what it does
depends on that moment:

* **Start-up** (the command's modules loading, its arguments being parsed: nothing is
  running nor written yet): the command prints the one line (:func:`interrupt_line`) and
  exits at once with ``128 + signal``: 130 for SIGINT, 143 for SIGTERM
  (:func:`prepare_command`).
* **While the command works**, both signals raise :class:`Interrupted` (a
  ``KeyboardInterrupt``) in the main thread (:class:`InterruptGuard`), so every
  ``with``/``finally`` block on the way out runs: the evaluators shut their Dask clusters
  and worker processes down and remove their temporary directories, atomic writers
  remove their half-written files, staging folders go.  The command then prints the one
  line and exits with ``128 + signal``.  Further signals while that clean-up runs are
  ignored; should it take longer than :data:`GRACE_SECONDS`, the command kills its
  remaining child processes, removes the evaluators' temporary directories and exits at
  once.  An evaluator releasing its cluster holds the interrupt until it is done
  (:func:`fuzzygait.uncertainty.execution.teardown.interrupts_held`); one arriving while
  Python runs a finalizer, where an exception cannot propagate, is delivered again once
  that is done; an error raised after it (a C extension being imported turns it into an
  ``ImportError``) is reported as the interrupt (:func:`received`).
* **Ending** (the work is done, the exit code decided; Python runs its exit handlers):
  a signal no longer interrupts anything, so it does not turn a finished command into a
  failed one, nor print a traceback from an exit handler; it only makes sure the end
  comes within :data:`GRACE_SECONDS`.

The worker processes of a local cluster never receive SIGINT nor SIGTERM
(:mod:`fuzzygait.uncertainty.execution.teardown`): a Ctrl-C reaches the whole process
group, and only the command decides what happens.

No process the command started outlives it, whether it succeeds, fails or is
interrupted: the evaluators stop their workers and whatever those started; the command
is a child subreaper (Linux), so a process orphaned on the way (a compiler a killed
worker had started) becomes the command's child; and at exit, after Python's own exit
handlers, the multiprocessing resource tracker is stopped and waited for, and any child
still running is killed and reaped (:func:`sweep_children`).
"""

from __future__ import annotations

import atexit
import importlib
import os
import signal
import sys
import threading
import time
from types import FrameType, TracebackType
from typing import Any

#: Seconds the clean-up after a signal may take before the command kills its children
#: and exits anyway.
GRACE_SECONDS = 30.0
#: The signals that interrupt a command.
SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: Seconds the end of a command waits for the resource tracker and killed children.
SWEEP_SECONDS = 5.0
#: prctl(2)'s PR_SET_CHILD_SUBREAPER (Linux).
_PR_SET_CHILD_SUBREAPER = 36


class Interrupted(KeyboardInterrupt):
    """A command was interrupted by ``signum`` (SIGINT or SIGTERM)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = int(signum)


def exit_code(signum: int) -> int:
    """The exit code of a command interrupted by ``signum``: ``128 + signum`` (the shell's
    convention: 130 for SIGINT, 143 for SIGTERM)."""
    return 128 + int(signum)


def interrupt_line(signum: int) -> str:
    """The one line an interrupted command prints on standard error."""
    return (f"fuzzygait: interrupted ({signal.Signals(signum).name}); partial output and temporary files "
            "removed, results completed before are kept")  # fmt: skip


def is_the_command() -> bool:
    """Whether this process is the ``fuzzygait`` command itself (its console script, or
    ``python -m fuzzygait``) and this is its main thread; not a program or test importing
    the package, nor a worker process of a pool (which imports the command's script)."""
    if threading.current_thread() is not threading.main_thread() or "--multiprocessing-fork" in sys.argv:
        return False
    main = sys.modules.get("__main__")
    spec = getattr(main, "__spec__", None)
    if spec is not None:
        return bool(spec.name == "fuzzygait.__main__")
    path = getattr(main, "__file__", None)
    return bool(path) and os.path.splitext(os.path.basename(str(path)))[0] in ("fuzzygait", "fuzzygait-script")


_prepared: list[bool] = []


def prepare_command() -> None:
    """Set up the ``fuzzygait`` process (nothing elsewhere, see :func:`is_the_command`;
    once): a signal during start-up ends it at once with the one line; orphaned
    descendants become its children (:func:`adopt_orphans`); at exit, after every other
    exit handler, :func:`sweep_children` runs."""
    if _prepared or not is_the_command():
        return
    _prepared.append(True)
    for signum in SIGNALS:
        signal.signal(signum, _stop_at_start_up)
    adopt_orphans()
    atexit.register(sweep_children)  # registered first: run last


def _stop_at_start_up(signum: int, frame: FrameType | None) -> None:
    """Nothing runs nor is written yet: the line, and exit."""
    _write_line(interrupt_line(signum))
    os._exit(exit_code(signum))


def _write_line(line: str) -> None:
    try:
        sys.stderr.flush()
    except Exception:  # noqa: BLE001 - a closed stream: the line goes straight to the descriptor
        pass
    try:
        os.write(2, (line + "\n").encode())
    except OSError:
        pass


def adopt_orphans() -> bool:
    """Make this process a child subreaper (Linux): a descendant whose parent dies (a
    compiler started by a worker that was killed) becomes this process's child instead of
    init's, so it is still found, killed and reaped at the end.  False where unsupported."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        return bool(libc.prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)
    except Exception:  # noqa: BLE001 - best effort: the evaluators kill their workers' processes anyway
        return False


class InterruptGuard:
    """While active (``with InterruptGuard() as guard:``), SIGINT and SIGTERM raise
    :class:`Interrupted` once; :attr:`signum` is the first signal received (None: none).
    The previous handlers are restored on exit; ``ending``: the ending handlers are
    installed instead (the process is about to exit; see the module docstring).  Outside
    the main thread it does nothing (Python delivers signals to the main thread only)."""

    def __init__(self, grace_seconds: float = GRACE_SECONDS, ending: bool = False) -> None:
        self.grace_seconds = float(grace_seconds)
        self.ending = bool(ending)
        self.signum: int | None = None
        self._previous: dict[int, object] = {}
        self._timer: threading.Timer | None = None
        self._unraisable_hook: Any = None
        self._in_hook = False

    def __enter__(self) -> InterruptGuard:
        if threading.current_thread() is threading.main_thread():
            for signum in SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
            _ACTIVE.append(self)
            self._unraisable_hook = sys.unraisablehook
            sys.unraisablehook = self._unraisable
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        if self in _ACTIVE:
            _ACTIVE.remove(self)
        if self._unraisable_hook is not None and sys.unraisablehook == self._unraisable:
            sys.unraisablehook = self._unraisable_hook
        self._unraisable_hook = None
        ending = _Ending(self.grace_seconds, self._timer) if self.ending and self._previous else None
        for signum, handler in self._previous.items():
            signal.signal(signum, ending or handler)  # type: ignore[arg-type]
        self._previous.clear()
        if self._timer is not None and ending is None:  # ending: the hard stop still covers the exit
            self._timer.cancel()

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self._in_hook:  # not here either (an exception in the hook is printed too): a moment later
            _deliver_again(signum)
            return
        if self.signum is not None:
            return  # the clean-up of the first signal is running: let it finish
        self.signum = signum
        evaluator = sys.modules.get("fuzzygait.uncertainty.execution.evaluator")
        if evaluator is not None:  # the pools need not wait for the tasks they run
            evaluator.stop_quickly()
        self._timer = _start_timer(self.grace_seconds, signum)
        teardown = sys.modules.get("fuzzygait.uncertainty.execution.teardown")
        if teardown is not None and teardown.holding_interrupts():  # an evaluator releasing its cluster
            teardown.hold(Interrupted(signum))
            return
        raise Interrupted(signum)

    def _unraisable(self, unraisable: Any) -> None:
        """``sys.unraisablehook`` while active: the signal came while Python ran code whose
        exceptions cannot propagate (a ``weakref.finalize`` callback, a ``__del__``, the
        garbage collector's), where :class:`Interrupted` would only be printed ("Exception
        ignored in ...") and lost.  Deliver the signal again instead: it is raised at the
        next ordinary point of the main thread.  Anything else goes to the usual hook."""
        self._in_hook = True
        try:
            error = getattr(unraisable, "exc_value", None)
            if isinstance(error, Interrupted) and error.signum == self.signum:
                if self._timer is not None:
                    self._timer.cancel()
                self.signum = self._timer = None  # the next delivery is handled as the first
                _deliver_again(error.signum)
            elif self._unraisable_hook is not None:
                self._unraisable_hook(unraisable)
        finally:
            self._in_hook = False


def _deliver_again(signum: int, delay: float = 0.01) -> None:
    """Send ``signum`` to this process again ``delay`` seconds from now (from a thread)."""

    def send() -> None:
        time.sleep(delay)
        os.kill(os.getpid(), signum)

    threading.Thread(target=send, daemon=True).start()


#: The active guards (innermost last).
_ACTIVE: list[InterruptGuard] = []


def received() -> int | None:
    """The signal the active guard has received (None: none, or no guard active).  An
    exception raised after it is the interrupt's doing, whatever its type (a C
    extension being imported turns the KeyboardInterrupt into ``ImportError:
    initialization failed``): the command reports the interrupt, not that error."""
    return _ACTIVE[-1].signum if _ACTIVE else None


class _Ending:
    """The handler while the process ends: a signal arms the hard stop, nothing more."""

    def __init__(self, grace_seconds: float, timer: threading.Timer | None) -> None:
        self.grace_seconds = grace_seconds
        self.timer = timer  # armed by a signal while the command worked: it still runs

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        if self.timer is None:
            self.timer = _start_timer(self.grace_seconds, signum)


def _start_timer(seconds: float, signum: int) -> threading.Timer:
    timer = threading.Timer(seconds, hard_stop, args=(signum, seconds))
    timer.daemon = True
    timer.start()
    return timer


def hard_stop(signum: int, seconds: float) -> None:
    """The clean-up after ``signum`` took over ``seconds``: kill the children, remove the
    evaluators' temporary directories, print the line and exit now."""
    kill_children()
    from fuzzygait.uncertainty.execution.evaluator import remove_temporary_directories

    remove_temporary_directories()
    _write_line(interrupt_line(signum) + f" (clean-up took over {seconds:g} s: child processes killed)")
    os._exit(exit_code(signum))


def kill_children(timeout: float = SWEEP_SECONDS) -> list[int]:
    """SIGKILL every descendant process of this one and reap those that are its children;
    returns their ids."""
    try:
        psutil: Any = importlib.import_module("psutil")  # untyped; it comes with distributed
    except ImportError:  # pragma: no cover
        return []
    children = psutil.Process().children(recursive=True)
    for child in children:
        try:
            child.kill()
        except psutil.Error:
            pass
    psutil.wait_procs(children, timeout=timeout)
    return [child.pid for child in children]


def stop_resource_tracker(timeout: float = SWEEP_SECONDS) -> bool:
    """Stop multiprocessing's resource tracker, if this process started one, and wait for
    it (killed after ``timeout``), so that it does not outlive the command.  Call it once
    nothing else is left that registers resources: at exit, after multiprocessing's own
    exit handler has unlinked them.  Returns whether there was one."""
    module = sys.modules.get("multiprocessing.resource_tracker")
    tracker = getattr(module, "_resource_tracker", None)
    fd, pid = getattr(tracker, "_fd", None), getattr(tracker, "_pid", None)
    if tracker is None or fd is None or pid is None:
        return False
    tracker._fd = tracker._pid = None
    try:
        os.close(fd)  # its end of the pipe: the tracker reads end-of-file and exits
    except OSError:
        pass
    deadline = time.monotonic() + timeout
    while True:
        try:
            done, _ = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:
            return True
        if done:
            return True
        if time.monotonic() > deadline:
            try:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
            except OSError:
                pass
            return True
        time.sleep(0.005)


def sweep_children() -> None:
    """The last exit handler of the command: multiprocessing's exit handler (the pools'
    leftover children stopped, their shared semaphores unlinked; a no-op if it has run),
    then the resource tracker stopped and waited for, then every child still running
    killed and reaped.  The command's process group is empty when it has exited.  Then
    SIGINT and SIGTERM are ignored for the last moments of the interpreter's
    finalization, which would otherwise reset them to their default action (a signal
    then killed the command, its work done, without its exit code)."""
    try:
        util = sys.modules.get("multiprocessing.util")
        if util is not None:
            util._exit_function()
        stop_resource_tracker()
        kill_children()
    except Exception:  # noqa: BLE001 - the last exit handler: nothing may escape from it
        pass
    if threading.current_thread() is threading.main_thread():
        for signum in SIGNALS:
            signal.signal(signum, signal.SIG_IGN)
