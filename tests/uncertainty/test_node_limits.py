"""A model's limits (capability ``"node_limits"``): a row beyond them is no band whatever
its value (a joint moment whose segment frame turned past 90°), so the batched optimisers
stop a bound at the first such row they meet, and the hull reports the model's value there.

Independent truths: a concave quadratic over a ball (maximum at the projection of its
peak, in closed form) with a half-space of the ball declared beyond the limits; without
the capability, or with limits no point of the ball reaches, the run is the same as
before, value for value; the protocol check compares the limited methods with the plain
ones.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from fuzzygait.testing import ModelCheckError, check_model
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower
from fuzzygait.uncertainty.domains import BallsDomain
from fuzzygait.uncertainty.gfa.batched import maximise
from fuzzygait.uncertainty.gfa.objective import BatchCounts, BatchedObjective, reported_values
from fuzzygait.uncertainty.gfa.spectral import maximise_spectral
from support import Bowl


class LimitedBowl(Bowl):
    """:class:`~support.Bowl` (``f(p, t) = −|p − PEAK|² + t``) whose rows with ``p_x > edge``
    lie beyond the model's limits.  Over the ball of radius 2 about 0 the maximum is at
    ``0.4 PEAK`` (``p_x = 1.2``), worth ``−9 + t``; the minimum at ``−0.4 PEAK`` (``p_x =
    −1.2``), ``−49 + t``."""

    def __init__(self, edge: float | None = 1.0, n_time: int = 6) -> None:
        super().__init__(n_time=n_time)
        self.edge = edge
        if edge is not None:
            self.capabilities = self.capabilities | {"node_limits"}

    def beyond(self, P: np.ndarray) -> np.ndarray:
        return np.asarray(P)[:, 0] > (np.inf if self.edge is None else self.edge)

    def evaluate_nodes_limited(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.evaluate_nodes(P, nodes), self.beyond(P)

    def evaluate_nodes_gradients_limited(self, P: np.ndarray,
                                         nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        return *self.evaluate_nodes_gradients(P, nodes), self.beyond(P)


def objective(model: LimitedBowl, counts: BatchCounts, limited: bool) -> BatchedObjective:
    return BatchedObjective(SimpleNamespace(model=model), np.array([1.0]), 4, np.ones(3), 1e-6,  # type: ignore[arg-type]
                            counts, exact=True, limited=limited)  # fmt: skip


@pytest.mark.parametrize("solver", [maximise_spectral, maximise])
def test_a_point_stops_at_the_first_row_beyond_the_limits(solver) -> None:  # noqa: ANN001
    """Radius 2, started on the sphere at (0, 0, 2) (inside the limits): without limits every
    node reaches the maximum −9 + t at p_x = 1.2; with the half-space p_x > 1 beyond, every
    node ends at a row beyond it (value +inf in the objective), in fewer iterations, and the
    model's value there is below the maximum."""
    domain = BallsDomain(np.zeros((1, 3)), np.array([2.0]))
    nodes = np.arange(4)
    start = [np.tile([0.0, 0.0, 2.0], (4, 1))]
    free, stopped = BatchCounts(), BatchCounts()
    _, values = solver(objective(LimitedBowl(), free, limited=False), domain, nodes, start, 60, 1e-12)
    np.testing.assert_allclose(values, -9.0 + nodes, atol=1e-6)
    limited = objective(LimitedBowl(), stopped, limited=True)
    points, ends = solver(limited, domain, nodes, start, 60, 1e-12)
    assert np.all(np.isposinf(ends)) and np.all(points[:, 0] > 1.0)
    assert np.all(np.linalg.norm(points, axis=1) <= 2.0 + 1e-12)
    reported = reported_values(limited, points, ends, nodes)
    np.testing.assert_array_equal(reported, LimitedBowl().evaluate_nodes(points, nodes))
    assert np.all(reported <= -9.0 + nodes + 1e-12)
    assert stopped.point_iterations < free.point_iterations


def test_limits_no_row_reaches_change_nothing() -> None:
    """The Graph Follower with the capability and an edge outside the ball (p_x > 5) gives
    the hulls and extremisers of the run without it, value for value."""
    params = FuzzyBalls(np.zeros((1, 3)), np.array([2.0]), ("m",))
    strategy = BatchedDirect(starts=3, stride=2, follow=3)
    free = graph_follower(LimitedBowl(edge=None), params, (0.0, 0.5, 1.0), strategy=strategy)
    far = graph_follower(LimitedBowl(edge=5.0), params, (0.0, 0.5, 1.0), strategy=strategy)
    np.testing.assert_array_equal(free.hull.to_numpy(), far.hull.to_numpy())
    np.testing.assert_array_equal(free["extremiser"].to_numpy(), far["extremiser"].to_numpy())


