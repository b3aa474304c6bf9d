"""FuzzySimRequest and command_strategy: each bad field refused in one line naming it."""

from __future__ import annotations

import pytest

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.options import Option
from fuzzygait.uncertainty import Linearised
from fuzzygait.workflows.fuzzy_dynamics import MAX_ITERATIONS, FuzzySimRequest, command_strategy


@pytest.mark.parametrize("fields, said", [
    ({"spreads": {}}, "spreads: give at least one fuzzy parameter"),
    ({"spreads": [("E", 0.1)]}, "spreads: give at least one fuzzy parameter"),
    ({"spreads": {"E": 1.5}}, "spreads: E's spread must lie between 0 and 1"),
    ({"spreads": {"E": "10%"}}, "spreads: E's spread must lie between 0 and 1"),
    ({"target": "energy"}, "unknown target 'energy'; choose one of"),
    ({"alphas": ()}, "alphas: give α-levels between 0 and 1"),
    ({"alphas": (0.0, 1.5)}, "alphas: give α-levels between 0 and 1"),
    ({"alphas": "0,1"}, "alphas: give α-levels between 0 and 1"),
    ({"strategy": {"stride": 10}}, "strategy: give a Linearised strategy; got dict"),
])  # fmt: skip
def test_a_bad_request_field_is_refused_in_one_line(fields, said) -> None:
    with pytest.raises(FuzzyGaitError, match=f"^{said}") as caught:
        FuzzySimRequest(**{"spreads": {"E": 0.1}, **fields})
    assert "\n" not in str(caught.value)


def test_the_default_strategy_is_the_commands() -> None:
    request = FuzzySimRequest({"E": 0.1})
    assert request.linearised == Linearised(stride=100, novelty_tol=1e-4, max_iterations=MAX_ITERATIONS,
                                            tracks="side-by-side")  # fmt: skip
    assert request.linearised == command_strategy(100, 1e-4) and request.target is None
    assert request.alphas == (0.0, 0.5, 1.0)
    given = command_strategy(20, 1e-3, tracks="one-by-one")
    assert FuzzySimRequest({"E": 0.1}, strategy=given).linearised is given


def test_command_strategy_names_the_option() -> None:
    with pytest.raises(FuzzyGaitError, match=f"^{Option.STRIDE} must be ≥ 1; got 0"):
        command_strategy(0, 1e-4)
    with pytest.raises(ParameterError, match="novelty_tol"):
        command_strategy(10, -1.0)
