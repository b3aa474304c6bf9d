"""The spatio-temporal parameters of a batch of trials (``fuzzygait gait-parameters``):
each trial read once, its parameters computed from its events and toe markers
(:mod:`fuzzygait.gait.spatiotemporal`), one table for all, written atomically; a trial
that fails is reported by its one-line error and the others are still tabulated."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import pandas as pd

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Option
from fuzzygait.core.paths import check_table_path
from fuzzygait.gait.spatiotemporal import (
    SELECTIONS,
    TrialParameters,
    parameters_table,
    spatiotemporal_parameters,
)
from fuzzygait.io import read_c3d
from fuzzygait.io.tables import write_table
from fuzzygait.mocap.sanity import check_trial

__all__ = ["GaitParametersRun", "gait_parameters_files"]


@dataclass
class GaitParametersRun:
    """What :func:`gait_parameters_files` produced.

    Attributes:
        table: one row per trial and side (see
            :func:`~fuzzygait.gait.spatiotemporal.parameters_table`); ``trial`` is the
            path as given.
        results: the per-cycle parameters of every trial that succeeded.
        failures: one line per trial that failed (names the file, the cause and what
            to do).
        out: the table file written, or ``None`` (no trial succeeded, or none asked).
    """

    table: pd.DataFrame
    results: list[TrialParameters] = field(default_factory=list)
    failures: list[str] = field(default_factory=list)
    out: Path | None = None


def gait_parameters_files(
    paths: Sequence[str | os.PathLike[str]],
    out: str | os.PathLike[str] | None = None,
    selection: str = "all",
) -> GaitParametersRun:
    """Spatio-temporal parameters of every trial in ``paths``, as one table.

    Args:
        out: ``.csv`` or ``.parquet`` file to write (atomically; not written when every
            trial failed), or ``None``.
        selection: ``"all"`` (mean ± SD over complete cycles), ``"nexus"`` (the first
            complete cycle per side, what Vicon Nexus stores) or ``"workstation"`` (the
            first cycle with Vicon Workstation's definitions).

    Raises:
        FuzzyGaitError: a bad ``out`` suffix or ``selection`` (before any trial is read).
    """
    out_path = check_table_path(out) if out is not None else None
    if selection not in SELECTIONS:
        raise FuzzyGaitError(f"{Option.CYCLES} must be one of {', '.join(SELECTIONS)}; got {selection!r}")
    results: list[TrialParameters] = []
    failures: list[str] = []
    for path in paths:
        try:
            trial = check_trial(read_c3d(path))  # rate, units, spikes: one line or a note
            result = spatiotemporal_parameters(trial)
        except FuzzyGaitError as exc:
            failures.append(str(exc))
            continue
        results.append(replace(result, trial=str(path), notes=[*trial.notes, *result.notes]))
    table = parameters_table(results, selection)
    run = GaitParametersRun(table, results, failures)
    if out_path is not None and results:
        metadata = {"program": f"fuzzygait {__version__}", "cycles": selection}
        run.out = write_table(table, out_path, metadata=metadata)
    return run
