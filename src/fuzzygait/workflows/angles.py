"""The joint-angle pipeline shared by the CLI, the batch report and notebooks.

read C3D -> fill gaps -> low-pass -> subject parameters (file, or PROCESSING group) ->
static calibration (optional) -> Plug-in Gait lower body -> gait events -> cycles.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.gait.cycles import mean_sd_table, normalised_angle_table
from fuzzygait.gait.events import trial_gait_events
from fuzzygait.io import Event, Trial, read_c3d, write_c3d
from fuzzygait.io.subject import SubjectParameters, read_subject, subject_from_processing
from fuzzygait.io.tables import write_table
from fuzzygait.kinematics import ANGLE_NAMES, CGMResult, compute_lower_body, static_calibration
from fuzzygait.kinematics.clusters import ClusterCalibration, calibrate_clusters
from fuzzygait.kinematics.kad import knee_method
from fuzzygait.kinematics.versions import model_version, supported_version
from fuzzygait.mocap import fill_trial_gaps, filter_trial
from fuzzygait.mocap.gaps import Gap, Method

AXES = ("X", "Y", "Z")
#: Marker diameters (mm) taken as plausible (the subject parameters' check).
MARKER_DIAMETER_RANGE = (1.0, 40.0)


@dataclass(frozen=True)
class Preprocessing:
    """Pre-processing options: gaps up to ``max_gap`` frames filled by ``fill_method``
    (``"auto"``, ``"spline"`` or ``"pattern"``, see :func:`fuzzygait.mocap.gaps.fill_gaps`),
    then a zero-lag Butterworth low-pass at ``cutoff`` Hz unless ``filter`` is False."""

    max_gap: int = 10
    cutoff: float = 6.0
    filter: bool = True
    fill_method: Method = "auto"

    def apply(self, trial: Trial) -> tuple[Trial, list[Gap]]:
        """The pre-processed trial and its gap report."""
        filled, gaps = fill_trial_gaps(trial, max_gap=self.max_gap, method=self.fill_method)
        return (filter_trial(filled, cutoff=self.cutoff) if self.filter else filled), gaps


#: The default pre-processing (gaps up to 10 frames, auto method; 6 Hz low-pass).
DEFAULT_PREPROCESSING = Preprocessing()


def preprocess_file(
    input_file: str | os.PathLike[str], out_file: str | os.PathLike[str], preprocessing: Preprocessing = Preprocessing()
) -> tuple[Trial, list[Gap]]:
    """Read a C3D file, pre-process it and write the result to ``out_file`` (its folder
    created); returns the trial as read and the gap report."""
    raw = read_c3d(input_file)
    cleaned, gaps = preprocessing.apply(raw)
    Path(out_file).parent.mkdir(parents=True, exist_ok=True)
    write_c3d(cleaned, out_file)
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
        notes: data-quality notes for reports.
    """

    raw: Trial
    trial: Trial
    subject: SubjectParameters
    result: CGMResult
    gaps: list[Gap]
    events: list[Event]
    event_source: str
    notes: list[str] = field(default_factory=list)

    def angle_table(self) -> pd.DataFrame:
        """One row per frame: ``frame``, ``time`` (s), then ``<Angle>_X/Y/Z`` in degrees
        for every Plug-in Gait angle (NaN where it could not be computed)."""
        columns: dict[str, np.ndarray] = {"frame": self.trial.frames, "time": self.trial.times}
        nan = np.full((self.trial.n_frames, 3), np.nan)
        for name in ANGLE_NAMES:
            values = self.result.angles.get(name, nan)
            for k, axis in enumerate(AXES):
                columns[f"{name}_{axis}"] = values[:, k]
        return pd.DataFrame(columns)

    def cycle_table(self) -> pd.DataFrame:
        """Gait-cycle-normalised angles, long format (angle, side, cycle, percent, value)."""
        return normalised_angle_table(self.result.angles, self.trial, self.events)

    def cycle_statistics(self) -> pd.DataFrame:
        """Mean and SD over cycles per angle component and percent of the cycle."""
        return mean_sd_table(self.cycle_table())


