"""Tools for testing models and the engine: :func:`check_model`, which every model of
the package passes, and cheap analytic models with exact sensitivities (with a recipe,
for the parallel :class:`~fuzzygait.uncertainty.execution.Evaluator`).

    from fuzzygait.testing import check_model
    report = check_model(model, p)       # raises ModelCheckError naming the first failure
    check_result(dataset)                # a fuzzy result: its layout, bounds and nesting

The seeded C3D fault campaign shared by the fuzz tests and ``benchmarks/fuzz_c3d.py`` is
:mod:`fuzzygait.testing.c3d_fuzz`.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import xarray as xr

import fuzzygait.core.accessor  # noqa: F401 - registers ``dataset.fuzzy``
from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.execution import SharedArray
from fuzzygait.uncertainty.protocol import (
    CAPABILITY_MEMBERS,
    MANY,
    NODE_GRADIENTS,
    NODE_LIMITS,
    NODES,
    SENSITIVITIES,
    TIME_STEP,
    Evaluation,
    Output,
    declared_blocks,
    model_problem,
    undeclared_capabilities,
)


class ModelCheckError(ParameterError):
    """A model does not keep the protocol of :mod:`fuzzygait.uncertainty.protocol`."""


def check_model(model: object, p: np.ndarray, *, scale: np.ndarray | None = None, fd_step: float = 1e-6,
                sensitivity_rtol: float = 1e-4, n_nodes: int = 7, seed: int = 0) -> dict[str, float]:  # fmt: skip
    """Check that ``model`` keeps the model protocol at the parameter vector ``p``.

    Checks: the declared attributes (``times`` 1-D, ``parameter_names`` as many as
    ``p``, ``output``, known ``capabilities``); ``evaluate(p)`` gives an
    :class:`~fuzzygait.uncertainty.protocol.Evaluation` of ``(n_time,)`` finite values,
    the same on a second call (deterministic); with ``"sensitivities"``, a jacobian of
    shape ``(n_time, n_p)`` with the same values (to 1e-8 relative), that agrees with central finite
    differences (step ``fd_step`` × ``scale``) to ``sensitivity_rtol`` of the largest
    derivative; with ``"nodes"``, ``evaluate_nodes`` at ``n_nodes`` random
    (node, parameter) pairs equals the full trajectories there (to 1e-9 relative); with
    ``"node_gradients"``, ``evaluate_nodes_gradients`` at those pairs gives the same
    values and gradients that agree with central differences of ``evaluate_nodes`` to
    ``sensitivity_rtol`` of the largest derivative; with ``"many"``, ``evaluate_many``
    (and with sensitivities ``evaluate_many_with_sensitivities``) gives ``evaluate``'s
    rows; with ``"time_step"``, every step between time nodes of a block is a whole
    number of time steps; with ``"node_limits"``, ``evaluate_nodes_limited`` (and with
    node gradients ``evaluate_nodes_gradients_limited``) gives the values (and gradients)
    of the methods without limits at those pairs, and one boolean per row. A model that
    has the members of a capability it does not declare (``evaluate_nodes`` without
    ``"nodes"``, a ``blocks`` attribute without ``"blocks"``, ...) is rejected: the engine
    would ignore them.

    Returns:
        The measured figures: ``n_time``, ``sensitivity_error`` (relative, or 0),
        ``nodes_error`` (relative, or 0), ``node_gradients_error`` (relative, or 0).

    Raises:
        ModelCheckError: naming the first check that failed.
    """
    problem = model_problem(model)
    if problem is not None:
        raise ModelCheckError(problem)
    undeclared = undeclared_capabilities(model)
    if undeclared:
        members = [m for c in undeclared for m in CAPABILITY_MEMBERS[c]]
        raise ModelCheckError(f"{type(model).__name__} has {', '.join(members)} but does not declare "
                              f"{', '.join(repr(c) for c in undeclared)} in its capabilities: the engine ignores "
                              "what a model does not declare; declare it, or rename the member")  # fmt: skip
    p = np.asarray(p, dtype=float).ravel()
    names = tuple(model.parameter_names)  # type: ignore[attr-defined]
    if names and len(names) != p.size:
        raise ModelCheckError(f"{len(names)} parameter names {list(names)} for {p.size} parameters")
    capabilities = frozenset(model.capabilities)  # type: ignore[attr-defined]
    n_time = int(np.asarray(model.times).size)  # type: ignore[attr-defined]
    first = _values(model, p, n_time)
    if not np.array_equal(first, _values(model, p, n_time)):
        raise ModelCheckError("two evaluations at the same parameters differ (the model must be deterministic)")
    scale = np.maximum(np.abs(p), 1.0) if scale is None else np.asarray(scale, dtype=float)
    report = {"n_time": float(n_time), "sensitivity_error": 0.0, "nodes_error": 0.0, "node_gradients_error": 0.0}
    if SENSITIVITIES in capabilities:
        report["sensitivity_error"] = _check_sensitivities(model, p, first, scale, fd_step, sensitivity_rtol)
    if NODES in capabilities:
        report["nodes_error"] = _check_nodes(model, p, scale, n_time, n_nodes, seed)
    if NODE_GRADIENTS in capabilities:
        report["node_gradients_error"] = _check_node_gradients(model, p, scale, n_time, n_nodes, seed, fd_step,
                                                               sensitivity_rtol)  # fmt: skip
    if NODE_LIMITS in capabilities:
        _check_node_limits(model, p, scale, n_time, n_nodes, seed, NODE_GRADIENTS in capabilities)
    if MANY in capabilities:
        _check_many(model, p, scale, n_time, seed, SENSITIVITIES in capabilities)
    if TIME_STEP in capabilities:
        _check_time_step(model, n_time)
    return report


def _check_node_limits(model: Any, p: np.ndarray, scale: np.ndarray, n_time: int, n_nodes: int, seed: int,
                       gradients: bool) -> None:  # fmt: skip
    """``evaluate_nodes_limited`` (and ``evaluate_nodes_gradients_limited``) give the values
    (and gradients) of the methods without limits, and a boolean per row."""
    P, nodes = _random_pairs(p, scale, n_time, n_nodes, seed)
    values, beyond = model.evaluate_nodes_limited(P, nodes)
    beyond = np.asarray(beyond)
    if beyond.shape != (n_nodes,) or beyond.dtype != bool:
        raise ModelCheckError(f"evaluate_nodes_limited gave {beyond.dtype} flags of shape {beyond.shape} for "
                              f"{n_nodes} pairs; one boolean per row is needed")  # fmt: skip
    if not np.array_equal(np.asarray(values, dtype=float), np.asarray(model.evaluate_nodes(P, nodes), dtype=float)):
        raise ModelCheckError("evaluate_nodes_limited's values differ from evaluate_nodes'")
    if not gradients:
        return
    limited = model.evaluate_nodes_gradients_limited(P, nodes)
    plain = model.evaluate_nodes_gradients(P, nodes)
    same = all(np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
               for a, b in zip(limited[:2], plain, strict=True))  # fmt: skip
    if not same or not np.array_equal(np.asarray(limited[2]), beyond):
        raise ModelCheckError("evaluate_nodes_gradients_limited differs from evaluate_nodes_gradients or from "
                              "evaluate_nodes_limited's flags")  # fmt: skip


def _check_many(model: Any, p: np.ndarray, scale: np.ndarray, n_time: int, seed: int, sensitivities: bool) -> None:
    """``evaluate_many`` (and ``evaluate_many_with_sensitivities``) give ``evaluate``'s rows."""
    P, _ = _random_pairs(p, scale, n_time, 3, seed)
    rows = np.array([_values(model, row, n_time) for row in P])
    many = np.asarray(model.evaluate_many(P), dtype=float)
    if many.shape != rows.shape or not np.allclose(many, rows, rtol=1e-9, atol=0.0):
        raise ModelCheckError(f"evaluate_many gives other trajectories (shape {many.shape}) than evaluate row by row")
    if sensitivities:
        values, jacobians = model.evaluate_many_with_sensitivities(P)
        expected = [model.evaluate(row.copy(), sensitivities=True).jacobian for row in P]
        if not (np.allclose(values, rows, rtol=1e-9, atol=0.0)
                and np.allclose(jacobians, np.array(expected, dtype=float), rtol=1e-9, atol=0.0)):  # fmt: skip
            raise ModelCheckError("evaluate_many_with_sensitivities gives other values or sensitivities than evaluate")


