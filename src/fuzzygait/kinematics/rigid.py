"""Least-squares rigid-body pose of a marker cluster (Söderkvist & Wedin 1993).

A segment's tracking markers have fixed positions ``r_i`` in its technical frame
(calibrated on the static trial).  In each frame the pose ``(R, t)`` minimising
``sum_i w_i |R r_i + t - x_i|²`` over the *visible* markers ``x_i`` is found in closed
form: ``t`` aligns the weighted centroids and ``R = U diag(1, 1, det(U Vᵀ)) Vᵀ`` from the
SVD ``U S Vᵀ`` of the weighted cross-covariance ``C = Σ w_i (x_i - x̄)(r_i - r̄)ᵀ`` (the
determinant factor keeps ``R`` a rotation, never a reflection).  All frames are solved at
once; a frame with fewer than :data:`MIN_MARKERS` visible markers, or with its visible
markers on one line, gets NaN.

Speed: ``U Vᵀ`` is the orthogonal factor of the polar decomposition of ``C``, which
:func:`polar_rotation` computes by Higham's scaled Newton iteration ``X <- (γX + (γX)⁻ᵀ)/2``
on closed-form 3×3 cofactors -- about ten times faster than numpy's batched SVD and equal
to it to ~1e-15; frames where ``det C <= 0`` (the reflection case) or the iteration does
not settle fall back to the SVD.  Whether the visible markers are collinear depends only
on which markers are visible, so it is decided once per visibility pattern.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import autograd.numpy as anp
import numpy as np
from autograd.extend import defvjp, primitive

from fuzzygait.core.arrays import floats, plain, symbolic, undefined_above

#: Fewest visible markers that fix a rigid pose.
MIN_MARKERS = 3
#: Ratio of the second to the first singular value of the centred local cluster below
#: which the visible markers are taken as collinear (no rotation about their line).
COLLINEAR_RATIO = 1e-6


@dataclass(frozen=True)
class RigidFit:
    """Per-frame poses of one cluster.

    Attributes:
        rotation: ``(n, 3, 3)`` technical frame axes (columns) in the lab; NaN where not
            fixed.
        origin: ``(n, 3)`` mm, the technical frame's origin in the lab.
        residual: ``(n,)`` mm, weighted RMS distance of the visible markers from the
            fitted cluster.
        visible: ``(n, m)`` bool, the markers used in each frame.
    """

    rotation: np.ndarray
    origin: np.ndarray
    residual: np.ndarray
    visible: np.ndarray

    def to_lab(self, local: np.ndarray) -> np.ndarray:
        """A point fixed in the technical frame (``(3,)`` mm) in the lab, ``(n, 3)``."""
        return self.origin + np.einsum("nij,j->ni", self.rotation, local)


def fit_rigid(local: np.ndarray, observed: np.ndarray, weights: np.ndarray | None = None) -> RigidFit:
    """Pose of the cluster ``local`` fitted to ``observed`` in every frame.

    Args:
        local: ``(m, 3)`` mm, the markers' positions in the technical frame.
        observed: ``(n, m, 3)`` mm, lab positions, NaN where a marker is not seen.
        weights: ``(m,)`` non-negative marker weights (default all 1); a zero weight
            leaves a marker out.

    Returns:
        :class:`RigidFit`; frames with fewer than :data:`MIN_MARKERS` visible markers of
        positive weight, or collinear ones, are NaN.
    """
    local = np.asarray(local, dtype=float)
    observed = floats(observed)
    m = local.shape[0]
    if observed.ndim != 3 or observed.shape[1:] != (m, 3) or local.shape != (m, 3):
        raise ValueError(f"fit_rigid: local {local.shape} and observed {observed.shape} do not match (m, 3), (n, m, 3)")
    w = np.ones(m) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (m,) or np.any(w < 0) or not np.all(np.isfinite(w)):
        raise ValueError(f"fit_rigid: weights must be {m} finite non-negative numbers")
    if symbolic(observed):  # traced for a compiled model: every marker seen (a row missing one takes numpy)
        visible = np.ones(observed.shape[:2], dtype=bool) & (w > 0)
    else:
        visible = np.all(np.isfinite(plain(observed)), axis=2) & (w > 0)
    wv = np.where(visible, w, 0.0)  # (n, m)
    total = wv.sum(axis=1)  # (n,)
    safe_total = np.where(total > 0, total, 1.0)
    x = anp.where(visible[:, :, None], observed, 0.0)
    x_bar = anp.matmul(wv[:, None, :], x)[:, 0, :] / safe_total[:, None]
    r_bar = (wv @ local) / safe_total[:, None]
    xc = x - x_bar[:, None, :]
    rc = local[None, :, :] - r_bar[:, None, :]
    covariance = anp.matmul(anp.swapaxes(xc * wv[:, :, None], 1, 2), rc)  # sum_m w x_c r_cᵀ
    rotation = polar_rotation(covariance)
    origin = x_bar - anp.einsum("nij,nj->ni", rotation, r_bar)
    fitted = origin[:, None, :] + anp.matmul(local, anp.swapaxes(rotation, 1, 2))
    squared = anp.sum((fitted - anp.where(visible[:, :, None], observed, fitted)) ** 2, axis=2)
    residual = anp.sqrt(anp.einsum("nm,nm->n", wv, squared) / safe_total)
    bad = (visible.sum(axis=1) < MIN_MARKERS) | _collinear(local, w, visible)
    rotation = anp.where(bad[:, None, None], np.nan, rotation)
    origin = anp.where(bad[:, None], np.nan, origin)
    residual = anp.where(bad, np.nan, residual)
    return RigidFit(rotation, origin, residual, visible)


def _collinear(local: np.ndarray, weights: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """Per frame, whether the visible markers' local positions lie on one line (the pose
    about that line is not fixed); decided once per visibility pattern."""
    codes = visible.astype(np.int64) @ (np.int64(1) << np.arange(visible.shape[1], dtype=np.int64))
    patterns, which = np.unique(codes, return_inverse=True)
    flags = np.ones(len(patterns), dtype=bool)
    for k, code in enumerate(patterns):
        pattern = (int(code) >> np.arange(visible.shape[1])) & 1 == 1
        w = np.where(pattern, weights, 0.0)
        if w.sum() <= 0.0:
            continue
        centred = (local - (w @ local) / w.sum()) * np.sqrt(w)[:, None]
        spread = np.linalg.svd(centred, compute_uv=False)
        flags[k] = not spread[1] > COLLINEAR_RATIO * spread[0]
    return flags[np.ravel(which)]


Entries = list[list[np.ndarray]]


def _cofactor(a: Entries) -> tuple[Entries, np.ndarray]:
    """Cofactor matrix and determinant of 3×3 matrices given entry-wise (``a[i][j]`` a
    1-D array over the matrices, contiguous: numpy's fast path): ``a⁻ᵀ = cof / det``."""
    def minor(i: int, j: int) -> np.ndarray:
        p, q, r, s = (i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3
        return a[p][r] * a[q][s] - a[p][s] * a[q][r]

    cof = [[minor(i, j) for j in range(3)] for i in range(3)]
    return cof, a[0][0] * cof[0][0] + a[0][1] * cof[0][1] + a[0][2] * cof[0][2]


def _newton_step(a: Entries) -> Entries:
    """One scaled Newton step ``X <- (γX + (γX)⁻ᵀ)/2`` of the polar factor, entry-wise
    (``γ = (|X⁻ᵀ|_F / |X|_F)^½``; numbers or symbols alike)."""
    cof, d = _cofactor(a)
    inverse_t = [[cof[i][j] / d for j in range(3)] for i in range(3)]
    gamma = (sum(v * v for row in inverse_t for v in row) / sum(v * v for row in a for v in row)) ** 0.25
    return [[0.5 * (gamma * a[i][j] + inverse_t[i][j] / gamma) for j in range(3)] for i in range(3)]


#: Scaled Newton iterations of :func:`polar_rotation` (quadratic convergence: condition
#: numbers up to ~1e6 settle within 10) and the entry change that counts as settled.
POLAR_ITERATIONS = 12
POLAR_TOLERANCE = 1e-13


@primitive
def polar_rotation(covariance: np.ndarray) -> np.ndarray:
    """The rotation ``U diag(1, 1, det(U Vᵀ)) Vᵀ`` of the SVD ``U S Vᵀ`` of each ``(3, 3)``
    matrix in ``(n, 3, 3)`` ``covariance`` (the least-squares rotation of
    :func:`fit_rigid`), by scaled Newton iteration for the polar factor where ``det > 0``
    and by the SVD elsewhere (module docstring).

    Traced for derivatives (:mod:`fuzzygait.core.arrays`), its reverse sweep is the
    closed form of :func:`_polar_rotation_vjp`, not the iteration's.  Symbolic
    (:func:`_fixed_polar_rotation`): the iteration's fixed steps."""
    if symbolic(covariance):
        return _fixed_polar_rotation(covariance)
    covariance = np.asarray(covariance, dtype=float)
    entries = np.ascontiguousarray(np.moveaxis(covariance, 0, -1))  # (3, 3, n)
    _, det = _cofactor([[entries[i, j] for j in range(3)] for i in range(3)])
    positive = np.isfinite(det) & (det > 0.0)
    newton = np.flatnonzero(positive)
    block = entries if positive.all() else entries[:, :, newton]
    a = [[block[i, j] for j in range(3)] for i in range(3)]
    out = np.empty_like(covariance)
    previous = a
    for _ in range(POLAR_ITERATIONS if len(newton) else 0):
        previous, a = a, _newton_step(a)
        if max(float(np.abs(a[i][j] - previous[i][j]).max()) for i in range(3) for j in range(3)) < POLAR_TOLERANCE:
            break
    settled = np.zeros(out.shape[0], dtype=bool)
    if len(newton):
        result = np.array(a)  # (3, 3, k)
        settled[newton] = np.abs(result - np.array(previous)).max(axis=(0, 1)) < 1e-9
        out[newton] = np.moveaxis(result, -1, 0)
    rest = ~settled
    if rest.any():
        u, _, vt = np.linalg.svd(np.nan_to_num(covariance[rest]))
        sign = np.sign(np.linalg.det(u @ vt))
        u[:, :, 2] *= np.where(sign == 0.0, 1.0, sign)[:, None]
        out[rest] = u @ vt
    return out


#: Largest entry change of the last Newton step for which a row counts as settled (as in
#: :func:`polar_rotation`, whose rows above it take the SVD).
POLAR_SETTLED = 1e-9


def _fixed_polar_rotation(covariance: np.ndarray) -> np.ndarray:
    """:func:`polar_rotation` of a symbolic ``(n, 3, 3)`` ``covariance`` (a chain traced
    for a compiled model, :mod:`fuzzygait.markererror.row_kernel`): all
    :data:`POLAR_ITERATIONS` Newton steps (no test can stop them), and NaN where numpy
    would take the SVD — ``det C <= 0`` or a last step larger than :data:`POLAR_SETTLED`
    in sum of squares — so those rows are computed by numpy."""
    entries = np.moveaxis(covariance, 0, -1)  # (3, 3, n)
    a = [[entries[i, j] for j in range(3)] for i in range(3)]
    _, det = _cofactor(a)
    previous = a
    for _ in range(POLAR_ITERATIONS):
        previous, a = a, _newton_step(a)
    step = sum((a[i][j] - previous[i][j]) ** 2 for i in range(3) for j in range(3))
    unsettled = undefined_above(step, POLAR_SETTLED**2) + undefined_above(-det, 0.0)
    return np.moveaxis(np.array(a), -1, 0) + unsettled[:, None, None]


def _hat(x: np.ndarray) -> np.ndarray:
    """Skew matrices ``[x]×`` ``(k, 3, 3)`` of vectors ``(k, 3)``."""
    zero = np.zeros(x.shape[0])
    return np.stack([np.stack([zero, -x[:, 2], x[:, 1]], -1), np.stack([x[:, 2], zero, -x[:, 0]], -1),
                     np.stack([-x[:, 1], x[:, 0], zero], -1)], axis=1)  # fmt: skip


def _polar_rotation_vjp(rotation: np.ndarray, covariance: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Reverse-mode derivative of :func:`polar_rotation` at ``covariance`` (``(k, 3, 3)``)
    with result ``rotation``.

    ``R`` maximises ``tr(Rᵀ C)`` over rotations, so ``S = Rᵀ C`` is symmetric; keeping it so
    under ``dC`` gives ``dR = R Ω`` with ``Ω`` skew and ``S Ω + Ω S = Rᵀ dC − dCᵀ R``.  That
    operator is self-adjoint, so the cotangent ``G`` of ``R`` becomes ``C̄ = 2 R X`` with
    ``S X + X S = skew(Rᵀ G)``, and for ``X = [x]×`` the equation is ``(tr(S) I − S) x =
    vee(skew(Rᵀ G))``: one 3×3 solve per matrix.  Rows where that system is singular (a
    degenerate cluster: the rotation is not unique) or not finite get NaN."""
    s = np.swapaxes(rotation, 1, 2) @ covariance
    s = 0.5 * (s + np.swapaxes(s, 1, 2))
    system = np.trace(s, axis1=1, axis2=2)[:, None, None] * np.eye(3) - s
    with np.errstate(invalid="ignore"):
        det = np.linalg.det(np.where(np.isfinite(system), system, 0.0))
        size = np.abs(system).max(axis=(1, 2)) if system.size else np.zeros(0)
        ok = np.isfinite(system).all(axis=(1, 2)) & (np.abs(det) > 1e-12 * size**3)

    def vjp(cotangent: np.ndarray) -> np.ndarray:
        m = np.swapaxes(rotation, 1, 2) @ cotangent
        a = 0.5 * np.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]], axis=-1)
        x = np.full(a.shape, np.nan)
        x[ok] = np.linalg.solve(system[ok], a[ok][:, :, None])[:, :, 0]
        return np.asarray(2.0 * rotation @ _hat(x))

    return vjp


defvjp(polar_rotation, _polar_rotation_vjp)


def frame_from_points(origin: np.ndarray, along: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """Right-handed frames: x along ``along - origin``, z normal to the plane of the three
    points (``x × (plane - origin)``), y = z × x.  ``(n, 3)`` mm in, ``(n, 3, 3)`` out."""
    x = along - origin
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    z = np.cross(x, plane - origin)
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=-1)


__all__ = ["COLLINEAR_RATIO", "MIN_MARKERS", "RigidFit", "fit_rigid", "frame_from_points", "polar_rotation"]