def resolve_subject(
    trial: Trial, subject_file: str | os.PathLike[str] | None, marker_diameter: float | None = None
) -> SubjectParameters:
    """Subject parameters from ``subject_file`` or else the trial's PROCESSING group, with
    ``marker_diameter`` (mm) in place of theirs when given (Nexus keeps the marker size in
    the pipeline, not in the C3D; the default is the subject file's, else 14 mm)."""
    if subject_file is not None:
        subject = read_subject(subject_file)
    elif not trial.parameters:
        raise FuzzyGaitError(
            f"{trial.name}: no subject parameters in the file (no PROCESSING group); "
            "give a subject file with --subject SUBJECT.toml or .vsk"
        )
    else:
        subject = subject_from_processing(trial.parameters, source=f"{trial.name} PROCESSING group")
    if marker_diameter is None:
        return subject
    low, high = MARKER_DIAMETER_RANGE
    if not (math.isfinite(marker_diameter) and low <= marker_diameter <= high):
        raise FuzzyGaitError(f"marker diameter {marker_diameter:g} mm is implausible: give it in mm "
                             f"({low:g} to {high:g}, e.g. --marker-diameter 14)")  # fmt: skip
    return replace(subject, marker_diameter=float(marker_diameter))


@dataclass(frozen=True)
class StaticCalibration:
    """A static calibration: the calibrated ``subject``, the knee/ankle ``method``
    (``"plain"``, ``"KAD"`` or ``"KAD+MED"``, :func:`fuzzygait.kinematics.kad.knee_method`;
    for a cluster model its name and the knee/ankle centre rule), the cluster
    calibration (cluster models only),
    whether foot flat was on, and the static trial's name."""

    subject: SubjectParameters
    method: str
    flat_foot: bool
    static: str
    clusters: ClusterCalibration | None = None

    def describe(self) -> str:
        """``"static offsets calibrated from S.c3d (KAD, foot flat off, 14 mm markers)"``."""
        return (f"static offsets calibrated from {self.static} ({self.method}, foot flat "
                f"{'on' if self.flat_foot else 'off'}, {self.subject.marker_diameter:g} mm markers)")  # fmt: skip


def calibrate_static(
    static: str | os.PathLike[str] | Trial,
    subject: SubjectParameters,
    *,
    preprocessing: Preprocessing = DEFAULT_PREPROCESSING,
    flat_foot: bool = False,
    model: str = "cgm1.0",
) -> StaticCalibration:
    """Fill the static trial's gaps as the walking trials' and calibrate ``subject`` on it
    (:func:`fuzzygait.kinematics.static_calibration`: every offset Nexus stores after a
    static run, the inter-ASIS distance when ``subject`` has none).

    The static trial is **not** low-pass filtered, whatever ``preprocessing.filter``
    says: every offset is a mean over the standing frames already, and a Butterworth
    over a short standing trial only adds its edge transients (measured on Nexus'
    foot-flat static trial, 6 Hz: StaticPlantFlex 1.3e-4 rad off Nexus' value,
    unfiltered 1e-8 rad).
    """
    trial = static if isinstance(static, Trial) else read_c3d(static)
    clean, _ = replace(preprocessing, filter=False).apply(trial)
    calibrated = static_calibration(clean, subject, flat_foot=flat_foot, model=model)
    method = knee_method(clean)
    clusters = None
    if model_version(model).clusters:
        clusters = calibrate_clusters(clean, calibrated, forefoot=model_version(model).forefoot)
        medial = all(clean.has_marker(side + m) for side in "LR" for m in ("KNM", "MED"))
        method = f"{model} clusters, {'KNM/MED' if medial else 'chord'} knee/ankle centres"
    return StaticCalibration(calibrated, method, flat_foot, trial.name, clusters)


