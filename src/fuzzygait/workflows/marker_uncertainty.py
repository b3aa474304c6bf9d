"""Fuzzy joint angles of a trial from fuzzy marker errors (thesis §3.7.3, §5.5), as a job.

:func:`analyse_run` takes a joint-angle run that is already computed
(:func:`fuzzygait.workflows.angles.run_angles`), so a caller that needs both the
deterministic angles and their uncertainty reads and processes the trial once;
:func:`analyse_trial` does both from the files of a :class:`MarkerErrorRequest`.  The
analysis itself (arrays in, dataset out) is :func:`fuzzygait.markererror.analysis.fuzzy_joint_angles`.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from numbers import Integral, Real
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict, Unpack

import numpy as np
import pandas as pd
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.names import angle_of
from fuzzygait.kinematics import ALL_ANGLE_NAMES
from fuzzygait.markererror.allowable import DEFAULT_TOLERANCE, AllowableRequest, allowable_errors
from fuzzygait.markererror.analysis import (
    DEFAULT_ALPHAS,
    METHODS,
    FuzzyAngleOptions,
    fuzzy_joint_angles,
    relative_envelope_width,
    split_component,
)
from fuzzygait.markererror.fuzzy_kinetics import DEFAULT_TOLERANCE as DEFAULT_KINETIC_TOLERANCE
from fuzzygait.markererror.moment_model import DEFAULT_COP_ERROR_MM
from fuzzygait.markererror.per_source import FLEXION_COMPONENTS, PerSourceRequest, per_source_bands
from fuzzygait.markererror.result import MarkerErrorResult, angle_components, error_sources, save_marker_result
from fuzzygait.markererror.sources import SOURCES, ErrorModel, parse_sources, read_error_model
from fuzzygait.uncertainty.execution import Evaluator
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.progress import SILENT, StageProgress, announce, takes_estimates
from fuzzygait.workflows.trial_inputs import TrialInputs

if TYPE_CHECKING:
    from fuzzygait.workflows.work_estimate import WorkEstimate

__all__ = [
    "DEFAULT_SETTINGS",
    "MarkerErrorAnalysis",
    "MarkerErrorRequest",
    "MarkerErrorSettings",
    "analyse_run",
    "analyse_to_files",
    "analyse_trial",
]

Progress = Callable[[int, int], None]


@dataclass
class MarkerErrorAnalysis:
    """A trial's deterministic run, its fuzzy angles (``fuzzy``, the bands), their ΔΦ
    table, the allowable-marker-error table
    (:func:`fuzzygait.markererror.allowable.allowable_table`; None when no tolerance was
    set) and the whole result (``result``: the bands ``fuzzy``, the refinement and the
    per-source bands; None given: the bands alone)."""

    run: AnglesRun
    fuzzy: xr.Dataset
    delta_phi: pd.DataFrame
    notes: list[Finding]
    allowable: pd.DataFrame | None = None
    result: MarkerErrorResult | None = None

    def __post_init__(self) -> None:
        if self.result is None:
            self.result = MarkerErrorResult(self.fuzzy)
        elif self.result.bands is not self.fuzzy:
            raise ParameterError("result: its bands must be the analysis' fuzzy dataset")


class SettingsArguments(TypedDict, total=False):
    """Arguments of :meth:`MarkerErrorSettings.create`."""

    errors_file: str | os.PathLike[str] | None
    sources: Sequence[str]
    alphas: Sequence[float]
    angles: Sequence[str] | None
    method: str
    workers: int | None
    tolerance: float | None
    allowable_angles: Sequence[str] | None
    per_source: bool
    kinetics: bool
    cop_error_mm: float
    kinetic_tolerance: float


@dataclass(frozen=True)
class MarkerErrorSettings:
    """What the marker-error analysis assumes and computes.

    Attributes:
        error_model: the marker error sizes (default: thesis Table 3.1).
        sources: error sources summed into each marker's ball radius.
        alphas: α-levels (1, the measured angle, is added).
        angles: angle names to analyse (None: every computed angle).
        method: ``"cartesian"`` or ``"spherical"`` marker deviations.
        workers: processes for the angles (None: up to 2).
        tolerance: ± degrees of the allowable-marker-error refinement
            (:func:`~fuzzygait.markererror.allowable.allowable_errors`; None: none).
        allowable_angles: angle names or components to refine (None: every analysed one).
        per_source: also the bands of each selected error source alone for the analysed
            hip/knee/ankle flexion components, at the smallest α-level (thesis Fig. 5.9;
            :func:`~fuzzygait.markererror.per_source.per_source_bands`); nothing when one
            source is selected or no flexion component is analysed.
        kinetics: also the fuzzy sagittal joint moments and the joint powers of ankle,
            knee and hip, both sides, when the trial has force plates
            (:func:`~fuzzygait.markererror.fuzzy_kinetics.fuzzy_joint_moments`, the same
            α-levels and error sources; about as long again as the fuzzy angles on a
            whole trial, hence off by default).
        cop_error_mm: the centre-of-pressure error ball's radius at α = 0, mm
            (:data:`~fuzzygait.markererror.moment_model.DEFAULT_COP_ERROR_MM`).
        kinetic_tolerance: ± N·m/kg of the moments' allowable-error answer
            (:func:`~fuzzygait.markererror.fuzzy_kinetics.allowable_kinetic_error`).
    """

    error_model: ErrorModel = field(default_factory=ErrorModel)
    sources: tuple[str, ...] = SOURCES
    alphas: tuple[float, ...] = DEFAULT_ALPHAS
    angles: tuple[str, ...] | None = None
    method: str = "cartesian"
    workers: int | None = None
    tolerance: float | None = DEFAULT_TOLERANCE
    allowable_angles: tuple[str, ...] | None = None
    per_source: bool = True
    kinetics: bool = False
    cop_error_mm: float = DEFAULT_COP_ERROR_MM
    kinetic_tolerance: float = DEFAULT_KINETIC_TOLERANCE

    def __post_init__(self) -> None:
        object.__setattr__(self, "alphas", _alpha_levels(self.alphas))
        object.__setattr__(self, "angles", _angle_selection("angles", self.angles))
        object.__setattr__(self, "allowable_angles", _angle_selection("allowable_angles", self.allowable_angles))
        if self.workers is not None and (isinstance(self.workers, bool) or not isinstance(self.workers, Integral)
                                         or self.workers < 1):  # fmt: skip
            raise ParameterError(f"workers must be a whole number of processes >= 1 (or None: up to 2); "
                                 f"got {self.workers!r}")  # fmt: skip
        if self.method not in METHODS:
            raise ParameterError(f"method must be one of {', '.join(METHODS)}; got {self.method!r}")
        if self.tolerance is not None and not (math.isfinite(self.tolerance) and self.tolerance > 0):
            raise ParameterError(f"tolerance must be a finite number of degrees > 0 (or None: no "
                                 f"allowable-error table); got {self.tolerance}")  # fmt: skip
        if not (math.isfinite(self.cop_error_mm) and self.cop_error_mm >= 0):
            raise ParameterError(f"the centre-of-pressure error must be a distance >= 0 mm; got {self.cop_error_mm}")
        if not (math.isfinite(self.kinetic_tolerance) and self.kinetic_tolerance > 0):
            raise ParameterError(f"the kinetic tolerance must be a finite number of N·m/kg > 0; got "
                                 f"{self.kinetic_tolerance}")  # fmt: skip

    @classmethod
    def create(cls, **arguments: Unpack[SettingsArguments]) -> MarkerErrorSettings:
        """Settings with the error sizes read from ``errors_file`` (once) and the sources
        checked; the other arguments as the attributes (defaults: theirs); ParameterError for
        an unknown keyword (naming it and the accepted ones) or an impossible value."""
        accepted = SettingsArguments.__optional_keys__ | SettingsArguments.__required_keys__
        unknown = [k for k in arguments if k not in accepted]
        if unknown:
            raise ParameterError(f"MarkerErrorSettings.create: unknown keyword argument {', '.join(unknown)}; "
                                 f"it takes {', '.join(k for k in SettingsArguments.__annotations__)}")  # fmt: skip
        names = parse_sources(arguments.get("sources", SOURCES))
        errors_file = arguments.get("errors_file")
        error_model = read_error_model(errors_file) if errors_file is not None else ErrorModel()
        angles = _angle_selection("angles", arguments.get("angles"))
        refined = _angle_selection("allowable_angles", arguments.get("allowable_angles"))
        return cls(error_model, names, _alpha_levels(arguments.get("alphas", DEFAULT_ALPHAS)),
                   angles, arguments.get("method", "cartesian"),
                   arguments.get("workers"), arguments.get("tolerance", DEFAULT_TOLERANCE),
                   refined, bool(arguments.get("per_source", True)),
                   bool(arguments.get("kinetics", False)), float(arguments.get("cop_error_mm", DEFAULT_COP_ERROR_MM)),
                   float(arguments.get("kinetic_tolerance", DEFAULT_KINETIC_TOLERANCE)))  # fmt: skip

    def options(self) -> FuzzyAngleOptions:
        """The options of :func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles`."""
        workers = self.workers if self.workers is not None else min(2, os.cpu_count() or 1)
        return FuzzyAngleOptions(alphas=self.alphas, sources=self.sources, error_model=self.error_model,
                                 method=self.method, workers=workers)  # fmt: skip


def _alpha_levels(alphas: object) -> tuple[float, ...]:
    """``alphas`` as a tuple of α-levels, checked: finite numbers in [0, 1], at least one
    below 1 (1, the measured angle, is always added)."""
    if isinstance(alphas, (str, bytes)) or not isinstance(alphas, (Sequence, np.ndarray)) \
            or not all(isinstance(a, Real) and not isinstance(a, bool) for a in alphas) \
            or not all(0.0 <= float(a) <= 1.0 for a in alphas) or not any(float(a) < 1.0 for a in alphas):
        raise ParameterError(f"alphas must be α-levels from 0 to below 1, e.g. (0, 0.5); got {alphas!r} (1, the "
                             "measured angle, is always added)")  # fmt: skip
    return tuple(float(a) for a in alphas)


def _angle_selection(field_name: str, names: object) -> tuple[str, ...] | None:
    """``names`` (a setting ``field_name`` selecting angles) as a tuple, checked: None, or
    one or more angle names (``"LKneeAngles"``) or components (``"LKneeAngles_X"``)."""
    if names is None:
        return None
    if isinstance(names, (str, bytes)) or not isinstance(names, (Sequence, np.ndarray)) or len(names) == 0:
        raise ParameterError(f"{field_name} must be a list of one or more angle names or components, e.g. "
                             f"['LKneeAngles', 'RHipAngles_X'] (None: every angle); got {names!r}")  # fmt: skip
    unknown = [n for n in names if not isinstance(n, str) or angle_of(n) not in ALL_ANGLE_NAMES]
    if unknown:
        raise ParameterError(f"{field_name}: unknown angle {', '.join(map(repr, unknown))}; give angle names such "
                             f"as {', '.join(ALL_ANGLE_NAMES[:4])}, ... or components such as "
                             f"{ALL_ANGLE_NAMES[0]}_X")  # fmt: skip
    return tuple(names)


#: The default analysis: Table 3.1 errors, all sources, α = 0, 0.25, 0.5, 0.75 (and 1),
#: the allowable marker error for ±2.5°, the flexion angles' bands per source at α = 0.
DEFAULT_SETTINGS = MarkerErrorSettings()


@dataclass(frozen=True)
class MarkerErrorRequest:
    """A marker-error analysis of one trial: its inputs and angle options (``trial``) and
    what the analysis assumes and computes (``settings``)."""

    trial: TrialInputs
    settings: MarkerErrorSettings = DEFAULT_SETTINGS

    def __post_init__(self) -> None:
        if not isinstance(self.trial, TrialInputs):
            raise ParameterError(f"trial must be TrialInputs; got {type(self.trial).__name__}")
        if not isinstance(self.settings, MarkerErrorSettings):
            raise ParameterError(f"settings must be MarkerErrorSettings; got {type(self.settings).__name__}")


def analyse_run(
    run: AnglesRun,
    settings: MarkerErrorSettings = DEFAULT_SETTINGS,
    progress: Progress | None = None,
    *,
    stages: StageProgress = SILENT,
) -> MarkerErrorAnalysis:
    """The fuzzy marker-error analysis of an already computed joint-angle run.

    ``progress(done, total)`` is called per angle of the first stage; ``stages``
    sees the whole run: ``"fuzzy angles"`` (per angle), ``"allowable marker
    error"`` (per refinement run, its total an estimate that shrinks as the searches
    converge) and ``"per-source bands"`` (per source × flexion component).  The
    marker-error model is the run's model version (a cluster model with the run's static
    cluster calibration held fixed).  With ``settings.tolerance`` the allowable-marker-error
    refinement (:func:`~fuzzygait.markererror.allowable.allowable_errors`) follows on the
    same evaluator: the bands are nested over every level and the result holds the
    refinement (``result.allowable``); with ``settings.per_source`` then the per-source
    bands of the flexion angles (:func:`~fuzzygait.markererror.per_source.per_source_bands`,
    ``result.sources``).
    The dataset's ``trial`` attribute is the trial's file name, ``model`` that version; the
    notes are the run's plus one line on the assumed errors (and one each on the
    per-source runs and the refinement's, the latter last, with their runs and time).
    """
    options = settings.options()
    allowable = None
    not_computed = _angles_not_computed(run, settings)

    def components(done: int, total: int) -> None:
        if progress is not None:
            progress(done, total)
        stages.update(done, total)

    per_source_note = None
    if takes_estimates(stages) and (estimate := _estimate(run, settings)) is not None:
        announce(stages, estimate)
    with Evaluator(workers=max(1, int(options.workers))) as evaluator:
        stages.stage("fuzzy angles")
        plain = fuzzy_joint_angles(run.trial, run.subject, run.result, options, settings.angles, components,
                                   evaluator=evaluator, clusters=run.clusters)  # fmt: skip
        result = MarkerErrorResult(plain)
        if settings.tolerance is not None:
            stages.stage("allowable marker error")
            request = AllowableRequest(options, settings.tolerance, settings.allowable_angles)
            allowable, result = allowable_errors(run.trial, run.subject, run.result, request, fuzzy=result.bands,
                                                 evaluator=evaluator, clusters=run.clusters,
                                                 progress=stages.update)  # fmt: skip
        fuzzy = result.bands
        if settings.per_source:
            flexion = [c for c in FLEXION_COMPONENTS if c in angle_components(fuzzy)]
            if len(options.sources) < 2:
                per_source_note = "per-source bands: not computed (a single error source is selected)"
            elif not flexion or not any(a < 1.0 for a in fuzzy["alpha"].to_numpy()):
                per_source_note = "per-source bands: not computed (no hip/knee/ankle flexion analysed)"
            else:
                stages.stage("per-source bands", len(options.sources) * len(flexion))
                sources = per_source_bands(run.trial, run.subject, run.result, fuzzy, PerSourceRequest(options),
                                           evaluator=evaluator, clusters=run.clusters,
                                           progress=stages.update)  # fmt: skip
                result = replace(result, sources=sources)
                per_source_note = _per_source_note(fuzzy, sources, len(flexion))
    fixed = "static cluster calibration, " if run.clusters is not None else ""
    notes = list(run.notes) + [Finding(
        FindingKind.UNCERTAINTY,
        f"marker errors: {', '.join(options.sources)} ({settings.error_model.source}), {options.method} "
        f"formulation, α-levels {', '.join(f'{a:g}' for a in fuzzy['alpha'].to_numpy())}; {run.model} marker "
        f"model ({fixed}static offsets and subject measures fixed)",
    )]
    if not_computed:
        notes.append(Finding(FindingKind.UNCERTAINTY, f"fuzzy angles: {', '.join(not_computed)} not analysed: this "
                             f"{run.model} run did not compute them", Severity.WARNING))  # fmt: skip
    if per_source_note is not None:
        notes.append(Finding(FindingKind.UNCERTAINTY, per_source_note))
    if allowable is not None:
        which = "" if settings.allowable_angles is None else f" ({', '.join(settings.allowable_angles)})"
        assert result.allowable is not None
        runs, seconds = result.allowable.attrs["runs"], result.allowable.attrs["seconds"]
        notes.append(Finding(FindingKind.ALLOWABLE_ERROR, f"allowable marker error for ±{settings.tolerance:g}°"
                             f"{which}: {runs} refinement runs, {seconds:.1f} s"))  # fmt: skip
    if settings.kinetics:
        result = _with_kinetics(run, settings, result, notes, stages)
    fuzzy.attrs["trial"] = Path(run.trial.name).name
    fuzzy.attrs["model"] = run.model
    return MarkerErrorAnalysis(run, fuzzy, relative_envelope_width(fuzzy), notes, allowable, result)


def _angles_not_computed(run: AnglesRun, settings: MarkerErrorSettings) -> list[str]:
    """The angles (or components) of ``settings.angles`` that ``run`` did not compute (the
    analysis skips them; empty when every angle is asked for); ParameterError when the run
    computed none of them (naming them and what it computed)."""
    wanted = settings.angles or ALL_ANGLE_NAMES
    missing = [n for n in wanted if split_component(n)[0] not in run.result.angles]
    if len(missing) == len(wanted):
        asked = "" if settings.angles is None else f" ({', '.join(settings.angles)})"
        raise ParameterError(f"{Path(run.trial.name).name}: none of the requested angles{asked} was computed by this "
                             f"{run.model} run; it computed {', '.join(run.result.angles) or 'no angle'}")  # fmt: skip
    return missing if settings.angles is not None else []


def _estimate(run: AnglesRun, settings: MarkerErrorSettings) -> WorkEstimate | None:
    """The analysis' work on ``run``: per component asked for, the frames it is optimised
    on (measured, and computable from the markers) × the α-levels, and the later runs;
    None when no component asked for is computed (the analysis then says so)."""
    from fuzzygait.markererror.analysis import component_tasks
    from fuzzygait.markererror.angle_model import AXES
    from fuzzygait.workflows.work_estimate import marker_error_work

    names = [n for n in (settings.angles or ALL_ANGLE_NAMES) if split_component(n)[0] in run.result.angles]
    if not names:
        return None
    tasks, _ = component_tasks(run.trial, run.subject, run.result, settings.options(), names, run.clusters)
    return marker_error_work({f"{t.name}_{AXES[t.axis]}": int(t.frames.size) for t in tasks}, settings)


def _per_source_note(fuzzy: xr.Dataset, sources: xr.Dataset, n_components: int) -> str:
    """The notes line of the per-source runs (``sources``: their bands beside the bands
    ``fuzzy``): what, how many, how long, and whether a source's band reaches beyond the
    all-sources band (it should not: nested balls)."""
    alpha = float(sources["alpha"].to_numpy()[0])
    text = (f"per-source bands (Fig. 5.9): {', '.join(error_sources(fuzzy))} each alone for "
            f"{n_components} flexion components at α = {alpha:g}: {sources.attrs['runs']} runs, "
            f"{float(sources.attrs['seconds']):.1f} s")  # fmt: skip
    excess = float(sources.attrs["nesting_excess_deg"])
    if excess > 0.01:
        text += (f"; a single source's band reaches up to {excess:.2f}° beyond the all-sources band (the "
                 "all-sources optimum is a local one there)")  # fmt: skip
    return text


def analyse_trial(
    request: MarkerErrorRequest, progress: Progress | None = None, *, stages: StageProgress = SILENT
) -> MarkerErrorAnalysis:
    """The pipeline of :func:`fuzzygait.workflows.angles.run_angles` on ``request.trial``
    (its model version or ``"auto"``, as there) followed by the fuzzy marker-error analysis
    of every computed angle (or ``request.settings.angles``) by the same version, with
    ``request.settings``; ``progress`` and ``stages`` as for :func:`analyse_run`."""
    return analyse_run(request.trial.run(), request.settings, progress, stages=stages)


def analyse_to_files(
    request: MarkerErrorRequest,
    out_file: Path,
    *,
    rrd: Path | None = None,
    progress: Progress | None = None,
    stages: StageProgress = SILENT,
) -> MarkerErrorAnalysis:
    """Run the pipeline and the marker-error analysis of one trial as
    :func:`analyse_trial`, save its result to ``out_file`` (.nc or .zarr; the bands at
    the root, the refinement and the per-source bands as groups:
    :func:`~fuzzygait.markererror.result.save_marker_result`) and,
    with ``rrd``, a Rerun recording of the trial with its bands (folders created);
    ``progress`` and ``stages`` as for :func:`analyse_run`."""
    run = request.trial.run()
    analysis = analyse_run(run, request.settings, progress, stages=stages)
    out_file.parent.mkdir(parents=True, exist_ok=True)
    assert analysis.result is not None  # set by MarkerErrorAnalysis
    save_marker_result(analysis.result, out_file)
    if rrd is not None:
        from fuzzygait.workflows.rerun_recordings import write_recording

        rrd.parent.mkdir(parents=True, exist_ok=True)
        write_recording(rrd, run.trial, run.result, analysis.fuzzy,
                        kinetics=run.kinetics.data if run.kinetics is not None else None)  # fmt: skip
    return analysis


def fuzzy_kinetics(run: AnglesRun, settings: MarkerErrorSettings,
                   stages: StageProgress = SILENT) -> tuple[xr.Dataset | None, Finding]:  # fmt: skip
    """The fuzzy sagittal joint moments and the joint powers of ankle, knee and hip of both
    legs (those the run's kinetics computed) at ``settings``' α-levels, error sources and
    centre-of-pressure ball, with each moment's allowable-error answer at
    ``settings.kinetic_tolerance`` (the kinetics group of
    :class:`~fuzzygait.markererror.result.MarkerErrorResult`), and the note saying what
    was computed; None and the note's reason when the trial has no force plates or the
    fuzzy kinetics cannot be computed (the angle bands stand).  Each foot's load is the
    one the run's kinetics used: its plates (analog rate) and each contact of the
    automatic (or the subject file's) assignment.
    ``stages`` sees the stage ``"fuzzy kinetics"`` (the moments, then the powers)."""
    from fuzzygait.core.errors import FuzzyGaitError
    from fuzzygait.core.findings import Severity
    from fuzzygait.core.names import Side
    from fuzzygait.kinetics.plug_in_gait import JOINTS
    from fuzzygait.markererror.fuzzy_kinetics import FuzzyKineticsOptions, contacts_ground, fuzzy_joint_moments
    from fuzzygait.workflows.work_estimate import FUZZY_KINETICS_STAGE

    source = run.raw.source
    if run.kinetics is None or source is None:
        failed = any(n.kind is FindingKind.KINETICS and n.severity is Severity.WARNING for n in run.notes)
        why = "the kinetics were not computed" if failed or source is None else f"no force plates in {source.name}"
        return None, Finding(FindingKind.UNCERTAINTY, f"fuzzy kinetics: not computed ({why})")
    sides = [side for side in Side if side not in run.kinetics.unavailable]
    if not sides:
        return None, Finding(FindingKind.UNCERTAINTY, "fuzzy kinetics: not computed (neither leg's kinetics were)")
    trial = run.trial
    start = time.perf_counter()
    try:
        plates = run.kinetics.force_plates
        ground = {side: contacts_ground(plates, run.kinetics.contacts, side, trial.n_frames, trial.rate)
                  for side in sides}  # fmt: skip
        parts = []
        stages.stage(FUZZY_KINETICS_STAGE, 2)
        for kind, axis in (("Moment", "_X"), ("Power", "_Z")):
            options = FuzzyKineticsOptions(alphas=settings.alphas, sources=settings.sources,
                                           error_model=settings.error_model, cop_error_mm=settings.cop_error_mm,
                                           kind=kind)  # fmt: skip
            outputs = [f"{side.value}{joint}{kind}{axis}" for side in sides for joint in JOINTS]
            parts.append(fuzzy_joint_moments(trial, run.subject, run.result, ground, options, outputs))
            stages.update(len(parts), 2)
    except FuzzyGaitError as exc:
        return None, Finding(FindingKind.UNCERTAINTY, f"fuzzy kinetics: not computed: {exc}", Severity.WARNING)
    kinetics = kinetics_group(parts, settings.kinetic_tolerance)
    kinetics.attrs["trial"] = Path(trial.name).name
    return kinetics, Finding(FindingKind.UNCERTAINTY, (
        f"fuzzy kinetics: sagittal moments and powers of {len(sides) * len(JOINTS)} joints with a "
        f"{settings.cop_error_mm:g} mm centre-of-pressure ball per loaded plate (plates "
        f"{', '.join(str(p.number) for p in plates if p.number in {c.plate for c in run.kinetics.contacts if c.side})}"
        f"), {time.perf_counter() - start:.1f} s"))  # fmt: skip


def _with_kinetics(run: AnglesRun, settings: MarkerErrorSettings, result: MarkerErrorResult,
                   notes: list[Finding], stages: StageProgress) -> MarkerErrorResult:  # fmt: skip
    """``result`` with the run's fuzzy kinetics (:func:`fuzzy_kinetics`), their note
    appended to ``notes``."""
    kinetics, note = fuzzy_kinetics(run, settings, stages)
    notes.append(note)
    return replace(result, kinetics=kinetics)


def kinetics_group(parts: Sequence[xr.Dataset], tolerance: float) -> xr.Dataset:
    """The fuzzy moments and the fuzzy powers (``parts``: datasets of
    :func:`~fuzzygait.markererror.fuzzy_kinetics.fuzzy_joint_moments`) stacked along
    ``component`` with their units as a coordinate, and each moment's allowable-error
    answer at ``tolerance`` N·m/kg (layout: :attr:`MarkerErrorResult.kinetics
    <fuzzygait.markererror.result.MarkerErrorResult>`)."""
    from fuzzygait.markererror.fuzzy_kinetics import allowable_kinetic_error
    from fuzzygait.markererror.moment_model import KINDS
    from fuzzygait.markererror.result import UNITS_COORD

    units = KINDS["Moment"]
    stacked = [p.assign_coords({UNITS_COORD: ("component", [str(p.attrs["units"])] * p.sizes["component"])})
               for p in parts]  # fmt: skip
    group = xr.concat(stacked, dim="component", data_vars="minimal", coords="minimal", compat="override",
                      join="outer", combine_attrs="drop_conflicts")  # fmt: skip
    group["hull"].attrs["units"] = "per component (coordinate 'units')"
    counts = ("forward_simulations", "node_evaluations", "node_gradients", "seconds")
    group.attrs.update({key: sum(p.attrs[key] for p in parts) for key in counts})
    group.attrs.update(output="joint moment and power", units=group["hull"].attrs["units"],
                       kinetic_tolerance=float(tolerance))  # fmt: skip
    names = [str(c) for c in group["component"].to_numpy()]
    answers = {c: allowable_kinetic_error(p, c, tolerance) for p in parts if p.attrs["units"] == units
               for c in p["component"].to_numpy().astype(str)}  # fmt: skip
    for var, attr, unit in (("allowable_scale", "scale", "1"), ("allowable_failing", "failing", "1"),
                            ("allowable_marker_mm", "marker_mm", "mm"), ("allowable_cop_mm", "cop_mm", "mm")):
        values = [getattr(answers[c], attr) if c in answers else np.nan for c in names]
        group[var] = ("component", np.asarray(values, dtype=float), {"units": unit})
    return group
