"""The feet of the synthetic CGM 2.4 session (:mod:`fuzzygait.synthetic.cgm24`): the
CGM 2.4 forefoot -- pyCGM2's forefoot frame on exact markers
(:func:`pycgm2_forefoot_frame`), ForeFootAngles to and from the forefoot's rotation, the
static (neutral) ForeFootAngles and the known walking curves -- and pyCGM2's CGM 2.3 foot
of a walker with a tibial torsion (:func:`cgm23_foot_rotation`), the truth of
``make_cgm24_walking(foot_truth="cgm2.3")``.

The definitions are in the :mod:`~fuzzygait.synthetic.cgm24` docstring ("Forefoot
definition", "Tibial torsion").
"""

from __future__ import annotations

import numpy as np

from fuzzygait.synthetic.cgm24_geometry import Cgm24Geometry
from fuzzygait.synthetic.gait_curves import FourierCurve, limb_phase
from fuzzygait.synthetic.leg_model import (
    Pose,
    _apply,
    _side_factor,
    joint_angles_from_rotation,
    joint_rotation,
    rot_z,
)

#: Forefoot-marker excursion from the static pose during walking: ForeFootAngles
#: (degrees, ``(X, Y, Z)``) minus the static (neutral) ones, as functions of the limb's
#: own phase; a few degrees, smooth, periodic.
FOREFOOT_DEVIATION_CURVES: tuple[FourierCurve, FourierCurve, FourierCurve] = (
    FourierCurve(1.0, (1.5, -1.0), (-2.5, 0.5)),
    FourierCurve(-0.5, (1.0, 0.3), (2.0, -0.4)),
    FourierCurve(0.5, (-1.5, 0.5), (1.0, 0.2)),
)
#: Diameter pyCGM2 uses to put the forefoot joint centre below TOE, mm (its default).
FJC_MARKER_DIAMETER = 14.0


# ----------------------------------------------------------------------------- forefoot
def forefoot_rotation(angles: np.ndarray, side: str) -> np.ndarray:
    """Forefoot relative to hindfoot, ``(n, 3, 3)``, from ForeFootAngles ``(n, 3)`` (deg).

    pyCGM2's CGM 2.4 definition (``R_rel = R_hindfoot^T R_forefoot`` of its anatomical
    frames, intrinsic Y-X-Z Cardan ``(e1, e2, e3)``, left output ``(-e1, -e3, -e2)``, right
    ``(-e1, +e3, +e2)``; both frames with Z along the foot, posterior, X dorsal, Y left)
    written in this package's foot frames (x anterior, y left, z dorsal = pyCGM2's frame
    turned by ``R_y(90 deg)``) is the ankle's Y-Z-X sequence with the ankle's signs:
    ``R_y(-X) @ R_z(-s Z) @ R_x(s Y)`` (``s = +1`` left, ``-1`` right), i.e.
    :func:`~fuzzygait.synthetic.leg_model.joint_rotation` with ``joint="ankle"``.  So X
    + = forefoot dorsiflexion (toes up), Y + = the forefoot's lateral border up
    (eversion-like, as the Plug-in Gait ankle Y), Z + = forefoot adduction (toes medial).
    """
    a = np.atleast_2d(np.asarray(angles, dtype=float))
    return joint_rotation(a[:, 0], a[:, 1], a[:, 2], side, "ankle")


def forefoot_angles_from_rotation(rotation: np.ndarray, side: str) -> np.ndarray:
    """ForeFootAngles ``(n, 3)`` in degrees of ``R_hindfoot^T @ R_forefoot``.

    The exact inverse of :func:`forefoot_rotation` (for ``|Y| < 90`` deg).
    """
    return joint_angles_from_rotation(rotation, side, "ankle")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


#: pyCGM2's foot axes (X dorsal, Y left, Z posterior) in this package's foot axes (x
#: anterior, y left, z dorsal): ``R_pyCGM2 = R_here @ _PYCGM2_FOOT_AXES``.
_PYCGM2_FOOT_AXES = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])


