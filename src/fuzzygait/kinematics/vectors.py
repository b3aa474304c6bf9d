"""Small vectorised helpers for 3-D vectors and rotation frames.

Conventions
-----------
* A vector array has shape ``(n, 3)`` (one vector per frame) in laboratory coordinates;
  a single ``(3,)`` vector broadcasts against it.
* A **frame** (segment orientation) is an ``(n, 3, 3)`` array of rotation matrices whose
  **columns** are the segment's unit x, y and z axes expressed in the laboratory frame,
  so ``lab = R @ local`` and ``local = R.T @ lab``.  ``R[:, :, 0]`` is the x axis.
* Missing samples are NaN and simply propagate (no interpolation, no warnings).

Everything works on whole trials at once; there are no per-frame Python loops.

The operations are ``autograd.numpy``'s (``anp``): on plain arrays they are numpy's, and
arrays traced for derivatives pass through them (see :mod:`fuzzygait.core.arrays`).
"""

from __future__ import annotations

import autograd.numpy as anp
import numpy as np
from autograd.extend import defvjp, primitive

from fuzzygait.core.arrays import floats

__all__ = [
    "axis_rotation",
    "cross",
    "dot",
    "frame_from_axes",
    "norm",
    "relative_rotation",
    "rotate_about",
    "rotate_frame",
    "to_lab",
    "to_local",
    "unit",
]


def _unbroadcast(gradient: np.ndarray, like: np.ndarray) -> np.ndarray:
    """``gradient`` summed back to the shape of the operand ``like`` it was broadcast from."""
    shape = np.shape(like)
    while gradient.ndim > len(shape):
        gradient = gradient.sum(axis=0)
    for axis, size in enumerate(shape):
        if size == 1 and gradient.shape[axis] != 1:
            gradient = gradient.sum(axis=axis, keepdims=True)
    return gradient


@primitive
def norm(v: np.ndarray) -> np.ndarray:
    """Euclidean length of each vector of ``(n, 3)`` -> ``(n,)``."""
    v = floats(v)
    return np.sqrt(v[..., 0] ** 2 + v[..., 1] ** 2 + v[..., 2] ** 2)


@primitive
def unit(v: np.ndarray) -> np.ndarray:
    """Vectors scaled to unit length (NaN for zero-length or missing vectors)."""
    v = floats(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / norm(v)[..., None]


@primitive
def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of ``(n, 3)`` arrays -> ``(n,)``."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


@primitive
def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product ``a x b`` of ``(n, 3)`` arrays (broadcasting)."""
    a = floats(a)
    b = floats(b)
    return np.stack(
        [
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ],
        axis=-1,
    )


# Reverse-mode derivatives of the four (one recorded operation each when traced, see
# fuzzygait.core.arrays): d|v| = u·dv;  du = (dv - u (u·dv)) / |v|;  d(a·b) = b·da + a·db;
# d(a × b) = da × b + a × db, whose adjoints are ḡ·(da × b) = da·(b × ḡ), ḡ·(a × db) = db·(ḡ × a).
defvjp(norm, lambda n, v: lambda g: g[..., None] * np.asarray(v) / n[..., None])
defvjp(unit, lambda u, v: lambda g: (g - u * dot(u, g)[..., None]) / norm(v)[..., None])
defvjp(dot, lambda d, a, b: lambda g: _unbroadcast(g[..., None] * np.asarray(b), a),
       lambda d, a, b: lambda g: _unbroadcast(g[..., None] * np.asarray(a), b))  # fmt: skip
defvjp(cross, lambda c, a, b: lambda g: _unbroadcast(cross(np.broadcast_to(b, g.shape), g), a),
       lambda c, a, b: lambda g: _unbroadcast(cross(g, np.broadcast_to(a, g.shape)), b))  # fmt: skip


def frame_from_axes(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Stack three ``(n, 3)`` axis arrays as the columns of ``(n, 3, 3)`` frames."""
    return anp.stack([x, y, z], axis=-1)


def axis_rotation(axis: int, angle: np.ndarray | float) -> np.ndarray:
    """Right-handed rotation(s) by ``angle`` (rad) about coordinate axis ``axis``
    (0 = x, 1 = y, 2 = z); ``(3, 3)`` for a scalar angle, ``(n, 3, 3)`` for ``(n,)``."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def rotate_frame(frame: np.ndarray, axis: int, angle: np.ndarray | float) -> np.ndarray:
    """Rotate each frame about its **own** axis ``axis`` by ``angle`` (rad, right-handed):
    ``frame @ R_axis(angle)``."""
    return frame @ axis_rotation(axis, angle)


def rotate_about(
    points: np.ndarray, origin: np.ndarray, axis: np.ndarray, angle: np.ndarray | float
) -> np.ndarray:
    """``points`` ``(n, 3)`` rotated by ``angle`` (rad, ``(n,)`` or scalar, right-handed)
    about the line through ``origin`` along the **unit** vector ``axis`` (Rodrigues)."""
    v = points - origin
    angle = floats(angle)[..., None]
    cos_a, sin_a = anp.cos(angle), anp.sin(angle)
    along = (1.0 - cos_a) * dot(axis, v)[..., None] * axis
    return origin + cos_a * v + sin_a * cross(axis, v) + along


def relative_rotation(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """Orientation of ``distal`` in ``proximal`` coordinates, ``proximal.T @ distal``.

    Either argument may be a single ``(3, 3)`` frame (e.g. the progression frame).
    """
    return anp.swapaxes(proximal, -1, -2) @ distal


def to_local(frame: np.ndarray, origin: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Coordinates of lab ``points`` ``(n, 3)`` in the frame at ``origin``."""
    return anp.einsum("nji,nj->ni", frame, points - origin)


def to_lab(frame: np.ndarray, origin: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Lab positions of ``local`` coordinates (``(3,)`` or ``(n, 3)``) in the frame at
    ``origin``: ``origin + frame @ local``."""
    local = floats(local)
    if local.ndim == 1:
        return origin + frame @ local
    return origin + anp.einsum("nij,nj->ni", frame, local)
