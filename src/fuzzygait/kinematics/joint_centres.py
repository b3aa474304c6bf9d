"""Joint-centre constructions of Plug-in Gait: Davis hip regression and the chord function.

All positions are in mm in the laboratory frame; arrays are ``(n, 3)``.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.kinematics.vectors import cross, dot, norm, unit

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
    half = proximal - mid
    with np.errstate(invalid="ignore"):
        angle = 2.0 * np.arccos(offset / norm(to_proximal))
    cos_a, sin_a = np.cos(angle)[:, None], np.sin(angle)[:, None]
    # Rodrigues' rotation of ``half`` about ``normal`` (``half`` is perpendicular to it).
    along_normal = (1.0 - cos_a) * dot(normal, half)[:, None] * normal  # 0 up to rounding
    return mid + cos_a * half + sin_a * cross(normal, half) + along_normal
