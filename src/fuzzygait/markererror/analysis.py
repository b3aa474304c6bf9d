"""Fuzzy joint angles from fuzzy marker errors (thesis §3.7.3, §5.5).

For every joint-angle component, frame and α-level the largest and smallest angle over
all marker deviations inside the α-level balls is found by the Graph Follower algorithm
in direct mode (all frames side by side, see :mod:`fuzzygait.uncertainty.batched`).

Result layout (an ``xarray.Dataset``; read it through :mod:`fuzzygait.markererror.result`):
the fuzzy results (:mod:`fuzzygait.core.schema`) of every angle component stacked along
a ``component`` dimension, on the trial's frames:

* dims ``component`` (``LKneeAngles_X`` …; coordinates ``angle`` and ``axis`` along it),
  ``alpha`` (ascending, includes 1 = the measured angle), ``bound`` (``lower``,
  ``upper``), ``frame`` (1-based C3D frame numbers; coordinate ``time`` in s),
  ``marker``;
* ``hull (component, alpha, bound, frame)`` in degrees; NaN on frames where a needed
  marker is missing; where the band is undetermined by a bound beyond 90° the search of
  that bound stopped once it passed 91° (the models' ``excursion_limit``), so the value
  there only says "beyond", not how far;
* ``deviation (component, alpha, bound, frame, marker)``: Euclidean norm (mm) of each
  marker's deviation that produces the hull value (Fig. 5.12); NaN for markers the
  component does not use;
* ``undetermined (component, alpha, frame)``: True where the band is not a band — a
  bound more than 90° from the measured angle on its continuous branch (the segment frame
  can flip inside the ball, :func:`~fuzzygait.markererror.undetermined.undetermined`), or,
  for every component of an angle, its middle Cardan component's band within 15° of ±90°
  (the Cardan singularity; the middle band is closed at ±90° there,
  :func:`~fuzzygait.markererror.undetermined.gimbal_undetermined`);
* ``ball_radius (marker)``: α = 0 ball radius Σ (mm);
* coordinate ``error_source`` (its own dim): the error sources summed into the balls, in
  order (read with :func:`~fuzzygait.markererror.result.error_sources`);
* attributes: ``trial``, ``model`` (the model version), ``method``,
  ``starts``, ``output``, ``units``, ``strategy``, ``forward_simulations``,
  ``node_evaluations`` and ``node_gradients`` (exact gradient rows; in total), ``seconds``.

Hulls are taken of each angle on the continuous branch through the measured angle
(:class:`~fuzzygait.markererror.angle_model.JointAngleModel` ``reference``), so a band
that passes ±180° is one band, not a 360° one.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np
import pandas as pd
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import ALL_ANGLE_NAMES, CGMResult
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.markererror.angle_model import AXES, AngleComponentsModel, JointAngleModel, fixed_subject
from fuzzygait.markererror.result import (
    AngleAxes,
    fuzzy_angles_dataset,
    undetermined_flags,
    with_error_sources,
)
from fuzzygait.markererror.sources import SOURCES, ErrorModel, parse_sources
from fuzzygait.markererror.spherical import SphericalDeviationModel
from fuzzygait.markererror.undetermined import gimbal_undetermined, undetermined
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, FuzzyNumber, FuzzyVector, graph_follower
from fuzzygait.uncertainty.execution import Evaluator

DEFAULT_ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
METHODS = ("cartesian", "spherical")

Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class SearchOptions:
    """The marker-error analysis' search, shared by the fuzzy joint angles and the fuzzy
    kinetics (:class:`~fuzzygait.markererror.fuzzy_kinetics.FuzzyKineticsOptions`).

    Attributes:
        alphas: α-levels (1 is added).
        sources: error sources summed into each marker's radius (Table 3.1).
        error_model: segment values and per-marker overrides.
        starts: multistart points per frame and α-level (the deterministic deviations,
            then screened random ones; the levels then exchange their optima,
            :mod:`fuzzygait.uncertainty.gfa.levels`).
        iterations: optimiser iterations (model calls) per start at most.
        stride: frames between full multistart optimisations; the frames in between are
            followed from their neighbours' optima (the Graph Follower's warm starts,
            :class:`~fuzzygait.uncertainty.BatchedDirect`) with ``follow`` iterations.
        follow: optimiser iterations at the followed frames.
        seed: seed of the random starting points.
        solver: the batched Graph Follower's local solver (``"spectral"``, or
            ``"frank-wolfe"`` for comparison; :class:`~fuzzygait.uncertainty.BatchedDirect`).
    """

    alphas: Sequence[float] = DEFAULT_ALPHAS
    sources: Sequence[str] = SOURCES
    error_model: ErrorModel = field(default_factory=ErrorModel)
    starts: int = 5
    iterations: int = 40
    stride: int = 8
    follow: int = 8
    seed: int = 0
    solver: str = "spectral"

    def strategy(self) -> BatchedDirect:
        """The batched Graph Follower strategy of these settings."""
        return BatchedDirect(starts=self.starts, iterations=self.iterations, seed=self.seed, stride=self.stride,
                             follow=self.follow, solver=self.solver)  # fmt: skip


@dataclass(frozen=True)
class FuzzyAngleOptions(SearchOptions):
    """Options of the fuzzy joint-angle analysis: the search (:class:`SearchOptions`) and

    Attributes:
        method: ``"cartesian"`` (deviation vectors with the norm constraint) or
            ``"spherical"`` (radius and two angles per marker, box constraints).
        workers: processes for the angles (1: in this process), when no
            :class:`~fuzzygait.uncertainty.execution.Evaluator` is given.
        gradients: ``"auto"``: the optimiser takes the exact gradients of the angle with
            respect to the marker deviations (reverse-mode differentiation of the
            kinematic model); ``"differences"``: forward differences (``1 + n_p``
            evaluations per gradient; for comparison).
    """

    method: str = "cartesian"
    workers: int = 1
    gradients: str = "auto"

    def strategy(self) -> BatchedDirect:
        """The batched Graph Follower strategy of these settings (and gradient source)."""
        return replace(super().strategy(), gradients=self.gradients)


class ComponentTask(NamedTuple):
    """One angle component's α-level optimisation, as :func:`fuzzy_joint_angles` maps it.

    Attributes:
        trial, subject: the trial and the subject with its inter-ASIS distance fixed.
        progression: ``(3, 3)`` progression frame of the unperturbed trial.
        name, axis: the angle (``"LKneeAngles"``) and its component (0, 1, 2 = X, Y, Z).
        frames: 0-based samples where the angle is measured and computable.
        markers: the markers whose deviations are the parameters.
        radii: their α = 0 ball radii Σ, mm.
        options: the analysis options (its ``alphas`` ascending, 1 included).
        reference: the measured angle component at ``frames``, degrees.
        version: the model version; clusters: its static cluster calibration (cluster
            models).
    """

    trial: Trial
    subject: SubjectParameters
    progression: np.ndarray
    name: str
    axis: int
    frames: np.ndarray
    markers: list[str]
    radii: np.ndarray
    options: FuzzyAngleOptions
    reference: np.ndarray
    version: str
    clusters: ClusterCalibration | None

    def angle_model(self) -> JointAngleModel:
        """The model :func:`run_component_task` optimises (the angle component on the
        branch through the measured angle, parameters the deviations of ``markers``)."""
        return JointAngleModel(self.trial, self.subject, self.progression, self.name, self.axis, self.frames,
                               self.markers, reference=self.reference, model=self.version,
                               clusters=self.clusters)  # fmt: skip


def run_component_task(args: ComponentTask) -> tuple[str, np.ndarray, np.ndarray, dict[str, int]]:
    """Run one angle component's task: ``(component name, hull (alpha, bound, n_valid) in
    degrees, deviation norms (alpha, bound, n_valid, n_markers) in mm, work counts)``."""
    return run_angle_task([args])[0]


def run_angle_task(tasks: Sequence[ComponentTask]) -> list[tuple[str, np.ndarray, np.ndarray, dict[str, int]]]:
    """Run the tasks of components of one angle (the same frames, markers, radii and
    options) in one α-level optimisation of an :class:`AngleComponentsModel`: every model
    call serves all components (one pass of the kinematic model gives the three), and
    each component is optimised as it would be alone, with the same seed: the same hull
    up to the rounding of batched array operations (measured on both sample trials: the
    hulls bit-identical, the extremisers within 4e-15 mm).  Per task, as
    :func:`run_component_task`.  The work counts of the shared optimisation are the
    first task's (the others' are zero), so they add up over the tasks."""
    first = tasks[0]
    markers, radii, options = first.markers, first.radii, first.options
    if any(t.name != first.name or t.markers != markers or not np.array_equal(t.frames, first.frames)
           for t in tasks[1:]):  # fmt: skip
        raise ParameterError(f"the components optimised together must be of one angle; got "
                             f"{', '.join(f'{t.name}_{AXES[t.axis]}' for t in tasks)}")  # fmt: skip
    model = first.angle_model()
    node_model: JointAngleModel | AngleComponentsModel = model
    if len(tasks) > 1:
        node_model = AngleComponentsModel(model, tuple(t.axis for t in tasks), np.stack([t.reference for t in tasks]))
    if options.method == "cartesian":
        params: FuzzyBalls | FuzzyVector = FuzzyBalls(np.zeros((len(markers), 3)), radii, tuple(markers))
        fuzzy_model: JointAngleModel | AngleComponentsModel | SphericalDeviationModel = node_model
    else:
        numbers = []
        for label, radius in zip(markers, radii):
            numbers += [
                FuzzyNumber(np.array([0.0, 1.0]), np.array([0.0, 0.0]), np.array([radius, 0.0]), f"{label}_r"),
                FuzzyNumber(np.array([0.0, 1.0]), np.array([0.0, 0.0]), np.array([np.pi, np.pi]), f"{label}_theta"),
                FuzzyNumber(np.array([0.0, 1.0]), np.array([-np.pi, -np.pi]), np.array([np.pi, np.pi]), f"{label}_phi"),
            ]
        params, fuzzy_model = FuzzyVector(numbers), SphericalDeviationModel(node_model)
    result = graph_follower(fuzzy_model, params, options.alphas, strategy=options.strategy())
    hull = result["hull"].to_numpy()  # (alpha, bound, components x frames)
    extremiser = result["extremiser"].to_numpy().reshape(*hull.shape, len(markers), 3)
    if options.method == "spherical":
        norms = np.abs(extremiser[..., 0])
    else:
        norms = np.linalg.norm(extremiser, axis=-1)
    n_frames = first.frames.size
    seen = model.seen()  # a cluster marker missing at a frame (the pose from the others) has no deviation there
    counts = {key: int(result.attrs[key]) for key in ("forward_simulations", "node_evaluations", "node_gradients")}
    outputs = []
    for b, task in enumerate(tasks):
        block = slice(b * n_frames, (b + 1) * n_frames)
        outputs.append((f"{task.name}_{AXES[task.axis]}", hull[..., block], np.where(seen, norms[:, :, block], np.nan),
                        counts if b == 0 else dict.fromkeys(counts, 0)))  # fmt: skip
    return outputs


def angle_groups(tasks: Sequence[ComponentTask]) -> list[list[int]]:
    """Indices of ``tasks`` grouped by angle (the components :func:`run_angle_task` runs
    together), in first-use order."""
    groups: dict[str, list[int]] = {}
    for i, task in enumerate(tasks):
        groups.setdefault(task.name, []).append(i)
    return list(groups.values())


def fuzzy_joint_angles(
    trial: Trial,
    subject: SubjectParameters,
    result: CGMResult,
    options: FuzzyAngleOptions = FuzzyAngleOptions(),
    angles: Sequence[str] | None = None,
    progress: Progress | None = None,
    evaluator: Evaluator | None = None,
    clusters: ClusterCalibration | None = None,
) -> xr.Dataset:
    """Fuzzy joint angles of a trial (see the module docstring for the layout).

    The marker-error model is that of the version that computed ``result``
    (``result.model``, :class:`~fuzzygait.markererror.angle_model.JointAngleModel`): for
    ``cgm2.3`` / ``cgm2.4`` the cluster chain with the static calibration ``clusters``
    held fixed, perturbing the dynamic markers each angle is computed from.

    Args:
        trial: the pre-processed trial the angles were computed from.
        subject: the subject parameters used (static offsets included).
        result: the deterministic model output of ``trial``.
        options: α-levels, error sources, method, optimiser settings.
        angles: angle names (all three components) or single components
            (``"LKneeAngles_X"``) (default: every angle ``result`` holds, the CGM 2.4
            forefoot's included).
        progress: called as ``progress(done, total)`` per angle (its components are
            optimised together, :func:`run_angle_task`).
        evaluator: where the components are computed (default: serial, or a local pool
            of ``options.workers`` processes); the hulls are the same either way.
        clusters: the static cluster calibration ``result`` was computed with (cluster
            models only; :attr:`fuzzygait.workflows.angles.AnglesRun.clusters`).

    Raises:
        ParameterError: an unknown method, no requested angle computed, or a cluster
            model without ``clusters``.
    """
    if options.method not in METHODS:
        raise ParameterError(f"method must be one of {METHODS}; got {options.method!r}")
    sources = parse_sources(options.sources)
    names = [n for n in (angles or ALL_ANGLE_NAMES) if split_component(n)[0] in result.angles]
    if not names:
        raise ParameterError(f"{trial.name}: none of the requested angles could be computed")
    alphas = np.union1d(np.asarray(options.alphas, dtype=float), [1.0])
    options = FuzzyAngleOptions(**{**options.__dict__, "alphas": tuple(alphas)})
    tasks, markers_all = component_tasks(trial, subject, result, options, names, clusters)

    groups = angle_groups(tasks)
    jobs = [[tasks[i] for i in group] for group in groups]
    start = time.perf_counter()
    if evaluator is None:
        with Evaluator(workers=max(1, int(options.workers))) as own:
            grouped = own.map(run_angle_task, jobs, progress)
    else:
        grouped = evaluator.map(run_angle_task, jobs, progress)
    by_task = {i: output for group, results in zip(groups, grouped, strict=True)
               for i, output in zip(group, results, strict=True)}  # fmt: skip
    outputs = [by_task[i] for i in range(len(tasks))]
    fuzzy = _assemble(trial, tasks, outputs, markers_all, alphas, options, sources, time.perf_counter() - start)
    fuzzy.attrs["model"] = result.model
    return fuzzy


def split_component(requested: str) -> tuple[str, list[int]]:
    """``"LKneeAngles"`` -> ``("LKneeAngles", [0, 1, 2])``; ``"LKneeAngles_X"`` ->
    ``("LKneeAngles", [0])``.  A component analysed without its angle's middle Cardan
    component gets the 90° rule of the undetermined mask only, not the singularity rule
    (:func:`~fuzzygait.markererror.undetermined.gimbal_undetermined` needs the middle band)."""
    component = AngleComponent.maybe(requested)
    if component is not None:
        return component.angle, [component.axis.column]
    return requested, [0, 1, 2]


def component_tasks(
    trial: Trial,
    subject: SubjectParameters,
    result: CGMResult,
    options: FuzzyAngleOptions,
    names: Sequence[str],
    clusters: ClusterCalibration | None = None,
) -> tuple[list[ComponentTask], list[str]]:
    """The tasks :func:`fuzzy_joint_angles` maps (per angle in ``names``, X, Y, Z, or the
    single components named ``"LKneeAngles_X"``) and
    every marker they perturb, in first-use order.  ``options.alphas`` are used as given
    (ascending, 1 included)."""
    sources = parse_sources(options.sources)
    fixed = fixed_subject(trial, subject)
    tasks: list[ComponentTask] = []
    markers_all: list[str] = []
    wanted: dict[str, list[int]] = {}
    for requested in names:
        name, axes = split_component(requested)
        wanted.setdefault(name, [])
        wanted[name] += [a for a in axes if a not in wanted[name]]
    for name, axes in wanted.items():
        # frames where the angle is measured and the model computes it (a Plug-in Gait
        # angle needs every marker; a cluster pose three of its cluster's)
        every = np.arange(trial.n_frames)
        zero = JointAngleModel(trial, fixed, result.progression, name, 0, every, model=result.model,
                               clusters=clusters)  # fmt: skip
        model_markers = zero.markers
        computed = zero.measured_angles()
        usable = np.all(np.isfinite(result.angles[name]), axis=1) & np.all(np.isfinite(computed), axis=1)
        frames = np.flatnonzero(usable)
        radii = np.array([options.error_model.radius(m, sources) for m in model_markers])
        markers_all += [m for m in model_markers if m not in markers_all]
        for axis in sorted(axes):
            reference = result.angles[name][frames, axis]
            tasks.append(ComponentTask(trial, fixed, result.progression, name, axis, frames, model_markers, radii,
                                       options, reference, result.model, clusters))  # fmt: skip
    return tasks, markers_all


def _assemble(trial: Trial, tasks: list[ComponentTask], outputs: list[tuple], markers: list[str],
              alphas: np.ndarray, options: FuzzyAngleOptions, sources: Sequence[str],
              seconds: float) -> xr.Dataset:  # fmt: skip
    n_frames = trial.n_frames
    hulls: dict[str, np.ndarray] = {}
    deviations: dict[str, np.ndarray] = {}
    totals = {"forward_simulations": 0, "node_evaluations": 0, "node_gradients": 0}
    for task, (column, values, norms, counts) in zip(tasks, outputs, strict=True):
        frames, used = task.frames, task.markers
        hulls[column] = np.full((alphas.size, 2, n_frames), np.nan)
        hulls[column][:, :, frames] = values
        deviations[column] = np.full((alphas.size, 2, n_frames, len(markers)), np.nan)
        columns = np.asarray([markers.index(m) for m in used])
        deviations[column][:, :, frames[:, None], columns[None, :]] = norms
        for key in totals:
            totals[key] += counts[key]
    attrs = {"trial": trial.name, "method": options.method,
             "starts": options.starts, "iterations": options.iterations, "stride": options.stride,
             "follow": options.follow, "solver": options.solver, "gradients": options.gradients,
             "output": "joint angle", "strategy": BatchedDirect.name, **totals,
             "seconds": round(seconds, 3)}  # fmt: skip
    measured_index = int(np.argmin(np.abs(alphas - 1.0)))
    flags = {column: undetermined(hull[:, 0], hull[:, 1], hull[measured_index, 1][None, :])
             for column, hull in hulls.items()}  # fmt: skip
    gimbal_undetermined(hulls, flags, measured_index)
    axes = AngleAxes(alphas=alphas, frames=trial.frames, times=trial.times, markers=markers,
                     ball_radius=[options.error_model.radius(m, sources) for m in markers])  # fmt: skip
    return with_error_sources(fuzzy_angles_dataset(hulls, axes, deviations=deviations, attrs=attrs, undetermined=flags),
                              sources)  # fmt: skip


def undetermined_levels(fuzzy: xr.Dataset) -> pd.DataFrame:
    """Per angle component (rows) and α-level < 1 (columns): True when the band is
    undetermined at some frame (ΔΦ is then "undetermined", not a number)."""
    flags = undetermined_flags(fuzzy).any("frame")
    return _by_level(flags.sel(alpha=fuzzy["alpha"] < 1.0).transpose("component", "alpha"), bool)


def _by_level(table: xr.DataArray, kind: type) -> pd.DataFrame:
    """A ``(component, alpha)`` array as the tables' frame: rows the components
    (index "angle"), columns the α-levels as floats, highest first."""
    frame = pd.DataFrame(table.to_numpy().astype(kind), index=[str(c) for c in table["component"].to_numpy()],
                         columns=[float(a) for a in table["alpha"].to_numpy()])  # fmt: skip
    frame.index.name = "angle"
    return frame[sorted(frame.columns, reverse=True)]


def relative_envelope_width(fuzzy: xr.Dataset) -> pd.DataFrame:
    """ΔΦ of Eq. 5.3 in % per angle component (rows) and α-level < 1 (columns):
    ``max_t (upper − lower) / max_t |Φ(t)|`` with Φ the measured angle (α = 1), the
    maximum over the frames where the band is determined (:func:`undetermined_levels`
    says where an α-level is undetermined somewhere: report "undetermined" there).

    The thesis divides by the largest angle; the magnitude is used here so angles that
    stay negative get a positive reference.
    """
    hull = fuzzy["hull"]
    reference = abs(hull.sel(alpha=1.0, bound="upper")).max("frame")  # NaN frames skipped
    spread = (hull.sel(bound="upper") - hull.sel(bound="lower")).where(~undetermined_flags(fuzzy))
    width = spread.sel(alpha=fuzzy["alpha"] < 1.0).max("frame")
    with np.errstate(divide="ignore", invalid="ignore"):  # an angle zero throughout: inf (NaN if no width)
        return _by_level((100.0 * width / reference).transpose("component", "alpha"), float)

