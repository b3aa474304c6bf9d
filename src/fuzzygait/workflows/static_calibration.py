"""How a walking trial's run is calibrated: on its static trial (:func:`calibrate_static`,
also what ``fuzzygait calibrate`` writes to a subject file) or, without one, from the
subject file's stored cluster calibration (:func:`stored_clusters`); what the joint-angle
pipeline (:func:`~fuzzygait.workflows.angles.run_angles`) takes of either is a
:class:`RunCalibration` (:func:`calibrate_run`, :func:`stored_calibration`)."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.options import Option
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.io import Trial, read_c3d
from fuzzygait.io.calibration_table import sidecar_path
from fuzzygait.kinematics import static_calibration
from fuzzygait.kinematics.calibration_file import StoredCalibration
from fuzzygait.kinematics.clusters import ClusterCalibration, calibrate_clusters
from fuzzygait.kinematics.kad import knee_method
from fuzzygait.kinematics.knee_ankle import RULE_NAMES, knee_ankle_rule
from fuzzygait.kinematics.marker_names import canonical_labels
from fuzzygait.kinematics.versions import model_version
from fuzzygait.mocap.marker_placement import moved_markers
from fuzzygait.mocap.sanity import check_trial
from fuzzygait.workflows.crosscheck import recover_flat_foot
from fuzzygait.workflows.preprocessing import DEFAULT_PREPROCESSING, Preprocessing
from fuzzygait.workflows.subject_resolution import for_static_calibration, inter_asis_notes

__all__ = ["RunCalibration", "StaticCalibration", "calibrate_run", "calibrate_static", "stored_calibration",
           "stored_clusters"]  # fmt: skip


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
            override = Option.NO_FLAT_FOOT if flat_foot else Option.FLAT_FOOT
            notes += (Finding(FindingKind.STATIC_CALIBRATION, f"foot flat {'on' if flat_foot else 'off'} as "
                              f"{Path(subject.source).name} sets it (feet {'' if flat_foot else 'not '}normalised to "
                              f"the static trial); {override} overrides it"),)  # fmt: skip
    calibrated = static_calibration(clean, subject, flat_foot=flat_foot, model=model,
                                    knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    method = knee_method(clean)
    clusters = None
    if model_version(model).clusters:
        clusters = calibrate_clusters(clean, calibrated, knee_ankle_centres, forefoot=model_version(model).forefoot)
        method = f"{model} clusters, {RULE_NAMES[knee_ankle_rule(clean, knee_ankle_centres)]} knee/ankle centres"
    return StaticCalibration(calibrated, method, flat_foot, trial.name, clusters, notes)


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


@dataclass(frozen=True)
class RunCalibration:
    """What a walking trial's run takes of its calibration.

    Attributes:
        subject: the subject parameters the model uses (calibrated on the static trial,
            or as resolved from the subject file or the trial).
        clusters: the static cluster calibration of a cluster model (CGM 2.3+), else None.
        notes: the findings on the calibration, in the order the run notes them (the
            moved markers last).
        moved: the segments whose markers moved between the static trial and the walking
            trial (:func:`fuzzygait.mocap.marker_placement.moved_markers`; empty without
            a static trial).
    """

    subject: SubjectParameters
    clusters: ClusterCalibration | None = None
    notes: tuple[Finding, ...] = ()
    moved: tuple[Finding, ...] = ()


def calibrate_run(
    static: Trial,
    walking: Trial,
    subject: SubjectParameters,
    subject_file: str | os.PathLike[str] | None,
    *,
    preprocessing: Preprocessing,
    flat_foot: bool | None,
    model: str,
    knee_ankle_centres: str | None,
) -> RunCalibration:
    """The run's calibration on its static trial (labels canonical): ``subject`` (the
    resolved parameters, :func:`~fuzzygait.workflows.subject_resolution.for_static_calibration`
    of them) calibrated by :func:`calibrate_static`, its notes (inter-ASIS distance, the
    calibration, the static trial's content checks) and the markers moved between the
    static trial and the pre-processed ``walking`` trial."""
    to_calibrate = for_static_calibration(subject, subject_file)
    calibration = calibrate_static(static, to_calibrate, preprocessing=preprocessing, flat_foot=flat_foot,
                                   model=model, knee_ankle_centres=knee_ankle_centres)  # fmt: skip
    notes = inter_asis_notes(subject, to_calibrate, calibration.subject, calibration.static)
    notes.append(Finding(FindingKind.STATIC_CALIBRATION, calibration.describe()))
    notes += [Finding(FindingKind.STATIC_TRIAL, f"static trial {calibration.static}: {note.message}", note.severity)
              for note in calibration.notes]  # fmt: skip
    moved = tuple(moved_markers(static, walking))
    return RunCalibration(calibration.subject, calibration.clusters, (*notes, *moved), moved)


def stored_calibration(
    stored: StoredCalibration, subject: SubjectParameters, subject_file: str | os.PathLike[str] | None, model: str
) -> RunCalibration:
    """The run's calibration without a static trial: ``subject`` as it is and, for a
    cluster model, the subject file's cluster calibration (:func:`stored_clusters`;
    noted), with a warning when the file was calibrated for another model."""
    clusters, notes = None, []
    if model_version(model).clusters:
        clusters = stored_clusters(stored, subject_file, model)
        notes.append(Finding(FindingKind.SUBJECT, f"cluster calibration from "
                             f"{stored.source.name if stored.source else subject_file}"
                             + (f" (static trial {stored.static})" if stored.static else "")))  # fmt: skip
    if stored.model is not None and stored.model != model:
        notes.append(Finding(FindingKind.SUBJECT, f"{Path(subject_file or '').name} was calibrated for "
                             f"{stored.model}; its offsets are used by {model} as they are",
                             Severity.WARNING))  # fmt: skip
    return RunCalibration(subject, clusters, tuple(notes))
