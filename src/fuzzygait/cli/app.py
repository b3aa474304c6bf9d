"""The ``fuzzygait`` command: the typer app, errors as one line and an exit code,
warnings as one line, progress bars on stderr.

Every command reports bad input as one line ``fuzzygait: error: <file>: <cause>`` on
standard error and exits with a non-zero code; no partial output file is left behind.
``--debug`` shows the full traceback instead (for bug reports).  A usage error (unknown
option, missing argument, a value of the wrong type) is such a line too, naming the
option and the command's ``--help``, exit 1.  Warnings raised while a command works are
held until that work ends: printed (one line each) when it succeeds, left out when it
fails (the error line says how many; ``--debug`` shows them), so a failing command
prints its one error line only.  SIGINT and SIGTERM stop a command cleanly at any
moment, from its start-up to its exit (:mod:`~fuzzygait.cli.interrupts`): one line, exit
130 or 143, and no process it started is left running.
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Annotated, Any, TypeVar

from fuzzygait.cli.interrupts import prepare_command  # isort: skip

# First, before the slower imports below: in the `fuzzygait` process, a signal from now on
# ends the command with its one line (no KeyboardInterrupt traceback from an import).
prepare_command()

import typer  # noqa: E402
from rich.console import Console  # noqa: E402
from rich.progress import (  # noqa: E402
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from typer._click.exceptions import ClickException, NoArgsIsHelpError, UsageError  # noqa: E402
from typer.core import TyperGroup  # noqa: E402

from fuzzygait import __version__  # noqa: E402
from fuzzygait.cli.interrupts import (  # noqa: E402
    Interrupted,
    InterruptGuard,
    exit_code,
    interrupt_line,
    is_the_command,
    received,
)
from fuzzygait.cli.usage import usage_line  # noqa: E402
from fuzzygait.core.errors import FuzzyGaitError  # noqa: E402
from fuzzygait.core.options import use_command_line_names  # noqa: E402

EXIT_USER_ERROR = 1
EXIT_INTERNAL_ERROR = 3

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)

_state: dict[str, Any] = {"debug": False}
#: Warnings held by the active :func:`user_errors` blocks (innermost last).
_held: list[list[str]] = []
T = TypeVar("T")


class Commands(TyperGroup):
    """The command group, run as one process should end: a usage error as one line and
    exit 1 (``--help`` as typer prints it), SIGINT/SIGTERM as one line and exit
    130/143 after the clean-up (:class:`~fuzzygait.cli.interrupts.InterruptGuard`)."""

    def main(self, args: Sequence[str] | None = None, prog_name: str | None = None,
             complete_var: str | None = None, standalone_mode: bool = True, windows_expand_args: bool = True,
             **extra: Any) -> Any:  # fmt: skip
        _held.clear()
        code: int
        # the command's own process: once the guard ends, the process is ending (interrupts.py)
        with InterruptGuard(ending=standalone_mode and is_the_command()) as guard:
            try:
                value = super().main(args, prog_name, complete_var, standalone_mode=False,
                                     windows_expand_args=windows_expand_args, **extra)  # fmt: skip
                code = value if isinstance(value, int) and not isinstance(value, bool) else 0
            except NoArgsIsHelpError as exc:  # `fuzzygait` alone: the help, as --help prints it
                out.print(exc.format_message(), markup=False)
                code = 0
            except UsageError as exc:
                err.print(usage_line(exc, self._command_in(args)), markup=False)
                code = EXIT_USER_ERROR
            except ClickException as exc:
                err.print(f"fuzzygait: error: {' '.join(exc.format_message().split())}", markup=False)
                code = EXIT_USER_ERROR
            except (typer.Abort, EOFError):
                err.print("fuzzygait: error: aborted", markup=False)
                code = EXIT_USER_ERROR
            except KeyboardInterrupt:  # raised before the guard was active, or not by a signal
                guard.signum = guard.signum or 2
            except BaseException as exc:  # after a signal: the interrupt's doing (interrupts.received)
                if guard.signum is None or isinstance(exc, SystemExit):
                    raise
        if guard.signum is not None:
            err.print(interrupt_line(guard.signum), markup=False)
            code = exit_code(guard.signum)
        if standalone_mode:
            sys.exit(code)
        return code

    def _command_in(self, args: Sequence[str] | None) -> str | None:
        """The first of ``args`` (default: the process's) that names a command."""
        return next((a for a in (sys.argv[1:] if args is None else args) if a in self.commands), None)


app = typer.Typer(
    name="fuzzygait",
    help="Gait analysis that says how far to trust its numbers.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    cls=Commands,
)


def debugging() -> bool:
    """Whether ``--debug`` was given (tracebacks instead of one-line errors)."""
    return _state["debug"]


def fail(message: str, code: int = EXIT_USER_ERROR) -> typer.Exit:
    """Print the one-line error; returns the exit to raise."""
    err.print(f"fuzzygait: error: {message}", markup=False)
    return typer.Exit(code)


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn exceptions into the one-line error and exit code (traceback with --debug).

    The warnings raised inside are held: printed when the block succeeds (to the
    enclosing block, if any), left out when it fails, the error line counting them.  An
    interrupt (``KeyboardInterrupt``) passes through to :class:`Commands`, and so does an
    error raised after a signal was received (it is the interrupt's doing)."""
    held: list[str] = []
    _held.append(held)
    try:
        yield
    except typer.Exit as exc:
        _drop(held, exc.exit_code != 0)
        raise
    except FuzzyGaitError as exc:
        _drop(held)
        _interrupted_instead()
        if _state["debug"]:
            raise
        raise fail(str(exc) + _left_out(held)) from None
    except Exception as exc:  # a bug (still one line, unless debugging), or a file the system refuses
        _drop(held)
        _interrupted_instead()
        if _state["debug"]:
            raise
        if (problem := _file_problem(exc)) is not None:
            raise fail(problem + _left_out(held)) from None
        raise fail(
            f"internal error {type(exc).__name__}: {exc} (rerun with --debug and report it)" + _left_out(held),
            EXIT_INTERNAL_ERROR,
        ) from None
    except BaseException:  # interrupted: the interrupt's line is the only one
        _drop(held)
        raise
    _drop(held, failed=False)


def _file_problem(exc: Exception) -> str | None:
    """The line of an operating system's refusal on a named file (no permission, a
    read-only or full disk, a file where a folder should be ...): the user's to mend, not
    a bug; None for any other exception."""
    if not isinstance(exc, OSError) or exc.filename is None:
        return None
    return f"{exc.filename}: {exc.strerror or exc}; check the path, its folder and its permissions"


def _interrupted_instead() -> None:
    """After a signal, an error is the interrupt's doing: raise the interrupt instead, so
    that its line is the only one (:func:`fuzzygait.cli.interrupts.received`)."""
    signum = received()
    if signum is not None:
        raise Interrupted(signum) from None


def _drop(held: list[str], failed: bool = True) -> None:
    """End a :func:`user_errors` block's holding of warnings: on success pass them on (to
    the enclosing block, or print them)."""
    if _held and _held[-1] is held:
        _held.pop()
    if not failed:
        for line in held:
            _warn_line(line)
        held.clear()


def _left_out(held: Sequence[str]) -> str:
    if not held:
        return ""
    return f" ({len(held)} warning{'s' if len(held) > 1 else ''} left out; --debug shows them)"


def _warn_line(line: str) -> None:
    """A warning line: held by the innermost :func:`user_errors` block, else printed."""
    if _held:
        if line not in _held[-1]:
            _held[-1].append(line)
    else:
        err.print(line, markup=False)


def progress_bars() -> Progress:
    """Progress bars on stderr (removed when done; silent when stderr is not a terminal)."""
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                    console=err, transient=True, disable=not err.is_terminal)  # fmt: skip


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
    use_command_line_names()  # messages name settings as this command's options (--static)
    if not debug:  # data-quality warnings as one plain line each, not Python's two-line form
        warnings.showwarning = _show_warning


def _show_warning(message: Warning | str, category: type[Warning], *_args: object, **_kwargs: object) -> None:
    _warn_line(f"fuzzygait: warning: {message}")


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``fuzzygait`` console script."""
    app(args=list(argv) if argv is not None else None, prog_name="fuzzygait")
