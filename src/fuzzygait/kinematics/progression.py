"""The per-trial progression frame in which Plug-in Gait reports pelvis and
foot-progression angles.

Vicon does not use the laboratory frame for these angles but the laboratory axis (±X or
±Y) along which the subject walks: the axis along which the pelvis origin travels most
between the first and the last frame where it is seen. In a static trial (the pelvis
travels less than :data:`MIN_TRAVEL_MM`) it is the lab axis closest to the direction the
pelvis faces (its mean anterior axis). Z is the laboratory vertical in both cases.

Checked against Vicon Nexus output: ``Movement_trial.c3d`` (a stair descent: the pelvis
travels 1.3 m along -X and 1 m down) gives the progression frame (-X, -Y, Z) and
``Static_trial.c3d`` (standing, facing +X) the lab frame; with them the pelvis and
foot-progression angles agree with Nexus to 1e-5 degree.  The model passes the hip joint
centre midpoint (Vicon's ``PELO``) as the pelvis origin; any point of the pelvis gives
the same axis.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.core.errors import ParameterError

#: Horizontal travel of the pelvis (mm) below which a trial counts as static.
MIN_TRAVEL_MM = 200.0


def _axis_rotation(direction_xy: np.ndarray) -> np.ndarray:
    """Rotation (columns: forward, left, up in lab coordinates) for the lab axis ±X/±Y
    closest to ``direction_xy``."""
    axis = int(np.argmax(np.abs(direction_xy)))
    forward = np.zeros(3)
    forward[axis] = np.sign(direction_xy[axis]) or 1.0
    up = np.array([0.0, 0.0, 1.0])
    left = np.cross(up, forward)
    return np.column_stack([forward, left, up])


def progression_frame(pelvis_origin: np.ndarray, pelvis_anterior: np.ndarray) -> np.ndarray:
    """The progression frame of a trial.

    Args:
        pelvis_origin: ``(n_frames, 3)`` pelvis origin in the lab, mm (NaN allowed).
        pelvis_anterior: ``(n_frames, 3)`` unit anterior axis of the pelvis in the lab.

    Returns:
        ``(3, 3)`` rotation whose columns are the progression frame's forward, left and up
        axes in lab coordinates (so ``R.T @ v`` expresses a lab vector ``v`` in it).

    Raises:
        ParameterError: when the pelvis is never seen.
    """
    seen = np.all(np.isfinite(pelvis_origin), axis=1)
    if not seen.any():
        raise ParameterError("the pelvis is never visible; cannot find the walking direction")
    first, last = np.flatnonzero(seen)[[0, -1]]
    travel = pelvis_origin[last, :2] - pelvis_origin[first, :2]
    if np.linalg.norm(travel) >= MIN_TRAVEL_MM:
        return _axis_rotation(travel)
    facing = np.nanmean(pelvis_anterior[seen, :2], axis=0)
    return _axis_rotation(facing)
