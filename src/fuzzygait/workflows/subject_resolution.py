"""Which subject parameters a run uses, and what it says about the ones no file states.

A C3D file of Vicon Nexus holds the subject's measurements in its ``PROCESSING`` group
but not the marker diameter (a setting of Nexus' pipeline); a subject file may or may not
state it.  :func:`settle_marker_diameter` decides, in this order:

1. a diameter given by the user (command line or API) -- checked against the trial's own
   Plug-in Gait outputs when it carries them;
2. the subject file's ``MarkerDiameter`` -- checked the same way;
3. the diameter recovered from the trial's own outputs
   (:func:`fuzzygait.kinematics.marker_size.recover_marker_diameter`: Nexus' hip joint
   centres in its pelvis frame through the Davis regression);
4. the default :data:`~fuzzygait.io.subject.DEFAULT_MARKER_DIAMETER`, said to be assumed.

A stated diameter that differs from the recovered one by more than
:data:`~fuzzygait.kinematics.marker_size.CONTRADICTION_MM` is a warning naming both.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.options import Option
from fuzzygait.core.trial import Trial
from fuzzygait.io.subject import DEFAULT_MARKER_DIAMETER, SubjectParameters, read_subject, subject_from_processing
from fuzzygait.kinematics.marker_size import CONTRADICTION_MM, RecoveredDiameter, recover_marker_diameter
from fuzzygait.workflows.session import subject_file_name, subject_mismatch

#: Marker diameters (mm) taken as plausible (the subject parameters' check).
MARKER_DIAMETER_RANGE = (1.0, 40.0)


def check_marker_diameter(marker_diameter: float) -> float:
    """``marker_diameter`` (mm) if plausible, else one line saying what to give."""
    low, high = MARKER_DIAMETER_RANGE
    if not (math.isfinite(marker_diameter) and low <= marker_diameter <= high):
        raise FuzzyGaitError(f"marker diameter {marker_diameter:g} mm is implausible: give it in mm "
                             f"({low:g} to {high:g}, e.g. {Option.MARKER_DIAMETER} 14)")  # fmt: skip
    return float(marker_diameter)


def resolve_subject(
    trial: Trial, subject_file: str | os.PathLike[str] | None, marker_diameter: float | None = None
) -> SubjectParameters:
    """Subject parameters from ``subject_file`` or else the trial's PROCESSING group, with
    ``marker_diameter`` (mm) in place of theirs when given.  (The diameter a run uses,
    when neither states one, is settled by :func:`settle_marker_diameter`.)"""
    if subject_file is not None:
        subject = read_subject(subject_file)
    elif not trial.parameters:
        raise FuzzyGaitError(
            f"{trial.name}: no subject parameters in the file (no PROCESSING group); "
            f"give a subject file with {Option.SUBJECT} SUBJECT.toml or .vsk"
        )
    else:
        subject = subject_from_processing(trial.parameters, source=f"{trial.name} PROCESSING group")
    if marker_diameter is None:
        return subject
    return replace(subject, marker_diameter=check_marker_diameter(marker_diameter), marker_diameter_stated=True)


@dataclass(frozen=True)
class DiameterChoice:
    """The marker diameter a run uses and what to tell the user about it.

    Attributes:
        subject: the subject parameters with that diameter.
        recovered: what the trials' own outputs gave (None: no trial had them).
        note: the run's finding on it (:attr:`~fuzzygait.core.findings.FindingKind.MARKER_DIAMETER`:
            where the diameter comes from).
        warning: a contradiction between a stated and the recovered diameter ("" none).
    """

    subject: SubjectParameters
    recovered: RecoveredDiameter | None
    note: Finding
    warning: str = ""


def _recover(subject: SubjectParameters, evidence: Sequence[Trial | None]) -> tuple[RecoveredDiameter | None, str]:
    """The first trial whose outputs give a diameter, and its name; else the last
    attempt's reason (None when no trial carries the outputs at all)."""
    attempt: RecoveredDiameter | None = None
    where = ""
    for trial in evidence:
        if trial is None:
            continue
        found = recover_marker_diameter(trial, subject)
        if found.diameter is not None:
            return found, Path(trial.name).name
        if found.estimates and attempt is None:
            attempt, where = found, Path(trial.name).name
    return attempt, where


