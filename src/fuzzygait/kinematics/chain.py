"""The Plug-in Gait lower-body chain of one trial: joint centres and segment frames.

:class:`LowerBodyChain` computes, on demand and once, every intermediate quantity of the
model for all frames at once (``(n, 3)`` positions in mm, ``(n, 3, 3)`` frames, lab
coordinates).  It is shared by the dynamic model (:mod:`fuzzygait.kinematics.model`) and
the static calibration (:mod:`fuzzygait.kinematics.static`).

Joint centres
-------------
* HJC: Davis regression in the pelvis frame (:func:`~fuzzygait.kinematics.joint_centres.davis_hjc_local`);
  Hara's with ``hip="hara"`` (:func:`~fuzzygait.kinematics.joint_centres.hara_hjc_local`).
* KJC: chord function on THI, HJC, KNE with ``KneeWidth / 2 + marker radius``, the
  THI wand turned by ``ThighRotation``.
* AJC: chord function on TIB, KJC, ANK with ``AnkleWidth / 2 + marker radius``, the TIB
  wand turned by ``ShankRotation``, then turned by ``AnkleAbAdd`` (see
  :mod:`fuzzygait.kinematics.joint_centres`; a static trial with a knee alignment device
  uses :class:`fuzzygait.kinematics.kad.StaticKneeChain` instead).
* Optional medial markers (``use_medial_markers=True``, CGM 2.x as pyCGM2, not Plug-in
  Gait): KJC on the KNE->KNM line at ``KneeWidth / 2 + marker radius`` from KNE, AJC on
  the ANK->MED line at ``AnkleWidth / 2 + marker radius`` from ANK (the midpoints when the
  widths match the markers); THI and TIB are then not used.  The segment frames are built
  the same way from these centres (the lateral
  marker direction is made orthogonal to the long axis).

Foot
----
In a dynamic trial the foot is the uncorrected foot (TOE, AJC, ankle axis) turned by the
static offsets.  In the static trial itself Nexus reports the *heel foot* instead
(``static_foot``): the same construction with HEE in place of AJC, i.e. z =
``unit(HEE - TOE)``, x = ``unit(y_ankle × z)`` (the uncorrected foot's ankle axis);
with the foot-flat option HEE is first brought to the height of TOE + ``SoleDelta``
along the laboratory vertical (lab Z).
Measured: Nexus 2 ``Static_trial.c3d`` (flat foot off) within 4.5e-5° of its ``LFO*``
frames, Nexus 1.4 ``PiG_Calibration-FlatFoot-Full.c3d`` (flat foot on) within 4.4e-5°.
The static calibration offsets are the angles of this heel foot's z axis in the
uncorrected foot (see :mod:`fuzzygait.kinematics.static`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.joint_centres import (
    abducted_joint_centre,
    davis_hjc_local,
    hara_hjc_local,
    rotated_chord_joint_centre,
)
from fuzzygait.kinematics.pelvis import inter_asis_distance, pelvis_frame
from fuzzygait.kinematics.segments import (
    corrected_foot,
    long_bone_frame,
    side_sign,
    uncorrected_foot,
    untorsioned_tibia,
)
from fuzzygait.kinematics.vectors import to_lab, unit

#: Segments of one leg in chain order.
LEG_SEGMENTS = ("thigh", "tibia", "foot")

#: Laboratory vertical axis (Z up) along which the foot-flat option levels HEE.
VERTICAL_AXIS = 2

#: Hip joint centre regressions (``hip=``): Davis (Plug-in Gait, CGM 1.x), Hara (CGM 2.x).
HIP_REGRESSIONS = ("davis", "hara")

#: ``static_foot`` values: the heel foot as is, or levelled (Plug-in Gait "foot flat").
STATIC_FOOT_MODES = ("heel", "flat")


def _memo(method: Callable[..., Any]) -> Callable[..., Any]:
    """Cache a ``LowerBodyChain`` method per side: every quantity is computed once."""

    @functools.wraps(method)
    def cached(self: LowerBodyChain, side: str = "") -> Any:
        key = (method.__name__, side)
        if key not in self._cache:
            self._cache[key] = method(self, side) if side else method(self)
        return self._cache[key]

    return cached


def pelvis_markers(trial: Trial) -> list[str]:
    """Markers of the pelvis: LASI, RASI and SACR when labelled, else LPSI and RPSI."""
    return ["LASI", "RASI"] + (["SACR"] if trial.has_marker("SACR") else ["LPSI", "RPSI"])


def segment_markers(trial: Trial, segment: str, side: str, use_medial_markers: bool) -> list[str]:
    """Every marker needed to build ``segment`` of ``side`` (including the chain above it).

    Args:
        segment: ``"pelvis"``, ``"thigh"``, ``"tibia"`` or ``"foot"``.
    """
    needed = pelvis_markers(trial)
    if segment == "pelvis":
        return needed
    own = {
        "thigh": ["KNE", "KNM"] if use_medial_markers else ["THI", "KNE"],
        "tibia": ["ANK", "MED"] if use_medial_markers else ["TIB", "ANK"],
        "foot": ["TOE"],
    }
    for seg in LEG_SEGMENTS[: LEG_SEGMENTS.index(segment) + 1]:
        needed += [side + m for m in own[seg]]
    return needed


def required_markers(trial: Trial, use_medial_markers: bool) -> list[str]:
    """All markers of the complete lower-body chain (both feet)."""
    labels = pelvis_markers(trial)
    for side in "LR":
        labels += segment_markers(trial, "foot", side, use_medial_markers)[len(pelvis_markers(trial)) :]
    return labels


class LowerBodyChain:
    """Lazily computed joint centres and frames of a trial (see the module docstring).

    Args:
        trial: markers in mm.
        subject: validated subject parameters; ``inter_asis_distance`` None means "measure
            it on this trial".
        use_medial_markers: KJC/AJC on the KNE-KNM / ANK-MED lines instead of the chord.
        static_foot: None (dynamic trial: foot from the static offsets), ``"heel"`` or
            ``"flat"``: the foot of a static trial as Nexus reports it, built from HEE and
            TOE (``"flat"``: HEE levelled to TOE + ``SoleDelta``), see the module
            docstring.  HEE is then needed.
        hip: ``"davis"`` (Plug-in Gait) or ``"hara"`` (CGM 2.1+) hip joint centres.
        single_tibia: CGM 1.1+: the knee angles and the foot's ankle axis use the
            marker-based (torsioned) tibia, as the ankle angles do; Plug-in Gait's knee
            uses the tibia turned back by ``TibialTorsion``.
        pelvis_sequence: ``"TOR"`` (Plug-in Gait: tilt, obliquity, rotation) or
            ``"ROT"`` (CGM 1.1+: rotation, obliquity, tilt) pelvis angles.

    Accessing a quantity whose markers are absent raises :class:`MarkerError`.
    """

    def __init__(
        self,
        trial: Trial,
        subject: SubjectParameters,
        use_medial_markers: bool = False,
        static_foot: str | None = None,
        hip: str = "davis",
        single_tibia: bool = False,
        pelvis_sequence: str = "TOR",
    ):
        if static_foot is not None and static_foot not in STATIC_FOOT_MODES:
            raise ValueError(f"static_foot must be None, 'heel' or 'flat'; got {static_foot!r}")
        if hip not in HIP_REGRESSIONS:
            raise ValueError(f"hip must be one of {HIP_REGRESSIONS}; got {hip!r}")
        if pelvis_sequence not in ("TOR", "ROT"):
            raise ValueError(f"pelvis_sequence must be 'TOR' or 'ROT'; got {pelvis_sequence!r}")
        self.hip = hip
        self.single_tibia = single_tibia
        self.pelvis_sequence = pelvis_sequence
        self.trial = trial
        self.subject = subject
        self.use_medial_markers = use_medial_markers
        self.static_foot = static_foot
        self._cache: dict[tuple[str, str], Any] = {}

    def marker(self, label: str) -> np.ndarray:
        """Trajectory of ``label`` (raises MarkerError when absent)."""
        return self.trial.marker(label)

    def missing(self, segment: str, side: str = "L") -> list[str]:
        """Markers of ``segment`` (and the chain above it) missing from the trial."""
        return [
            m
            for m in segment_markers(self.trial, segment, side, self.use_medial_markers)
            if not self.trial.has_marker(m)
        ]

    # ------------------------------------------------------------------ pelvis
    def sacrum(self) -> np.ndarray:
        """SACR, or the PSIS midpoint when there is no SACR marker, mm."""
        if self.trial.has_marker("SACR"):
            return self.marker("SACR")
        return 0.5 * (self.marker("LPSI") + self.marker("RPSI"))

    @_memo
    def pelvis(self) -> tuple[np.ndarray, np.ndarray]:
        """``(ASIS midpoint, pelvis frame)``."""
        return pelvis_frame(self.marker("LASI"), self.marker("RASI"), self.sacrum())

    @_memo
    def inter_asis_distance(self) -> float:
        """The subject's inter-ASIS distance, or this trial's mean LASI-RASI distance."""
        if self.subject.inter_asis_distance is not None:
            return self.subject.inter_asis_distance
        return inter_asis_distance(self.marker("LASI"), self.marker("RASI"))

    @_memo
    def hjc(self, side: str) -> np.ndarray:
        """Hip joint centre (Davis, or Hara with ``hip="hara"``), mm."""
        origin, frame = self.pelvis()
        s = self.subject
        if self.hip == "hara":
            return to_lab(frame, origin, hara_hjc_local(s.side(side).leg_length, s.marker_radius, side))
        local = davis_hjc_local(
            0.5 * (s.left.leg_length + s.right.leg_length),
            s.side(side).asis_trochanter,
            self.inter_asis_distance(),
            s.marker_radius,
            side,
        )
        return to_lab(frame, origin, local)

    # ------------------------------------------------------------------ leg
    def _offset(self, width: float) -> float:
        return width / 2.0 + self.subject.marker_radius

    @_memo
    def kjc(self, side: str) -> np.ndarray:
        """Knee joint centre, mm."""
        if self.use_medial_markers:
            kne, offset = self.marker(side + "KNE"), self._offset(self.subject.side(side).knee_width)
            return kne + offset * unit(self.marker(side + "KNM") - kne)
        params = self.subject.side(side)
        thi, kne = self.marker(side + "THI"), self.marker(side + "KNE")
        rotation = side_sign(side) * params.thigh_rotation
        return rotated_chord_joint_centre(thi, self.hjc(side), kne, self._offset(params.knee_width), rotation)

    @_memo
    def ajc(self, side: str) -> np.ndarray:
        """Ankle joint centre, mm."""
        if self.use_medial_markers:
            ank, offset = self.marker(side + "ANK"), self._offset(self.subject.side(side).ankle_width)
            return ank + offset * unit(self.marker(side + "MED") - ank)
        params = self.subject.side(side)
        return self.chord_ajc(side, params.shank_rotation, params.ankle_abadd)

    def chord_ajc(self, side: str, shank_rotation: float | np.ndarray, ankle_abadd: float | np.ndarray) -> np.ndarray:
        """Plug-in Gait's ankle centre with these offsets (rad, scalars or one per frame):
        the chord on TIB, KJC, ANK with the TIB wand turned by ``ShankRotation``, then
        turned about ANK by ``AnkleAbAdd``; mm."""
        tib, ank, kjc = self.marker(side + "TIB"), self.marker(side + "ANK"), self.kjc(side)
        offset = self._offset(self.subject.side(side).ankle_width)
        centre = rotated_chord_joint_centre(tib, kjc, ank, offset, side_sign(side) * shank_rotation)
        return abducted_joint_centre(centre, kjc, ank, ankle_abadd)

    @_memo
    def thigh(self, side: str) -> np.ndarray:
        """Thigh (femur) frame, origin KJC."""
        return long_bone_frame(self.hjc(side), self.kjc(side), self.marker(side + "KNE"), side)

    @_memo
    def torsioned_tibia(self, side: str) -> np.ndarray:
        """Marker-based tibia frame (from KJC, AJC, ANK), origin AJC: the proximal frame
        of the ankle angles."""
        return long_bone_frame(self.kjc(side), self.ajc(side), self.marker(side + "ANK"), side)

    def ankle_tibia(self, side: str) -> np.ndarray:
        """Proximal frame of the ankle angles: the torsioned tibia."""
        return self.torsioned_tibia(side)

    @_memo
    def tibia(self, side: str) -> np.ndarray:
        """Untorsioned tibia frame, origin AJC: distal frame of the knee angles, ``L/RTI*``
        and the ankle axis of the foot (with ``single_tibia`` the torsioned tibia)."""
        if self.single_tibia:
            return self.torsioned_tibia(side)
        return untorsioned_tibia(self.torsioned_tibia(side), self.subject.side(side).tibial_torsion, side)

    @_memo
    def uncorrected_foot(self, side: str) -> np.ndarray:
        """Foot frame before the static offsets (z from TOE to AJC; ankle axis: the
        untorsioned tibia's y axis)."""
        ankle_axis = self.tibia(side)[:, :, 1]
        return uncorrected_foot(self.ajc(side), self.marker(side + "TOE"), ankle_axis)

    @_memo
    def heel_foot(self, side: str) -> np.ndarray:
        """Static-trial foot from TOE and HEE (HEE levelled when ``static_foot="flat"``);
        z from TOE to HEE, x dorsal."""
        toe, hee = self.marker(side + "TOE"), self.marker(side + "HEE")
        if self.static_foot == "flat":
            hee = hee.copy()
            hee[:, VERTICAL_AXIS] = toe[:, VERTICAL_AXIS] + self.subject.side(side).sole_delta
        return uncorrected_foot(hee, toe, self.tibia(side)[:, :, 1])

    @_memo
    def foot(self, side: str) -> np.ndarray:
        """Anatomical Plug-in Gait foot frame (z along the foot, backwards; x dorsal)."""
        if self.static_foot is not None:
            return self.heel_foot(side)
        p = self.subject.side(side)
        return corrected_foot(self.uncorrected_foot(side), p.static_plant_flex, p.static_rot_off, side)


__all__ = ["LowerBodyChain", "pelvis_markers", "required_markers", "segment_markers"]
