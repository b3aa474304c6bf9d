"""Synthetic subjects for Plug-in Gait's calibration options: knee alignment device (KAD),
medial malleoli, misplaced thigh/shank wands and tibial torsion, with known values.

Opt-in: :func:`~fuzzygait.synthetic.generate.make_static_trial` and
:func:`~fuzzygait.synthetic.generate.make_walking_trial` take ``options=PigOptions(...)``;
the bundled ``sample_data`` does not use them.  Every marker is placed physically from the
hidden skeleton of :mod:`fuzzygait.synthetic.leg_model` (nothing is solved with the
model's code), so that the definitions of :mod:`fuzzygait.kinematics.kad` (static) and
:mod:`fuzzygait.kinematics.joint_centres` (dynamic) recover the known values exactly.

Per side, ``s = +1`` left, ``-1`` right, ``R_thigh`` and ``R_shank`` as in
:mod:`~fuzzygait.synthetic.leg_model` (``R_shank``, the distal frame of the knee angles,
is Plug-in Gait's *untorsioned* tibia):

* **tibial torsion** ``τ``: the malleolar (ankle) axis is the shank's y axis turned
  about its long axis: the *torsioned* tibia ``R_ankle_tibia = R_shank @ R_z(-s τ)``
  (Nexus' ``R_untorsioned = R_torsioned @ R_z(s τ)``), ``ANK = AJC + s (AnkleWidth / 2 +
  r) y_ankle_tibia`` (with AnkleAbAdd 0, see below) and ``MED`` its mirror image through the AJC.  The knee axis stays
  the thigh's y axis (``KNE = KJC + s (KneeWidth / 2 + r) y_thigh``), so ``TibialTorsion
  = -s ×`` (the angle from KNE to ANK about the tibia's long axis) is ``τ`` whenever the
  knee's axial rotation is 0 (the static trial's pose).  The ankle angles are those of
  the foot relative to the torsioned tibia.
* **wand misplacement** ``ThighRotation`` ``θ_t`` / ``ShankRotation`` ``θ_s``: THI (TIB)
  sits ``thi_offset`` (``tib_offset``) from the long axis in the direction of KNE (ANK)
  turned by ``s θ`` about the segment's long axis (right-handed, proximal), at the same
  height as the plain wand.
* **KAD** (static trial only, replacing KNE): three equal (:data:`KAD_ARM_MM`), mutually
  perpendicular arms meet at KNE, the lateral knee marker position on the knee flexion
  axis; ``KAX`` lies along the flexion axis, laterally (``KNE + L s y_thigh``); ``KD1``
  and ``KD2`` lie in the thigh's sagittal plane, anterior-proximal and anterior-distal
  (``KNE + L (x_thigh ± z_thigh) / √2``), so that (KAX, KD1, KD2) are right-handed on
  the left and left-handed on the right: the arrangement of Vicon Nexus 2.3's
  ``PiGKad_Calibration.c3d`` (KAX within 0.3° of the thigh's y axis, KD1/KD2 at about
  ±45° in its x-z plane, arms 101.7-102.4 mm).
* The PiG foot has no roll of its own (TOE and the ankle axis of the untorsioned tibia,
  :mod:`fuzzygait.kinematics.segments`), so the ankle Y of the truth is the one that
  makes the posed foot that foot (:func:`torsioned_ankle_y`).  The static trial stands
  with every angle 0, the feet along the torsioned tibiae (level, turned by the
  torsion): with MED, Nexus builds the static foot on the marker-based tibia's axis
  (:mod:`fuzzygait.kinematics.kad`), so StaticPlantFlex and StaticRotOff are exactly
  those of the plain subject (``StaticRotOff`` 0) and the dynamic foot on the untorsioned
  axis is the posed one.
* KAD without MED: Nexus' KAD chord puts the AJC in the plane of KAX, KJC and ANK, which
  holds the true AJC only without torsion; give ``tibial_torsion = 0`` for a static trial
  whose calibration recovers the known values exactly.
* **ankle ab/adduction** ``α`` (``AnkleAbAdd``, default 0): the malleolar line is
  tilted in the plane of the torsioned tibia's y and z axes, the lateral malleolus
  lower: ``ANK = AJC + (AnkleWidth / 2 + r) (s cos α y_ankle_tibia - sin α z_shank)``,
  MED its mirror image through the AJC, so the angle at the AJC between ANK and KJC is
  ``90° + α`` (the static definition).  Nexus' dynamic AnkleAbAdd (the chord centre
  turned about ANK by ``α``) is not the exact inverse of that: the triangle ANK-AJC-KJC
  with the angle ``90° + α`` at the AJC has the angle ``acos(d / D) - α + O((d / D)
  α²)`` at ANK (``d = |ANK - AJC|``, ``D = |ANK - KJC|``), so with ``α ≠ 0`` the walking
  trial's AJC is recovered only to about ``d (d / D) α² / 2`` (measured 0.006 mm and
  0.003° at ``α = 0.05`` rad, 0.012° at 0.1 rad, 0.09 mm and 0.05° at 0.2 rad) while the static
  calibration still recovers every value exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzygait.synthetic.leg_model import (
    SIDES,
    SIGNS,
    Pose,
    SubjectGeometry,
    _apply,
    _side_factor,
    joint_angles_from_rotation,
    joint_rotation,
    pose_lower_body,
    rot_y,
    rot_z,
    static_offsets,
)

#: KAD arm length, mm: Motion Lab Systems' KAD markers are 143.8 mm apart (= L √2).
KAD_ARM_MM = 143.8 / np.sqrt(2.0)
#: The KAD markers (after the side letter).
KAD_LABELS = ("KAX", "KD1", "KD2")


@dataclass(frozen=True)
class LegOffsets:
    """Known Plug-in Gait offsets of one leg, rad (Nexus' ``PROCESSING`` meaning; see the
    module docstring for how each is realised)."""

    thigh_rotation: float = 0.0
    shank_rotation: float = 0.0
    tibial_torsion: float = 0.0
    ankle_abadd: float = 0.0


@dataclass(frozen=True)
class PigOptions:
    """A synthetic subject's misplaced wands and tibial torsion, and the static markers.

    Attributes:
        left, right: the known offsets of each leg.
        kad: the static trial carries the KAD (``L/RKAX``, ``L/RKD1``, ``L/RKD2``) in
            place of KNE.
        medial_malleoli: the static trial also carries ``L/RMED``.
        kad_arm: KAD arm length, mm.
    """

    left: LegOffsets = field(default_factory=lambda: LegOffsets(0.12, -0.09, -0.21))
    right: LegOffsets = field(default_factory=lambda: LegOffsets(-0.16, 0.06, -0.31))
    kad: bool = True
    medial_malleoli: bool = True
    kad_arm: float = KAD_ARM_MM

    def side(self, side: str) -> LegOffsets:
        """The offsets of ``"L"`` or ``"R"``."""
        _side_factor(side)
        return self.left if side == "L" else self.right

    def parameters(self, geometry: SubjectGeometry) -> dict[str, float]:
        """The geometry's ``PROCESSING`` parameters with the known offsets filled in."""
        params = geometry.parameters()
        for side in SIDES:
            leg = self.side(side)
            params[side + "ThighRotation"] = float(leg.thigh_rotation)
            params[side + "ShankRotation"] = float(leg.shank_rotation)
            params[side + "TibialTorsion"] = float(leg.tibial_torsion)
            params[side + "AnkleAbAdd"] = float(leg.ankle_abadd)
        return params

    def static_labels(self, dynamic_labels: tuple[str, ...]) -> list[str]:
        """Static-trial labels: the dynamic ones, KNE replaced by the KAD, then MED."""
        if not self.kad:
            return list(dynamic_labels) + [side + "MED" for side in SIDES] * self.medial_malleoli
        labels: list[str] = []
        for label in dynamic_labels:
            labels += [label[0] + m for m in KAD_LABELS] if label[1:] == "KNE" else [label]
        return labels + [side + "MED" for side in SIDES] * self.medial_malleoli


