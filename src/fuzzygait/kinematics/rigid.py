"""Least-squares rigid-body pose of a marker cluster (Söderkvist & Wedin 1993).

A segment's tracking markers have fixed positions ``r_i`` in its technical frame
(calibrated on the static trial).  In each frame the pose ``(R, t)`` minimising
``sum_i w_i |R r_i + t - x_i|²`` over the *visible* markers ``x_i`` is found in closed
form: ``t`` aligns the weighted centroids and ``R = U diag(1, 1, det(U Vᵀ)) Vᵀ`` from the
SVD ``U S Vᵀ`` of the weighted cross-covariance ``Σ w_i (x_i - x̄)(r_i - r̄)ᵀ`` (the
determinant factor keeps ``R`` a rotation, never a reflection).  All frames are solved at
once (batched SVD); a frame with fewer than :data:`MIN_MARKERS` visible markers, or with
its visible markers on one line, gets NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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
    observed = np.asarray(observed, dtype=float)
    m = local.shape[0]
    if observed.ndim != 3 or observed.shape[1:] != (m, 3) or local.shape != (m, 3):
        raise ValueError(f"fit_rigid: local {local.shape} and observed {observed.shape} do not match (m, 3), (n, m, 3)")
    w = np.ones(m) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (m,) or np.any(w < 0) or not np.all(np.isfinite(w)):
        raise ValueError(f"fit_rigid: weights must be {m} finite non-negative numbers")
    visible = np.all(np.isfinite(observed), axis=2) & (w > 0)
    wv = np.where(visible, w, 0.0)  # (n, m)
    total = wv.sum(axis=1)  # (n,)
    safe_total = np.where(total > 0, total, 1.0)
    x = np.where(visible[:, :, None], observed, 0.0)
    x_bar = np.einsum("nm,nmk->nk", wv, x) / safe_total[:, None]
    r_bar = (wv @ local) / safe_total[:, None]
    xc = x - x_bar[:, None, :]
    rc = local[None, :, :] - r_bar[:, None, :]
    covariance = np.einsum("nm,nmi,nmj->nij", wv, xc, rc)
    u, _, vt = np.linalg.svd(covariance)
    d = np.sign(np.linalg.det(u @ vt))
    d = np.where(d == 0.0, 1.0, d)
    u = u.copy()
    u[:, :, 2] *= d[:, None]
    rotation = u @ vt
    origin = x_bar - np.einsum("nij,nj->ni", rotation, r_bar)
    fitted = origin[:, None, :] + np.einsum("nij,mj->nmi", rotation, local)
    squared = np.sum((fitted - observed) ** 2, axis=2)
    residual = np.sqrt(np.einsum("nm,nm->n", wv, np.where(visible, squared, 0.0)) / safe_total)
    # poses the visible markers do not fix
    spread = np.linalg.svd(rc * np.sqrt(wv)[:, :, None], compute_uv=False)  # (n, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        collinear = ~(spread[:, 1] > COLLINEAR_RATIO * spread[:, 0])
    bad = (visible.sum(axis=1) < MIN_MARKERS) | collinear
    rotation[bad] = np.nan
    origin[bad] = np.nan
    residual[bad] = np.nan
    return RigidFit(rotation, origin, residual, visible)


def frame_from_points(origin: np.ndarray, along: np.ndarray, plane: np.ndarray) -> np.ndarray:
    """Right-handed frames: x along ``along - origin``, z normal to the plane of the three
    points (``x × (plane - origin)``), y = z × x.  ``(n, 3)`` mm in, ``(n, 3, 3)`` out."""
    x = along - origin
    x = x / np.linalg.norm(x, axis=-1, keepdims=True)
    z = np.cross(x, plane - origin)
    z = z / np.linalg.norm(z, axis=-1, keepdims=True)
    return np.stack([x, np.cross(z, x), z], axis=-1)


__all__ = ["COLLINEAR_RATIO", "MIN_MARKERS", "RigidFit", "fit_rigid", "frame_from_points"]