def settle_marker_diameter(
    subject: SubjectParameters, given: float | None, evidence: Sequence[Trial | None]
) -> DiameterChoice:
    """The marker diameter of a run (see the module docstring for the order).

    Args:
        subject: the subject parameters as read (``marker_diameter_stated`` tells whether
            their source states the diameter).
        given: mm, the user's diameter, or None.
        evidence: trials whose stored Plug-in Gait outputs may tell the diameter, in
            order of preference (the walking trial, then the static one); None entries
            are skipped.
    """
    if given is not None:
        subject = replace(subject, marker_diameter=check_marker_diameter(given), marker_diameter_stated=True)
        stated_by = "as given"
    elif subject.marker_diameter_stated:
        stated_by = f"from {Path(subject.source).name or 'the subject parameters'}"
    else:
        stated_by = ""
    recovered, where = _recover(subject, evidence)
    if stated_by:
        note = f"marker diameter {subject.marker_diameter:g} mm ({stated_by})"
        if recovered is None or recovered.diameter is None:
            return DiameterChoice(subject, recovered, _diameter(note))
        if abs(recovered.diameter - subject.marker_diameter) <= CONTRADICTION_MM:
            return DiameterChoice(subject, recovered, _diameter(f"{note}; {where}'s own Plug-in Gait outputs agree "
                                                                f"({recovered.diameter:.2f} mm)"))  # fmt: skip
        warning = (f"marker diameter {subject.marker_diameter:g} mm ({stated_by}) contradicts {where}'s own "
                   f"Plug-in Gait outputs, made with {recovered.diameter:.2f} mm markers ({recovered.describe(where)}):"
                   " the joint centres and angles will differ from the file's; use the diameter the file was "
                   "processed with unless it is wrong")  # fmt: skip
        return DiameterChoice(subject, recovered, _diameter(note), warning)
    if recovered is not None and recovered.diameter is not None:
        subject = replace(subject, marker_diameter=recovered.diameter)
        return DiameterChoice(subject, recovered,
                              _diameter(f"marker diameter {recovered.diameter:g} mm, {recovered.describe(where)}"))
    why = ("no subject file or C3D states it" + (f", and {recovered.reason}" if recovered is not None
                                                 else " and the files hold no Plug-in Gait hip joint centres "
                                                      "to recover it from"))  # fmt: skip
    subject = replace(subject, marker_diameter=DEFAULT_MARKER_DIAMETER)
    note = (f"marker diameter {DEFAULT_MARKER_DIAMETER:g} mm assumed ({why}); give MarkerDiameter in the subject "
            "file or the marker diameter on the command line if the markers were of another size")  # fmt: skip
    return DiameterChoice(subject, recovered, _diameter(note, Severity.WARNING))


def _diameter(message: str, severity: Severity = Severity.INFO) -> Finding:
    """The marker-diameter finding of a run."""
    return Finding(FindingKind.MARKER_DIAMETER, message, severity)


#: A PROCESSING group's InterAsisDistance that differs from the static trial's by more
#: than this (mm) is named in a note.
INTER_ASIS_NOTE_MM = 0.5


def for_static_calibration(
    subject: SubjectParameters, subject_file: str | os.PathLike[str] | None
) -> SubjectParameters:
    """``subject`` as the static calibration is to take it: the inter-ASIS distance is
    measured on the static trial unless the user's own subject file sets a non-zero one
    (a C3D ``PROCESSING`` group's value is an earlier calibration's, of another static
    trial perhaps, and Plug-in Gait measures it afresh on each static run)."""
    return subject if subject_file is not None else replace(subject, inter_asis_distance=None)


def inter_asis_notes(
    stated: SubjectParameters, used: SubjectParameters, calibrated: SubjectParameters, static_name: str
) -> list[Finding]:
    """What the run says about the inter-ASIS distance of a static calibration: measured
    on ``static_name`` (``used`` gave none), and how far a value ``stated`` by a PROCESSING
    group lies from it when more than :data:`INTER_ASIS_NOTE_MM`."""
    measured = calibrated.inter_asis_distance
    if used.inter_asis_distance is not None or measured is None:
        return []
    source = Path(stated.source).name or "the subject"
    note = f"InterAsisDistance measured on the static trial {static_name}: {measured:.2f} mm"
    if stated.inter_asis_distance is None:
        text = f"{note} ({source} gives none, or 0: Plug-in Gait's 'compute it from the ASIS markers')"
    elif (differs := abs(stated.inter_asis_distance - measured)) > INTER_ASIS_NOTE_MM:
        text = (f"{note}, not {source}'s {stated.inter_asis_distance:.2f} mm ({differs:.2f} mm apart: an earlier "
                "calibration's value; the static trial given is measured afresh, as Plug-in Gait does)")
    else:
        text = f"{note} ({source}: {stated.inter_asis_distance:.2f} mm)"
    return [Finding(FindingKind.SUBJECT, text)]


