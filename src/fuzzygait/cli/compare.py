"""Command comparing our angles with the ones a trial already stores: compare."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from fuzzygait.cli.app import app, err, out, user_errors
from fuzzygait.cli.options import (
    DEFAULT_CALIBRATION,
    DEFAULT_PREPROCESSING,
    CalibrationOptions,
    KneeAnkleCentresOption,
    PreprocessingOptions,
    check_knee_ankle_centres,
    with_option_groups,
)
from fuzzygait.core.paths import check_c3d_input, check_table_path

_PLANES = {"X": "sagittal", "Y": "frontal", "Z": "transverse"}


@app.command(short_help="Our joint angles against the ones the file stores.")
@with_option_groups
def compare(
    dynamic: Annotated[Path, typer.Argument(metavar="TRIAL.c3d", help="A trial holding another tool's angles.")],
    calibration: CalibrationOptions = DEFAULT_CALIBRATION,
    preprocessing: PreprocessingOptions = DEFAULT_PREPROCESSING,
    model: Annotated[
        str, typer.Option("--model", help="Model version to compare (as for `angles`; default auto).")
    ] = "auto",
    knee_ankle_centres: KneeAnkleCentresOption = None,
    out_table: Annotated[
        Path | None, typer.Option("--out", "-o", help="The table as .csv or .parquet (one row per component).")
    ] = None,
) -> None:
    """Our joint angles against the ones the file already stores (Vicon Nexus' Plug-in
    Gait, pyCGM2's): RMS and largest difference per component, ours computed on the
    file's own markers with the same subject parameters; differences over 0.1° flagged
    with their likeliest cause (marker diameter, subject values, static offsets)."""
    with user_errors():
        if out_table is not None:
            check_table_path(out_table)
        check_knee_ankle_centres(knee_ankle_centres)
        check_c3d_input(dynamic)
        calibration.check_files()
        from fuzzygait.workflows.compare import compare_trial
        from fuzzygait.workflows.trial_inputs import TrialInputs

        inputs = TrialInputs(dynamic, static=calibration.static, subject_file=calibration.subject,
                             preprocessing=preprocessing.preprocessing(), flat_foot=calibration.flat_foot,
                             marker_diameter=calibration.marker_diameter, model=model,
                             knee_ankle_centres=knee_ankle_centres)  # fmt: skip
        comparison = compare_trial(inputs, out_table)
    run, check = comparison.run, comparison.check
    for warning in run.warnings:
        err.print(f"fuzzygait: warning: {warning}", markup=False)
    table = Table(title=f"{run.raw.name} ({run.model}): ours minus the file's stored angles, deg",
                  title_justify="left")  # fmt: skip
    table.add_column("angle", no_wrap=True)
    table.add_column("component")
    if check.prefixed:
        table.add_column("stored as", no_wrap=True)
    table.add_column("frames", justify="right")
    table.add_column("RMS", justify="right")
    table.add_column("max", justify="right")
    for row in check.rows:
        flag = " !" if row.max > comparison.flag_deg else ""
        stored = (row.stored,) if check.prefixed else ()
        table.add_row(row.angle, _PLANES[row.axis], *stored, str(row.frames), f"{row.rms:.4f}", f"{row.max:.4f}{flag}")
    out.print(table)
    for note in check.notes():
        out.print(note.message, markup=False)
    if run.diameter is not None:
        out.print(run.diameter.note.message, markup=False)
    if comparison.written is not None:
        out.print(f"wrote {comparison.written}", markup=False)