def _check_time_step(model: Any, n_time: int) -> None:
    """Each step between time nodes (within a block) is a whole number of ``time_step``s."""
    step = float(model.time_step)
    blocks = declared_blocks(model)
    times = np.asarray(model.times, dtype=float).reshape(blocks, n_time // blocks)
    ratios = np.diff(times, axis=1) / step
    if ratios.size and not (np.all(ratios > 0.5) and np.allclose(ratios, np.round(ratios), rtol=0.0, atol=1e-6)):
        low, high = float(np.min(ratios)), float(np.max(ratios))
        raise ModelCheckError(f"time_step {step:g} does not divide the steps between the time nodes "
                              f"(from {low:.4g} to {high:.4g} time steps)")  # fmt: skip


class FuzzyParts(Protocol):
    """A result of several parts, each in the fuzzy-result schema (e.g.
    :class:`fuzzygait.markererror.result.MarkerErrorResult`)."""

    def parts(self) -> Mapping[str, xr.Dataset]: ...


def check_result(result: xr.Dataset | FuzzyParts, *, rtol: float = 1e-9) -> dict[str, float]:
    """Check that ``result`` — a dataset, or every part of a result of several
    (:class:`FuzzyParts`; the figures summed, the largest violation over all, an error
    naming the part) — keeps the fuzzy-result schema (:mod:`fuzzygait.core.accessor`):
    the layout (``hull (..., alpha, bound, time|frame)``, α ascending to 1, the bounds,
    stated units), and the numbers: lower ≤ upper, α = 1 a single value (lower = upper),
    and the bands nested — the band at a higher α-level lies within the band at a lower
    one — wherever both are determined and finite, to ``rtol`` of the largest magnitude.

    Returns:
        ``values`` (finite hull values checked) and ``largest_violation`` (the largest
        breach found, relative; 0 when none).

    Raises:
        ModelCheckError: naming the first check that failed.
    """
    if not isinstance(result, xr.Dataset):
        parts = dict(result.parts())
        if not parts:
            raise ModelCheckError("the result has no parts")
        total = {"values": 0.0, "largest_violation": 0.0}
        for name, part in parts.items():
            try:
                figures = check_result(part, rtol=rtol)
            except ModelCheckError as error:
                raise ModelCheckError(f"{name}: {error}") from None
            total = {"values": total["values"] + figures["values"],
                     "largest_violation": max(total["largest_violation"], figures["largest_violation"])}  # fmt: skip
        return total
    problems = result.fuzzy.problems()
    if problems:
        raise ModelCheckError(f"not a fuzzy result: {'; '.join(problems)}")
    hull = result.fuzzy.hull().load()
    flags = result.fuzzy.undetermined().load()
    values = np.asarray(hull.transpose(..., "alpha", "bound", result.fuzzy.axis).values, dtype=float)
    hidden = np.asarray(flags.transpose(..., "alpha", result.fuzzy.axis).values, dtype=bool)
    lower, upper = values[..., 0, :], values[..., 1, :]
    lower, upper = np.where(hidden, np.nan, lower), np.where(hidden, np.nan, upper)
    scale = max(float(np.nanmax(np.abs(values))) if np.isfinite(values).any() else 0.0, np.finfo(float).tiny)
    breaches = {
        "lower above upper": lower - upper,
        "α = 1 not a single value": np.abs(upper[..., -1, :] - lower[..., -1, :]),
        "a band wider than the band of a lower α-level (not nested)": np.maximum(
            lower[..., :-1, :] - lower[..., 1:, :], upper[..., 1:, :] - upper[..., :-1, :]),
    }  # fmt: skip
    largest = 0.0
    for what, excess in breaches.items():
        worst = float(np.nanmax(excess)) / scale if np.isfinite(excess).any() else 0.0
        if worst > rtol:
            raise ModelCheckError(f"{what}: by {worst:.2e} of the largest value (tolerance {rtol:g})")
        largest = max(largest, worst)
    return {"values": float(np.isfinite(values).sum()), "largest_violation": largest}


def _values(model: object, p: np.ndarray, n_time: int, sensitivities: bool = False) -> np.ndarray:
    evaluation = model.evaluate(p.copy(), sensitivities=sensitivities)  # type: ignore[attr-defined]
    if not isinstance(evaluation, Evaluation):
        raise ModelCheckError(f"evaluate() returned {type(evaluation).__name__}, expected an Evaluation")
    values = np.asarray(evaluation.values, dtype=float)
    if values.shape != (n_time,):
        raise ModelCheckError(f"evaluate() returned values of shape {values.shape} for {n_time} time nodes")
    if not np.all(np.isfinite(values)):
        raise ModelCheckError(f"evaluate() returned non-finite values at parameters {p.tolist()}")
    return values


def _check_sensitivities(model: object, p: np.ndarray, values: np.ndarray, scale: np.ndarray, fd_step: float,
                         rtol: float) -> float:  # fmt: skip
    evaluation = model.evaluate(p.copy(), sensitivities=True)  # type: ignore[attr-defined]
    if evaluation.jacobian is None:
        raise ModelCheckError("the model declares 'sensitivities' but evaluate(p, sensitivities=True) gave none")
    jac = np.asarray(evaluation.jacobian, dtype=float)
    if jac.shape != (values.size, p.size):
        raise ModelCheckError(f"jacobian of shape {jac.shape}, expected {(values.size, p.size)}")
    drift = float(np.max(np.abs(np.asarray(evaluation.values, dtype=float) - values)))
    if drift > 1e-8 * max(float(np.max(np.abs(values))), 1.0):  # adaptive integrators may step differently
        raise ModelCheckError(f"evaluate(p, sensitivities=True) gives values {drift:.2e} away from evaluate(p)")
    fd = _central_differences(lambda q: _values(model, q, values.size), p, fd_step * scale)
    reference = max(float(np.max(np.abs(fd))), np.finfo(float).tiny)
    error = float(np.max(np.abs(jac - fd))) / reference
    if error > rtol:
        raise ModelCheckError(f"sensitivities differ from central finite differences by {error:.2e} "
                              f"of the largest derivative (tolerance {rtol:g})")  # fmt: skip
    return error


def _check_nodes(model: object, p: np.ndarray, scale: np.ndarray, n_time: int, n_nodes: int, seed: int) -> float:
    P, nodes = _random_pairs(p, scale, n_time, n_nodes, seed)
    at_nodes: np.ndarray = np.asarray(model.evaluate_nodes(P, nodes), dtype=float)  # type: ignore[attr-defined]
    if at_nodes.shape != (n_nodes,):
        raise ModelCheckError(f"evaluate_nodes returned shape {at_nodes.shape} for {n_nodes} pairs")
    full = np.array([_values(model, row, n_time)[j] for row, j in zip(P, nodes, strict=True)])
    error = float(np.max(np.abs(at_nodes - full)) / max(float(np.max(np.abs(full))), 1.0))
    if error > 1e-9:
        raise ModelCheckError(f"evaluate_nodes differs from the full trajectories by {error:.2e} (relative)")
    return error


def _central_differences(function: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                         steps: np.ndarray) -> np.ndarray:  # fmt: skip
    """Central differences of ``function`` with respect to each entry of ``x``'s last axis
    (steps ``steps``), stacked on a new last axis: ``(*function(x).shape, x.shape[-1])``."""
    columns = []
    for i, h in enumerate(steps):
        up, down = x.copy(), x.copy()
        up[..., i] += h
        down[..., i] -= h
        columns.append((function(up) - function(down)) / (2 * h))
    return np.stack(columns, axis=-1)


def _random_pairs(p: np.ndarray, scale: np.ndarray, n_time: int, n_nodes: int,
                  seed: int) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``n_nodes`` parameter rows near ``p`` and time nodes, seeded."""
    rng = np.random.default_rng(seed)
    return p + 1e-3 * scale * rng.standard_normal((n_nodes, p.size)), rng.integers(0, n_time, n_nodes)


def _check_node_gradients(model: object, p: np.ndarray, scale: np.ndarray, n_time: int, n_nodes: int, seed: int,
                          fd_step: float, rtol: float) -> float:  # fmt: skip
    P, nodes = _random_pairs(p, scale, n_time, n_nodes, seed)
    returned = model.evaluate_nodes_gradients(P, nodes)  # type: ignore[attr-defined]
    values: np.ndarray = np.asarray(returned[0], dtype=float)
    gradients: np.ndarray = np.asarray(returned[1], dtype=float)
    if values.shape != (n_nodes,) or gradients.shape != P.shape:
        raise ModelCheckError(f"evaluate_nodes_gradients returned shapes {values.shape} and {gradients.shape} for "
                              f"{n_nodes} pairs of {p.size} parameters")  # fmt: skip
    at_nodes: np.ndarray = np.asarray(model.evaluate_nodes(P, nodes), dtype=float)  # type: ignore[attr-defined]
    if np.max(np.abs(values - at_nodes)) > 1e-9 * max(float(np.max(np.abs(at_nodes))), 1.0):
        raise ModelCheckError("evaluate_nodes_gradients gives other values than evaluate_nodes")
    fd = _central_differences(lambda Q: np.asarray(model.evaluate_nodes(Q, nodes), dtype=float),  # type: ignore[attr-defined]
                              P, fd_step * scale)  # fmt: skip
    error = float(np.max(np.abs(gradients - fd))) / max(float(np.max(np.abs(fd))), np.finfo(float).tiny)
    if not error <= rtol:
        raise ModelCheckError(f"node gradients differ from central differences of evaluate_nodes by {error:.2e} "
                              f"of the largest derivative (tolerance {rtol:g})")  # fmt: skip
    return error


@dataclass
class AnalyticModel:
    """The model an :class:`AnalyticRecipe` builds (see there)."""

    kind: str
    times: np.ndarray
    fail_above: float | None
    offset: np.ndarray | None

    def _check(self, p: np.ndarray) -> None:
        if self.fail_above is not None and p[0] > self.fail_above:
            raise ParameterError(f"p[0] = {p[0]:g} exceeds fail_above = {self.fail_above:g}")

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return ()  # any number of parameters

    output = Output("analytic", "")
    capabilities = frozenset({SENSITIVITIES})

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        p = np.asarray(p, dtype=float).ravel()
        self._check(p)
        t = self.times[:, None]
        omega = np.arange(1, p.size + 1, dtype=float)[None, :]
        if self.kind == "sin":
            terms, jac = np.sin(omega * t * p), omega * t * np.cos(omega * t * p)
        else:  # poly
            terms, jac = p**2 * t**omega, 2.0 * p * t**omega
        values = terms.sum(axis=1)
        if self.offset is not None:
            values = values + self.offset
        return Evaluation(values, jac if sensitivities else None)


@dataclass(frozen=True)
class AnalyticRecipe:
    """A cheap analytic model, for tests and examples of the parallel machinery.

    ``kind="sin"``: ``f(t) = Σ_i sin((i+1)·t·p_i)``; ``kind="poly"``:
    ``f(t) = Σ_i p_i²·t^(i+1)``, on ``n_time`` nodes of ``[0, t_end]``, with exact
    sensitivities. ``offset`` (a :class:`SharedArray` of shape ``(n_time,)``) is added to
    the output; ``fail_above`` makes evaluation raise
    :class:`~fuzzygait.core.errors.ParameterError` when ``p[0] > fail_above`` (to test errors).
    """

    kind: str = "sin"
    n_time: int = 101
    t_end: float = 1.0
    fail_above: float | None = None
    offset: SharedArray | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("sin", "poly"):
            raise ParameterError(f"unknown analytic model {self.kind!r}; choose 'sin' or 'poly'")
        if self.n_time < 1:
            raise ParameterError(f"n_time must be ≥ 1; got {self.n_time}")

    @property
    def key(self) -> Hashable:
        return ("AnalyticRecipe", self.kind, self.n_time, self.t_end, self.fail_above, self.offset)

    def build(self) -> AnalyticModel:
        offset = None if self.offset is None else np.asarray(self.offset.load(), dtype=float)
        if offset is not None and offset.shape != (self.n_time,):
            raise ParameterError(f"offset must have shape ({self.n_time},); got {offset.shape}")
        times = np.linspace(0.0, self.t_end, self.n_time)
        return AnalyticModel(self.kind, times, self.fail_above, offset)
