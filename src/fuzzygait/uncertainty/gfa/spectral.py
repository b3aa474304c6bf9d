"""Spectral projected-gradient ascent (SPG: Birgin, Martínez & Raydan 2000) of many
α-level optimisations side by side: the default solver of
:class:`~fuzzygait.uncertainty.gfa.strategies.BatchedDirect`.

Each point ``x`` (one start of one bound node) moves along ``d = P(x + Λ g) − x`` — ``P``
the projection onto the α-level set (a radial clip per ball, a clip per box side), ``g``
the exact gradient of the (sense-adjusted) objective, ``Λ`` a step per block (per marker
ball; per coordinate of a box): the Barzilai–Borwein step ``sᵀs / (−sᵀy)`` of the
block's part of the point's last move (``s`` the move, ``y`` the change of the
gradient), i.e. the objective's own curvature along the path as a diagonal scaling;
where the move met no curvature (``sᵀy ≥ 0``) the step doubles.  A start's first
direction is the Frank–Wolfe one, to the linear model's optimum over the set (every ball's
surface point along its gradient), from where the first step per block is the one that
reaches its boundary.  A trial ``x + t d`` is accepted on the non-monotone Armijo condition
``f ≥ min(last 10 accepted values) + 10⁻⁴ t gᵀd`` (Grippo, Lampariello & Lucidi 1986:
the Barzilai–Borwein steps are erratic by nature and a monotone search throws most of
them away); a rejected one is followed by ``t`` from the quadratic through ``f(x)``,
``gᵀd`` and the trial's value (within ``[t/10, t/2]``).  Every iteration is one model call
with values and gradients of every active point's trial, so the gradient of an accepted
point is there for its next direction.  The best point a start visited is its result,
so the result is never worse than the start.

A point stops when its Frank–Wolfe gap ``gᵀ(argmax_{y∈D} gᵀy − x)`` — the most a linear
model could still gain anywhere in the set, zero at a first-order optimum — or an accepted
step's change of value falls to the node's tolerance, when its step fraction has shrunk
below 10⁻⁶, at the iteration cap, or once its value — or that of another start of the
same node — reaches the node's ceiling (the model's output is no band there:
:meth:`~fuzzygait.uncertainty.gfa.objective.BatchedObjective.ceilings`; the best of the
node's starts is that point whatever the others reach).

On an extreme that lies on a kink of the objective (the gradient does not vanish there)
the steps crawl; :func:`~fuzzygait.uncertainty.gfa.levels.polish_kinks` finishes such
optima with Frank–Wolfe iterations.  Measured against the Frank–Wolfe solver on the joint
angles of the sample trials (``benchmarks/markererror_solvers.py``,
``benchmarks/RESULTS.md``): closer to the widest band any run found, in less CPU.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.gfa.objective import NodeObjective, best_of_starts, nodes_at_ceiling, stacked_starts

#: Sufficient increase of the Armijo condition.
ARMIJO = 1e-4
#: A rejected trial shrinks its step fraction to between these fractions of it.
SHRINK = (0.1, 0.5)
#: A point stops once its step fraction has shrunk below this.
MIN_FRACTION = 1e-6
#: Accepted values remembered by the non-monotone line search (Grippo, Lampariello & Lucidi 1986).
MEMORY = 10
#: Bounds of the Barzilai–Borwein step, relative to the point's first step.
STEP_RANGE = (1e-8, 1e8)


def _rows_dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def _block_size(domain: BoxDomain | BallsDomain) -> int:
    """Coordinates per block of the step: a ball's (3 for a marker), 1 for a box."""
    return domain.block if isinstance(domain, BallsDomain) else 1


