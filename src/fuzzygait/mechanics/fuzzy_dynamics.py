"""Fuzzy forward dynamics of the leg + prosthesis (thesis §5.2–5.3).

:func:`fuzzy_forward_dynamics` runs the Graph Follower algorithm (linearised mode, thesis
OP-III) on a scenario's target output with triangular fuzzy parameters, using the
simulator's forward sensitivities for the linearisation.  Defaults follow the thesis:
stride 100 (an optimisation every 0.1 s at dt = 1 ms), novelty tolerance 0.01 %, α-levels
0, 0.5 and 1.  :func:`dense_reference` samples the α = 0 interval of one parameter densely
for comparison.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Option
from fuzzygait.mechanics.leg import LEG_PARAMETERS, PARAMETER_UNITS
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.targets import TARGETS, LegModelRecipe, LegTargetModel
from fuzzygait.uncertainty import FuzzyVector, Linearised, graph_follower, triangular_relative
from fuzzygait.uncertainty.execution import Evaluator

DEFAULT_TARGET = {"swing": "total_deformation_energy", "stance": "max_element_energy"}
ELEVEN_PARAMETERS: tuple[str, ...] = tuple(n for n in LEG_PARAMETERS if n != "eta")  # §5.3
#: The Graph Follower settings of :func:`fuzzy_forward_dynamics` (the thesis': an
#: optimisation every 100th time node, novelty tolerance 0.01 %, at most 4 linearised steps).
DEFAULT_STRATEGY = Linearised(stride=100, novelty_tol=1e-4, max_iterations=4, tracks="one-by-one")


def parse_fuzzy(specs: Sequence[str]) -> dict[str, float]:
    """``["E=10%", "rho=0.05"]`` → ``{"E": 0.10, "rho": 0.05}`` (relative half-widths).

    Raises :class:`ParameterError` naming the entry for unknown names, bad numbers or
    spreads outside (0, 100 %).
    """
    spreads: dict[str, float] = {}
    for spec in specs:
        for item in filter(None, (part.strip() for part in spec.split(","))):
            name, sep, value = item.partition("=")
            name = name.strip()
            if not sep:
                raise ParameterError(f"{Option.FUZZY} {item!r}: write NAME=SPREAD, e.g. E=10%")
            if name not in LEG_PARAMETERS:
                known = ", ".join(LEG_PARAMETERS)
                raise ParameterError(f"{Option.FUZZY} {item!r}: unknown parameter {name!r}; known: {known}")
            text = value.strip()
            try:
                spread = float(text[:-1]) / 100 if text.endswith("%") else float(text)
            except ValueError:
                raise ParameterError(f"{Option.FUZZY} {item!r}: {text!r} is not a spread (e.g. 10% or 0.1)") from None
            if not 0 < spread < 1:
                raise ParameterError(f"{Option.FUZZY} {item!r}: the spread must lie between 0 and 100 %")
            if name in spreads:
                raise ParameterError(f"{Option.FUZZY} {name} is given twice")
            spreads[name] = spread
    if not spreads:
        raise ParameterError(f"give at least one fuzzy parameter, e.g. {Option.FUZZY} E=10%")
    return spreads


def fuzzy_forward_dynamics(
    simulator: LegSimulator,
    spreads: Mapping[str, float],
    *,
    target: str | None = None,
    base: np.ndarray | None = None,
    settings: SolverSettings | None = None,
    alphas: Sequence[float] = (0.0, 0.5, 1.0),
    strategy: Linearised = DEFAULT_STRATEGY,
    progress: Callable[[int, int], None] | None = None,
    evaluator: Evaluator | None = None,
) -> xr.Dataset:
    """Fuzzy target output of a scenario for triangular fuzzy parameters.

    Args:
        simulator: the scenario.
        spreads: parameter name → relative half-width of its symmetric triangular fuzzy
            number about the base value (0.1 = ±10 %).
        target: one of :data:`~fuzzygait.mechanics.targets.TARGETS` (default: total
            deformation energy for swing, maximum element energy for stance).
        base: full parameter vector (default: the scenario's).
        settings: the simulations' solver settings (default: the scenario's,
            :attr:`~fuzzygait.mechanics.presets.ScenarioPreset.solver`).
        alphas: the α-levels.
        strategy: the Graph Follower's :class:`~fuzzygait.uncertainty.Linearised` settings
            (default :data:`DEFAULT_STRATEGY`: stride 100, novelty tolerance 1e-4, 4
            iterations, ``tracks`` "one-by-one", the thesis' order; "side-by-side": the (α,
            bound) tracks at once, their simulations of a round evaluated together, in
            parallel on ``evaluator``).
        evaluator: runs the forward simulations on its workers (default: in this
            process); the hulls are bit-identical either way.

    Returns:
        The Graph Follower result (``hull (alpha, bound, time)``, ``deterministic``,
        ``extremiser``) with the fuzzy parameters' names, units and base values, the scenario
        settings and the wall time in the attributes.
    """
    target = target or DEFAULT_TARGET[simulator.scenario]
    if target not in TARGETS:
        raise ParameterError(f"unknown target {target!r}; choose one of {', '.join(TARGETS)}")
    names = tuple(spreads)
    model = LegTargetModel(simulator, target, names, base=base, settings=settings)
    numbers = [triangular_relative(model.base[LEG_PARAMETERS.index(n)], spreads[n], n) for n in names]
    start = time.perf_counter()
    engine_model = model if evaluator is None else evaluator.model(_recipe_of(model), sensitivities=True)
    result = graph_follower(engine_model, FuzzyVector(numbers), alphas, strategy=strategy, progress=progress)
    result.attrs.update(
        scenario=simulator.scenario,
        target=target,
        target_units="m" if target.startswith("last_node") else "J",
        fuzzy_parameters=list(names),
        fuzzy_spreads=[float(spreads[n]) for n in names],
        fuzzy_units=[PARAMETER_UNITS[n] for n in names],
        base_parameters=[float(v) for v in model.base],
        base_parameter_names=list(LEG_PARAMETERS),
        dt=float(model.dt),
        duration=float(model.duration),
        scheme=model.scheme,
        nodes=simulator.configuration.nodes,
        wall_time_s=time.perf_counter() - start,
    )
    result["time"].attrs["units"] = "s"
    return result


def _recipe_of(model: LegTargetModel) -> LegModelRecipe:
    """The recipe that rebuilds ``model`` in a worker process."""
    simulator = model.simulator
    return LegModelRecipe(simulator.scenario, model.target, tuple(model.names), tuple(float(v) for v in model.base),
                          nodes=simulator.configuration.nodes, settings=model.settings,
                          foot=simulator.configuration.foot)  # fmt: skip


def dense_reference(model: LegTargetModel, low: float, high: float, count: int = 41,
                    evaluator: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Target trajectories at ``count`` equally spaced values of a single fuzzy parameter
    (the α = 0 interval ``[low, high]``): shape ``(count, n_time)``.  ``evaluator`` may run
    them in parallel (``P (k, 1) -> (k, n_time)``)."""
    grid = np.linspace(low, high, count)[:, None]
    if evaluator is not None:
        return np.asarray(evaluator(grid))
    return np.array([model.evaluate(p).values for p in grid])


