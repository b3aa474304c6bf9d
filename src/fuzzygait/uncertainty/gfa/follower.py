"""The Graph Follower algorithm (thesis §2.6, with the improvements of §2.6.2).

For every α-level below 1 and every optimisation node (every ``stride``-th time node),
the upper and the lower hull of the target output are sought by α-level optimisation
(Eq. 2.23) over the α-level set of the fuzzy parameters:

* ``mode="linearised"`` (thesis OP-III): the model is replaced by its first-order Taylor
  expansion about the library entry that currently gives the extreme at this node; the
  linear model's optimum over the α-level set is known in closed form (a vertex of the
  box, a point on the ball surfaces). The first step is the thesis' step; when it does
  not improve the node's extreme, the directional derivatives at both ends locate the
  interior extremum by a secant step (at most ``max_iterations`` steps per node), which
  finds interior extrema that a single linear step cannot.
* ``mode="direct"`` (thesis OP-II, for cheap models): multistart local optimisation of
  the model itself at the node (``starts`` starting points: the previous node's
  optimum, the library's best entry and seeded random points).

A candidate parameter is simulated only when it differs from every library entry by
more than ``novelty_tol`` relative to the deterministic value (Eq. 2.24). Post-
processing (step 5 of the algorithm) takes, at every time node, the max and min over
every library trajectory whose parameters lie in the α-level set — entries found for a
higher α-level count for the lower ones, since the α-level sets are nested — followed
by a nesting repair (Fig. 2.11) so a lower α-level's hull always contains the higher
one's. The α = 1 hull is the deterministic run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy.optimize import minimize

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import batched
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.library import Library
from fuzzygait.uncertainty.model import CountedModel
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector
from fuzzygait.uncertainty.postprocess import repair_nesting

BOUNDS = ("lower", "upper")
SENSES = {"lower": -1.0, "upper": 1.0}
#: Slack (relative to the parameter scale) when deciding whether a library entry lies
#: in an α-level set; covers rounding in projections onto the set.
MEMBERSHIP_SLACK = 1e-12

Progress = Callable[[int, int], None]


@dataclass
class _Counts:
    optimisations: int = 0


def _check_arguments(alphas: Sequence[float], mode: str, stride: int, starts: int) -> np.ndarray:
    levels = np.unique(np.asarray(alphas, dtype=float))
    if levels.size == 0 or levels.min() < 0 or levels.max() > 1:
        raise ParameterError(f"alphas must lie in [0, 1]; got {list(alphas)}")
    if mode not in ("linearised", "direct"):
        raise ParameterError(f"mode must be 'linearised' or 'direct'; got {mode!r}")
    if not isinstance(stride, int) or stride < 1:
        raise ParameterError(f"stride must be a whole number >= 1; got {stride!r}")
    if not isinstance(starts, int) or starts < 1:
        raise ParameterError(f"starts must be a whole number >= 1; got {starts!r}")
    return levels


def optimisation_nodes(n_time: int, stride: int) -> np.ndarray:
    """Every ``stride``-th time node, plus the last one."""
    return np.unique(np.append(np.arange(0, n_time, stride), n_time - 1))


class _Follower:
    """State of one Graph Follower run (library, counters, options)."""

    def __init__(self, model: CountedModel, params: FuzzyVector | FuzzyBalls, *, mode: str,
                 novelty_tol: float, starts: int, max_iterations: int, seed: int,
                 nodes: np.ndarray) -> None:  # fmt: skip
        self.model, self.params, self.mode = model, params, mode
        self.novelty_tol, self.starts, self.max_iterations = novelty_tol, starts, max_iterations
        self.rng = np.random.default_rng(seed)
        self.scale = params.scale
        self.library = Library(params.dim, model.n_time, self.scale, nodes=nodes)
        self._domains: dict[float, BoxDomain | BallsDomain] = {}
        self.counts = _Counts()
        self.linearised = mode == "linearised"
        self.gain_tol = 0.0  # set once the deterministic trajectory is known

    # ------------------------------------------------------------------ evaluations
    def simulate(self, p: np.ndarray) -> int:
        """Evaluate ``p`` (with sensitivities in linearised mode) and store it."""
        if self.linearised:
            f, jac = self.model.trajectory_and_sensitivities(p)
            return self.library.add(p, f, jac)
        return self.library.add(p, self.model.trajectory(p))

    def domain(self, alpha: float) -> BoxDomain | BallsDomain:
        """The α-level set (one object per level, so membership caching can key on α)."""
        if alpha not in self._domains:
            self._domains[alpha] = self.params.domain(alpha)
        return self._domains[alpha]

    def admissible(self, alpha: float) -> np.ndarray:
        """Mask of the library entries inside the α-level set (cached, incremental)."""
        domain, slack = self.domain(alpha), MEMBERSHIP_SLACK * float(self.scale.max())
        return self.library.inside(alpha, lambda p: domain.contains(p, tol=slack))

    # ------------------------------------------------------------------ one node
    def optimise_node(self, alpha: float, node: int, sense: float,
                      warm: np.ndarray | None) -> np.ndarray:  # fmt: skip
        self.counts.optimisations += 1
        if self.linearised:
            return self._linearised(alpha, node, sense)
        return self._direct(alpha, node, sense, warm)

    def _linearised(self, alpha: float, node: int, sense: float) -> np.ndarray:
        library, domain = self.library, self.domain(alpha)
        best = library.best(self.admissible(alpha), node, sense)
        if not library.has_sensitivities(best):  # stored without sensitivities: add them
            best = self.simulate(library.parameters[best])
        p0, f0 = library.parameters[best], library.trajectories[best, node]
        g0 = sense * library.gradient(best, node)
        step = self._linear_step(domain, g0, p0)  # the thesis' step: the linear model's optimum
        for _ in range(self.max_iterations):
            size = float(np.max(np.abs(step) / self.scale)) if step.size else 0.0
            if size <= self.novelty_tol or float(g0 @ step) <= self.gain_tol:
                break
            candidate = domain.project(p0 + step)
            index, distance = library.closest(candidate)
            if distance > self.novelty_tol or not library.has_sensitivities(index):
                index = self.simulate(candidate)
            f1 = library.trajectories[index, node]
            g1 = sense * library.gradient(index, node)
            if sense * f1 > sense * f0:  # improvement: continue from there
                p0, f0, g0 = library.parameters[index], f1, g1
                step = self._linear_step(domain, g0, p0)
                continue
            step = self._shortened(domain, step, g0, g1)
        return p0

    def _linear_step(self, domain: BoxDomain | BallsDomain, g0: np.ndarray, p0: np.ndarray) -> np.ndarray:
        """Step from ``p0`` to the linear model's optimum over the α-level set.

        In a box, coordinates whose own predicted gain ``g_i · Δp_i`` is at most
        ``gain_tol / n_p`` stay where they are: a parameter with (numerically) no effect
        at this node — an inert inertia in a planar motion, or one whose sensitivity is
        passing through zero — would otherwise flip to the opposite vertex on the sign of
        round-off and make an otherwise known parameter set "new". Together the skipped
        coordinates give up at most ``gain_tol`` of predicted output.
        """
        step = domain.linear_argmax(g0) - p0
        if isinstance(domain, BoxDomain) and step.size:
            gains = g0 * step
            step = np.where(gains > self.gain_tol / step.size, step, 0.0)
        return step

    @staticmethod
    def _shortened(domain: BoxDomain | BallsDomain, step: np.ndarray, g0: np.ndarray,
                   g1: np.ndarray) -> np.ndarray:  # fmt: skip
        """Shorten a step that overshot: where the derivative along the step changed sign
        between its ends, a secant estimate of the stationary point. In a box this is
        done per coordinate (an interior optimum in one coordinate, a bound in another);
        otherwise along the whole step. Without a sign change: a quarter step."""
        slope0, slope1 = g0 * step, g1 * step
        if isinstance(domain, BoxDomain):
            crossed = (slope0 > 0) & (slope1 < 0)
            with np.errstate(invalid="ignore", divide="ignore"):
                secant = np.where(crossed, slope0 / (slope0 - slope1), 1.0)
            fraction = np.clip(secant, 0.05, 1.0)
            if np.all(fraction > 0.999):  # no coordinate crossed: coupling; back off
                fraction = np.full_like(fraction, 0.25)
            return step * fraction
        total0, total1 = float(slope0.sum()), float(slope1.sum())
        fraction = total0 / (total0 - total1) if total1 < 0 else 0.25
        return step * float(np.clip(fraction, 0.05, 0.9))

    def _direct(self, alpha: float, node: int, sense: float,
                warm: np.ndarray | None) -> np.ndarray:  # fmt: skip
        library, domain = self.library, self.domain(alpha)
        starts = [library.parameters[library.best(self.admissible(alpha), node, sense)]]
        if warm is not None:
            starts.append(domain.project(warm))
        if self.starts > len(starts):
            starts += list(domain.sample(self.rng, self.starts - len(starts)))
        starts = starts[: self.starts]

        def objective(p: np.ndarray) -> float:
            value, trajectory = self.model.node(p, node)
            if trajectory is not None:  # a full simulation was needed: keep it
                library.add(p.copy(), trajectory)
            return -sense * value

        method = "L-BFGS-B" if isinstance(domain, BoxDomain) else "SLSQP"
        best_p, best_v = starts[0], objective(starts[0])
        for start in starts:
            result = minimize(objective, start, method=method, bounds=domain.scipy_bounds(),
                              constraints=domain.scipy_constraints(),
                              options={"maxiter": 200})  # fmt: skip
            candidate = domain.project(result.x)
            if result.fun < best_v and domain.contains(candidate, tol=1e-9):
                best_p, best_v = candidate, float(result.fun)
        # Novelty is judged against the entries inside this α-level set only: SLSQP may
        # end marginally outside a ball (~1e-7); that iterate is in the library but never
        # counts in the hull, so it must not stop the projected optimum being simulated.
        inside = library.parameters[self.admissible(alpha)]
        distance = np.max(np.abs(inside - best_p) / self.scale, axis=1)
        if distance.size == 0 or float(distance.min()) > self.novelty_tol:
            self.simulate(best_p)
        return best_p


def graph_follower(
    model: object,
    params: FuzzyVector | FuzzyBalls,
    alphas: Sequence[float] = (0.0, 0.5, 1.0),
    *,
    mode: str = "linearised",
    stride: int = 1,
    novelty_tol: float = 1e-4,
    starts: int = 10,
    max_iterations: int = 4,
    gain_tol: float = 1e-7,
    seed: int = 0,
    progress: Progress | None = None,
    batch_iterations: int = 25,
    window: int = 2,
    screen: int = 64,
) -> xr.Dataset:
    """Fuzzy target output of ``model`` for fuzzy parameters ``params``.

    Args:
        model: see :mod:`fuzzygait.uncertainty.model` (``times``, ``evaluate``, and
            optionally ``evaluate_with_sensitivities`` / ``evaluate_node``).
        params: :class:`FuzzyVector` (α-cut boxes) or :class:`FuzzyBalls`.
        alphas: α-levels; 1 is always added (the deterministic run).
        mode: ``"linearised"`` or ``"direct"`` (see module docstring).
        stride: optimise at every ``stride``-th time node (and the last).
        novelty_tol: relative parameter difference below which no new simulation is
            run (default 1e-4 = 0.01 %, Eq. 2.24).
        starts: multistart points per node in direct mode (default 10).
        max_iterations: linearised steps per node at most (1 = the thesis' single step).
        gain_tol: a linearised step is not simulated when the linear model predicts a
            gain below ``gain_tol`` times the largest deterministic output magnitude.
        seed: seed of the random multistart points.
        progress: called as ``progress(done, total)`` after each optimisation.
        batch_iterations: iterations of the all-nodes-at-once direct mode (used when the
            model offers ``evaluate_nodes``; see :mod:`fuzzygait.uncertainty.batched`).
        window: neighbouring nodes (each side) at which that mode re-evaluates each
            node's optimum.
        screen: random points per node screened for that mode's random starts.

    Returns:
        ``xarray.Dataset`` with ``hull (alpha, bound, time)``, ``deterministic (time)``,
        ``extremiser (alpha, bound, time, parameter)`` (the library parameters that give
        each hull value) and attributes ``model_evaluations``, ``node_evaluations``,
        ``optimisations``, ``library_size``, ``mode``, ``stride``, ``novelty_tol``,
        ``starts``, ``max_iterations``, ``seed``.
    """
    levels = _check_arguments(alphas, mode, stride, starts)
    levels = np.union1d(levels, [1.0])
    counted = CountedModel(model, scale=params.scale)
    if mode == "direct" and callable(getattr(model, "evaluate_nodes", None)):
        return _batched_direct(counted, params, levels, stride=stride, starts=starts, seed=seed,
                               iterations=batch_iterations, window=window, screen=screen,
                               progress=progress)  # fmt: skip
    nodes = optimisation_nodes(counted.n_time, stride)
    follower = _Follower(counted, params, mode=mode, novelty_tol=novelty_tol, starts=starts,
                         max_iterations=max_iterations, seed=seed, nodes=nodes)  # fmt: skip
    det_index = follower.simulate(params.deterministic)
    deterministic = follower.library.trajectories[det_index].copy()
    follower.gain_tol = gain_tol * max(float(np.max(np.abs(deterministic))), np.finfo(float).tiny)

    below_one = levels[levels < 1.0][::-1]  # highest first: its finds help lower levels
    total, done = 2 * nodes.size * below_one.size, 0
    for alpha in below_one:
        for bound in BOUNDS:
            warm = None
            for node in nodes:
                warm = follower.optimise_node(float(alpha), int(node), SENSES[bound], warm)
                done += 1
                if progress is not None:
                    progress(done, total)

    hull, extremiser = _post_process(follower, params, levels, deterministic)
    hull = repair_nesting(hull)
    times = np.asarray(model.times, dtype=float)
    return xr.Dataset(
        {
            "hull": (("alpha", "bound", "time"), hull),
            "deterministic": (("time",), deterministic),
            "extremiser": (("alpha", "bound", "time", "parameter"), extremiser),
        },
        coords={"alpha": levels, "bound": list(BOUNDS), "time": times, "parameter": params.names},
        attrs={
            "model_evaluations": counted.evaluations,
            "node_evaluations": counted.node_evaluations,
            "optimisations": follower.counts.optimisations,
            "library_size": len(follower.library),
            "mode": mode,
            "stride": stride,
            "novelty_tol": novelty_tol,
            "starts": starts,
            "max_iterations": max_iterations,
            "gain_tol": gain_tol,
            "seed": seed,
        },
    )


def _result_dataset(model: CountedModel, params: FuzzyVector | FuzzyBalls, levels: np.ndarray,
                    hull: np.ndarray, extremiser: np.ndarray, deterministic: np.ndarray,
                    attrs: dict[str, object]) -> xr.Dataset:  # fmt: skip
    times = np.asarray(model.model.times, dtype=float)
    return xr.Dataset(
        {
            "hull": (("alpha", "bound", "time"), hull),
            "deterministic": (("time",), deterministic),
            "extremiser": (("alpha", "bound", "time", "parameter"), extremiser),
        },
        coords={"alpha": levels, "bound": list(BOUNDS), "time": times, "parameter": params.names},
        attrs={"model_evaluations": model.evaluations, "node_evaluations": model.node_evaluations, **attrs},
    )


def _batched_direct(model: CountedModel, params: FuzzyVector | FuzzyBalls, levels: np.ndarray, *,
                    stride: int, starts: int, seed: int, iterations: int, window: int,
                    screen: int, progress: Progress | None) -> xr.Dataset:  # fmt: skip
    """Direct mode with all optimisation nodes solved side by side (see
    :mod:`fuzzygait.uncertainty.batched`)."""
    deterministic = model.trajectory(params.deterministic)
    n_time, rng = model.n_time, np.random.default_rng(seed)
    nodes = optimisation_nodes(n_time, stride)
    others = np.setdiff1d(np.arange(n_time), nodes)
    counts = batched.BatchCounts()
    hull = np.empty((levels.size, 2, n_time))
    extremiser = np.empty((levels.size, 2, n_time, params.dim))
    hull[-1], extremiser[-1] = deterministic, params.deterministic
    tolerance = 1e-7 * max(float(np.max(np.abs(deterministic))), 1.0)
    previous: dict[str, np.ndarray] = {}
    previous_domain = params.domain(1.0)
    below_one = np.arange(levels.size - 1)[::-1]
    for step, a in enumerate(below_one):
        domain = params.domain(float(levels[a]))
        for b, bound in enumerate(BOUNDS):
            objective = batched.BatchedObjective(model.model, SENSES[bound], params.scale, 1e-6, counts)
            first = [np.tile(params.deterministic, (nodes.size, 1))]
            if bound in previous:  # the higher level's optimum, as it is and scaled out
                first += [previous[bound], domain.rescale_from(previous_domain, previous[bound])]
            extra = batched.screened_starts(objective, domain, nodes, rng, max(0, starts - len(first)), screen)
            points, values = batched.maximise(objective, domain, nodes, first + extra, iterations, tolerance)
            points, values = batched.neighbour_pass(objective, nodes, points, values, window)
            previous[bound] = points
            hull[a, b, nodes], extremiser[a, b, nodes] = SENSES[bound] * values, points
            if others.size:  # nodes between optimisation nodes: the bracketing optima
                right = np.minimum(np.searchsorted(nodes, others), nodes.size - 1)
                left = np.maximum(right - 1, 0)
                v_left = objective.values(points[left], others)
                v_right = objective.values(points[right], others)
                use_right = v_right > v_left
                hull[a, b, others] = SENSES[bound] * np.where(use_right, v_right, v_left)
                extremiser[a, b, others] = np.where(use_right[:, None], points[right], points[left])
            if progress is not None:
                progress(2 * step + b + 1, 2 * below_one.size)
        previous_domain = domain
    model.node_evaluations += counts.node_evaluations
    attrs = {"optimisations": int(2 * below_one.size * nodes.size), "library_size": 0, "mode": "direct",
             "stride": stride, "starts": starts, "batch_iterations": iterations, "window": window, "screen": screen,
             "iterations": counts.iterations, "seed": seed}  # fmt: skip
    return _result_dataset(model, params, levels, repair_nesting(hull), extremiser, deterministic, attrs)


def _post_process(follower: _Follower, params: FuzzyVector | FuzzyBalls, levels: np.ndarray,
                  deterministic: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Hulls from the whole library at every time node (algorithm step 5)."""
    library = follower.library
    n_time = deterministic.size
    hull = np.empty((levels.size, 2, n_time))
    extremiser = np.empty((levels.size, 2, n_time, params.dim))
    columns = np.arange(n_time)
    for a, alpha in enumerate(levels):
        if alpha == 1.0:
            hull[a] = deterministic
            extremiser[a] = params.deterministic
            continue
        admissible = np.flatnonzero(follower.admissible(float(alpha)))
        values = library.trajectories[admissible]
        for b, bound in enumerate(BOUNDS):
            pick = np.argmax(SENSES[bound] * values, axis=0)
            hull[a, b] = values[pick, columns]
            extremiser[a, b] = library.parameters[admissible[pick]]
    return hull, extremiser
