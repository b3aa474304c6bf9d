"""Direct-mode α-level optimisation of all time nodes at once, for models that evaluate
many ``(parameter, node)`` pairs in one vectorised call.

Cheap models such as joint angles from markers (thesis §3.7.3, OP-II) offer::

    model.evaluate_nodes(P, nodes) -> values      # P (k, n_p), nodes (k,) -> (k,)

and, with the ``"node_gradients"`` capability, their exact gradients::

    model.evaluate_nodes_gradients(P, nodes) -> (values (k,), gradients (k, n_p))

The α-level optimisations of different nodes and of the two bounds are independent, so
they are solved side by side (:class:`BatchedObjective`'s bound nodes): every iteration
evaluates the gradients of all nodes' current points, lower and upper, in one call
(the model's exact ones, or forward differences: ``1 + n_p`` rows per point), moves
each towards the optimum of its linearisation over the α-level set (a point on the ball
surfaces or a box vertex, closed form; a point that did not move in the last iteration
keeps its value and gradient, no new evaluation) with a line search (Frank–Wolfe steps,
``τ ∈ {1, 1/2, …, 1/16}``), and keeps a node's point only if it improves. Starting
points (multistart): the deterministic parameters, the higher α-level's optimum of the
same node (admissible, since the α-level sets are nested — this also makes the hulls
nested by construction) and the best of a screen of seeded random points (inside the
set and on its boundary). After the optimisation each node's optimum is also evaluated
at the ``window`` neighbouring nodes on either side and the best value found there
counts (the library post-processing of the Graph Follower, restricted to neighbours
because whole trajectories are not needed).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.schema import BOUNDS, SENSES
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.gfa.objective import (
    STEP_FRACTIONS,
    BatchCounts,
    BatchedObjective,
    NodeObjective,
    best_of_starts,
    nodes_at_ceiling,
    reported_values,
    stacked_starts,
)
from fuzzygait.uncertainty.gfa.strategies import BatchedDirect
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector
from fuzzygait.uncertainty.protocol import NODE_LIMITS, declared_blocks, declared_excursion_limit, declared_time_step

#: A point stops once its step scale has shrunk below this (steps < 1e-6 of the set).
MIN_REACH = 1e-6


def maximise(
    objective: NodeObjective,
    domain: BoxDomain | BallsDomain,
    nodes: np.ndarray,
    starts: list[np.ndarray],
    iterations: int,
    tolerance: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Best point and value per node over all starting points.

    Args:
        objective: the (sense-adjusted) objective to maximise.
        domain: the α-level set.
        nodes: ``(k,)`` node indices.
        starts: list of ``(k, n_p)`` starting points (projected onto the domain).
        iterations: Frank–Wolfe iterations at most.
        tolerance: a node stops once its improvement falls below this (one for all, or
            ``(k,)`` per node).

    Returns:
        ``(points (k, n_p), values (k,))`` in the objective's sense.
    """
    P, rows, stop = stacked_starts(domain, nodes, starts, tolerance)  # (S k, n_p): start-major
    value = np.full(P.shape[0], -np.inf)
    reach = np.ones(P.shape[0])  # per-point step scale: shrinks after failures, grows after full steps
    active = np.ones(P.shape[0], dtype=bool)
    counts = objective.counts
    counts.points += P.shape[0]
    gradient = np.empty_like(P)
    known = np.zeros(P.shape[0], dtype=bool)  # gradient (and value) of the point as it is: kept while it does not move
    ceiling = objective.ceilings(rows)  # a value there or beyond: no band, nothing more to find
    for _ in range(iterations):
        counts.iterations += 1
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        counts.point_iterations += idx.size
        need = idx[~known[idx]]
        if need.size:
            value[need], gradient[need] = objective.values_and_gradients(P[need], rows[need])
            known[need] = True
            active &= ~nodes_at_ceiling(value, ceiling, len(starts))  # a start at its ceiling ends its node
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
        v0, g = value[idx], gradient[idx]
        target = domain.linear_argmax(g)
        tau = STEP_FRACTIONS[None, :, None] * reach[idx, None, None]
        chord = target - P[idx]  # Frank-Wolfe: towards the linear model's optimum
        ascent = target - domain.centre  # projected gradient: along the gradient, projected
        fw = P[idx, None, :] + tau * chord[:, None, :]
        pg = domain.project(P[idx, None, :] + tau * ascent[:, None, :])
        trial = np.concatenate([fw, pg], axis=1)  # chords cut through a ball, projections follow its surface
        n_f = trial.shape[1]
        tried = objective.values(trial.reshape(-1, P.shape[1]), np.repeat(rows[idx], n_f)).reshape(-1, n_f)
        best = np.argmax(tried, axis=1)
        gain = tried[np.arange(idx.size), best] - v0
        better = gain > 0
        counts.no_gain += int(idx.size - np.count_nonzero(better))
        counts.steps += np.bincount(best[better], minlength=counts.steps.size)
        P[idx[better]] = trial[better, best[better]]
        value[idx[better]] = tried[better, best[better]]
        known[idx[better]] = False
        full_step = better & (best % STEP_FRACTIONS.size == 0)
        reach[idx[full_step]] = np.minimum(1.0, 4.0 * reach[idx[full_step]])
        reach[idx[~better]] *= STEP_FRACTIONS[-1]  # no gain: the next finer set of steps
        active[idx[(better & (gain <= stop[idx])) | (reach[idx] < MIN_REACH) | (value[idx] >= ceiling[idx])]] = False
        active &= ~nodes_at_ceiling(value, ceiling, len(starts))
    counts.unconverged += int(np.count_nonzero(active))
    return best_of_starts(counts, P, value, len(starts))


