"""``graph_follower``: fuzzy output of a model for fuzzy parameters (thesis §2.6).

    result = graph_follower(model, params, alphas, strategy=Linearised(max_iterations=4))

``model`` is a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel` or a plain function
``p -> (n_time,)`` together with ``times=``; ``params`` a
:class:`~fuzzygait.uncertainty.parameters.FuzzyVector`, a
:class:`~fuzzygait.uncertainty.parameters.FuzzyBalls` or a list of fuzzy numbers. The
strategy (:mod:`fuzzygait.uncertainty.gfa.strategies`) owns its options; every
strategy returns one fuzzy result (:mod:`fuzzygait.core.schema`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.schema import HullArrays, ResultInfo, fuzzy_result
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.fuzzy import FuzzyNumber
from fuzzygait.uncertainty.gfa.batched import run_batched
from fuzzygait.uncertainty.gfa.follower import run_follower
from fuzzygait.uncertainty.gfa.levels import run_levels_together
from fuzzygait.uncertainty.gfa.strategies import BatchedDirect, Direct, Linearised, Strategy
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector
from fuzzygait.uncertainty.postprocess import repair_nesting
from fuzzygait.uncertainty.protocol import NODES, Array, FuzzyModel, as_model, check_parameter_names

Progress = Callable[[int, int], None]


def as_parameters(params: FuzzyVector | FuzzyBalls | Sequence[FuzzyNumber]) -> FuzzyVector | FuzzyBalls:
    """``params`` as a :class:`FuzzyVector` or :class:`FuzzyBalls` (a list of fuzzy
    numbers becomes a vector)."""
    if isinstance(params, FuzzyVector | FuzzyBalls):
        return params
    if isinstance(params, FuzzyNumber):
        return FuzzyVector([params])
    if isinstance(params, Sequence) and params and all(isinstance(n, FuzzyNumber) for n in params):
        return FuzzyVector(list(params))
    raise ParameterError(
        f"params must be a FuzzyVector, FuzzyBalls or a list of fuzzy numbers (e.g. [triangular(0.9, 1, 1.1)]); "
        f"got {type(params).__name__}"
    )


def alpha_levels(alphas: Sequence[float]) -> Array:
    """Sorted, unique α-levels in [0, 1] with 1 (the deterministic run) added."""
    levels = np.unique(np.asarray(list(alphas), dtype=float))
    if levels.size == 0 or levels.min() < 0 or levels.max() > 1:
        raise ParameterError(f"alphas must lie in [0, 1]; got {list(alphas)}")
    return np.union1d(levels, [1.0])


def graph_follower(
    model: FuzzyModel | Callable[[Array], Array],
    params: FuzzyVector | FuzzyBalls | Sequence[FuzzyNumber],
    alphas: Sequence[float] = (0.0, 0.5, 1.0),
    *,
    strategy: Strategy | None = None,
    times: Sequence[float] | Array | None = None,
    progress: Progress | None = None,
) -> xr.Dataset:
    """Fuzzy output of ``model`` for fuzzy parameters ``params``.

    Args:
        model: a :class:`~fuzzygait.uncertainty.protocol.FuzzyModel`, or a function
            ``p -> (n_time,)`` with ``times``.
        params: fuzzy parameters; their names must be the model's ``parameter_names``.
        alphas: α-levels; 1 is always added (the deterministic run).
        strategy: :class:`Linearised` (default), :class:`Direct` or
            :class:`BatchedDirect` (models with the ``"nodes"`` capability).
        times: the time nodes, only with a plain function as ``model``.
        progress: called as ``progress(done, total)`` as the optimisation advances.

    Returns:
        A fuzzy result (:mod:`fuzzygait.core.schema`): ``hull (alpha, bound, time)``,
        ``deterministic (time)``, ``extremiser (alpha, bound, time, parameter)``,
        attributes ``output``, ``units``, ``strategy`` and its options,
        ``forward_simulations``, ``node_evaluations``, ``optimisations``,
        ``library_size`` (Linearised/Direct) or ``solver_iterations`` (BatchedDirect).
    """
    fuzzy_model = as_model(model, times)
    parameters = as_parameters(params)
    check_parameter_names(fuzzy_model, parameters.names, parameters.named)
    strategy = Linearised() if strategy is None else strategy
    if not isinstance(strategy, Linearised | Direct | BatchedDirect):
        raise ParameterError(f"strategy must be Linearised(...), Direct(...) or BatchedDirect(...); got {strategy!r}")
    if isinstance(strategy, BatchedDirect) and NODES not in fuzzy_model.capabilities:
        raise ParameterError(
            f"BatchedDirect needs a model with the 'nodes' capability (evaluate_nodes); "
            f"{type(fuzzy_model).__name__} has {sorted(fuzzy_model.capabilities) or 'none'}: use Direct(...)"
        )
    levels = alpha_levels(alphas)
    counted = CountedModel(fuzzy_model, scale=parameters.scale)
    if isinstance(strategy, BatchedDirect) and strategy.solver == "spectral" and isinstance(parameters, FuzzyBalls):
        run = run_levels_together(counted, parameters, levels, strategy, progress)
    elif isinstance(strategy, BatchedDirect):
        run = run_batched(counted, parameters, levels, strategy, progress)
    else:
        run = run_follower(counted, parameters, levels, strategy, progress)
    arrays = HullArrays(
        alphas=levels,
        times=np.asarray(fuzzy_model.times, dtype=float),
        parameter_names=parameters.names,
        hull=repair_nesting(run["hull"]),  # type: ignore[arg-type]
        deterministic=run["deterministic"],  # type: ignore[arg-type]
        extremiser=run["extremiser"],  # type: ignore[arg-type]
    )
    info = ResultInfo(output=fuzzy_model.output.name, units=fuzzy_model.output.units, strategy=strategy.name,
                      forward_simulations=counted.evaluations, node_evaluations=counted.node_evaluations)  # fmt: skip
    return fuzzy_result(arrays, info, attrs={**run["attrs"], **strategy.options()})  # type: ignore[dict-item]
