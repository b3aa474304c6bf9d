"""The refinement runs of the allowable-error search
(:func:`~fuzzygait.markererror.allowable.allowable_errors`): rounds of Graph Follower runs,
one per component at the error scale its :class:`~fuzzygait.markererror.scale_search.ScaleSearch`
proposes (the components of a round side by side on the evaluator), each run's excursion
recorded in its search, until every search has converged or used its runs.

The runs of a round that are components of one angle share their model calls
(:func:`run_component_blocks`, as :func:`~fuzzygait.markererror.analysis.run_angle_task`
does for the bands): each component at its own α-level is one block of a
:class:`ScaledComponentsModel` whose parameters are deviations in unit balls, scaled per
block to that component's ball radii ``(1 − α)·Σ`` — the same optimisation as alone up
to the rounding of the scaling (the batched optimiser's steps, projections and random
points are equivariant under it), in a third of the model calls.  The per-source bands
(:mod:`fuzzygait.markererror.per_source`) group the sources of one component the same way.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np

from fuzzygait.core.names import angle_names
from fuzzygait.core.trial import Trial
from fuzzygait.io.subject import SubjectParameters
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.markererror.analysis import ComponentTask, FuzzyAngleOptions, component_tasks, run_component_task
from fuzzygait.markererror.angle_model import AXES, AngleComponentsModel
from fuzzygait.markererror.scale_search import ScaleSearch
from fuzzygait.markererror.undetermined import undetermined
from fuzzygait.uncertainty import FuzzyBalls, graph_follower
from fuzzygait.uncertainty.execution import Evaluator

Progress = Callable[[int, int], None]

#: Where the refinement runs stop a point: an iteration gaining less than this fraction of
#: the angle's largest |value| (about 6e-4° on a 60° angle; the bands' runs: 1e-7).  A
#: refinement run answers one number per component — the band's largest excursion over
#: the frames, against the tolerance, to the scale resolution of 0.1 mm — so the last
#: ten-thousandths of a degree of every bound buy nothing there.  Measured on walking.c3d
#: (``benchmarks/RESULTS.md``): the allowable errors the same within 9e-7 mm, the refined
#: levels' hulls within 0.004°, the refinement's model calls 776 → 511 and the whole
#: analysis 5 % less CPU (the slowest 1 % of the points kept a third of the calls going).
REFINEMENT_STOP = 1e-5


def component_setups(trial: Trial, subject: SubjectParameters, result: CGMResult, options: FuzzyAngleOptions,
                     components: Sequence[str],
                     clusters: ClusterCalibration | None) -> dict[str, ComponentTask]:  # fmt: skip
    """The Graph Follower task of each component (as fuzzy_joint_angles builds it)."""
    names = angle_names(components)
    tasks, _ = component_tasks(trial, subject, result, options, names, clusters)
    by_component = {f"{t.name}_{AXES[t.axis]}": t for t in tasks}
    return {c: by_component[c] for c in components}


Run = tuple[str, np.ndarray, np.ndarray, dict[str, int]]


@dataclass
class ScaledComponentsModel(AngleComponentsModel):
    """An :class:`AngleComponentsModel` whose block ``b``'s marker deviations (mm) are its
    parameters times ``factors[b]`` (``(blocks, n_p)``): unit balls become the balls of
    radius ``factors`` per marker, so blocks with different ball radii (α-levels, error
    sources) share the optimiser's calls."""

    factors: np.ndarray = field(default_factory=lambda: np.ones((1, 0)))

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        """The components (degrees) at ``nodes`` (k,) for unit-ball parameters ``P`` (k, n_p)."""
        block = np.asarray(nodes, dtype=int) // self.angle.frames.size
        return super().evaluate_nodes(P * self.factors[block], nodes)

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and exact gradients with respect to the unit-ball parameters (degrees per
        unit: the deviations' gradients times ``factors``)."""
        scale = self.factors[np.asarray(nodes, dtype=int) // self.angle.frames.size]
        values, gradients = super().evaluate_nodes_gradients(P * scale, nodes)
        return values, gradients * scale


class BlockJob(NamedTuple):
    """Components of one angle optimised side by side (:func:`run_component_blocks`): the
    tasks (one angle's, the same frames and markers; their options' optimiser settings are
    the first's), each one's ball radii scaled by ``shrink`` (``1 − α`` of its level, or 1),
    the α-levels ``levels`` (ascending, 1 included) of the scaled balls, and the optimiser's
    ``stop`` fraction (None: the options' strategy's)."""

    tasks: tuple[ComponentTask, ...]
    shrink: tuple[float, ...]
    levels: tuple[float, ...]
    stop: float | None = None


def run_component_blocks(job: BlockJob) -> list[Run]:
    """Per task, as :func:`~fuzzygait.markererror.analysis.run_component_task` gives it for
    the task's radii ``shrink``-scaled at ``levels``: ``(component name, hull (level, bound,
    n_valid) deg, deviation norms (level, bound, n_valid, n_markers) mm, work counts)``,
    all tasks in one α-level optimisation (the counts the first's, the others zero)."""
    first = job.tasks[0]
    options, markers = first.options, first.markers
    model = first.angle_model()
    factors = np.stack([np.repeat(np.asarray(t.radii, dtype=float) * s, 3) for t, s in zip(job.tasks, job.shrink,
                                                                                             strict=True)])  # fmt: skip
    node_model = ScaledComponentsModel(model, tuple(t.axis for t in job.tasks),
                                       np.stack([t.reference for t in job.tasks]), factors)  # fmt: skip
    params = FuzzyBalls(np.zeros((len(markers), 3)), np.ones(len(markers)), tuple(markers))
    strategy = options.strategy() if job.stop is None else replace(options.strategy(), stop=job.stop)
    result = graph_follower(node_model, params, job.levels, strategy=strategy)
    hull = result["hull"].to_numpy()  # (level, bound, blocks x frames)
    n_frames = first.frames.size
    extremiser = result["extremiser"].to_numpy().reshape(*hull.shape[:2], len(job.tasks), n_frames, len(markers), 3)
    seen = model.seen()
    counts = {key: int(result.attrs[key]) for key in ("forward_simulations", "node_evaluations", "node_gradients")}
    outputs: list[Run] = []
    for b, task in enumerate(job.tasks):
        norms = np.linalg.norm(extremiser[:, :, b] * factors[b].reshape(-1, 3), axis=-1)
        outputs.append((f"{task.name}_{AXES[task.axis]}", hull[..., b * n_frames : (b + 1) * n_frames],
                        np.where(seen, norms, np.nan), counts if b == 0 else dict.fromkeys(counts, 0)))  # fmt: skip
    return outputs


def map_blocks(jobs: Sequence[BlockJob], evaluator: Evaluator, progress: Progress | None = None) -> list[list[Run]]:
    """:func:`run_component_blocks` of every job on ``evaluator``; ``progress(done, n)`` in
    tasks (not jobs)."""
    sizes = np.cumsum([0] + [len(j.tasks) for j in jobs])

    def step(k: int, _n: int) -> None:
        if progress is not None:
            progress(int(sizes[k]), int(sizes[-1]))

    return evaluator.map(run_component_blocks, list(jobs), step)


def _evaluate(tasks: Sequence[ComponentTask], alphas: Sequence[float], evaluator: Evaluator,
              progress: Progress | None = None) -> list[Run]:  # fmt: skip
    """One Graph Follower run per component at its α-level (and 1): hull (2, bound, n_valid)
    deg, deviation norms (2, bound, n_valid, n_markers) mm, counts; ``progress(done, n)``
    as :meth:`~fuzzygait.uncertainty.execution.Evaluator.map` calls it.  The components of
    one angle (Cartesian deviations) run side by side (:func:`run_component_blocks`),
    stopping their points at :data:`REFINEMENT_STOP`."""
    if tasks and tasks[0].options.method != "cartesian":
        runs = [t._replace(options=replace(t.options, alphas=(float(a), 1.0)))
                for t, a in zip(tasks, alphas, strict=True)]  # fmt: skip
        return evaluator.map(run_component_task, runs, progress)
    groups: dict[str, list[int]] = {}
    for i, task in enumerate(tasks):
        groups.setdefault(task.name, []).append(i)
    jobs = [BlockJob(tuple(tasks[i] for i in group), tuple(1.0 - float(alphas[i]) for i in group), (0.0, 1.0),
                     REFINEMENT_STOP) for group in groups.values()]  # fmt: skip
    grouped = map_blocks(jobs, evaluator, progress)
    by_task = {i: run for group, runs in zip(groups.values(), grouped, strict=True)
               for i, run in zip(group, runs, strict=True)}  # fmt: skip
    return [by_task[i] for i in range(len(tasks))]


def _run_excursion(values: np.ndarray, setup: ComponentTask) -> float:
    """Excursion (deg) of one refinement run's hull ``(2, bound, n_valid)`` at its α-level."""
    lower, upper = values[0, 0], values[0, 1]
    if lower.size == 0:
        return math.nan
    if np.any(undetermined(lower, upper, setup.reference)):
        return math.inf
    return float(np.max(np.maximum(upper - setup.reference, setup.reference - lower)))


@dataclass
class Refinement:
    """What the refinement ran: each run's output by ``(component, α)``, the runs per
    component, the Graph Follower's node evaluations and the wall time (s)."""

    runs: dict[tuple[str, float], tuple]
    counts: dict[str, int]
    node_evaluations: int
    seconds: float


def refine(setups: dict[str, ComponentTask], searches: dict[str, ScaleSearch], runner: Evaluator,
           max_evaluations: int, progress: Progress | None) -> Refinement:  # fmt: skip
    """Run the searches of ``setups``' components (``max_evaluations`` runs each at most, a
    component without frames none); ``progress(done, expected)`` as for
    :func:`~fuzzygait.markererror.allowable.allowable_errors`, a last ``progress(n, n)``."""
    components = list(setups)
    runs: dict[tuple[str, float], tuple] = {}
    counts = {c: 0 for c in components}
    start, node_evaluations = time.perf_counter(), 0
    while True:
        pending = []
        for c in components:
            scale = searches[c].propose() if setups[c].frames.size and counts[c] < max_evaluations else None
            if scale is not None:
                pending.append((c, round(scale, 9)))
        if not pending:
            break
        done = sum(counts.values())
        expected = done + sum(min(max_evaluations - counts[c], searches[c].remaining())
                              for c in components if setups[c].frames.size)  # fmt: skip
        expected = max(expected, done + len(pending))

        def step(k: int, _n: int, done: int = done, expected: int = expected) -> None:
            if progress is not None:
                progress(done + k, expected)

        step(0, len(pending))
        outputs = _evaluate([setups[c] for c, _ in pending], [round(1.0 - s, 9) for _, s in pending], runner,
                            step)  # fmt: skip
        for (c, scale), output in zip(pending, outputs, strict=True):
            runs[(c, round(1.0 - scale, 9))] = output
            counts[c] += 1
            node_evaluations += output[3]["node_evaluations"]
            searches[c].record(scale, _run_excursion(output[1], setups[c]))
    seconds = time.perf_counter() - start
    if progress is not None:
        progress(sum(counts.values()), sum(counts.values()))
    return Refinement(runs, counts, node_evaluations, seconds)


@contextmanager
def evaluator_or_own(evaluator: Evaluator | None, workers: int) -> Iterator[Evaluator]:
    """``evaluator``, or else an evaluator of ``workers`` processes of its own, closed after use."""
    if evaluator is not None:
        yield evaluator
        return
    own = Evaluator(workers=max(1, int(workers)))
    try:
        yield own
    finally:
        own.close()
