"""The axes of the fuzzy joint-angle dataset: each bad field is one clear error."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset


def axes(**changes: object) -> AngleAxes:
    fields: dict[str, object] = {"alphas": [0.0, 0.5, 1.0], "frames": [1, 2], "times": [0.0, 0.01],
                                 "markers": ["LKNE", "LANK"], "ball_radius": [10.0, 12.0]}  # fmt: skip
    return AngleAxes(**{**fields, **changes})  # type: ignore[arg-type]


def test_axes_build_the_dataset() -> None:
    fuzzy = fuzzy_angles_dataset({"LKneeAngles_X": np.zeros((3, 2, 2))}, axes())
    assert list(fuzzy["marker"].values) == ["LKNE", "LANK"]
    assert fuzzy["time"].values.tolist() == [0.0, 0.01]


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("alphas", [], "alphas must be ascending"), ("alphas", [0.5, 0.0, 1.0], "alphas must be ascending"),
     ("alphas", [0.0, 1.5], "alphas must be ascending"),
     ("times", [0.0], "times must have one value per frame"),
     ("ball_radius", [10.0], "ball_radius must have one value per marker"),
     ("ball_radius", [10.0, -1.0], "ball_radius must be finite and >= 0"),
     ("ball_radius", [10.0, float("nan")], "ball_radius must be finite and >= 0")],
)  # fmt: skip
def test_axes_reject_each_bad_field(field: str, value: object, message: str) -> None:
    with pytest.raises(ParameterError, match=f"^{message}"):
        axes(**{field: value})
