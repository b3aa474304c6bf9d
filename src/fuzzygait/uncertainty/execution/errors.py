"""The error of a parallel evaluation (:class:`~fuzzygait.uncertainty.execution.Evaluator`)."""

from __future__ import annotations

from fuzzygait.core.errors import FuzzyGaitError


class ParallelEvaluationError(FuzzyGaitError):
    """A parallel evaluation failed.

    Attributes:
        row: index of the failing parameter row or item (None when no row is to blame,
            e.g. an unreachable scheduler).
        parameters: that row's parameter vector (list of floats) or None.
        error_type: name of the original exception type (e.g. ``"SimulationError"``).
    """

    def __init__(self, message: str, row: int | None = None, parameters: list[float] | None = None,
                 error_type: str | None = None) -> None:  # fmt: skip
        super().__init__(message)
        self.row, self.parameters, self.error_type = row, parameters, error_type
