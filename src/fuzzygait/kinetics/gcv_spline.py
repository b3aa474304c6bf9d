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

Banded, ``O(n)`` per trajectory and per λ (Reinsch's formulation for degree ``2m - 1``).
A natural quintic spline's ``s'''`` is a quadratic spline vanishing with its slope at
both ends: ``s''' = sum_k γ_k N(t - k)``, ``N`` the cardinal quadratic B-spline
(support three frames, ``k = 0 … n - 4``).  By the Peano kernel of the third difference
``Δu_j = u_{j+3} - 3u_{j+2} + 3u_{j+1} - u_j = ∫ N(t - j) s'''(t) dt``, i.e. ``Δu = G γ``
with ``G`` the B-splines' Gram matrix (Toeplitz 11/20, 13/60, 1/120), so
``K = Δᵀ G⁻¹ Δ``, and the smoothing is one banded SPD system of ``n - 3`` unknowns and
half-bandwidth 3:

``(G + λ Δ Δᵀ) γ = Δ x``,  ``u = x - λ Δᵀ γ``,  ``n - tr H = λ tr((G + λ Δ Δᵀ)⁻¹ Δ Δᵀ)``.

``A = G + λ Δ Δᵀ`` is Toeplitz, so its inverse's band (all the trace needs) follows from
its first column ``a = A⁻¹ e_0`` by the Gohberg–Semencul formula
``A⁻¹ = (L(a) L(a)ᵀ - L(b) L(b)ᵀ) / a_0`` (``L(v)`` lower-triangular Toeplitz with first
column ``v``, ``b = (0, a_{N-1}, …, a_1)``): band sums are weighted sums of lagged
products, ``O(n)``.  The grid's λ are solved together as one block-diagonal banded
system (LAPACK ``pbtrf``/``pbtrs``), in chunks of bounded size.  ``s''`` at a frame
follows from the second difference of ``u`` and ``γ`` (Peano kernel of the second
difference).

The grid search of trajectories of 12 … 729 frames runs in the sine basis instead (all
361 λ and all of a trial's trajectories in a few matrix products, the per-length parts
cached): ``G`` and ``ΔΔᵀ`` are polynomials in ``T = tridiag(-1, 2, -1)``, which the
orthonormal DST-I diagonalises (eigenvalues ``μ = 4 sin²(θ/2)``, ``ΔΔᵀ`` ↔ ``μ³``), except
for ``2 × 2`` blocks at both ends of the diagonal, which Woodbury's identity adds back
(:func:`_sine_grid`).  Its GCV equals the banded solves' within 1e-12 where λ ≤ 1 and
1e-6 above (where the banded system's condition, up to 6e9, limits them); the chosen
λ's golden-section refinement and the second derivative stay banded, so on every shared
trial's centres of mass the λ and accelerations are bit-for-bit those of the banded
search (``tests/kinetics/test_gcv_spline.py``; all 46 shared trajectories checked once).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray
from scipy.fft import dst
from scipy.linalg.lapack import dpbtrf, dpbtrs

from fuzzygait.core.errors import ParameterError

Array = NDArray[np.float64]

#: log10 λ searched (λ in frame units: time measured in frames), from heavy smoothing
#: down to all but interpolation, and the grid step.
LOG_LAMBDA_RANGE = (8.0, -10.0)
LOG_LAMBDA_STEP = 0.05
#: Fewer frames than this: no spline (NaN), as too short to cross-validate.
MIN_FRAMES = 12
#: Unknowns (frames × λ) solved in one block-diagonal system: bounds the work memory
#: (about 80 bytes each) whatever the trial's length.
CHUNK_UNKNOWNS = 1 << 18
#: The search grid: log10 λ from the range's top down, in steps of LOG_LAMBDA_STEP.
_GRID = np.arange(LOG_LAMBDA_RANGE[0], LOG_LAMBDA_RANGE[1] - 1e-9, -LOG_LAMBDA_STEP)

#: Third difference ``Δ`` (frames j … j+3), the Gram matrix ``G`` of the cardinal
#: quadratic B-splines and ``Δ Δᵀ`` by diagonal offset 0 … 3 (both Toeplitz).
_DELTA = np.array([-1.0, 3.0, -3.0, 1.0])
_GRAM = np.array([11.0 / 20.0, 13.0 / 60.0, 1.0 / 120.0, 0.0])
_DDT = np.array([20.0, -15.0, 6.0, -1.0])


def _peano_second() -> Array:
    """Weights ``w_d`` (d = -3 … 0) with ``s''(i) = Δ²u_i - sum_d w_d γ_{i+d}`` at an inner
    frame ``i``: ``Δ²u_i = ∫ hat(t - i) s''(t) dt`` and ``s''(t) = s''(i) + ∫_i^t s'''``,
    integrated exactly (3-point Gauss–Legendre on each frame interval: quartic pieces)."""
    nodes, weights = np.polynomial.legendre.leggauss(3)

    def bspline(t: Array) -> Array:  # cardinal quadratic B-spline on [0, 3]
        return np.where((t >= 0) & (t < 1), t**2 / 2, np.where((t >= 1) & (t < 2), (-2 * t**2 + 6 * t - 3) / 2,
                        np.where((t >= 2) & (t <= 3), (3 - t) ** 2 / 2, 0.0)))  # fmt: skip

    out = np.zeros(4)
    for left in (-1.0, 0.0):  # the frame intervals [i-1, i] and [i, i+1], i = 0
        tau = left + 0.5 + 0.5 * nodes
        kernel = np.where(tau >= 0, (1 - tau) ** 2 / 2, -((1 + tau) ** 2) / 2)  # ∫ hat · 1[τ between i and t]
        for d in range(-3, 1):
            out[d + 3] += float(np.sum(0.5 * weights * kernel * bspline(tau - d)))
    return out


_SECOND = _peano_second()


@dataclass(frozen=True)
class _Factor:
    """The Cholesky factors of the blocks ``A = G + λ ΔΔᵀ`` of ``n`` frames for ``L``
    values λ (LAPACK's upper band, ``(4, L·(n - 3))``, the blocks one after the other) and
    ``n - tr H`` per λ (``(L,)``)."""

    cholesky: Array
    shrink: Array


def _factor(n: int, lam: Array) -> _Factor:
    """:class:`_Factor` of ``n`` frames for the values ``lam``: one block-diagonal banded
    Cholesky (LAPACK ``pbtrf``); the trace from ``a = A⁻¹ e_0`` (Gohberg–Semencul)."""
    size, count = n - 3, len(lam)
    band = np.empty((count * size, 4))  # Fortran order (4, count·size)
    blocks = band.reshape(count, size, 4)
    for d in range(4):  # row 3 - d holds the d-th superdiagonal
        blocks[:, :, 3 - d] = _GRAM[d] + lam[:, None] * _DDT[d]
        blocks[:, :d, 3 - d] = 0.0  # no coupling between the blocks
    cholesky, info = dpbtrf(band.T, lower=0, overwrite_ab=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"banded smoothing system not positive definite (LAPACK info {info})")
    first = np.zeros((count, size))
    first[:, 0] = 1.0
    a = _solve(cholesky, first[None])[0]
    b = np.zeros_like(a)
    b[:, 1:] = a[:, :0:-1]
    trace = np.zeros(count)
    for d in range(4):  # sum_i (A⁻¹)_{i,i+d} = sum_j (size - d - j) (a_j a_{j+d} - b_j b_{j+d}) / a_0
        weight = np.arange(size - d, 0, -1, dtype=float)
        lagged = a[:, : size - d] * a[:, d:] - b[:, : size - d] * b[:, d:]
        trace += (1.0 if d == 0 else 2.0) * _DDT[d] * (lagged @ weight)
    return _Factor(cholesky, lam * trace / a[:, 0])


def _solve(cholesky: Array, rhs: Array) -> Array:
    """``A⁻¹ rhs`` per block: ``rhs`` ``(c, L, n - 3)``, the same shape back (``pbtrs``)."""
    columns = len(rhs)
    solution, info = dpbtrs(cholesky, np.ascontiguousarray(rhs).reshape(columns, -1).T, lower=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"banded smoothing solve failed (LAPACK info {info})")
    return np.asarray(solution).T.reshape(rhs.shape)


def _third_differences(x: Array) -> Array:
    """``Δx``: ``(c, n - 3)`` of the ``(n, c)`` samples ``x``."""
    return (np.lib.stride_tricks.sliding_window_view(x, 4, axis=0) @ _DELTA).T


def _gcv_batch(dx: Array, width: int, lam: Array, factor: _Factor) -> Array:
    """``(t, L)``: GCV of ``t`` trajectories of ``width`` components each at the values
    ``lam`` of ``factor``, from their third differences ``dx`` (``(t·width, n - 3)``, the
    trajectories' components one after the other): one banded solve of all of them."""
    columns, size = dx.shape
    gamma = _solve(factor.cholesky, np.broadcast_to(dx[:, None, :], (columns, len(lam), size)))
    residual = _transpose_delta(gamma)
    residual *= lam[:, None]  # x - u: (t·width, L, n)
    np.square(residual, out=residual)
    rss = np.stack([residual[k : k + width].sum(axis=(0, 2)) for k in range(0, columns, width)])
    return rss / np.maximum(factor.shrink, 1e-300) ** 2


def _gcv_of(x: Array, lam: Array, factor: _Factor) -> Array:
    """GCV of the ``(n, c)`` samples ``x`` at the values ``lam`` of ``factor``."""
    return _gcv_batch(_third_differences(x), x.shape[1], lam, factor)[0]


def gcv_values(x: Array, log_lambda: Array) -> Array:
    """GCV(λ) of the ``(n, c)`` samples ``x`` at each log10 λ of ``log_lambda``, solved in
    chunks of at most :data:`CHUNK_UNKNOWNS` unknowns."""
    lam = 10.0 ** np.atleast_1d(np.asarray(log_lambda, dtype=float))
    step = max(1, CHUNK_UNKNOWNS // len(x))
    out = np.empty(len(lam))
    for start in range(0, len(lam), step):
        part = lam[start : start + step]
        out[start : start + step] = _gcv_of(x, part, _factor(len(x), part))
    return out


def _transpose_delta(gamma: Array) -> Array:
    """``Δᵀ γ`` along the last axis (``n - 3`` → ``n`` frames)."""
    size = gamma.shape[-1]
    out = np.zeros(gamma.shape[:-1] + (size + 3,))
    term = np.empty_like(gamma)
    for k, weight in enumerate(_DELTA):
        np.multiply(gamma, weight, out=term)
        np.add(out[..., k : k + size], term, out=out[..., k : k + size])
    return out


@dataclass(frozen=True)
class _SineGrid:
    """The search grid's GCV parts for ``n`` frames in the sine basis (see
    :func:`_sine_grid`): the basis' rows at the corner indices ``rows`` (``(q, n - 3)``),
    ``1/p`` and ``μ³/p²`` per λ and mode (``(L, n - 3)``), the capacitance solve ``F``, the
    corner blocks ``Z`` and ``Σ μ³/p² s_q s_r`` (``(L, q, q)``), ``K_D`` (``(q, q)``), and
    ``n - tr H`` per λ (``(L,)``)."""

    basis: Array
    inverse: Array
    weight: Array
    capacitance: Array
    corner: Array
    weighted: Array
    corner_ddt: Array
    shrink: Array


def _corner_blocks() -> tuple[int, Array, Array]:
    """``(a, C_G, C_D)``: ``G`` and ``ΔΔᵀ`` minus the polynomials in ``T = tridiag(-1, 2, -1)``
    with their symbols differ only in the ``a × a`` blocks at both ends of the diagonal:
    those blocks (from 16 unknowns; the same for any size), the first at both ends."""
    m = 16
    t = np.diag(np.full(m, 2.0)) - np.diag(np.ones(m - 1), 1) - np.diag(np.ones(m - 1), -1)
    cosine = np.eye(m) - t / 2.0
    toeplitz = [sum(np.diag(np.full(m - d, v), d) + (np.diag(np.full(m - d, v), -d) if d else 0) for d, v in
                 enumerate(band)) for band in (_GRAM, _DDT)]  # fmt: skip
    gram = toeplitz[0] - (0.55 - 1.0 / 60.0) * np.eye(m) - (13.0 / 30.0) * cosine - (1.0 / 30.0) * cosine @ cosine
    ddt = toeplitz[1] - t @ t @ t
    a = 2
    assert np.abs(gram[a:-a, :]).max() < 1e-15 and np.abs(ddt[a:-a, :]).max() == 0.0
    return a, gram[:a, :a], ddt[:a, :a]


@lru_cache(maxsize=4)
def _sine_grid(n: int) -> _SineGrid:
    """:class:`_SineGrid` of the whole search grid for ``n`` frames.  ``A = G + λΔΔᵀ`` is
    ``P(T) + C``: ``P(T)`` diagonal in the orthonormal sine basis ``S`` (DST-I, eigenvalues
    ``p = g(θ) + λ μ³``, ``μ = 4 sin²(θ/2)``, ``g`` the Gram symbol) and ``C = U K Uᵀ`` two
    ``2 × 2`` corner blocks (Woodbury: ``A⁻¹ = P⁻¹ - P⁻¹ U F Uᵀ P⁻¹``, ``F = (I + K Z)⁻¹ K``,
    ``Z = Uᵀ P⁻¹ U``); ``n - tr H = λ tr(A⁻¹ΔΔᵀ) = λ (Σ μ³/p + tr(Z K_D) - tr(F (W + Z K_D Z)))``,
    ``W = Uᵀ P⁻¹ S diag(μ³) S P⁻¹ U``."""
    size = n - 3
    a, gram, ddt = _corner_blocks()
    index = np.r_[np.arange(a), np.arange(size - a, size)]
    modes = np.arange(1, size + 1)
    theta = modes * np.pi / (size + 1)
    basis = np.sqrt(2.0 / (size + 1)) * np.sin(np.outer(index + 1, modes) * np.pi / (size + 1))
    mu3 = (4.0 * np.sin(theta / 2.0) ** 2) ** 3
    symbol = (0.55 - 1.0 / 60.0) + (13.0 / 30.0) * np.cos(theta) + (1.0 / 30.0) * np.cos(theta) ** 2
    lam = 10.0**_GRID
    inverse = 1.0 / (symbol[None, :] + lam[:, None] * mu3[None, :])
    weight = mu3 * inverse**2
    pairs = (basis[:, None, :] * basis[None, :, :]).reshape(-1, size).T  # (size, q²)
    q = len(index)
    corner = (inverse @ pairs).reshape(-1, q, q)
    k_ddt = np.zeros((q, q))
    k_ddt[:a, :a], k_ddt[a:, a:] = ddt, ddt[::-1, ::-1]
    k_gram = np.zeros((q, q))
    k_gram[:a, :a], k_gram[a:, a:] = gram, gram[::-1, ::-1]
    k = k_gram[None] + lam[:, None, None] * k_ddt[None]
    capacitance = np.linalg.solve(np.eye(q)[None] + k @ corner, k)
    weighted = (weight @ pairs).reshape(-1, q, q)
    trace = (inverse @ mu3 + np.einsum("lqr,rq->l", corner, k_ddt)
             - np.einsum("lqr,lrq->l", capacitance, weighted + corner @ k_ddt @ corner))  # fmt: skip
    return _SineGrid(basis, inverse, weight, capacitance, corner, weighted, k_ddt, lam * trace)


def _sine_rss(dx: Array) -> Array:
    """``(L, c)``: ``RSS(λ) = λ² γᵀ ΔΔᵀ γ`` of each column of ``dx`` (``(c, n - 3)``, third
    differences) at every λ of the grid, by :func:`_sine_grid`: a few matrix products."""
    size = dx.shape[1]
    sine = _sine_grid(size + 3)
    hat = dst(dx.T, type=1, norm="ortho", axis=0)  # S Δx: (size, c)
    q, c = len(sine.basis), dx.shape[0]
    spread = (sine.basis[:, :, None] * hat[None]).transpose(1, 0, 2).reshape(size, q * c)
    w = (sine.inverse @ spread).reshape(-1, q, c)  # Uᵀ P⁻¹ Δx
    h = sine.capacitance @ w
    cross = (sine.weight @ spread).reshape(-1, q, c)
    quad = sine.weight @ hat**2 - 2.0 * np.einsum("lqc,lqc->lc", h, cross) + np.einsum("lqc,lqr,lrc->lc", h,
                                                                                        sine.weighted, h)  # fmt: skip
    ends = w - sine.corner @ h  # Uᵀ γ
    quad += np.einsum("lqc,qr,lrc->lc", ends, sine.corner_ddt, ends)
    return (10.0**_GRID)[:, None] ** 2 * quad


def _first_minimum(values: Array) -> int:
    """Index of the first local minimum (``<=`` both neighbours) of ``values``; -1: none."""
    minima = np.flatnonzero((values[1:-1] <= values[:-2]) & (values[1:-1] <= values[2:])) + 1
    return int(minima[0]) if len(minima) else -1


def _grid_search(xs: list[Array]) -> tuple[Array, Array]:
    """The grid's GCV of the ``(n, c)`` trajectories ``xs`` (all of one shape) and each
    one's first local minimum's index (-1: none): ``(t, grid)`` values.  12 … 729 frames:
    the whole grid at once in the sine basis (:func:`_sine_grid`, cached per length, and
    :func:`_sine_rss`); else banded, from the top in chunks until each one's first
    local minimum is known (NaN past a trajectory's stop), a chunk's factors made once
    for all the pending trajectories."""
    n, width = xs[0].shape
    dx = np.concatenate([_third_differences(x) for x in xs])
    grid = _GRID
    step = max(8, CHUNK_UNKNOWNS // n)
    if MIN_FRAMES <= n and len(grid) * (n - 3) <= CHUNK_UNKNOWNS:  # the whole grid at once, in the sine basis
        rss = _sine_rss(dx).reshape(len(grid), len(xs), width).sum(axis=2)
        values = (rss / np.maximum(_sine_grid(n).shrink, 1e-300)[:, None] ** 2).T
        return values, np.array([_first_minimum(v) for v in values])
    values = np.full((len(xs), len(grid)), np.nan)
    best = np.full(len(xs), -1)
    stop = 0
    while (best < 0).any() and stop < len(grid):
        start, stop = stop, min(stop + step, len(grid))
        pending = np.flatnonzero(best < 0)
        lam = 10.0 ** grid[start:stop]
        inner = max(1, CHUNK_UNKNOWNS // n)  # as gcv_values
        for first in range(start, stop, inner):
            last = min(first + inner, stop)
            part = lam[first - start : last - start]
            factor = _factor(n, part)
            for t in pending:  # one trajectory per LAPACK call (pbtrs solves column by column)
                values[t, first:last] = _gcv_batch(dx[t * width : (t + 1) * width], width, part, factor)[0]
        for t in pending:
            best[t] = _first_minimum(values[t, :stop])
    return values, best


def _refined(xs: list[Array], best: Array) -> list[float]:
    """log10 λ for each of the ``(n, c)`` trajectories ``xs`` whose grid GCV has its first
    local minimum at index ``best`` (-1: the grid's last λ), refined to 1e-3 by golden
    section between the grid's neighbours, all the trajectories' steps together: per
    step one block-diagonal factorisation of their two λ each (the same steps, the same
    values as one at a time)."""
    grid = _GRID
    refine = np.flatnonzero(best >= 0)
    out = np.full(len(xs), grid[-1])
    if not len(refine):
        return [float(v) for v in out]
    lo, hi = grid[best[refine] + 1].astype(float), grid[best[refine] - 1].astype(float)
    dx = np.stack([_third_differences(xs[t]) for t in refine], axis=1)  # (c, k, n - 3)
    rhs = np.repeat(dx, 2, axis=1)  # each trajectory's at both of its λ
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    while np.any(active := hi - lo > 1e-3):  # (all take ten steps: 0.1 · 0.618^k)
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        lam = 10.0 ** np.stack([a, b], axis=1).ravel()
        factor = _factor(len(xs[0]), lam)
        gamma = _solve(factor.cholesky, rhs)
        residual = _transpose_delta(gamma) * lam[:, None]
        values = (residual**2).sum(axis=(0, 2)) / np.maximum(factor.shrink, 1e-300) ** 2
        left = values[0::2] - values[1::2] <= 0.0
        hi, lo = np.where(active & left, b, hi), np.where(active & ~left, a, lo)
    out[refine] = 0.5 * (lo + hi)
    return [float(v) for v in out]


def gcv_log_lambdas(xs: list[Array]) -> list[float]:
    """:func:`gcv_log_lambda` of each of the trajectories ``xs`` (``(n, c)`` samples, all
    of one shape, no NaN, ``n >= 4``), their grid searched together: the same values as
    one at a time, for the cost of one search's Python work."""
    xs = [np.asarray(x, dtype=float).reshape(len(x), -1) for x in xs]
    if len({x.shape for x in xs}) > 1:
        raise ParameterError(f"trajectories searched together must have one shape (frames, components); "
                             f"got {sorted({x.shape for x in xs})}")  # fmt: skip
    _, best = _grid_search(xs)
    return _refined(xs, best)


def gcv_log_lambda(x: Array) -> float:
    """log10 of the λ (frame units) GCV picks for the ``(n, c)`` samples ``x`` (no NaN,
    ``n >= 4``): the first local minimum of GCV on a grid from :data:`LOG_LAMBDA_RANGE`'s
    heavy smoothing downwards (the grid's last λ without one), refined to 1e-3 by
    golden-section search between the grid's neighbours.  The grid: see
    :func:`_grid_search`."""
    return gcv_log_lambdas([x])[0]


def _second_derivative(x: Array, log_lambda: float) -> Array:
    """``(n, c)``: the smoothing spline's second derivative (per frame²) at every frame of
    the ``(n, c)`` samples ``x`` for the given log10 λ."""
    lam = 10.0**log_lambda
    dx = _third_differences(x)  # (c, n - 3)
    gamma = _solve(_factor(len(x), np.array([lam])).cholesky, dx[:, None, :])[:, 0].T  # (n - 3, c)
    u = x - lam * _transpose_delta(gamma.T).T
    out = np.empty_like(x)
    inner = u[2:] - 2.0 * u[1:-1] + u[:-2]  # Δ²u at frames 1 … n - 2
    padded = np.concatenate([np.zeros((3, x.shape[1])), gamma, np.zeros((2, x.shape[1]))])  # γ_{k} at k + 3
    for d, weight in enumerate(_SECOND):  # γ_{i+d-3} for inner frame i = 1 … n - 2
        inner -= weight * padded[1 + d : len(x) - 1 + d]
    out[1:-1] = inner
    out[0] = inner[0] - gamma[0] / 6.0  # s''(0) = s''(1) - ∫_0^1 s''' (only γ_0 there: ∫ = 1/6)
    out[-1] = inner[-1] + gamma[-1] / 6.0
    return out


def spline_second_derivatives(xs: list[Array], rate: float) -> list[Array]:
    """:func:`spline_second_derivative` of each of the trajectories ``xs`` (``(n, c)``
    samples at ``rate`` Hz; as a trial's centres of mass), the runs of one length and
    width searched together (:func:`gcv_log_lambdas`): the same values as one at a time."""
    arrays = [np.asarray(x, dtype=float) for x in xs]
    outs = [np.full(x.shape, np.nan) for x in arrays]
    groups: dict[tuple[int, int], list[tuple[int, int, int]]] = {}
    for index, x in enumerate(arrays):
        flat = x.reshape(len(x), -1)
        finite = np.all(np.isfinite(flat), axis=1)
        edges = np.flatnonzero(np.diff(np.r_[0, finite.astype(np.int8), 0]))
        for start, stop in zip(edges[::2], edges[1::2], strict=True):
            if stop - start >= MIN_FRAMES:
                groups.setdefault((int(stop - start), flat.shape[1]), []).append((index, int(start), int(stop)))
    for runs in groups.values():
        pieces = [arrays[index][start:stop].reshape(stop - start, -1) for index, start, stop in runs]
        for (index, start, stop), run, log_lambda in zip(runs, pieces, gcv_log_lambdas(pieces), strict=True):
            second = _second_derivative(run, log_lambda)
            outs[index][start:stop] = (second * rate**2).reshape(arrays[index][start:stop].shape)
    return outs


def spline_second_derivative(x: Array, rate: float) -> Array:
    """``(n, c)``: the second time derivative (units of ``x`` per s²) of the quintic GCV
    smoothing spline through ``x`` (``(n, c)`` samples at ``rate`` Hz, the components
    sharing one λ), at every frame, the first and last included.  Each run of frames
    without NaN is its own spline; runs shorter than :data:`MIN_FRAMES` and NaN frames
    give NaN."""
    return spline_second_derivatives([x], rate)[0]
