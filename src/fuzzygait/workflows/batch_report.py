"""The clinicians' batch report (``fuzzygait report``): every trial read, processed and
analysed once, its page written before the next trial is computed, a failed trial listed
in the index with its one-line error while the others are still reported."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.viz.report import ReportItem, ReportWriter, TrialEntry
from fuzzygait.workflows.angles import DEFAULT_PREPROCESSING, Preprocessing, run_angles
from fuzzygait.workflows.marker_uncertainty import (
    DEFAULT_SETTINGS,
    MarkerErrorAnalysis,
    MarkerErrorSettings,
    analyse_run,
)
from fuzzygait.workflows.progress import SILENT, Prefixed, StageProgress

__all__ = ["BatchReport", "report_inputs", "write_batch_report"]


def report_inputs(inputs: Sequence[Path], static: Path | None) -> list[Path]:
    """The trials of a batch report: files as given; folders searched recursively for
    ``*.c3d`` (any case), skipping files there whose name contains "static" (any case:
    calibration trials). The ``static`` file is never a trial; duplicates once."""
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


@dataclass
class BatchReport:
    """The written report: its ``index.html`` and the index entry of every trial."""

    index: Path
    entries: list[TrialEntry]

    @property
    def n_ok(self) -> int:
        """Trials with a page."""
        return sum(e.ok for e in self.entries)

    @property
    def n_failed(self) -> int:
        """Trials listed as failed."""
        return len(self.entries) - self.n_ok


def _report_item(path: Path, analyse: Callable[[Path], MarkerErrorAnalysis], strict: bool) -> ReportItem:
    """The analysis of one trial, or the one-line error that stopped it (re-raised when
    ``strict``)."""
    try:
        return ReportItem(path, analyse(path), None)
    except FuzzyGaitError as exc:
        if strict:
            raise
        return ReportItem(path, None, str(exc))
    except Exception as exc:  # a bug: listed as failed, the batch goes on
        if strict:
            raise
        return ReportItem(path, None, f"internal error {type(exc).__name__}: {exc} "
                          "(rerun with --debug and report it)")  # fmt: skip


def write_batch_report(
    inputs: Sequence[Path],
    out_dir: str | os.PathLike[str],
    *,
    static: Path | None = None,
    subject_file: Path | None = None,
    marker_diameter: float | None = None,
    flat_foot: bool = False,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    settings: MarkerErrorSettings = DEFAULT_SETTINGS,
    model: str = "auto",
    strict: bool = False,
    trials: StageProgress = SILENT,
    components: StageProgress = SILENT,
    on_failure: Callable[[Path, str], None] | None = None,
) -> BatchReport:
    """Analyse every trial of ``inputs`` (see :func:`report_inputs`) and write the report
    into ``out_dir`` (:class:`~fuzzygait.viz.report.ReportWriter`: nothing changes there
    when writing fails).

    Args:
        inputs: C3D files and folders.
        out_dir: the report folder.
        static, subject_file, marker_diameter, flat_foot, preprocessing: as for
            :func:`~fuzzygait.workflows.angles.run_angles`, the same for every trial.
        settings: the marker-error analysis.
        model: the model version of the angles and of their marker-error model, or
            ``"auto"`` (per trial, as :func:`~fuzzygait.workflows.angles.run_angles`).
        strict: re-raise a trial's error instead of listing it as failed (debugging).
        trials: progress over the trials; ``components``: over the stages of a trial's
            analysis (:func:`~fuzzygait.workflows.marker_uncertainty.analyse_run`: fuzzy
            angles, allowable marker error, per-source bands), named after the trial.
        on_failure: called as ``on_failure(path, error)`` for every failed trial.
    """
    paths = report_inputs(inputs, static)

    def analyse(path: Path) -> MarkerErrorAnalysis:
        run = run_angles(path, static=static, subject_file=subject_file, marker_diameter=marker_diameter,
                         flat_foot=flat_foot, preprocessing=preprocessing, model=model)  # fmt: skip
        return analyse_run(run, settings, stages=Prefixed(components, f"{path.name}: "))

    with ReportWriter(out_dir, strict=strict) as writer:
        trials.stage("trials", len(paths))
        for done, path in enumerate(paths, 1):
            components.stage(f"{path.name}: joint angles")
            item = _report_item(path, analyse, strict)
            entry = writer.add(item)
            trials.update(done)
            del item
            if not entry.ok and on_failure is not None:
                on_failure(path, entry.error or "")
        index = writer.finish()
    return BatchReport(index, writer.entries)
