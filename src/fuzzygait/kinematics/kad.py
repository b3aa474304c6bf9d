"""Plug-in Gait static calibration with a knee alignment device (KAD) and medial malleoli.

The definitions below were inferred from Vicon Nexus 2.3 output (``pig-options/
PiGKad_Calibration.c3d`` and ``PiGKadMed_Calibration.c3d``: Nexus' virtual ``L/RKNE``,
its segment-frame markers and the offsets in ``PROCESSING``); with them every offset
Nexus stored is reproduced within 6.5e-9 rad and the joint centres within 6e-5 mm.

KAD (markers ``KAX``, ``KD1``, ``KD2`` on each knee, static trial only)
    The three markers sit at the ends of three mutually perpendicular arms whose common
    point, the **virtual knee marker** ``KNE``, rests on the lateral knee (Nexus exports
    it as ``L/RKNE``).  Nexus takes the arms as equal: ``KNE`` lies on the normal of the
    marker triangle through its centroid ``c``, at ``h = rc / sqrt(2)`` from it, where
    ``rc`` is the root mean square distance of the three markers from ``c``
    (``h = sqrt((a² + b² + c²) / 18)`` for sides ``a, b, c``; the mean side over
    ``sqrt(6)`` is 5e-4 mm off), on the side ``-s n`` with ``n = unit((KD1 - KAX) ×
    (KD2 - KAX))`` and ``s = +1`` left, ``-1`` right.  The KAD marker size enters no
    further: ``KNE`` is the arms' meeting point of the marker centres, and the knee centre
    is ``KneeWidth / 2 + marker radius`` from it as from a KNE marker.

    * KJC = the chord function with ``KAX`` as the wand: ``chord(KAX, HJC, KNE,
      KneeWidth / 2 + r)``; the thigh frame takes ``KNE`` as its lateral marker.
    * AJC (no medial malleolus) = ``chord(KAX, KJC, ANK, AnkleWidth / 2 + r)``.
    * ``ThighRotation`` = ``s`` × the angle about the thigh axis ``KJC -> HJC`` from
      ``KNE`` to ``THI``; ``ShankRotation`` = ``s`` × the angle about the tibia axis
      ``AJC -> KJC`` from ``ANK`` to ``TIB`` (right-handed, the same angle the dynamic
      chord restores, see :mod:`fuzzygait.kinematics.joint_centres`).

Medial malleolus (``MED`` on each ankle, static trial only, with the KAD)
    * AJC = ``ANK + (AnkleWidth / 2 + r) unit(MED - ANK)`` (on the malleolar line, not at
      its midpoint).
    * ``TibialTorsion`` = ``-s`` × the angle about ``AJC -> KJC`` from ``KNE`` (the knee
      axis) to ``ANK`` (the ankle axis).
    * ``AnkleAbAdd`` = the angle at AJC between ``ANK - AJC`` and ``KJC - AJC``, minus
      90° (either side).
    * In the static trial the tibia frame is the marker-based one (KJC, AJC, ANK) with no
      torsion turned in: Nexus' static ``L/RTI*`` frames, its foot frames and its
      ``StaticPlantFlex`` / ``StaticRotOff`` use it.  The static trial's own **ankle
      angles** alone take another proximal frame: that tibia turned about its long axis
      to the azimuth (x axis) of the walking model's tibia ``(KJC, AJC', ANK)``, ``AJC'``
      the rotated chord of ``TIB, KJC, ANK`` turned by ``AnkleAbAdd`` with **this frame's
      own** ``ShankRotation`` and ``AnkleAbAdd`` (not their means).  This reproduces
      Nexus' static ankle angles within 4.5e-7° (the marker-based tibia is 0.014° off:
      the walking model's chord is not the exact inverse of the static definitions).
      Without MED the subject's
      ``TibialTorsion`` is kept and applied as in a dynamic trial (not checked against
      Nexus: the data at hand have zero torsion then).

Every offset is the mean of its per-frame values over the frames where every marker is
seen (rad).
"""

from __future__ import annotations

import numpy as np

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.chain import LowerBodyChain, _memo
from fuzzygait.kinematics.joint_centres import chord_joint_centre
from fuzzygait.kinematics.segments import long_bone_frame, side_sign
from fuzzygait.kinematics.vectors import cross, dot, norm, rotate_frame, unit

#: The KAD's markers (after the side letter).
KAD_MARKERS = ("KAX", "KD1", "KD2")
#: The knee/ankle calibration methods :func:`knee_method` tells apart.
METHODS = ("plain", "KAD", "KAD+MED")
#: Largest relative spread of the three KAD marker distances still taken for a KAD (the
#: device's markers are equidistant, 143.8 mm apart on Motion Lab Systems' KAD).
KAD_SPREAD = 0.1