#: Leg length against the static trial's ASIS-malleolus marker distance (ASI-MED, else
#: ASI-ANK): a tape measure over the thigh and knee runs 1-3 % longer than the straight
#: line, the markers sit a radius off the bone and a tape reads within 1-2 cm; more than
#: this fraction apart is not a measurement of this subject.
LEG_LENGTH_MARGIN = 0.10
#: Knee (ankle) width against the static trial's KNE-KNM (ANK-MED) distance less one
#: marker diameter: calipers press the soft tissue that the markers sit on; beyond both
#: of these (mm and fraction) the width is not this subject's.
WIDTH_MARGIN_MM = 15.0
WIDTH_MARGIN = 0.20


def _median_distance(trial: Trial, a: str, b: str) -> float | None:
    if not (trial.has_marker(a) and trial.has_marker(b)):
        return None
    distance = np.linalg.norm(trial.marker(a) - trial.marker(b), axis=1)
    distance = distance[np.isfinite(distance)]
    return float(np.median(distance)) if distance.size else None


def measurement_warnings(subject: SubjectParameters, static: Trial) -> list[str]:
    """Subject measurements that the static trial's markers contradict beyond a plausible
    margin (:data:`LEG_LENGTH_MARGIN`, :data:`WIDTH_MARGIN_MM` and :data:`WIDTH_MARGIN`):
    leg length against the ASIS-malleolus distance, knee and ankle widths against the
    KNE-KNM and ANK-MED distances less a marker diameter, where the markers are there."""
    found = []
    source = Path(subject.source).name or "the subject parameters"
    for side in "LR":
        values = subject.side(side)
        malleolus = "MED" if static.has_marker(side + "MED") else "ANK"
        measured = _median_distance(static, side + "ASI", side + malleolus)
        if measured is not None and abs(measured - values.leg_length) > LEG_LENGTH_MARGIN * values.leg_length:
            found.append(f"{source} gives {side}LegLength {values.leg_length:g} mm but the static trial "
                         f"{Path(static.name).name}'s {side}ASI-{side}{malleolus} distance is {measured:.0f} mm "
                         f"(more than {LEG_LENGTH_MARGIN:.0%} apart): check the measurement and the subject file")
        for name, width, lateral, medial in (("KneeWidth", values.knee_width, "KNE", "KNM"),
                                             ("AnkleWidth", values.ankle_width, "ANK", "MED")):  # fmt: skip
            between = _median_distance(static, side + lateral, side + medial)
            if between is None:
                continue
            measured = between - subject.marker_diameter
            if abs(measured - width) > max(WIDTH_MARGIN_MM, WIDTH_MARGIN * width):
                found.append(f"{source} gives {side}{name} {width:g} mm but the static trial's {side}{lateral}-"
                             f"{side}{medial} distance less the {subject.marker_diameter:g} mm marker diameter is "
                             f"{measured:.0f} mm: check the measurement and the subject file")
    return found


def subject_warnings(
    trial: Trial, subject_file: str | os.PathLike[str] | None, static: Trial | None, subject: SubjectParameters
) -> list[str]:
    """What a run warns of about its subject: a subject file or static trial of another
    subject than ``trial``'s (C3D ``SUBJECTS:NAMES``; the batch report's rule,
    :func:`fuzzygait.workflows.session.subject_mismatch`), and measurements the static
    trial contradicts (:func:`measurement_warnings`)."""
    found = []
    if subject_file is not None:
        path = Path(subject_file)
        found.append(subject_mismatch(Path(trial.name).name, trial.subject, "subject file", path,
                                      subject_file_name(path)))  # fmt: skip
    if static is not None and static is not trial:
        found.append(subject_mismatch(Path(trial.name).name, trial.subject, "static trial", Path(static.name),
                                      static.subject))  # fmt: skip
    warnings = [w for w in found if w]
    if static is not None:
        warnings += measurement_warnings(subject, static)
    return warnings