def neighbour_pass(objective: NodeObjective, curves: list[np.ndarray], points: np.ndarray, values: np.ndarray,
                   window: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Evaluate each node's optimum at up to ``window`` neighbouring nodes on either side
    within its curve and keep, per node, the best value found (library post-processing).

    ``curves``: the objective's nodes of each curve (one bound of one output block) in
    time order, disjoint; ``points``/``values`` are indexed by those nodes.  Every curve
    is served by the same call per neighbour shift."""
    points, values = points.copy(), values.copy()
    for shift in [s for w in range(1, window + 1) for s in (w, -w)]:
        sources, targets = [], []
        for curve in curves:
            source = np.arange(curve.size) - shift
            ok = (source >= 0) & (source < curve.size)
            sources.append(curve[source[ok]])
            targets.append(curve[ok])
        source_nodes, target = np.concatenate(sources), np.concatenate(targets)
        candidate = points[source_nodes]
        v = objective.values(candidate, target)
        better = v > values[target]
        points[target[better]] = candidate[better]
        values[target[better]] = v[better]
    return points, values


def screened_starts(objective: NodeObjective, domain: BoxDomain | BallsDomain, nodes: np.ndarray,
                    block_of: np.ndarray, rngs: Sequence[np.random.Generator], n_starts: int,
                    n_screen: int) -> list[np.ndarray]:  # fmt: skip
    """``n_starts`` starting points per node: the best of ``n_screen`` seeded random
    points per node (half inside the set, half on its boundary, where extremes of angle
    functions mostly lie).  Each block's points (``block_of``: each node's block) are drawn
    by its own generator ``rngs[block]`` as if it ran alone; all are evaluated in one call,
    so a model whose blocks share rows (the same deviation at the same frame, one pass of
    its chain giving every block) computes each such row once."""
    if n_starts <= 0:
        return []
    n_screen = max(n_screen, n_starts)
    half = n_screen // 2
    k = nodes.size
    candidates = np.empty((n_screen, k, domain.centre.size))
    for block, rng in enumerate(rngs):
        mine = np.flatnonzero(block_of == block)
        drawn = [domain.sample(rng, mine.size * half), domain.sample(rng, mine.size * (n_screen - half), surface=True)]
        candidates[:, mine] = np.concatenate(drawn).reshape(n_screen, mine.size, -1)
    values = objective.values(candidates.reshape(n_screen * k, -1), np.tile(nodes, n_screen)).reshape(n_screen, k)
    order = np.argsort(-values, axis=0)[:n_starts]  # (n_starts, k)
    return [candidates[order[i], np.arange(k)] for i in range(n_starts)]


Progress = Callable[[int, int], None]
Solver = Callable[[NodeObjective, BoxDomain | BallsDomain, np.ndarray, list[np.ndarray], int, float | np.ndarray],
                  tuple[np.ndarray, np.ndarray]]  # fmt: skip


def optimisation_nodes(n_time: int, stride: int) -> np.ndarray:
    """Every ``stride``-th time node, plus the last one."""
    return np.unique(np.append(np.arange(0, n_time, stride), n_time - 1))


def followed_nodes(times: np.ndarray, stride: int, time_step: float | None = None) -> np.ndarray:
    """The nodes of :func:`optimisation_nodes` taken within each run of evenly spaced
    ``times`` (s): a step longer than 1.5 ``time_step`` (the sampling period, s; default:
    the median step) starts a new run — frames left out, e.g. a marker gap or a sparse
    selection —, whose first and last node are optimisation nodes too, so a node is only
    followed from neighbours of its own run."""
    times = np.asarray(times, dtype=float)
    if stride == 1 or times.size < 3:
        return np.arange(times.size)
    step = np.diff(times)
    period = float(np.median(step)) if time_step is None else float(time_step)
    breaks = np.flatnonzero(step > 1.5 * period) + 1
    runs = np.split(np.arange(times.size), breaks)
    return np.concatenate([run[optimisation_nodes(run.size, stride)] for run in runs])


def follow_nodes(objective: NodeObjective, domain: BoxDomain | BallsDomain, nodes: np.ndarray,
                 points: np.ndarray, others: np.ndarray, extra: list[np.ndarray], iterations: int,
                 tolerance: float | np.ndarray,
                 solver: Solver = maximise) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Optima at the nodes ``others`` between the optimisation nodes ``nodes`` (optima
    ``points``): each starts from the best of its two bracketing optima and the
    candidates ``extra`` (``(len(others), n_p)`` each, e.g. the higher α-level's optimum
    there) and is refined by ``iterations`` first-order iterations (0: the best start as
    it is) — the Graph Follower's idea of starting a node from its neighbours' optima —
    by ``solver``."""
    right = np.minimum(np.searchsorted(nodes, others), nodes.size - 1)
    left = np.maximum(right - 1, 0)
    candidates = [points[left], points[right]] + [domain.project(c) for c in extra]
    values = np.stack([objective.values(c, others) for c in candidates])  # (n_candidates, len(others))
    pick = np.argmax(values, axis=0)
    start = np.stack(candidates)[pick, np.arange(others.size)]
    if iterations == 0:
        return start, values[pick, np.arange(others.size)]
    return solver(objective, domain, others, [start], iterations, tolerance)