def pycgm2_forefoot_frame(
    toe: np.ndarray, fmh: np.ndarray, vmh: np.ndarray, smh: np.ndarray, side: str,
    diameter: float = FJC_MARKER_DIAMETER,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """pyCGM2's CGM 2.4 forefoot construction on one set of marker positions (3-vectors).

    * FJC: ``n = unit(VMH - TOE) x unit(FMH - TOE)``, ``z = -n`` (left) / ``+n`` (right),
      ``FJC = TOE - diameter z``;
    * technical frame [FMH, TOE, VMH]: ``Z = unit(TOE - FMH)``, ``X = -/+ unit(Z x (VMH -
      FMH))`` (left/right), ``Y = Z x X``; vSMH = SMH with its local X set to 0 (SMH
      projected onto the TOE-FMH-VMH plane);
    * anatomical frame [vSMH, FJC, VMH]: ``Z = unit(FJC - vSMH)``, ``X = -/+ unit(Z x
      (VMH - vSMH))``, ``Y = Z x X``, origin vSMH.

    Returns ``(fjc, vsmh, axes)`` with ``axes`` the anatomical frame in **this package's
    foot-axis convention** (columns x anterior, y left, z dorsal: pyCGM2's ``[X Y Z] @
    _PYCGM2_FOOT_AXES.T``), in the coordinates the points are given in.
    """
    sign = -_side_factor(side)  # pyCGM2: ZXiY (X = -a2) on the left, ZXY on the right
    n = np.cross(_unit(vmh - toe), _unit(fmh - toe))
    fjc = toe - diameter * (sign * n)

    def frame(a1: np.ndarray, v: np.ndarray) -> np.ndarray:
        z = _unit(a1)
        x = sign * _unit(np.cross(z, v))
        return np.stack([x, np.cross(z, x), z], axis=-1)

    technical = frame(toe - fmh, vmh - fmh)
    local = technical.T @ (smh - toe)
    vsmh = toe + technical @ np.array([0.0, local[1], local[2]])
    anatomical = frame(fjc - vsmh, vmh - vsmh)
    return fjc, vsmh, anatomical @ _PYCGM2_FOOT_AXES.T


def forefoot_static_axes(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """``Q``: pyCGM2's forefoot anatomical frame in the static hindfoot frame, ``(3, 3)``."""
    local = geometry.foot_local(side)
    return pycgm2_forefoot_frame(local["TOE"], local["FMH"], local["VMH"], local["SMH"], side)[2]


def fjc_local(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """pyCGM2's forefoot joint centre in the hindfoot frame (AJC origin), mm."""
    local = geometry.foot_local(side)
    return pycgm2_forefoot_frame(local["TOE"], local["FMH"], local["VMH"], local["SMH"], side)[0]


def neutral_forefoot_angles(geometry: Cgm24Geometry | None, side: str) -> np.ndarray:
    """ForeFootAngles ``(3,)`` (deg) of the static pose (forefoot markers as placed)."""
    g = geometry or Cgm24Geometry()
    return forefoot_angles_from_rotation(forefoot_static_axes(g, side)[None], side)[0]


def forefoot_angle_curves(
    phase: np.ndarray | float, side: str, geometry: Cgm24Geometry | None = None
) -> np.ndarray:
    """Known ForeFootAngles ``(n, 3)`` (deg) at the global ``phase`` for ``side``:
    :func:`neutral_forefoot_angles` + :data:`FOREFOOT_DEVIATION_CURVES`."""
    p = limb_phase(np.atleast_1d(np.asarray(phase, dtype=float)), side)
    deviation = np.stack([curve(p) for curve in FOREFOOT_DEVIATION_CURVES], axis=-1)
    return neutral_forefoot_angles(geometry, side) + deviation


# ----------------------------------------------------------------------------- CGM 2.3 foot
def _turn_about(axis: np.ndarray, from_axis: np.ndarray, to_axis: np.ndarray) -> np.ndarray:
    """Per row, the angle (rad) about the unit ``axis`` from ``unit(from_axis × axis)`` to
    ``unit(to_axis × axis)``: how far the uncorrected-foot x axis built on ``to_axis``
    is turned from the one built on ``from_axis``."""
    a = np.cross(from_axis, axis)
    b = np.cross(to_axis, axis)
    a /= np.linalg.norm(a, axis=-1, keepdims=True)
    b /= np.linalg.norm(b, axis=-1, keepdims=True)
    return np.arctan2(np.einsum("ni,ni->n", axis, np.cross(a, b)), np.einsum("ni,ni->n", a, b))


def _knee_axis_in_shank(geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """The knee flexion axis in the posed shank's frame: ``R_z(s τ) e_y``, ``(3,)``."""
    return rot_z(_side_factor(side) * geometry.torsion(side))[0] @ np.array([0.0, 1.0, 0.0])


def cgm23_static_correction(geometry: Cgm24Geometry, side: str) -> float:
    """``δ`` (rad): :func:`_turn_about` of the static pose (foot = shank frame, TOE at
    ``toe_local`` from the AJC), from the knee axis to the shank's y axis."""
    long_axis = -np.asarray(geometry.foot_local(side)["TOE"], dtype=float)
    long_axis /= np.linalg.norm(long_axis)
    knee = _knee_axis_in_shank(geometry, side)
    return float(_turn_about(long_axis[None], knee[None], np.array([[0.0, 1.0, 0.0]]))[0])


def cgm23_foot_rotation(pose: Pose, geometry: Cgm24Geometry, side: str) -> np.ndarray:
    """pyCGM2's CGM 2.3 foot of a posed walker, ``(n, 3, 3)`` in this package's foot axes:
    the posed hindfoot turned about ``z_u = unit(AJC - TOE)`` by ``δ - γ(t)`` (``cgm24``
    docstring, "Tibial torsion"); the posed hindfoot itself without torsion."""
    R_foot = pose.rotations[side + "Foot"]
    if geometry.torsion(side) == 0.0:
        return R_foot
    R_shank = pose.rotations[side + "Shank"]
    long_axis = pose.joint_centres[side + "AJC"] - pose.markers[side + "TOE"]
    long_axis = long_axis / np.linalg.norm(long_axis, axis=-1, keepdims=True)
    knee = _apply(R_shank, _knee_axis_in_shank(geometry, side))
    angle = cgm23_static_correction(geometry, side) - _turn_about(long_axis, knee, R_shank[:, :, 1])
    c, s_ = np.cos(angle)[:, None, None], np.sin(angle)[:, None, None]
    k = long_axis
    skew = np.zeros(k.shape + (3,))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    skew -= np.swapaxes(skew, 1, 2)
    turn = c * np.eye(3) + s_ * skew + (1.0 - c) * np.einsum("ni,nj->nij", k, k)
    return turn @ R_foot
