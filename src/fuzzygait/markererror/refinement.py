"""The refinement runs of the allowable-error search
(:func:`~fuzzygait.markererror.allowable.allowable_errors`): rounds of Graph Follower runs,
one per component at the error scale its :class:`~fuzzygait.markererror.scale_search.ScaleSearch`
proposes (the components of a round side by side on the evaluator), each run's excursion
recorded in its search, until every search has converged or used its runs.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace

import numpy as np

from fuzzygait.core.names import angle_names
from fuzzygait.core.trial import Trial
from fuzzygait.io.subject import SubjectParameters
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.markererror.analysis import ComponentTask, FuzzyAngleOptions, component_tasks, run_component_task
from fuzzygait.markererror.angle_model import AXES, undetermined
from fuzzygait.markererror.scale_search import ScaleSearch
from fuzzygait.uncertainty.execution import Evaluator

Progress = Callable[[int, int], None]


def component_setups(trial: Trial, subject: SubjectParameters, result: CGMResult, options: FuzzyAngleOptions,
                     components: Sequence[str],
                     clusters: ClusterCalibration | None) -> dict[str, ComponentTask]:  # fmt: skip
    """The Graph Follower task of each component (as fuzzy_joint_angles builds it)."""
    names = angle_names(components)
    tasks, _ = component_tasks(trial, subject, result, options, names, clusters)
    by_component = {f"{t.name}_{AXES[t.axis]}": t for t in tasks}
    return {c: by_component[c] for c in components}


Run = tuple[str, np.ndarray, np.ndarray, dict[str, int]]


def _evaluate(tasks: Sequence[ComponentTask], alphas: Sequence[float], evaluator: Evaluator,
              progress: Progress | None = None) -> list[Run]:  # fmt: skip
    """One Graph Follower run per component at its α-level (and 1): hull (2, bound, n_valid)
    deg, deviation norms (2, bound, n_valid, n_markers) mm, counts; ``progress(done, n)``
    as :meth:`~fuzzygait.uncertainty.execution.Evaluator.map` calls it."""
    runs = [t._replace(options=replace(t.options, alphas=(float(a), 1.0))) for t, a in zip(tasks, alphas, strict=True)]
    return evaluator.map(run_component_task, runs, progress)


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
