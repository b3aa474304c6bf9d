"""The objective of the batched α-level optimisations (:mod:`~fuzzygait.uncertainty.gfa.batched`,
:mod:`~fuzzygait.uncertainty.gfa.spectral`): both bounds' nodes in one model call, exact or
forward-difference gradients, the work counted, and the best of several starts per node."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain

#: Frank–Wolfe step fractions of :func:`~fuzzygait.uncertainty.gfa.batched.maximise` (counted in ``steps``).
STEP_FRACTIONS = np.array([1.0, 0.5, 0.25, 0.125, 0.0625])


@dataclass
class BatchCounts:
    """Work done: node evaluations (rows), exact node gradients (rows) and iterations, and
    where the solvers' iterations go (``benchmarks/markererror_work.py`` prints them):
    starting points, point-iterations (an active point's iteration), points still active
    after the last iteration, iterations without gain, the step taken (``steps``: Frank–Wolfe
    fractions 1 … 1/16, then the projected-gradient ones), and per node the starts that end
    within 1e-3 of the best value (``same_optimum``, the best not counted) and which start
    wins (``winner``: index in ``starts``)."""

    node_evaluations: int = 0
    node_gradients: int = 0
    iterations: int = 0
    points: int = 0
    point_iterations: int = 0
    unconverged: int = 0
    no_gain: int = 0
    same_optimum: int = 0
    steps: np.ndarray = field(default_factory=lambda: np.zeros(2 * STEP_FRACTIONS.size, dtype=int))
    winner: np.ndarray = field(default_factory=lambda: np.zeros(16, dtype=int))


class BatchedObjective:
    """``sense · f(P, nodes)`` for both bounds at once, with counting and gradients.

    The objective's nodes are *bound nodes* ``b · n_time + t``: time node ``t`` of bound
    ``b`` (:data:`~fuzzygait.core.schema.BOUNDS` order, sense ``senses[b]``), so one call
    serves the lower and the upper bound's optimisations side by side.  Gradients are the
    model's exact ones when ``exact`` (it declares ``"node_gradients"``), else forward
    differences of step ``fd_step · scale``.  ``ceiling`` (per bound node, in the
    objective's sense; default none): a value there or above ends the node's optimisation
    (:meth:`ceilings`).  ``limited``: the model declares ``"node_limits"``; a row beyond its
    limits is worth ``+inf`` in either sense — no band there, so the row wins and its node's
    optimisation ends, as at a ceiling — and :meth:`reported` gives the model's value
    there."""

    def __init__(self, model: CountedModel, senses: np.ndarray, n_time: int, scale: np.ndarray, fd_step: float,
                 counts: BatchCounts, exact: bool = False, ceiling: np.ndarray | None = None,
                 limited: bool = False):  # fmt: skip
        self.model, self.counts, self.exact, self.limited = model, counts, exact, limited
        self.senses, self.n_time = np.asarray(senses, dtype=float), int(n_time)
        self.h = fd_step * np.asarray(scale, dtype=float)
        self.ceiling = np.full(self.senses.size * self.n_time, np.inf) if ceiling is None else ceiling

    def ceilings(self, nodes: np.ndarray) -> np.ndarray:
        """Per bound node the value from which on its optimisation may stop: the model's
        output there is no band any more (capability ``"excursion_limit"``), so a wider
        value means nothing more; ``inf`` where the model declares no limit."""
        return self.ceiling[np.asarray(nodes, dtype=int)]

    def _split(self, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(sense per row, time node per row)`` of bound nodes."""
        nodes = np.asarray(nodes, dtype=int)
        return self.senses[nodes // self.n_time], nodes % self.n_time

    def values(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        if P.shape[0] == 0:  # e.g. no neighbours at this shift: nothing to evaluate
            return np.empty(0)
        self.counts.node_evaluations += int(P.shape[0])
        value, beyond = self._evaluate(P, nodes)
        return np.where(beyond, np.inf, value)

    def _evaluate(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray | bool]:
        """The model's values in the objective's sense and the rows beyond its limits
        (False where it declares none), uncounted."""
        sense, times = self._split(nodes)
        model = self.model.model
        if not self.limited:
            plain = model.evaluate_nodes(P, times)  # type: ignore[attr-defined]
            return sense * np.asarray(plain, dtype=float), False
        out, beyond = model.evaluate_nodes_limited(P, times)  # type: ignore[attr-defined]
        return sense * np.asarray(out, dtype=float), np.asarray(beyond, dtype=bool)

    def reported(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """The model's values in the objective's sense, a row beyond the model's limits
        included (the value :meth:`values` gives ``+inf``), uncounted: for the hull."""
        if P.shape[0] == 0:
            return np.empty(0)
        return self._evaluate(P, nodes)[0]

    def values_and_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values (``+inf`` at a row beyond the model's limits) and gradients: exact, or
        forward differences of the model's values (beyond its limits or not)."""
        if self.exact:
            self.counts.node_gradients += int(P.shape[0])
            sense, times = self._split(nodes)
            model = self.model.model
            if self.limited:
                values, gradients, beyond = model.evaluate_nodes_gradients_limited(P, times)  # type: ignore[attr-defined]
            else:
                values, gradients = model.evaluate_nodes_gradients(P, times)  # type: ignore[attr-defined]
                beyond = False
            value = np.where(beyond, np.inf, sense * np.asarray(values, dtype=float))
            return value, sense[:, None] * np.asarray(gradients, dtype=float)
        k, n_p = P.shape
        shifted = np.repeat(P[:, None, :], n_p + 1, axis=1)  # (k, n_p + 1, n_p)
        shifted[:, 1:, :] += np.diag(self.h)[None]
        self.counts.node_evaluations += int(shifted.shape[0] * shifted.shape[1])
        values, beyond = self._evaluate(shifted.reshape(-1, n_p), np.repeat(nodes, n_p + 1))
        values = values.reshape(k, n_p + 1)
        at = np.where(np.reshape(beyond, (k, n_p + 1))[:, 0], np.inf, values[:, 0]) if self.limited else values[:, 0]
        return at, (values[:, 1:] - values[:, :1]) / self.h


class NodeObjective(Protocol):
    """What the batched solvers optimise: values and gradients of ``(point, node)`` rows
    in the sense of a maximisation, the work counted in ``counts``."""

    counts: BatchCounts

    def values(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray: ...

    def values_and_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def ceilings(self, nodes: np.ndarray) -> np.ndarray: ...

    def reported(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray: ...


def reported_values(objective: NodeObjective, points: np.ndarray, values: np.ndarray,
                    nodes: np.ndarray) -> np.ndarray:  # fmt: skip
    """``values`` (per node of ``nodes``, optima ``points``) with each ``+inf`` — a row
    beyond the model's limits (:class:`BatchedObjective`'s ``limited``) — replaced by the
    model's value there, in the objective's sense: the hull a limited model reports."""
    stopped = np.flatnonzero(np.isposinf(values))
    if stopped.size == 0:
        return values
    values = values.copy()
    values[stopped] = objective.reported(points[stopped], np.asarray(nodes)[stopped])
    return values


def stacked_starts(domain: BoxDomain | BallsDomain, nodes: np.ndarray, starts: list[np.ndarray],
                   tolerance: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The solvers' points: every start projected onto ``domain``, start-major ``(S k,
    n_p)``, with the node and the stopping tolerance of each row."""
    P = np.concatenate([domain.project(s) for s in starts])
    stop = np.broadcast_to(np.asarray(tolerance, dtype=float), (nodes.size,))
    return P, np.tile(nodes, len(starts)), np.tile(stop, len(starts))


def nodes_at_ceiling(value: np.ndarray, ceiling: np.ndarray, n_starts: int) -> np.ndarray:
    """Per point of a start-major ``(n_starts k,)`` stack, whether some point of its node
    has reached the node's ceiling (or a row beyond the model's limits, ``+inf``): that
    node's optimisation is over — the best of its starts is that point whatever the others
    reach — so none of its points need iterate further."""
    reached = (value >= ceiling).reshape(n_starts, -1).any(axis=0)
    return np.tile(reached, n_starts)


def best_of_starts(counts: BatchCounts, P: np.ndarray, value: np.ndarray,
                   n_starts: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Per node the best of its ``n_starts`` optimised points: ``P`` ``(n_starts k, n_p)``
    and ``value`` ``(n_starts k,)`` start-major; counts the starts that end at the best
    optimum and which start wins."""
    per_start = value.reshape(n_starts, -1)
    k = per_start.shape[1]
    pick = np.argmax(per_start, axis=0)
    counts.same_optimum += int(np.count_nonzero(per_start >= per_start[pick, np.arange(k)] - 1e-3)) - k
    n_win = min(n_starts, counts.winner.size)
    counts.winner[:n_win] += np.bincount(pick, minlength=n_starts)[:n_win]
    points = P.reshape(n_starts, k, -1)[pick, np.arange(k)]
    return points, per_start[pick, np.arange(k)]