def _transposed(rotations: np.ndarray) -> np.ndarray:
    return np.swapaxes(rotations, -1, -2)


def torsion_turn(torsion: float, side: str) -> np.ndarray:
    """``R_shank^T @ R_ankle_tibia = R_z(-s τ)``, ``(1, 3, 3)``."""
    return rot_z(-_side_factor(side) * torsion)


def torsioned_ankle_y(
    flexion: np.ndarray, rotation: np.ndarray, torsion: float, side: str, plantar_flex_offset: float
) -> np.ndarray:
    """Ankle Y (degrees) of a Plug-in Gait foot at ankle ``flexion`` and ``rotation``
    (degrees, relative to the torsioned tibia) with tibial torsion ``torsion`` (rad).

    Plug-in Gait's foot ``F`` (anatomical axes: x along HEE->TOE, z dorsal) has its y axis
    in the plane of the untorsioned tibia's y axis ``e`` and AJC->TOE ``t = (cos β, 0,
    -sin β)`` (``β`` the static plantarflexion offset): ``u = F^T e`` satisfies ``u_x sin β
    + u_z cos β = 0``.  With ``F = R_ankle_tibia R_y(F_) R_z(Z) R_x(A)`` (the signed angles
    of :func:`~fuzzygait.synthetic.leg_model.joint_rotation`), ``u = R_x(-A) w`` with ``w
    = R_z(-Z) R_y(-F_) R_z(s τ) e_y``, hence ``ρ sin(A - φ) = w_x tan β`` (``ρ, φ`` the
    polar form of ``(w_y, w_z)``).  With ``τ = 0`` this is
    :func:`~fuzzygait.synthetic.gait_curves.plug_in_gait_ankle_y`.
    """
    fs, as_, rs = SIGNS[("ankle", side)]
    flex = rot_y(np.radians(fs * np.asarray(flexion, dtype=float)))
    turn = rot_z(np.radians(rs * np.asarray(rotation, dtype=float)))
    e_y = np.array([0.0, 1.0, 0.0])
    w = _apply(_transposed(turn) @ _transposed(flex) @ _transposed(torsion_turn(torsion, side)), e_y)
    rho, phi = np.hypot(w[:, 1], w[:, 2]), np.arctan2(w[:, 2], w[:, 1])
    adduction = phi + np.arcsin(w[:, 0] * np.tan(plantar_flex_offset) / rho)
    return np.degrees(as_ * adduction)


