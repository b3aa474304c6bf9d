"""Every α-level of a ball-shaped problem in one optimisation: the default of
:class:`~fuzzygait.uncertainty.gfa.strategies.BatchedDirect` (``solver="spectral"``) for
fuzzy balls (:class:`~fuzzygait.uncertainty.parameters.FuzzyBalls`).

The α-level sets of fuzzy balls are the support balls shrunk about their centres by
``1 − α``, so a point ``u`` of the support balls is the point ``c + (1 − α)(u − c)`` of
level α: the levels are blocks of one optimisation over the support balls
(:class:`LevelObjective`), every model call serving all of them, instead of one run per
level with its own calls — the calls, not the rows, were most of the cost
(``benchmarks/RESULTS.md``, issue 40).  Per node and level the starts are the
deterministic parameters and screened random points
(:func:`~fuzzygait.uncertainty.gfa.batched.screened_starts`), solved by
:func:`~fuzzygait.uncertainty.gfa.spectral.maximise_spectral`; the nodes between
multistart nodes are followed from their neighbours' optima
(:func:`~fuzzygait.uncertainty.gfa.batched.follow_nodes`).  Then the levels exchange
their optima (:func:`exchange_levels`: each node's optimum of every other level, at the
same relative position in this level's balls — the sequential run's "higher level's
optimum scaled out", here in both directions), the nodes a neighbour level improved are
polished by ``follow`` further iterations, the optima that are not first-order stationary
get a few Frank–Wolfe iterations (:func:`polish_kinks`), and the neighbouring nodes' optima
are evaluated (:func:`~fuzzygait.uncertainty.gfa.batched.neighbour_pass`).
"""

from __future__ import annotations

import numpy as np

from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.domains import BallsDomain
from fuzzygait.uncertainty.gfa.batched import (
    Progress,
    follow_nodes,
    layout,
    maximise,
    neighbour_pass,
    screened_starts,
)
from fuzzygait.uncertainty.gfa.objective import BatchedObjective, reported_values
from fuzzygait.uncertainty.gfa.spectral import frank_wolfe_gap, maximise_spectral
from fuzzygait.uncertainty.gfa.strategies import BatchedDirect
from fuzzygait.uncertainty.parameters import FuzzyBalls

#: Frank–Wolfe iterations polishing the optima that are not first-order stationary
#: (:func:`polish_kinks`).  Measured: without them the real CGM 2.4 session's left ankle
#: bands missed Monte Carlo samples by up to 0.05° (``benchmarks/markererror_soundness.py``).
POLISH_ITERATIONS = 3


