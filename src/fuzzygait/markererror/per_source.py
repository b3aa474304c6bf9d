"""Per-source bands of the flexion angles (thesis §5.5, Fig. 5.9: "effect of the individual
uncertainty sources on the flexion angles"): the fuzzy joint angles with each error
source of Table 3.1 alone — measurement system, marker placement, soft-tissue artefact —
beside the band of all sources together, so a reader sees which one dominates.

:func:`per_source_bands` runs the Graph Follower tasks of
:func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles` (the same
:func:`~fuzzygait.markererror.analysis.component_tasks`, the same optimiser settings) once
per source, with ``FuzzyAngleOptions(sources=(s,))``, for the hip/knee/ankle flexion
components of an existing fuzzy result, on the same evaluator, and returns their bands as
a dataset of their own (:attr:`MarkerErrorResult.sources
<fuzzygait.markererror.result.MarkerErrorResult>`, the group ``sources`` of a saved
result). "All sources together" is the bands' own ``hull``.

Layout (the fuzzy-result schema of :mod:`fuzzygait.core.accessor`, stacked by source):

* dims ``source`` (``measurement``, ``placement``, ``sta``: the sources run alone),
  ``component`` (``LKneeAngles_X`` …: the flexion components analysed), ``alpha`` (the
  per-source α-levels, ascending, 1 included), ``bound``, ``frame`` (with ``time``) and
  ``marker`` as the bands';
* ``hull (source, component, alpha, bound, frame)`` deg: the band of the source alone
  (continuous branch through the measured angle, NaN where the angle is not computed);
* ``undetermined (source, component, alpha, frame)``: a bound more than 90° from the
  measured angle (as the bands' ``undetermined``);
* ``ball_radius (source, marker)`` mm: each marker's α = 0 radius with that source alone
  (a marker with a fixed total radius in the errors file keeps it for every source);
* attributes ``units`` (deg), ``seconds`` (wall time), ``runs``, ``forward_simulations``,
  ``node_evaluations`` and ``nesting_excess_deg``: how far (deg) a source's band reaches
  beyond the all-sources band at the same α on frames where both are determined (0 when
  nested, as the balls are: each source's ball lies inside the sum's; a positive value
  means the all-sources optimum is a local one there).

Cost: one Graph Follower run per source and flexion component at the per-source α-levels;
by default only the smallest α-level of the result (α = 0: what the figure and the table
show; every further level costs about as much again), i.e. 3 sources × 6 components × 1
level: measured +5.5-8 % wall time (+7.5-8 % node evaluations) on the default ``fuzzygait
uncertainty`` run of the sample trials, Plug-in Gait and CGM 2.4 (benchmarks/RESULTS.md,
"Per-source bands").
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.markererror.analysis import ComponentTask, FuzzyAngleOptions, component_tasks, run_component_task
from fuzzygait.markererror.refinement import BlockJob, Run, evaluator_or_own, map_blocks
from fuzzygait.markererror.result import (
    MarkerErrorResult,
    angle_components,
    component_hull,
    component_undetermined,
)
from fuzzygait.markererror.sources import SOURCE_TITLES, SOURCES, parse_sources
from fuzzygait.markererror.undetermined import undetermined
from fuzzygait.uncertainty.execution import Evaluator

__all__ = [
    "ALL",
    "FLEXION_COMPONENTS",
    "PerSourceRequest",
    "SourceWidths",
    "has_source_bands",
    "per_source_bands",
    "source_bands_dataset",
    "source_components",
    "source_hull",
    "source_names",
    "source_title",
    "source_undetermined",
    "widest_source_bands",
]

Progress = Callable[[int, int], None]

#: The components Fig. 5.9 shows: hip, knee and ankle flexion, left and right.
FLEXION_COMPONENTS = tuple(f"{side}{joint}Angles_X" for joint in ("Hip", "Knee", "Ankle") for side in "LR")
#: The name of "all sources together" (the bands' own ``hull``) in the accessors and tables.
ALL = "all"
#: α-levels closer to each other than this are the same level.
_SAME_ALPHA = 1e-9


# ---------------------------------------------------------------------------- dataset
def source_bands_dataset(
    fuzzy: xr.Dataset,
    hulls: Mapping[str, Mapping[str, np.ndarray]],
    alphas: Sequence[float] | np.ndarray,
    *,
    radii: Mapping[str, Sequence[float] | np.ndarray] | None = None,
    attrs: Mapping[str, object] | None = None,
) -> xr.Dataset:
    """The per-source bands as a dataset (layout in the module docstring).

    Args:
        fuzzy: the bands (all sources together): their frames, markers and hulls.
        hulls: source -> component -> hull ``(alpha, bound [lower, upper], frame)`` deg
            on the bands' frames; every source must have the same components.
        alphas: the α-levels of the hulls (ascending, 1 included: its upper bound is the
            measured angle, the reference of ``undetermined``).
        radii: source -> α = 0 ball radius (mm) per marker of ``fuzzy``; None: NaN.
        attrs: attributes to add (``units`` and ``nesting_excess_deg`` are set here).

    Raises:
        ParameterError: unknown sources, components the bands do not hold, shapes that
            do not fit, or α-levels without 1.
    """
    sources = list(hulls)
    if not sources or [s for s in sources if s not in SOURCES]:
        raise ParameterError(f"hulls: sources must be among {', '.join(SOURCES)}; got {sources}")
    components = list(hulls[sources[0]])
    if any(list(hulls[s]) != components for s in sources) or not components:
        raise ParameterError("hulls: every source needs the same (non-empty) list of components")
    missing = [c for c in components if c not in angle_components(fuzzy)]
    if missing:
        raise ParameterError(f"hulls: the fuzzy result has no components {missing}")
    levels = np.asarray(alphas, dtype=float)
    ones = np.flatnonzero(np.abs(levels - 1.0) <= _SAME_ALPHA)
    if ones.size != 1 or np.any(np.diff(levels) <= 0):
        raise ParameterError(f"alphas must be ascending and include 1; got {list(levels)}")
    shape = (levels.size, 2, fuzzy.sizes["frame"])
    stacked = np.stack([np.stack([np.asarray(hulls[s][c], dtype=float) for c in components]) for s in sources])
    if stacked.shape[2:] != shape:
        raise ParameterError(f"hulls: each must be (alpha, bound, frame) = {shape}; got {stacked.shape[2:]}")
    measured = stacked[:, :, ones[0], 1][:, :, None, :]
    flags = undetermined(stacked[:, :, :, 0], stacked[:, :, :, 1], measured)
    n_markers = fuzzy.sizes.get("marker", 0)
    radius = np.full((len(sources), n_markers), np.nan)
    for i, source in enumerate(sources):
        if radii is not None and source in radii:
            radius[i] = np.asarray(radii[source], dtype=float)
    data = {
        "hull": (("source", "component", "alpha", "bound", "frame"), stacked,
                 {"units": "deg", "long_name": "joint angle bounds of the α-level with one error source alone"}),
        "undetermined": (("source", "component", "alpha", "frame"), flags,
                         {"long_name": "band of the source alone undetermined: a bound more than 90 deg from "
                                       "the measured angle"}),
        "ball_radius": (("source", "marker"), radius,
                        {"units": "mm", "long_name": "marker error ball radius at α = 0 with the source alone"}),
    }  # fmt: skip
    coords: dict[str, tuple] = {name: (fuzzy[name].dims, fuzzy[name].to_numpy(), fuzzy[name].attrs)
              for name in ("bound", "frame", "time", "marker")}  # fmt: skip
    coords |= {"source": ("source", sources), "component": ("component", components), "alpha": ("alpha", levels)}
    out = xr.Dataset(data, coords=coords, attrs={**dict(attrs or {}), "units": "deg"})
    out.attrs["nesting_excess_deg"] = round(_nesting_excess(MarkerErrorResult(fuzzy, sources=out)), 6)
    return out


def has_source_bands(result: MarkerErrorResult | None) -> bool:
    """Whether ``result`` holds per-source bands (:func:`per_source_bands`)."""
    return result is not None and result.sources is not None


def _require(result: MarkerErrorResult) -> xr.Dataset:
    if result.sources is None:
        raise ParameterError(f"{result.bands.attrs.get('trial', 'the result')} has no per-source bands; compute "
                             f"them with per_source_bands (fuzzygait uncertainty {Option.PER_SOURCE})")  # fmt: skip
    return result.sources


def source_names(result: MarkerErrorResult) -> list[str]:
    """The sources run alone, e.g. ``["measurement", "placement", "sta"]``."""
    return [str(s) for s in _require(result)["source"].to_numpy()]


def source_components(result: MarkerErrorResult) -> list[str]:
    """The flexion components with per-source bands, in dataset order."""
    return [str(c) for c in _require(result)["component"].to_numpy()]


def _main_levels(fuzzy: xr.Dataset, component: str, alphas: np.ndarray) -> tuple[xr.DataArray, xr.DataArray]:
    """The all-sources hull and flags of ``component`` at ``alphas`` (dim ``alpha``)."""
    hull, flags = component_hull(fuzzy, component), component_undetermined(fuzzy, component)
    main = hull["alpha"].to_numpy().astype(float)
    index = []
    for alpha in alphas:
        near = np.flatnonzero(np.abs(main - alpha) <= _SAME_ALPHA)
        if near.size == 0:
            raise ParameterError(f"the fuzzy result has no α = {alpha:g} (its levels: "
                                 f"{', '.join(f'{a:g}' for a in main)})")  # fmt: skip
        index.append(int(near[0]))
    hull = hull.isel(alpha=index).assign_coords(alpha=alphas)
    flags = flags.isel(alpha=index).assign_coords(alpha=alphas)
    return hull, flags


def source_hull(result: MarkerErrorResult, source: str, component: str) -> xr.DataArray:
    """Band of ``component`` with ``source`` alone (or :data:`ALL`: the bands' own hull at
    the same levels), deg, dims ``(alpha, bound, frame)`` (the per-source α-levels)."""
    sources = _require(result)
    if source == ALL:
        return _main_levels(result.bands, component, sources["alpha"].to_numpy().astype(float))[0]
    return sources["hull"].sel(source=source, component=component, drop=True)


def source_undetermined(result: MarkerErrorResult, source: str, component: str) -> xr.DataArray:
    """Where the band of :func:`source_hull` is undetermined, dims ``(alpha, frame)``."""
    sources = _require(result)
    if source == ALL:
        return _main_levels(result.bands, component, sources["alpha"].to_numpy().astype(float))[1]
    return sources["undetermined"].sel(source=source, component=component, drop=True)


def _nesting_excess(result: MarkerErrorResult) -> float:
    """Largest distance (deg) a source's bound lies outside the all-sources band at the
    same α, over the frames where both are determined (0 when nested)."""
    sources = _require(result)
    components = source_components(result)
    levels = sources["alpha"].to_numpy().astype(float)
    main = [_main_levels(result.bands, component, levels) for component in components]
    outer = xr.concat([hull for hull, _ in main], "component").assign_coords(component=components)
    outer_flags = xr.concat([flags for _, flags in main], "component").assign_coords(component=components)
    inner, flags = sources["hull"], sources["undetermined"]  # dims (source, component, alpha, …)
    keep = ~(flags | outer_flags)
    beyond = xr.concat([inner.sel(bound="upper") - outer.sel(bound="upper"),
                        outer.sel(bound="lower") - inner.sel(bound="lower")], "side").where(keep)  # fmt: skip
    return max(0.0, float(beyond.max(skipna=True))) if bool(np.isfinite(beyond).any()) else 0.0


# ---------------------------------------------------------------------------- the runs
@dataclass(frozen=True)
class PerSourceRequest:
    """What :func:`per_source_bands` runs.

    Attributes:
        options: error model and optimiser settings of the bands; their ``sources`` are
            the ones run alone unless ``sources`` is given.
        sources: the sources to run alone (None: those of ``options``).
        components: flexion components (or any components of the bands); None:
            :data:`FLEXION_COMPONENTS` that the bands hold.
        alphas: α-levels below 1 of the per-source runs, each one of the bands' levels
            (None: the bands' smallest, α = 0 normally: what the report draws).
    """

    options: FuzzyAngleOptions = field(default_factory=FuzzyAngleOptions)
    sources: Sequence[str] | None = None
    components: Sequence[str] | None = None
    alphas: Sequence[float] | None = None

    def chosen(self, fuzzy: xr.Dataset) -> tuple[tuple[str, ...], list[str], np.ndarray]:
        """The sources, the components and the α-levels (1 included) to run on ``fuzzy``.

        Raises:
            ParameterError: a source or component ``fuzzy`` does not have (or no flexion
                component at all), or an α-level ``fuzzy`` does not have.
        """
        sources = parse_sources(self.options.sources if self.sources is None else self.sources)
        available = angle_components(fuzzy)
        if self.components is None:
            wanted = [c for c in FLEXION_COMPONENTS if c in available]
            if not wanted:
                raise ParameterError(f"{fuzzy.attrs.get('trial', 'the fuzzy result')} has no flexion component "
                                     f"({', '.join(FLEXION_COMPONENTS)}) to show per source")  # fmt: skip
        else:
            wanted = list(dict.fromkeys(self.components))
            missing = [c for c in wanted if c not in available]
            if missing or not wanted:
                raise ParameterError(f"components: the fuzzy result has no {missing or 'components'}; "
                                     f"it holds {', '.join(available)}")  # fmt: skip
        main_alphas = fuzzy["alpha"].to_numpy().astype(float)
        below = main_alphas[main_alphas < 1.0 - _SAME_ALPHA]
        if self.alphas is None:
            if below.size == 0:
                raise ParameterError("the fuzzy result has no α-level below 1 to show per source")
            return sources, wanted, np.array([float(below.min()), 1.0])
        levels = np.union1d(np.asarray(self.alphas, dtype=float), [1.0])
        absent = [a for a in levels if not np.any(np.abs(main_alphas - a) <= _SAME_ALPHA)]
        if absent:
            raise ParameterError(f"alphas: the fuzzy result has no α = {', '.join(f'{a:g}' for a in absent)} "
                                 f"(its levels: {', '.join(f'{a:g}' for a in main_alphas)})")  # fmt: skip
        return sources, wanted, levels


def per_source_bands(
    trial: Trial,
    subject: SubjectParameters,
    result: CGMResult,
    fuzzy: xr.Dataset,
    request: PerSourceRequest | None = None,
    *,
    evaluator: Evaluator | None = None,
    clusters: ClusterCalibration | None = None,
    progress: Progress | None = None,
) -> xr.Dataset:
    """The bands of each error source alone beside the bands ``fuzzy`` (all sources
    together), as a dataset of their own (:func:`source_bands_dataset`; layout in the
    module docstring).

    Args:
        trial, subject, result, clusters: as for
            :func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles` (those ``fuzzy``
            was computed from).
        fuzzy: the all-sources bands (computed with ``request.options``).
        request: the options, sources, components and α-levels
            (:class:`PerSourceRequest`; default ``PerSourceRequest()``).
        evaluator: where the Graph Follower runs (default: ``options.workers`` processes).
        progress: called as ``progress(done, total)`` over the runs (source × component),
            at least once per angle (its components and sources run side by side).

    Raises:
        ParameterError: as :meth:`PerSourceRequest.chosen`, or ``fuzzy`` of other frames
            than the trial's.
    """
    request = PerSourceRequest() if request is None else request
    options = request.options
    chosen, wanted, levels = request.chosen(fuzzy)
    frame_index = {int(f): i for i, f in enumerate(fuzzy["frame"].to_numpy())}
    sample_frames = np.array([frame_index.get(int(f), -1) for f in trial.frames])
    if np.any(sample_frames < 0) or len(frame_index) != trial.n_frames:
        raise ParameterError("fuzzy: its frames are not the trial's; compute it from the same trial")
    total = len(chosen) * len(wanted)
    hulls: dict[str, dict[str, np.ndarray]] = {source: {} for source in chosen}
    radii: dict[str, np.ndarray] = {}
    counts = {"forward_simulations": 0, "node_evaluations": 0}
    markers = [str(m) for m in fuzzy["marker"].to_numpy()]
    start = time.perf_counter()
    runs: list[tuple[str, ComponentTask]] = []
    for source in chosen:
        alone = replace(options, sources=(source,), alphas=tuple(float(a) for a in levels))
        runs += [(source, task) for task in component_tasks(trial, subject, result, alone, wanted, clusters)[0]]
        radii[source] = np.array([alone.error_model.radius(m, (source,)) for m in markers])
    with evaluator_or_own(evaluator, options.workers) as runner:
        outputs = _run_sources([task for _, task in runs], levels, runner, progress)
    for (source, task), (column, values, _norms, work) in zip(runs, outputs, strict=True):
        full = np.full((levels.size, 2, trial.n_frames), np.nan)
        full[:, :, sample_frames[task.frames]] = values
        hulls[source][column] = full
        for key in counts:
            counts[key] += int(work[key])
    attrs = {"seconds": round(time.perf_counter() - start, 3), "runs": total, **counts}
    return source_bands_dataset(fuzzy, hulls, levels, radii=radii, attrs=attrs)


def _run_sources(tasks: list[ComponentTask], levels: np.ndarray, runner: Evaluator,
                 progress: Progress | None) -> list[Run]:  # fmt: skip
    """Every task's run at ``levels``: the tasks of one angle (its components, each source's
    radii) side by side in one optimisation (:func:`~fuzzygait.markererror.refinement.run_component_blocks`,
    Cartesian deviations; the same hulls as one run each up to rounding); ``progress(done,
    total)`` in tasks."""
    if tasks[0].options.method != "cartesian":
        return runner.map(run_component_task, tasks, progress)
    groups: dict[str, list[int]] = {}
    for i, task in enumerate(tasks):
        groups.setdefault(task.name, []).append(i)
    jobs = [BlockJob(tuple(tasks[i] for i in group), (1.0,) * len(group), tuple(float(a) for a in levels))
            for group in groups.values()]  # fmt: skip
    grouped = map_blocks(jobs, runner, progress)
    by_task = {i: run for group, out in zip(groups.values(), grouped, strict=True)
               for i, run in zip(group, out, strict=True)}  # fmt: skip
    return [by_task[i] for i in range(len(tasks))]


# ---------------------------------------------------------------------------- the table
@dataclass(frozen=True)
class SourceWidths:
    """The widest band per source of a trial at one α-level (rows: components in dataset
    order; columns: the sources run alone, then :data:`ALL`).

    Attributes:
        alpha: the α-level.
        widths: widest ``upper − lower`` (deg) over the frames where that band is
            determined (NaN: no such frame).
        undetermined: frames where that band is undetermined.
        n_frames: frames with a band (the angle computed).
    """

    alpha: float
    widths: pd.DataFrame
    undetermined: pd.DataFrame
    n_frames: pd.Series

    @property
    def sources(self) -> list[str]:
        """The sources run alone (columns without :data:`ALL`)."""
        return [str(c) for c in self.widths.columns if c != ALL]

    def width(self, component: str, source: str) -> float:
        """Widest determined band (deg) of ``component`` with ``source`` (NaN: none)."""
        return float(self.widths[source].to_numpy(dtype=float)[self.widths.index.get_loc(component)])

    def frames_undetermined(self, component: str, source: str) -> int:
        """Frames where the band of ``component`` with ``source`` is undetermined."""
        return int(self.undetermined[source].to_numpy(dtype=int)[self.undetermined.index.get_loc(component)])

    def dominant(self, component: str) -> str | None:
        """The source alone with the widest band of ``component`` — a band undetermined
        somewhere counts as the widest (its frame can flip; most such frames first) — or
        None when no source has a band."""
        flipped = [s for s in self.sources if self.frames_undetermined(component, s) > 0]
        if flipped:
            return max(flipped, key=lambda s: (self.frames_undetermined(component, s), self.width(component, s)))
        finite = [s for s in self.sources if math.isfinite(self.width(component, s))]
        return max(finite, key=lambda s: self.width(component, s)) if finite else None


def widest_source_bands(result: MarkerErrorResult, alpha: float | None = None) -> SourceWidths:
    """Widest band per source alone and all together (:class:`SourceWidths`) at ``alpha``
    (default: the smallest per-source level, α = 0 normally)."""
    levels = _require(result)["alpha"].to_numpy().astype(float)
    level = float(levels.min()) if alpha is None else float(alpha)
    if not np.any(np.abs(levels - level) <= _SAME_ALPHA):
        listed = ", ".join(f"{a:g}" for a in levels)
        raise ParameterError(f"alpha: no per-source band at α = {level:g} (levels {listed})")
    at = int(np.argmin(np.abs(levels - level)))
    columns = [*source_names(result), ALL]
    components = source_components(result)
    widths = pd.DataFrame(np.nan, index=components, columns=columns)
    flags = pd.DataFrame(0, index=components, columns=columns)
    n_frames = pd.Series(0, index=components)
    for component in components:
        for source in columns:
            hull = source_hull(result, source, component).isel(alpha=at)
            mask = source_undetermined(result, source, component).isel(alpha=at).to_numpy()
            width = (hull.sel(bound="upper") - hull.sel(bound="lower")).to_numpy().astype(float)
            finite = np.isfinite(width)
            good = finite & ~mask
            widths.at[component, source] = float(width[good].max()) if good.any() else math.nan
            flags.at[component, source] = int((mask & finite).sum())
            if source == ALL:
                n_frames[component] = int(finite.sum())
    widths.index.name = flags.index.name = n_frames.index.name = "component"
    return SourceWidths(level, widths, flags, n_frames)


def source_title(source: str) -> str:
    """``"sta"`` -> ``"soft-tissue artefact"``; :data:`ALL` -> ``"all sources together"``."""
    return "all sources together" if source == ALL else SOURCE_TITLES.get(source, source)
