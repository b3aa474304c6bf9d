"""The library-based Graph Follower (thesis §2.6, with the improvements of §2.6.2): the
:class:`~fuzzygait.uncertainty.gfa.strategies.Linearised` and
:class:`~fuzzygait.uncertainty.gfa.strategies.Direct` strategies.

For every α-level below 1 (highest first) and every optimisation node, the upper and the
lower hull are sought by α-level optimisation (Eq. 2.23) over the α-level set. A
candidate parameter is simulated only when it differs from every library entry by more
than ``novelty_tol`` relative to the parameter scale (Eq. 2.24). Post-processing (step 5
of the algorithm) takes, at every time node, the max and min over every library
trajectory whose parameters lie in the α-level set — entries found for a higher α-level
count for the lower ones, since the α-level sets are nested — followed by a nesting
repair (Fig. 2.11) in the caller. The α = 1 hull is the deterministic run.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass

import numpy as np

from fuzzygait.core.schema import BOUNDS, SENSES
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.domains import BallsDomain, BoxDomain
from fuzzygait.uncertainty.gfa.batched import optimisation_nodes
from fuzzygait.uncertainty.gfa.library import Library
from fuzzygait.uncertainty.gfa.strategies import Direct, Linearised
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector

#: Slack (relative to the parameter scale) when deciding whether a library entry lies
#: in an α-level set; covers rounding in projections onto the set.
MEMBERSHIP_SLACK = 1e-12

Progress = Callable[[int, int], None]


@dataclass
class _Counts:
    optimisations: int = 0


class _Follower:
    """State of one Graph Follower run (library, counters, options)."""

    def __init__(self, model: CountedModel, params: FuzzyVector | FuzzyBalls, strategy: Linearised | Direct,
                 nodes: np.ndarray) -> None:  # fmt: skip
        self.model, self.params = model, params
        self.linearised = isinstance(strategy, Linearised)
        self.novelty_tol = strategy.novelty_tol
        self.max_iterations = strategy.max_iterations if isinstance(strategy, Linearised) else 0
        self.starts = strategy.starts if isinstance(strategy, Direct) else 0
        self.rng = np.random.default_rng(strategy.seed if isinstance(strategy, Direct) else 0)
        self.scale = params.scale
        self.library = Library(params.dim, model.n_time, self.scale, nodes=nodes)
        self._domains: dict[float, BoxDomain | BallsDomain] = {}
        self.counts = _Counts()
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
        steps = self.linearised_steps(alpha, node, sense)
        try:
            wanted = next(steps)
            while True:
                wanted = steps.send(self.simulate(wanted))
        except StopIteration as done:
            return np.asarray(done.value)

    def linearised_steps(self, alpha: float, node: int, sense: float) -> Generator[np.ndarray, int, np.ndarray]:
        """The linearised optimisation of one node as a generator: it yields each
        parameter vector it needs simulated (with sensitivities) and is sent back that
        simulation's library index; it returns the optimum found."""
        library, domain = self.library, self.domain(alpha)
        best = library.best(self.admissible(alpha), node, sense)
        if not library.has_sensitivities(best):  # stored without sensitivities: add them
            best = yield library.parameters[best]
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
                index = yield candidate
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
        along = total0 / (total0 - total1) if total1 < 0 else 0.25
        return step * float(np.clip(along, 0.05, 0.9))

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

        from scipy.optimize import minimize  # here: scipy.optimize costs a worker process 0.25 s to import

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


def run_follower(model: CountedModel, params: FuzzyVector | FuzzyBalls, levels: np.ndarray,
                 strategy: Linearised | Direct, progress: Progress | None) -> dict[str, object]:  # fmt: skip
    """Hulls ``(alpha, bound, time)`` (before the nesting repair), their extremisers,
    the deterministic trajectory and the run's counts."""
    nodes = optimisation_nodes(model.n_time, strategy.stride)
    follower = _Follower(model, params, strategy, nodes)
    det_index = follower.simulate(params.deterministic)
    deterministic = follower.library.trajectories[det_index].copy()
    if isinstance(strategy, Linearised):
        follower.gain_tol = strategy.gain_tol * max(float(np.max(np.abs(deterministic))), np.finfo(float).tiny)

    below_one = levels[levels < 1.0][::-1]  # highest first: its finds help lower levels
    if isinstance(strategy, Linearised) and strategy.tracks == "side-by-side":
        _side_by_side(follower, [(float(a), SENSES[b]) for a in below_one for b in BOUNDS], nodes, progress)
    else:
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
    return {"hull": hull, "extremiser": extremiser, "deterministic": deterministic,
            "attrs": {"optimisations": follower.counts.optimisations, "library_size": len(follower.library)}}


def _side_by_side(follower: _Follower, tracks: list[tuple[float, float]], nodes: np.ndarray,
                  progress: Progress | None) -> None:
    """Follow every ``(alpha, sense)`` track at once, node after node: in each round
    every track runs until it needs a simulation (or finishes a node and starts its
    next), then the round's simulations are evaluated together and added to the library
    in track order. Everything depends on the tracks and the library only, never on how
    the rows are evaluated."""
    total, done = len(tracks) * nodes.size, 0
    position = [0] * len(tracks)
    steps: list[Generator[np.ndarray, int, np.ndarray] | None] = [None] * len(tracks)
    wanted: list[np.ndarray | None] = [None] * len(tracks)
    answer: list[int | None] = [None] * len(tracks)
    while True:
        for k, (alpha, sense) in enumerate(tracks):
            while wanted[k] is None and position[k] < nodes.size:
                if steps[k] is None:
                    follower.counts.optimisations += 1
                    steps[k] = follower.linearised_steps(alpha, int(nodes[position[k]]), sense)
                generator, reply = steps[k], answer[k]
                assert generator is not None
                try:
                    wanted[k] = next(generator) if reply is None else generator.send(reply)
                    answer[k] = None
                except StopIteration:
                    steps[k], answer[k] = None, None
                    position[k] += 1
                    done += 1
                    if progress is not None:
                        progress(done, total)
        asked = [k for k in range(len(tracks)) if wanted[k] is not None]
        if not asked:
            return
        rows = np.array([wanted[k] for k in asked])
        values, jacobians = follower.model.trajectories_and_sensitivities_many(rows)
        for k, f, jac in zip(asked, values, jacobians, strict=True):
            answer[k] = follower.library.add(np.asarray(wanted[k]), f, jac)
            wanted[k] = None


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
