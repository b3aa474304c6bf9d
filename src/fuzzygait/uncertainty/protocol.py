"""The model protocol of the uncertainty engine.

The engine knows nothing of markers or beams. A model maps a parameter vector ``p``
(shape ``(n_p,)``, in the order of :attr:`FuzzyModel.parameter_names`) to the trajectory
of one scalar output over its time nodes, and declares what else it can do::

    model.times              (n_time,)  time of each node (any unit, e.g. s)
    model.parameter_names    tuple of n_p names (checked against the FuzzyVector)
    model.output             Output(name, units, description, bounds=(lower, upper))
    model.capabilities       frozenset, a subset of CAPABILITIES (below)
    model.evaluate(p, sensitivities=False) -> Evaluation(values (n_time,), jacobian (n_time, n_p) | None)

and, only when it declares the capability in brackets::

    model.evaluate_nodes(P, nodes) -> (k,)      ["nodes"] output of row P[i] at node nodes[i]
    model.evaluate_nodes_gradients(P, nodes) -> ((k,), (k, n_p))
                                                ["node_gradients"] those outputs and their
                                                gradients with respect to each row's parameters
    model.evaluate_many(P) -> (k, n_time)       ["many"] the trajectories of all rows at once
    model.evaluate_many_with_sensitivities(P) -> ((k, n_time), (k, n_time, n_p))
                                                ["many" with "sensitivities"]
    model.blocks -> int                         ["blocks"] the time nodes are that many equal,
                                                consecutive runs of independent outputs of the
                                                same parameters (the X/Y/Z of one joint angle)
    model.time_step -> float                    ["time_step"] the sampling period, in the unit
                                                of ``times``: a longer step between nodes is
                                                a gap (frames without data)
    model.excursion_limit -> float              ["excursion_limit"] how far (output units) a
                                                bound may lie from the deterministic output
                                                at its node and still be a band: a bound
                                                found beyond it means the same as any other
                                                beyond it (a joint angle whose segment frame
                                                can flip), so the optimisers stop there
    model.evaluate_nodes_limited(P, nodes) -> ((k,), (k,) bool)
                                                ["node_limits"] ``evaluate_nodes``' outputs
                                                and whether each row lies beyond the model's
                                                limits (a joint moment whose segment frame
                                                turned past 90°): no band there, whatever
                                                the value; the batched optimisers stop a
                                                bound at such a row
    model.evaluate_nodes_gradients_limited(P, nodes) -> ((k,), (k, n_p), (k,) bool)
                                                ["node_limits" with "node_gradients"] the same
                                                with the gradients

The engine uses a method or attribute of this list only when its capability is declared
(an undeclared one is ignored, and :func:`fuzzygait.testing.check_model` rejects a model
that has one without declaring it).

One call of ``evaluate`` is one forward simulation. Without ``"sensitivities"`` the
engine uses forward finite differences (``1 + n_p`` forward simulations, all counted).
``"nodes"`` lets the direct strategies evaluate single time nodes without a whole
trajectory (a joint angle at one frame, say); with ``"node_gradients"`` as well, their
first-order iterations take the model's gradients instead of forward differences.

A plain function ``p -> (n_time,)`` becomes a model with :class:`FunctionModel`, or
implicitly by :func:`as_model` (which :func:`~fuzzygait.uncertainty.graph_follower`
calls).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError

Array = NDArray[np.float64]

SENSITIVITIES = "sensitivities"
NODES = "nodes"
NODE_GRADIENTS = "node_gradients"
MANY = "many"
BLOCKS = "blocks"
TIME_STEP = "time_step"
EXCURSION_LIMIT = "excursion_limit"
NODE_LIMITS = "node_limits"
CAPABILITIES = frozenset({SENSITIVITIES, NODES, NODE_GRADIENTS, MANY, BLOCKS, TIME_STEP, EXCURSION_LIMIT, NODE_LIMITS})

#: What each capability needs the model to have: methods (callable) and attributes.
CAPABILITY_MEMBERS: dict[str, tuple[str, ...]] = {
    NODES: ("evaluate_nodes",),
    NODE_GRADIENTS: ("evaluate_nodes_gradients",),
    MANY: ("evaluate_many",),
    BLOCKS: ("blocks",),
    TIME_STEP: ("time_step",),
    EXCURSION_LIMIT: ("excursion_limit",),
    NODE_LIMITS: ("evaluate_nodes_limited",),
}


def declared_blocks(model: object) -> int:
    """The independent outputs a model's time nodes hold (``"blocks"``; 1 without it)."""
    return int(getattr(model, "blocks")) if BLOCKS in getattr(model, "capabilities", ()) else 1  # noqa: B009