def test_the_hull_reports_the_model_value_where_a_bound_stopped() -> None:
    """Edge p_x > 1 inside the radius-2 ball: the hull is finite everywhere and holds the
    model's value at each bound's extremiser (inside the α-ball; the nesting repair may
    widen a level's hull to the next level's, never narrow it), within the true extremes
    −49 + t and −9 + t; the upper bounds at α = 0 stopped beyond the limits (the maximum
    lies beyond them), those at α = 0.5 (radius 1: no row beyond) reach the maximum −16 + t."""
    params = FuzzyBalls(np.zeros((1, 3)), np.array([2.0]), ("m",))
    model = LimitedBowl()
    result = graph_follower(model, params, (0.0, 0.5, 1.0), strategy=BatchedDirect(starts=3, stride=2, follow=3))
    hull = result.hull.to_numpy()  # (alpha, bound, time)
    extremiser = result["extremiser"].to_numpy()  # (alpha, bound, time, 3)
    nodes = np.arange(model.times.size)
    assert np.all(np.isfinite(hull))
    for a, alpha in enumerate((0.0, 0.5, 1.0)):
        at = [model.evaluate_nodes(extremiser[a, b], nodes) for b in range(2)]
        assert np.all(hull[a, 0] <= at[0] + 1e-9) and np.all(hull[a, 1] >= at[1] - 1e-9)
        assert np.all(np.linalg.norm(extremiser[a], axis=-1) <= 2.0 * (1.0 - alpha) + 1e-9)
    assert np.all(hull[:, 0] >= -49.0 + nodes - 1e-9) and np.all(hull[:, 1] <= -9.0 + nodes + 1e-9)
    assert np.all(model.beyond(extremiser[0, 1]))
    np.testing.assert_allclose(hull[1, 1], -16.0 + nodes, atol=1e-6)


def test_the_protocol_check_compares_the_limited_methods() -> None:
    """A model declaring the capability passes; one with ``evaluate_nodes_limited`` not
    declared, or flags that are not one boolean per row, is refused with a message."""
    check_model(LimitedBowl(), np.zeros(3))
    undeclared = LimitedBowl()
    undeclared.capabilities = frozenset({"nodes", "node_gradients", "time_step"})
    with pytest.raises(ModelCheckError, match="node_limits"):
        check_model(undeclared, np.zeros(3))
    wrong = LimitedBowl()
    wrong.evaluate_nodes_limited = lambda P, nodes: (wrong.evaluate_nodes(P, nodes), np.zeros(len(P)))  # type: ignore[method-assign]
    with pytest.raises(ModelCheckError, match="one boolean per row"):
        check_model(wrong, np.zeros(3))


@pytest.mark.parametrize("solver", [maximise_spectral, maximise])
def test_a_node_ends_when_one_of_its_starts_is_beyond(solver) -> None:  # noqa: ANN001
    """Two starts per node: one beyond the limits (p_x = 1.5), one on the sphere at (0, 0, 2).
    The node's best is the first whatever the second reaches, so the second stops with it:
    the spectral solver takes no iteration, Frank–Wolfe one (the node is checked after its
    first step), fewer than the second alone takes without limits."""
    domain = BallsDomain(np.zeros((1, 3)), np.array([2.0]))
    nodes = np.arange(4)
    beyond, inside = np.tile([1.5, 0.0, 0.0], (4, 1)), np.tile([0.0, 0.0, 2.0], (4, 1))
    alone, together = BatchCounts(), BatchCounts()
    solver(objective(LimitedBowl(), alone, limited=False), domain, nodes, [inside], 60, 1e-12)
    points, values = solver(objective(LimitedBowl(), together, limited=True), domain, nodes, [beyond, inside], 60,
                            1e-12)  # fmt: skip
    assert np.all(np.isposinf(values)) and np.all(points[:, 0] > 1.0)
    assert together.point_iterations <= (0 if solver is maximise_spectral else 2 * nodes.size)
    assert alone.point_iterations > together.point_iterations


def test_forward_differences_take_the_model_values_beyond_the_limits() -> None:
    """Without exact gradients a row beyond the limits is still +inf, and the differences
    are those of the model's values (finite, −2 (p − PEAK) to the step's order)."""
    counts = BatchCounts()
    fd = BatchedObjective(SimpleNamespace(model=LimitedBowl()), np.array([1.0]), 4, np.ones(3), 1e-6,  # type: ignore[arg-type]
                          counts, exact=False, limited=True)  # fmt: skip
    P = np.array([[1.5, 0.0, 0.0], [0.0, 0.0, 1.0]])
    values, gradients = fd.values_and_gradients(P, np.array([0, 1]))
    assert np.isposinf(values[0]) and values[1] == LimitedBowl().evaluate_nodes(P[1:], np.array([1]))[0]
    np.testing.assert_allclose(gradients, -2.0 * (P - np.array([3.0, -4.0, 0.0])), atol=1e-5)
    assert counts.node_evaluations == 2 * 4
