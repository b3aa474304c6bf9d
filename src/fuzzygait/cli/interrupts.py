"""Clean interruption of a command by SIGINT (Ctrl-C) or SIGTERM.

While a command runs, both signals raise :class:`Interrupted` (a ``KeyboardInterrupt``)
in the main thread, so every ``with``/``finally`` block on the way out runs: the
evaluators shut their Dask clusters and worker processes down and remove their temporary
directories, atomic writers remove their half-written files, staging folders go.  The
command then prints one line (:func:`interrupt_line`) and exits with ``128 + signal``:
130 for SIGINT, 143 for SIGTERM.  Further signals while that clean-up runs are ignored;
should it take longer than :data:`GRACE_SECONDS`, the command kills its remaining child
processes, removes the evaluators' temporary directories and exits at once.

The worker processes of a local cluster ignore SIGINT
(:func:`fuzzygait.uncertainty.execution.workers.dask_setup`): a Ctrl-C reaches the whole
process group, and only the command decides what happens.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading
from types import FrameType, TracebackType
from typing import Any

#: Seconds the clean-up after a signal may take before the command kills its children
#: and exits anyway.
GRACE_SECONDS = 30.0
#: The signals that interrupt a command.
SIGNALS = (signal.SIGINT, signal.SIGTERM)


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


class InterruptGuard:
    """While active (``with InterruptGuard() as guard:``), SIGINT and SIGTERM raise
    :class:`Interrupted` once; :attr:`signum` is the first signal received (None: none).
    The previous handlers are restored on exit.  Outside the main thread it does nothing
    (Python delivers signals to the main thread only)."""

    def __init__(self, grace_seconds: float = GRACE_SECONDS) -> None:
        self.grace_seconds = float(grace_seconds)
        self.signum: int | None = None
        self._previous: dict[int, object] = {}
        self._timer: threading.Timer | None = None

    def __enter__(self) -> InterruptGuard:
        if threading.current_thread() is threading.main_thread():
            for signum in SIGNALS:
                self._previous[signum] = signal.signal(signum, self._handle)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:  # fmt: skip
        if self._timer is not None:
            self._timer.cancel()
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        self._previous.clear()

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is not None:
            return  # the clean-up of the first signal is running: let it finish
        self.signum = signum
        evaluator = sys.modules.get("fuzzygait.uncertainty.execution.evaluator")
        if evaluator is not None:  # the pools need not wait for the tasks they run
            evaluator.stop_quickly()
        self._timer = threading.Timer(self.grace_seconds, self._hard_stop)
        self._timer.daemon = True
        self._timer.start()
        raise Interrupted(signum)

    def _hard_stop(self) -> None:
        """The clean-up took too long: kill the children, remove the evaluators'
        temporary directories, print the line and exit now."""
        kill_children()
        from fuzzygait.uncertainty.execution.evaluator import remove_temporary_directories

        remove_temporary_directories()
        signum = self.signum if self.signum is not None else signal.SIGTERM
        sys.stderr.write(interrupt_line(signum) + f" (clean-up took over {self.grace_seconds:g} s: "
                         "child processes killed)\n")  # fmt: skip
        sys.stderr.flush()
        os._exit(exit_code(signum))


def kill_children() -> list[int]:
    """SIGKILL every descendant process of this one; returns their ids."""
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
    psutil.wait_procs(children, timeout=5)
    return [child.pid for child in children]