def ankle_angles_on_shank(ankle: np.ndarray, torsion: float, side: str) -> np.ndarray:
    """Ankle angles (degrees) relative to ``R_shank`` of a foot whose angles relative to
    the torsioned tibia are ``ankle`` (what :func:`pose_lower_body` takes)."""
    rotation = joint_rotation(ankle[:, 0], ankle[:, 1], ankle[:, 2], side, "ankle")
    return joint_angles_from_rotation(torsion_turn(torsion, side) @ rotation, side, "ankle")


def pose_with_options(
    origin: np.ndarray,
    pelvis_angles: np.ndarray,
    joint_angles: dict[tuple[str, str], np.ndarray],
    geometry: SubjectGeometry,
    options: PigOptions,
    static: bool = False,
) -> Pose:
    """Forward kinematics (:func:`~fuzzygait.synthetic.leg_model.pose_lower_body`) with
    the wands, ANK and (``static``) the KAD and MED placed as the module docstring says.

    Args:
        origin, pelvis_angles: as for ``pose_lower_body``.
        joint_angles: clinical angles (degrees) keyed ``(side, joint)``; the ankle angles
            are relative to the torsioned tibia.
        geometry: the subject.
        options: the known offsets and the static markers.
        static: add the KAD (in place of KNE) and MED as ``options`` asks.
    """
    g = geometry
    on_shank = dict(joint_angles)
    for side in SIDES:
        ankle = np.atleast_2d(joint_angles[(side, "ankle")])
        on_shank[(side, "ankle")] = ankle_angles_on_shank(ankle, options.side(side).tibial_torsion, side)
    pose = pose_lower_body(origin, pelvis_angles, on_shank, g)
    m = pose.markers
    for side in SIDES:
        s, leg = _side_factor(side), options.side(side)
        R_thigh, R_shank = pose.rotations[side + "Thigh"], pose.rotations[side + "Shank"]
        R_ankle_tibia = R_shank @ torsion_turn(leg.tibial_torsion, side)
        kjc, ajc = pose.joint_centres[side + "KJC"], pose.joint_centres[side + "AJC"]
        thi = rot_z(s * leg.thigh_rotation)[0] @ np.array([0.0, s * g.thi_offset, 0.0])
        m[side + "THI"] = kjc + _apply(R_thigh, thi + [0.0, 0.0, g.thi_fraction * g.thigh_length])
        tib = rot_z(s * leg.shank_rotation)[0] @ np.array([0.0, s * g.tib_offset, 0.0])
        m[side + "TIB"] = ajc + _apply(R_ankle_tibia, tib + [0.0, 0.0, g.tib_fraction * g.shank_length])
        ankle_off = g.ankle_width / 2.0 + g.marker_radius
        lateral = s * np.cos(leg.ankle_abadd) * R_ankle_tibia[:, :, 1] - np.sin(leg.ankle_abadd) * R_shank[:, :, 2]
        m[side + "ANK"] = ajc + ankle_off * lateral
        if static and options.medial_malleoli:
            m[side + "MED"] = ajc - ankle_off * lateral
        if static and options.kad:
            kne = m.pop(side + "KNE")
            arm = options.kad_arm
            m[side + "KAX"] = kne + _apply(R_thigh, np.array([0.0, s * arm, 0.0]))
            m[side + "KD1"] = kne + _apply(R_thigh, np.array([arm, 0.0, arm]) / np.sqrt(2.0))
            m[side + "KD2"] = kne + _apply(R_thigh, np.array([arm, 0.0, -arm]) / np.sqrt(2.0))
    return pose


def walking_ankle_angles(
    ankle: np.ndarray, options: PigOptions, side: str, geometry: SubjectGeometry
) -> np.ndarray:
    """The walking truth's ankle angles ``(n, 3)``: ``ankle``'s flexion and rotation
    (relative to the torsioned tibia) with the Y of :func:`torsioned_ankle_y`."""
    out = np.array(ankle, dtype=float)
    beta = static_offsets(geometry)["plantarflexion"]
    out[:, 1] = torsioned_ankle_y(out[:, 0], out[:, 2], options.side(side).tibial_torsion, side, beta)
    return out
