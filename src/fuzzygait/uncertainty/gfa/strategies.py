"""The α-level optimisation strategies of the Graph Follower algorithm, each with its
own options (thesis §2.6, §2.6.2).

* :class:`Linearised` (thesis OP-III): the model is replaced by its first-order Taylor
  expansion about the library entry that currently gives the extreme at a node; the
  linear model's optimum over the α-level set is closed form (a box vertex, a point on
  the ball surfaces). When that step does not improve the node, a secant step on the
  directional derivatives finds interior extrema (at most ``max_iterations`` steps per
  node; 1 = the thesis' single step).
* :class:`Direct` (thesis OP-II, cheap models): multistart L-BFGS-B/SLSQP on the model
  itself at each node, warm-started from the previous node.
* :class:`BatchedDirect` (OP-II for models with the ``"nodes"`` capability, e.g. joint
  angles from markers): all optimisation nodes side by side, first-order steps with a
  line search (see :mod:`fuzzygait.uncertainty.gfa.batched`).

Linearised and Direct keep a library of whole trajectories and take the hulls from it
(post-processing, step 5 of the algorithm); BatchedDirect evaluates single nodes only.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from fuzzygait.core.errors import ParameterError


def _whole(name: str, value: object, minimum: int) -> None:
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise ParameterError(f"{name} must be a whole number >= {minimum}; got {value!r}")


def _non_negative(name: str, value: float) -> None:
    if not value >= 0:
        raise ParameterError(f"{name} must be >= 0; got {value!r}")


#: The orders in which the Linearised strategy follows its (α-level, bound) tracks.
TRACKS = ("one-by-one", "side-by-side")


@dataclass(frozen=True)
class Linearised:
    """Linearised α-level optimisation (OP-III).

    Attributes:
        stride: optimise at every ``stride``-th time node (and the last).
        novelty_tol: relative parameter difference below which no new simulation is
            run (default 1e-4 = 0.01 %, Eq. 2.24).
        max_iterations: linearised steps per node at most (1 = the thesis' single step).
        gain_tol: a step is not simulated when the linear model predicts a gain below
            ``gain_tol`` times the largest deterministic output magnitude.
        tracks: ``"one-by-one"`` (the thesis' order: each α-level, highest first, its
            upper then its lower hull, node after node) or ``"side-by-side"``: every
            (α-level, bound) track advances at once, sharing one library, and the
            simulations the tracks ask for in a round are evaluated together — in
            parallel on a model that evaluates many parameter rows at once (an
            :class:`~fuzzygait.uncertainty.execution.Evaluator`'s). The rounds do not
            depend on the number of workers, so neither do the hulls.
    """

    stride: int = 1
    novelty_tol: float = 1e-4
    max_iterations: int = 4
    gain_tol: float = 1e-7
    tracks: str = "one-by-one"

    name = "linearised"

    def __post_init__(self) -> None:
        _whole("stride", self.stride, 1)
        _whole("max_iterations", self.max_iterations, 1)
        _non_negative("novelty_tol", self.novelty_tol)
        _non_negative("gain_tol", self.gain_tol)
        if self.tracks not in TRACKS:
            raise ParameterError(f"tracks must be {' or '.join(TRACKS)}; got {self.tracks!r}")

    def options(self) -> dict[str, object]:
        """The options, for the result's attributes."""
        return asdict(self)


@dataclass(frozen=True)
class Direct:
    """Multistart optimisation of the model itself at each node (OP-II).

    Attributes:
        stride: optimise at every ``stride``-th time node (and the last).
        novelty_tol: as in :class:`Linearised`.
        starts: starting points per node (the library's best entry, the previous node's
            optimum, then seeded random points).
        seed: seed of the random starting points.
    """

    stride: int = 1
    novelty_tol: float = 1e-4
    starts: int = 10
    seed: int = 0

    name = "direct"

    def __post_init__(self) -> None:
        _whole("stride", self.stride, 1)
        _whole("starts", self.starts, 1)
        _non_negative("novelty_tol", self.novelty_tol)

    def options(self) -> dict[str, object]:
        return asdict(self)


#: Where :class:`BatchedDirect` takes its gradients from.
GRADIENT_SOURCES = ("auto", "differences")
#: :class:`BatchedDirect`'s local solvers.
BATCHED_SOLVERS = ("spectral", "frank-wolfe")


@dataclass(frozen=True)
class BatchedDirect:
    """All optimisation nodes solved side by side (needs the ``"nodes"`` capability).

    A model may declare ``blocks`` (int): its time nodes are that many independent
    outputs of the same parameters, one after the other (e.g. the three components of a
    joint angle); each is then optimised as it would be alone, in shared calls
    (:func:`~fuzzygait.uncertainty.gfa.batched.run_batched`).

    Attributes:
        stride: optimise at every ``stride``-th time node (and the last) with the full
            multistart; the nodes in between start from the best of the two bracketing
            optima (and the higher α-level's optimum there) — the Graph Follower's
            neighbour starts — and are refined by ``follow`` iterations.
        follow: iterations at the nodes between optimisation nodes (0: they take the
            better bracketing optimum as it is).
        starts: starting points per node (the deterministic parameters, the higher
            α-level's optimum as it is and scaled out, then screened random points).
        iterations: first-order iterations at most (``"spectral"``: model calls per
            start at most).
        window: neighbouring nodes (each side) at which each node's optimum is
            re-evaluated.
        screen: random points per node screened for the random starts.
        seed: seed of the random points.
        gradients: ``"auto"``: the model's exact gradients where it declares
            ``"node_gradients"``, else forward differences; ``"differences"``: forward
            differences always (``1 + n_p`` evaluations per gradient).
        solver: ``"spectral"``: for fuzzy balls, every α-level in one optimisation
            (:mod:`fuzzygait.uncertainty.gfa.levels`) by spectral projected-gradient
            ascent, one model call per iteration (:mod:`fuzzygait.uncertainty.gfa.spectral`),
            the optima on kinks finished by a few Frank–Wolfe iterations;
            box-shaped α-cuts (:class:`~fuzzygait.uncertainty.parameters.FuzzyVector`,
            e.g. the spherical marker-error formulation, whose seams at φ = ±π stall the
            spectral steps — measured wider bands with Frank–Wolfe there) are solved level
            by level by Frank–Wolfe either way.  ``"frank-wolfe"``: level by level,
            Frank–Wolfe and projected-gradient steps with a ten-point line search
            (:func:`fuzzygait.uncertainty.gfa.batched.maximise`, the solver before).
        stop: a node's point stops once a step gains less than this fraction of the
            largest deterministic output magnitude of its block (at least 1).
    """

    stride: int = 1
    starts: int = 10
    iterations: int = 25
    window: int = 2
    screen: int = 64
    seed: int = 0
    follow: int = 0
    gradients: str = "auto"
    solver: str = "spectral"
    stop: float = 1e-7

    name = "batched-direct"

    def __post_init__(self) -> None:
        if self.gradients not in GRADIENT_SOURCES:
            raise ParameterError(f"BatchedDirect gradients must be one of {', '.join(GRADIENT_SOURCES)}; "
                                 f"got {self.gradients!r}")  # fmt: skip
        if self.solver not in BATCHED_SOLVERS:
            raise ParameterError(f"BatchedDirect solver must be one of {', '.join(BATCHED_SOLVERS)}; "
                                 f"got {self.solver!r}")  # fmt: skip
        _whole("stride", self.stride, 1)
        _whole("follow", self.follow, 0)
        _whole("starts", self.starts, 1)
        _whole("iterations", self.iterations, 1)
        _whole("window", self.window, 0)
        _whole("screen", self.screen, 1)
        if isinstance(self.stop, bool) or not isinstance(self.stop, int | float) or not 0.0 < self.stop < 1.0:
            raise ParameterError(f"BatchedDirect stop must be a fraction in (0, 1); got {self.stop!r}")

    def options(self) -> dict[str, object]:
        return asdict(self)


Strategy = Linearised | Direct | BatchedDirect
