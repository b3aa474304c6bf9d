"""The allowable-marker-error refinement in the marker-error workflow (issue 15, Deliver 3
integration): run after the fuzzy analysis on the same evaluator when a tolerance is set,
the refined dataset is the one returned and saved, one note line, the demo summary's
knee-flexion sentences.

Speed: the sample trial cut to 6 frames (markers NaN elsewhere, as in
tests/markererror/test_allowable.py), left knee, α = 0 and 0.5, one worker.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind, messages
from fuzzygait.markererror.allowable import allowable_table, refined_levels
from fuzzygait.markererror.result import read_marker_result
from fuzzygait.workflows import trial_inputs
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.demo import allowable_lines
from fuzzygait.workflows.marker_uncertainty import (
    MarkerErrorAnalysis,
    MarkerErrorRequest,
    MarkerErrorSettings,
    analyse_run,
    analyse_to_files,
)
from fuzzygait.workflows.trial_inputs import TrialInputs
from support import sparse_angles_run

N_FRAMES = 6
SETTINGS = MarkerErrorSettings(alphas=(0.0, 0.5), angles=("LKneeAngles",), workers=1)


@pytest.fixture(scope="module")
def sparse_run(angles_run: AnglesRun) -> AnglesRun:
    """The sample run with every marker NaN outside 6 frames spread over the trial."""
    return sparse_angles_run(angles_run, N_FRAMES)


@pytest.fixture(scope="module")
def analysis(sparse_run: AnglesRun) -> MarkerErrorAnalysis:
    return analyse_run(sparse_run, SETTINGS)


def test_refinement_follows_the_fuzzy_analysis(analysis: MarkerErrorAnalysis) -> None:
    table, fuzzy = analysis.allowable, analysis.result
    assert table is not None and list(table.index) == ["LKneeAngles_X", "LKneeAngles_Y", "LKneeAngles_Z"]
    assert fuzzy is not None and fuzzy.allowable is not None
    pd.testing.assert_frame_equal(allowable_table(fuzzy), table)
    assert fuzzy.allowable.attrs["tolerance_deg"] == 2.5 and fuzzy.allowable.attrs["runs"] > 0
    assert int(refined_levels(fuzzy, "LKneeAngles_X")["refined"].sum()) == table.loc["LKneeAngles_X", "evaluations"]
    (note,) = [n for n in messages(analysis.notes) if n.startswith("allowable marker error")]
    assert note.startswith(f"allowable marker error for ±2.5°: {fuzzy.allowable.attrs['runs']} refinement runs, ")
    assert note.endswith(" s")
    # ΔΦ of the refined dataset (its plain levels), the trial's name
    assert list(analysis.delta_phi.columns) == [0.5, 0.0] and analysis.fuzzy.attrs["trial"] == "walking.c3d"


def test_no_tolerance_no_refinement(sparse_run: AnglesRun) -> None:
    plain = analyse_run(sparse_run, dataclasses.replace(SETTINGS, tolerance=None, angles=("LKneeAngles",)))
    assert plain.allowable is None and plain.result is not None and plain.result.allowable is None
    assert not [n for n in messages(plain.notes) if n.startswith("allowable")]


@pytest.mark.parametrize("tolerance", [0.0, -1.0, float("nan"), float("inf")])
def test_settings_reject_a_bad_tolerance(tolerance: float) -> None:
    with pytest.raises(ParameterError, match="tolerance"):
        MarkerErrorSettings(tolerance=tolerance)
    assert MarkerErrorSettings.create(tolerance=None).tolerance is None


def test_saved_dataset_is_the_refined_one(sparse_run: AnglesRun, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    """analyse_to_files saves the refined dataset: the table read back from the file is
    the one in memory (the sparse run stands in for the pipeline)."""
    monkeypatch.setattr(trial_inputs, "run_angles", lambda *args, **kwargs: sparse_run)
    settings = dataclasses.replace(SETTINGS, allowable_angles=("LKneeAngles_X",))
    out = tmp_path / "fuzzy.nc"
    analysis = analyse_to_files(MarkerErrorRequest(TrialInputs(sparse_run.trial), settings), out)
    assert analysis.allowable is not None and list(analysis.allowable.index) == ["LKneeAngles_X"]
    again = read_marker_result(out)
    assert analysis.result is not None
    pd.testing.assert_frame_equal(allowable_table(again), analysis.allowable, check_dtype=False)
    np.testing.assert_allclose(refined_levels(again, "LKneeAngles_X")["hull"],
                               refined_levels(analysis.result, "LKneeAngles_X")["hull"])  # fmt: skip
    assert analysis.notes[-1].kind is FindingKind.ALLOWABLE_ERROR and "(LKneeAngles_X)" in analysis.notes[-1].message


def test_demo_summary_has_the_flexion_sentence(analysis: MarkerErrorAnalysis) -> None:
    lines = allowable_lines(analysis)
    assert analysis.allowable is not None
    sentence = str(analysis.allowable.loc["LKneeAngles_X", "text"])
    assert sentence.startswith("Left knee, sagittal (+ flexion): known within ±2.5° if every marker stays within ")
    assert f"- {sentence}" in lines
    (row,) = [line for line in lines if line.startswith("| LKneeAngles_X ")]
    assert f"| {analysis.allowable.loc['LKneeAngles_X', 'allowable_mm']:.1f} |" in row
    assert allowable_lines(dataclasses.replace(analysis, result=None)) == []  # the bands alone
