"""The typed requests of the trial workflows: each bad field is one clear error."""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.workflows.angles import Preprocessing
from fuzzygait.workflows.marker_uncertainty import DEFAULT_SETTINGS, MarkerErrorRequest
from fuzzygait.workflows.trial_inputs import TrialInputs

TRIAL = Path("walking.c3d")


def test_defaults_are_the_pipeline_defaults() -> None:
    inputs = TrialInputs(TRIAL)
    assert (inputs.static, inputs.subject_file, inputs.flat_foot, inputs.marker_diameter) == (None,) * 4
    assert inputs.preprocessing == Preprocessing() and inputs.model == "auto" and inputs.knee_ankle_centres is None
    assert MarkerErrorRequest(inputs).settings is DEFAULT_SETTINGS


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("dynamic", None, "dynamic must be a trial file or a Trial"),
     ("static", 3, "static must be a trial file, a Trial or None"),
     ("subject_file", 1.0, "subject_file must be a file or None"),
     ("preprocessing", "6 Hz", "preprocessing must be a Preprocessing"),
     ("flat_foot", "yes", "flat_foot must be True, False or None"),
     ("marker_diameter", 0.0, "marker_diameter must be a finite number of mm > 0"),
     ("marker_diameter", float("inf"), "marker_diameter must be a finite number of mm > 0"),
     ("model", "cgm9", "model must be one of"), ("model", None, "model must be a model version"),
     ("knee_ankle_centres", "lateral", "knee_ankle_centres must be one of")],
)  # fmt: skip
def test_trial_inputs_reject_each_bad_field(field: str, value: object, message: str) -> None:
    arguments: dict[str, object] = {"dynamic": TRIAL, field: value}
    with pytest.raises(ParameterError, match=f"^{message}"):
        TrialInputs(**arguments)  # type: ignore[arg-type]


def test_marker_error_request_rejects_each_bad_field() -> None:
    with pytest.raises(ParameterError, match="^trial must be TrialInputs"):
        MarkerErrorRequest(TRIAL)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="^settings must be MarkerErrorSettings"):
        MarkerErrorRequest(TrialInputs(TRIAL), {"alphas": (0.0,)})  # type: ignore[arg-type]
