"""Leg + prosthesis simulations as jobs (``fuzzygait simulate`` and ``fuzzy-sim``): the
scenario's simulator built (or its compiled code loaded), one forward run or the fuzzy
forward dynamics of :func:`fuzzygait.mechanics.fuzzy_dynamics.fuzzy_forward_dynamics`,
and every output file written, or none of them."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.core.errors import FuzzyGaitError, ParameterError, SimulationError
from fuzzygait.core.options import Option
from fuzzygait.mechanics.scenarios import SCENARIOS, LegSimulator
from fuzzygait.mechanics.solver import BladeFolded, SolverSettings
from fuzzygait.workflows.outputs import write_all_or_none
from fuzzygait.workflows.progress import SILENT, StageProgress, announce, takes_estimates

if TYPE_CHECKING:
    import xarray as xr

    from fuzzygait.uncertainty import Linearised
    from fuzzygait.workflows.work_estimate import SimulationTiming, WorkEstimate

#: Linearised steps per α-level optimisation at most (fuzzy-sim; the engine's default).
MAX_ITERATIONS = 4
#: Share of a simulation's time steps :func:`time_simulation` runs (at least TIMED_STEPS).
TIMED_SHARE, TIMED_STEPS = 0.05, 10

__all__ = [
    "FuzzySimOutputs",
    "LegSetup",
    "SimulationOutputs",
    "build_simulator",
    "check_scenario",
    "check_scheme",
    "command_setup",
    "named_fixes",
    "fuzzy_simulation",
    "simulate_leg",
    "simulation_timing",
    "solver_settings",
    "time_simulation",
]


def check_scenario(scenario: str) -> None:
    """A :class:`FuzzyGaitError` unless ``scenario`` is one of the presets."""
    if scenario not in SCENARIOS:
        raise FuzzyGaitError(f"unknown scenario {scenario!r}; choose {' or '.join(SCENARIOS)}")


def check_scheme(scheme: str) -> None:
    """A :class:`FuzzyGaitError` unless ``scheme`` is a time integrator."""
    from fuzzygait.mechanics.solver import SCHEMES

    if scheme not in SCHEMES:
        raise FuzzyGaitError(f"{Option.SCHEME} must be {' or '.join(SCHEMES)}; got {scheme!r}")


def simulation_timing(scenario: str, dt: float | None, duration: float | None) -> tuple[float, float]:
    """The time step and simulated time (s): the given ones, else the scenario's."""
    preset = SCENARIOS[scenario]
    step = preset.dt if dt is None else dt
    if not (np.isfinite(step) and step > 0):
        raise FuzzyGaitError(f"{Option.DT} must be a time step > 0 s; got {dt:g}")
    span = preset.duration if duration is None else duration
    if not (np.isfinite(span) and span >= step):
        raise FuzzyGaitError(f"{Option.DURATION} must be at least the time step ({step:g} s); got {span:g}")
    return step, span


def solver_settings(scenario: str, dt: float | None, duration: float | None, scheme: str) -> SolverSettings:
    """The scenario's solver settings with the command's time step and simulated time (s;
    None: the scenario's) and ``scheme``; a :class:`FuzzyGaitError` naming the option for
    an impossible one."""
    check_scheme(scheme)
    step, span = simulation_timing(scenario, dt, duration)
    return SCENARIOS[scenario].solver.derive(dt=step, duration=span, scheme=scheme)


@dataclass(frozen=True)
class LegSetup:
    """A leg scenario as simulated: preset, blade nodes, parameter ``values`` in SI units
    (the others: the scenario's) and the ``solver`` settings (None: the scenario's,
    :attr:`~fuzzygait.mechanics.presets.ScenarioPreset.solver`)."""

    scenario: str
    nodes: int = 20
    values: Mapping[str, float] = field(default_factory=dict)
    solver: SolverSettings | None = None

    @property
    def settings(self) -> SolverSettings:
        """The solver settings, the scenario's filled in."""
        return SCENARIOS[self.scenario].solver if self.solver is None else self.solver

    @property
    def scheme(self) -> str:
        """The time integrator."""
        return self.settings.scheme