@dataclass(frozen=True)
class Layout:
    """What a batched run optimises: the deterministic trajectory, the model's ``blocks``
    of ``n_block`` nodes (``spans``), the multistart ``nodes`` and the followed ``others``
    (time nodes), the per-node stopping ``tolerance``, the bounds' ``senses`` and the
    objective of the bound nodes ``b · n_time + t``."""

    deterministic: np.ndarray
    n_time: int
    n_block: int
    spans: list[slice]
    nodes: np.ndarray
    others: np.ndarray
    tolerance: np.ndarray
    senses: np.ndarray
    objective: BatchedObjective
    exact: bool

    @property
    def blocks(self) -> int:
        return len(self.spans)

    def bound_nodes(self, time_nodes: np.ndarray) -> np.ndarray:
        """``time_nodes`` of every bound, as bound nodes (lower bound's first)."""
        return np.concatenate([time_nodes + b * self.n_time for b in range(self.senses.size)])

    def finish(self, model: CountedModel, n_levels: int) -> dict[str, object]:
        """Add the run's work to ``model``'s counts; the run's attributes for ``n_levels``
        α-levels below 1."""
        counts = self.objective.counts
        model.node_evaluations += counts.node_evaluations
        model.node_gradients += counts.node_gradients
        return {"optimisations": int(self.senses.size * n_levels * self.nodes.size),
                "solver_iterations": counts.iterations, "node_gradients": counts.node_gradients,
                "gradient_source": "exact" if self.exact else "forward differences"}  # fmt: skip

    def curves(self) -> list[np.ndarray]:
        """The bound nodes of each bound's curve of each block, in time order."""
        return [np.arange(span.start, span.stop) + b * self.n_time
                for b in range(self.senses.size) for span in self.spans]  # fmt: skip


def ceilings(deterministic: np.ndarray, senses: np.ndarray, limit: float | None) -> np.ndarray | None:
    """Per bound node ``b · n_time + t`` the objective's value ``senses[b] · deterministic[t]
    + limit`` at which its optimisation stops (the model's excursion limit); None without
    a limit, ``inf`` where the deterministic output is missing."""
    if limit is None:
        return None
    values = senses[:, None] * np.asarray(deterministic, dtype=float)[None, :] + limit
    return np.where(np.isfinite(values), values, np.inf).reshape(-1)


