"""Our joint angles against the ones a C3D file already carries (Nexus' or pyCGM2's).

The first thing a lab does when it switches tools is to compare the new angles with the
old ones.  Whenever a trial holds stored angle outputs, the angle pipeline computes the
model once more on the file's own markers (no gap filling, no low-pass: the stored angles
were made from them) with the same subject parameters and calibration, and compares:

* **Which stored set is Plug-in Gait's.**  Nexus writes Plug-in Gait's angles as
  ``LKneeAngles``; a file that also holds another model's (a custom pipeline, or a
  second run) may carry Plug-in Gait's as ``LViconKneeAngles`` instead.  Where both
  ``L/RVicon<X>Angles`` and ``L/R<X>Angles`` exist, the ``Vicon``-prefixed set is
  Plug-in Gait's; otherwise the unprefixed names are.  Suffixed names (pyCGM2's or our
  own ``LKneeAngles_CGM_2.3``) are not compared.
* **Per angle group** (``LKneeAngles``: its three components) the largest absolute
  difference over the frames where both are finite, deg; per component RMS and max
  (:class:`ComponentDifference`, the table of ``fuzzygait compare``).
* **Standing trials** are modelled as Nexus models its static trials (the foot from HEE
  and TOE, levelled with foot flat), since their stored outputs are a static run's.
* **Anything over** :data:`FLAG_DEG` is flagged, with the likeliest input that explains it
  where it can be told: a marker diameter other than the one the file's outputs were made
  with, subject values or static offsets other than the file's ``PROCESSING`` ones.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinematics.clusters import ClusterCalibration
from fuzzygait.kinematics.marker_size import RecoveredDiameter
from fuzzygait.mocap.sanity import MOTIONLESS_TRAVEL, motion_ranges

#: A group differing by more than this (deg) is flagged.
FLAG_DEG = 0.1
#: "Agree" in the notes: every group within this (deg).
AGREE_DEG = 0.01
#: Subject values that differ by more than these are named as likely causes (mm, rad, kg).
LENGTH_TOLERANCE_MM = 0.05
ANGLE_TOLERANCE_RAD = 1e-4
AXES = ("X", "Y", "Z")
#: The angle groups the foot-flat setting changes.
FOOT_GROUPS = ("LAnkleAngles", "RAnkleAngles", "LFootProgressAngles", "RFootProgressAngles")
#: Endings of the PROCESSING names that are static offsets (rad).
OFFSET_SUFFIXES = ("Rotation", "Torsion", "AbAdd", "PlantFlex", "RotOff")


@dataclass(frozen=True)
class ComponentDifference:
    """One angle component, ours minus the file's (deg), over the frames both have.

    Attributes:
        angle: our output name (``"LKneeAngles"``).
        axis: ``"X"``, ``"Y"`` or ``"Z"`` (sagittal, frontal, transverse).
        stored: the file's output compared with (``"LKneeAngles"`` or ``"LViconKneeAngles"``).
        frames: frames where both are finite.
        rms, max: RMS and largest absolute difference, deg (NaN without common frames).
    """

    angle: str
    axis: str
    stored: str
    frames: int
    rms: float
    max: float


def stored_angle_names(trial: Trial, names: list[str]) -> dict[str, str]:
    """Our angle name -> the file's Plug-in Gait output to compare with (see the module
    docstring: the ``Vicon``-prefixed set where both exist)."""
    found = {}
    for name in names:
        vicon = f"{name[0]}Vicon{name[1:]}"
        if vicon in trial.outputs and name in trial.outputs:
            found[name] = vicon
        elif name in trial.outputs:
            found[name] = name
        elif vicon in trial.outputs:
            found[name] = vicon
    return found


def compare_angles(ours: Mapping[str, np.ndarray], trial: Trial) -> list[ComponentDifference]:
    """Every component of ``ours`` (``(n_frames, 3)`` deg, the trial's frames) that the
    file carries, against the file's stored values; ``[]`` when it carries none."""
    rows = []
    for name, stored in stored_angle_names(trial, list(ours)).items():
        theirs = np.asarray(trial.outputs[stored], dtype=float)
        mine = np.asarray(ours[name], dtype=float)
        if mine.shape != theirs.shape:
            continue
        for k, axis in enumerate(AXES):
            both = np.isfinite(mine[:, k]) & np.isfinite(theirs[:, k])
            diff = mine[both, k] - theirs[both, k]
            rms = float(np.sqrt(np.mean(diff**2))) if diff.size else float("nan")
            largest = float(np.max(np.abs(diff))) if diff.size else float("nan")
            rows.append(ComponentDifference(name, axis, stored, int(both.sum()), rms, largest))
    return rows


def group_maxima(rows: list[ComponentDifference]) -> dict[str, float]:
    """Largest difference per angle group (deg), in the rows' order; NaN groups left out."""
    out: dict[str, float] = {}
    for row in rows:
        if np.isfinite(row.max):
            out[row.angle] = max(out.get(row.angle, 0.0), row.max)
    return out


def likely_causes(
    used: SubjectParameters, file_parameters: Mapping[str, float], recovered: RecoveredDiameter | None
) -> list[str]:
    """Inputs of ours that differ from the ones the file's outputs were made with: the
    marker diameter (when the file's outputs tell it), then every ``PROCESSING`` value
    the file states that differs from ours (lengths beyond :data:`LENGTH_TOLERANCE_MM`,
    offsets beyond :data:`ANGLE_TOLERANCE_RAD`)."""
    causes = []
    if recovered is not None and recovered.diameter is not None and abs(
        recovered.diameter - used.marker_diameter
    ) > 0.05:
        causes.append(f"marker diameter ({used.marker_diameter:g} mm used; the file's outputs were made with "
                      f"{recovered.diameter:.2f} mm)")  # fmt: skip
    ours = used.to_processing()
    differing: list[tuple[str, bool]] = []  # (text, is an offset)
    for name, value in file_parameters.items():
        if name not in ours or name in ("MarkerDiameter", "Bodymass", "Height"):
            continue
        if name.endswith("AsisTrocanterDistance") and value == 0.0:
            continue  # "from the regression": ours holds the regression's value
        offset = name.endswith(OFFSET_SUFFIXES)
        if abs(ours[name] - value) > (ANGLE_TOLERANCE_RAD if offset else LENGTH_TOLERANCE_MM):
            differing.append((f"{name} {ours[name]:.4g} vs {value:.4g} {'rad' if offset else 'mm'}", offset))
    if differing:
        kind = "static offsets" if all(offset for _, offset in differing) else "subject values"
        texts = [text for text, _ in differing]
        causes.append(f"{kind} other than the file's PROCESSING ({', '.join(texts[:6])}"
                      + (f", {len(texts) - 6} more" if len(texts) > 6 else "") + ")")  # fmt: skip
    return causes


@dataclass(frozen=True)
class CrossCheck:
    """Ours against the file's stored angles.

    Attributes:
        rows: per component (:func:`compare_angles`), ours computed on the file's markers.
        written: largest difference per group of the angles the run writes (after gap
            filling and low-pass), deg.
        causes: likeliest inputs behind a flagged difference (:func:`likely_causes`).
        prefixed: the stored set compared is the ``Vicon``-prefixed one.
    """

    rows: list[ComponentDifference]
    written: dict[str, float]
    causes: list[str]
    prefixed: bool

    @property
    def groups(self) -> dict[str, float]:
        """Largest difference per angle group, ours on the file's markers, deg."""
        return group_maxima(self.rows)

    @property
    def flagged(self) -> dict[str, float]:
        """The groups over :data:`FLAG_DEG`."""
        return {name: value for name, value in self.groups.items() if value > FLAG_DEG}

    def with_cause(self, cause: str) -> CrossCheck:
        """The same check with ``cause`` first among the likely causes when anything is
        flagged (else unchanged)."""
        return replace(self, causes=[cause, *self.causes]) if self.flagged else self

    def notes(self) -> list[Finding]:
        """One or two findings for the run's notes (none without stored angles): a warning
        when a group differs by more than :data:`FLAG_DEG`."""
        groups = self.groups
        if not groups:
            return []
        which = "LVicon*/RVicon*Angles, Plug-in Gait's beside other angle outputs" if self.prefixed else "L/R*Angles"
        listed = ", ".join(f"{name} {value:.4f}°" for name, value in groups.items())
        worst = max(groups.values())
        if worst <= AGREE_DEG:
            head = f"agree within {AGREE_DEG:g}° in every group"
        elif worst <= FLAG_DEG:
            head = f"agree within {FLAG_DEG:g}° in every group"
        else:
            head = (f"DIFFER by more than {FLAG_DEG:g}° in {', '.join(self.flagged)}; likely cause: "
                    + ("; ".join(self.causes) if self.causes else "not told by the file (its markers, "
                       "model or options differ from ours)"))  # fmt: skip
        severity = Severity.WARNING if worst > FLAG_DEG else Severity.INFO
        lines = [Finding(FindingKind.CROSSCHECK, f"the file's stored angles ({which}) against ours on the file's "
                         f"markers: {head} (largest difference per group: {listed})", severity)]  # fmt: skip
        written = max(self.written.values(), default=0.0)
        if written > AGREE_DEG:
            lines.append(Finding(FindingKind.CROSSCHECK, f"the angles written, gap-filled and low-pass filtered, "
                                 f"differ from the file's stored ones by up to {written:.3f}° through that "
                                 "pre-processing"))  # fmt: skip
        return lines


def cross_check(
    file_markers_angles: Mapping[str, np.ndarray],
    written_angles: Mapping[str, np.ndarray],
    raw: Trial,
    used: SubjectParameters,
    recovered: RecoveredDiameter | None,
) -> CrossCheck | None:
    """Compare ``file_markers_angles`` (ours on the file's markers) and ``written_angles``
    (the run's) with the angles ``raw`` stores; None when it stores none."""
    rows = compare_angles(file_markers_angles, raw)
    if not rows:
        return None
    written = group_maxima(compare_angles(written_angles, raw))
    prefixed = any(row.stored != row.angle for row in rows)
    flagged = any(row.max > FLAG_DEG for row in rows if np.isfinite(row.max))
    causes = likely_causes(used, raw.parameters, recovered) if flagged else []
    return CrossCheck(rows, written, causes, prefixed)


def is_standing(trial: Trial) -> bool:
    """The trial stands still (pelvis and feet within the motionless-trial range of
    :func:`fuzzygait.mocap.sanity.motion_ranges`): Nexus' outputs of it are a static
    trial's."""
    ranges = motion_ranges(trial)
    return "pelvis" in ranges and max(ranges.values()) < MOTIONLESS_TRAVEL


def check_run(
    on_file: Trial,
    written_angles: Mapping[str, np.ndarray],
    raw: Trial,
    subject: SubjectParameters,
    recovered: RecoveredDiameter | None,
    *,
    model: str,
    clusters: ClusterCalibration | None,
    flat_foot: bool | None,
) -> CrossCheck | None:
    """The cross-check of a run: the model once more on ``on_file`` (the file's markers,
    content-checked, neither filled nor filtered) with the run's ``subject``, ``model``
    and ``clusters``, against what ``raw`` stores.  A standing trial is modelled as Nexus
    models its static trials (:func:`~fuzzygait.kinematics.compute_lower_body`'s
    ``static_foot``: ``"flat"`` with foot flat, else ``"heel"``).  With ``flat_foot``
    None (nobody set it) a standing trial takes the setting its stored angles were made
    with (:func:`recover_flat_foot`, off when they do not tell); when the foot angles of
    a given setting differ but the other setting agrees, that setting is named."""
    if not stored_angle_names(raw, list(written_angles)):
        return None
    standing = is_standing(on_file)
    if flat_foot is None:
        flat_foot = bool(standing and recover_flat_foot(on_file, subject, model))
    foot = ("flat" if flat_foot else "heel") if standing else None
    angles = compute_lower_body(on_file, subject, model=model, clusters=clusters, static_foot=foot).angles
    check = cross_check(angles, written_angles, raw, subject, recovered)
    if check is None or not check.flagged or not standing:
        return check
    other = "heel" if flat_foot else "flat"
    alternative = compute_lower_body(on_file, subject, model=model, clusters=clusters, static_foot=other).angles
    if max(group_maxima(compare_angles(alternative, raw)).values(), default=np.inf) <= AGREE_DEG:
        return check.with_cause(f"foot flat (the file's static outputs were made with foot flat "
                                f"{'off' if flat_foot else 'on'})")  # fmt: skip
    return check


def recover_flat_foot(static: Trial, subject: SubjectParameters, model: str = "cgm1.0") -> bool | None:
    """Plug-in Gait's foot-flat setting of the static run whose outputs ``static`` stores:
    True (False) when its stored ankle and foot angles are reproduced within
    :data:`AGREE_DEG` with foot flat on (off) and not with the other; None when the trial
    stores none, neither or both agree (a trial whose heel and toe are level)."""
    if not stored_angle_names(static, ["LAnkleAngles", "RAnkleAngles"]) or not is_standing(static):
        return None
    agree = {}
    for flat, foot in ((True, "flat"), (False, "heel")):
        angles = compute_lower_body(static, subject, model=model, static_foot=foot).angles
        groups = group_maxima(compare_angles(angles, static))
        feet = [groups[name] for name in FOOT_GROUPS if name in groups]
        agree[flat] = bool(feet) and max(feet) <= AGREE_DEG
    return agree[True] if agree[True] != agree[False] else None