def _per_block(domain: BoxDomain | BallsDomain, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``aᵀb`` per row and block: ``(n, n_blocks)``."""
    block = _block_size(domain)
    shape = (a.shape[0], a.shape[1] // block, block)
    return np.einsum("ijk,ijk->ij", a.reshape(shape), b.reshape(shape))


def _half_width(domain: BoxDomain | BallsDomain) -> np.ndarray:
    """Per block the distance from the centre to the set's boundary (radius, half side)."""
    if isinstance(domain, BallsDomain):
        return np.asarray(domain.radii, dtype=float)
    return 0.5 * (np.asarray(domain.upper, dtype=float) - np.asarray(domain.lower, dtype=float))


def frank_wolfe_gap(domain: BoxDomain | BallsDomain, P: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """``gᵀ(argmax_{y ∈ D} gᵀy − x)`` per row: ≥ 0, zero at a first-order optimum."""
    return _rows_dot(gradient, domain.linear_argmax(gradient) - P)


def maximise_spectral(
    objective: NodeObjective,
    domain: BoxDomain | BallsDomain,
    nodes: np.ndarray,
    starts: list[np.ndarray],
    iterations: int,
    tolerance: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Best point and value per node over all starting points (the signature of
    :func:`~fuzzygait.uncertainty.gfa.batched.maximise`; ``iterations`` model calls at
    most, the first the starts' gradients)."""
    P, rows, stop = stacked_starts(domain, nodes, starts, tolerance)  # (S k, n_p): start-major
    counts = objective.counts
    counts.points += P.shape[0]
    counts.iterations += 1
    value, gradient = objective.values_and_gradients(P, rows)
    block = _block_size(domain)
    norm = np.sqrt(_per_block(domain, gradient, gradient))  # (n, n_blocks)
    width = np.broadcast_to(_half_width(domain), norm.shape)
    first = np.where(norm > 0, width / np.where(norm > 0, norm, 1.0), 0.0)  # each block reaches its boundary
    first = np.maximum(first, 1e-300)
    step = first.copy()
    fraction = np.ones(P.shape[0])
    direction = np.zeros_like(P)
    fresh = np.ones(P.shape[0], dtype=bool)  # a new direction is due (the point moved)
    started = np.zeros(P.shape[0], dtype=bool)  # the point has a direction
    ceiling = objective.ceilings(rows)  # a value there or beyond: no band, nothing more to find
    active = (frank_wolfe_gap(domain, P, gradient) > stop) & (value < ceiling)
    active &= ~nodes_at_ceiling(value, ceiling, len(starts))
    recent = np.repeat(value[:, None], MEMORY, axis=1)  # the last accepted values: the line search's reference
    best_P, best_value = P.copy(), value.copy()
    for _ in range(iterations - 1):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        counts.iterations += 1
        counts.point_iterations += idx.size
        new = idx[fresh[idx]]
        direction[new] = domain.project(P[new] + np.repeat(step[new], block, axis=1) * gradient[new]) - P[new]
        opening = new[~started[new]]  # a start's first move: to the linear model's optimum
        direction[opening] = domain.linear_argmax(gradient[opening]) - P[opening]
        fraction[new], fresh[new], started[new] = 1.0, False, True
        t, P_i, gradient_i = fraction[idx], P[idx], gradient[idx]  # gathered once: (active, n_p) copies
        direction_i = direction[idx]
        slope = _rows_dot(gradient_i, direction_i)  # >= 0: d is an ascent direction
        trial = P_i + t[:, None] * direction_i
        tried, tried_gradient = objective.values_and_gradients(trial, rows[idx])
        value_i = value[idx]
        gain = tried - value_i
        reference = recent[idx].min(axis=1) - value_i  # <= 0: the worst of the last accepted values
        accept = (gain > reference) & (gain >= reference + ARMIJO * t * slope)
        counts.no_gain += int(idx.size - np.count_nonzero(accept))
        moved = idx[accept]
        to_P, to_value, to_gradient = trial[accept], tried[accept], tried_gradient[accept]
        s, y = to_P - P_i[accept], to_gradient - gradient_i[accept]
        sy, ss = _per_block(domain, s, y), _per_block(domain, s, s)  # per block: a diagonal scaling
        lo, hi = STEP_RANGE[0] * first[moved], STEP_RANGE[1] * first[moved]
        longer = np.minimum(2.0 * step[moved], hi)  # no curvature seen along the move: a longer step
        bb = np.where(sy < 0, np.clip(ss / np.where(sy < 0, -sy, 1.0), lo, hi), longer)
        step[moved] = np.where(ss > 0, bb, step[moved])  # a block that did not move keeps its step
        P[moved], value[moved], gradient[moved] = to_P, to_value, to_gradient
        recent[moved] = np.roll(recent[moved], 1, axis=1)
        recent[moved, 0] = to_value
        gained = to_value > best_value[moved]
        up = moved[gained]
        best_P[up], best_value[up] = to_P[gained], to_value[gained]
        fresh[moved] = True
        held = idx[~accept]  # back along the same direction: the quadratic's maximiser
        curvature = 2.0 * (t[~accept] * slope[~accept] - gain[~accept])
        guess = np.where(curvature > 0, t[~accept] ** 2 * slope[~accept] / np.where(curvature > 0, curvature, 1.0),
                         SHRINK[0] * t[~accept])  # fmt: skip
        fraction[held] = np.clip(guess, SHRINK[0] * t[~accept], SHRINK[1] * t[~accept])
        gap = frank_wolfe_gap(domain, to_P, to_gradient)
        converged = (gap <= stop[moved]) | (np.abs(gain[accept]) <= stop[moved]) | (to_value >= ceiling[moved])
        active[moved[converged]] = False
        active[held[(fraction[held] < MIN_FRACTION) | (slope[~accept] <= stop[held])]] = False
        active &= ~nodes_at_ceiling(best_value, ceiling, len(starts))
    counts.unconverged += int(np.count_nonzero(active))
    return best_of_starts(counts, best_P, best_value, len(starts))