def leg_frv_study(
    scenario: str,
    spec,
    n_samples: int,
    store,
    *,
    target: str | None = None,
    base_overrides: Mapping[str, float] | None = None,
    n_disc: int | Sequence[int] = 100,
    seed: int = 0,
    nodes: int = 20,
    settings: SolverSettings | None = None,
    workers: int = 1,
    scheduler: str | None = None,
    sensitivities: bool = True,
    chunk: int = 256,
    overwrite: bool = False,
    options: Mapping[str, object] | None = None,
):
    """Run (or extend) the FRV-GFA of a leg scenario (thesis §5.7) into a zarr ``store``.

    ``spec`` is a :class:`~fuzzygait.uncertainty.frv.FRVSpec` whose ``name`` is a leg
    parameter, or a sequence of several (independent FRVs, one α-level set: an
    :class:`~fuzzygait.uncertainty.frv.FRVMultiStudy`; ``n_disc`` one grid size for all
    or one per parameter; refined with the sensitivities as one parameter is); the other
    parameters are the scenario's with ``base_overrides``; ``settings``: the solver
    settings (default: the scenario's with the energy-momentum scheme).  Forward
    simulations run on an :class:`~fuzzygait.uncertainty.execution.Evaluator`
    (``workers`` local processes, or the Dask cluster at ``scheduler``); each worker loads the
    compiled simulator library from the on-disk cache.  An existing store is extended with
    ``n_samples`` more samples (every stored library trajectory and interval hull reused)
    unless ``overwrite``; a new study records ``options`` (what it was made with, for the
    caller to compare before extending it).  Returns the
    :class:`~fuzzygait.uncertainty.frv.FRVStudy` (one parameter) or the
    :class:`~fuzzygait.uncertainty.frv.FRVMultiStudy` (several).
    """
    from pathlib import Path

    from fuzzygait.uncertainty.frv import FRVMultiStudy, FRVStudy, StudyOptions, check_specs, open_study

    specs = check_specs(spec)
    for one in specs:
        if one.name not in LEG_PARAMETERS:
            raise ParameterError(f"FRV parameter {one.name!r} is not a leg parameter ({', '.join(LEG_PARAMETERS)})")
    simulator = LegSimulator(scenario, nodes=nodes)
    base = simulator.parameters(**dict(base_overrides or {}))
    target = target or DEFAULT_TARGET[scenario]
    names = tuple(one.name for one in specs)
    settings = simulator.preset.solver.derive(scheme="energy-momentum") if settings is None else settings
    model = LegTargetModel(simulator, target, names, base=base, settings=settings)
    path = Path(store)
    multi = len(specs) > 1
    study: FRVStudy | FRVMultiStudy
    with Evaluator(workers=workers, scheduler=scheduler) as pool:
        evaluator = pool.batch(_recipe_of(model), sensitivities=sensitivities)
        if path.exists() and not overwrite:
            study = open_study(path, model, evaluator=evaluator)
            study.add_samples(n_samples)
        elif multi:
            made = StudyOptions(n_disc=n_disc, seed=seed, chunk=chunk, overwrite=overwrite, record=options)
            study = FRVMultiStudy.create(model, specs, n_samples, made, store=path, evaluator=evaluator)
        else:
            if not isinstance(n_disc, int):
                if len(n_disc) != 1:
                    raise ParameterError(f"n_disc: one FRV parameter takes one grid size; got {list(n_disc)}")
                n_disc = int(n_disc[0])
            made = StudyOptions(n_disc=n_disc, seed=seed, chunk=chunk, overwrite=overwrite, record=options)
            study = FRVStudy.create(model, specs[0], n_samples, made, store=path, evaluator=evaluator)
    return study
