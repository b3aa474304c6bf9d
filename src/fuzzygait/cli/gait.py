"""Commands on gait trials: info, preprocess, calibrate, angles, demo (uncertainty and report:
:mod:`fuzzygait.cli.marker_errors`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from fuzzygait.cli.app import (
    EXIT_USER_ERROR,
    app,
    err,
    out,
    progress_over,
    user_errors,
)
from fuzzygait.cli.options import (
    DEFAULT_CALIBRATION,
    DEFAULT_PREPROCESSING,
    CalibrationOptions,
    FlatFootOption,
    KneeAnkleCentresOption,
    MarkerDiameterOption,
    MaxGapOption,
    PreprocessingOptions,
    SubjectOption,
    check_calibration_files,
    check_knee_ankle_centres,
    with_option_groups,
)
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import FindingKind
from fuzzygait.core.options import Option
from fuzzygait.core.paths import (
    check_c3d_input,
    check_c3d_path,
    check_not_input,
    check_subject_path,
    check_table_path,
)

if TYPE_CHECKING:
    from fuzzygait.io.subject import SubjectParameters
    from fuzzygait.workflows.angles import AnglesRun


# --------------------------------------------------------------------------- info
@app.command(short_help="Summarise C3D files: rate, frames, markers, gaps, events.")
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
@app.command(short_help="Fill marker gaps, low-pass filter (zero-lag Butterworth).")
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
    with user_errors():
        check_c3d_path(out_file)
        check_c3d_input(input_file)
        check_not_input(out_file, [input_file])
        from fuzzygait.mocap.gaps import METHODS, methods_used
        from fuzzygait.workflows.angles import Preprocessing, preprocess_file

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


@app.command(short_help="Static calibration to a subject file (.toml or .vsk).")
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
    with user_errors():
        check_subject_path(out_file)
        check_knee_ankle_centres(knee_ankle_centres)
        check_calibration_files(static, subject)
        from fuzzygait.workflows.angles import Preprocessing
        from fuzzygait.workflows.calibrate import calibrate_to_file

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
@dataclass(frozen=True)
class AngleFileOptions:
    """The files ``angles`` writes: ``--out`` (per frame), ``--c3d-out``, ``--cycles``,
    and the ``--suffix`` of the angle names in the C3D."""

    out_table: Annotated[
        Path | None, typer.Option("--out", "-o", help="Angles per frame, .csv or .parquet.")
    ] = None
    c3d_out: Annotated[
        Path | None, typer.Option("--c3d-out", help="C3D with markers, angles and virtual markers.")
    ] = None
    cycles: Annotated[
        Path | None, typer.Option("--cycles", help="Mean and SD over gait cycles, .csv or .parquet.")
    ] = None
    suffix: Annotated[
        str,
        typer.Option(
            "--suffix",
            help="Appended to the angle output names in --c3d-out (e.g. _CGM_2.3, or 'model': the model's "
            "pyCGM2 suffix); default none: Vicon's names (LKneeAngles).",
        ),
    ] = ""


DEFAULT_ANGLE_FILES = AngleFileOptions()


@app.command(short_help="Joint angles of a walking trial (Plug-in Gait, CGM 2.x).")
@with_option_groups
def angles(
    dynamic: Annotated[Path, typer.Argument(metavar="DYNAMIC.c3d", help="Walking trial.")],
    calibration: CalibrationOptions = DEFAULT_CALIBRATION,
    files: AngleFileOptions = DEFAULT_ANGLE_FILES,
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
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
    knee_ankle_centres: KneeAnkleCentresOption = None,
) -> None:
    """Lower-body joint angles (degrees) of a walking trial by a Conventional Gait Model
    version (Plug-in Gait for a Plug-in Gait marker set). Every output names the model:
    a last column `model` in the tables (Parquet: also its metadata), the FUZZYGAIT:MODEL
    parameter in the C3D."""
    with user_errors():
        for path, option in ((files.out_table, "--out"), (files.cycles, "--cycles")):
            if path is not None:
                check_table_path(path, option)
        if files.c3d_out is not None:
            check_c3d_path(files.c3d_out, Option.C3D_OUT)
        check_knee_ankle_centres(knee_ankle_centres)
        check_c3d_input(dynamic)
        calibration.check_files()
        if files.c3d_out is not None:
            check_not_input(files.c3d_out, [dynamic, calibration.static], Option.C3D_OUT)
        from fuzzygait.workflows.angles import AngleOutputs, angles_to_files, output_suffix
        from fuzzygait.workflows.trial_inputs import TrialInputs

        output_suffix(files.suffix, "cgm1.0")  # checked before any work
        trial = TrialInputs(dynamic, static=calibration.static, subject_file=calibration.subject,
                            preprocessing=preprocessing.preprocessing(), flat_foot=calibration.flat_foot,
                            marker_diameter=calibration.marker_diameter, model=model,
                            knee_ankle_centres=knee_ankle_centres)  # fmt: skip
        outputs = AngleOutputs(table=files.out_table, cycles=files.cycles, c3d=files.c3d_out, suffix=files.suffix)
        run, written = angles_to_files(trial, outputs)
    print_run_summary(run)
    for path in written:
        out.print(f"wrote {path}", markup=False)


def print_run_summary(run: AnglesRun) -> None:
    """One line on the trial and the angles computed, one on the kinetics when computed,
    then the run's notes (the kinetics' among them); its warnings on stderr first."""
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
    if run.kinetics is not None:  # plates used per side, contacts not used (each in the notes)
        out.print(f"  {run.kinetics.summary()}", markup=False)
    for note in run.notes:
        out.print(f"  note: {note.message}", markup=False)


# --------------------------------------------------------------------------- demo
@app.command(short_help="The main job on the bundled sample data.")
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