def command_setup(scenario: str, nodes: int | None, dt: float | None, duration: float | None,
                  values: Mapping[str, float], scheme: str | None) -> tuple[LegSetup, str | None]:
    """The setup a command runs: the scenario's :data:`~fuzzygait.mechanics.presets.COMMAND_DEFAULTS`
    (values and scheme the thesis' tables do not run with on the shipped blade) under what
    the user gave. Returns it and a note naming each default taken from there (None: none)."""
    from fuzzygait.mechanics.presets import COMMAND_DEFAULTS

    check_scenario(scenario)
    if scheme is not None:
        check_scheme(scheme)
    step, span = simulation_timing(scenario, dt, duration)
    defaults = COMMAND_DEFAULTS[scenario]
    taken = {k: v for k, v in defaults.values.items() if k not in values}
    changed = [f"{Option.SET} {k}={v:g}" for k, v in taken.items()]
    if scheme is None:
        scheme = defaults.scheme
        if scheme != "variational":
            changed.append(f"{Option.SCHEME} {scheme}")
    if nodes is None:
        nodes = defaults.nodes
        if nodes != 20:
            changed.append(f"{Option.NODES} {nodes}")
    note = (f"{scenario} runs with {', '.join(changed)} by default ({defaults.reason}); give the option to change it"
            if changed else None)  # fmt: skip
    solver = defaults.solver(SCENARIOS[scenario]).derive(dt=step, duration=span, scheme=scheme)
    return LegSetup(scenario, nodes, {**taken, **values}, solver), note


@contextmanager
def named_fixes(setup: LegSetup) -> Iterator[None]:
    """Add to a :class:`SimulationError` the command-line options that fix it: more
    damping (``--set eta=``, ten times the run's), and for a failed Newton step the other
    scheme or half the time step (``--dt``)."""
    try:
        yield
    except SimulationError as exc:
        preset = SCENARIOS[setup.scenario]
        eta = float(setup.values.get("eta", preset.material.damping))
        step = setup.settings.dt
        fixes = [f"{Option.SET.flag} eta={max(10 * eta, 1e5):g}"]  # command-line options, as the message says
        if isinstance(exc, BladeFolded):
            fixes.append(f"{Option.NODES.flag} {2 * setup.nodes}")
        else:
            if setup.scheme != "energy-momentum":
                fixes.append(f"{Option.SCHEME.flag} energy-momentum")
            fixes.append(f"{Option.DT.flag} {step / 2:g}")
        raise SimulationError(f"{exc}; on the command line: {' or '.join(fixes)}") from None


def build_simulator(setup: LegSetup, progress: StageProgress = SILENT) -> tuple[LegSimulator, np.ndarray]:
    """The scenario's simulator (built, or its compiled code loaded) and its full
    parameter vector with the setup's values set."""
    progress.stage(f"{setup.scenario}: building the model")
    sim = LegSimulator(scenario=setup.scenario, nodes=setup.nodes)
    return sim, sim.parameters(**setup.values)


def time_simulation(sim: LegSimulator, p: np.ndarray, setup: LegSetup) -> SimulationTiming | None:
    """How long one forward simulation of ``setup`` with sensitivities takes at the full
    parameter vector ``p``: its first :data:`TIMED_SHARE` of the time steps (at least
    :data:`TIMED_STEPS`) and its first step alone timed here (after one warm-up step),
    the cost of a run extrapolated linearly in its steps from the two. None when those
    steps fail (the run itself then says why)."""
    import time

    from fuzzygait.workflows.work_estimate import SimulationTiming

    settings = setup.settings
    step, steps = settings.dt, max(1, settings.steps)
    timed = min(steps, max(TIMED_STEPS, int(np.ceil(TIMED_SHARE * steps))))
    seconds = []
    try:
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            for n in (1, 1, timed):  # the first loads and warms up
                start = time.perf_counter()
                sim.run(p, settings.derive(duration=n * step), sensitivities=True)
                seconds.append(time.perf_counter() - start)
    except FuzzyGaitError:
        return None
    per_step = max(0.0, seconds[2] - seconds[1]) / (timed - 1) if timed > 1 else seconds[1]
    return SimulationTiming(max(seconds[1], seconds[1] + per_step * (steps - 1)), timed, steps)


@dataclass(frozen=True)
class SimulationOutputs:
    """Files of a simulation: the results (``out_file``, .nc or .zarr) and optionally the
    energies over time (``plot``) and a Rerun recording (``rrd``)."""

    out_file: Path
    plot: Path | None = None
    rrd: Path | None = None


