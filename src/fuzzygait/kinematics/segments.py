"""Plug-in Gait segment frames: thigh (femur), tibia (torsioned and untorsioned), foot.

Frames are ``(n, 3, 3)`` rotation matrices whose columns are the segment axes in lab
coordinates (see :mod:`fuzzygait.kinematics.vectors`).  Both sides use the same
right-handed axis directions (no mirroring of axes):

* **thigh** (origin KJC): z = ``unit(HJC - KJC)`` (proximal); y points to the subject's
  left, along ``KNE - KJC`` on the left leg and ``KJC - KNE`` on the right; x = y × z
  (anterior).  Vicon exports it as ``LFEO/LFEA/LFEL/LFEP``.
* **tibia** (origin AJC): the same construction from KJC, AJC and ANK.  The frame built
  from the markers is the *torsioned* tibia, the proximal frame of the ankle angles.  The
  *untorsioned* tibia, used for the knee angles, exported as ``LTIO...`` and whose y
  axis is the ankle axis of the foot frame, is the torsioned one turned about its z axis
  by the tibial torsion ``τ``: ``R_untorsioned = R_torsioned @ R_z(s τ)`` with ``s = +1``
  left, ``-1`` right (Nexus 2.3, ``PiGKadMed_Motion.c3d``, ``TibialTorsion`` -0.21 and
  -0.31 rad: this reproduces its ``L/RTI*`` frames, knee, ankle and foot progression
  angles to float32 rounding; the opposite sign is 12° and 18° off in knee rotation).
* **foot** (Plug-in Gait orientation, as Vicon exports ``LFOA/LFOL/LFOP``): z runs along
  the foot from the toe backwards, x points dorsally (up), y to the left.  The
  *uncorrected* foot has z = ``unit(AJC - TOE)``, x = ``unit(y_ankle × z)`` with
  ``y_ankle`` the untorsioned tibia's y axis, y = z × x.  The static calibration offsets
  turn it into the anatomical foot: ``R_foot = R_uncorrected @ R_y(-StaticPlantFlex) @
  R_x(-s StaticRotOff)`` (``s = +1`` left, ``-1`` right).
* **CGM 2.3 foot with a tibial torsion** (pyCGM2, static trial with MED): the ankle
  axis of the uncorrected foot is the untorsioned tibia's y axis (pyCGM2's "proximal
  shank": the knee's flexion axis as the shank carries it), and the uncorrected foot is
  then turned about its own z axis by a constant ``δ`` calibrated on the static trial,
  the angle that brings it onto the foot built on the torsioned tibia's own y axis
  there: ``R_uncorrected = U(TOE, AJC, y_untorsioned) @ R_z(δ)``
  (:func:`turned_uncorrected_foot`, :func:`foot_axis_correction`).  The tibial torsion
  itself is the static angle between the thigh's and the tibia's flexion axes about the
  tibia's long axis (:func:`flexion_axis_torsion`), Nexus' sign: negative when the ankle
  axis is turned externally (lateral malleolus posterior) from the knee axis.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.kinematics.vectors import cross, dot, frame_from_axes, relative_rotation, rotate_frame, unit


def side_sign(side: str) -> float:
    """``+1.0`` for the left side, ``-1.0`` for the right."""
    if side == "L":
        return 1.0
    if side == "R":
        return -1.0
    raise ValueError(f"side must be 'L' or 'R'; got {side!r}")


def long_bone_frame(
    proximal_jc: np.ndarray, distal_jc: np.ndarray, lateral_marker: np.ndarray, side: str
) -> np.ndarray:
    """Frame of a thigh or tibia, origin at ``distal_jc``.

    z = ``unit(proximal_jc - distal_jc)``; y = the component orthogonal to z of the
    direction from the lateral marker towards the subject's left (``marker - jc`` on the
    left leg, ``jc - marker`` on the right); x = y × z.  For joint centres from
    :func:`~fuzzygait.kinematics.joint_centres.chord_joint_centre` the marker direction is
    already orthogonal to z.

    Args:
        proximal_jc, distal_jc, lateral_marker: ``(n, 3)`` mm.
        side: ``"L"`` or ``"R"``.
    """
    z = unit(proximal_jc - distal_jc)
    towards_left = side_sign(side) * (lateral_marker - distal_jc)
    x = unit(cross(towards_left, z))
    y = cross(z, x)
    return frame_from_axes(x, y, z)


def untorsioned_tibia(torsioned: np.ndarray, tibial_torsion: float, side: str) -> np.ndarray:
    """Untorsioned (knee) tibia from the marker-based torsioned (ankle) tibia.

    Args:
        torsioned: ``(n, 3, 3)`` tibia frame from KJC, AJC and ANK.
        tibial_torsion: ``TibialTorsion`` in rad (Nexus' sign; see the module docstring).
        side: ``"L"`` or ``"R"``.
    """
    if tibial_torsion == 0.0:
        return torsioned
    return rotate_frame(torsioned, 2, side_sign(side) * tibial_torsion)


def uncorrected_foot(ajc: np.ndarray, toe: np.ndarray, ankle_axis: np.ndarray) -> np.ndarray:
    """Plug-in Gait foot frame before the static offsets (z from TOE to AJC).

    The same construction with HEE (possibly levelled) in place of AJC is the foot Nexus
    reports in a static trial (see :mod:`fuzzygait.kinematics.chain`).

    Args:
        ajc, toe: ``(n, 3)`` mm (``ajc``: the point the z axis points to from TOE).
        ankle_axis: ``(n, 3)`` ankle flexion axis (the untorsioned tibia's y axis).
    """
    z = unit(ajc - toe)
    x = unit(cross(ankle_axis, z))
    y = cross(z, x)
    return frame_from_axes(x, y, z)


def corrected_foot(
    uncorrected: np.ndarray, static_plant_flex: float, static_rot_off: float, side: str
) -> np.ndarray:
    """Anatomical foot frame: the uncorrected foot turned by the static offsets (rad)."""
    foot = rotate_frame(uncorrected, 1, -static_plant_flex)
    return rotate_frame(foot, 0, -side_sign(side) * static_rot_off)


def foot_offsets(uncorrected: np.ndarray, foot_axis: np.ndarray, side: str) -> np.ndarray:
    """Static offsets ``(plantar_flex, rot_off)`` in rad, per frame ``(n, 2)``.

    Inverse of :func:`corrected_foot` for the foot's long axis: ``foot_axis`` is the unit
    direction the anatomical foot z axis must take (TOE towards HEE, see
    :mod:`fuzzygait.kinematics.static`).  With ``u`` its coordinates in the uncorrected
    frame, ``plantar_flex = atan(-u_x / u_z)`` and ``rot_off = s * atan(u_y /
    sqrt(u_x² + u_z²))`` (``s = +1`` left, ``-1`` right).
    """
    u = np.einsum("nji,nj->ni", uncorrected, foot_axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        plantar_flex = np.arctan(-u[:, 0] / u[:, 2])
        rot_off = side_sign(side) * np.arctan(u[:, 1] / np.hypot(u[:, 0], u[:, 2]))
    return np.stack([plantar_flex, rot_off], axis=-1)


def flexion_axis_torsion(thigh: np.ndarray, tibia: np.ndarray, side: str) -> np.ndarray:
    """pyCGM2's tibial torsion: the angle between the knee and the ankle flexion axes about
    the tibia's long axis, per frame, rad ``(n,)``.

    With ``φ`` the azimuth of the thigh's y axis (the knee flexion axis) in the tibia's x-y
    plane, measured from the tibia's x axis towards its y axis (right-handed about the
    tibia's z axis, ``AJC -> KJC``), the torsion is ``s (φ - 90°)`` (``s = +1`` left,
    ``-1`` right), wrapped into ``[-π, π)``: 0 when the two flexion axes are parallel,
    negative when the ankle axis is turned externally from the knee axis.  The same angle
    and sign as Plug-in Gait's ``TibialTorsion`` (:mod:`fuzzygait.kinematics.kad`: ``-s``
    × the angle from KNE to ANK about ``AJC -> KJC``) whenever the thigh's y axis is the
    KNE direction, and :func:`untorsioned_tibia` turned by it has its y axis in the plane
    of the tibia's z axis and the knee flexion axis.

    Args:
        thigh: ``(n, 3, 3)`` thigh frames (y = knee flexion axis).
        tibia: ``(n, 3, 3)`` torsioned (marker-based) tibia frames (y = ankle axis).
        side: ``"L"`` or ``"R"``.
    """
    knee_axis = thigh[:, :, 1]
    azimuth = np.arctan2(dot(knee_axis, tibia[:, :, 1]), dot(knee_axis, tibia[:, :, 0]))
    return side_sign(side) * (np.mod(azimuth - np.pi / 2 + np.pi, 2 * np.pi) - np.pi)


def foot_axis_correction(
    ajc: np.ndarray, toe: np.ndarray, tibia: np.ndarray, tibial_torsion: float, side: str
) -> np.ndarray:
    """The CGM 2.3 foot's static correction ``δ`` (rad, per frame ``(n,)``): the angle about
    the uncorrected foot's z axis (``TOE -> AJC``) from the x axis of the foot built on the
    untorsioned tibia's y axis to that of the foot built on the torsioned tibia's own y
    axis, ``R_z(δ) = U(y_untorsioned)^T U(y_torsioned)``.  Calibrated on the static trial
    (mean over its frames), it makes :func:`turned_uncorrected_foot` equal the plain
    uncorrected foot there.

    Args:
        ajc, toe: ``(n, 3)`` mm.
        tibia: ``(n, 3, 3)`` torsioned tibia frames.
        tibial_torsion: rad (:func:`flexion_axis_torsion`).
        side: ``"L"`` or ``"R"``.
    """
    turned = uncorrected_foot(ajc, toe, untorsioned_tibia(tibia, tibial_torsion, side)[:, :, 1])
    relative = relative_rotation(turned, uncorrected_foot(ajc, toe, tibia[:, :, 1]))
    return np.asarray(np.arctan2(relative[:, 1, 0], relative[:, 0, 0]))


def turned_uncorrected_foot(
    ajc: np.ndarray, toe: np.ndarray, tibia: np.ndarray, tibial_torsion: float, correction: float, side: str
) -> np.ndarray:
    """The CGM 2.3 uncorrected foot with a tibial torsion: :func:`uncorrected_foot` on the
    y axis of the tibia turned by ``tibial_torsion`` (:func:`untorsioned_tibia`), then
    turned about its own z axis by ``correction`` (rad, :func:`foot_axis_correction`).

    Args:
        ajc, toe: ``(n, 3)`` mm.
        tibia: ``(n, 3, 3)`` torsioned tibia frames.
        tibial_torsion, correction: rad.
        side: ``"L"`` or ``"R"``.
    """
    axis = untorsioned_tibia(tibia, tibial_torsion, side)[:, :, 1]
    return rotate_frame(uncorrected_foot(ajc, toe, axis), 2, correction)
