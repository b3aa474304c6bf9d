"""The ``fuzzygait`` command.

Every command reports bad input as one line ``fuzzygait: error: <file>: <cause>`` on
standard error and exits with a non-zero code; no partial output file is left behind.
``--debug`` shows the full traceback instead (for bug reports).
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from fuzzygait import __version__
from fuzzygait.errors import FuzzyGaitError

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


def _fail(message: str, code: int = EXIT_USER_ERROR) -> typer.Exit:
    err.print(f"fuzzygait: error: {message}", markup=False)
    return typer.Exit(code)


@contextmanager
def _user_errors() -> Iterator[None]:
    """Turn exceptions into the one-line error and exit code (traceback with --debug)."""
    try:
        yield
    except typer.Exit:
        raise
    except FuzzyGaitError as exc:
        if _state["debug"]:
            raise
        raise _fail(str(exc)) from None
    except KeyboardInterrupt:
        raise _fail("interrupted", 130) from None
    except Exception as exc:  # a bug: still one line, unless debugging
        if _state["debug"]:
            raise
        raise _fail(
            f"internal error {type(exc).__name__}: {exc} (rerun with --debug and report it)",
            EXIT_INTERNAL_ERROR,
        ) from None


def progress_over(items: Sequence[T], description: str) -> Iterator[T]:
    """Iterate ``items`` with a progress bar on stderr when there is more than one."""
    if len(items) <= 1:
        yield from items
        return
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=err, transient=True) as progress:
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


# --------------------------------------------------------------------------- info
@app.command()
def info(
    files: Annotated[list[Path], typer.Argument(help="C3D files to summarise.")],
) -> None:
    """Summarise C3D files: rate, frames, markers, gaps, events, units, subject parameters.

    Files that cannot be read get one error line each; the others are still summarised.
    The exit code is non-zero when any file failed.
    """
    from fuzzygait.io import read_c3d
    from fuzzygait.viz.summary import describe_trial

    failed = 0
    for path in progress_over(files, "reading"):
        try:
            with _user_errors():
                trial = read_c3d(path)
                out.print(describe_trial(trial), markup=False)
        except typer.Exit:
            failed += 1
    if failed:
        if len(files) > 1:
            err.print(f"fuzzygait: {failed} of {len(files)} files could not be read", markup=False)
        raise typer.Exit(EXIT_USER_ERROR)


# --------------------------------------------------------------------------- preprocess
@app.command()
def preprocess(
    input_file: Annotated[Path, typer.Argument(metavar="IN.c3d", help="Trial to clean.")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Output C3D file.")],
    max_gap: Annotated[
        int, typer.Option(help="Longest gap (frames) to fill by cubic spline; 0 fills none.")
    ] = 10,
    cutoff: Annotated[
        float, typer.Option(help="Low-pass cutoff (Hz) of the 4th-order zero-lag Butterworth.")
    ] = 6.0,
    no_filter: Annotated[bool, typer.Option("--no-filter", help="Fill gaps only.")] = False,
) -> None:
    """Fill marker gaps with cubic splines and low-pass filter (Butterworth, zero lag)."""
    from fuzzygait.io import read_c3d, write_c3d
    from fuzzygait.mocap import fill_trial_gaps, filter_trial

    with _user_errors():
        if out_file.suffix.lower() != ".c3d":
            raise FuzzyGaitError(f"{out_file}: --out must name a .c3d file")
        trial = read_c3d(input_file)
        filled, gaps = fill_trial_gaps(trial, max_gap=max_gap)
        cleaned = filled if no_filter else filter_trial(filled, cutoff=cutoff)
        out_file.parent.mkdir(parents=True, exist_ok=True)
        write_c3d(cleaned, out_file)
    n_filled = sum(g.filled for g in gaps)
    left = [g for g in gaps if not g.filled]
    out.print(
        f"{input_file.name}: filled {n_filled} of {len(gaps)} gaps"
        + ("" if no_filter else f", low-pass {cutoff:g} Hz")
        + f" -> {out_file}",
        markup=False,
    )
    for gap in left:
        out.print(
            f"  not filled: {gap.marker} frames {trial.first_frame + gap.start}"
            f"-{trial.first_frame + gap.start + gap.length - 1} ({gap.reason})",
            markup=False,
        )


# --------------------------------------------------------------------------- angles
@app.command()
def angles(
    dynamic: Annotated[Path, typer.Argument(metavar="DYNAMIC.c3d", help="Walking trial.")],
    static: Annotated[
        Path | None, typer.Option("--static", help="Static trial for the calibration offsets.")
    ] = None,
    subject: Annotated[
        Path | None,
        typer.Option("--subject", help="Subject parameters (.toml or .vsk); default: the file's PROCESSING group."),
    ] = None,
    out_table: Annotated[
        Path | None, typer.Option("--out", "-o", help="Angles per frame, .csv or .parquet.")
    ] = None,
    c3d_out: Annotated[
        Path | None, typer.Option("--c3d-out", help="C3D with markers, angles and virtual markers.")
    ] = None,
    cycles: Annotated[
        Path | None, typer.Option("--cycles", help="Mean and SD over gait cycles, .csv or .parquet.")
    ] = None,
    no_filter: Annotated[bool, typer.Option("--no-filter", help="Do not low-pass the markers.")] = False,
    max_gap: Annotated[int, typer.Option(help="Longest gap (frames) to fill.")] = 10,
    cutoff: Annotated[float, typer.Option(help="Low-pass cutoff (Hz).")] = 6.0,
    flat_foot: Annotated[bool, typer.Option("--flat-foot", help="Static calibration with flat feet.")] = False,
) -> None:
    """Plug-in Gait lower-body joint angles (degrees) of a walking trial."""
    from fuzzygait.io import write_c3d
    from fuzzygait.io.tables import check_table_path, write_table
    from fuzzygait.pipeline import Preprocessing, model_output_trial, run_angles

    with _user_errors():
        for path, option in ((out_table, "--out"), (cycles, "--cycles")):
            if path is not None:
                check_table_path(path, option)
        if c3d_out is not None and c3d_out.suffix.lower() != ".c3d":
            raise FuzzyGaitError(f"{c3d_out}: --c3d-out must name a .c3d file")
        run = run_angles(
            dynamic,
            static=static,
            subject_file=subject,
            preprocessing=Preprocessing(max_gap=max_gap, cutoff=cutoff, filter=not no_filter),
            flat_foot=flat_foot,
        )
        written = []
        for path, make in (
            (out_table, run.angle_table),
            (cycles, run.cycle_statistics),
        ):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                written.append(write_table(make(), path))
        if c3d_out is not None:
            c3d_out.parent.mkdir(parents=True, exist_ok=True)
            write_c3d(model_output_trial(run), c3d_out)
            written.append(c3d_out)
    _print_run_summary(run)
    for path in written:
        out.print(f"wrote {path}", markup=False)


def _print_run_summary(run: object) -> None:
    from fuzzygait.pipeline import AnglesRun

    assert isinstance(run, AnglesRun)
    trial = run.trial
    computed = [name for name in run.result.angles if name not in run.result.unavailable]
    counts = {side: sum(1 for e in run.events if e.context == ctx and e.label == "Foot Strike")
              for side, ctx in (("L", "Left"), ("R", "Right"))}  # fmt: skip
    out.print(
        f"{trial.name}: {trial.n_frames} frames at {trial.rate:g} Hz, "
        f"{len(computed)} angles computed, foot strikes L {counts['L']} / R {counts['R']} "
        f"(events: {run.event_source})",
        markup=False,
    )
    for note in run.notes:
        out.print(f"  note: {note}", markup=False)


# --------------------------------------------------------------------------- demo
@app.command()
def demo(
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Folder for the results.")] = Path(
        "results/demo"
    ),
    data: Annotated[
        Path, typer.Option("--data", help="Sample-data folder (generated when absent).")
    ] = Path("sample_data"),
) -> None:
    """The main job on the bundled sample: angles, gait cycles, a plot and a summary."""
    from fuzzygait.viz.demo import run_demo

    with _user_errors():
        summary = run_demo(data, out_dir, progress=err)
    out.print(summary, markup=False)


# --------------------------------------------------------------------------- sample data
@app.command("sample-data")
def sample_data(
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Folder to write.")] = Path(
        "sample_data"
    ),
) -> None:
    """Regenerate the synthetic sample trials (deterministic) into a folder."""
    from fuzzygait.synthetic import write_sample_data

    with _user_errors():
        written = write_sample_data(out_dir)
    for path in written:
        out.print(str(path), markup=False)


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the ``fuzzygait`` console script."""
    app(args=list(argv) if argv is not None else None, prog_name="fuzzygait")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
