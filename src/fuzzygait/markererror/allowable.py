"""Allowable marker error — the inverse question of thesis §5.5.2: how small must the
marker errors be for an angle component to be known within a tolerance?

The fuzzy joint-angle band at level α is the Graph Follower hull for balls of radius
``(1 − α)·Σ_i`` around every marker ``i`` (Σ_i: the marker's cumulative error, Table 3.1
with the selected sources, :mod:`fuzzygait.markererror.sources`). So the **error scale**
``s = 1 − α`` is a fraction of Table 3.1, the same for every marker, and ``s·Σ_segment``
(mm) is how far every marker of that segment may be from where it was measured.

The band of a component is **within the tolerance τ** (degrees) at scale ``s`` when, over
the frames of the trial where the angle exists, neither bound is further than τ from the
measured angle and the band is determined (:func:`band_excursion`):
``max_t max(upper(t) − Φ(t), Φ(t) − lower(t)) ≤ τ``. The **allowable scale** is the
largest ``s`` for which it is.

The balls are nested in ``s``, so the true excursion grows monotonically with ``s``; the
search (:func:`allowable_errors`) brackets the allowable scale between the dataset's
α-levels (``s = 0`` always passes), then refines the bracket on α for each component
alone — interpolation of the excursion (quadratic through the nearest evaluated levels,
else the chord), with a bisection step whenever the bracket has not halved in two steps
— until the bracket is narrower than ``resolution`` mm on the component's largest ball.
The hulls of each component are made nested over all its levels (an optimum over a ball
cannot be worse than over a smaller one; the Graph Follower's are local optima, so this
only widens them).

Layout of the refinement (:attr:`MarkerErrorResult.allowable
<fuzzygait.markererror.result.MarkerErrorResult>`, the group ``allowable`` of a saved
result), over the bands' ``component``, ``bound``, ``frame`` (with ``time``) and
``marker`` and a dimension ``refinement`` (each component's evaluated levels, ascending,
NaN-padded: every component refines at its own levels, so a shared α axis would be
mostly NaN; :func:`refined_levels` merges one component's levels with the bands along
``alpha``):

* ``alpha (component, refinement)``: the α-level evaluated; ``hull (component, refinement,
  bound, frame)`` deg; ``undetermined (component, refinement, frame)``; ``deviation
  (component, refinement, bound, frame, marker)`` mm (when the bands have one);
* the outcome per component (NaN / "" where not analysed): ``scale`` (fraction of Σ),
  ``mm`` (on the component's largest ball), ``failing_scale``, ``excursion`` deg,
  ``evaluations``, ``status`` (:data:`STATUSES`) and ``segment_radius (component,
  segment)`` mm (the largest Σ of the segment's markers the component uses);
* attributes ``tolerance_deg``, ``resolution_mm``, ``source`` (what Σ is), ``seconds``
  (refinement wall time), ``runs`` and ``node_evaluations``.

Cost: each refinement step is one Graph Follower run of one component at one α-level
(the components of a step side by side on the evaluator); near α = 1 the balls are small
and the runs cheap.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import angle_of
from fuzzygait.core.trial import Trial
from fuzzygait.io.subject import SubjectParameters
from fuzzygait.kinematics import CGMResult
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.kinematics.labels import component_label
from fuzzygait.markererror.analysis import (
    ComponentTask,
    FuzzyAngleOptions,
    fuzzy_joint_angles,
)
from fuzzygait.markererror.angle_model import AXES
from fuzzygait.markererror.refinement import Progress, component_setups, evaluator_or_own, refine
from fuzzygait.markererror.result import (
    MarkerErrorResult,
    angle_components,
    component_hull,
    component_undetermined,
    error_sources,
)
from fuzzygait.markererror.scale_search import ScaleSearch
from fuzzygait.markererror.sources import SOURCES, TABLE_3_1, marker_segment, parse_sources
from fuzzygait.markererror.undetermined import undetermined
from fuzzygait.uncertainty.execution import Evaluator
from fuzzygait.uncertainty.postprocess import repair_nesting

#: Default tolerance (degrees, either side of the measured angle).
DEFAULT_TOLERANCE = 2.5
#: Default resolution (mm on the component's largest ball radius) of the allowable error.
DEFAULT_RESOLUTION = 0.1
#: Refinement runs per component at most.
MAX_EVALUATIONS = 12
#: Segments in the table's per-segment columns (Table 3.1 order).
SEGMENTS = tuple(TABLE_3_1)

# ---------------------------------------------------------------------------- excursion
def band_excursion(fuzzy: MarkerErrorResult | xr.Dataset, component: str) -> pd.Series:
    """Largest distance (degrees) of the band of ``component`` from the measured angle over
    the trial, per α-level (index, ascending; refined levels included,
    :func:`refined_levels`; ``fuzzy``: a result or its bands alone):
    ``max_t max(upper − Φ, Φ − lower)``.

    ``inf`` where the band is undetermined at some frame (the segment frame can flip: no
    tolerance holds); NaN where the level was not evaluated for this component (or the
    angle has no frame). α = 1 gives 0.
    """
    levels = refined_levels(fuzzy, component)
    hull = levels["hull"]
    measured = hull.sel(alpha=1.0, bound="upper")
    sides = xr.concat([hull.sel(bound="upper") - measured, measured - hull.sel(bound="lower")], "side")
    largest = sides.max(["side", "frame"], skipna=True).to_numpy().astype(float)
    largest[levels["undetermined"].any("frame").to_numpy()] = np.inf
    return pd.Series(largest, index=hull["alpha"].to_numpy().astype(float), name=component)

# ---------------------------------------------------------------------------- dataset
def _merge(fuzzy: xr.Dataset, runs: dict[tuple[str, float], tuple],
           setups: dict[str, ComponentTask]) -> tuple[xr.Dataset, xr.Dataset]:  # fmt: skip
    """The bands with each component's hulls nested over all its levels (plain and
    refined) and undetermined updated, and the refinement's levels as a dataset of their
    own (layout in the module docstring; the outcome is added by :func:`_store`)."""
    alphas = fuzzy["alpha"].to_numpy().astype(float)
    components = angle_components(fuzzy)
    markers = [str(m) for m in fuzzy["marker"].to_numpy()]
    levels = {c: sorted(a for (name, a) in runs if name == c) for c in components}
    n_levels = max([len(v) for v in levels.values()] + [0])
    n_c, n_f = len(components), fuzzy.sizes["frame"]
    hull, flags = fuzzy["hull"].to_numpy().copy(), fuzzy["undetermined"].to_numpy().astype(bool).copy()
    refined_alpha = np.full((n_c, n_levels), np.nan)
    refined_hull = np.full((n_c, n_levels, 2, n_f), np.nan)
    refined_flags = np.zeros((n_c, n_levels, n_f), dtype=bool)
    has_deviation = "deviation" in fuzzy.data_vars
    refined_deviation = np.full((n_c, n_levels, 2, n_f, len(markers)), np.nan) if has_deviation else None
    measured_index = int(np.argmin(np.abs(alphas - 1.0)))
    for c, component in enumerate(components):
        setup = setups.get(component)
        for k, alpha in enumerate(levels[component]):
            assert setup is not None
            _, values, norms, _ = runs[(component, alpha)]
            refined_alpha[c, k] = alpha
            refined_hull[c, k][:, setup.frames] = values[0]
            if refined_deviation is not None:
                columns = np.asarray([markers.index(m) for m in setup.markers])
                refined_deviation[c, k][:, setup.frames[:, None], columns[None, :]] = norms[0]
        if not levels[component]:
            continue
        # nesting over plain + refined levels, in ascending α
        every = np.concatenate([alphas, refined_alpha[c, : len(levels[component])]])
        order = np.argsort(every, kind="stable")
        stacked = np.concatenate([hull[c], refined_hull[c, : len(levels[component])]])[order]
        finite = np.isfinite(stacked).any(axis=(1, 2))
        stacked[finite] = repair_nesting(stacked[finite])
        measured = hull[c, measured_index, 1][None, :]
        unsorted = np.empty_like(stacked)
        unsorted[order] = stacked
        hull[c], refined_hull[c, : len(levels[component])] = unsorted[: alphas.size], unsorted[alphas.size :]
        flags[c] |= undetermined(hull[c, :, 0], hull[c, :, 1], measured)
        refined_flags[c] = undetermined(refined_hull[c, :, 0], refined_hull[c, :, 1], measured)
    bands = fuzzy.copy()
    bands["hull"] = fuzzy["hull"].copy(data=hull)
    bands["undetermined"] = fuzzy["undetermined"].copy(data=flags)
    data: dict[str, tuple] = {
        "alpha": (("component", "refinement"), refined_alpha,
                  {"units": "1", "long_name": "α-level evaluated by the allowable-error refinement"}),
        "hull": (("component", "refinement", "bound", "frame"), refined_hull,
                 {"units": "deg", "long_name": "joint angle bounds at the refined α-level"}),
        "undetermined": (("component", "refinement", "frame"), refined_flags,
                         {"long_name": "band undetermined at the refined α-level"}),
    }  # fmt: skip
    if refined_deviation is not None:
        data["deviation"] = (("component", "refinement", "bound", "frame", "marker"), refined_deviation,
                             {"units": "mm", "long_name": "marker deviation norm at the bound"})  # fmt: skip
    coords = {name: (fuzzy[name].dims, fuzzy[name].to_numpy(), fuzzy[name].attrs)
              for name in ("component", "bound", "frame", "time", "marker")}  # fmt: skip
    return bands, xr.Dataset(data, coords=coords)


def refined_components(result: MarkerErrorResult) -> list[str]:
    """The components the refinement analysed (a ``status``), in dataset order; [] without one."""
    if result.allowable is None:
        return []
    return [str(c) for c, status in zip(result.allowable["component"].to_numpy(),
                                        result.allowable["status"].to_numpy(), strict=True) if str(status)]  # fmt: skip


def refined_levels(fuzzy: MarkerErrorResult | xr.Dataset, component: str) -> xr.Dataset:
    """One component's plain and refined α-levels merged along ``alpha`` (ascending):
    ``hull (alpha, bound, frame)`` deg, ``undetermined (alpha, frame)`` and the coordinate
    ``refined (alpha)``; the plain levels only for bands (or a result) without refinement."""
    result = fuzzy if isinstance(fuzzy, MarkerErrorResult) else MarkerErrorResult(fuzzy)
    hull = component_hull(result.bands, component)
    flags = component_undetermined(result.bands, component)
    plain = xr.Dataset({"hull": hull, "undetermined": flags}).assign_coords(
        refined=("alpha", np.zeros(hull.sizes["alpha"], dtype=bool))
    )
    if result.allowable is None:
        return plain
    levels = result.allowable.sel(component=component, drop=True)
    alphas = levels["alpha"].to_numpy()
    keep = np.flatnonzero(np.isfinite(alphas))
    extra = (
        xr.Dataset(
            {
                "hull": levels["hull"].isel(refinement=keep),
                "undetermined": levels["undetermined"].isel(refinement=keep),
            }
        )
        .rename({"refinement": "alpha"})
        .assign_coords(alpha=alphas[keep], refined=("alpha", np.ones(keep.size, bool)))
    )
    return xr.concat([plain, extra], "alpha").sortby("alpha")  # fmt: skip


# ---------------------------------------------------------------------------- the table
def _segment_radii(markers: Sequence[str], radii: Sequence[float] | np.ndarray) -> dict[str, float]:
    """Largest Σ (mm) per segment of Table 3.1 (a marker without a segment counts as its own)."""
    out: dict[str, float] = {}
    for marker, radius in zip(markers, radii, strict=True):
        try:
            segment = marker_segment(marker)
        except ParameterError:
            segment = marker
        out[segment] = max(out.get(segment, 0.0), float(radius))
    return out


def allowable_sentence(label: str, tolerance: float, scale: float, segments: dict[str, float], source: str,
                       full_passes: bool, smallest_fails: bool, failing: float) -> str:  # fmt: skip
    """One sentence for the report, e.g. "Left knee, sagittal (+ flexion): known within
    ±2.5° if every marker stays within 2.3 mm of where it was measured (7 % of Table 3.1:
    pelvis 2.3, thigh 2.3, shank 2.2, ankle 1.4 mm)."

    Args:
        label: the component's label (:func:`~fuzzygait.kinematics.labels.component_label`).
        tolerance: degrees.
        scale: the allowable scale (fraction of Σ); NaN: the angle has no frame.
        segments: the largest Σ (mm) per segment the component uses.
        source: what Σ is (``"Table 3.1"``, an errors file, the sources).
        full_passes: α = 0 is within the tolerance.
        smallest_fails: no scale tried is; ``failing`` is the smallest tried (fraction).
    """
    if not segments or not math.isfinite(scale):
        return f"{label}: no frame with every marker it needs."
    largest = max(segments.values())
    if full_passes:
        return (f"{label}: known within ±{tolerance:g}° even with the full errors of {source} "
                f"(every marker within {largest:.0f} mm); larger errors were not tried.")  # fmt: skip
    if smallest_fails:
        return (f"{label}: not known within ±{tolerance:g}° even if every marker stays within "
                f"{failing * largest:.2f} mm of where it was measured (the smallest error tried).")  # fmt: skip
    parts = ", ".join(f"{name} {scale * mm:.1f}" for name, mm in segments.items())
    return (f"{label}: known within ±{tolerance:g}° if every marker stays within {scale * largest:.1f} mm "
            f"of where it was measured ({100 * scale:.0f} % of {source}: {parts} mm).")  # fmt: skip


#: ``status`` values: bracketed, α = 0 passes, no scale tried passes, no frame.
STATUSES = ("within", "full table passes", "smallest fails", "no data")


def _store(merged: xr.Dataset, searches: dict[str, ScaleSearch], setups: dict[str, ComponentTask],
           counts: dict[str, int]) -> xr.Dataset:  # fmt: skip
    """The refinement's levels ``merged`` with each search's outcome added as ``(component)``
    variables and the segments' Σ as ``segment_radius (component, segment)`` (NaN / ""
    for components not analysed)."""
    every = [str(c) for c in merged["component"].to_numpy()]
    radii = {c: _segment_radii(setups[c].markers, setups[c].radii) for c in searches}
    segments = list(SEGMENTS) + sorted({k for r in radii.values() for k in r} - set(SEGMENTS))
    n = len(every)
    scale, failing, excursion = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    status, evaluations = np.full(n, "", dtype=object), np.zeros(n, dtype=int)
    radius = np.full((n, len(segments)), np.nan)
    for i, c in enumerate(every):
        if c not in searches:
            continue
        lo, hi = searches[c].bracket()
        failing[i], evaluations[i] = (np.nan if hi is None else hi), counts[c]
        if setups[c].frames.size == 0:
            status[i] = "no data"
        else:
            status[i] = "full table passes" if hi is None else "smallest fails" if lo == 0.0 else "within"
            scale[i], excursion[i] = lo, searches[c].excursions()[lo]
        for segment, value in radii[c].items():
            radius[i, segments.index(segment)] = value
    largest = np.nanmax(np.where(np.isnan(radius), 0.0, radius), axis=1)
    variables = {
        "scale": (scale, "1", "allowable error scale (fraction of Σ)"),
        "mm": (scale * largest, "mm", "allowable error on the component's largest ball"),
        "failing_scale": (failing, "1", "smallest error scale found outside the tolerance"),
        "excursion": (excursion, "deg", "largest distance of the band from the measured angle there"),
        "evaluations": (evaluations, "1", "refinement runs"),
        "status": (status.astype(str), "", "one of " + ", ".join(STATUSES)),
    }
    for name, (values, units, long_name) in variables.items():
        merged[name] = (("component",), values, {"long_name": long_name, **({"units": units} if units else {})})
    merged["segment_radius"] = (
        ("component", "segment"),
        radius,
        {"units": "mm", "long_name": "largest Σ of the segment's markers the component uses"},
    )
    return merged.assign_coords(segment=segments)  # fmt: skip


def allowable_table(result: MarkerErrorResult) -> pd.DataFrame:
    """The allowable-error table of a refined result (the one :func:`allowable_errors`
    returns, also after saving and reading it); columns described there."""
    refinement = result.allowable
    if refinement is None:
        raise ParameterError(f"{result.bands.attrs.get('trial', 'the result')} has no allowable-error refinement; "
                             "compute it with allowable_errors")  # fmt: skip
    tolerance, source = float(refinement.attrs["tolerance_deg"]), str(refinement.attrs["source"])
    step_mm = float(refinement.attrs["resolution_mm"])
    rows = {}
    for c in refined_components(result):
        status = str(refinement["status"].sel(component=c).item())
        value = {k: float(refinement[k].sel(component=c)) for k in ("scale", "mm", "failing_scale", "excursion")}
        value["alpha"] = 1.0 - value["scale"]
        radii = refinement["segment_radius"].sel(component=c)
        pairs = zip(radii["segment"].to_numpy(), radii.to_numpy().astype(float))
        segments = {str(k): float(v) for k, v in pairs if np.isfinite(v)}
        label = component_label(c)
        full, smallest = status == "full table passes", status == "smallest fails"
        row: dict[str, object] = {
            "label": label, "tolerance_deg": tolerance, "allowable_scale": value["scale"],
            "allowable_mm": value["mm"], "alpha": value["alpha"], "excursion_deg": value["excursion"],
            "failing_scale": value["failing_scale"], "full_table_passes": full, "smallest_fails": smallest,
            "evaluations": int(refinement["evaluations"].sel(component=c)),
        }  # fmt: skip
        for segment in SEGMENTS:
            row[f"{segment}_mm"] = value["scale"] * segments[segment] if segment in segments else math.nan
        row["text"] = allowable_sentence(label, tolerance, value["scale"], segments, source, full, smallest,
                                         value["failing_scale"])  # fmt: skip
        rows[c] = row
    table = pd.DataFrame.from_dict(rows, orient="index")
    table.index.name = "component"
    table.attrs.update({"tolerance_deg": tolerance, "resolution_mm": step_mm, "source": source})
    return table


def _components(fuzzy: xr.Dataset, angles: Sequence[str] | None) -> list[str]:
    available = angle_components(fuzzy)
    if angles is None:
        return available
    wanted = [c for a in angles for c in ([a] if "_" in a else [f"{a}_{x}" for x in AXES])]
    missing = [c for c in wanted if c not in available]
    if missing:
        raise ParameterError(f"the fuzzy result has no components {missing}; it holds {available}")
    return list(dict.fromkeys(wanted))


def _check_consistent(fuzzy: xr.Dataset, options: FuzzyAngleOptions, sources: Sequence[str]) -> None:
    used = error_sources(fuzzy)
    if used != tuple(sources):
        raise ParameterError(f"the fuzzy result used sources {', '.join(used) or 'none named'}, the options "
                             f"{', '.join(sources)}: refine it with the options it was computed with")  # fmt: skip
    for marker, radius in zip(fuzzy["marker"].to_numpy(), fuzzy["ball_radius"].to_numpy(), strict=True):
        if not math.isclose(options.error_model.radius(str(marker), sources), float(radius), abs_tol=1e-9):
            raise ParameterError(f"the fuzzy result's ball radius of {marker} ({radius} mm) is not the error "
                                 f"model's: refine it with the error model it was computed with")  # fmt: skip


@dataclass(frozen=True)
class AllowableRequest:
    """What :func:`allowable_errors` refines and how.

    Attributes:
        options: α-levels of the plain run (the starting bracket), error sources and model,
            optimiser settings, workers.
        tolerance: τ in degrees (> 0), either side of the measured angle.
        angles: angle names (``"LKneeAngles"``: its three components) or components
            (``"LKneeAngles_X"``); None: every component of the fuzzy result.
        resolution: mm (> 0); the search stops when the allowable error of the component's
            largest ball is bracketed this closely.
        max_evaluations: refinement runs per component at most (≥ 1).
    """

    options: FuzzyAngleOptions = field(default_factory=FuzzyAngleOptions)
    tolerance: float = DEFAULT_TOLERANCE
    angles: Sequence[str] | None = None
    resolution: float = DEFAULT_RESOLUTION
    max_evaluations: int = MAX_EVALUATIONS

    def __post_init__(self) -> None:
        if not isinstance(self.options, FuzzyAngleOptions):
            raise ParameterError(f"options must be FuzzyAngleOptions; got {type(self.options).__name__}")
        if not self.tolerance > 0:
            raise ParameterError(f"tolerance must be > 0 degrees; got {self.tolerance}")
        if isinstance(self.angles, str):
            raise ParameterError(f"angles must be a sequence of names, not the string {self.angles!r}")
        if not self.resolution > 0:
            raise ParameterError(f"resolution must be > 0 mm; got {self.resolution}")
        if isinstance(self.max_evaluations, bool) or not isinstance(self.max_evaluations, int) \
                or self.max_evaluations < 1:
            raise ParameterError(f"max_evaluations must be a whole number >= 1; got {self.max_evaluations!r}")


def _start_searches(fuzzy: xr.Dataset, setups: dict[str, ComponentTask], tolerance: float,
                    resolution: float) -> dict[str, ScaleSearch]:  # fmt: skip
    """Each component's search for its allowable scale, started from the excursions of the
    plain run's α-levels; its resolution is ``resolution`` mm on the component's largest ball."""
    searches = {}
    for c, setup in setups.items():
        largest = max(setup.radii, default=0.0)
        excursion = band_excursion(fuzzy, c)
        points = {
            round(1.0 - float(a), 9): float(e)  # type: ignore[arg-type]
            for a, e in excursion.items()
            if not np.isnan(e)
        }
        searches[c] = ScaleSearch(tolerance, resolution / largest if largest > 0 else 1.0, points)
    return searches


def allowable_errors(
    trial: Trial,
    subject: SubjectParameters,
    result: CGMResult,
    request: AllowableRequest = AllowableRequest(),
    *,
    fuzzy: xr.Dataset | None = None,
    evaluator: Evaluator | None = None,
    clusters: ClusterCalibration | None = None,
    progress: Progress | None = None,
) -> tuple[pd.DataFrame, MarkerErrorResult]:
    """The largest marker error for which each angle component stays within ``request.tolerance``.

    Args:
        trial, subject, result: as for :func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles`.
        request: the plain run's options, the tolerance, the angles, the resolution and the
            runs per component at most (:class:`AllowableRequest`).
        fuzzy: the plain run's dataset (computed with ``request.options``); None: computed here.
        evaluator: where the Graph Follower runs (default: ``request.options.workers`` processes).
        clusters: the static cluster calibration (cluster models, as for
            :func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles`).
        progress: called as ``progress(done, total)`` over the refinement runs (at least
            once per round of runs); ``total`` is the runs done plus those still expected
            (:meth:`ScaleSearch.remaining`, at most ``request.max_evaluations`` per component), so
            it can shrink as the searches converge; a last ``progress(n, n)`` at the end.

    Returns:
        ``(table, result)``. ``table`` has one row per component (index ``component``):
        ``label``; ``tolerance_deg``; ``allowable_scale`` (fraction of Σ, Table 3.1 with
        the selected sources: the largest scale found within the tolerance, 0 if none);
        ``allowable_mm`` (that scale on the component's largest Σ, mm); ``alpha``
        (``1 − scale``); ``excursion_deg`` (the band's largest distance from the measured
        angle there); ``failing_scale`` (smallest scale found outside the tolerance, NaN if
        none); ``full_table_passes`` (even α = 0 is within the tolerance: the allowable
        error is at least Table 3.1's); ``smallest_fails`` (even the smallest scale tried
        fails); ``evaluations`` (refinement runs); ``<segment>_mm`` (the allowable error of
        each segment the component uses, NaN otherwise); ``text`` (a sentence for the
        report). ``result`` holds the bands (the hulls nested over all levels) and the
        refinement (:attr:`MarkerErrorResult.allowable`: every level evaluated and the
        outcome per component; layout in the module docstring; :func:`allowable_table`
        rebuilds the table from it).
    """
    options, tolerance, angles, resolution = request.options, request.tolerance, request.angles, request.resolution
    sources = parse_sources(options.sources)
    with evaluator_or_own(evaluator, options.workers) as runner:
        if fuzzy is None:
            names = None if angles is None else list(dict.fromkeys(angle_of(a) for a in angles))
            fuzzy = fuzzy_joint_angles(trial, subject, result, options, names, evaluator=runner, clusters=clusters)
        _check_consistent(fuzzy, options, sources)
        components = _components(fuzzy, angles)
        setups = component_setups(trial, subject, result, options, components, clusters)
        searches = _start_searches(fuzzy, setups, tolerance, resolution)
        done = refine(setups, searches, runner, request.max_evaluations, progress)
    source = options.error_model.source + ("" if set(sources) == set(SOURCES) else f" ({', '.join(sources)})")
    bands, levels = _merge(fuzzy, done.runs, setups)
    refinement = _store(levels, searches, setups, done.counts)
    refinement.attrs.update({"tolerance_deg": float(tolerance), "resolution_mm": float(resolution), "source": source,
                             "seconds": round(done.seconds, 3), "runs": int(sum(done.counts.values())),
                             "node_evaluations": int(done.node_evaluations)})  # fmt: skip
    refined = MarkerErrorResult(bands, refinement)
    return allowable_table(refined), refined