def run_angles(
    dynamic: str | os.PathLike[str] | Trial,
    *,
    static: str | os.PathLike[str] | Trial | None = None,
    subject_file: str | os.PathLike[str] | None = None,
    preprocessing: Preprocessing = Preprocessing(),
    flat_foot: bool = False,
    marker_diameter: float | None = None,
    model: str = "cgm1.0",
) -> AnglesRun:
    """Run the joint-angle pipeline on one dynamic trial.

    Args:
        dynamic: the walking trial (path or :class:`Trial`).
        static: static calibration trial; without it the static offsets of the subject
            parameters are used as they are.
        subject_file: ``.toml`` or ``.vsk``; without it the dynamic trial's PROCESSING
            group.
        preprocessing: gap filling and filter options (the static trial: gap filling
            only, see :func:`calibrate_static`).
        flat_foot: static calibration with the flat-foot option (uses SoleDelta).
        marker_diameter: mm, in place of the subject parameters' (see :func:`resolve_subject`).
        model: a model version (:data:`fuzzygait.kinematics.versions.MODEL_VERSIONS`) or
            ``"auto"``: the richest the markers support (the choice and why in the notes).
    """
    raw = dynamic if isinstance(dynamic, Trial) else read_c3d(dynamic)
    trial, gaps = preprocessing.apply(raw)
    subject = resolve_subject(raw, subject_file, marker_diameter)
    notes = list(trial.notes)
    static_trial = None if static is None else static if isinstance(static, Trial) else read_c3d(static)
    if model == "auto":
        version, why = supported_version(raw, static_trial)
        model = version.name
        notes.append(f"model {model} ({why})")
    clusters = None
    if static_trial is not None:
        calibration = calibrate_static(static_trial, subject, preprocessing=preprocessing, flat_foot=flat_foot,
                                       model=model)  # fmt: skip
        subject, clusters = calibration.subject, calibration.clusters
        notes.append(calibration.describe())
    result = compute_lower_body(trial, subject, model=model, clusters=clusters)
    notes += result.notes
    notes += [f"{name} not computed: {why}" for name, why in result.unavailable.items()]
    events, source = trial_gait_events(trial)
    if source != "file":
        notes.append(f"gait events {source}")
    return AnglesRun(raw, trial, subject, result, gaps, events, source, notes)


def model_output_trial(run: AnglesRun) -> Trial:
    """The pre-processed trial with the computed angles and virtual markers as model
    outputs, the subject parameters used and the events (for ``--c3d-out``)."""
    out = run.trial.with_markers(run.trial.markers)
    for name, values in run.result.angles.items():
        out.outputs[name] = values
        out.output_kinds[name] = "angle"
    for name, values in run.result.virtual_markers.items():
        if name not in out.marker_labels:
            out.outputs[name] = values
            out.output_kinds[name] = "modeled_marker" if name.endswith("JC") else "segment_frame"
    out.parameters.update(run.subject.to_processing())
    out.events = list(run.events)
    return out



@dataclass(frozen=True)
class AngleOutputs:
    """Files to write from a run (each optional): the angles per frame (``table``, .csv or
    .parquet), their mean and SD over gait cycles (``cycles``) and the model-output C3D
    (``c3d``, see :func:`model_output_trial`)."""

    table: Path | None = None
    cycles: Path | None = None
    c3d: Path | None = None

    def write(self, run: AnglesRun) -> list[Path]:
        """Write the files asked for (folders created); returns them in that order."""
        written = []
        for path, make in ((self.table, run.angle_table), (self.cycles, run.cycle_statistics)):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                written.append(write_table(make(), path))
        if self.c3d is not None:
            self.c3d.parent.mkdir(parents=True, exist_ok=True)
            write_c3d(model_output_trial(run), self.c3d)
            written.append(self.c3d)
        return written


def angles_to_files(
    dynamic: str | os.PathLike[str] | Trial,
    outputs: AngleOutputs,
    *,
    static: str | os.PathLike[str] | Trial | None = None,
    subject_file: str | os.PathLike[str] | None = None,
    preprocessing: Preprocessing = Preprocessing(),
    flat_foot: bool = False,
    marker_diameter: float | None = None,
    model: str = "cgm1.0",
) -> tuple[AnglesRun, list[Path]]:
    """:func:`run_angles` and then ``outputs.write``: the run and the files written."""
    run = run_angles(dynamic, static=static, subject_file=subject_file, preprocessing=preprocessing,
                     flat_foot=flat_foot, marker_diameter=marker_diameter, model=model)  # fmt: skip
    return run, outputs.write(run)
