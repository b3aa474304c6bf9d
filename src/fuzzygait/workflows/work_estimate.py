"""What a heavy command is about to do, said before it starts (issue 37): the work in the
unit that costs — forward simulations of the leg for ``fuzzy-sim`` and ``frv-sim``,
α-level optimisations (frames × α-levels × angle components) and refinement / per-source
runs for the marker-error analysis of ``uncertainty`` and ``report`` — and, where one was
timed, how long one simulation takes.

Each estimate says what it is: *exactly* where the algorithm fixes the count in advance
(a new one-parameter FRV study: one simulation per grouping bin), *at most* where it
stops early (the Graph Follower's novelty check, the allowable-error searches), *about*
where inputs not yet read decide it (the frames of a report's trials).  A
:class:`WorkEstimate` holds the line a command prints and the labels its progress bars
add to the stages' descriptions (:class:`~fuzzygait.workflows.progress.Announced`).

The limits of what a command accepts without being told twice live here too:
:data:`MAX_ALPHA_LEVELS` (``--alphas``) and :data:`MAX_FRV_SAMPLES` (``--samples``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import Option

if TYPE_CHECKING:
    from fuzzygait.uncertainty.frv import FRVSpec, Grid
    from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings

__all__ = [
    "EXACTLY",
    "AT_MOST",
    "ABOUT",
    "MAX_ALPHA_LEVELS",
    "MAX_FRV_SAMPLES",
    "SimulationTiming",
    "WorkEstimate",
    "check_alpha_count",
    "check_frv_samples",
    "duration_text",
    "frv_work",
    "fuzzy_sim_optimisations",
    "fuzzy_sim_work",
    "marker_error_work",
    "report_work",
]

#: α-levels below 1 a command takes (each one is a whole optimisation more per frame or
#: time node and bound; the thesis uses 2 to 4).
MAX_ALPHA_LEVELS = 20
#: FRV samples ``frv-sim`` draws in one run without ``--force`` (every sample's hulls are
#: stored: 10⁶ samples of the thesis' stance study are ~10¹⁰ numbers).
MAX_FRV_SAMPLES = 1_000_000
#: How sure a count is.
EXACTLY, AT_MOST, ABOUT = "exactly", "at most", "about"


def check_alpha_count(levels: Sequence[float]) -> None:
    """One clear error for more than :data:`MAX_ALPHA_LEVELS` α-levels below 1."""
    below = len({float(a) for a in levels if a < 1.0})
    if below > MAX_ALPHA_LEVELS:
        raise FuzzyGaitError(f"{Option.ALPHAS} gives {below} α-levels below 1; at most {MAX_ALPHA_LEVELS} are taken "
                             "(each one is a whole optimisation more per frame or time node and bound; the thesis "
                             "uses 2 to 4): give fewer, e.g. 0,0.25,0.5,0.75")  # fmt: skip


def check_frv_samples(samples: int, force: bool) -> None:
    """One clear error for more than :data:`MAX_FRV_SAMPLES` samples without ``force``."""
    if samples > MAX_FRV_SAMPLES and not force:
        raise FuzzyGaitError(f"{Option.SAMPLES} {samples}: more than {MAX_FRV_SAMPLES:,} FRV samples in one run "
                             "(the hulls of every sample are computed and stored: hours and gigabytes); give at most "
                             f"{MAX_FRV_SAMPLES} and extend the study with further runs, or add {Option.FORCE} to run "
                             "it anyway")  # fmt: skip


def duration_text(seconds: float) -> str:
    """``0.07 s``, ``6.9 s``, ``4.2 min``, ``1.5 h``."""
    if seconds < 1:
        return f"{seconds:.2g} s"
    if seconds < 90:
        return f"{seconds:.1f} s" if seconds < 10 else f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


def _plural(n: int, word: str) -> str:
    return f"{n:,} {word if n == 1 else word + 's'}"


@dataclass(frozen=True)
class SimulationTiming:
    """One forward simulation's time (s), extrapolated from ``timed_steps`` of its
    ``steps`` time steps timed before the work starts."""

    seconds: float
    timed_steps: int
    steps: int

    def text(self) -> str:
        how = ("timed here" if self.timed_steps >= self.steps
               else f"extrapolated from its first {self.timed_steps} of {self.steps} steps, timed here")  # fmt: skip
        return f"≈ {duration_text(self.seconds)} each ({how})"


@dataclass(frozen=True)
class WorkEstimate:
    """The work a command is about to do.

    Attributes:
        count: the work in ``unit`` (the figure the line leads with).
        unit: e.g. ``"forward simulations"``.
        certainty: :data:`EXACTLY`, :data:`AT_MOST` or :data:`ABOUT`.
        text: the line, after ``"estimate: "``.
        stages: progress-stage description → what its bar adds (``"≤ 337 forward simulations"``).
    """

    count: int
    unit: str
    certainty: str
    text: str
    stages: Mapping[str, str] = field(default_factory=dict)

    def line(self) -> str:
        """The line a command prints before it starts."""
        return f"estimate: {self.text}"

    def prefixed(self, prefix: str) -> WorkEstimate:
        """The estimate with ``prefix`` before every stage description it labels."""
        return replace(self, stages={prefix + stage: label for stage, label in self.stages.items()})


def _sign(certainty: str) -> str:
    return {EXACTLY: "", AT_MOST: "≤ ", ABOUT: "≈ "}[certainty]


def _timing_text(count: int, certainty: str, timing: SimulationTiming | None, parallel: int | None) -> str:
    """``, ≈ 6.9 s each (…): at most ≈ 19 min in all on 2 workers`` (empty without a timing)."""
    if timing is None or count == 0:
        return ""
    text = ", " + timing.text()
    if parallel is not None:
        total = count * timing.seconds / max(1, parallel)
        lead = "at most " if certainty == AT_MOST else ""
        text += f": {lead}≈ {duration_text(total)} in all" + (f" on {parallel} workers" if parallel > 1 else "")
    return text


def fuzzy_sim_optimisations(n_time: int, stride: int, alphas: Sequence[float]) -> int:
    """``fuzzy-sim``'s α-level optimisations: 2 bounds × α-levels below 1 × optimisation
    nodes (every ``stride``-th of ``n_time`` time nodes and the last)."""
    from fuzzygait.uncertainty.gfa import optimisation_nodes

    return 2 * len({float(a) for a in alphas if a < 1.0}) * int(optimisation_nodes(n_time, stride).size)


def fuzzy_sim_work(scenario: str, n_time: int, stride: int, alphas: Sequence[float], max_iterations: int,
                   stage: str, timing: SimulationTiming | None = None,
                   workers: int | None = None) -> WorkEstimate:  # fmt: skip
    """The forward simulations of ``fuzzy-sim`` (the linearised Graph Follower,
    :class:`~fuzzygait.uncertainty.gfa.strategies.Linearised`): the deterministic run,
    then per α-level below 1, bound and optimisation node at most ``max_iterations``
    linearised steps, each a simulation unless the novelty check finds it in the library
    — an upper bound; the α-level optimisations (the bar's total) are exact."""
    from fuzzygait.uncertainty.gfa import optimisation_nodes

    nodes = int(optimisation_nodes(n_time, stride).size)
    levels = len({float(a) for a in alphas if a < 1.0})
    optimisations = 2 * levels * nodes
    bound = 1 + optimisations * max_iterations
    parallel = None if workers is None else max(1, min(workers, 2 * levels))
    made_of = (f"{_plural(optimisations, 'α-level optimisation')}: {_plural(levels, 'α-level')} × 2 bounds × "
               f"{_plural(nodes, 'time node')}, ≤ {max_iterations} linearised steps each, + the deterministic run; "
               "the novelty check skips most")  # fmt: skip
    text = (f"at most {_plural(bound, 'forward simulation')} of the {scenario} ({made_of})"
            + _timing_text(bound, AT_MOST, timing, parallel))  # fmt: skip
    return WorkEstimate(bound, "forward simulations", AT_MOST, text, {stage: f"≤ {bound:,} forward simulations"})


def _sample_ranges(specs: Sequence[FRVSpec], seed: int, start: int, n: int) -> list[tuple[float, float]]:
    """Per parameter the smallest and largest α-cut end of samples ``start … start+n−1``."""
    from fuzzygait.uncertainty.frv import BLOCK, generate_samples

    ranges = []
    for k, spec in enumerate(specs):
        low, high = math.inf, -math.inf
        for a in range(start, start + n, BLOCK):
            cuts = generate_samples(spec, min(BLOCK, start + n - a), seed, a, stream=k)
            low, high = min(low, float(cuts[:, 0, 0].min())), max(high, float(cuts[:, 0, 1].max()))
        ranges.append((low, high))
    return ranges


def _extended_grids(meta: Mapping[str, Any], samples: int) -> list[Grid]:
    """The study's grids (its commit record ``meta``) as ``samples`` more samples extend them."""
    import numpy as np

    from fuzzygait.uncertainty.frv import FRVSpec, Grid

    def listed(value: Any) -> list[dict[str, Any]]:
        return value if isinstance(value, list) else [value]

    grids = [Grid(**g) for g in listed(meta["grid"])]
    if samples == 0:
        return grids
    specs = [FRVSpec.from_dict(spec) for spec in listed(meta["spec"])]
    ranges = _sample_ranges(specs, int(meta["seed"]), int(meta["n_samples"]), samples)
    return [g.extended(np.array(r)) for g, r in zip(grids, ranges, strict=True)]


def _frv_simulations(specs: Sequence[FRVSpec], disc: int | Sequence[int], samples: int,
                     meta: Mapping[str, Any] | None) -> tuple[int, str, str]:  # fmt: skip
    """``(count, certainty, how it is made up)`` of an FRV study's new forward simulations."""
    from fuzzygait.uncertainty.frv.multi import PEAK_CHECKS, PEAK_FACTORS

    n_params = len(specs)
    if meta is None:
        bins = [int(disc) - 1] * n_params if isinstance(disc, int) else [int(n) - 1 for n in disc]
    else:
        bins = [g.n_bins for g in _extended_grids(meta, samples)]
    if n_params == 1 and meta is None:
        return bins[0], EXACTLY, f"one per grouping bin: {Option.DISC} {bins[0] + 1} points"
    if n_params == 1:
        before = int(meta["library_rows"])  # type: ignore[index]
        new = max(0, bins[0] - before) if samples else 0
        return new, AT_MOST, f"the bins the new samples add to the grid: {bins[0]} in all, {before} simulated before"
    corners = 2**n_params
    lattice = math.prod(max(PEAK_FACTORS) * (b - 1) + 1 for b in bins)  # the finest α = 1 lattice's points
    chosen = meta is not None and meta.get("peak_refine", [1]) is not None  # the α = 1 lattice of the study
    checks = 0 if chosen else min(PEAK_CHECKS, samples) * n_params  # test peaks, each lattice level's corners
    peaks = min(lattice, samples * corners + len(PEAK_FACTORS) * checks * corners)
    points = math.prod(bins)
    how = (f"≤ {points:,} grid points inside the occurring boxes of {' × '.join(map(str, bins))} bins, ≤ {peaks:,} "
           f"α = 1 lattice points around the samples' peaks" + (f" and {checks} lattice checks" if checks else "")
           + "; usually far fewer")  # fmt: skip
    return (points + peaks + checks) if samples else 0, AT_MOST, how


def frv_work(scenario: str, specs: Sequence[FRVSpec], disc: int | Sequence[int], samples: int, stage: str, *,
             meta: Mapping[str, Any] | None = None, timer: Callable[[], SimulationTiming | None] | None = None,
             workers: int | None = None) -> WorkEstimate:  # fmt: skip
    """The forward simulations of ``frv-sim``: a new study of one parameter simulates
    every bin centre of its grid (exactly ``disc − 1``); an extension (``meta``: the
    study's commit record) only the bins its new samples add; several parameters the grid
    points inside the occurring boxes and the α = 1 lattice around the peaks (a bound).
    ``timer`` times one simulation, called only when there are any."""
    count, certainty, how = _frv_simulations(specs, disc, samples, meta)
    timing = timer() if timer is not None and count else None
    if count == 0:
        library = 0 if meta is None else int(meta["library_rows"])
        reused = f" (the study's {_plural(library, 'library simulation')} reused)" if library else ""
        text = f"no new forward simulations{reused}; the hulls of {_plural(samples, 'new sample')}"
        return WorkEstimate(0, "forward simulations", EXACTLY, text, {stage: "no new forward simulations"})
    lead = "" if certainty == EXACTLY else f"{certainty} "
    text = (f"{lead}{_plural(count, 'forward simulation')} of the {scenario} ({how})"
            + _timing_text(count, certainty, timing, workers) + f"; then the hulls of {_plural(samples, 'sample')}")
    return WorkEstimate(count, "forward simulations", certainty, text,
                        {stage: f"{_sign(certainty)}{count:,} forward simulations"})  # fmt: skip


#: The fuzzy kinetics' components (sagittal moment and power of ankle, knee and hip, both
#: sides; :func:`~fuzzygait.workflows.marker_uncertainty.fuzzy_kinetics`), their progress
#: stage, and their cost per component and frame relative to an angle component's
#: (measured on the whole sample trial, the sagittal moments and the powers against every
#: angle, one process: 3.2-3.6, ``benchmarks/RESULTS.md``, "Fuzzy moments stop where a frame turns").
KINETIC_COMPONENTS = 12
FUZZY_KINETICS_STAGE = "fuzzy kinetics"
KINETIC_COST_FACTOR = 3.5


@dataclass(frozen=True)
class MarkerErrorWork:
    """The marker-error analysis' work: ``optimisations`` = Σ over the analysed components
    of their frames × the α-levels below 1 (each for the upper and the lower bound), the
    allowable-error refinement runs at most and the per-source runs (each one Graph
    Follower run of one component at one α-level over the frames)."""

    frames: int
    levels: int
    components: int
    optimisations: int
    allowable_runs: int
    source_runs: int
    sources: int
    flexion: int
    runs_per_component: int
    kinetic_components: int = 0

    def text(self, frames: str, components: str, per_trial: str = "") -> str:
        """The estimate's line (``frames``/``components``: how to name those factors)."""
        text = (f"{_plural(self.optimisations, 'α-level optimisation')} of the fuzzy angles ({frames} × "
                f"{_plural(self.levels, 'α-level')} × {components}, each for the upper and the lower "
                "bound)")  # fmt: skip
        later = []
        if self.allowable_runs:
            later.append(f"at most {_plural(self.allowable_runs, 'allowable-error refinement run')} (≤ "
                         f"{self.runs_per_component} per component)")  # fmt: skip
        if self.source_runs:
            later.append(f"{_plural(self.source_runs, 'per-source run')} ({_plural(self.sources, 'source')} × "
                         f"{_plural(self.flexion, 'flexion component')})")  # fmt: skip
        if later:
            text += f", then{per_trial} " + " and ".join(later) + ", each one α-level over the frames"
        if self.kinetic_components:
            text += (f"; where the trial has force plates, the fuzzy kinetics of "
                     f"{_plural(self.kinetic_components, 'moment or power component')} over the same frames and "
                     f"α-levels, each about {KINETIC_COST_FACTOR} times an angle component's work")  # fmt: skip
        return text


def _components(names: Sequence[str]) -> list[str]:
    """Angle names (all three components) or single components as component names."""
    from fuzzygait.markererror.analysis import split_component
    from fuzzygait.markererror.angle_model import AXES

    out: list[str] = []
    for requested in names:
        name, axes = split_component(requested)
        out += [c for c in (f"{name}_{AXES[a]}" for a in axes) if c not in out]
    return out


def _marker_work(frames: Mapping[str, int], settings: MarkerErrorSettings) -> MarkerErrorWork:
    """The work of ``settings`` on components analysed on ``frames[component]`` frames."""
    from fuzzygait.markererror.allowable import MAX_EVALUATIONS
    from fuzzygait.markererror.per_source import FLEXION_COMPONENTS

    levels = len({float(a) for a in settings.alphas if a < 1.0})
    analysed = [c for c, n in frames.items() if n > 0]
    refined = analysed if settings.allowable_angles is None else [
        c for c in _components(settings.allowable_angles) if c in analysed]  # fmt: skip
    flexion = [c for c in analysed if c in FLEXION_COMPONENTS]
    per_source = settings.per_source and len(settings.sources) > 1 and levels > 0
    return MarkerErrorWork(
        frames=max(frames.values(), default=0), levels=levels, components=len(analysed),
        optimisations=levels * sum(frames.values()),
        allowable_runs=MAX_EVALUATIONS * len(refined) if settings.tolerance is not None else 0,
        source_runs=len(settings.sources) * len(flexion) if per_source else 0, sources=len(settings.sources),
        flexion=len(flexion), runs_per_component=MAX_EVALUATIONS,
        kinetic_components=KINETIC_COMPONENTS if settings.kinetics else 0,
    )  # fmt: skip


def marker_error_work(frames: Mapping[str, int], settings: MarkerErrorSettings,
                      stages: Sequence[str] = ("fuzzy angles", "allowable marker error",
                                               "per-source bands")) -> WorkEstimate:  # fmt: skip
    """The work of the marker-error analysis of one trial whose angles are computed:
    ``frames`` = analysed component (``"LKneeAngles_X"``) → the frames it is optimised
    on (:func:`~fuzzygait.markererror.analysis.component_tasks`)."""
    work = _marker_work(frames, settings)
    same = len({n for n in frames.values() if n > 0}) <= 1
    text = work.text(f"{'' if same else '≤ '}{_plural(work.frames, 'frame')}",
                     _plural(work.components, 'angle component'))  # fmt: skip
    labels = {stages[0]: f"{work.optimisations:,} α-level optimisations",
              stages[1]: f"≤ {work.allowable_runs:,} runs", stages[2]: f"{work.source_runs:,} runs",
              FUZZY_KINETICS_STAGE: f"{work.kinetic_components} components"}  # fmt: skip
    return WorkEstimate(work.optimisations, "α-level optimisations", EXACTLY, text, labels)


def _trial_frames(path: Path) -> int:
    """Frames a C3D file declares (its header or POINT:FRAMES; 0 when unreadable)."""
    from fuzzygait.io.c3d_guard import inspect

    try:
        layout = inspect(path)
    except OSError:
        return 0
    header, parameter = layout.declared_frames()
    return max(header or 0, parameter or 0)


def report_work(inputs: Sequence[Path], settings: MarkerErrorSettings, *, static: Path | None = None,
                subject_file: Path | None = None, force: bool = False,
                stage: str = "trials") -> WorkEstimate:  # fmt: skip
    """The work of ``report``'s marker-error analysis (``settings``: those of its
    ``--uncertainty`` mode) over the walking trials its discovery finds in ``inputs``:
    the frames their files declare × the α-levels × the components asked for (every
    angle's: up to 36, the CGM 2.4 forefoot's included) — an estimate made before any
    trial is read; trials unchanged since the last run on ``--out`` are reused (unless
    ``force``)."""
    from fuzzygait.kinematics import ALL_ANGLE_NAMES
    from fuzzygait.workflows.session import find_sessions

    trials = [t.path for s in find_sessions(inputs, static, subject_file) for t in s.trials]
    frames = sum(_trial_frames(p) for p in trials)
    components = _components(settings.angles if settings.angles is not None else ALL_ANGLE_NAMES)
    work = _marker_work(dict.fromkeys(components, frames), settings)
    upto = "up to " if settings.angles is None else ""
    text = (f"{_plural(len(trials), 'trial')}, {_plural(frames, 'frame')} in all: ≈ "
            + work.text("frames", f"{upto}{_plural(work.components, 'angle component')}", " per trial")
            + ("" if force else f"; trials unchanged since the last run on {Option.OUT} are reused"))  # fmt: skip
    return WorkEstimate(work.optimisations, "α-level optimisations", ABOUT, text,
                        {stage: f"≈ {work.optimisations:,} α-level optimisations"})  # fmt: skip