def layout(model: CountedModel, params: FuzzyVector | FuzzyBalls, strategy: BatchedDirect) -> Layout:
    """The :class:`Layout` of ``model``'s batched run with ``strategy``'s stride.

    Raises:
        ParameterError: the model's declared blocks do not divide its nodes."""
    deterministic = model.trajectory(params.deterministic)
    n_time = model.n_time
    blocks = declared_blocks(model.model)
    if blocks < 1 or n_time % blocks:
        raise ParameterError(f"a model of {n_time} time nodes cannot have {blocks} equal blocks")
    n_block = n_time // blocks
    times = np.asarray(model.model.times, dtype=float)
    time_step = declared_time_step(model.model)
    spans = [slice(i * n_block, (i + 1) * n_block) for i in range(blocks)]
    nodes = np.concatenate([followed_nodes(times[span], strategy.stride, time_step) + span.start for span in spans])
    tolerance = np.concatenate([np.full(n_block, strategy.stop * max(float(np.max(np.abs(deterministic[span]))), 1.0))
                                for span in spans])  # fmt: skip
    senses = np.array([SENSES[bound] for bound in BOUNDS])
    exact = strategy.gradients == "auto" and model.has_node_gradients
    objective = BatchedObjective(model, senses, n_time, params.scale, 1e-6, BatchCounts(), exact,
                                 ceilings(deterministic, senses, declared_excursion_limit(model.model)),
                                 NODE_LIMITS in getattr(model.model, "capabilities", ()))  # fmt: skip
    return Layout(deterministic, n_time, n_block, spans, nodes, np.setdiff1d(np.arange(n_time), nodes), tolerance,
                  senses, objective, exact)  # fmt: skip


def run_batched(model: CountedModel, params: FuzzyVector | FuzzyBalls, levels: np.ndarray,
                strategy: BatchedDirect, progress: Progress | None) -> dict[str, object]:  # fmt: skip
    """The :class:`BatchedDirect` strategy level by level with the Frank–Wolfe solver
    (``solver="frank-wolfe"``, and box-shaped α-cuts whatever the solver): hulls
    ``(alpha, bound, time)`` (before the nesting repair), extremisers, the deterministic trajectory and the counts.

    A model whose nodes are ``blocks`` independent outputs of the same parameters, one
    after the other (capability ``"blocks"``; without it 1: e.g. the components of one
    joint angle) has each block optimised as it would be alone — its own runs of followed
    nodes, neighbours, stopping tolerance and seeded random starts, so the same result
    up to the rounding of the model's batched array operations — while every model call
    serves all blocks."""
    plan = layout(model, params, strategy)
    deterministic, n_time, n_block = plan.deterministic, plan.n_time, plan.n_block
    nodes, others, tolerance, senses, objective = plan.nodes, plan.others, plan.tolerance, plan.senses, plan.objective
    blocks = plan.blocks
    hull = np.empty((levels.size, 2, n_time))
    extremiser = np.empty((levels.size, 2, n_time, params.dim))
    hull[-1], extremiser[-1] = deterministic, params.deterministic
    previous_domain = params.domain(1.0)
    below_one = np.arange(levels.size - 1)[::-1]
    both = senses.size
    # bound nodes (BatchedObjective): both bounds' optimisations in the same calls
    nodes_b, others_b = plan.bound_nodes(nodes), plan.bound_nodes(others)
    block_of = (nodes_b % n_time) // n_block  # each block's nodes in the order of a run of it alone
    rngs = [np.random.default_rng(strategy.seed) for _ in range(blocks)]
    previous: np.ndarray | None = None  # the higher level's optima, every bound node
    for step, a in enumerate(below_one):
        domain = params.domain(float(levels[a]))
        higher: list[np.ndarray] = []
        if previous is not None:  # the higher level's optimum, as it is and scaled out
            higher = [previous, domain.rescale_from(previous_domain, previous)]  # type: ignore[arg-type]
        first = [np.tile(params.deterministic, (nodes_b.size, 1))] + [h[nodes_b] for h in higher]
        n_extra = max(0, strategy.starts - len(first))
        extra = screened_starts(objective, domain, nodes_b, block_of, rngs, n_extra, strategy.screen)
        points = np.empty((both * n_time, params.dim))
        values = np.empty(both * n_time)
        points[nodes_b], values[nodes_b] = maximise(objective, domain, nodes_b, first + extra, strategy.iterations,
                                                    tolerance[nodes_b % n_time])  # fmt: skip
        if others.size:  # nodes between optimisation nodes: started from the bracketing optima (same bound)
            points[others_b], values[others_b] = follow_nodes(objective, domain, nodes_b, points[nodes_b], others_b,
                                                              [h[others_b] for h in higher], strategy.follow,
                                                              tolerance[others_b % n_time])  # fmt: skip
        points, values = neighbour_pass(objective, plan.curves(), points, values, strategy.window)
        previous = points
        values = reported_values(objective, points, values, np.arange(values.size))
        hull[a] = senses[:, None] * values.reshape(both, n_time)
        extremiser[a] = points.reshape(both, n_time, params.dim)
        if progress is not None:
            progress(step + 1, below_one.size)
        previous_domain = domain
    return {"hull": hull, "extremiser": extremiser, "deterministic": deterministic,
            "attrs": plan.finish(model, below_one.size)}  # fmt: skip
