"""The joint-angle pipeline shared by the CLI, the batch report and notebooks.

read C3D -> fill gaps -> low-pass -> subject parameters (file, or PROCESSING group) ->
static calibration (optional; or the subject file's cluster calibration) -> a CGM
version's lower body -> gait events -> cycles.  Every file written names the model
version (:class:`AngleOutputs`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.gait.cycles import mean_sd_table, normalised_angle_table
from fuzzygait.gait.events import SOURCE_FILE, trial_gait_events
from fuzzygait.io import Event, Trial, read_c3d, write_c3d
from fuzzygait.io.calibration_table import sidecar_path
from fuzzygait.io.tables import write_table
from fuzzygait.kinematics import (
    ALL_ANGLE_NAMES,
    ANGLE_NAMES,
    FOREFOOT_ANGLE_NAMES,
    CGMResult,
    compute_lower_body,
    static_calibration,
)
from fuzzygait.kinematics.calibration_file import StoredCalibration, read_stored_calibration
from fuzzygait.kinematics.clusters import ClusterCalibration, calibrate_clusters
from fuzzygait.kinematics.kad import knee_method
from fuzzygait.kinematics.knee_ankle import RULE_NAMES, knee_ankle_rule
from fuzzygait.kinematics.marker_names import canonical_labels
from fuzzygait.kinematics.versions import model_version, supported_version
from fuzzygait.mocap import fill_trial_gaps, filter_trial, labelled_markers
from fuzzygait.mocap.gaps import Gap, Method
from fuzzygait.mocap.marker_placement import moved_markers
from fuzzygait.mocap.sanity import check_trial
from fuzzygait.workflows.crosscheck import CrossCheck, check_run, recover_flat_foot
from fuzzygait.workflows.subject_resolution import (  # noqa: F401  (resolve_subject: re-exported)
    MARKER_DIAMETER_RANGE,
    DiameterChoice,
    for_static_calibration,
    inter_asis_notes,
    resolve_subject,
    settle_marker_diameter,
    subject_warnings,
)
from fuzzygait.workflows.uncomputed import mark_empty_angles, refuse_empty

AXES = ("X", "Y", "Z")
#: Characters of a C3D point label (Vicon's limit, :func:`fuzzygait.io.write_c3d`).
MAX_LABEL = 32


@dataclass(frozen=True)
class Preprocessing:
    """Pre-processing options: gaps up to ``max_gap`` frames filled by ``fill_method``
    (``"auto"``, ``"spline"`` or ``"pattern"``, see :func:`fuzzygait.mocap.gaps.fill_gaps`),
    then a zero-lag Butterworth low-pass at ``cutoff`` Hz unless ``filter`` is False.

    With ``labelled_only`` (the default of the model pipelines) unlabelled trajectories
    (Vicon's ``*127``, :func:`fuzzygait.mocap.gaps.is_unlabelled`) are neither filled nor
    filtered nor reported: no model reads them, and their many short fragments only filled
    the gap report and the filter's short-run warnings; ``fuzzygait preprocess`` (a file
    in, the same file cleaned out) treats every trajectory."""

    max_gap: int = 10
    cutoff: float = 6.0
    filter: bool = True
    fill_method: Method = "auto"
    labelled_only: bool = True

    def apply(self, trial: Trial) -> tuple[Trial, list[Gap]]:
        """The pre-processed trial and its gap report."""
        labelled = labelled_markers(trial.marker_labels) if self.labelled_only else list(trial.marker_labels)
        markers = None if len(labelled) == trial.n_markers else labelled
        filled, gaps = fill_trial_gaps(trial, max_gap=self.max_gap, method=self.fill_method, markers=markers)
        return (filter_trial(filled, cutoff=self.cutoff, markers=markers) if self.filter else filled), gaps


#: The default pre-processing (gaps up to 10 frames, auto method; 6 Hz low-pass).
DEFAULT_PREPROCESSING = Preprocessing()


def preprocess_file(
    input_file: str | os.PathLike[str], out_file: str | os.PathLike[str], preprocessing: Preprocessing = Preprocessing()
) -> tuple[Trial, list[Gap]]:
    """Read a C3D file, pre-process it and write the result to ``out_file`` (its folder
    created); returns the trial as read after the content checks
    (:func:`fuzzygait.mocap.sanity.check_trial`: implausible samples of the labelled
    markers blanked, each noted in its ``notes``) and the gap report. The written file
    carries the input's analog channels, force platforms, events and parameters over
    (:func:`fuzzygait.io.write_c3d`); what could not be is one more note.

    Raises:
        C3DError, MarkerError: an absurd rate, a unit mismatch, a marker with too many
            implausible samples (nothing written)."""
    raw = check_trial(read_c3d(input_file))
    cleaned, gaps = preprocessing.apply(raw)
    Path(out_file).parent.mkdir(parents=True, exist_ok=True)
    raw.notes.extend(write_c3d(cleaned, out_file, source=input_file))
    return raw, gaps


@dataclass
class AnglesRun:
    """Everything one run of the pipeline produced.

    Attributes:
        raw: the trial as read.
        trial: the pre-processed trial the model saw.
        subject: subject parameters used (after static calibration, if any).
        result: model output (angles in degrees, joint centres in mm).
        gaps: gap report of the dynamic trial.
        events: gait events used for the cycles.
        event_source: ``"file"`` or how they were detected.
        notes: data-quality and processing findings for reports (:class:`~fuzzygait.core.findings.Finding`;
            their messages are what the commands print and the pages show).
        warnings: what the user must know before trusting the angles (a stated marker
            diameter that contradicts the file's own outputs, ...); shown on report pages
            and printed by the commands.
        crosscheck: ours against the angles the file already stores (Nexus', pyCGM2's),
            None when it stores none (:mod:`fuzzygait.workflows.crosscheck`).
        diameter: where the marker diameter came from
            (:func:`~fuzzygait.workflows.subject_resolution.settle_marker_diameter`).
        clusters: the static cluster calibration of a cluster model (cgm2.3, cgm2.4; the
            marker-error analysis holds it fixed), else None.
    """

    raw: Trial
    trial: Trial
    subject: SubjectParameters
    result: CGMResult
    gaps: list[Gap]
    events: list[Event]
    event_source: str
    notes: list[Finding] = field(default_factory=list)
    clusters: ClusterCalibration | None = None
    warnings: list[str] = field(default_factory=list)
    crosscheck: CrossCheck | None = None
    diameter: DiameterChoice | None = None

    @property
    def model(self) -> str:
        """The model version that computed the angles (``"cgm1.0"``, ``"cgm2.3"``, ...)."""
        return self.result.model

    def angle_names(self) -> list[str]:
        """The angle outputs of the tables: every Plug-in Gait angle, and the CGM 2.4
        forefoot angles when the model computed (or tried) them."""
        forefoot = [n for n in FOREFOOT_ANGLE_NAMES if n in self.result.angles or n in self.result.unavailable]
        return [*ANGLE_NAMES, *forefoot]

    def angle_table(self) -> pd.DataFrame:
        """One row per frame: ``frame``, ``time`` (s), then ``<Angle>_X/Y/Z`` in degrees
        for every angle of :meth:`angle_names` (NaN where it could not be computed);
        ``attrs["model"]`` the model version."""
        columns: dict[str, np.ndarray] = {"frame": self.trial.frames, "time": self.trial.times}
        nan = np.full((self.trial.n_frames, 3), np.nan)
        for name in self.angle_names():
            values = self.result.angles.get(name, nan)
            for k, axis in enumerate(AXES):
                columns[f"{name}_{axis}"] = values[:, k]
        table = pd.DataFrame(columns)
        table.attrs["model"] = self.model
        return table

    def cycle_table(self) -> pd.DataFrame:
        """Gait-cycle-normalised angles, long format (angle, side, cycle, percent, value)."""
        table = normalised_angle_table(self.result.angles, self.trial, self.events)
        table.attrs["model"] = self.model
        return table

    def cycle_statistics(self) -> pd.DataFrame:
        """Mean and SD over cycles per angle component and percent of the cycle."""
        table = mean_sd_table(self.cycle_table())
        table.attrs["model"] = self.model
        return table


@dataclass(frozen=True)
class StaticCalibration:
    """A static calibration: the calibrated ``subject``, the knee/ankle ``method``
    (``"plain"``, ``"KAD"`` or ``"KAD+MED"``, :func:`fuzzygait.kinematics.kad.knee_method`;
    for a cluster model its name and the knee/ankle centre rule), the cluster
    calibration (cluster models only),
    whether foot flat was on, the static trial's name and the content checks' notes on
    it (:func:`fuzzygait.mocap.sanity.check_trial`: implausible samples blanked)."""

    subject: SubjectParameters
    method: str
    flat_foot: bool
    static: str
    clusters: ClusterCalibration | None = None
    notes: tuple[Finding, ...] = ()

    def describe(self) -> str:
        """``"static offsets calibrated from S.c3d (KAD, foot flat off, 14 mm markers)"``."""
        return (f"static offsets calibrated from {self.static} ({self.method}, foot flat "
                f"{'on' if self.flat_foot else 'off'}, {self.subject.marker_diameter:g} mm markers)")  # fmt: skip


def calibrate_static(
    static: str | os.PathLike[str] | Trial,
    subject: SubjectParameters,
    *,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    flat_foot: bool | None = None,
    model: str = "cgm1.0",
    knee_ankle_centres: str | None = None,
) -> StaticCalibration:
    """Fill the static trial's gaps as the walking trials' and calibrate ``subject`` on it
    (:func:`fuzzygait.kinematics.static_calibration`: every offset Nexus stores after a
    static run, the inter-ASIS distance when ``subject`` has none).

    The static trial is **not** low-pass filtered, whatever ``preprocessing.filter``
    says: every offset is a mean over the standing frames already, and a Butterworth
    over a short standing trial only adds its edge transients (measured on Nexus'
    foot-flat static trial, 6 Hz: StaticPlantFlex 1.3e-4 rad off Nexus' value,
    unfiltered 1e-8 rad).  ``knee_ankle_centres``: a cluster model's knee/ankle centre
    rule (:mod:`fuzzygait.kinematics.knee_ankle`; None: KNM/MED when present, else chord).
    ``flat_foot`` None takes the subject file's own setting (``subject.flat_foot``: a QTM
    session.xml's "foot normalised to static trial"; noted), else the setting the static
    trial's own stored Plug-in Gait angles were made with
    (:func:`~fuzzygait.workflows.crosscheck.recover_flat_foot`; noted), else off.

    The content checks run first (:func:`fuzzygait.mocap.sanity.check_trial`): a trial
    that moves (a walking trial given as the static one), in the wrong unit or at an
    absurd rate is refused in one line; implausible samples are blanked and noted.
    """
    trial, relabelled = canonical_labels(static if isinstance(static, Trial) else read_c3d(static))
    checked = check_trial(trial, static=True)
    clean, _ = replace(preprocessing, filter=False).apply(checked)
    notes = (*relabelled, *checked.notes[len(trial.notes) :])
    if flat_foot is None and subject.flat_foot is None and (found := recover_flat_foot(clean, subject)) is not None:
        flat_foot = found
        notes += (Finding(FindingKind.STATIC_CALIBRATION, f"foot flat {'on' if found else 'off'}, as the static "
                          "trial's own stored Plug-in Gait angles were made (reproduced with it, not "
                          "without)"),)  # fmt: skip
    if flat_foot is None:
        flat_foot = bool(subject.flat_foot)
        if subject.flat_foot is not None:
            notes += (Finding(FindingKind.STATIC_CALIBRATION, f"foot flat {'on' if flat_foot else 'off'} as "
                              f"{Path(subject.source).name} sets it (feet {'' if flat_foot else 'not '}normalised to "
                              f"the static trial); --{'no-' if flat_foot else ''}flat-foot overrides it"),)  # fmt: skip
    calibrated = static_calibration(clean, subject, flat_foot=flat_foot, model=model,
                                    knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    method = knee_method(clean)
    clusters = None
    if model_version(model).clusters:
        clusters = calibrate_clusters(clean, calibrated, knee_ankle_centres, forefoot=model_version(model).forefoot)
        method = f"{model} clusters, {RULE_NAMES[knee_ankle_rule(clean, knee_ankle_centres)]} knee/ankle centres"
    return StaticCalibration(calibrated, method, flat_foot, trial.name, clusters, notes)


def run_angles(
    dynamic: str | os.PathLike[str] | Trial,
    *,
    static: str | os.PathLike[str] | Trial | None = None,
    subject_file: str | os.PathLike[str] | None = None,
    preprocessing: Preprocessing = Preprocessing(),
    flat_foot: bool | None = None,
    marker_diameter: float | None = None,
    model: str = "cgm1.0",
    knee_ankle_centres: str | None = None,
) -> AnglesRun:
    """Run the joint-angle pipeline on one dynamic trial.

    Args:
        dynamic: the walking trial (path or :class:`Trial`).
        static: static calibration trial; without it the static offsets of the subject
            parameters are used as they are, and a cluster model (CGM 2.3+) takes its
            cluster calibration from ``subject_file`` (written by ``fuzzygait calibrate``).
        subject_file: ``.toml`` or ``.vsk``; without it the dynamic trial's PROCESSING
            group.
        preprocessing: gap filling and filter options (the static trial: gap filling
            only, see :func:`calibrate_static`).
        flat_foot: static calibration with the flat-foot option (uses SoleDelta); None:
            the subject file's own setting when it has one (QTM session.xml), else off.
        marker_diameter: mm, in place of the subject parameters' (see :func:`resolve_subject`).
        model: a model version (:data:`fuzzygait.kinematics.versions.MODEL_VERSIONS`) or
            ``"auto"``: the richest the markers support, or without ``static`` the model
            of the subject file's cluster calibration (:func:`choose_model`).  The model
            used and why is the first note.
        knee_ankle_centres: a cluster model's knee/ankle centre rule in the static
            calibration (:mod:`fuzzygait.kinematics.knee_ankle`; None: KNM/MED when the
            static trial has them, else the chord).

    Raises:
        ParameterError: a cluster model with neither ``static`` nor a subject file
            holding a cluster calibration (says what to give).
    """
    raw, relabelled = canonical_labels(dynamic if isinstance(dynamic, Trial) else read_c3d(dynamic))
    checked = check_trial(raw)
    trial, gaps = preprocessing.apply(checked)
    static_trial = None if static is None else static if isinstance(static, Trial) else read_c3d(static)
    static_trial = None if static_trial is None else canonical_labels(static_trial)[0]
    diameter = settle_marker_diameter(resolve_subject(raw, subject_file), marker_diameter, (raw, static_trial))
    subject = diameter.subject
    notes = list(trial.notes)
    warnings = ([diameter.warning] if diameter.warning else []) + subject_warnings(raw, subject_file, static_trial,
                                                                                   subject)  # fmt: skip
    stored = StoredCalibration()
    if static_trial is None and subject_file is not None:
        stored = read_stored_calibration(subject_file)
    model, why = choose_model(model, raw, static_trial, stored)
    notes += [*relabelled, Finding(FindingKind.MODEL, f"model {model} ({why})"), diameter.note]
    clusters, moved = None, []
    if static_trial is not None:
        to_calibrate = for_static_calibration(subject, subject_file)
        calibration = calibrate_static(static_trial, to_calibrate, preprocessing=preprocessing, flat_foot=flat_foot,
                                       model=model, knee_ankle_centres=knee_ankle_centres)  # fmt: skip
        notes += inter_asis_notes(subject, to_calibrate, calibration.subject, calibration.static)
        subject, clusters = calibration.subject, calibration.clusters
        notes.append(Finding(FindingKind.STATIC_CALIBRATION, calibration.describe()))
        notes += [Finding(FindingKind.STATIC_TRIAL, f"static trial {calibration.static}: {note.message}", note.severity)
                  for note in calibration.notes]  # fmt: skip
        moved = moved_markers(static_trial, trial)
        notes += moved
    else:
        if model_version(model).clusters:
            clusters = stored_clusters(stored, subject_file, model)
            notes.append(Finding(FindingKind.SUBJECT, f"cluster calibration from "
                                 f"{stored.source.name if stored.source else subject_file}"
                                 + (f" (static trial {stored.static})" if stored.static else "")))  # fmt: skip
        if stored.model is not None and stored.model != model:
            notes.append(Finding(FindingKind.SUBJECT, f"{Path(subject_file or '').name} was calibrated for "
                                 f"{stored.model}; its offsets are used by {model} as they are",
                                 Severity.WARNING))  # fmt: skip
    result = compute_lower_body(trial, subject, model=model, clusters=clusters)
    mark_empty_angles(result, raw)
    refuse_empty(result, raw.name)
    notes += result.notes
    check = check_run(checked, result.angles, raw, subject, diameter.recovered, model=model, clusters=clusters,
                      flat_foot=flat_foot if flat_foot is not None else subject.flat_foot)  # fmt: skip
    if check is not None and moved:
        check = check.with_cause(f"markers moved between the static trial and this one ({len(moved)} segments)")
    notes += check.notes() if check is not None else []
    notes += [Finding(FindingKind.ANGLE_NOT_COMPUTED, f"{name} not computed: {why}", Severity.WARNING)
              for name, why in result.unavailable.items()]  # fmt: skip
    events, source = trial_gait_events(trial)
    if source != "file":
        notes.append(Finding(FindingKind.EVENTS, f"gait events {source}"))
    return AnglesRun(raw, trial, subject, result, gaps, events, source, notes, clusters, warnings, check, diameter)


def choose_model(
    model: str, dynamic: Trial, static: Trial | None, stored: StoredCalibration | None = None
) -> tuple[str, str]:
    """The model version to run on ``dynamic`` and why (a phrase for the notes).

    ``model`` by name; ``"auto"``: with a static trial the richest version the markers
    support (:func:`~fuzzygait.kinematics.versions.supported_version`); without one, the
    version of the subject file's cluster calibration (``stored``) when it holds one,
    else ``cgm1.0``.
    """
    if model != "auto":
        return model_version(model).name, "given by name"
    if static is None and stored is not None and stored.clusters is not None:
        name = stored.model or ("cgm2.4" if stored.has_forefoot() else "cgm2.3")
        where = stored.source.name if stored.source is not None else "the subject file"
        return model_version(name).name, f"the model of the cluster calibration in {where}"
    version, why = supported_version(dynamic, static)
    return version.name, why


def stored_clusters(
    stored: StoredCalibration, subject_file: str | os.PathLike[str] | None, model: str
) -> ClusterCalibration:
    """The subject file's cluster calibration for the cluster model ``model``, or one
    line saying what to give instead."""
    version = model_version(model)
    make = (f"give the static trial ({Option.STATIC} STATIC.c3d), or calibrate once with `fuzzygait calibrate "
            f"STATIC.c3d {Option.MODEL.flag} {version.name} {Option.OUT.flag} CAL.toml` and use {Option.SUBJECT} "
            "CAL.toml")  # fmt: skip
    if subject_file is None:
        raise ParameterError(f"{version.name} tracks the thigh and shank clusters calibrated on a static trial: {make}")
    if stored.clusters is None:
        where = str(subject_file)
        if Path(subject_file).suffix.lower() == ".vsk":
            where += f" (no {sidecar_path(subject_file).name} beside it)"
        raise ParameterError(f"{where}: no cluster calibration for {version.name}; {make}")
    if version.forefoot and not stored.has_forefoot():
        raise ParameterError(f"{stored.source}: its cluster calibration ({stored.model or 'cgm2.3'}) has no "
                             f"forefoot for {version.name}; {make}")  # fmt: skip
    return stored.clusters


def output_suffix(suffix: str, model: str) -> str:
    """The output-name suffix asked for: ``""`` none, ``"model"`` the version's pyCGM2
    suffix (``"_CGM_2.3"``), else ``suffix`` itself (letters, digits, ``_ . -``)."""
    if suffix == "model":
        return model_version(model).suffix
    longest = max(map(len, ALL_ANGLE_NAMES))
    if suffix and not (re.fullmatch(r"[A-Za-z0-9_.\-]+", suffix) and len(suffix) <= MAX_LABEL - longest):
        raise FuzzyGaitError(f"{Option.SUFFIX} {suffix!r}: use up to {MAX_LABEL - longest} letters, digits, '_', '.' "
                             "or '-' (e.g. _CGM_2.3; C3D labels hold 32 characters), or 'model'")  # fmt: skip
    return suffix


def model_output_trial(run: AnglesRun, suffix: str = "") -> Trial:
    """The pre-processed trial with the computed angles and virtual markers as model
    outputs, the subject parameters used and the events (for ``--c3d-out``: the trial's
    own, and the detected gait events when it had none).  The angle
    outputs keep Vicon's names (``LKneeAngles``) with ``suffix`` appended
    (:func:`output_suffix`); virtual markers and joint centres are not suffixed."""
    out = run.trial.with_markers(run.trial.markers)
    suffix = output_suffix(suffix, run.model)
    for name, values in run.result.angles.items():
        out.outputs[name + suffix] = values
        out.output_kinds[name + suffix] = "angle"
    for name, values in run.result.virtual_markers.items():
        if name not in out.marker_labels:
            out.outputs[name] = values
            out.output_kinds[name] = "modeled_marker" if name.endswith("JC") else "segment_frame"
    out.parameters.update(run.subject.to_processing())
    out.events = list(run.trial.events) + ([] if run.event_source == SOURCE_FILE else list(run.events))
    return out


def model_parameters(run: AnglesRun, suffix: str = "") -> dict[str, dict[str, str]]:
    """The C3D parameters naming the model of a run's outputs: group ``FUZZYGAIT``,
    ``MODEL`` (``"cgm2.3"``), ``VERSION`` of fuzzygait and, when the angle outputs have
    one, their ``SUFFIX`` (an empty text parameter reads back as no value)."""
    group = {"MODEL": run.model, "VERSION": __version__}
    if output_suffix(suffix, run.model):
        group["SUFFIX"] = output_suffix(suffix, run.model)
    return {"FUZZYGAIT": group}


def table_metadata(run: AnglesRun) -> dict[str, str]:
    """What the angle tables say about themselves: ``model`` and ``fuzzygait`` version."""
    return {"model": run.model, "fuzzygait": __version__}



@dataclass(frozen=True)
class AngleOutputs:
    """Files to write from a run (each optional): the angles per frame (``table``, .csv or
    .parquet), their mean and SD over gait cycles (``cycles``) and the model-output C3D
    (``c3d``, see :func:`model_output_trial`; its angle outputs named with ``suffix``,
    :func:`output_suffix`).

    Each names the model version: the tables in a last constant column ``model`` (and
    ``fuzzygait``, the version; Parquet also in its metadata, :func:`fuzzygait.io.tables.write_table`),
    the C3D in its ``FUZZYGAIT`` parameter group (:func:`model_parameters`).
    """

    table: Path | None = None
    cycles: Path | None = None
    c3d: Path | None = None
    suffix: str = ""

    def write(self, run: AnglesRun) -> list[Path]:
        """Write the files asked for (folders created); returns them in that order."""
        written = []
        metadata = table_metadata(run)
        for path, make in ((self.table, run.angle_table), (self.cycles, run.cycle_statistics)):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                written.append(write_table(make(), path, metadata=metadata, columns=("model",)))
        if self.c3d is not None:
            self.c3d.parent.mkdir(parents=True, exist_ok=True)
            trial = model_output_trial(run, self.suffix)
            # the input's analog channels, force platforms and parameters carried over; a note if not all
            parameters = model_parameters(run, self.suffix)
            run.notes += write_c3d(trial, self.c3d, text_parameters=parameters, source=trial.source)
            written.append(self.c3d)
        return written


def angles_to_files(
    dynamic: str | os.PathLike[str] | Trial,
    outputs: AngleOutputs,
    *,
    static: str | os.PathLike[str] | Trial | None = None,
    subject_file: str | os.PathLike[str] | None = None,
    preprocessing: Preprocessing = Preprocessing(),
    flat_foot: bool | None = None,
    marker_diameter: float | None = None,
    model: str = "cgm1.0",
    knee_ankle_centres: str | None = None,
) -> tuple[AnglesRun, list[Path]]:
    """:func:`run_angles` and then ``outputs.write``: the run and the files written."""
    run = run_angles(dynamic, static=static, subject_file=subject_file, preprocessing=preprocessing,
                     flat_foot=flat_foot, marker_diameter=marker_diameter, model=model,
                     knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    return run, outputs.write(run)
