"""The model protocol of the uncertainty engine and evaluation counting.

The engine knows nothing of markers or beams. A model maps a parameter vector ``p``
(shape ``(n_p,)``) to the trajectory of one scalar target output over its time nodes::

    model.times                      -> (n_time,)  time of each node (any unit)
    model.evaluate(p)                -> (n_time,)  one forward simulation

and may offer, to make the engine cheaper:

    model.evaluate_with_sensitivities(p) -> ((n_time,), (n_time, n_p))   f and df/dp
    model.evaluate_node(p, j)            -> float   the output at node j only

Without sensitivities the engine uses forward finite differences (``1 + n_p`` forward
simulations, all counted). One call of ``evaluate`` or
``evaluate_with_sensitivities`` is one forward simulation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from fuzzygait.core.errors import ParameterError


@runtime_checkable
class Model(Protocol):
    """What the Graph Follower algorithm needs of a model (see module docstring)."""

    times: np.ndarray

    def evaluate(self, p: np.ndarray) -> np.ndarray: ...


@dataclass
class FunctionModel:
    """A model from plain functions.

    Args:
        function: ``p -> (n_time,)`` trajectory.
        times: the time nodes.
        jacobian: optional ``p -> (n_time, n_p)`` sensitivities.
    """

    function: Callable[[np.ndarray], np.ndarray]
    times: np.ndarray
    jacobian: Callable[[np.ndarray], np.ndarray] | None = None

    def evaluate(self, p: np.ndarray) -> np.ndarray:
        return np.asarray(self.function(p), dtype=float)

    def evaluate_with_sensitivities(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.jacobian is None:
            raise AttributeError("no jacobian given")
        return self.evaluate(p), np.asarray(self.jacobian(p), dtype=float)


def has_sensitivities(model: object) -> bool:
    """Whether ``model`` computes its own sensitivities."""
    if isinstance(model, FunctionModel):
        return model.jacobian is not None
    return callable(getattr(model, "evaluate_with_sensitivities", None))


@dataclass
class CountedModel:
    """Wraps a model, validates its outputs and counts forward simulations.

    Attributes:
        model: the wrapped model.
        fd_step: relative step of forward finite differences (times the parameter scale).
        scale: per-parameter scale for the finite-difference step.
        evaluations: forward simulations run (finite-difference runs included).
        node_evaluations: single-node evaluations (``evaluate_node``).
    """

    model: Any
    scale: np.ndarray
    fd_step: float = 1e-6
    evaluations: int = 0
    node_evaluations: int = 0
    n_time: int = field(init=False)

    def __post_init__(self) -> None:
        times = np.asarray(getattr(self.model, "times", None), dtype=float)
        if times.ndim != 1 or times.size == 0:
            raise ParameterError("the model must have 1-D `times` (its time nodes)")
        self.n_time = int(times.size)

    def _check(self, f: np.ndarray, p: np.ndarray) -> np.ndarray:
        f = np.asarray(f, dtype=float).reshape(-1)
        if f.size != self.n_time:
            raise ParameterError(f"the model returned {f.size} values for {self.n_time} time nodes")
        if not np.all(np.isfinite(f)):
            raise ParameterError(f"the model returned non-finite outputs for parameters {p.tolist()}")
        return f

    def trajectory(self, p: np.ndarray) -> np.ndarray:
        """One forward simulation."""
        self.evaluations += 1
        return self._check(self.model.evaluate(p), p)

    def trajectory_and_sensitivities(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Trajectory and ``df/dp`` ``(n_time, n_p)``: the model's own, or forward
        finite differences."""
        if has_sensitivities(self.model):
            self.evaluations += 1
            f, jac = self.model.evaluate_with_sensitivities(p)
            return self._check(f, p), np.asarray(jac, dtype=float).reshape(self.n_time, p.size)
        f = self.trajectory(p)
        jac = np.empty((self.n_time, p.size))
        for i in range(p.size):
            h = self.fd_step * self.scale[i]
            shifted = p.copy()
            shifted[i] += h
            jac[:, i] = (self.trajectory(shifted) - f) / h
        return f, jac

    def node(self, p: np.ndarray, j: int) -> tuple[float, np.ndarray | None]:
        """Output at node ``j``; the full trajectory too when it had to be computed."""
        if callable(getattr(self.model, "evaluate_node", None)):
            self.node_evaluations += 1
            return float(self.model.evaluate_node(p, j)), None
        f = self.trajectory(p)
        return float(f[j]), f
