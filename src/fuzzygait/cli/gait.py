"""Commands on gait trials: info, preprocess, calibrate, angles, demo, uncertainty, report."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from fuzzygait.cli.app import (
    EXIT_USER_ERROR,
    app,
    debugging,
    err,
    out,
    progress_bars,
    progress_over,
    user_errors,
)
from fuzzygait.cli.options import (
    DEFAULT_CALIBRATION,
    DEFAULT_MARKER_ERRORS,
    DEFAULT_PREPROCESSING,
    CalibrationOptions,
    FlatFootOption,
    KneeAnkleCentresOption,
    MarkerDiameterOption,
    MarkerErrorOptions,
    MaxGapOption,
    ModelOption,
    PreprocessingOptions,
    SchedulerOption,
    StaticOption,
    SubjectOption,
    check_knee_ankle_centres,
    check_model,
    estimated_stages,
    parse_alphas,
    parse_angles,
    with_option_groups,
)
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import FindingKind

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

    from fuzzygait.io.subject import SubjectParameters
    from fuzzygait.workflows.angles import AnglesRun


def _check_workers(workers: int) -> None:
    if workers < 1:
        raise FuzzyGaitError(f"--workers must be at least 1; got {workers}")


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
            with user_errors():
                out.print(describe_trial(read_c3d(path)), markup=False)
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
    from fuzzygait.mocap.gaps import METHODS, methods_used
    from fuzzygait.workflows.angles import Preprocessing, preprocess_file

    with user_errors():
        if out_file.suffix.lower() != ".c3d":
            raise FuzzyGaitError(f"{out_file}: --out must name a .c3d file")
        if fill_method not in METHODS:
            raise FuzzyGaitError(f"--fill-method must be one of {', '.join(METHODS)}; got {fill_method!r}")
        options = Preprocessing(max_gap=max_gap, cutoff=cutoff, filter=not no_filter, fill_method=fill_method,
                                labelled_only=False)  # fmt: skip
        trial, gaps = preprocess_file(input_file, out_file, options)
    n_filled = sum(g.filled for g in gaps)
    by_method = methods_used(gaps)
    out.print(
        f"{input_file.name}: filled {n_filled} of {len(gaps)} gaps"
        + (f" ({by_method})" if by_method else "")
        + ("" if no_filter else f", low-pass {cutoff:g} Hz")
        + f" -> {out_file}",
        markup=False,
    )
    for gap in (g for g in gaps if not g.filled):
        out.print(
            f"  not filled: {gap.marker} frames {trial.first_frame + gap.start}"
            f"-{trial.first_frame + gap.start + gap.length - 1} ({gap.reason})",
            markup=False,
        )
    for note in trial.notes:  # the reader's and the content checks' (the gap/filter ones are above)
        if note.kind not in (FindingKind.GAP_FILLING, FindingKind.LOW_PASS):
            out.print(f"  note: {note.message}", markup=False)


# --------------------------------------------------------------------------- calibrate
#: The calibrated values ``calibrate`` prints per side (SideParameters field, Vicon name).
_CALIBRATED = (("thigh_rotation", "ThighRotation"), ("shank_rotation", "ShankRotation"),
               ("tibial_torsion", "TibialTorsion"), ("ankle_abadd", "AnkleAbAdd"),
               ("static_plant_flex", "StaticPlantFlex"), ("static_rot_off", "StaticRotOff"))  # fmt: skip


@app.command()
@with_option_groups
def calibrate(
    static: Annotated[Path, typer.Argument(metavar="STATIC.c3d", help="Static (standing) trial.")],
    out_file: Annotated[
        Path, typer.Option("--out", "-o", help="Calibrated subject parameters, .toml or .vsk.")
    ],
    subject: SubjectOption = None,
    flat_foot: FlatFootOption = None,
    marker_diameter: MarkerDiameterOption = None,
    max_gap: MaxGapOption = 10,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            help="Model to calibrate for: cgm1.0 (Plug-in Gait; its offsets serve cgm1.1 and cgm2.1 too), "
            "cgm2.3 (also the thigh/shank clusters), cgm2.4 (also the forefoot) or auto: a cluster model when "
            "the static trial has the clusters (THAP, THAD, TIAP, TIAD) and KNM/MED (cgm2.4 with FMH/SMH/VMH), "
            "else cgm1.0.",
        ),
    ] = "auto",
    knee_ankle_centres: KneeAnkleCentresOption = None,
) -> None:
    """Static calibration to a subject file: every value a Nexus static run stores
    (ThighRotation, ShankRotation, TibialTorsion, AnkleAbAdd, StaticPlantFlex,
    StaticRotOff, InterAsisDistance when absent), the method (plain, KAD or KAD+MED, told
    by the static trial's markers) and, for a cluster model, the cluster calibration (in
    the TOML file; beside a .vsk in OUT.clusters.toml). Gaps are filled; a static trial is
    not low-pass filtered (each offset is a mean over its frames). `angles --subject OUT`
    then gives what `angles --static STATIC.c3d` gives."""
    from fuzzygait.workflows.angles import Preprocessing
    from fuzzygait.workflows.calibrate import calibrate_to_file

    with user_errors():
        check_knee_ankle_centres(knee_ankle_centres)
        written = calibrate_to_file(static, out_file, subject_file=subject, marker_diameter=marker_diameter,
                                    preprocessing=Preprocessing(max_gap=max_gap), flat_foot=flat_foot,
                                    model=model, knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    calibration = written.calibration
    for warning in written.warnings:
        err.print(f"fuzzygait: warning: {warning}", markup=False)
    out.print(f"model {written.model} ({written.why})", markup=False)
    out.print(calibration.describe(), markup=False)
    for note in written.notes:
        out.print(f"  note: {note.message}", markup=False)
    for note in calibration.notes:  # the content checks' notes on the static trial
        out.print(f"  note: {note.message}", markup=False)
    _print_calibrated(calibration.subject)
    if calibration.clusters is not None:
        segments = sorted(calibration.clusters.segments.items(), key=lambda item: ("LR".index(item[0][0]), item[0][1]))
        out.print("  clusters: " + ", ".join(f"{side} {name} ({len(cluster.markers)} markers)"
                                             for (side, name), cluster in segments), markup=False)  # fmt: skip
    for path in written.removed:
        out.print(f"removed {path} (a cluster calibration of an earlier run; this one has none)", markup=False)
    for path in written.files:
        out.print(f"wrote {path}", markup=False)


def _print_calibrated(subject: SubjectParameters) -> None:
    """The calibrated offsets per side (degrees) and the inter-ASIS distance."""
    import math

    for side in "LR":
        values = subject.side(side)
        out.print(f"  {side}: " + ", ".join(f"{vicon} {math.degrees(getattr(values, name)):.4f}°"
                                            for name, vicon in _CALIBRATED), markup=False)  # fmt: skip
    if subject.inter_asis_distance is not None:
        out.print(f"  InterAsisDistance {subject.inter_asis_distance:.3f} mm", markup=False)


# --------------------------------------------------------------------------- angles
@app.command()
@with_option_groups
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
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
    flat_foot: FlatFootOption = None,
    marker_diameter: MarkerDiameterOption = None,
    model: Annotated[
        str,
        typer.Option(
            "--model",
            help="cgm1.0 (Plug-in Gait), cgm1.1, cgm2.1 (Hara hips), cgm2.3 (clusters; needs --static, or "
            "--subject written by `calibrate --model cgm2.3`), cgm2.4 (also the forefoot: ForeFootAngles) or "
            "auto: the richest the markers support (without --static: the model of the --subject file's "
            "cluster calibration, if any).",
        ),
    ] = "auto",
    suffix: Annotated[
        str,
        typer.Option(
            "--suffix",
            help="Appended to the angle output names in --c3d-out (e.g. _CGM_2.3, or 'model': the model's "
            "pyCGM2 suffix); default none: Vicon's names (LKneeAngles).",
        ),
    ] = "",
    knee_ankle_centres: KneeAnkleCentresOption = None,
) -> None:
    """Lower-body joint angles (degrees) of a walking trial by a Conventional Gait Model
    version (Plug-in Gait for a Plug-in Gait marker set). Every output names the model:
    a last column `model` in the tables (Parquet: also its metadata), the FUZZYGAIT:MODEL
    parameter in the C3D."""
    from fuzzygait.io.tables import check_table_path
    from fuzzygait.workflows.angles import AngleOutputs, angles_to_files, output_suffix

    with user_errors():
        for path, option in ((out_table, "--out"), (cycles, "--cycles")):
            if path is not None:
                check_table_path(path, option)
        if c3d_out is not None and c3d_out.suffix.lower() != ".c3d":
            raise FuzzyGaitError(f"{c3d_out}: --c3d-out must name a .c3d file")
        output_suffix(suffix, "cgm1.0")  # checked before any work
        check_knee_ankle_centres(knee_ankle_centres)
        run, written = angles_to_files(
            dynamic,
            AngleOutputs(table=out_table, cycles=cycles, c3d=c3d_out, suffix=suffix),
            static=static,
            subject_file=subject,
            preprocessing=preprocessing.preprocessing(),
            flat_foot=flat_foot,
            marker_diameter=marker_diameter,
            model=model,
            knee_ankle_centres=knee_ankle_centres,
        )
    _print_run_summary(run)
    for path in written:
        out.print(f"wrote {path}", markup=False)


def _print_run_summary(run: AnglesRun) -> None:
    """One line on the trial and the angles computed, then the run's notes; its warnings
    on stderr first."""
    for warning in run.warnings:
        err.print(f"fuzzygait: warning: {warning}", markup=False)
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
        out.print(f"  note: {note.message}", markup=False)


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
    """The main job on the bundled sample: Plug-in Gait angles, gait cycles, fuzzy marker-error
    bands, a report, a plot and a summary, and the CGM 2.4 session by the model --model auto
    picks (cgm2.4) checked against its known angles."""
    from fuzzygait.workflows.demo import run_demo

    with user_errors():
        summary = run_demo(data, out_dir, progress=err)
    out.print(summary, markup=False)


# --------------------------------------------------------------------------- uncertainty
@app.command()
@with_option_groups
def uncertainty(
    dynamic: Annotated[Path, typer.Argument(metavar="DYNAMIC.c3d", help="Walking trial.")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Fuzzy joint angles, .nc or .zarr.")],
    calibration: CalibrationOptions = DEFAULT_CALIBRATION,
    marker_errors: MarkerErrorOptions = DEFAULT_MARKER_ERRORS,
    method: Annotated[str, typer.Option(help="cartesian or spherical marker deviations.")] = "cartesian",
    rrd: Annotated[Path | None, typer.Option("--rrd", help="Also write a Rerun recording (.rrd).")] = None,
    workers: Annotated[int, typer.Option(help="Processes for the angles.")] = 2,
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
    model: ModelOption = "auto",
) -> None:
    """Fuzzy joint angles from fuzzy marker errors: per frame and α-level the range of
    every angle component over all marker deviations inside the α-level balls, by the
    model version of the angles (--model; the dataset's `model` attribute names it), the
    allowable marker error of each (--tolerance; its refined α-levels saved too) and the
    flexion bands of each error source alone (--per-source, the default)."""
    from fuzzygait.uncertainty.storage import SUFFIXES
    from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_to_files

    with user_errors():
        if out_file.suffix.lower() not in SUFFIXES:
            raise FuzzyGaitError(f"{out_file}: --out must end in .nc or .zarr")
        if rrd is not None and rrd.suffix.lower() != ".rrd":
            raise FuzzyGaitError(f"{rrd}: --rrd must end in .rrd")
        _check_workers(workers)
        check_model(model)
        selected = parse_angles(marker_errors.angle_names)
        settings = MarkerErrorSettings.create(errors_file=marker_errors.errors, sources=marker_errors.sources,
                                              alphas=parse_alphas(marker_errors.alphas), angles=selected,
                                              method=method, workers=workers,
                                              tolerance=marker_errors.tolerance_deg(),
                                              per_source=marker_errors.per_source)  # fmt: skip
        with progress_bars() as bars:
            bar = estimated_stages(bars)
            bar.stage("joint angles")
            analysis = analyse_to_files(
                dynamic, out_file, rrd=rrd, static=calibration.static, subject_file=calibration.subject,
                marker_diameter=calibration.marker_diameter, flat_foot=calibration.flat_foot, settings=settings,
                preprocessing=preprocessing.preprocessing(), model=model, stages=bar,
            )  # fmt: skip
    _print_run_summary(analysis.run)
    for note in analysis.notes[len(analysis.run.notes) :]:
        out.print(f"  note: {note.message}", markup=False)
    out.print("ΔΦ, relative envelope width (Eq. 5.3), % of the largest |angle|, over the determined frames "
              '("undetermined": a segment frame can flip at that α-level):', markup=False)  # fmt: skip
    out.print(_delta_phi_text(analysis.fuzzy, analysis.delta_phi), markup=False)
    if (allowable := _allowable_text(analysis.fuzzy)) is not None:
        out.print(allowable, markup=False)
    if (sources := _per_source_text(analysis.fuzzy)) is not None:
        out.print(sources, markup=False)
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


def _allowable_text(fuzzy: xr.Dataset) -> str | None:
    """The allowable-marker-error table (None without the refinement): per component the
    largest error on its largest ball (mm) and as % of Table 3.1, with its status."""
    from fuzzygait.viz.report.allowable import allowable_summary

    summary = allowable_summary(fuzzy)
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


def _per_source_text(fuzzy: xr.Dataset) -> str | None:
    """The widest band of each flexion component per error source alone and all together
    (deg, over the determined frames; "undetermined (n)" when no frame is determined), and
    the source that dominates; None without per-source bands."""
    import math

    from fuzzygait.markererror.per_source import ALL, has_source_bands, widest_source_bands

    if not has_source_bands(fuzzy):
        return None
    table = widest_source_bands(fuzzy)
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


# --------------------------------------------------------------------------- report
@app.command()
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
    uncertainty: Annotated[
        str, typer.Option(help="none: the angles only (seconds per trial); fast: the α = 0 and 0.5 bands of hip, "
                          "knee and ankle angles; full: the marker-error analysis of the options below.")
    ] = "full",
    marker_errors: MarkerErrorOptions = DEFAULT_MARKER_ERRORS,
    workers: Annotated[int, typer.Option(help="Processes for the trials (a local Dask pool; one trial: for its "
                                         "angle components).")] = 2,
    scheduler: SchedulerOption = None,
    pdf: Annotated[bool, typer.Option("--pdf", help="Also a PDF (A4) of every trial page and session page.")] = False,
    force: Annotated[bool, typer.Option("--force", help="Recompute trials whose inputs and options are unchanged "
                                        "since the last run on --out (they are skipped otherwise).")] = False,
    normative: Annotated[
        Path | None, typer.Option("--normative", metavar="NORM.csv",
                                  help="Normative mean/SD per % gait cycle (see README 'Normative data').")
    ] = None,
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
    from fuzzygait.workflows.batch_report import write_batch_report
    from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings
    from fuzzygait.workflows.trial_job import mode_settings
    from fuzzygait.workflows.work_estimate import report_work

    def failed(path: Path, error: str) -> None:
        where = "" if path.name in error else f"{path}: "
        err.print(f"fuzzygait: failed: {where}{error}", markup=False)

    with user_errors():
        alpha_levels = parse_alphas(marker_errors.alphas)
        _check_workers(workers)
        check_model(model)
        if normative is not None and not normative.is_file():
            raise FuzzyGaitError(f"{normative}: no such normative file; check the path (--normative)")
        settings = MarkerErrorSettings.create(errors_file=marker_errors.errors, sources=marker_errors.sources,
                                              alphas=alpha_levels, angles=parse_angles(marker_errors.angle_names),
                                              workers=workers, tolerance=marker_errors.tolerance_deg(),
                                              per_source=marker_errors.per_source)  # fmt: skip
        analysed = mode_settings(uncertainty, settings)  # one clear line for a bad --uncertainty, before any work
        with progress_bars() as bars:
            stages = estimated_stages(bars)
            if analysed is not None:  # the work, before any trial is read
                stages.estimate(report_work(inputs, analysed, static=calibration.static,
                                            subject_file=calibration.subject, force=force))  # fmt: skip
            result = write_batch_report(
                inputs, out_dir, static=calibration.static, subject_file=calibration.subject,
                marker_diameter=calibration.marker_diameter, flat_foot=calibration.flat_foot, settings=settings,
                uncertainty=uncertainty, preprocessing=preprocessing.preprocessing(), model=model, pdf=pdf,
                workers=workers, scheduler=scheduler, force=force, normative=normative, strict=debugging(),
                trials=stages, on_failure=failed,
            )  # fmt: skip
    for summary in result.sessions:
        for warning in summary.warnings:
            err.print(f"fuzzygait: warning: {summary.name}/{warning}", markup=False)
    skipped = f", {result.n_skipped} unchanged (reused; --force recomputes)" if result.n_skipped else ""
    out.print(f"report: {len(result.sessions)} session(s), {result.n_ok} of {len(result.entries)} trials OK"
              + (f", {result.n_failed} failed" if result.n_failed else "") + skipped, markup=False)  # fmt: skip
    out.print(f"wrote {result.index}", markup=False)
    if result.n_ok == 0:
        raise typer.Exit(EXIT_USER_ERROR)
