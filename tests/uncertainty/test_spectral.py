"""The spectral projected-gradient solver of the batched α-level optimisation
(:func:`~fuzzygait.uncertainty.gfa.spectral.maximise_spectral`).

Independent truths: a linear objective over a product of balls has its maximum
``Σ r_k |c_k|`` at ``r_k c_k/|c_k|`` (over a box: the vertex ``sign(c)``); a concave
quadratic ``−|p − a|²`` has its maximum at ``a`` when ``a`` is inside the set and at the
projection of ``a`` onto each ball otherwise; on a non-concave objective the values never
fall below the start's (monotone steps), checked against the objective evaluated at the
returned points; and the Frank–Wolfe solver on the same problems.  The α-levels
solved together (:mod:`~fuzzygait.uncertainty.gfa.levels`) exchange their optima at the
same relative position in the balls, worth ``(1 − α) r |c|`` for a linear objective.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FuzzyBalls, graph_follower
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.gfa.batched import maximise
from fuzzygait.uncertainty.gfa.levels import LevelObjective, exchange_levels
from fuzzygait.uncertainty.gfa.objective import BatchCounts, BatchedObjective
from fuzzygait.uncertainty.gfa.spectral import frank_wolfe_gap, maximise_spectral
from fuzzygait.uncertainty.gfa.strategies import BatchedDirect
from fuzzygait.uncertainty.protocol import Evaluation, Output


class Quadratic:
    """``f(p) = −|p − a_node|² + c · p`` per node, with its exact gradient."""

    def __init__(self, a: np.ndarray, c: np.ndarray, curvature: float = 1.0) -> None:
        self.a, self.c, self.curvature = a, c, curvature

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return -self.curvature * np.sum((P - self.a[nodes]) ** 2, axis=1) + P @ self.c

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.evaluate_nodes(P, nodes), -2.0 * self.curvature * (P - self.a[nodes]) + self.c


class Wavy:
    """A non-concave objective with many local maxima: ``Σ sin(w p_i + node)``."""

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return np.sum(np.sin(3.0 * P + nodes[:, None]), axis=1)

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return self.evaluate_nodes(P, nodes), 3.0 * np.cos(3.0 * P + nodes[:, None])


def objective(model: object, n_time: int, dim: int, counts: BatchCounts | None = None) -> BatchedObjective:
    return BatchedObjective(SimpleNamespace(model=model), np.array([1.0]), n_time, np.ones(dim),  # type: ignore[arg-type]
                            1e-6, counts or BatchCounts(), exact=True)  # fmt: skip


def balls(radii: list[float]) -> BallsDomain:
    return BallsDomain(np.zeros((len(radii), 3)), np.array(radii))


def test_linear_objective_over_balls_reaches_the_analytic_maximum() -> None:
    rng = np.random.default_rng(3)
    radii = [2.0, 0.5, 7.0, 1.0]
    c = rng.normal(size=12)
    domain = balls(radii)
    counts = BatchCounts()
    nodes = np.arange(5)
    starts = [np.zeros((5, 12)), domain.sample(rng, 5)]
    points, values = maximise_spectral(objective(Quadratic(np.zeros((5, 12)), c, 0.0), 5, 12, counts), domain,
                                       nodes, starts, 25, 1e-12)  # fmt: skip
    blocks = c.reshape(4, 3)
    norms = np.linalg.norm(blocks, axis=1)
    np.testing.assert_allclose(values, np.sum(np.array(radii) * norms), rtol=1e-9)
    np.testing.assert_allclose(points, np.tile((np.array(radii)[:, None] * blocks / norms[:, None]).ravel(), (5, 1)),
                               atol=1e-6)  # fmt: skip
    assert counts.iterations <= 10
    from_centre = BatchCounts()
    maximise_spectral(objective(Quadratic(np.zeros((5, 12)), c, 0.0), 5, 12, from_centre), domain, nodes,
                      [np.zeros((5, 12))], 25, 1e-12)  # fmt: skip
    assert from_centre.iterations == 2 and from_centre.node_gradients == 10  # one step lands on the optimum


@pytest.mark.parametrize("inside", [True, False])
def test_concave_quadratic_optimum_inside_and_on_the_spheres(inside: bool) -> None:
    rng = np.random.default_rng(7)
    radii = np.array([3.0, 1.0, 2.0])
    direction = rng.normal(size=(4, 3, 3))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    length = radii[None, :, None] * (0.5 if inside else 2.5)
    a = (direction * length).reshape(4, 9)  # per node a point inside every ball, or outside every ball
    domain = balls(list(radii))
    expected = a if inside else (direction * radii[None, :, None]).reshape(4, 9)  # the projection of a
    points, values = maximise_spectral(objective(Quadratic(a, np.zeros(9)), 4, 9), domain, np.arange(4),
                                       [np.zeros((4, 9))], 50, 1e-14)  # fmt: skip
    np.testing.assert_allclose(points, expected, atol=1e-5)
    np.testing.assert_allclose(values, -np.sum((expected - a) ** 2, axis=1), atol=1e-8)
    frank_wolfe, _ = maximise(objective(Quadratic(a, np.zeros(9)), 4, 9), domain, np.arange(4),
                              [np.zeros((4, 9))], 200, 1e-14)  # fmt: skip
    np.testing.assert_allclose(points, frank_wolfe, atol=1e-3)  # the other solver agrees


def test_values_never_fall_below_the_start_and_are_the_objectives_values() -> None:
    rng = np.random.default_rng(11)
    domain = balls([1.0, 0.7, 1.3])
    nodes = np.arange(30)
    starts = [domain.sample(rng, 30), domain.sample(rng, 30, surface=True)]
    model = Wavy()
    points, values = maximise_spectral(objective(model, 30, 9), domain, nodes, starts, 25, 1e-9)
    at_start = np.max([model.evaluate_nodes(s, nodes) for s in starts], axis=0)
    assert np.all(values >= at_start)
    np.testing.assert_allclose(values, model.evaluate_nodes(points, nodes), rtol=0, atol=1e-12)
    assert np.all(domain.contains(points, tol=1e-12))
    gap = frank_wolfe_gap(domain, points, model.evaluate_nodes_gradients(points, nodes)[1])
    assert np.all(gap >= -1e-12) and np.median(gap) < 1e-3  # first-order optima, but for the iteration cap


def test_linear_objective_over_a_box_reaches_its_vertex() -> None:
    c = np.array([2.0, -1.0, 0.5, -3.0])
    lower, upper = np.array([-1.0, -2.0, 0.0, -0.5]), np.array([1.0, 0.5, 3.0, 0.5])
    domain = BoxDomain(lower, upper)
    _, values = maximise_spectral(objective(Quadratic(np.zeros((2, 4)), c, 0.0), 2, 4), domain, np.arange(2),
                                  [np.zeros((2, 4))], 25, 1e-12)  # fmt: skip
    np.testing.assert_allclose(values, np.sum(np.where(c > 0, upper, lower) * c), rtol=1e-12)


def test_an_unknown_solver_is_named() -> None:
    with pytest.raises(ParameterError, match="solver must be one of spectral, frank-wolfe; got 'newton'"):
        BatchedDirect(solver="newton")


def test_levels_exchange_their_optima_at_the_same_relative_position() -> None:
    """Level 0 (full balls) at the centre, level 1 (half the radii) at its optimum: the
    exchange hands level 0 the same relative position, worth twice level 1's value
    (linear objective: ``(1 − α) r |c|``), and leaves level 1 alone."""
    c = np.array([1.0, 2.0, -2.0])  # |c| = 3
    r = 2.0
    inner = objective(Quadratic(np.zeros((1, 3)), c, 0.0), 1, 3)
    levels = LevelObjective(inner, np.zeros(3), np.array([1.0, 0.5]), 1)
    optimum = r * c / 3.0  # in the support ball: level 1's optimum is 0.5 of it
    points = np.stack([np.zeros(3), optimum])
    values = levels.values(points, np.arange(2))
    np.testing.assert_allclose(values, [0.0, 0.5 * r * 3.0])
    exchanged, new_values, improved = exchange_levels(levels, points, values)
    np.testing.assert_array_equal(improved, [0])
    np.testing.assert_allclose(new_values, [r * 3.0, 0.5 * r * 3.0])
    np.testing.assert_allclose(exchanged[0], optimum)
    _, gradients = levels.values_and_gradients(points, np.arange(2))
    np.testing.assert_allclose(gradients, [c, 0.5 * c])  # the chain rule of the shrink


class KinkModel:
    """``f(p, t) = −|p_x − c(t)| − |p_y| − 0.1 |p_z|`` (one 3-vector, no gradient at the
    maximum 0, reached at ``(c(t), 0, 0)`` inside a ball of radius 2): an extreme on a kink,
    as the middle angle of a Cardan sequence can have one."""

    times = np.arange(40) / 100.0
    time_step = 0.01
    parameter_names = ("m_x", "m_y", "m_z")
    output = Output("f", "1")
    capabilities = frozenset({"nodes", "node_gradients"})

    def centre(self, nodes: np.ndarray) -> np.ndarray:
        return 0.8 * np.sin(2 * np.pi * self.times[nodes])

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        nodes = np.arange(self.times.size)
        return Evaluation(self.evaluate_nodes(np.tile(p, (nodes.size, 1)), nodes))

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return -np.abs(P[:, 0] - self.centre(nodes)) - np.abs(P[:, 1]) - 0.1 * np.abs(P[:, 2])

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        gradient = -np.stack([np.sign(P[:, 0] - self.centre(nodes)), np.sign(P[:, 1]), 0.1 * np.sign(P[:, 2])], axis=1)
        return self.evaluate_nodes(P, nodes), gradient


def test_an_extreme_on_a_kink_is_reached_at_every_level() -> None:
    """The upper hull of the kinked model is 0 at α = 0 and 0.5 (the maximum lies inside
    both balls): the spectral steps stall on the kink, the Frank–Wolfe polish of the
    optima that are not stationary (:func:`~fuzzygait.uncertainty.gfa.levels.polish_kinks`)
    gets there.  Measured: within 4.3e-3 everywhere (4.3e-2 without the polish); bound
    1e-2 (of a range of 2.8)."""
    model = KinkModel()
    params = FuzzyBalls(np.zeros((1, 3)), np.array([2.0]), ("m",))
    result = graph_follower(model, params, (0.0, 0.5), strategy=BatchedDirect(starts=3, stride=8, follow=5))
    upper = result.hull.sel(bound="upper").sel(alpha=[0.0, 0.5]).to_numpy()
    assert np.all(upper <= 1e-12) and np.all(upper >= -1e-2)
    extremiser = result["extremiser"].sel(bound="upper", alpha=0.0).to_numpy()
    assert np.all(np.linalg.norm(extremiser, axis=1) <= 2.0 + 1e-12)  # inside the ball
    # the hull is at least the value at the extremiser (more where the nesting repair lifts it)
    assert np.all(model.evaluate_nodes(extremiser, np.arange(40)) <= upper[0] + 1e-12)


def test_a_looser_stop_ends_the_points_sooner_and_a_bad_one_is_named() -> None:
    """``BatchedDirect.stop`` is the fraction of the block's largest |output| an iteration
    must gain to go on: 1e-2 on the kinked model (range 2.8) does less work than the
    default 1e-7 and its hull still holds values of the model (≤ 0, the maximum); outside
    (0, 1) it is refused with its name."""
    model = KinkModel()
    params = FuzzyBalls(np.zeros((1, 3)), np.array([2.0]), ("m",))
    runs = {stop: graph_follower(model, params, (0.0,), strategy=BatchedDirect(starts=3, stride=8, follow=5, stop=stop))
            for stop in (1e-7, 1e-2)}  # fmt: skip
    assert runs[1e-2].attrs["node_gradients"] < runs[1e-7].attrs["node_gradients"]
    for result in runs.values():
        assert np.all(result.hull.sel(alpha=0.0, bound="upper").to_numpy() <= 1e-12)
    assert runs[1e-2].attrs["stop"] == 1e-2
    for bad in (0.0, 1.0, -1e-3, True):
        with pytest.raises(ParameterError, match="BatchedDirect stop must be a fraction in \\(0, 1\\)"):
            BatchedDirect(stop=bad)
