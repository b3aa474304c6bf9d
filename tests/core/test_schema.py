"""The fuzzy result's builder types: each bad field is one clear error."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.schema import HullArrays, ResultInfo, fuzzy_result, schema_problems

ALPHAS = np.array([0.0, 1.0])
TIMES = np.array([0.0, 0.1, 0.2])


def arrays(**changes: object) -> HullArrays:
    fields: dict[str, object] = {"alphas": ALPHAS, "times": TIMES, "parameter_names": ["E"],
                                 "hull": np.zeros((2, 2, 3)), "deterministic": np.zeros(3),
                                 "extremiser": np.zeros((2, 2, 3, 1))}  # fmt: skip
    return HullArrays(**{**fields, **changes})  # type: ignore[arg-type]


def info(**changes: object) -> ResultInfo:
    fields: dict[str, object] = {"output": "x", "units": "m", "strategy": "direct", "forward_simulations": 3,
                                 "node_evaluations": 0}  # fmt: skip
    return ResultInfo(**{**fields, **changes})  # type: ignore[arg-type]


def test_builds_a_fuzzy_result() -> None:
    result = fuzzy_result(arrays(), info(), attrs={"starts": 2})
    assert schema_problems(result) == []
    assert result.attrs["forward_simulations"] == 3 and result.attrs["starts"] == 2
    assert result["hull"].attrs["units"] == "m"


@pytest.mark.parametrize(
    ("field", "value"),
    [("hull", np.zeros((2, 3))), ("deterministic", np.zeros(4)), ("extremiser", np.zeros((2, 2, 3, 2)))],
)
def test_hull_arrays_reject_each_wrong_shape(field: str, value: object) -> None:
    with pytest.raises(ParameterError, match=f"^{field} must have the shape"):
        arrays(**{field: value})


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("output", None, "output must be a string"), ("units", 1, "units must be a string"),
     ("strategy", None, "strategy must be a string"),
     ("forward_simulations", -1, "forward_simulations must be a whole number"),
     ("node_evaluations", 1.5, "node_evaluations must be a whole number"),
     ("node_evaluations", True, "node_evaluations must be a whole number")],
)  # fmt: skip
def test_result_info_rejects_each_bad_field(field: str, value: object, message: str) -> None:
    with pytest.raises(ParameterError, match=f"^{message}"):
        info(**{field: value})
