"""Command on gait trials' timing and foot placement: gait-parameters."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from fuzzygait.cli.app import EXIT_USER_ERROR, app, err, out, user_errors
from fuzzygait.core.paths import check_table_path


@app.command("gait-parameters", short_help="Spatio-temporal parameters as Vicon Nexus names them.")
def gait_parameters(
    files: Annotated[list[Path], typer.Argument(metavar="TRIAL.c3d...", help="Walking trials with gait events.")],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Table to write (.csv or .parquet).")],
    cycles: Annotated[
        str,
        typer.Option(
            "--cycles",
            help="all: mean ± SD over every complete gait cycle of a side; nexus: the "
            "first complete cycle of each side, the one Vicon Nexus reports; workstation: "
            "the first cycle with Vicon Workstation's definitions (its step length is the "
            "opposite foot's step).",
        ),
    ] = "all",
) -> None:
    """Spatio-temporal parameters as Vicon Nexus names them (cadence, walking speed,
    stride/step time and length, foot off, single/double support), per trial and side.

    Events come from the file (else they are detected from the heel/toe markers);
    lengths from the toe markers at the foot strikes. One row per trial and side, units
    in the column names. A trial that fails gets one error line; the others are written.
    """
    with user_errors():
        check_table_path(out_file)
        from fuzzygait.gait.spatiotemporal import NAMES, column_name
        from fuzzygait.workflows.gait_parameters import gait_parameters_files

        run = gait_parameters_files(files, out_file, cycles)
    for message in run.failures:
        err.print(f"fuzzygait: error: {message}", markup=False)
    heading = {"nexus": "first complete cycle", "workstation": "first cycle, Vicon Workstation's definitions"}.get(
        cycles, "mean ± SD over complete cycles")
    for result in run.results:
        rows = run.table[run.table["trial"] == result.trial].to_dict("records")
        table = Table(title=f"{result.trial}: {heading} (events: {result.event_source})", title_justify="left")
        table.add_column("parameter")
        for row in rows:
            n = int(row["cycles"])
            table.add_column(f"{row['side']} ({n} cycle{'' if n == 1 else 's'})", justify="right")
        for name in NAMES:
            table.add_row(column_name(name), *(_cell(r[column_name(name)], r[column_name(name, "SD")]) for r in rows))
        out.print(table)
        for note in result.notes:
            out.print(f"{Path(result.trial).name}: {note.message}", markup=False)
    if run.out is not None:
        out.print(f"-> {run.out}", markup=False)
    if run.failures:
        if len(files) > 1:
            err.print(f"fuzzygait: {len(run.failures)} of {len(files)} trials failed", markup=False)
        raise typer.Exit(EXIT_USER_ERROR)


def _cell(value: float, sd: float) -> str:
    """``"1.159 ± 0.010"`` (3 decimals below 10, 2 below 100, else 1), ``"1.159"``
    without an SD, ``"-"`` when not computed."""
    if not math.isfinite(value):
        return "-"
    decimals = 1 if abs(value) >= 100 else 2 if abs(value) >= 10 else 3
    return f"{value:.{decimals}f}" + (f" ± {sd:.{decimals}f}" if math.isfinite(sd) else "")
