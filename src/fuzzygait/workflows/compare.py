"""``fuzzygait compare``: a trial's stored angles against ours, as a table."""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass
from pathlib import Path

import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.io.tables import write_table
from fuzzygait.workflows.angles import AnglesRun, table_metadata
from fuzzygait.workflows.crosscheck import FLAG_DEG, CrossCheck
from fuzzygait.workflows.trial_inputs import TrialInputs


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare_trial` found: the run, its cross-check, the flag threshold
    (deg) and the table written (None when none was asked for)."""

    run: AnglesRun
    check: CrossCheck
    flag_deg: float = FLAG_DEG
    written: Path | None = None

    def table(self) -> pd.DataFrame:
        """One row per component: ``angle``, ``axis``, ``stored``, ``frames``, ``rms``,
        ``max`` (deg, ours minus the file's, ours on the file's markers)."""
        return pd.DataFrame([asdict(row) for row in self.check.rows])


def compare_trial(inputs: TrialInputs, out_table: str | os.PathLike[str] | None = None) -> Comparison:
    """Run the angle pipeline on ``inputs`` (:func:`~fuzzygait.workflows.angles.run_angles`)
    and compare with the angles the trial stores; ``out_table`` (.csv or .parquet)
    receives the per-component table.

    Raises:
        FuzzyGaitError: the trial stores no angle outputs of the names ours have.
    """
    run = inputs.run()
    if run.crosscheck is None:
        names = ", ".join(sorted(run.result.angles)[:3])
        raise FuzzyGaitError(f"{run.raw.name}: holds no stored angles to compare with (none of {names}, ... nor "
                             "their LVicon*/RVicon* names among its model outputs); run it through Nexus or "
                             "pyCGM2 first, or use `fuzzygait angles`")  # fmt: skip
    comparison = Comparison(run, run.crosscheck)
    if out_table is None:
        return comparison
    path = Path(out_table)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_table(comparison.table(), path, metadata=table_metadata(run))
    return Comparison(run, run.crosscheck, written=path)
