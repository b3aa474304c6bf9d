"""Command building a lab's normative data from its reference trials: normative."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from fuzzygait.cli.app import EXIT_USER_ERROR, app, err, out, user_errors
from fuzzygait.cli.options import ModelOption, StaticOption, SubjectOption, check_calibration_files, check_model


@app.command("normative", short_help="Normative mean ± SD per % gait cycle from reference trials.")
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
    """Normative mean ± SD per % gait cycle and angle component from reference trials,
    and of the kinetics where the trials have force plates.

    Session folders are searched as `report` does (static trial, subject file, walking
    trials); files given directly use --static/--subject (else their PROCESSING group).
    Every gait cycle of every trial counts once; a cycle's joint moments (KneeMoment_X,
    N·m/kg), powers (KneePower_Z, W/kg) and ground reaction over stance (NormalisedGRF_Z,
    % body weight) count when its stance was on a force plate. The file format is in
    docs/reports.md ("Normative data"). A trial that fails gets one error line; the
    others are used.
    """
    from fuzzygait.core.errors import FuzzyGaitError

    with user_errors():
        if out_file.suffix.lower() != ".csv":
            raise FuzzyGaitError(f"{out_file}: the normative file is a .csv file")
        check_model(model)
        check_calibration_files(static, subject)
        from fuzzygait.gait.cycles import gait_cycles
        from fuzzygait.gait.normative import build_normative, normalised_cycles, write_normative
        from fuzzygait.workflows.angles import run_angles
        from fuzzygait.workflows.report_folder import run_kinetic_cycles
        from fuzzygait.workflows.session import find_sessions

        trials = [t for s in find_sessions(inputs, static, subject) for t in s.trials]
    stacks, kinetic_stacks, failures, names = [], [], 0, []
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
        cut = run_kinetic_cycles(run, {side: gait_cycles(run.trial, run.events, side) for side in "LR"})
        stacks.append(normalised_cycles(run.result.angles, run.trial, run.events))
        kinetic_stacks.append(cut.cycles if cut is not None else {})
        names.append(trial.path.name)
    with user_errors():
        if not stacks:
            raise FuzzyGaitError("no reference trial could be processed; nothing written")
        data = build_normative(stacks, per_side=per_side, source=", ".join(names))
        if not data.curves:
            raise FuzzyGaitError("the reference trials have no complete gait cycle; nothing written")
        kinetic = build_normative(kinetic_stacks, per_side=per_side)
        angles = len(data.curves)
        data.curves.update(kinetic.curves)
        data.cycles.update(kinetic.cycles)
        write_normative(data, out_file)
    cycles = max(data.cycles.values(), default=0)
    kinetics = f" and {len(kinetic.curves)} kinetic components" if kinetic.curves else ""
    none = "" if kinetic.curves else " (no kinetics: no gait cycle's stance on a force plate)"
    out.print(f"{angles} angle components{kinetics} from {len(stacks)} trial{'s' if len(stacks) != 1 else ''} "
              f"(up to {cycles} cycles each) -> {out_file}{none}", markup=False)  # fmt: skip
    if failures:
        err.print(f"fuzzygait: {failures} of {len(trials)} trials failed", markup=False)
        raise typer.Exit(EXIT_USER_ERROR)