def simulate_leg(
    setup: LegSetup, outputs: SimulationOutputs, *, sensitivities: bool = False, progress: StageProgress = SILENT
) -> tuple[xr.Dataset, list[Path]]:
    """Simulate a scenario and write its outputs (all or none).

    The dataset has positions, directors, joint angles and energies over time, and the
    segment lengths and centre-of-mass distances (``thigh_length_m`` ...) in its
    attributes.  Returns it and the files written.
    """
    from fuzzygait.io.figure_files import save_figure
    from fuzzygait.uncertainty.storage import save_result
    from fuzzygait.viz.mechanics import energy_figure
    from fuzzygait.workflows.rerun_recordings import write_simulation_recording

    check_scenario(setup.scenario)
    settings = setup.settings
    sim, p = build_simulator(setup, progress)
    progress.stage(f"{setup.scenario}: time steps", settings.steps)
    # the integrator checks for non-finite values itself; numpy's overflow warnings on a
    # diverging step would only add lines to its one-line error
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"), named_fixes(setup):
        ds = sim.run(p, settings, sensitivities=sensitivities, progress=progress.update)
    config = sim.configuration
    ds.attrs.update({f"{seg.name}_{key}_m": float(getattr(seg, key))
                     for seg in (config.thigh, config.shank) for key in ("length", "com_from_proximal")})  # fmt: skip
    written = write_all_or_none([
        (outputs.out_file, lambda path: save_result(ds, path)),
        (outputs.plot, lambda path: save_figure(energy_figure(ds), path)),
        (outputs.rrd, lambda path: write_simulation_recording(ds, path, configuration=config)),
    ])  # fmt: skip
    return ds, written


@dataclass(frozen=True)
class FuzzySimOutputs:
    """Files of a fuzzy simulation: the result (``out_file``, .zarr or .nc) and optionally
    the hull plot, the extremising parameter sets (Fig. 5.6) and a Rerun recording."""

    out_file: Path
    plot: Path | None = None
    parameter_plot: Path | None = None
    rrd: Path | None = None


@dataclass(frozen=True)
class FuzzySimRequest:
    """What a fuzzy simulation computes: the hulls of ``target`` (None: the scenario's,
    :data:`~fuzzygait.mechanics.fuzzy_dynamics.DEFAULT_TARGET`) for triangular fuzzy
    parameters of relative half-widths ``spreads`` (name → spread in (0, 1)) at the
    ``alphas``, by the Graph Follower's linearised ``strategy`` (None: an optimisation every
    100th time node, novelty tolerance 1e-4, :data:`MAX_ITERATIONS` steps, the (α, bound)
    tracks side by side; :func:`command_strategy` builds one from the command's options)."""

    spreads: Mapping[str, float]
    target: str | None = None
    alphas: Sequence[float] = (0.0, 0.5, 1.0)
    strategy: Linearised | None = None

    def __post_init__(self) -> None:
        from fuzzygait.uncertainty import Linearised

        if not isinstance(self.spreads, Mapping) or not self.spreads:
            raise ParameterError(f"spreads: give at least one fuzzy parameter NAME -> spread; got {self.spreads!r}")
        for name, spread in self.spreads.items():
            if isinstance(spread, bool) or not isinstance(spread, (int, float, np.floating)) or not 0 < spread < 1:
                raise ParameterError(f"spreads: {name}'s spread must lie between 0 and 1 (0.1 = ±10 %); got {spread!r}")
        _check_target(self.target)
        if isinstance(self.alphas, str) or not isinstance(self.alphas, Sequence) or not self.alphas or not all(
                not isinstance(a, bool) and isinstance(a, (int, float, np.floating)) and 0 <= a <= 1
                for a in self.alphas):  # fmt: skip
            raise ParameterError(f"alphas: give α-levels between 0 and 1; got {self.alphas!r}")
        if self.strategy is not None and not isinstance(self.strategy, Linearised):
            raise ParameterError(f"strategy: give a Linearised strategy; got {type(self.strategy).__name__}")

    @property
    def linearised(self) -> Linearised:
        """The strategy, the default filled in."""
        from fuzzygait.uncertainty import Linearised

        if self.strategy is not None:
            return self.strategy
        return Linearised(stride=100, novelty_tol=1e-4, max_iterations=MAX_ITERATIONS, tracks="side-by-side")


