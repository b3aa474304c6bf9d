"""Fuzzy forward dynamics of the leg + prosthesis (thesis §5.2–5.3).

:func:`fuzzy_forward_dynamics` runs the Graph Follower algorithm (linearised mode, thesis
OP-III) on a scenario's target output with triangular fuzzy parameters, using the
simulator's forward sensitivities for the linearisation.  Defaults follow the thesis:
stride 100 (an optimisation every 0.1 s at dt = 1 ms), novelty tolerance 0.01 %, α-levels
0, 0.5 and 1.  :func:`dense_reference` samples the α = 0 interval of one parameter densely
for comparison.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

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
from fuzzygait.uncertainty.frv.options import StudyOptions

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy

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


@dataclass(frozen=True, eq=False)
class LegTarget:
    """The output a leg scenario's fuzzy analysis follows and the model it is computed with.

    Attributes:
        name: one of :data:`~fuzzygait.mechanics.targets.TARGETS` (None: total
            deformation energy for swing, maximum element energy for stance).
        base: the full parameter vector, :data:`~fuzzygait.mechanics.leg.LEG_PARAMETERS`
            order, SI (None: the scenario's).
        settings: the simulations' solver settings (None: the scenario's,
            :attr:`~fuzzygait.mechanics.presets.ScenarioPreset.solver`).
    """

    name: str | None = None
    base: np.ndarray | None = None
    settings: SolverSettings | None = None

    def __post_init__(self) -> None:
        _check_target_name(self.name)
        if self.base is not None:
            base = np.asarray(self.base)
            if base.shape != (len(LEG_PARAMETERS),) or not np.issubdtype(base.dtype, np.number) \
                    or not np.all(np.isfinite(base)):  # fmt: skip
                raise ParameterError(f"base: give the {len(LEG_PARAMETERS)} finite leg parameters "
                                     f"({', '.join(LEG_PARAMETERS)}); got shape {base.shape}")  # fmt: skip
        _check_settings(self.settings)


def _check_target_name(target: object) -> None:
    if target is not None and target not in TARGETS:
        raise ParameterError(f"unknown target {target!r}; choose one of {', '.join(TARGETS)}")


def _check_settings(settings: object) -> None:
    if settings is not None and not isinstance(settings, SolverSettings):
        raise ParameterError(f"settings: give a SolverSettings; got {type(settings).__name__}")


def fuzzy_forward_dynamics(
    simulator: LegSimulator,
    spreads: Mapping[str, float],
    *,
    target: LegTarget | None = None,
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
        target: the :class:`LegTarget` (output name, base parameters, solver settings;
            default: the scenario's target, parameters and settings).
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
    leg = LegTarget() if target is None else target
    target_name = leg.name or DEFAULT_TARGET[simulator.scenario]
    names = tuple(spreads)
    model = LegTargetModel(simulator, target_name, names, base=leg.base, settings=leg.settings)
    numbers = [triangular_relative(model.base[LEG_PARAMETERS.index(n)], spreads[n], n) for n in names]
    start = time.perf_counter()
    engine_model = model if evaluator is None else evaluator.model(_recipe_of(model), sensitivities=True)
    result = graph_follower(engine_model, FuzzyVector(numbers), alphas, strategy=strategy, progress=progress)
    result.attrs.update(
        scenario=simulator.scenario,
        target=target_name,
        target_units="m" if target_name.startswith("last_node") else "J",
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
    for name in ("hull", "deterministic"):
        if name in result:
            result[name].attrs.setdefault("units", result.attrs["target_units"])
    if "extremiser" in result and "parameter" in result["extremiser"].dims:
        result = result.assign_coords(parameter_unit=("parameter", [PARAMETER_UNITS[n] for n in names]))
        result["extremiser"].attrs.update(long_name="the fuzzy parameters' values giving each bound, in their "
                                          "parameter_unit")  # fmt: skip
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


@dataclass(frozen=True)
class LegStudyModel:
    """The leg model of an FRV study (:func:`leg_frv_study`).

    Attributes:
        target: one of :data:`~fuzzygait.mechanics.targets.TARGETS` (None: the scenario's).
        base_overrides: leg parameter values (SI) laid over the scenario's.
        nodes: blade nodes (default 20, as in the thesis).
        settings: the solver settings (None: the scenario's with the energy-momentum scheme).
        sensitivities: the forward simulations return the sensitivities (the study refines
            α = 1 with them).
    """

    target: str | None = None
    base_overrides: Mapping[str, float] = field(default_factory=dict)
    nodes: int = 20
    settings: SolverSettings | None = None
    sensitivities: bool = True

    def __post_init__(self) -> None:
        _check_target_name(self.target)
        if not isinstance(self.base_overrides, Mapping):
            raise ParameterError(f"base_overrides: give a mapping NAME -> value; got {self.base_overrides!r}")
        unknown = [n for n in self.base_overrides if n not in LEG_PARAMETERS]
        if unknown:
            raise ParameterError(f"base_overrides: {unknown[0]!r} is not a leg parameter ({', '.join(LEG_PARAMETERS)})")
        if isinstance(self.nodes, bool) or not isinstance(self.nodes, (int, np.integer)) or self.nodes < 2:
            raise ParameterError(f"nodes must be a whole number >= 2; got {self.nodes!r}")
        _check_settings(self.settings)
        if not isinstance(self.sensitivities, (bool, np.bool_)):
            raise ParameterError(f"sensitivities must be True or False; got {self.sensitivities!r}")


def leg_frv_study(
    scenario: str,
    spec: FRVSpec | Sequence[FRVSpec],
    n_samples: int,
    store: str | os.PathLike[str],
    *,
    leg: LegStudyModel | None = None,
    study: StudyOptions | None = None,
    workers: int = 1,
    scheduler: str | None = None,
) -> FRVStudy:
    """Run (or extend) the FRV-GFA of a leg scenario (thesis §5.7) into a zarr ``store``.

    ``spec`` is a :class:`~fuzzygait.uncertainty.frv.FRVSpec` whose ``name`` is a leg
    parameter, or a sequence of several (independent FRVs, one α-level set: boxes and an
    α = 1 lattice, :class:`~fuzzygait.uncertainty.frv.FRVStudy`; ``study.n_disc`` one grid size for
    all or one per parameter, default 100; refined with the sensitivities as one parameter
    is); the other parameters are the scenario's with ``leg.base_overrides``; the
    :class:`LegStudyModel` ``leg`` also gives the target, blade nodes, solver settings
    (default: the scenario's with the energy-momentum scheme) and whether the simulations
    return sensitivities.  Forward simulations run on an
    :class:`~fuzzygait.uncertainty.execution.Evaluator` (``workers`` local processes, or
    the Dask cluster at ``scheduler``); each worker loads the compiled simulator library
    from the on-disk cache.  An existing store is extended with ``n_samples`` more samples
    (every stored library trajectory and interval hull reused) unless
    ``study.overwrite``; a new study is made with the
    :class:`~fuzzygait.uncertainty.frv.StudyOptions` ``study`` and records its ``record``
    (what it was made with, for the caller to compare before extending it).  Returns the
    :class:`~fuzzygait.uncertainty.frv.FRVStudy` (of one parameter or several).
    """
    from pathlib import Path

    from fuzzygait.uncertainty.frv import FRVStudy, check_specs

    specs = check_specs(spec)
    for one in specs:
        if one.name not in LEG_PARAMETERS:
            raise ParameterError(f"FRV parameter {one.name!r} is not a leg parameter ({', '.join(LEG_PARAMETERS)})")
    leg = LegStudyModel() if leg is None else leg
    study_options = StudyOptions(n_disc=100) if study is None else study
    if study_options.n_disc is None:
        study_options = replace(study_options, n_disc=100)
    simulator = LegSimulator(scenario, nodes=leg.nodes)
    base = simulator.parameters(**dict(leg.base_overrides))
    target = leg.target or DEFAULT_TARGET[scenario]
    names = tuple(one.name for one in specs)
    settings = simulator.preset.solver.derive(scheme="energy-momentum") if leg.settings is None else leg.settings
    model = LegTargetModel(simulator, target, names, base=base, settings=settings)
    path = Path(store)
    result: FRVStudy
    with Evaluator(workers=workers, scheduler=scheduler) as pool:
        evaluator = pool.batch(_recipe_of(model), sensitivities=leg.sensitivities)
        if path.exists() and not study_options.overwrite:
            result = FRVStudy.open(path, model, evaluator=evaluator)
            result.add_samples(n_samples)
        else:
            result = FRVStudy.create(model, specs, n_samples, study_options, store=path, evaluator=evaluator)
    return result
