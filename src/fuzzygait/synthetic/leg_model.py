"""Kinematic chain of the synthetic walker: segment frames, joint centres and markers.

Frames and units
----------------
* Laboratory frame: X = walking direction, Y = left, Z = up; positions in **mm**.
* A rotation matrix ``R`` of a segment has the segment's unit axes as **columns**,
  expressed in the lab frame: ``lab_vector = R @ local_vector``; arrays are ``(n, 3, 3)``.
* Segment frames (both sides): pelvis, thigh and shank have x anterior, y left, z
  proximal (up along the segment); the foot has x anterior along the foot (heel to toe),
  y left, z dorsal (up).  Because the foot's z is "up" and its x is "forward", the foot
  frame coincides with the shank frame at ankle angle 0, i.e. the neutral-pose rotation
  ``R_neutral`` of ``R_foot = R_shank @ R_ankle @ R_neutral`` is the identity: in the
  neutral pose the foot's x axis is perpendicular to the shank's z axis (foot flat when
  standing upright).
* Origins: pelvis = midpoint of LASI and RASI; thigh = HJC; shank = KJC; foot = AJC.

Joint rotations (Grood-Suntay / Plug-in Gait order)
---------------------------------------------------
``R_distal = R_proximal @ R_joint`` with ``R_joint = R_y(fs*flexion) @ R_x(as*adduction)
@ R_z(rs*rotation)`` (intrinsic Y-X-Z: flexion about the proximal y axis, adduction
about the floating axis, rotation about the distal z axis) for the pelvis, hip and knee.
The **ankle** uses Vicon Plug-in Gait's Y-Z-X sequence in these frames: ``R_joint =
R_y(fs*flexion) @ R_z(rs*rotation) @ R_x(as*adduction)`` (rotation about the floating
axis, "inversion" last about the foot's long x axis); this is what Nexus computes with
its own foot frame (z along the foot), verified on Vicon output
(``fuzzygait.kinematics``).  ``R_x, R_y, R_z`` are right-handed rotations.  The signs
``fs, as, rs`` (see :data:`SIGNS`) reproduce Plug-in Gait's outputs on both sides:

=======  ====  =========  =========  =============================================
joint    fs    as (L/R)   rs (L/R)   meaning of + (flexion / adduction / rotation)
=======  ====  =========  =========  =============================================
pelvis   +1    +1 / -1    -1 / +1    anterior tilt / own side up / own ASIS forward
hip      -1    -1 / +1    -1 / +1    flexion (knee anterior) / adduction (knee
                                     medial) / internal (lateral knee turns anterior)
knee     +1    -1 / +1    -1 / +1    flexion (ankle posterior) / varus (ankle
                                     medial) / internal rotation of the shank
ankle    -1    +1 / -1    -1 / +1    dorsiflexion (toe up) / Plug-in Gait "inversion"
                                     (see below) / internal (toe points medially)
=======  ====  =========  =========  =============================================

The pelvis "joint" is pelvis relative to the lab (= progression) frame.  For the joints
the left side's adduction and rotation axes are mirrored (sign flipped) relative to the
right, as in Plug-in Gait.  The ankle's Y output is what Vicon labels
"inversion/adduction", but as Nexus computes it a positive value turns the foot about
its long axis so that the **lateral** border rises (the sole faces laterally) on both
sides; the generator follows Vicon's numbers, not the label.  In the walking trial the
ankle Y is not free (Plug-in Gait's two-marker foot cannot roll on its own; see
:func:`fuzzygait.synthetic.gait_curves.plug_in_gait_ankle_y`).
:func:`joint_angles_from_rotation` inverts :func:`joint_rotation` exactly (for
|adduction| < 90 deg).

Geometry
--------
Hip joint centres use Plug-in Gait's Davis regression (see :func:`davis_hjc`).  Knee and
ankle markers are placed so that Plug-in Gait's chord construction recovers the joint
centres exactly: ``KNE = KJC + s*(KneeWidth/2 + r)*y_thigh`` and ``ANK = AJC +
s*(AnkleWidth/2 + r)*y_shank`` (``s = +1`` left, ``-1`` right, ``r`` = marker radius); THI
and TIB lie in the y-z plane of their segment, laterally.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Sign factors ``(flexion, adduction, rotation)`` per ``(joint, side)``.
SIGNS: dict[tuple[str, str], tuple[float, float, float]] = {
    ("pelvis", "L"): (1.0, 1.0, -1.0),
    ("pelvis", "R"): (1.0, -1.0, 1.0),
    ("hip", "L"): (-1.0, -1.0, -1.0),
    ("hip", "R"): (-1.0, 1.0, 1.0),
    ("knee", "L"): (1.0, -1.0, -1.0),
    ("knee", "R"): (1.0, 1.0, 1.0),
    ("ankle", "L"): (-1.0, 1.0, -1.0),
    ("ankle", "R"): (-1.0, -1.0, 1.0),
}

SIDES = ("L", "R")

#: Plug-in Gait lower-body marker labels of a dynamic trial, in column order.
DYNAMIC_LABELS: tuple[str, ...] = (
    "LASI", "RASI", "LPSI", "RPSI",
    "LTHI", "LKNE", "LTIB", "LANK", "LHEE", "LTOE",
    "RTHI", "RKNE", "RTIB", "RANK", "RHEE", "RTOE",
)  # fmt: skip
#: Extra medial markers of the static trial.
MEDIAL_LABELS: tuple[str, ...] = ("LKNM", "RKNM", "LMED", "RMED")
#: Labels of the static trial, in column order.
STATIC_LABELS: tuple[str, ...] = DYNAMIC_LABELS + MEDIAL_LABELS


def _side_factor(side: str) -> float:
    if side == "L":
        return 1.0
    if side == "R":
        return -1.0
    raise ValueError(f"side must be 'L' or 'R'; got {side!r}")


# ------------------------------------------------------------------------- rotations
def rot_x(angle_rad: np.ndarray | float) -> np.ndarray:
    """Right-handed rotation(s) about x by ``angle_rad``; ``(n, 3, 3)``."""
    a = np.atleast_1d(np.asarray(angle_rad, dtype=float))
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = [np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)]
    return np.stack(rows, -2)


def rot_y(angle_rad: np.ndarray | float) -> np.ndarray:
    """Right-handed rotation(s) about y by ``angle_rad``; ``(n, 3, 3)``."""
    a = np.atleast_1d(np.asarray(angle_rad, dtype=float))
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = [np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)]
    return np.stack(rows, -2)


def rot_z(angle_rad: np.ndarray | float) -> np.ndarray:
    """Right-handed rotation(s) about z by ``angle_rad``; ``(n, 3, 3)``."""
    a = np.atleast_1d(np.asarray(angle_rad, dtype=float))
    c, s = np.cos(a), np.sin(a)
    o, z = np.ones_like(a), np.zeros_like(a)
    rows = [np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)]
    return np.stack(rows, -2)


def joint_rotation(
    flexion: np.ndarray | float,
    adduction: np.ndarray | float,
    rotation: np.ndarray | float,
    side: str,
    joint: str,
) -> np.ndarray:
    """Rotation of the distal segment relative to the proximal one, ``(n, 3, 3)``.

    ``R_joint = R_y(fs*flexion) @ R_x(as*adduction) @ R_z(rs*rotation)`` (ankle:
    ``R_y(fs*flexion) @ R_z(rs*rotation) @ R_x(as*adduction)``) with the signs of
    :data:`SIGNS` (see the module docstring for the meaning of each sign); the distal
    frame is ``R_proximal @ R_joint``.  For ``joint="pelvis"`` the proximal frame is the
    lab (progression) frame.

    Args:
        flexion: flexion / dorsiflexion / anterior tilt in **degrees**, scalar or ``(n,)``.
        adduction: adduction / varus / Plug-in Gait ankle "inversion" / obliquity (own
            side up) in degrees.
        rotation: internal rotation / own ASIS forward (pelvis) in degrees.
        side: ``"L"`` or ``"R"``.
        joint: ``"pelvis"``, ``"hip"``, ``"knee"`` or ``"ankle"``.
    """
    try:
        fs, as_, rs = SIGNS[(joint, side)]
    except KeyError:
        raise ValueError(f"unknown joint/side {joint!r}/{side!r}") from None
    f, a, r = np.broadcast_arrays(
        np.atleast_1d(np.asarray(flexion, dtype=float)),
        np.atleast_1d(np.asarray(adduction, dtype=float)),
        np.atleast_1d(np.asarray(rotation, dtype=float)),
    )
    flex = rot_y(np.radians(fs * f))
    add = rot_x(np.radians(as_ * a))
    rot = rot_z(np.radians(rs * r))
    if joint == "ankle":
        return flex @ rot @ add
    return flex @ add @ rot


def euler_yxz(rotation: np.ndarray) -> np.ndarray:
    """Angles ``(a, b, c)`` in rad with ``R = R_y(a) @ R_x(b) @ R_z(c)``; ``(n, 3)``."""
    R = np.asarray(rotation, dtype=float).reshape(-1, 3, 3)
    a = np.arctan2(R[:, 0, 2], R[:, 2, 2])
    b = np.arcsin(np.clip(-R[:, 1, 2], -1.0, 1.0))
    c = np.arctan2(R[:, 1, 0], R[:, 1, 1])
    return np.stack([a, b, c], axis=-1)


def euler_yzx(rotation: np.ndarray) -> np.ndarray:
    """Angles ``(a, b, c)`` in rad with ``R = R_y(a) @ R_z(b) @ R_x(c)``; ``(n, 3)``."""
    R = np.asarray(rotation, dtype=float).reshape(-1, 3, 3)
    a = np.arctan2(-R[:, 2, 0], R[:, 0, 0])
    b = np.arcsin(np.clip(R[:, 1, 0], -1.0, 1.0))
    c = np.arctan2(-R[:, 1, 2], R[:, 1, 1])
    return np.stack([a, b, c], axis=-1)


def joint_angles_from_rotation(rotation: np.ndarray, side: str, joint: str) -> np.ndarray:
    """Inverse of :func:`joint_rotation`: clinical angles ``(n, 3)`` in degrees.

    Args:
        rotation: ``R_proximal^T @ R_distal`` (or the pelvis rotation for ``"pelvis"``).
        side, joint: as for :func:`joint_rotation`.
    """
    signs = np.asarray(SIGNS[(joint, side)])
    if joint == "ankle":
        flexion, rotation_z, adduction = euler_yzx(rotation).T
        return np.degrees(np.stack([flexion, adduction, rotation_z], axis=-1)) * signs
    return np.degrees(euler_yxz(rotation)) * signs


#: Plug-in Gait's foot axes (x dorsal, y left, z posterior, along the foot) in this
#: package's foot axes (x anterior, y left, z dorsal): ``R_pig = R_here @ PIG_FOOT_AXES``
#: (= ``R_y(-90 deg)``).
PIG_FOOT_AXES = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def foot_progression_angles(foot_rotation: np.ndarray, side: str) -> np.ndarray:
    """Vicon's ``L/RFootProgressAngles`` ``(n, 3)`` (deg) of a foot frame in the lab.

    The progression frame is the lab (the synthetic subject walks along +X).  As Plug-in
    Gait defines it: the foot frame in Plug-in Gait's axes, ``R_y(a) R_x(b) R_z(c)``
    (intrinsic Y-X-Z), output ``(a, c, -b)`` left and ``(a, -c, b)`` right -- so at a level
    foot pointing along +X the angles are ``(-90, 0, 0)``; Z + = the toes turned medially
    (internal foot progression) on both sides, X = ``-90 +`` the foot's pitch, toes down +
    (Z is about the pitched foot's dorsal axis, not the heading's azimuth).
    """
    R = np.asarray(foot_rotation, dtype=float).reshape(-1, 3, 3) @ PIG_FOOT_AXES
    a, b, c = np.degrees(euler_yxz(R)).T
    s = _side_factor(side)
    return np.stack([a, s * c, -s * b], axis=-1)


# ------------------------------------------------------------------------- subject
@dataclass(frozen=True)
class SubjectGeometry:
    """Anthropometry and marker placement of the synthetic subject (both sides equal).

    Lengths in mm, mass in kg.  Vicon ``PROCESSING`` parameters are produced by
    :meth:`parameters`; the remaining attributes describe the hidden skeleton.

    Attributes:
        bodymass: kg.
        height: mm.
        marker_diameter: mm (marker radius ``r`` = half of it).
        inter_asis_distance: LASI-RASI distance, mm.
        leg_length: L/RLegLength, mm (ASIS to medial malleolus).
        knee_width, ankle_width: mm.
        thigh_length: HJC-KJC distance, mm.
        shank_length: KJC-AJC distance, mm.
        psis_back: PSIS distance behind the ASIS along -x_pelvis, mm.
        psis_half_width: PSIS lateral offset from the pelvis mid-plane, mm.
        thi_fraction, tib_fraction: height of THI (TIB) above the KJC (AJC) as a fraction
            of the thigh (shank) length.
        thi_offset, tib_offset: lateral distance of THI (TIB) from the segment's long
            axis, mm.
        toe_local, hee_local: TOE and HEE positions in the foot frame relative to the AJC
            (x anterior, y left, z dorsal), mm.  Both have y = 0 and the same z, so
            HEE->TOE is parallel to the foot x axis.
        sole_depth: depth of the sole plane below the AJC along -z_foot, mm (the foot
            touches the floor at ``z_foot = -sole_depth``).
    """

    bodymass: float = 72.0
    height: float = 1780.0
    marker_diameter: float = 14.0
    inter_asis_distance: float = 250.0
    leg_length: float = 900.0
    knee_width: float = 105.0
    ankle_width: float = 70.0
    thigh_length: float = 410.0
    shank_length: float = 395.0
    psis_back: float = 160.0
    psis_half_width: float = 45.0
    thi_fraction: float = 0.5
    thi_offset: float = 75.0
    tib_fraction: float = 0.5
    tib_offset: float = 65.0
    toe_local: tuple[float, float, float] = (140.0, 0.0, -60.0)
    hee_local: tuple[float, float, float] = (-50.0, 0.0, -60.0)
    sole_depth: float = 90.0

    # ---------------------------------------------------------------- derived values
    @property
    def marker_radius(self) -> float:
        """Marker radius in mm (``MarkerDiameter / 2``)."""
        return self.marker_diameter / 2.0

    @property
    def asis_trocanter_distance(self) -> float:
        """Plug-in Gait regression ``0.1288 * LegLength - 48.56`` in mm."""
        return round(0.1288 * self.leg_length - 48.56, 9)

    def parameters(self) -> dict[str, float]:
        """Vicon ``PROCESSING`` subject parameters (mm, rad, kg), in a fixed order."""
        params: dict[str, float] = {
            "Bodymass": self.bodymass,
            "Height": self.height,
            "MarkerDiameter": self.marker_diameter,
            "InterAsisDistance": self.inter_asis_distance,
        }
        per_side = {
            "LegLength": self.leg_length,
            "KneeWidth": self.knee_width,
            "AnkleWidth": self.ankle_width,
            "AsisTrocanterDistance": self.asis_trocanter_distance,
            "TibialTorsion": 0.0,
            "ThighRotation": 0.0,
            "ShankRotation": 0.0,
            "AnkleAbAdd": 0.0,
            "SoleDelta": 0.0,
        }
        # the offsets Vicon's static calibration stores in calibrated trials
        offsets = static_offsets(self)
        per_side["StaticPlantFlex"] = offsets["plantarflexion"]
        per_side["StaticRotOff"] = offsets["rotation"]
        for name, value in per_side.items():
            for side in SIDES:
                params[side + name] = float(value)
        return {k: float(v) for k, v in params.items()}

    def pelvis_markers_local(self) -> dict[str, np.ndarray]:
        """LASI, RASI, LPSI, RPSI in the pelvis frame (origin = ASIS midpoint), mm.

        The PSIS lie in the pelvis x-y plane (z = 0), so SACR = their midpoint lies on
        the -x axis and Plug-in Gait's pelvis x axis (component of ASIS-mid - SACR
        orthogonal to y) equals this frame's x axis exactly.  In the walking trial the
        mean anterior tilt (5 deg) puts the PSIS ~14 mm higher than the ASIS.
        """
        half = self.inter_asis_distance / 2.0
        return {
            "LASI": np.array([0.0, half, 0.0]),
            "RASI": np.array([0.0, -half, 0.0]),
            "LPSI": np.array([-self.psis_back, self.psis_half_width, 0.0]),
            "RPSI": np.array([-self.psis_back, -self.psis_half_width, 0.0]),
        }

    def hjc_local(self, side: str) -> np.ndarray:
        """Hip joint centre of ``side`` in the pelvis frame, mm (see :func:`davis_hjc`)."""
        return davis_hjc(
            inter_asis_distance=self.inter_asis_distance,
            leg_length_left=self.leg_length,
            leg_length_right=self.leg_length,
            asis_trocanter_distance=self.asis_trocanter_distance,
            marker_diameter=self.marker_diameter,
            side=side,
        )

    def standing_pelvis_height(self) -> float:
        """ASIS-midpoint height (mm) with all angles 0 and the soles on the floor."""
        return -self.hjc_local("L")[2] + self.thigh_length + self.shank_length + self.sole_depth


def davis_hjc(
    inter_asis_distance: float,
    leg_length_left: float,
    leg_length_right: float,
    asis_trocanter_distance: float,
    marker_diameter: float,
    side: str,
) -> np.ndarray:
    """Plug-in Gait (Davis) hip joint centre in the pelvis frame, mm.

    With marker radius ``r = MarkerDiameter/2``, mean leg length ``L``,
    ``C = 0.115 L - 15.3``, ``theta = 0.5``, ``beta = 0.314`` rad, ``aa =
    InterAsisDistance/2`` and ``X_dis`` = the side's AsisTrocanterDistance::

        x = (-X_dis - r) cos(beta) + C cos(theta) sin(beta)
        y = s (aa - C sin(theta))            (s = +1 left, -1 right)
        z = (-X_dis - r) sin(beta) - C cos(theta) cos(beta)
    """
    s = _side_factor(side)
    r = marker_diameter / 2.0
    mean_leg = 0.5 * (leg_length_left + leg_length_right)
    c = 0.115 * mean_leg - 15.3
    theta, beta = 0.5, 0.314
    aa = inter_asis_distance / 2.0
    x = (-asis_trocanter_distance - r) * np.cos(beta) + c * np.cos(theta) * np.sin(beta)
    z = (-asis_trocanter_distance - r) * np.sin(beta) - c * np.cos(theta) * np.cos(beta)
    y = s * (aa - c * np.sin(theta))
    return np.array([x, y, z])


def static_offsets(geometry: SubjectGeometry | None = None) -> dict[str, float]:
    """Expected Plug-in Gait static foot offsets (rad) implied by the marker geometry.

    * ``"plantarflexion"``: angle between the AJC->TOE line and the foot x axis (HEE->TOE,
      the foot-flat long axis); positive because TOE lies below the AJC's x line
      (``atan2(-toe_z, toe_x)``, 0.404892 rad = 23.199 deg for the default geometry).
    * ``"rotation"``: angle of AJC->TOE out of the foot's x-z plane (``atan2(toe_y,
      toe_x)``), 0 because TOE and HEE lie in that plane.
    """
    g = geometry or SubjectGeometry()
    tx, ty, tz = g.toe_local
    return {
        "plantarflexion": float(np.arctan2(-tz, tx)),
        "rotation": float(np.arctan2(ty, tx)),
    }


# ------------------------------------------------------------------------- pose
@dataclass
class Pose:
    """Kinematic state of the walker over ``n`` frames.

    Attributes:
        rotations: segment rotation matrices ``(n, 3, 3)`` (columns = axes in lab) keyed
            ``"Pelvis"``, ``"LThigh"``, ``"LShank"``, ``"LFoot"``, ``"RThigh"``, ...
        joint_centres: ``(n, 3)`` mm keyed ``"LHJC"``, ``"LKJC"``, ``"LAJC"``, ``"RHJC"`` ...
        markers: ``(n, 3)`` mm keyed by marker label.
        sole_points: ``(n, 3)`` mm of the heel and forefoot sole points keyed
            ``"LHeelSole"``, ``"LToeSole"`` ... (used to place the walker on the floor).
    """

    rotations: dict[str, np.ndarray] = field(default_factory=dict)
    joint_centres: dict[str, np.ndarray] = field(default_factory=dict)
    markers: dict[str, np.ndarray] = field(default_factory=dict)
    sole_points: dict[str, np.ndarray] = field(default_factory=dict)


def _apply(R: np.ndarray, local: np.ndarray) -> np.ndarray:
    """``R @ local`` for ``(n,3,3)`` rotations and a ``(3,)`` or ``(n,3)`` local vector."""
    return np.einsum("nij,nj->ni", R, np.broadcast_to(local, (R.shape[0], 3)))


def pose_lower_body(
    pelvis_origin: np.ndarray,
    pelvis_angles: np.ndarray,
    joint_angles: dict[tuple[str, str], np.ndarray],
    geometry: SubjectGeometry | None = None,
    medial_markers: bool = False,
) -> Pose:
    """Forward kinematics of pelvis + both legs.

    Args:
        pelvis_origin: ``(n, 3)`` ASIS-midpoint positions in the lab, mm.
        pelvis_angles: ``(n, 3)`` **left-side** pelvis angles (tilt, obliquity, rotation)
            in degrees relative to the lab (progression) frame.
        joint_angles: ``(n, 3)`` clinical angles in degrees keyed ``(side, joint)`` with
            ``side`` in ``"L"``, ``"R"`` and ``joint`` in ``"hip"``, ``"knee"``,
            ``"ankle"``; the columns are flexion, adduction, rotation.
        geometry: subject geometry (default :class:`SubjectGeometry`).
        medial_markers: also produce KNM and MED (static trial).
    """
    g = geometry or SubjectGeometry()
    origin = np.atleast_2d(np.asarray(pelvis_origin, dtype=float))
    pa = np.atleast_2d(np.asarray(pelvis_angles, dtype=float))
    r = g.marker_radius
    pose = Pose()
    R_pelvis = joint_rotation(pa[:, 0], pa[:, 1], pa[:, 2], "L", "pelvis")
    pose.rotations["Pelvis"] = R_pelvis
    for label, local in g.pelvis_markers_local().items():
        pose.markers[label] = origin + _apply(R_pelvis, local)

    for side in SIDES:
        s = _side_factor(side)
        hip = np.atleast_2d(joint_angles[(side, "hip")])
        knee = np.atleast_2d(joint_angles[(side, "knee")])
        ankle = np.atleast_2d(joint_angles[(side, "ankle")])
        R_thigh = R_pelvis @ joint_rotation(hip[:, 0], hip[:, 1], hip[:, 2], side, "hip")
        R_shank = R_thigh @ joint_rotation(knee[:, 0], knee[:, 1], knee[:, 2], side, "knee")
        R_foot = R_shank @ joint_rotation(ankle[:, 0], ankle[:, 1], ankle[:, 2], side, "ankle")

        hjc = origin + _apply(R_pelvis, g.hjc_local(side))
        kjc = hjc - g.thigh_length * R_thigh[:, :, 2]
        ajc = kjc - g.shank_length * R_shank[:, :, 2]
        knee_off = g.knee_width / 2.0 + r
        ankle_off = g.ankle_width / 2.0 + r

        pose.rotations[side + "Thigh"] = R_thigh
        pose.rotations[side + "Shank"] = R_shank
        pose.rotations[side + "Foot"] = R_foot
        pose.joint_centres[side + "HJC"] = hjc
        pose.joint_centres[side + "KJC"] = kjc
        pose.joint_centres[side + "AJC"] = ajc

        m = pose.markers
        m[side + "THI"] = kjc + _apply(
            R_thigh, np.array([0.0, s * g.thi_offset, g.thi_fraction * g.thigh_length])
        )
        m[side + "KNE"] = kjc + s * knee_off * R_thigh[:, :, 1]
        m[side + "TIB"] = ajc + _apply(
            R_shank, np.array([0.0, s * g.tib_offset, g.tib_fraction * g.shank_length])
        )
        m[side + "ANK"] = ajc + s * ankle_off * R_shank[:, :, 1]
        m[side + "HEE"] = ajc + _apply(R_foot, np.asarray(g.hee_local, dtype=float))
        m[side + "TOE"] = ajc + _apply(R_foot, np.asarray(g.toe_local, dtype=float))
        if medial_markers:
            m[side + "KNM"] = kjc - s * knee_off * R_thigh[:, :, 1]
            m[side + "MED"] = ajc - s * ankle_off * R_shank[:, :, 1]

        pose.sole_points[side + "HeelSole"] = ajc + _apply(
            R_foot, np.array([g.hee_local[0], 0.0, -g.sole_depth])
        )
        pose.sole_points[side + "ToeSole"] = ajc + _apply(
            R_foot, np.array([g.toe_local[0], 0.0, -g.sole_depth])
        )
    return pose