def command_strategy(stride: int, novelty: float, tracks: str = "side-by-side") -> Linearised:
    """The Graph Follower strategy of the fuzzy-sim command: an optimisation every ``stride``-th
    time node, novelty tolerance ``novelty``, :data:`MAX_ITERATIONS` steps (a bad ``--stride``:
    a :class:`FuzzyGaitError` naming the option)."""
    from fuzzygait.uncertainty import Linearised

    if stride < 1:
        raise FuzzyGaitError(f"{Option.STRIDE} must be ≥ 1; got {stride}")
    return Linearised(stride=stride, novelty_tol=novelty, max_iterations=MAX_ITERATIONS, tracks=tracks)


def fuzzy_simulation(
    setup: LegSetup,
    request: FuzzySimRequest,
    outputs: FuzzySimOutputs,
    *,
    workers: int = 1,
    scheduler: str | None = None,
    progress: StageProgress = SILENT,
) -> tuple[xr.Dataset, list[Path]]:
    """Fuzzy forward dynamics of a scenario (the :class:`FuzzySimRequest`: hulls of its
    target for triangular fuzzy parameters) and its outputs (all or none). The forward
    simulations run on ``workers`` local processes (1: this one) or the Dask
    ``scheduler``; with the strategy's ``tracks="side-by-side"`` (the Graph Follower's (α,
    bound) tracks at once) those of a round run in parallel, and the hulls do not depend
    on the number of workers."""
    from fuzzygait.io.figure_files import save_figure
    from fuzzygait.mechanics.fuzzy_dynamics import LegTarget, fuzzy_forward_dynamics
    from fuzzygait.uncertainty.execution import Evaluator
    from fuzzygait.uncertainty.storage import save_result
    from fuzzygait.viz.fuzzy_dynamics import extremiser_figure, hull_figure
    from fuzzygait.workflows.rerun_recordings import write_fuzzy_recording

    check_scenario(setup.scenario)
    strategy, alphas = request.linearised, request.alphas
    sim, base = build_simulator(setup, progress)
    stage = f"{setup.scenario}: α-level optimisations"
    work, optimisations = _fuzzy_work(sim, base, setup, stage, alphas, strategy.stride,
                                      None if scheduler is not None else workers, progress)  # fmt: skip
    announce(progress, work)
    progress.stage(stage, optimisations)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"), named_fixes(setup), \
            Evaluator(workers=workers, scheduler=scheduler) as evaluator:  # fmt: skip
        target = LegTarget(request.target, base=base, settings=setup.settings)
        result = fuzzy_forward_dynamics(
            sim, request.spreads, target=target, alphas=alphas, strategy=strategy,
            progress=progress.update, evaluator=None if evaluator.serial else evaluator,
        )  # fmt: skip
    result.attrs["workers"] = workers if scheduler is None else f"scheduler {scheduler}"
    written = write_all_or_none([
        (outputs.out_file, lambda path: save_result(result, path)),
        (outputs.plot, lambda path: save_figure(hull_figure(result), path)),
        (outputs.parameter_plot, lambda path: save_figure(extremiser_figure(result), path)),
        (outputs.rrd, lambda path: write_fuzzy_recording(result, path)),
    ])  # fmt: skip
    return result, written


def _check_target(target: str | None) -> None:
    """A :class:`FuzzyGaitError` for an unknown target, before any work."""
    from fuzzygait.mechanics.targets import TARGETS

    if target is not None and target not in TARGETS:
        raise FuzzyGaitError(f"unknown target {target!r}; choose one of {', '.join(TARGETS)}")


def _fuzzy_work(sim: LegSimulator, base: np.ndarray, setup: LegSetup, stage: str, alphas: Sequence[float],
                stride: int, workers: int | None, progress: StageProgress) -> tuple[WorkEstimate, int]:  # fmt: skip
    """The estimate of a fuzzy simulation (one simulation timed first when ``progress``
    takes estimates) and its α-level optimisations (the bar's total)."""
    from fuzzygait.workflows.work_estimate import fuzzy_sim_optimisations, fuzzy_sim_work

    n_time = setup.settings.steps + 1
    timing = None
    if takes_estimates(progress):
        progress.stage(f"{setup.scenario}: timing a forward simulation")
        timing = time_simulation(sim, base, setup)
    work = fuzzy_sim_work(setup.scenario, n_time, stride, alphas, MAX_ITERATIONS, stage, timing, workers)
    return work, fuzzy_sim_optimisations(n_time, stride, alphas)
