"""Commands of the marker-error analysis: uncertainty (one trial's fuzzy joint angles) and
report (whole sessions, the clinicians' HTML report)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from fuzzygait.cli.app import EXIT_USER_ERROR, app, debugging, err, out, progress_bars, user_errors
from fuzzygait.cli.gait import print_run_summary
from fuzzygait.cli.options import (
    DEFAULT_CALIBRATION,
    DEFAULT_MARKER_ERRORS,
    DEFAULT_PREPROCESSING,
    CalibrationOptions,
    MarkerErrorOptions,
    ModelOption,
    PreprocessingOptions,
    SchedulerOption,
    check_model,
    estimated_stages,
    parse_alphas,
    parse_angles,
    with_option_groups,
)
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.paths import check_c3d_input

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

    from fuzzygait.markererror.result import MarkerErrorResult


#: ``--cop-error`` (mm) and ``--kinetic-tolerance`` (N·m/kg) defaults: the library's
#: (:data:`fuzzygait.markererror.moment_model.DEFAULT_COP_ERROR_MM`,
#: :data:`fuzzygait.markererror.fuzzy_kinetics.DEFAULT_TOLERANCE`; a test keeps them equal),
#: written out so the command line starts without importing the engine.
DEFAULT_COP_ERROR_MM = 10.0
DEFAULT_KINETIC_TOLERANCE = 0.1


@dataclass(frozen=True)
class EngineOptions:
    """How ``uncertainty`` computes the bands: ``--method`` of the marker deviations,
    ``--workers`` processes, and the opt-in fuzzy kinetics (``--kinetics``, its
    ``--cop-error`` ball and ``--kinetic-tolerance``)."""

    method: Annotated[str, typer.Option(help="cartesian or spherical marker deviations.")] = "cartesian"
    workers: Annotated[int, typer.Option(help="Processes for the angles.")] = 2
    kinetics: Annotated[
        bool, typer.Option("--kinetics/--no-kinetics",
                           help="Also the fuzzy sagittal joint moments and the joint powers of ankle, knee and hip "
                           "(both sides) when the trial has force plates: the same α-levels and error sources plus "
                           "a centre-of-pressure error ball per loaded plate; about doubles the command's time.")
    ] = False
    cop_error: Annotated[
        float, typer.Option("--cop-error", metavar="MM",
                            help="Centre-of-pressure error ball radius at α = 0, mm, in the plate's plane "
                            "(with --kinetics; default: corrected plate accuracy, see docs/kinetics.md).")
    ] = DEFAULT_COP_ERROR_MM
    kinetic_tolerance: Annotated[
        float, typer.Option("--kinetic-tolerance", metavar="NM_PER_KG",
                            help="Moment tolerance, ± N·m/kg, of the allowable-error answer (with --kinetics).")
    ] = DEFAULT_KINETIC_TOLERANCE

    def check(self) -> None:
        """One line for a bad ``--workers``, ``--cop-error`` or ``--kinetic-tolerance``."""
        import math

        _check_workers(self.workers)
        if not (math.isfinite(self.cop_error) and self.cop_error >= 0):
            raise FuzzyGaitError(f"--cop-error must be a distance ≥ 0 mm; got {self.cop_error}")
        if not (math.isfinite(self.kinetic_tolerance) and self.kinetic_tolerance > 0):
            raise FuzzyGaitError(f"--kinetic-tolerance must be a number of N·m/kg > 0; got {self.kinetic_tolerance}")


@dataclass(frozen=True)
class ReportContentOptions:
    """What ``report`` shows: the ``--uncertainty`` bands, a ``--pdf`` beside the pages,
    the ``--normative`` reference curves and the fuzzy ``--kinetics``."""

    uncertainty: Annotated[
        str, typer.Option(help="none: the angles only (seconds per trial); fast: the α = 0 and 0.5 bands of hip, "
                          "knee and ankle angles; full: the marker-error analysis of the options below.")
    ] = "full"
    pdf: Annotated[bool, typer.Option("--pdf", help="Also a PDF (A4) of every trial page and session page.")] = False
    normative: Annotated[
        Path | None, typer.Option("--normative", metavar="NORM.csv",
                                  help="Normative mean/SD per % gait cycle (see README 'Normative data').")
    ] = None
    kinetics: Annotated[
        bool, typer.Option("--kinetics/--no-kinetics",
                           help="With --uncertainty fast or full: also the fuzzy sagittal joint moments and powers of "
                           "trials with force plates, their bands on the kinetic figures (as uncertainty --kinetics, "
                           "default centre-of-pressure error and tolerance); about doubles the uncertainty's time.")
    ] = False


@dataclass(frozen=True)
class BatchRunOptions:
    """How ``report`` runs its trials: ``--workers`` (a local Dask pool) or a
    ``--scheduler``, and ``--force`` to recompute unchanged trials."""

    workers: Annotated[int, typer.Option(help="Processes for the trials (a local Dask pool; one trial: for its "
                                         "angle components).")] = 2
    scheduler: SchedulerOption = None
    force: Annotated[bool, typer.Option("--force", help="Recompute trials whose inputs and options are unchanged "
                                        "since the last run on --out (they are skipped otherwise).")] = False


DEFAULT_ENGINE = EngineOptions()
DEFAULT_REPORT_CONTENTS = ReportContentOptions()
DEFAULT_BATCH_RUN = BatchRunOptions()


def _check_workers(workers: int) -> None:
    if workers < 1:
        raise FuzzyGaitError(f"--workers must be at least 1; got {workers}")


# --------------------------------------------------------------------------- uncertainty
@app.command(short_help="Fuzzy joint angles from fuzzy marker errors.")
@with_option_groups
def uncertainty(
    dynamic: Annotated[Path, typer.Argument(metavar="DYNAMIC.c3d", help="Walking trial.")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Fuzzy joint angles, .nc or .zarr.")],
    calibration: CalibrationOptions = DEFAULT_CALIBRATION,
    marker_errors: MarkerErrorOptions = DEFAULT_MARKER_ERRORS,
    engine: EngineOptions = DEFAULT_ENGINE,
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write a Rerun recording (.rrd).")] = None,
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
    model: ModelOption = "auto",
) -> None:
    """Fuzzy joint angles from fuzzy marker errors: per frame and α-level the range of
    every angle component over all marker deviations inside the α-level balls, by the
    model version of the angles (--model; the dataset's `model` attribute names it), the
    allowable marker error of each (--tolerance; its refined α-levels saved too) and the
    flexion bands of each error source alone (--per-source, the default)."""
    from fuzzygait.workflows.outputs import check_output_suffixes

    with user_errors():
        check_output_suffixes(out_file, rrd, {})
        engine.check()
        check_model(model)
        selected = parse_angles(marker_errors.angle_names)
        check_c3d_input(dynamic)
        calibration.check_files()
        from fuzzygait.workflows.marker_uncertainty import MarkerErrorRequest, MarkerErrorSettings, analyse_to_files
        from fuzzygait.workflows.trial_inputs import TrialInputs

        settings = MarkerErrorSettings.create(errors_file=marker_errors.errors, sources=marker_errors.sources,
                                              alphas=parse_alphas(marker_errors.alphas), angles=selected,
                                              method=engine.method, workers=engine.workers,
                                              tolerance=marker_errors.tolerance_deg(),
                                              per_source=marker_errors.per_source, kinetics=engine.kinetics,
                                              cop_error_mm=engine.cop_error,
                                              kinetic_tolerance=engine.kinetic_tolerance)  # fmt: skip
        inputs = TrialInputs(dynamic, static=calibration.static, subject_file=calibration.subject,
                             preprocessing=preprocessing.preprocessing(), flat_foot=calibration.flat_foot,
                             marker_diameter=calibration.marker_diameter, model=model)  # fmt: skip
        with progress_bars() as bars:
            bar = estimated_stages(bars)
            bar.stage("joint angles")
            analysis = analyse_to_files(MarkerErrorRequest(inputs, settings), out_file, rrd=rrd, stages=bar)
    print_run_summary(analysis.run)
    for note in analysis.notes[len(analysis.run.notes) :]:
        out.print(f"  note: {note.message}", markup=False)
    out.print("ΔΦ, relative envelope width (Eq. 5.3), % of the largest |angle|, over the determined frames "
              '("undetermined": a segment frame can flip at that α-level):', markup=False)  # fmt: skip
    out.print(_delta_phi_text(analysis.fuzzy, analysis.delta_phi), markup=False)
    if (allowable := _allowable_text(analysis.result)) is not None:
        out.print(allowable, markup=False)
    if (sources := _per_source_text(analysis.result)) is not None:
        out.print(sources, markup=False)
    if analysis.result is not None and analysis.result.kinetics is not None:
        out.print(kinetics_text(analysis.result.kinetics), markup=False)
    out.print(f"wrote {out_file}" + (f" and {rrd}" if rrd is not None else ""), markup=False)


def _delta_phi_text(fuzzy: xr.Dataset, delta_phi: pd.DataFrame) -> str:
    """The ΔΦ table, 1 decimal; "undetermined" where the α-level is undetermined at some
    frame (:func:`~fuzzygait.markererror.analysis.undetermined_levels`), "–" where no
    frame has a band."""
    import math

    import pandas as pd

    from fuzzygait.markererror.analysis import undetermined_levels

    flags = undetermined_levels(fuzzy).reindex(index=delta_phi.index, columns=delta_phi.columns, fill_value=False)
    values, undetermined = delta_phi.to_numpy(dtype=float), flags.to_numpy(dtype=bool)
    cells = [["undetermined" if flag else f"{value:.1f}" if math.isfinite(value) else "–"
              for value, flag in zip(row, row_flags, strict=True)]
             for row, row_flags in zip(values, undetermined, strict=True)]  # fmt: skip
    columns = [f"α = {float(a):g}" for a in delta_phi.columns]
    return pd.DataFrame(cells, index=delta_phi.index, columns=columns).to_string()


def _allowable_text(result: MarkerErrorResult | None) -> str | None:
    """The allowable-marker-error table (None without the refinement): per component the
    largest error on its largest ball (mm) and as % of Table 3.1, with its status."""
    from fuzzygait.viz.report.allowable import allowable_summary

    summary = allowable_summary(result)
    if summary is None or not summary.rows:
        return None
    header = ("", "angle", "mm", f"% of {summary.source}", "")
    rows = [header] + [(r.component, r.label, r.mm, r.percent, r.note) for r in summary.rows]
    widths = [max(len(row[k]) for row in rows) for k in range(len(header))]
    align = ("<", "<", ">", ">", "<")
    lines = ["  ".join(f"{cell:{a}{w}}" for cell, a, w in zip(row, align, widths, strict=True)).rstrip()
             for row in rows]  # fmt: skip
    title = (f"Allowable marker error for ±{summary.tolerance:g}°, the largest for which the angle stays within "
             f"it over the trial (mm on the largest ball, % of {summary.source}):")  # fmt: skip
    return "\n".join([title, *lines])


def _per_source_text(result: MarkerErrorResult | None) -> str | None:
    """The widest band of each flexion component per error source alone and all together
    (deg, over the determined frames; "undetermined (n)" when no frame is determined), and
    the source that dominates; None without per-source bands."""
    import math

    from fuzzygait.markererror.per_source import ALL, has_source_bands, widest_source_bands

    if result is None or not has_source_bands(result):
        return None
    table = widest_source_bands(result)
    columns = [*table.sources, ALL]
    header = ("", *columns, "dominates")
    rows = [header]
    for component in table.widths.index:
        cells = []
        for source in columns:
            width, flipped = table.width(component, source), table.frames_undetermined(component, source)
            text = f"{width:.1f}" if math.isfinite(width) else "undetermined" if flipped else "–"
            cells.append(text + (f" ({flipped} undet.)" if flipped and math.isfinite(width) else ""))
        rows.append((str(component), *cells, table.dominant(str(component)) or "–"))
    widths = [max(len(row[k]) for row in rows) for k in range(len(header))]
    lines = ["  ".join(f"{cell:{'<' if k in (0, len(header) - 1) else '>'}{w}}"
                       for k, (cell, w) in enumerate(zip(row, widths, strict=True))).rstrip()
             for row in rows]  # fmt: skip
    title = (f"Widest α = {table.alpha:g} band per error source alone and all together (deg, determined frames; "
             "Fig. 5.9):")  # fmt: skip
    return "\n".join([title, *lines])


def kinetics_text(kinetics: xr.Dataset) -> str:
    """What ``uncertainty --kinetics`` prints: the ΔΦ table of the fuzzy moments and of the
    powers (as the angles': % of the largest |value|, "undetermined" where a segment frame
    can flip at that α-level) and each moment's allowable-error sentence."""
    from fuzzygait.markererror.analysis import relative_envelope_width
    from fuzzygait.markererror.fuzzy_kinetics import allowable_kinetic_error
    from fuzzygait.markererror.result import UNITS_COORD, kinetic_part

    lines = []
    for units in dict.fromkeys(str(u) for u in kinetics[UNITS_COORD].to_numpy()):
        part = kinetic_part(kinetics, units)
        what = "joint moments" if units == "N·m/kg" else "joint powers"
        lines += [f"Fuzzy {what} ({units}), ΔΦ, % of the largest |value|, over the determined frames:",
                  _delta_phi_text(part, relative_envelope_width(part).rename_axis("output"))]  # fmt: skip
    tolerance = float(kinetics.attrs["kinetic_tolerance"])
    moments = kinetic_part(kinetics, "N·m/kg") if "N·m/kg" in kinetics[UNITS_COORD].to_numpy().astype(str) else None
    if moments is not None:
        lines.append(f"Allowable error for ±{tolerance:g} N·m/kg (the largest Table 3.1 and centre-of-pressure "
                     f"balls, among the α-levels, for which the moment stays within it on every frame):")  # fmt: skip
        lines += [f"  {allowable_kinetic_error(moments, str(c), tolerance).sentence}"
                  for c in moments["component"].to_numpy()]  # fmt: skip
    return "\n".join(lines)


# --------------------------------------------------------------------------- report
@app.command(short_help="Clinicians' HTML report of whole sessions.")
@with_option_groups
def report(
    inputs: Annotated[
        list[Path],
        typer.Argument(metavar="INPUT", help="Session folders (a folder per visit: static trial, walking trials, "
                       ".vsk/.toml/.mp/session.xml subject file; or a folder of such folders) or walking-trial "
                       "C3D files."),
    ],
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="Report folder (index.html, a folder per session).")],
    calibration: CalibrationOptions = DEFAULT_CALIBRATION,
    contents: ReportContentOptions = DEFAULT_REPORT_CONTENTS,
    marker_errors: MarkerErrorOptions = DEFAULT_MARKER_ERRORS,
    batch: BatchRunOptions = DEFAULT_BATCH_RUN,
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
    model: ModelOption = "auto",
) -> None:
    """Clinicians' HTML report of whole sessions: per session folder its static trial, subject file and
    walking trials are found (the static trial by its static-only markers, its file name or its near-zero
    motion: the page says which), one page per trial, one session summary page (mean ± SD over all cycles
    of all trials per side) and one index across sessions.

    Trials run in parallel (--workers, --scheduler); a trial that fails is listed with its error while the
    others are still reported; a re-run on the same --out skips unchanged trials (--force recomputes).
    Exit code 0 when at least one trial succeeded, 1 when all failed.
    """
    def failed(path: Path, error: str) -> None:
        where = "" if path.name in error else f"{path}: "
        err.print(f"fuzzygait: failed: {where}{error}", markup=False)

    with user_errors():
        alpha_levels = parse_alphas(marker_errors.alphas)
        _check_workers(batch.workers)
        check_model(model)
        calibration.check_files()
        from fuzzygait.workflows.batch_report import BatchReportRequest, write_batch_report
        from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings
        from fuzzygait.workflows.work_estimate import report_work

        normative = contents.normative
        settings = MarkerErrorSettings.create(errors_file=marker_errors.errors, sources=marker_errors.sources,
                                              alphas=alpha_levels, angles=parse_angles(marker_errors.angle_names),
                                              workers=batch.workers, tolerance=marker_errors.tolerance_deg(),
                                              per_source=marker_errors.per_source,
                                              kinetics=contents.kinetics)  # fmt: skip
        # checked when made: one clear line for a bad --uncertainty, --marker-diameter..., before any work
        request = BatchReportRequest(
            inputs, out_dir, static=calibration.static, subject_file=calibration.subject,
            marker_diameter=calibration.marker_diameter, flat_foot=calibration.flat_foot,
            preprocessing=preprocessing.preprocessing(), settings=settings, uncertainty=contents.uncertainty,
            model=model, pdf=contents.pdf, workers=batch.workers, scheduler=batch.scheduler, force=batch.force,
            normative=normative, strict=debugging(),
        )  # fmt: skip
        analysed = request.analysis()
        with progress_bars() as bars:
            stages = estimated_stages(bars)
            if analysed is not None:  # the work, before any trial is read
                stages.estimate(report_work(inputs, analysed, static=calibration.static,
                                            subject_file=calibration.subject, force=batch.force))  # fmt: skip
            result = write_batch_report(request, trials=stages, on_failure=failed)
    for summary in result.sessions:
        for warning in summary.warnings:
            err.print(f"fuzzygait: warning: {summary.name}/{warning}", markup=False)
    skipped = f", {result.n_skipped} unchanged (reused; --force recomputes)" if result.n_skipped else ""
    out.print(f"report: {len(result.sessions)} session(s), {result.n_ok} of {len(result.entries)} trials OK"
              + (f", {result.n_failed} failed" if result.n_failed else "") + skipped, markup=False)  # fmt: skip
    out.print(f"wrote {result.index}", markup=False)
    if result.n_ok == 0:
        raise typer.Exit(EXIT_USER_ERROR)
