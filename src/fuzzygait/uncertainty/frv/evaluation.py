"""Batch evaluation of the model at parameter rows for the FRV-GFA library: the
``evaluator`` interface ``P (k, n_p) -> F (k, n_time)`` or ``(F, J (k, n_time, n_p))``,
and the bounds the model declares for its output."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.protocol import FuzzyModel

#: ``P (k, n_p) -> F (k, n_time)`` or ``(F, J (k, n_time, n_p))``: a serial loop
#: (:func:`serial_evaluator`) or an engine batch on workers
#: (:meth:`fuzzygait.uncertainty.execution.Evaluator.batch`).
BatchFunction = Callable[[np.ndarray], "np.ndarray | tuple[np.ndarray, np.ndarray]"]


def serial_evaluator(model: FuzzyModel) -> BatchFunction:
    """The default batch function: ``P (k, n_p) -> F (k, n_time)`` by a loop over
    ``model.evaluate``, or ``(F, J (k, n_time, n_p))`` when the model declares the
    ``"sensitivities"`` capability."""
    counted = CountedModel(model, scale=np.ones(1))
    with_sensitivities = counted.has_sensitivities

    def evaluate(P: np.ndarray) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        P = np.atleast_2d(np.asarray(P, dtype=float))
        if with_sensitivities:
            pairs = [counted.trajectory_and_sensitivities(p) for p in P]
            return np.stack([f for f, _ in pairs]), np.stack([j for _, j in pairs])
        return np.stack([counted.trajectory(p) for p in P])

    return evaluate


def _run_evaluator(evaluator: BatchFunction, P: np.ndarray, n_time: int) -> tuple[np.ndarray, np.ndarray | None]:
    """``F (k, n_time)`` and, when the evaluator returns it, ``J (k, n_time, n_p)``, checked."""
    out = evaluator(P)
    F, J = (out[0], out[1]) if isinstance(out, tuple) else (out, None)
    F = np.asarray(F, dtype=float)
    k = P.shape[0]
    if F.shape != (k, n_time):
        raise ParameterError(f"the evaluator returned shape {F.shape} for {k} parameters and {n_time} time nodes")
    if not np.all(np.isfinite(F)):
        bad = np.flatnonzero(~np.all(np.isfinite(F), axis=1))
        raise ParameterError(f"the model returned non-finite outputs for parameters {P[bad, 0].tolist()}")
    if J is not None:
        J = np.asarray(J, dtype=float).reshape(k, n_time, -1)
    return F, J


def declared_bounds(model: FuzzyModel) -> tuple[float, float]:
    """``(lower, upper)`` the model declares for its output
    (:attr:`~fuzzygait.uncertainty.protocol.Output.bounds`; ``(-inf, inf)`` when it
    declares none, e.g. an output description without bounds)."""
    bounds = getattr(getattr(model, "output", None), "bounds", None)
    if bounds is None:
        return -math.inf, math.inf
    lower, upper = (float(b) for b in bounds)
    return lower, upper
