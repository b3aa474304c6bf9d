"""The ``fuzzygait`` command: the typer app, errors as one line and an exit code,
warnings as one line, progress bars on stderr.

Every command reports bad input as one line ``fuzzygait: error: <file>: <cause>`` on
standard error and exits with a non-zero code; no partial output file is left behind.
``--debug`` shows the full traceback instead (for bug reports).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Annotated, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TextColumn, TimeElapsedColumn

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError

app = typer.Typer(
    name="fuzzygait",
    help="Gait analysis that says how far to trust its numbers.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)

_state = {"debug": False}
T = TypeVar("T")

EXIT_USER_ERROR = 1
EXIT_INTERNAL_ERROR = 3


def debugging() -> bool:
    """Whether ``--debug`` was given (tracebacks instead of one-line errors)."""
    return _state["debug"]


def fail(message: str, code: int = EXIT_USER_ERROR) -> typer.Exit:
    """Print the one-line error; returns the exit to raise."""
    err.print(f"fuzzygait: error: {message}", markup=False)
    return typer.Exit(code)


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn exceptions into the one-line error and exit code (traceback with --debug)."""
    try:
        yield
    except typer.Exit:
        raise
    except FuzzyGaitError as exc:
        if _state["debug"]:
            raise
        raise fail(str(exc)) from None
    except KeyboardInterrupt:
        raise fail("interrupted", 130) from None
    except Exception as exc:  # a bug: still one line, unless debugging
        if _state["debug"]:
            raise
        raise fail(
            f"internal error {type(exc).__name__}: {exc} (rerun with --debug and report it)",
            EXIT_INTERNAL_ERROR,
        ) from None


def progress_bars() -> Progress:
    """Progress bars on stderr (removed when done; silent when stderr is not a terminal)."""
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), console=err, transient=True)  # fmt: skip


class StageBars:
    """One bar of ``bars`` showing a workflow's current stage
    (:class:`fuzzygait.workflows.progress.StageProgress`)."""

    def __init__(self, bars: Progress) -> None:
        self._bars = bars
        self._task: TaskID | None = None

    def stage(self, description: str, total: int | None = None) -> None:
        """Replace the bar of the previous stage by a new one."""
        if self._task is not None:
            self._bars.remove_task(self._task)
        self._task = self._bars.add_task(description, total=total)

    def update(self, completed: int, total: int | None = None) -> None:
        """Move the bar (``total`` None: unchanged)."""
        if self._task is not None:
            self._bars.update(self._task, completed=completed, total=total)


def progress_over(items: Sequence[T], description: str) -> Iterator[T]:
    """Iterate ``items`` with a progress bar on stderr when there is more than one."""
    if len(items) <= 1:
        yield from items
        return
    with progress_bars() as progress:
        task = progress.add_task(description, total=len(items))
        for item in items:
            yield item
            progress.advance(task)


def _version(value: bool) -> None:
    if value:
        out.print(f"fuzzygait {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    debug: Annotated[bool, typer.Option("--debug", help="Show full tracebacks.")] = False,
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Show the version.")
    ] = False,
) -> None:
    _state["debug"] = debug
    if not debug:  # data-quality warnings as one plain line each, not Python's two-line form
        warnings.showwarning = _show_warning


def _show_warning(message: Warning | str, category: type[Warning], *_args: object, **_kwargs: object) -> None:
    err.print(f"fuzzygait: warning: {message}", markup=False)


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``fuzzygait`` console script."""
    app(args=list(argv) if argv is not None else None, prog_name="fuzzygait")
