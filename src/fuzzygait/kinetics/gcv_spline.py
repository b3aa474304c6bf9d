"""Second derivatives by a quintic smoothing spline whose smoothing is chosen by
generalised cross-validation (Woltring's GCVSPL with m = 3, as Vicon Nexus' Plug-in
Gait differentiates the segments' centres of mass).

For samples ``x_i`` at equal steps (one frame) the natural quintic smoothing spline
minimises ``sum |x_i - s(t_i)|² + λ ∫ |s'''(t)|² dt`` over the trial; the three
components of a trajectory share one λ.  With the spline's values at the frames
``u = (I + λ K)⁻¹ x`` (``K`` the penalty in terms of the node values, the same for every
trajectory of ``n`` frames), generalised cross-validation picks λ where

``GCV(λ) = RSS(λ) / (n - tr H(λ))²``,  ``H = (I + λ K)⁻¹``

has its first local minimum coming from heavy smoothing (large λ) towards
interpolation; without one, the smallest λ of the search (nearly interpolating).  The
acceleration is the spline's second derivative at the frames.

Found by the joint forces Nexus stores (``docs/kinetics.md``): the centre-of-mass
acceleration they imply equals this spline's to 1e-4 m/s² RMS on the unfiltered
``PiGKad_Motion.c3d`` (the five-point differences: 0.2-0.7), at the edge frames of
``PiG_Motion-FlatFoot-Full.c3d`` too, and on the filtered trials (where GCV all but
interpolates) to 1e-4 as well.

``K`` is diagonalised once per trial length (``O(n³)``, cached); each trajectory then
costs ``O(n²)``.  Natural quintic splines with a knot at every frame: B-splines of
degree 5, ``s'''`` and ``s''''`` zero at both ends.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import BSpline
from scipy.linalg import null_space

Array = NDArray[np.float64]

#: log10 λ searched (λ in frame units: time measured in frames), from heavy smoothing
#: down to all but interpolation, and the grid step.
LOG_LAMBDA_RANGE = (8.0, -10.0)
LOG_LAMBDA_STEP = 0.05
#: Fewer frames than this: no spline (NaN), as too short to cross-validate.
MIN_FRAMES = 12


@dataclass(frozen=True)
class _Basis:
    """The penalty's eigenvectors ``v`` (columns) and eigenvalues ``lam`` (>= 0) for ``n``
    frames, and ``second_v``: the spline's second derivative at the frames (per frame²)
    of each eigenvector's node values."""

    v: Array
    lam: Array
    second_v: Array


@lru_cache(maxsize=8)
def _basis(n: int) -> _Basis:
    """:class:`_Basis` for ``n`` frames (time in frames)."""
    t = np.arange(n, dtype=float)
    knots = np.r_[[0.0] * 5, t, [t[-1]] * 5]
    size = n + 4
    spline = BSpline(knots, np.eye(size), 5)
    values = spline(t)
    ends = np.array([t[0], t[-1]])
    natural = np.vstack([spline.derivative(3)(ends), spline.derivative(4)(ends)])
    null = null_space(natural)  # (size, n): the natural splines' coefficients
    nodes, weights = np.polynomial.legendre.leggauss(3)  # exact for the quartic (s''')²
    points = (t[:-1, None] + 0.5 + 0.5 * nodes[None, :]).ravel()
    third = spline.derivative(3)(points) @ null
    penalty = third.T @ (np.tile(0.5 * weights, n - 1)[:, None] * third)
    to_nodes_inverse = np.linalg.inv(values @ null)  # node values -> natural-spline coordinates
    k = to_nodes_inverse.T @ penalty @ to_nodes_inverse
    lam, v = np.linalg.eigh(0.5 * (k + k.T))
    second = spline.derivative(2)(t) @ null @ to_nodes_inverse
    return _Basis(v, np.clip(lam, 0.0, None), second @ v)


def clear_basis_cache() -> None:
    """Forget the cached eigenbases (to time their construction for a new trial length)."""
    _basis.cache_clear()


def gcv_log_lambda(x: Array) -> float:
    """log10 of the λ (frame units) GCV picks for the ``(n, c)`` samples ``x`` (no NaN):
    the first local minimum of GCV on a grid from :data:`LOG_LAMBDA_RANGE`'s heavy
    smoothing downwards (the grid's last λ without one), refined to 1e-3 by
    golden-section search between the grid's neighbours."""
    basis = _basis(len(x))
    projected_sq = ((basis.v.T @ x) ** 2).sum(axis=1)

    def gcv(log_lambda: Array) -> Array:
        lam = 10.0 ** np.asarray(log_lambda, dtype=float)[..., None] * basis.lam
        shrink = lam / (1.0 + lam)  # 1 - H's eigenvalues; their sum is n - tr H
        return ((shrink**2) @ projected_sq) / np.maximum(shrink.sum(axis=-1), 1e-300) ** 2

    top, bottom = LOG_LAMBDA_RANGE
    grid = np.arange(top, bottom - 1e-9, -LOG_LAMBDA_STEP)
    values = gcv(grid)
    minima = np.flatnonzero((values[1:-1] <= values[:-2]) & (values[1:-1] <= values[2:])) + 1
    if not len(minima):
        return float(grid[-1])
    best = int(minima[0])
    lo, hi = float(grid[best + 1]), float(grid[best - 1])
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    while hi - lo > 1e-3:
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        if gcv(np.array(a)) <= gcv(np.array(b)):
            hi = b
        else:
            lo = a
    return 0.5 * (lo + hi)


def spline_second_derivative(x: Array, rate: float) -> Array:
    """``(n, c)``: the second time derivative (units of ``x`` per s²) of the quintic GCV
    smoothing spline through ``x`` (``(n, c)`` samples at ``rate`` Hz, the components
    sharing one λ), at every frame, the first and last included.  Each run of frames
    without NaN is its own spline; runs shorter than :data:`MIN_FRAMES` and NaN frames
    give NaN."""
    x = np.asarray(x, dtype=float)
    out = np.full(x.shape, np.nan)
    finite = np.all(np.isfinite(x.reshape(len(x), -1)), axis=1)
    edges = np.flatnonzero(np.diff(np.r_[0, finite.astype(np.int8), 0]))
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        if stop - start < MIN_FRAMES:
            continue
        run = x[start:stop].reshape(stop - start, -1)
        basis = _basis(stop - start)
        lam = 10.0 ** gcv_log_lambda(run) * basis.lam
        smoothed = (basis.v.T @ run) / (1.0 + lam)[:, None]
        out[start:stop] = (basis.second_v @ smoothed * rate**2).reshape(x[start:stop].shape)
    return out