def declared_time_step(model: object) -> float | None:
    """A model's sampling period (``"time_step"``), or None without it."""
    return float(getattr(model, "time_step")) if TIME_STEP in getattr(model, "capabilities", ()) else None  # noqa: B009


def declared_excursion_limit(model: object) -> float | None:
    """A model's excursion limit (``"excursion_limit"``, output units), or None without it."""
    if EXCURSION_LIMIT not in getattr(model, "capabilities", ()):
        return None
    return float(getattr(model, "excursion_limit"))  # noqa: B009


def undeclared_capabilities(model: object) -> list[str]:
    """The capabilities whose members ``model`` has without declaring them (the engine
    ignores those members)."""
    declared = set(getattr(model, "capabilities", ()))
    found = [c for c, members in CAPABILITY_MEMBERS.items()
             if c not in declared and all(hasattr(model, m) for m in members)]  # fmt: skip
    return sorted(found)


@dataclass(frozen=True)
class Output:
    """What a model's output is.

    Attributes:
        name: short name (e.g. ``"LKneeAngles_X"``, ``"total_deformation_energy"``).
        units: physical units (e.g. ``"deg"``, ``"J"``, ``"m"``); empty if dimensionless.
        description: one line for plots and reports.
        bounds: ``(lower, upper)``, the values the output can take at all (an energy:
            ``(0, inf)``); ``(-inf, inf)``, the default, declares none. Results built from
            the model's outputs (e.g. FRV hulls) are kept within them.
    """

    name: str = "output"
    units: str = ""
    description: str = ""
    bounds: tuple[float, float] = (-math.inf, math.inf)

    def __post_init__(self) -> None:
        try:
            lower, upper = (float(b) for b in self.bounds)
        except (TypeError, ValueError):
            raise ParameterError(f"Output {self.name!r}: bounds must be two numbers (lower, upper); "
                                 f"got {self.bounds!r}") from None  # fmt: skip
        if math.isnan(lower) or math.isnan(upper) or lower > upper:
            raise ParameterError(f"Output {self.name!r}: bounds must satisfy lower <= upper; got {self.bounds!r}")
        object.__setattr__(self, "bounds", (lower, upper))


@dataclass(frozen=True)
class Evaluation:
    """One forward simulation: ``values (n_time,)`` and, when asked for and available,
    ``jacobian (n_time, n_p)`` = d values / d p."""

    values: np.ndarray
    jacobian: np.ndarray | None = None


@runtime_checkable
class FuzzyModel(Protocol):
    """What the Graph Follower algorithm, the FRV-GFA and the checks need of a model
    (see the module docstring). Plain attributes or properties both do."""

    @property
    def times(self) -> np.ndarray: ...

    @property
    def parameter_names(self) -> tuple[str, ...]: ...

    @property
    def output(self) -> Output: ...

    @property
    def capabilities(self) -> frozenset[str]: ...

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation: ...


@runtime_checkable
class NodeModel(FuzzyModel, Protocol):
    """A :class:`FuzzyModel` with the ``"nodes"`` capability."""

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray: ...


@dataclass
class FunctionModel:
    """A model from plain functions.

    Args:
        function: ``p -> (n_time,)`` trajectory.
        times: the time nodes ``(n_time,)``.
        jacobian: optional ``p -> (n_time, n_p)`` sensitivities.
        parameter_names: names of the entries of ``p``; empty: taken from the fuzzy
            parameters the model is first run with.
        output: name and units of the output.
    """

    function: Callable[[Array], Array]
    times: Array
    jacobian: Callable[[Array], Array] | None = None
    parameter_names: tuple[str, ...] = ()
    output: Output = field(default_factory=Output)

    def __post_init__(self) -> None:
        if not callable(self.function):
            raise ParameterError("FunctionModel: function must be callable as function(p) -> (n_time,) values")
        self.times = np.asarray(self.times, dtype=float)
        self.parameter_names = tuple(self.parameter_names)

    @property
    def capabilities(self) -> frozenset[str]:
        return frozenset({SENSITIVITIES}) if self.jacobian is not None else frozenset()

    def evaluate(self, p: Array, *, sensitivities: bool = False) -> Evaluation:
        values = np.asarray(self.function(p), dtype=float)
        if sensitivities and self.jacobian is not None:
            return Evaluation(values, np.asarray(self.jacobian(p), dtype=float))
        return Evaluation(values)


