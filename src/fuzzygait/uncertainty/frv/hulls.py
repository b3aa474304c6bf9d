"""Interval hulls over the model library (thesis §2.7.4 step 5): sparse-table range
queries for all occurring intervals at once, and the cubic Hermite interpolant between
neighbouring library entries when the model gives sensitivities ``df/dp``.

The studies store only values their forward simulations produced, or interpolate
between: a hull is the extreme library value over its interval or box, and α = 1 is
the Hermite interpolant kept within its cell's corner values (``bounded``). The
interpolant's interior extrema (:func:`hermite_segment_extrema`, :func:`interval_hulls`
and :func:`hermite_box_extrema` with slopes) estimate the model between the library
entries; where the grid does not resolve the model they leave the range it can produce
at all (the stance blade's maximum element energy, ≥ 0, reached −0.05 J on a 20-point
grid), so no study stores them.
"""

from __future__ import annotations

import numpy as np

from fuzzygait.core.errors import ParameterError

#: The commit-record entry ``hulls`` of a study whose stored hulls are the extreme library
#: values over each interval or box (stores made before it held the Hermite extrema).
HULLS = "simulated"


def range_extrema(low_values: np.ndarray, high_values: np.ndarray, first: np.ndarray,
                  last: np.ndarray, time_block: int = 256) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Minimum of ``low_values`` and maximum of ``high_values`` over the rows
    ``first[q] … last[q]`` (inclusive) of every query ``q``, for all columns at once.

    A sparse table (row ranges of length 2^j) answers each query with two look-ups; it
    is built per block of ``time_block`` columns to bound memory.

    Returns:
        ``(minimum, maximum)``, each ``(n_queries, n_columns)``.
    """
    low_values, high_values = np.asarray(low_values, dtype=float), np.asarray(high_values, dtype=float)
    first, last = np.asarray(first, dtype=np.int64), np.asarray(last, dtype=np.int64)
    m, n_col = low_values.shape
    if first.size and (first.min() < 0 or last.max() >= m or np.any(first > last)):
        raise ParameterError("range query outside the rows or with first > last")
    length = last - first + 1
    powers = 1 << np.arange(max(1, int(m).bit_length()), dtype=np.int64)
    level = np.searchsorted(powers, length, side="right") - 1  # floor(log2(length))
    minimum, maximum = np.empty((first.size, n_col)), np.empty((first.size, n_col))
    levels = np.unique(level)
    for c0 in range(0, n_col, time_block):
        cols = slice(c0, c0 + time_block)
        lo, hi = low_values[:, cols], high_values[:, cols]
        for j in range(int(levels.max()) + 1 if levels.size else 0):
            if j:
                half = 1 << (j - 1)
                lo, hi = np.minimum(lo[:-half], lo[half:]), np.maximum(hi[:-half], hi[half:])
            sel = np.flatnonzero(level == j)
            if sel.size:
                a, b = first[sel], last[sel] - (1 << j) + 1
                minimum[sel, cols] = np.minimum(lo[a], lo[b])
                maximum[sel, cols] = np.maximum(hi[a], hi[b])
    return minimum, maximum


def hermite_segment_extrema(values: np.ndarray, slopes: np.ndarray, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Extrema of the cubic Hermite interpolant between neighbouring library entries.

    Args:
        values: ``(m, n_time)`` library values at equidistant parameters.
        slopes: ``(m, n_time)`` their derivatives ``df/dp``.
        spacing: the parameter distance ``h`` between neighbouring entries.

    Returns:
        ``(minimum, maximum)``, each ``(m − 1, n_time)``: per sub-interval the extremes of
        its ends and of the interpolant's interior stationary points (roots of the
        quadratic derivative, in closed form). The interpolant's error is at most
        ``h⁴/384·max|∂⁴f/∂p⁴|``, which bounds the error of these extrema too.
    """
    f0, f1 = values[:-1], values[1:]
    m0, m1 = spacing * slopes[:-1], spacing * slopes[1:]
    a = 2.0 * f0 + m0 - 2.0 * f1 + m1  # H(s) = a s³ + b s² + m0 s + f0, s ∈ [0, 1]
    b = -3.0 * f0 - 2.0 * m0 + 3.0 * f1 - m1
    lo, hi = np.minimum(f0, f1), np.maximum(f0, f1)
    qa, qb = 3.0 * a, 2.0 * b  # H'(s) = qa s² + qb s + m0
    disc = qb * qb - 4.0 * qa * m0
    real = disc >= 0.0
    q = -0.5 * (qb + np.copysign(np.sqrt(np.where(real, disc, 0.0)), qb))  # stable roots q/qa, m0/q
    with np.errstate(divide="ignore", invalid="ignore"):
        for s in (q / qa, m0 / q):
            inside = real & (s > 0.0) & (s < 1.0)
            s = np.where(inside, s, 0.0)
            h = ((a * s + b) * s + m0) * s + f0
            lo = np.where(inside, np.minimum(lo, h), lo)
            hi = np.where(inside, np.maximum(hi, h), hi)
    return lo, hi


