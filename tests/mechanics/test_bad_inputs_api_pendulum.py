"""The pendulum model checks its initial state and time nodes when made (audit item 13)."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.pendulum import Pendulum


@pytest.mark.parametrize(
    ("arguments", "needle"),
    [
        ({"theta0": np.nan}, r"pendulum theta0 must be a finite number; got nan"),
        ({"theta0": None}, r"pendulum theta0 must be a finite number; got None"),
        ({"gravity": np.inf}, r"pendulum gravity must be a finite number; got inf"),
        ({"times": []}, r"pendulum times must be a non-empty 1-D array of finite, strictly increasing times"),
        ({"times": [0.0, np.nan, 1.0]}, r"pendulum times must be .*got \[0\.0, nan, 1\.0\]"),
        ({"times": [0.0, 1.0, 1.0]}, r"strictly increasing"),
        ({"times": [[0.0, 1.0]]}, r"1-D"),
        ({"rtol": 0.0}, r"pendulum rtol must be a relative tolerance"),
    ],
)
def test_the_pendulum_refuses_an_impossible_state_or_time_nodes(arguments, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        Pendulum(**arguments)


def test_good_time_nodes_give_one_angle_each() -> None:
    assert Pendulum(times=[0.0, 0.5, 1.0]).evaluate(np.array([1.0])).values.shape == (3,)
    single = Pendulum(times=[0.0], theta0=0.3).evaluate(np.array([1.0]), sensitivities=True)
    assert single.values.tolist() == [0.3] and single.jacobian.tolist() == [[0.0]]