def knee_method(static: Trial) -> str:
    """Which Plug-in Gait knee/ankle calibration the static trial's markers call for.

    ``"KAD"`` when both knees carry ``KAX``, ``KD1`` and ``KD2``; ``"KAD+MED"`` when both
    ankles also carry ``MED``; ``"plain"`` (chord function with the THI/TIB wands and
    KNE) when no KAD marker is labelled; Plug-in Gait's calibration then ignores MED
    (and KNM), which serve the CGM 2.x option ``use_medial_markers`` of
    :func:`~fuzzygait.kinematics.model.compute_lower_body`.

    Raises:
        MarkerError: some but not all KAD markers are labelled (names the missing ones),
            or with a KAD, MED on one side only.
    """
    kad = [side + m for side in "LR" for m in KAD_MARKERS]
    med = ["LMED", "RMED"]
    have_kad = [m for m in kad if static.has_marker(m)]
    have_med = [m for m in med if static.has_marker(m)]
    if not have_kad:
        return "plain"
    missing = [m for m in kad if m not in have_kad]
    if missing:
        raise MarkerError(
            f"{static.name}: knee alignment device marker(s) {', '.join(missing)} missing; label all of "
            f"{', '.join(kad)} in the static trial, or none for the plain calibration"
        )
    if len(have_med) == 1:
        missing_med = [m for m in med if m not in have_med]
        raise MarkerError(f"{static.name}: medial malleolus marker {missing_med[0]} missing; label both or neither")
    return "KAD+MED" if have_med else "KAD"


def kad_virtual_knee(kax: np.ndarray, kd1: np.ndarray, kd2: np.ndarray, side: str) -> np.ndarray:
    """The KAD's virtual knee marker (mm, ``(n, 3)``), see the module docstring."""
    centroid = (kax + kd1 + kd2) / 3.0
    normal = unit(cross(kd1 - kax, kd2 - kax))
    mean_square = (norm(kax - kd1) ** 2 + norm(kd1 - kd2) ** 2 + norm(kd2 - kax) ** 2) / 3.0
    height = np.sqrt(mean_square / 6.0)
    return centroid - side_sign(side) * height[:, None] * normal