def interval_hulls(values: np.ndarray, left: np.ndarray, right: np.ndarray, *, slopes: np.ndarray | None = None,
                   spacing: float | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Lower and upper hull of the output over parameter intervals of a library.

    Args:
        values: ``(m, n_time)`` model outputs at ``m`` consecutive bin centres.
        left, right: ``(k,)`` row indices (into ``values``) of each interval's ends.
        slopes: optional ``(m, n_time)`` ``df/dp``; given, the hull also takes the
            extrema of the cubic Hermite interpolant between neighbouring rows inside the
            interval (the linearised refinement: an estimate of the model's extrema, which
            can leave the range the model produces, see the module docstring); otherwise
            it is exactly the extreme library value over rows ``left … right`` (what the
            studies store).
        spacing: parameter distance between rows (needed with ``slopes``).

    Returns:
        ``(lower, upper)``, each ``(k, n_time)``.
    """
    values = np.asarray(values, dtype=float)
    left, right = np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)
    if slopes is None:
        return range_extrema(values, values, left, right)
    if spacing is None:
        raise ParameterError("interval_hulls: spacing is needed with slopes")
    lower, upper = values[left], values[left].copy()
    proper = np.flatnonzero(right > left)
    if proper.size:
        seg_lo, seg_hi = hermite_segment_extrema(values, np.asarray(slopes, dtype=float), float(spacing))
        lower[proper], upper[proper] = range_extrema(seg_lo, seg_hi, left[proper], right[proper] - 1)
    return lower, upper



def _hermite_rows(values: np.ndarray, slopes: np.ndarray, first_centre: float, spacing: float,
                  x: np.ndarray, *, bounded: bool = False) -> np.ndarray:  # fmt: skip
    """Cubic Hermite interpolation of library rows (grid points ``first_centre + k·spacing``)
    at the parameter values ``x``: ``(len(x), n_nodes)``. ``bounded``: each value kept
    within its cell's two corner values (the end cell's beyond the outermost rows)."""
    u = (np.asarray(x, float) - first_centre) / spacing
    i = np.clip(np.floor(u).astype(np.int64), 0, values.shape[0] - 2)
    t = (u - i)[:, None]
    h00, h10 = 2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t
    h01, h11 = -2 * t**3 + 3 * t**2, t**3 - t**2
    out = (h00 * values[i] + h10 * spacing * slopes[i]
           + h01 * values[i + 1] + h11 * spacing * slopes[i + 1])  # fmt: skip
    if bounded:
        out = np.clip(out, np.minimum(values[i], values[i + 1]), np.maximum(values[i], values[i + 1]))
    return out


def box_extrema(low_values: np.ndarray, high_values: np.ndarray, first: np.ndarray, last: np.ndarray,
                time_block: int = 256) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Minimum of ``low_values`` and maximum of ``high_values`` over the boxes of grid
    points ``first[q, d] … last[q, d]`` (inclusive, every parameter ``d``) of each query
    ``q``, for all columns at once — :func:`range_extrema` generalised to several
    parameters.

    Method: the queries are grouped by their interval of the last parameter; per distinct
    interval that axis is reduced directly (``min``/``max`` over its slice), and the rest
    recursively, down to the first parameter, answered by :func:`range_extrema`'s sparse
    table. Min and max are exact, so the result does not depend on the grouping.

    Args:
        low_values, high_values: ``(m_1, …, m_D, n_columns)`` values on the grid points.
        first, last: ``(n_queries, D)`` grid indices of each box's corners.

    Returns:
        ``(minimum, maximum)``, each ``(n_queries, n_columns)``.
    """
    low_values, high_values = np.asarray(low_values, dtype=float), np.asarray(high_values, dtype=float)
    first, last = np.asarray(first, dtype=np.int64), np.asarray(last, dtype=np.int64)
    n_params = low_values.ndim - 1
    if first.ndim != 2 or first.shape[1] != n_params or last.shape != first.shape:
        raise ParameterError(f"box queries need (n, {n_params}) corners; got {first.shape} and {last.shape}")
    if first.size and (first.min() < 0 or np.any(last >= np.array(low_values.shape[:-1])) or np.any(first > last)):
        raise ParameterError("box query outside the grid or with first > last")
    if n_params == 1:
        return range_extrema(low_values, high_values, first[:, 0], last[:, 0], time_block)
    minimum = np.empty((first.shape[0], low_values.shape[-1]))
    maximum = np.empty_like(minimum)
    if not first.size:
        return minimum, maximum
    pairs, inverse = np.unique(np.stack([first[:, -1], last[:, -1]], axis=1), axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    for u, (a, b) in enumerate(pairs):
        sel = np.flatnonzero(inverse == u)
        lo = low_values[..., a : b + 1, :].min(axis=-2)
        hi = high_values[..., a : b + 1, :].max(axis=-2)
        minimum[sel], maximum[sel] = box_extrema(lo, hi, first[sel, :-1], last[sel, :-1], time_block)
    return minimum, maximum


def hermite_box_extrema(values: np.ndarray, slopes: np.ndarray, spacings: np.ndarray, first: np.ndarray,
                        last: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`box_extrema` refined by the sensitivities: the extrema over each box's grid
    points and over the cubic Hermite interpolant along every grid line segment inside it
    (along parameter ``d``, between neighbouring points, from their values and ``∂f/∂p_d``)
    — the one-parameter refinement of :func:`interval_hulls` applied axis by axis. With
    one parameter it is exactly that refinement; with several, the interpolant's extrema
    inside a cell (off the grid lines) are not searched.

    Args:
        values: ``(m_1, …, m_D, n_columns)`` values on the grid points (NaN where none).
        slopes: ``(m_1, …, m_D, n_columns, D)`` their derivatives ``∂f/∂p_d``.
        spacings: ``(D,)`` grid spacing per parameter (units of ``p_d``).
        first, last: ``(n_queries, D)`` grid indices of each box's corners.

    Returns:
        ``(minimum, maximum)``, each ``(n_queries, n_columns)``.
    """
    values, slopes = np.asarray(values, dtype=float), np.asarray(slopes, dtype=float)
    first, last = np.asarray(first, dtype=np.int64), np.asarray(last, dtype=np.int64)
    minimum, maximum = box_extrema(values, values, first, last)
    for d in range(values.ndim - 1):
        proper = np.flatnonzero(last[:, d] > first[:, d])
        if not proper.size:
            continue
        along = np.moveaxis(values, d, 0)
        shape = along.shape
        with np.errstate(invalid="ignore"):  # NaN grid points lie outside every box
            seg_lo, seg_hi = hermite_segment_extrema(along.reshape(shape[0], -1),
                                                     np.moveaxis(slopes[..., d], d, 0).reshape(shape[0], -1),
                                                     float(spacings[d]))  # fmt: skip
        seg_lo = np.moveaxis(seg_lo.reshape(shape[0] - 1, *shape[1:]), 0, d)
        seg_hi = np.moveaxis(seg_hi.reshape(shape[0] - 1, *shape[1:]), 0, d)
        segment_last = last[proper].copy()
        segment_last[:, d] -= 1
        lo, hi = box_extrema(seg_lo, seg_hi, first[proper], segment_last)
        minimum[proper] = np.minimum(minimum[proper], lo)
        maximum[proper] = np.maximum(maximum[proper], hi)
    return minimum, maximum


def hermite_cells(origins: np.ndarray, spacings: np.ndarray, first_bins: np.ndarray, last_bins: np.ndarray,
                  x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The grid cell of each point for :func:`hermite_values`: per parameter the lower
    corner bin ``k`` (bin centres ``origin + (k + ½)·spacing``) and the position
    ``t = (x − centre_k)/spacing`` (in [0, 1] inside the grid's centres; beyond its
    outermost centres the end cell is extrapolated, ``|t − ½| ≤ 1``). A parameter with a
    single bin has ``t = 0`` and no upper corner.

    Args:
        origins, spacings, first_bins, last_bins: ``(D,)`` per-parameter grids.
        x: ``(n, D)`` points.

    Returns:
        ``(k (n, D) int64, t (n, D))``.
    """
    u = (np.asarray(x, dtype=float) - origins) / spacings - 0.5
    k = np.clip(np.floor(u).astype(np.int64), first_bins, np.maximum(first_bins, last_bins - 1))
    t = np.where(last_bins > first_bins, u - k, 0.0)
    return k, t


def hermite_values(values: np.ndarray, slopes: np.ndarray, spacings: np.ndarray, t: np.ndarray, *,
                   bounded: bool = False) -> np.ndarray:  # fmt: skip
    """Cubic Hermite interpolation in ``D`` parameters, one parameter at a time.

    Along the last parameter the corner pairs are joined by the cubic Hermite interpolant
    of their values and ``∂f/∂p_D``, and the other slopes are interpolated linearly; then
    the next parameter, down to the first. The result takes every grid point's value and
    first derivatives exactly, reproduces ``f = Σ_d c_d(p_d) + Σ bilinear terms`` with
    cubic ``c_d`` exactly, and for one parameter is the cubic Hermite interpolant of
    :func:`hermite_segment_extrema`.

    Args:
        values: ``(n, 2^D, n_columns)`` values at each point's cell corners, corner ``j``
            having bit ``D−1−d`` of ``j`` set for the upper corner along parameter ``d``
            (the order of ``itertools.product((0, 1), repeat=D)``).
        slopes: ``(n, 2^D, n_columns, D)`` their derivatives ``∂f/∂p_d``.
        spacings: ``(D,)`` grid spacing per parameter.
        t: ``(n, D)`` positions in the cell (:func:`hermite_cells`).
        bounded: keep each value within the smallest and largest of its ``2^D`` corner
            values (the simulations it is interpolated from).

    Returns:
        ``(n, n_columns)``.
    """
    f, m = np.asarray(values, dtype=float), np.asarray(slopes, dtype=float)
    if bounded:
        return np.clip(hermite_values(f, m, spacings, t), f.min(axis=1), f.max(axis=1))
    n, corners, n_col = f.shape
    for d in range(t.shape[1] - 1, -1, -1):
        f = f.reshape(n, corners // 2, 2, n_col)
        m = m.reshape(n, corners // 2, 2, n_col, d + 1)
        s = t[:, d][:, None, None]
        h = float(spacings[d])
        f = ((2 * s**3 - 3 * s**2 + 1) * f[:, :, 0] + (s**3 - 2 * s**2 + s) * h * m[:, :, 0, :, d]
             + (-2 * s**3 + 3 * s**2) * f[:, :, 1] + (s**3 - s**2) * h * m[:, :, 1, :, d])  # fmt: skip
        m = (1 - s[..., None]) * m[:, :, 0, :, :d] + s[..., None] * m[:, :, 1, :, :d]
        corners //= 2
    return f[:, 0]
