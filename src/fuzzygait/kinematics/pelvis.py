"""Plug-in Gait pelvis segment.

Origin and axes (lab coordinates, mm):

* ASIS midpoint ``(LASI + RASI) / 2`` is the technical origin used for the hip joint
  centres; Vicon's exported pelvis origin (``PELO``) is the mid-point of the two hip joint
  centres (see :mod:`fuzzygait.kinematics.virtual_markers`).
* y (left): ``unit(LASI - RASI)``;
* x (anterior): the part of ``ASIS midpoint - SACR`` orthogonal to y, normalised, where
  ``SACR`` is the sacrum marker or, when absent, the mid-point of LPSI and RPSI;
* z (up): ``x × y``.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.kinematics.vectors import cross, dot, frame_from_axes, unit


def pelvis_frame(
    lasi: np.ndarray, rasi: np.ndarray, sacrum: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pelvis origin (ASIS midpoint, ``(n, 3)`` mm) and frame ``(n, 3, 3)``.

    Args:
        lasi, rasi: ASIS markers, ``(n, 3)`` mm.
        sacrum: SACR marker or the PSIS midpoint, ``(n, 3)`` mm.
    """
    origin = 0.5 * (lasi + rasi)
    y = unit(lasi - rasi)
    back_to_front = origin - sacrum
    x = unit(back_to_front - dot(back_to_front, y)[:, None] * y)
    z = cross(x, y)
    return origin, frame_from_axes(x, y, z)


def inter_asis_distance(lasi: np.ndarray, rasi: np.ndarray) -> float:
    """Mean LASI-RASI distance (mm) over the frames where both are seen (NaN if never)."""
    d = np.linalg.norm(lasi - rasi, axis=1)
    d = d[np.isfinite(d)]
    return float(d.mean()) if d.size else float("nan")