def axial_angle(distal_jc: np.ndarray, proximal_jc: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Per-frame angle (rad) from ``start`` to ``end`` seen along the long axis
    ``distal_jc -> proximal_jc``, right-handed about it (``(n,)``, all ``(n, 3)`` mm)."""
    axis = unit(proximal_jc - distal_jc)
    a = start - distal_jc
    b = end - distal_jc
    a = a - dot(axis, a)[:, None] * axis
    b = b - dot(axis, b)[:, None] * axis
    return np.arctan2(dot(axis, cross(a, b)), dot(a, b))


def check_kad(static: Trial, side: str) -> None:
    """Raise :class:`MarkerError` when the side's KAD markers are not roughly equidistant
    in some frame (a mislabelled or displaced KAD)."""
    kax, kd1, kd2 = (static.marker(side + m) for m in KAD_MARKERS)
    sides = np.stack([norm(kax - kd1), norm(kd1 - kd2), norm(kd2 - kax)], axis=1)
    seen = np.all(np.isfinite(sides), axis=1)
    spread = (sides[seen].max(axis=1) - sides[seen].min(axis=1)) / sides[seen].mean(axis=1)
    if spread.size and spread.max() > KAD_SPREAD:
        lengths = ", ".join(f"{v:.1f}" for v in np.nanmean(sides, axis=0))
        raise MarkerError(
            f"{static.name}: the {side}KAX-{side}KD1-{side}KD2 distances ({lengths} mm) differ by up to "
            f"{100 * spread.max():.0f} %; a knee alignment device's markers are equidistant: check the labels "
            "and that the device sits on the knee"
        )


class StaticKneeChain(LowerBodyChain):
    """The lower-body chain of a static trial calibrated with the KAD (and MED).

    ``KNE`` is the KAD's virtual knee marker, the KJC and AJC follow the module docstring
    and, with MED, the tibia frame is the marker-based one.  Everything else (pelvis,
    HJC, foot) is :class:`~fuzzygait.kinematics.chain.LowerBodyChain`'s.
    """

    def __init__(self, trial: Trial, subject: SubjectParameters, static_foot: str | None = None):
        super().__init__(trial, subject, static_foot=static_foot)
        self.medial_malleoli = trial.has_marker("LMED") and trial.has_marker("RMED")

    @_memo
    def marker(self, label: str) -> np.ndarray:
        """Trajectory of ``label``; ``L/RKNE`` is the KAD's virtual knee marker."""
        if label[1:] == "KNE":
            kax, kd1, kd2 = (self.trial.marker(label[0] + m) for m in KAD_MARKERS)
            return kad_virtual_knee(kax, kd1, kd2, label[0])
        return self.trial.marker(label)

    def missing(self, segment: str, side: str = "L") -> list[str]:
        """As the parent's, with the KAD markers (and MED) standing in for KNE."""
        stand_in = [side + m for m in KAD_MARKERS] if segment != "pelvis" else []
        if self.medial_malleoli and segment in ("tibia", "foot"):
            stand_in.append(side + "MED")
        labels = [m for m in super().missing(segment, side) if m != side + "KNE"] + stand_in
        return [m for m in labels if not self.trial.has_marker(m)]

    @_memo
    def kjc(self, side: str) -> np.ndarray:
        """Knee joint centre from the KAD, mm."""
        offset = self._offset(self.subject.side(side).knee_width)
        return chord_joint_centre(self.marker(side + "KAX"), self.hjc(side), self.marker(side + "KNE"), offset)

    @_memo
    def ajc(self, side: str) -> np.ndarray:
        """Ankle joint centre from the KAD (or on the ANK-MED line), mm."""
        offset = self._offset(self.subject.side(side).ankle_width)
        ank = self.marker(side + "ANK")
        if self.medial_malleoli:
            return ank + offset * unit(self.marker(side + "MED") - ank)
        return chord_joint_centre(self.marker(side + "KAX"), self.kjc(side), ank, offset)

    @_memo
    def tibia(self, side: str) -> np.ndarray:
        """Knee tibia: the marker-based frame with MED, else the parent's (torsion turned in)."""
        if self.medial_malleoli:
            return self.torsioned_tibia(side)
        return super().tibia(side)

    @_memo
    def ankle_tibia(self, side: str) -> np.ndarray:
        """Proximal frame of the static trial's own ankle angles.

        Without MED the parent's.  With MED (inferred from Nexus 2.3's
        ``PiGKadMed_Calibration.c3d``, see the module docstring): the marker-based tibia
        turned about its long axis to the azimuth of the walking model's tibia, whose
        ankle centre is the rotated chord of ``TIB``, ``KJC``, ``ANK`` with **this frame's
        own** ``ShankRotation`` and ``AnkleAbAdd``.
        """
        torsioned = self.torsioned_tibia(side)
        if not self.medial_malleoli:
            return torsioned
        per_frame = self.per_frame_offsets(side)
        walking_ajc = self.chord_ajc(side, per_frame["shank_rotation"], per_frame["ankle_abadd"])
        walking_tibia = long_bone_frame(self.kjc(side), walking_ajc, self.marker(side + "ANK"), side)
        x, z = torsioned[:, :, 0], torsioned[:, :, 2]
        turn = np.arctan2(dot(cross(x, walking_tibia[:, :, 0]), z), dot(x, walking_tibia[:, :, 0]))
        return rotate_frame(torsioned, 2, turn)

    @_memo
    def per_frame_offsets(self, side: str) -> dict[str, np.ndarray]:
        """The side's calibrated ``SideParameters`` fields in every frame (rad, ``(n,)``)."""
        s = side_sign(side)
        hjc, kjc, ajc = self.hjc(side), self.kjc(side), self.ajc(side)
        kne, ank = self.marker(side + "KNE"), self.marker(side + "ANK")
        per_frame = {
            "thigh_rotation": s * axial_angle(kjc, hjc, kne, self.marker(side + "THI")),
            "shank_rotation": s * axial_angle(ajc, kjc, ank, self.marker(side + "TIB")),
        }
        if self.medial_malleoli:
            per_frame["tibial_torsion"] = -s * axial_angle(ajc, kjc, kne, ank)
            cos_ankle = np.clip(dot(unit(ank - ajc), unit(kjc - ajc)), -1.0, 1.0)
            per_frame["ankle_abadd"] = np.arccos(cos_ankle) - np.pi / 2.0
        else:
            per_frame["ankle_abadd"] = np.zeros(len(kjc))
        return per_frame

    def offsets(self, side: str, seen: np.ndarray) -> dict[str, float]:
        """The side's calibrated ``SideParameters`` fields (rad), averaged over ``seen``."""
        return {name: float(np.mean(values[seen])) for name, values in self.per_frame_offsets(side).items()}


def check_medial_malleolus(chain: StaticKneeChain, side: str, seen: np.ndarray) -> None:
    """Raise :class:`MarkerError` when ``MED`` is not medial of ``ANK`` (on the side away
    from the KAD's knee marker)."""
    ank, med = chain.marker(side + "ANK"), chain.marker(side + "MED")
    lateral = chain.marker(side + "KNE") - chain.kjc(side)
    if np.mean(dot(med - ank, lateral)[seen]) >= 0.0:
        raise MarkerError(
            f"{chain.trial.name}: {side}MED is on the lateral side of {side}ANK (the same side as the knee "
            f"alignment device); it belongs on the medial malleolus: check the {side}MED/{side}ANK labels"
        )


__all__ = [
    "KAD_MARKERS",
    "METHODS",
    "StaticKneeChain",
    "axial_angle",
    "check_kad",
    "check_medial_malleolus",
    "kad_virtual_knee",
    "knee_method",
]
