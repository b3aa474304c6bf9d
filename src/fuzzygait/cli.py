"""The ``fuzzygait`` command.

Every command reports bad input as one line ``fuzzygait: error: <file>: <cause>`` on
standard error and exits with a non-zero code; no partial output file is left behind.
``--debug`` shows the full traceback instead (for bug reports).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, TypeVar

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError

if TYPE_CHECKING:
    import numpy as np

    from fuzzygait.mechanics.scenarios import LegSimulator

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


def _progress_bars() -> Progress:
    """Progress bars on stderr (removed when done; silent when stderr is not a terminal)."""
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), console=err, transient=True)  # fmt: skip


def _build_simulator(bars: Progress, scenario: str, nodes: int, values: dict[str, float]) -> tuple[LegSimulator, np.ndarray]:
    """The scenario's simulator (built, or its compiled code loaded, under a spinner) and
    its full parameter vector with ``values`` (SI units) set."""
    from fuzzygait.mechanics.scenarios import LegSimulator

    building = bars.add_task(f"{scenario}: building the model", total=None)
    sim = LegSimulator(scenario=scenario, nodes=nodes)
    parameters = sim.parameters(**values)
    bars.remove_task(building)
    return sim, parameters


def progress_over(items: Sequence[T], description: str) -> Iterator[T]:
    """Iterate ``items`` with a progress bar on stderr when there is more than one."""
    if len(items) <= 1:
        yield from items
        return
    with _progress_bars() as progress:
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


# --------------------------------------------------------------------------- shared options
StaticOption = Annotated[Path | None, typer.Option("--static", help="Static trial for the calibration offsets.")]
SubjectOption = Annotated[
    Path | None,
    typer.Option("--subject", help="Subject parameters (.toml or .vsk); default: the file's PROCESSING group."),
]
ErrorsOption = Annotated[
    Path | None, typer.Option("--errors", help="Marker error sizes (.toml); default: thesis Table 3.1.")
]
SourcesOption = Annotated[str, typer.Option(help="Marker error sources to add up, comma-separated.")]
AlphasOption = Annotated[
    str, typer.Option(help="α-levels below 1, comma-separated (1, the measured curve, is always added).")
]
AnglesOption = Annotated[
    str | None, typer.Option("--angles", help="Angles to analyse, comma-separated (e.g. LKneeAngles); default: all.")
]
NoFilterOption = Annotated[bool, typer.Option("--no-filter", help="Do not low-pass the markers.")]
MaxGapOption = Annotated[int, typer.Option(help="Longest gap (frames) to fill.")]
CutoffOption = Annotated[float, typer.Option(help="Low-pass cutoff (Hz).")]
DEFAULT_SOURCES = "measurement,placement,sta"
DEFAULT_ALPHAS = "0,0.25,0.5,0.75"


def _parse_angles(text: str | None) -> list[str] | None:
    """``"LKneeAngles,RKneeAngles"`` -> validated angle names (None: all)."""
    from fuzzygait.kinematics import ANGLE_NAMES

    if text is None:
        return None
    selected = [n.strip() for n in text.split(",") if n.strip()]
    unknown = [n for n in selected if n not in ANGLE_NAMES]
    if unknown or not selected:
        raise FuzzyGaitError(f"--angles: unknown angle {', '.join(unknown) or repr(text)}; "
                             f"choose from {', '.join(ANGLE_NAMES)}")  # fmt: skip
    return selected


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
    max_gap: Annotated[int, typer.Option(help="Longest gap (frames) to fill; 0 fills none.")] = 10,
    fill_method: Annotated[
        str,
        typer.Option(
            "--fill-method",
            help="auto (per gap, whichever refills nearby pseudo-gaps better), spline "
            "(cubic spline through the marker's own samples) or pattern (regression on "
            "the other markers visible, spline where there are too few).",
        ),
    ] = "auto",
    cutoff: Annotated[
        float, typer.Option(help="Low-pass cutoff (Hz) of the 4th-order zero-lag Butterworth.")
    ] = 6.0,
    no_filter: Annotated[bool, typer.Option("--no-filter", help="Fill gaps only.")] = False,
) -> None:
    """Fill marker gaps (spline or inter-marker pattern) and low-pass filter (Butterworth, zero lag)."""
    from fuzzygait.io import read_c3d, write_c3d
    from fuzzygait.mocap import fill_trial_gaps, filter_trial
    from fuzzygait.mocap.gaps import METHODS, methods_used

    with _user_errors():
        if out_file.suffix.lower() != ".c3d":
            raise FuzzyGaitError(f"{out_file}: --out must name a .c3d file")
        if fill_method not in METHODS:
            raise FuzzyGaitError(f"--fill-method must be one of {', '.join(METHODS)}; got {fill_method!r}")
        trial = read_c3d(input_file)
        filled, gaps = fill_trial_gaps(trial, max_gap=max_gap, method=fill_method)  # type: ignore[arg-type]
        cleaned = filled if no_filter else filter_trial(filled, cutoff=cutoff)
        out_file.parent.mkdir(parents=True, exist_ok=True)
        write_c3d(cleaned, out_file)
    n_filled = sum(g.filled for g in gaps)
    left = [g for g in gaps if not g.filled]
    by_method = methods_used(gaps)
    out.print(
        f"{input_file.name}: filled {n_filled} of {len(gaps)} gaps"
        + (f" ({by_method})" if by_method else "")
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
    static: StaticOption = None,
    subject: SubjectOption = None,
    out_table: Annotated[
        Path | None, typer.Option("--out", "-o", help="Angles per frame, .csv or .parquet.")
    ] = None,
    c3d_out: Annotated[
        Path | None, typer.Option("--c3d-out", help="C3D with markers, angles and virtual markers.")
    ] = None,
    cycles: Annotated[
        Path | None, typer.Option("--cycles", help="Mean and SD over gait cycles, .csv or .parquet.")
    ] = None,
    no_filter: NoFilterOption = False,
    max_gap: MaxGapOption = 10,
    cutoff: CutoffOption = 6.0,
    flat_foot: Annotated[bool, typer.Option("--flat-foot", help="Static calibration with flat feet.")] = False,
) -> None:
    """Plug-in Gait lower-body joint angles (degrees) of a walking trial."""
    from fuzzygait.io import write_c3d
    from fuzzygait.io.tables import check_table_path, write_table
    from fuzzygait.workflows.angles import Preprocessing, model_output_trial, run_angles

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
    from fuzzygait.workflows.angles import AnglesRun

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
    from fuzzygait.workflows.demo import run_demo

    with _user_errors():
        summary = run_demo(data, out_dir, progress=err)
    out.print(summary, markup=False)


# --------------------------------------------------------------------------- uncertainty
@app.command()
def uncertainty(
    dynamic: Annotated[Path, typer.Argument(metavar="DYNAMIC.c3d", help="Walking trial.")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Fuzzy joint angles, .nc or .zarr.")],
    static: StaticOption = None,
    subject: SubjectOption = None,
    errors: ErrorsOption = None,
    sources: SourcesOption = DEFAULT_SOURCES,
    alphas: AlphasOption = DEFAULT_ALPHAS,
    angle_names: AnglesOption = None,
    method: Annotated[str, typer.Option(help="cartesian or spherical marker deviations.")] = "cartesian",
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write a Rerun recording (.rrd).")] = None,
    workers: Annotated[int, typer.Option(help="Processes for the angle components.")] = 2,
    no_filter: NoFilterOption = False,
    max_gap: MaxGapOption = 10,
    cutoff: CutoffOption = 6.0,
) -> None:
    """Fuzzy joint angles from fuzzy marker errors: per frame and α-level the range of
    every angle component over all marker deviations inside the α-level balls."""
    from fuzzygait.markererror.analysis import analyse_trial
    from fuzzygait.workflows.angles import Preprocessing
    from fuzzygait.uncertainty.storage import SUFFIXES, save_result

    with _user_errors():
        if out_file.suffix.lower() not in SUFFIXES:
            raise FuzzyGaitError(f"{out_file}: --out must end in .nc or .zarr")
        if rrd is not None and rrd.suffix.lower() != ".rrd":
            raise FuzzyGaitError(f"{rrd}: --rrd must end in .rrd")
        if workers < 1:
            raise FuzzyGaitError(f"--workers must be at least 1; got {workers}")
        selected = _parse_angles(angle_names)
        progress = _progress_bars()
        with progress:
            task = progress.add_task("fuzzy angles", total=None)
            analysis = analyse_trial(
                dynamic, static=static, subject_file=subject, errors_file=errors, sources=sources.split(","),
                alphas=_parse_alphas(alphas), angles=selected, method=method, workers=workers,
                preprocessing=Preprocessing(max_gap=max_gap, cutoff=cutoff, filter=not no_filter),
                progress=lambda done, total: progress.update(task, completed=done, total=total),
            )  # fmt: skip
        out_file.parent.mkdir(parents=True, exist_ok=True)
        save_result(analysis.fuzzy, out_file)
        if rrd is not None:
            from fuzzygait.viz.rerun_log import write_recording

            rrd.parent.mkdir(parents=True, exist_ok=True)
            write_recording(rrd, analysis.run.trial, analysis.run.result, analysis.fuzzy)
    _print_run_summary(analysis.run)
    table = analysis.delta_phi
    out.print("ΔΦ, relative envelope width (Eq. 5.3), % of the largest |angle|:", markup=False)
    out.print(table.round(1).to_string(), markup=False)
    out.print(f"wrote {out_file}" + (f" and {rrd}" if rrd is not None else ""), markup=False)


# --------------------------------------------------------------------------- report
def _report_inputs(inputs: Sequence[Path], static: Path | None) -> list[Path]:
    """The trials of ``fuzzygait report``: files as given; folders searched recursively
    for ``*.c3d`` (any case), skipping files there whose name contains "static" (any
    case: calibration trials). The ``--static`` file is never a trial; duplicates once."""
    found: list[Path] = []
    for path in inputs:
        if path.is_dir():
            files = sorted(p for p in path.rglob("*") if p.is_file() and p.suffix.lower() == ".c3d"
                           and "static" not in p.name.lower())  # fmt: skip
            if not files:
                raise FuzzyGaitError(f"{path}: no walking trials (*.c3d without 'static' in the name) in this folder")
            found += files
        else:
            found.append(path)
    skip = {static.resolve()} if static is not None else set()
    unique: dict[Path, Path] = {}
    for path in found:
        if path.resolve() not in skip:
            unique.setdefault(path.resolve(), path)
    if not unique:
        raise FuzzyGaitError("no trials to report (the only input is the --static trial)")
    return list(unique.values())


def _parse_alphas(text: str) -> tuple[float, ...]:
    """``"0,0.25,0.5"`` -> sorted α-levels in [0, 1), plus 1 (the measured curve)."""
    message = f"--alphas must be comma-separated numbers from 0 to below 1, e.g. 0,0.5; got {text!r}"
    try:
        values = {float(v) for v in text.split(",") if v.strip()}
    except ValueError:
        raise FuzzyGaitError(message) from None
    values.discard(1.0)
    if not values or not all(0.0 <= v < 1.0 for v in values):
        raise FuzzyGaitError(message)
    return (*sorted(values), 1.0)


@app.command()
def report(
    inputs: Annotated[
        list[Path],
        typer.Argument(metavar="INPUT", help="Walking trials: C3D files, or folders searched "
                       "recursively for *.c3d (files there with 'static' in the name are skipped)."),
    ],
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Report folder (index.html + one page per trial).")],
    static: StaticOption = None,
    subject: SubjectOption = None,
    errors: ErrorsOption = None,
    sources: SourcesOption = DEFAULT_SOURCES,
    alphas: AlphasOption = DEFAULT_ALPHAS,
    angle_names: AnglesOption = None,
    workers: Annotated[int, typer.Option(help="Processes for the angle components of a trial.")] = 2,
    no_filter: NoFilterOption = False,
    max_gap: MaxGapOption = 10,
    cutoff: CutoffOption = 6.0,
) -> None:
    """Clinicians' HTML report: joint angles over the gait cycle with fuzzy uncertainty
    bands from marker errors, the ΔΦ table and data-quality notes, one page per trial.

    A trial that fails is listed in the index with its error; the others are still
    reported. Exit code 0 when at least one trial succeeded, 1 when all failed.
    """
    from fuzzygait.workflows.angles import Preprocessing
    from fuzzygait.viz.report import ReportItem, ReportWriter

    debug = _state["debug"]
    with _user_errors():
        alpha_levels = _parse_alphas(alphas)
        if workers < 1:
            raise FuzzyGaitError(f"--workers must be at least 1; got {workers}")
        selected = _parse_angles(angle_names)
        try:
            from fuzzygait.markererror.analysis import analyse_trial
            from fuzzygait.markererror.sources import parse_sources, read_error_model
        except ModuleNotFoundError as exc:
            if not (exc.name or "").startswith("fuzzygait"):
                raise
            raise FuzzyGaitError("the marker-error analysis is not available in this installation") from None
        error_sources = parse_sources(sources)
        if errors is not None:
            read_error_model(errors)  # a bad errors file fails once, not once per trial
        paths = _report_inputs(inputs, static)
        preprocessing = Preprocessing(max_gap=max_gap, cutoff=cutoff, filter=not no_filter)
        bars = _progress_bars()
        with ReportWriter(out_dir, strict=debug) as writer, bars:
            trials = bars.add_task("trials", total=len(paths))
            components = bars.add_task("angle components", total=None)

            def angle_progress(done: int, total: int) -> None:
                bars.update(components, completed=done, total=total)

            for path in paths:
                bars.update(components, completed=0, total=None, description=f"{path.name}: angle components")
                try:
                    item = ReportItem(path, analyse_trial(
                        path, static=static, subject_file=subject, preprocessing=preprocessing,
                        errors_file=errors, sources=error_sources, alphas=alpha_levels, angles=selected,
                        workers=workers, progress=angle_progress,
                    ), None)  # fmt: skip
                except FuzzyGaitError as exc:
                    if debug:
                        raise
                    item = ReportItem(path, None, str(exc))
                except Exception as exc:  # a bug: listed as failed, the batch goes on
                    if debug:
                        raise
                    item = ReportItem(path, None, f"internal error {type(exc).__name__}: {exc} "
                                      "(rerun with --debug and report it)")  # fmt: skip
                entry = writer.add(item)
                bars.advance(trials)
                del item
                if not entry.ok:
                    where = "" if path.name in (entry.error or "") else f"{path}: "
                    err.print(f"fuzzygait: failed: {where}{entry.error}", markup=False)
            index = writer.finish()
    n_ok = sum(e.ok for e in writer.entries)
    n_failed = len(writer.entries) - n_ok
    out.print(f"report: {n_ok} of {len(writer.entries)} trials OK" + (f", {n_failed} failed" if n_failed else ""),
              markup=False)  # fmt: skip
    out.print(f"wrote {index}", markup=False)
    if n_ok == 0:
        raise typer.Exit(EXIT_USER_ERROR)


# --------------------------------------------------------------------------- simulate
def _parse_overrides(texts: Sequence[str]) -> dict[str, float]:
    """``["E=6e5,eta=2", "rho=1700"]`` -> ``{"E": 6e5, "eta": 2.0, "rho": 1700.0}``."""
    from fuzzygait.mechanics.leg import LEG_PARAMETERS

    values: dict[str, float] = {}
    for text in texts:
        for item in (part.strip() for part in text.split(",")):
            if not item:
                continue
            name, sep, value = (s.strip() for s in item.partition("="))
            if not sep or not name:
                raise FuzzyGaitError(f"--set: expected name=value, got {item!r}")
            if name not in LEG_PARAMETERS:
                raise FuzzyGaitError(f"--set: unknown parameter {name!r}; known: {', '.join(LEG_PARAMETERS)}")
            try:
                number = float(value)
            except ValueError:
                raise FuzzyGaitError(f"--set: {name}={value!r} is not a number (SI units, e.g. {name}=1.5e6)") from None
            if name in values:
                raise FuzzyGaitError(f"--set: {name} is given twice")
            values[name] = number
    return values


def _remove_output(path: Path) -> None:
    import shutil

    if path.is_dir():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def _check_output_suffixes(out_file: Path, rrd: Path | None, plots: dict[str, Path | None]) -> None:
    """One clear error, before any work, for an output path with the wrong suffix."""
    from fuzzygait.uncertainty.storage import SUFFIXES
    from fuzzygait.viz.figures import FIGURE_SUFFIXES

    if out_file.suffix.lower() not in SUFFIXES:
        raise FuzzyGaitError(f"{out_file}: --out must end in {' or '.join(SUFFIXES)}")
    if rrd is not None and rrd.suffix.lower() != ".rrd":
        raise FuzzyGaitError(f"{rrd}: --rrd must end in .rrd")
    for option, plot in plots.items():
        if plot is not None and plot.suffix.lower().lstrip(".") not in FIGURE_SUFFIXES:
            raise FuzzyGaitError(f"{plot}: {option} must end in .png, .svg or .pdf")


def _write_all_or_none(writers: Sequence[tuple[Path | None, Callable[[Path], object]]]) -> list[Path]:
    """Run ``writer(path)`` for every given path (folders created first); on any failure
    remove what was already written and re-raise: all outputs or none."""
    written: list[Path] = []
    try:
        for path, _ in writers:
            if path is not None:
                try:
                    path.parent.mkdir(parents=True, exist_ok=True)
                except OSError as exc:
                    raise FuzzyGaitError(f"{path}: cannot create its folder ({exc.strerror or exc})") from None
        for path, write in writers:
            if path is not None:
                write(path)
                written.append(path)
    except BaseException:
        for path in written:
            _remove_output(path)
        raise
    return written


@app.command()
def simulate(
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="swing or stance (thesis Tables 4.3 / 4.4).")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Simulation results, .nc or .zarr.")],
    nodes: Annotated[int, typer.Option(help="Beam nodes of the prosthesis blade.")] = 20,
    dt: Annotated[float | None, typer.Option("--dt", help="Time step (s); default: the scenario's, 0.001.")] = None,
    duration: Annotated[
        float | None, typer.Option("--duration", help="Simulated time (s); default: the scenario's, 2.")
    ] = None,
    overrides: Annotated[
        list[str] | None,
        typer.Option("--set", metavar="NAME=VALUE,...", help="Parameter values in SI units, comma-separated "
                     "or repeated, e.g. E=6e5,eta=2 (names: E, nu, rho, eta, thigh_mass, thigh_J1..3, "
                     "shank_mass, shank_J1..3); default: the scenario's."),
    ] = None,  # fmt: skip
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write a Rerun recording (.rrd).")] = None,
    plot: Annotated[
        Path | None, typer.Option("--plot", help="Also plot the energies over time (.png, .svg or .pdf).")
    ] = None,
    scheme: Annotated[
        str, typer.Option(help="Time integrator: variational (thesis Eq. 4.26) or energy-momentum "
                          "(exact energy balance, more robust for very flexible and stiff blades).")
    ] = "variational",
    sensitivities: Annotated[
        bool, typer.Option("--sensitivities", help="Also integrate dq/dp and the target sensitivities "
                           "(about twice the cost of a plain run).")
    ] = False,
) -> None:
    """Simulate the leg with the prosthesis blade (swing or stance scenario) and save
    positions, directors, joint angles and energies over time.

    Nothing is written when the simulation fails: try a smaller --dt or more damping then.
    """
    import numpy as np

    from fuzzygait.mechanics.scenarios import SCENARIOS
    from fuzzygait.uncertainty.storage import save_result

    with _user_errors():
        if scenario not in SCENARIOS:
            raise FuzzyGaitError(f"unknown scenario {scenario!r}; choose {' or '.join(SCENARIOS)}")
        _check_output_suffixes(out_file, rrd, {"--plot": plot})
        if nodes < 2:
            raise FuzzyGaitError(f"--nodes must be at least 2; got {nodes}")
        preset = SCENARIOS[scenario]
        step = preset.dt if dt is None else dt
        if not (np.isfinite(step) and step > 0):
            raise FuzzyGaitError(f"--dt must be a time step > 0 s; got {dt:g}")
        span = preset.duration if duration is None else duration
        if not (np.isfinite(span) and span >= step):
            raise FuzzyGaitError(f"--duration must be at least the time step ({step:g} s); got {span:g}")
        from fuzzygait.mechanics.integrator import SCHEMES

        if scheme not in SCHEMES:
            raise FuzzyGaitError(f"--scheme must be {' or '.join(SCHEMES)}; got {scheme!r}")
        values = _parse_overrides(overrides or [])
        n_steps = int(round(span / step))

        bars = _progress_bars()
        with bars:
            sim, p = _build_simulator(bars, scenario, nodes, values)
            task = bars.add_task(f"{scenario}: time steps", total=n_steps)
            # the integrator checks for non-finite values itself; numpy's overflow warnings
            # on a diverging step would only add lines to its one-line error
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                ds = sim.run(p, dt=step, duration=span, sensitivities=sensitivities, scheme=scheme,
                             progress=lambda done: bars.update(task, completed=done))  # fmt: skip
        config = sim.configuration
        ds.attrs.update({f"{seg.name}_{key}_m": float(getattr(seg, key))
                         for seg in (config.thigh, config.shank) for key in ("length", "com_from_proximal")})  # fmt: skip
        from fuzzygait.viz.mechanics import write_energy_figure, write_simulation_recording

        written = _write_all_or_none([
            (out_file, lambda path: save_result(ds, path)),
            (plot, lambda path: write_energy_figure(ds, path)),
            (rrd, lambda path: write_simulation_recording(ds, path, configuration=config)),
        ])  # fmt: skip
    _print_simulation_summary(ds)
    out.print("wrote " + ", ".join(str(p) for p in written), markup=False)


@app.command("fuzzy-sim")
def fuzzy_sim(
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="swing or stance (thesis Tables 4.3 / 4.4).")],
    fuzzy: Annotated[
        list[str], typer.Option("--fuzzy", metavar="NAME=SPREAD,...",
                                help="Triangular fuzzy parameters as ± relative spreads, e.g. E=10% (repeatable).")
    ],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Fuzzy result, .zarr or .nc.")],
    target: Annotated[
        str | None, typer.Option(help="total_deformation_energy (swing default), max_element_energy (stance "
                                 "default), last_node_x|y|z.")
    ] = None,  # fmt: skip
    alphas: Annotated[str, typer.Option(help="α-levels, comma-separated (1 is always added).")] = "0,0.5,1",
    stride: Annotated[int, typer.Option(help="Optimise every STRIDE-th time node (thesis: 100).")] = 100,
    novelty: Annotated[float, typer.Option(help="Novelty tolerance, relative (thesis: 0.01 % = 1e-4).")] = 1e-4,
    nodes: Annotated[int, typer.Option(help="Beam nodes of the prosthesis blade.")] = 20,
    dt: Annotated[float | None, typer.Option("--dt", help="Time step (s); default: the scenario's.")] = None,
    duration: Annotated[float | None, typer.Option("--duration", help="Simulated time (s); default: the scenario's.")] = None,
    overrides: Annotated[
        list[str] | None, typer.Option("--set", metavar="NAME=VALUE,...", help="Fixed parameter values (SI units).")
    ] = None,
    scheme: Annotated[str, typer.Option(help="variational or energy-momentum.")] = "variational",
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write the hulls as a Rerun recording.")] = None,
    plot: Annotated[Path | None, typer.Option("--plot", help="Also plot the hulls (.png, .svg, .pdf).")] = None,
    parameter_plot: Annotated[
        Path | None, typer.Option("--parameter-plot", help="Also plot the extremising parameter sets (Fig. 5.6).")
    ] = None,
) -> None:
    """Fuzzy forward dynamics: hulls of a target output for triangular fuzzy parameters
    (Graph Follower algorithm, linearised with the simulator's sensitivities)."""
    import numpy as np

    from fuzzygait.mechanics.fuzzy_dynamics import fuzzy_forward_dynamics, parse_fuzzy
    from fuzzygait.mechanics.scenarios import SCENARIOS
    from fuzzygait.uncertainty.storage import save_result

    with _user_errors():
        if scenario not in SCENARIOS:
            raise FuzzyGaitError(f"unknown scenario {scenario!r}; choose {' or '.join(SCENARIOS)}")
        _check_output_suffixes(out_file, rrd, {"--plot": plot, "--parameter-plot": parameter_plot})
        spreads = parse_fuzzy(fuzzy)
        levels = _parse_alphas(alphas)
        values = _parse_overrides(overrides or [])
        if stride < 1:
            raise FuzzyGaitError(f"--stride must be ≥ 1; got {stride}")
        bars = _progress_bars()
        with bars:
            sim, base = _build_simulator(bars, scenario, nodes, values)
            task = bars.add_task(f"{scenario}: α-level optimisations", total=None)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                result = fuzzy_forward_dynamics(
                    sim, spreads, target=target, base=base, alphas=levels, stride=stride, novelty_tol=novelty,
                    dt=dt, duration=duration, scheme=scheme,
                    progress=lambda done, total: bars.update(task, completed=done, total=total),
                )  # fmt: skip
        from fuzzygait.viz.figures import save_figure
        from fuzzygait.viz.fuzzy_dynamics import extremiser_figure, hull_figure, write_fuzzy_recording

        written = _write_all_or_none([
            (out_file, lambda path: save_result(result, path)),
            (plot, lambda path: save_figure(hull_figure(result), path)),
            (parameter_plot, lambda path: save_figure(extremiser_figure(result), path)),
            (rrd, lambda path: write_fuzzy_recording(result, path)),
        ])  # fmt: skip
    attrs = result.attrs
    out.print(
        f"{scenario}: {attrs['target']} with fuzzy {', '.join(f'{n} ±{100 * s:g} %' for n, s in spreads.items())}; "
        f"{attrs['model_evaluations']} forward simulations, {attrs['optimisations']} optimisations, "
        f"wall time {attrs['wall_time_s']:.1f} s",
        markup=False,
    )
    out.print("wrote " + ", ".join(str(p) for p in written), markup=False)


@app.command("frv-sim")
def frv_sim(
    scenario: Annotated[str, typer.Argument(metavar="SCENARIO", help="stance (thesis §5.7) or swing.")],
    out_store: Annotated[Path, typer.Option("--out", "-o", help="FRV study, a .zarr directory; an existing "
                                            "study is extended with --samples more samples.")],
    parameter: Annotated[str, typer.Option("--frv", help="The fuzzy random leg parameter.")] = "E",
    value: Annotated[
        float | None, typer.Option("--value", help="Its deterministic value p_det (SI); default: the scenario's.")
    ] = None,
    samples: Annotated[int, typer.Option(help="Samples N_s to draw (or to add).")] = 10000,
    disc: Annotated[int, typer.Option(help="Grouping grid points N_p-disc.")] = 100,
    alphas: Annotated[str, typer.Option(help="α-levels, comma-separated (1 is always added).")] = "0,0.25,0.5,0.75",
    distribution: Annotated[str, typer.Option(help="normal (with redraw) or beta increments.")] = "normal",
    seed: Annotated[int, typer.Option(help="Seed of the sample streams.")] = 0,
    target: Annotated[str | None, typer.Option(help="Target output (default: per scenario).")] = None,
    overrides: Annotated[
        list[str] | None, typer.Option("--set", metavar="NAME=VALUE,...", help="Fixed parameter values (SI units).")
    ] = None,
    nodes: Annotated[int, typer.Option(help="Beam nodes of the prosthesis blade.")] = 20,
    dt: Annotated[float | None, typer.Option("--dt", help="Time step (s).")] = None,
    duration: Annotated[float | None, typer.Option("--duration", help="Simulated time (s).")] = None,
    scheme: Annotated[str, typer.Option(help="energy-momentum (default here) or variational.")] = "energy-momentum",
    workers: Annotated[int, typer.Option(help="Local worker processes for the forward simulations.")] = 2,
    scheduler: Annotated[
        str | None, typer.Option(help="Address of an existing Dask scheduler (e.g. tcp://host:8786).")
    ] = None,
    overwrite: Annotated[bool, typer.Option("--overwrite", help="Start a new study even if --out exists.")] = False,
) -> None:
    """FRV-GFA (thesis §2.7, §5.7): a leg parameter as a fuzzy random variable, grouped
    samples, Graph Follower hulls on the occurring intervals only, output samples and
    their counts in a chunked zarr store."""
    from fuzzygait.mechanics.fuzzy_dynamics import leg_frv_study
    from fuzzygait.mechanics.leg import LEG_PARAMETERS
    from fuzzygait.mechanics.scenarios import SCENARIOS
    from fuzzygait.uncertainty.frv import FRVSpec

    with _user_errors():
        if scenario not in SCENARIOS:
            raise FuzzyGaitError(f"unknown scenario {scenario!r}; choose {' or '.join(SCENARIOS)}")
        if out_store.suffix.lower() != ".zarr":
            raise FuzzyGaitError(f"{out_store}: --out must be a .zarr directory")
        if parameter not in LEG_PARAMETERS:
            raise FuzzyGaitError(f"--frv {parameter!r}: unknown parameter; known: {', '.join(LEG_PARAMETERS)}")
        values = _parse_overrides(overrides or [])
        levels = _parse_alphas(alphas)
        if value is not None:
            values[parameter] = value
        from fuzzygait.mechanics.leg import default_parameters

        preset = SCENARIOS[scenario]
        p_det = values.get(parameter, float(default_parameters(preset.material, shank_mass=preset.shank_mass)[
            LEG_PARAMETERS.index(parameter)]))  # fmt: skip
        spec = FRVSpec(parameter, p_det, alphas=levels, distribution=distribution)
        out_store.parent.mkdir(parents=True, exist_ok=True)
        with _progress_bars() as bars:
            bars.add_task(f"{scenario}: FRV-GFA ({samples} samples)", total=None)
            study = leg_frv_study(scenario, spec, samples, out_store, target=target, base_overrides=values,
                                  n_disc=disc, seed=seed, nodes=nodes, dt=dt, duration=duration, scheme=scheme,
                                  workers=workers, scheduler=scheduler, overwrite=overwrite)  # fmt: skip
    counts = study.counts
    out.print(
        f"{scenario}: {counts.get('samples')} samples; occurring intervals {counts.get('occurring_intervals')} of "
        f"{counts.get('possible_intervals')} possible; forward simulations {counts.get('forward_simulations')}; "
        f"interval optimisations {counts.get('interval_optimisations')}; wall time {counts.get('wall_time', 0):.1f} s",
        markup=False,
    )
    out.print(f"wrote {out_store}", markup=False)


def _print_simulation_summary(ds: object) -> None:
    import numpy as np
    import xarray as xr

    from fuzzygait.viz.mechanics import energy_drift

    assert isinstance(ds, xr.Dataset)
    attrs = ds.attrs
    iterations = np.asarray(ds["newton_iterations"].values)
    n_steps = iterations.size
    per_step = f"{iterations.mean():.2f} mean, {iterations.max()} max" if n_steps else "none"
    nodes = int(attrs.get("nodes", 0))
    out.print(
        f"{attrs.get('scenario')}: {n_steps} steps of {float(attrs['dt']):g} s to t = {float(attrs['duration']):g} s"
        + (f", {nodes} blade nodes" if nodes else "")
        + (f", {attrs['scheme']} scheme" if "scheme" in attrs else "")
        + f"; wall time {float(attrs.get('wall_time_s', np.nan)):.2f} s"
        + ("" if int(attrs.get("compiled", 0)) else " (not compiled)"),
        markup=False,
    )
    out.print(f"  Newton iterations per step: {per_step}", markup=False)
    out.print(f"  max internal energy: {float(ds['internal_energy'].max()):.4g} J", markup=False)
    drift = float(np.nanmax(np.abs(energy_drift(ds))))
    out.print(f"  energy drift max |total + dissipated − initial| / |initial|: {drift:.3g}", markup=False)


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
