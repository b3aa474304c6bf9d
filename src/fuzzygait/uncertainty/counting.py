"""Evaluation counting and output checks around a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.protocol import MANY, NODE_GRADIENTS, NODES, SENSITIVITIES, Array, FuzzyModel


@dataclass
class CountedModel:
    """Wraps a model, validates its outputs and counts forward simulations.

    Attributes:
        model: the wrapped model.
        scale: per-parameter scale for the finite-difference step.
        fd_step: relative step of forward finite differences (times the parameter scale).
        evaluations: forward simulations run (finite-difference runs included).
        node_evaluations: single-node evaluations (``evaluate_nodes`` rows, forward
            differences included).
        node_gradients: single-node gradients (``evaluate_nodes_gradients`` rows; each
            row's value comes with it and is not counted again).
    """

    model: FuzzyModel
    scale: Array
    fd_step: float = 1e-6
    evaluations: int = 0
    node_evaluations: int = 0
    node_gradients: int = 0
    n_time: int = field(init=False)

    def __post_init__(self) -> None:
        self.n_time = int(np.asarray(self.model.times).size)

    @property
    def has_sensitivities(self) -> bool:
        """Whether the model computes its own sensitivities (declares ``"sensitivities"``)."""
        return SENSITIVITIES in self.model.capabilities

    @property
    def has_nodes(self) -> bool:
        return NODES in self.model.capabilities

    @property
    def has_node_gradients(self) -> bool:
        """Whether the model gives exact gradients of single-node outputs (declares
        ``"node_gradients"``)."""
        return NODE_GRADIENTS in self.model.capabilities

    def _check(self, f: Array, p: Array) -> Array:
        f = np.asarray(f, dtype=float).reshape(-1)
        if f.size != self.n_time:
            raise ParameterError(f"the model returned {f.size} values for {self.n_time} time nodes")
        if not np.all(np.isfinite(f)):
            raise ParameterError(f"the model returned non-finite outputs for parameters {p.tolist()}")
        return f

    def trajectory(self, p: Array) -> Array:
        """One forward simulation."""
        self.evaluations += 1
        return self._check(self.model.evaluate(p).values, p)

    def trajectory_and_sensitivities(self, p: Array) -> tuple[Array, Array]:
        """Trajectory and ``df/dp`` ``(n_time, n_p)``: the model's own, or forward
        finite differences."""
        if self.has_sensitivities:
            self.evaluations += 1
            evaluation = self.model.evaluate(p, sensitivities=True)
            if evaluation.jacobian is None:
                raise ParameterError(f"{type(self.model).__name__} declares sensitivities but returned none")
            jac = np.asarray(evaluation.jacobian, dtype=float).reshape(self.n_time, p.size)
            return self._check(evaluation.values, p), jac
        f = self.trajectory(p)
        jac = np.empty((self.n_time, p.size))
        for i in range(p.size):
            h = self.fd_step * self.scale[i]
            shifted = p.copy()
            shifted[i] += h
            jac[:, i] = (self.trajectory(shifted) - f) / h
        return f, jac

    def trajectories_and_sensitivities_many(self, P: Array) -> tuple[Array, Array]:
        """:meth:`trajectory_and_sensitivities` of every row of ``P (k, n_p)``:
        ``(k, n_time)`` and ``(k, n_time, n_p)``. A model that evaluates many rows at
        once (capability ``"many"``, e.g. on an evaluator's workers) gets
        them in one call; otherwise row after row."""
        P = np.atleast_2d(np.asarray(P, dtype=float))
        if MANY not in self.model.capabilities or not self.has_sensitivities:
            pairs = [self.trajectory_and_sensitivities(p) for p in P]
            return np.array([f for f, _ in pairs]), np.array([j for _, j in pairs])
        self.evaluations += P.shape[0]
        values, jacobians = self.model.evaluate_many_with_sensitivities(P)  # type: ignore[attr-defined]
        values = np.array([self._check(f, p) for f, p in zip(values, P, strict=True)])
        return values, np.asarray(jacobians, dtype=float).reshape(P.shape[0], self.n_time, P.shape[1])

    def node(self, p: Array, j: int) -> tuple[float, Array | None]:
        """Output at node ``j``; the full trajectory too when it had to be computed."""
        if self.has_nodes:
            self.node_evaluations += 1
            value = self.model.evaluate_nodes(p.reshape(1, -1), np.array([j]))  # type: ignore[attr-defined]
            return float(np.asarray(value).reshape(-1)[0]), None
        f = self.trajectory(p)
        return float(f[j]), f
