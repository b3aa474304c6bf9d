"""Command building a lab's normative data from its reference trials: normative."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fuzzygait.cli.app import EXIT_USER_ERROR, app, err, out, user_errors
from fuzzygait.cli.options import ModelOption, StaticOption, SubjectOption, check_model


@app.command("normative")
def normative(
    inputs: Annotated[
        list[Path],
        typer.Argument(metavar="TRIALS_OR_SESSIONS...", help="Reference walking trials (C3D) or session folders."),
    ],
    out_file: Annotated[Path, typer.Option("--out", "-o", help="Normative file to write (.csv).")],
    static: StaticOption = None,
    subject: SubjectOption = None,
    model: ModelOption = "auto",
    per_side: Annotated[
        bool,
        typer.Option("--per-side/--pooled", help="Keep left and right apart (default: pool both sides' cycles)."),
    ] = False,
) -> None:
    """Normative mean ± SD per % gait cycle and angle component from reference trials.

    Session folders are searched as `report` does (static trial, subject file, walking
    trials); files given directly use --static/--subject (else their PROCESSING group).
    Every gait cycle of every trial counts once; the file format is in docs/reports.md
    ("Normative data"). A trial that fails gets one error line; the others are used.
    """
    from fuzzygait.core.errors import FuzzyGaitError
    from fuzzygait.gait.normative import build_normative, normalised_cycles, write_normative
    from fuzzygait.workflows.angles import run_angles
    from fuzzygait.workflows.session import find_sessions

    with user_errors():
        check_model(model)
        if out_file.suffix.lower() != ".csv":
            raise FuzzyGaitError(f"{out_file}: the normative file is a .csv file")
        trials = [t for s in find_sessions(inputs, static, subject) for t in s.trials]
    stacks, failures, names = [], 0, []
    for trial in trials:
        try:
            run = run_angles(trial.path, static=trial.static, subject_file=trial.subject_file, model=model)
        except FuzzyGaitError as exc:
            err.print(f"fuzzygait: error: {exc}", markup=False)
            failures += 1
            continue
        except Exception as exc:  # noqa: BLE001 - a bug in one trial: listed, the others used
            err.print(f"fuzzygait: error: {trial.path}: internal error {type(exc).__name__}: {exc}", markup=False)
            failures += 1
            continue
        stacks.append(normalised_cycles(run.result.angles, run.trial, run.events))
        names.append(trial.path.name)
    with user_errors():
        if not stacks:
            raise FuzzyGaitError("no reference trial could be processed; nothing written")
        data = build_normative(stacks, per_side=per_side, source=", ".join(names))
        if not data.curves:
            raise FuzzyGaitError("the reference trials have no complete gait cycle; nothing written")
        write_normative(data, out_file)
    cycles = max(data.cycles.values(), default=0)
    out.print(f"{len(data.curves)} angle components from {len(stacks)} trial{'s' if len(stacks) != 1 else ''} "
              f"(up to {cycles} cycles each) -> {out_file}", markup=False)  # fmt: skip
    if failures:
        err.print(f"fuzzygait: {failures} of {len(trials)} trials failed", markup=False)
        raise typer.Exit(EXIT_USER_ERROR)