class LevelObjective:
    """``objective`` at the balls of several α-levels for points of the support balls:
    node ``l · n_nodes + n`` is ``objective``'s node ``n`` at ``c + shrink[l] (p − c)``
    (``c`` the centres), its gradient chain-ruled."""

    def __init__(self, objective: BatchedObjective, centre: np.ndarray, shrink: np.ndarray, n_nodes: int) -> None:
        self.objective, self.counts = objective, objective.counts
        self.centre, self.shrink, self.n_nodes = centre, np.asarray(shrink, dtype=float), int(n_nodes)
        self.centred = not np.any(centre)  # balls about the origin (marker deviations): a plain scaling

    def _at(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        nodes = np.asarray(nodes, dtype=int)
        factor = self.shrink[nodes // self.n_nodes][:, None]
        at = factor * P if self.centred else self.centre + factor * (P - self.centre)
        return at, nodes % self.n_nodes, factor

    def ceilings(self, nodes: np.ndarray) -> np.ndarray:
        return self.objective.ceilings(np.asarray(nodes, dtype=int) % self.n_nodes)

    def values(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        x, inner, _ = self._at(P, nodes)
        return self.objective.values(x, inner)

    def reported(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        x, inner, _ = self._at(P, nodes)
        return self.objective.reported(x, inner)

    def values_and_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x, inner, factor = self._at(P, nodes)
        values, gradients = self.objective.values_and_gradients(x, inner)
        return values, factor * gradients


def exchange_levels(objective: LevelObjective, points: np.ndarray,
                    values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Each node's optimum of every other level evaluated at this level (one call); per
    node the best kept.  ``points``/``values``: every stacked node, one block of
    ``objective.n_nodes`` per level.  Returns ``(points, values, improved nodes)``."""
    span, n_levels = objective.n_nodes, objective.shrink.size
    points, values = points.copy(), values.copy()
    shifts = np.arange(1, n_levels)
    if shifts.size == 0:
        return points, values, np.empty(0, dtype=int)
    target = np.tile(np.arange(n_levels * span), shifts.size)
    source = (target + np.repeat(shifts, n_levels * span) * span) % (n_levels * span)
    tried = objective.values(points[source], target).reshape(shifts.size, -1)
    best = np.argmax(tried, axis=0)
    candidate = tried[best, np.arange(n_levels * span)]
    improved = np.flatnonzero(candidate > values)
    chosen = source.reshape(shifts.size, -1)[best[improved], improved]
    points[improved], values[improved] = points[chosen], candidate[improved]
    return points, values, improved


def polish_kinks(objective: LevelObjective, domain: BallsDomain, points: np.ndarray, values: np.ndarray,
                 tolerance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:data:`POLISH_ITERATIONS` Frank–Wolfe iterations
    (:func:`~fuzzygait.uncertainty.gfa.batched.maximise`) at every node whose optimum is
    not first-order stationary (Frank–Wolfe gap above its ``tolerance``, one gradient call
    to tell) and below its ceiling: an extreme on a kink of the angle function, where the
    gradient does not vanish and the spectral steps crawl, but Frank–Wolfe's ten trial
    steps along the chord and the projected gradient still move.  Values never fall
    (``maximise`` keeps a point's best)."""
    every = np.arange(points.shape[0])
    below = every[values < objective.ceilings(every)]
    _, gradients = objective.values_and_gradients(points[below], below)
    kinked = below[frank_wolfe_gap(domain, points[below], gradients) > tolerance[below]]
    if kinked.size == 0:
        return points, values
    points, values = points.copy(), values.copy()
    points[kinked], values[kinked] = maximise(objective, domain, kinked, [points[kinked]], POLISH_ITERATIONS,
                                              tolerance[kinked])  # fmt: skip
    return points, values


def run_levels_together(model: CountedModel, params: FuzzyBalls, levels: np.ndarray, strategy: BatchedDirect,
                        progress: Progress | None) -> dict[str, object]:  # fmt: skip
    """:func:`~fuzzygait.uncertainty.gfa.batched.run_batched`'s result (hulls before the
    nesting repair, extremisers, deterministic trajectory, attributes) with every level
    below 1 in one optimisation (module docstring); the model's blocks each optimised as
    they would be alone, as there."""
    plan = layout(model, params, strategy)
    below_one = np.arange(levels.size - 1)  # α ascending: stacked level l is levels[l]
    n_levels, both = below_one.size, plan.senses.size
    unit = params.domain(0.0)
    span = both * plan.n_time  # bound nodes per level
    objective = LevelObjective(plan.objective, unit.centre, 1.0 - levels[below_one], span)

    def stacked(time_nodes: np.ndarray) -> np.ndarray:
        bound_nodes = plan.bound_nodes(time_nodes)
        return np.concatenate([bound_nodes + level * span for level in range(n_levels)])

    nodes, others = stacked(plan.nodes), stacked(plan.others)
    tolerance = plan.tolerance[np.arange(n_levels * span) % plan.n_time]
    n_random = max(0, strategy.starts - 1)
    block_of = (nodes % plan.n_time) // plan.n_block
    rngs = [np.random.default_rng(strategy.seed) for _ in range(plan.blocks)]  # each block as if it ran alone
    starts = [np.tile(params.deterministic, (nodes.size, 1)),
              *screened_starts(objective, unit, nodes, block_of, rngs, n_random, strategy.screen)]  # fmt: skip
    points = np.empty((n_levels * span, params.dim))
    values = np.empty(n_levels * span)
    points[nodes], values[nodes] = maximise_spectral(objective, unit, nodes, starts, strategy.iterations,
                                                     tolerance[nodes])  # fmt: skip
    if others.size:
        points[others], values[others] = follow_nodes(objective, unit, nodes, points[nodes], others, [],
                                                      strategy.follow, tolerance[others],
                                                      maximise_spectral)  # fmt: skip
    points, values, improved = exchange_levels(objective, points, values)
    if improved.size and strategy.follow:
        points[improved], values[improved] = maximise_spectral(objective, unit, improved, [points[improved]],
                                                               strategy.follow, tolerance[improved])  # fmt: skip
    points, values = polish_kinks(objective, unit, points, values, tolerance)
    curves = [curve + level * span for level in range(n_levels) for curve in plan.curves()]
    points, values = neighbour_pass(objective, curves, points, values, strategy.window)
    values = reported_values(objective, points, values, np.arange(values.size))
    hull = np.empty((levels.size, both, plan.n_time))
    extremiser = np.empty((levels.size, both, plan.n_time, params.dim))
    hull[-1], extremiser[-1] = plan.deterministic, params.deterministic
    hull[:-1] = plan.senses[None, :, None] * values.reshape(n_levels, both, plan.n_time)
    shrink = objective.shrink[:, None, None, None]
    extremiser[:-1] = unit.centre + shrink * (points.reshape(n_levels, both, plan.n_time, params.dim) - unit.centre)
    if progress is not None:
        progress(n_levels, n_levels)
    return {"hull": hull, "extremiser": extremiser, "deterministic": plan.deterministic,
            "attrs": plan.finish(model, n_levels)}  # fmt: skip
