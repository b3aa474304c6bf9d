"""Plug-in Gait joint and segment angles from segment frames.

One decomposition serves every joint: the orientation of the distal frame in the
proximal frame, ``R = P.T @ D``, is split as intrinsic Y-X-Z Cardan angles (Grood-Suntay
order: first about the proximal y (flexion) axis, last about the distal z axis)::

    R = R_y(a) @ R_x(b) @ R_z(c)
    a = atan2(R[0, 2], R[2, 2]),  b = asin(-R[1, 2]),  c = atan2(R[1, 0], R[1, 1])

with ``b`` in [-90°, 90°] and ``a``, ``c`` in (-180°, 180°].  Each output then takes one
component with a sign and an offset from :data:`ANGLE_TABLE` (the right side's signs; the
left side's Y and Z are negated, which mirrors abduction/adduction and rotation):

==================  ===============  ========================================
output              proximal/distal  X, Y, Z (right side)
==================  ===============  ========================================
PelvisAngles        progression /    a, -b, c
                    pelvis
HipAngles           pelvis / thigh   -a, b, c
KneeAngles          thigh /          a, b, c
                    untorsioned tibia
AnkleAngles         torsioned tibia  -a - 90°, c, b
                    / foot
FootProgressAngles  progression /    a, -c, b
                    foot
ForeFootAngles      hindfoot /       -a, c, b
(CGM 2.4)           forefoot
==================  ===============  ========================================

Because the Plug-in Gait foot frame has its z axis along the foot (see
:mod:`fuzzygait.kinematics.segments`), the ankle's Y output is the rotation about the
foot's long axis and its Z output the rotation about the floating axis; in a foot frame
with x along the foot this is Vicon's documented Y-Z-X ankle sequence.  All outputs are in
degrees; X/Y/Z = sagittal/frontal/transverse as in Vicon's ``*Angles`` outputs.  Ankle X
is wrapped into (-180°, 180°] like the others.
"""

from __future__ import annotations

import autograd.numpy as anp
import numpy as np
from autograd.extend import defvjp, primitive

from fuzzygait.core.arrays import each, symbolic
from fuzzygait.kinematics.vectors import relative_rotation

#: Joint / segment name -> (component index per output X,Y,Z; right-side signs;
#: offsets in degrees).  Components: 0 = a (about proximal y), 1 = b (floating x),
#: 2 = c (about distal z).
Triple = tuple[float, float, float]
ANGLE_TABLE: dict[str, tuple[tuple[int, int, int], Triple, Triple]] = {
    "Pelvis": ((0, 1, 2), (1.0, -1.0, 1.0), (0.0, 0.0, 0.0)),
    "Hip": ((0, 1, 2), (-1.0, 1.0, 1.0), (0.0, 0.0, 0.0)),
    "Knee": ((0, 1, 2), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0)),
    "Ankle": ((0, 2, 1), (-1.0, 1.0, 1.0), (-90.0, 0.0, 0.0)),
    "FootProgress": ((0, 2, 1), (1.0, -1.0, 1.0), (0.0, 0.0, 0.0)),
    # CGM 2.4 forefoot relative to hindfoot: the ankle's decomposition, no offset
    "ForeFoot": ((0, 2, 1), (-1.0, 1.0, 1.0), (0.0, 0.0, 0.0)),
    # CGM 1.1+ pelvis ("ROT", Baker 2001): Z-X-Y components (0 = c about z, 1 = b, 2 = a)
    "PelvisROT": ((2, 1, 0), (1.0, -1.0, 1.0), (0.0, 0.0, 0.0)),
}
#: Joints decomposed Z-X-Y (:func:`cardan_zxy`) instead of Y-X-Z.
ZXY_JOINTS = frozenset({"PelvisROT"})

#: Sign factors applied on top of the right-side signs for the left side.
LEFT_MIRROR = np.array([1.0, -1.0, -1.0])


def cardan_yxz(rotation: np.ndarray) -> np.ndarray:
    """Intrinsic Y-X-Z angles ``(a, b, c)`` in **degrees** of ``(n, 3, 3)`` rotations
    ``R = R_y(a) R_x(b) R_z(c)``; NaN rows stay NaN."""
    r = rotation
    a = anp.arctan2(r[:, 0, 2], r[:, 2, 2])
    b = capped_arcsin(-r[:, 1, 2])
    c = anp.arctan2(r[:, 1, 0], r[:, 1, 1])
    return anp.degrees(anp.stack([a, b, c], axis=-1))


def cardan_zxy(rotation: np.ndarray) -> np.ndarray:
    """Intrinsic Z-X-Y angles ``(c, b, a)`` in **degrees** of ``(n, 3, 3)`` rotations
    ``R = R_z(c) R_x(b) R_y(a)`` (rotation, obliquity, tilt); NaN rows stay NaN."""
    r = rotation
    c = anp.arctan2(-r[:, 0, 1], r[:, 1, 1])
    b = capped_arcsin(r[:, 2, 1])
    a = anp.arctan2(-r[:, 2, 0], r[:, 2, 2])
    return anp.degrees(anp.stack([c, b, a], axis=-1))


@primitive
def capped_arcsin(x: np.ndarray) -> np.ndarray:
    """``arcsin`` (rad) of ``x`` clipped to [-1, 1] (a rotation matrix's entry may exceed
    1 by rounding).  Its reverse sweep stays finite at the cap, where the derivative is
    infinite: ``1 / sqrt(max(1 - x², 1e-12))``, a steep but usable ascent direction for
    the α-level optimiser (the plain chain rule gives ``inf · 0 = NaN`` there).  A
    symbolic array's elements give their own (``element.capped_arcsin()``)."""
    if symbolic(x):
        return each(x, "capped_arcsin")
    return np.arcsin(np.clip(x, -1.0, 1.0))


defvjp(capped_arcsin, lambda b, x: lambda g: g / np.sqrt(np.maximum(1.0 - np.square(x), 1e-12)))


def wrap_degrees(angles: np.ndarray) -> np.ndarray:
    """Angles wrapped into (-180, 180] degrees."""
    return 180.0 - anp.mod(180.0 - angles, 360.0)


def joint_angles(proximal: np.ndarray, distal: np.ndarray, joint: str, side: str) -> np.ndarray:
    """Plug-in Gait angles ``(n, 3)`` in degrees of ``distal`` relative to ``proximal``.

    Args:
        proximal: ``(n, 3, 3)`` frames, or one ``(3, 3)`` frame (the progression frame).
        distal: ``(n, 3, 3)`` frames.
        joint: a key of :data:`ANGLE_TABLE` (``"Pelvis"``, ``"Hip"``, ``"Knee"``,
            ``"Ankle"``, ``"FootProgress"``; ``"PelvisROT"``: the CGM 1.1+ pelvis, Z-X-Y).
        side: ``"L"`` or ``"R"``.
    """
    order, table_signs, offsets = ANGLE_TABLE[joint]
    signs = np.asarray(table_signs) * (LEFT_MIRROR if side == "L" else 1.0)
    decompose = cardan_zxy if joint in ZXY_JOINTS else cardan_yxz
    components = decompose(relative_rotation(proximal, distal))
    return wrap_degrees(components[:, list(order)] * signs + np.asarray(offsets))