def model_problem(model: object) -> str | None:
    """Why ``model`` is not a :class:`FuzzyModel` (one sentence), or None."""
    if callable(model) and not hasattr(model, "evaluate"):
        return ("got a plain function: pass times=... as well (graph_follower(f, params, times=t)) "
                "or wrap it as FunctionModel(f, times)")  # fmt: skip
    missing = [a for a in ("times", "parameter_names", "output", "capabilities", "evaluate") if not hasattr(model, a)]
    if missing:
        return (f"{type(model).__name__} lacks {', '.join(missing)}; a model needs times, parameter_names, "
                "output, capabilities and evaluate(p, sensitivities=False) -> Evaluation "
                "(see fuzzygait.uncertainty.protocol), or use FunctionModel(f, times)")  # fmt: skip
    name = type(model).__name__
    times = np.asarray(getattr(model, "times"))  # noqa: B009 - model is an unknown object here
    if times.ndim != 1 or times.size == 0:
        return f"{name}.times must be a non-empty 1-D array of time nodes; got shape {times.shape}"
    capabilities = set(getattr(model, "capabilities"))  # noqa: B009
    unknown = capabilities - CAPABILITIES
    if unknown:
        return f"{name} declares unknown capabilities {sorted(unknown)}; known: {sorted(CAPABILITIES)}"
    if NODES in capabilities and not callable(getattr(model, "evaluate_nodes", None)):
        return f"{type(model).__name__} declares 'nodes' but has no evaluate_nodes(P, nodes)"
    if NODE_GRADIENTS in capabilities and not (NODES in capabilities
                                               and callable(getattr(model, "evaluate_nodes_gradients", None))):
        return (f"{type(model).__name__} declares 'node_gradients' but not 'nodes' with "
                "evaluate_nodes_gradients(P, nodes)")  # fmt: skip
    if MANY in capabilities:
        needed = ["evaluate_many"] + (["evaluate_many_with_sensitivities"] if SENSITIVITIES in capabilities else [])
        lacking = [m for m in needed if not callable(getattr(model, m, None))]
        if lacking:
            return f"{name} declares 'many' but has no {' or '.join(f'{m}(P)' for m in lacking)}"
    if BLOCKS in capabilities:
        blocks = getattr(model, "blocks", None)
        if not isinstance(blocks, int | np.integer) or blocks < 1 or times.size % int(blocks):
            return f"{name} declares 'blocks' but its blocks ({blocks!r}) do not divide its {times.size} time nodes"
    if TIME_STEP in capabilities:
        step = getattr(model, "time_step", None)
        if not isinstance(step, float | int | np.floating) or not math.isfinite(step) or step <= 0:
            return f"{name} declares 'time_step' but its time_step ({step!r}) is not a positive number"
    return None


def as_model(model: object, times: Sequence[float] | Array | None = None) -> FuzzyModel:
    """``model`` itself when it is a :class:`FuzzyModel`; a plain callable with ``times``
    becomes a :class:`FunctionModel`. Anything else is one :class:`ParameterError` that
    says what to pass."""
    if times is not None:
        if isinstance(model, FuzzyModel):
            raise ParameterError("times= is only for plain functions; this model has its own times")
        if not callable(model):
            kind = type(model).__name__
            raise ParameterError(f"the model must be a FuzzyModel or a function p -> values; got {kind}")
        return FunctionModel(model, np.asarray(times, dtype=float))
    problem = model_problem(model)
    if problem is not None:
        raise ParameterError(f"not a model: {problem}")
    return model  # type: ignore[return-value]


def check_parameter_names(model: FuzzyModel, names: Sequence[str], named: Sequence[bool] | None = None) -> None:
    """The model's declared parameter names must be the fuzzy parameters' names, in
    order (``named[i]`` False: parameter ``i`` was given no name, only its position is
    checked). A model that declares no names (a :class:`FunctionModel` without them)
    takes any parameters."""
    names = tuple(names)
    named = tuple(named) if named is not None else (True,) * len(names)
    declared = tuple(model.parameter_names)
    if not declared:
        return
    if len(declared) != len(names):
        raise ParameterError(
            f"the model {type(model).__name__} takes {len(declared)} parameters {list(declared)} "
            f"but {len(names)} fuzzy parameters were given"
        )
    wrong = [(given, want) for given, want, has in zip(names, declared, named, strict=True) if has and given != want]
    if wrong:
        raise ParameterError(
            f"the fuzzy parameters are named {list(names)} but the model {type(model).__name__} takes "
            f"{list(declared)}: build the FuzzyVector with those names, in that order"
        )
