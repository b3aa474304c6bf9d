"""Post-processing of fuzzy outputs: nesting repair (Fig. 2.11), the combined envelope
(Fig. 5.3) and failure probabilities from a limit state (§5.6, Eq. 5.4)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from numbers import Real

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty.parameters import FuzzyBalls, FuzzyVector


def repair_nesting(hull: np.ndarray) -> np.ndarray:
    """Make every lower α-level's hull contain the next higher one's.

    Args:
        hull: ``(n_alpha, 2, ...)`` with α increasing along axis 0 and bound
            ``(lower, upper)`` along axis 1.

    Returns:
        A repaired copy: going down from the highest α, a lower hull value above the
        higher level's is lowered to it, an upper hull value below it is raised to it —
        an optimisation over a set cannot be worse than over a subset (thesis §2.7.2).
    """
    repaired = np.array(hull, dtype=float, copy=True)
    for a in range(repaired.shape[0] - 2, -1, -1):
        repaired[a, 0] = np.minimum(repaired[a, 0], repaired[a + 1, 0])
        repaired[a, 1] = np.maximum(repaired[a, 1], repaired[a + 1, 1])
    return repaired


def combined_envelope(result: xr.Dataset) -> xr.Dataset:
    """The overall extreme envelope over all α-levels (Fig. 5.3): ``lower``, ``upper``
    and ``deterministic`` over time. The membership information is dropped."""
    hull = result["hull"]
    # drop=True: the scalar `bound` coordinates ("lower" vs "upper") would otherwise
    # conflict when the two are put in one Dataset (xarray MergeError)
    return xr.Dataset(
        {
            "lower": hull.sel(bound="lower", drop=True).min("alpha"),
            "upper": hull.sel(bound="upper", drop=True).max("alpha"),
            "deterministic": result["deterministic"],
        }
    )


def failure_probability(result: xr.Dataset, limit: float, failure_above: bool = True) -> xr.DataArray:
    """Failure probability per time node from the fuzzy output (Eq. 5.4).

    The output's membership function at each node is the piecewise-linear function
    through the hull values of the α-levels; the limit state splits the area under it
    into the failure area ``A_f`` (output beyond ``limit``) and the safe area ``A_s``:
    ``v = A_f / (A_f + A_s)``, with the membership at the limit interpolated.

    Args:
        result: output of :func:`~fuzzygait.uncertainty.graph_follower`.
        limit: the limit value of the target output.
        failure_above: True if outputs above ``limit`` fail, False if below.

    Returns:
        ``v`` over ``time`` in [0, 1]. Where the output is crisp (zero area) ``v`` is 1
        or 0 by which side of the limit the deterministic value lies.

    Raises:
        ParameterError: ``limit`` is not a finite number, or the α-levels lack 0 or 1.
    """
    if isinstance(limit, bool) or not isinstance(limit, Real) or not np.isfinite(limit):
        raise ParameterError(f"limit must be a finite number in the output's units; got {limit!r}")
    alphas = result["alpha"].to_numpy()
    if alphas[0] != 0.0 or alphas[-1] != 1.0:
        raise ParameterError("failure probability needs the α-levels 0 and 1")
    lower = result["hull"].sel(bound="lower").to_numpy()  # (n_alpha, n_time)
    upper = result["hull"].sel(bound="upper").to_numpy()
    # the membership polygon: up the left flank, down the right flank
    xs = np.concatenate([lower, upper[::-1]], axis=0)  # (2 n_alpha, n_time)
    mu = np.concatenate([alphas, alphas[::-1]])
    total = _area_left_of(xs, mu, np.full(xs.shape[1], np.inf))
    below = _area_left_of(xs, mu, np.full(xs.shape[1], float(limit)))
    above = total - below
    with np.errstate(invalid="ignore", divide="ignore"):
        v = (above if failure_above else below) / total
    crisp = total <= 0
    det = result["deterministic"].to_numpy()
    v = np.where(crisp, (det > limit) if failure_above else (det < limit), v)
    return xr.DataArray(np.clip(v, 0.0, 1.0), coords={"time": result["time"]}, dims="time", name="failure_probability")


def _area_left_of(xs: np.ndarray, mu: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """Area under the piecewise-linear membership polygon ``(xs[:, t], mu)`` for
    ``x <= cut[t]``, exact for every segment (trapezoids clipped at the cut)."""
    area = np.zeros(xs.shape[1])
    for k in range(xs.shape[0] - 1):
        x0, x1 = xs[k], xs[k + 1]
        m0, m1 = mu[k], mu[k + 1]
        lo, hi = np.minimum(x0, x1), np.maximum(x0, x1)
        m_lo = np.where(x0 <= x1, m0, m1)
        m_hi = np.where(x0 <= x1, m1, m0)
        right = np.clip(cut, lo, hi)
        width = hi - lo
        with np.errstate(invalid="ignore", divide="ignore"):
            m_right = np.where(width > 0, m_lo + (m_hi - m_lo) * (right - lo) / width, m_lo)
        area += 0.5 * (m_lo + m_right) * (right - lo)
    return area


def sufficient_runs(result: xr.Dataset, params: FuzzyVector | FuzzyBalls, evaluate: Callable[[np.ndarray], object],
                    tolerances: Sequence[float] = (0.01,)) -> tuple[int, list[tuple[int, int]]]:  # fmt: skip
    """How many forward runs a Graph Follower result's hulls actually need.

    The hulls (α < 1, both bounds) are attained by a set of distinct parameter vectors
    (``result.extremiser``). Which of them are needed to keep every hull value within a
    tolerance × that α-level's largest hull width, each vector counting only for the
    α-levels whose set contains it, is a set-cover problem: a greedy cover gives an
    achievable count, the linear-programming relaxation a lower bound (no subset of these
    vectors smaller than it will do). Between them lies the number of runs that would have
    sufficed had one known the right parameter sets in advance — the yardstick for how much
    of a run's cost the model itself imposes.

    Args:
        result: a :func:`~fuzzygait.uncertainty.graph_follower` result.
        params: the fuzzy parameters of that run (``domain(alpha)`` gives the α-level set).
        evaluate: maps one parameter vector ``(n_p,)`` to its trajectory ``(n_time,)``
            (same units as the hull), e.g. ``model.evaluate``; called once per distinct
            extremiser, whatever the number of tolerances.
        tolerances: allowed shortfalls as fractions of the hull width (default 1 %).

    Returns:
        ``(distinct, [(lower_bound, greedy) per tolerance])``: the distinct extremising
        vectors, and per tolerance the LP lower bound (rounded up) and the greedy cover
        size. Hull values that no recorded extremiser attains (possible after the nesting
        repair) are left out.
    """
    tolerances = [float(t) for t in tolerances]
    bad = [t for t in tolerances if not 0.0 <= t < 1.0]
    if bad or not tolerances:
        raise ParameterError(f"tolerances must be fractions in [0, 1); got {tolerances!r}")
    alphas = [float(a) for a in result["alpha"].values if a < 1.0]
    if not alphas:
        return 0, [(0, 0)] * len(tolerances)
    extremisers = result["extremiser"].sel(alpha=alphas).to_numpy()
    points = np.unique(extremisers.reshape(-1, extremisers.shape[-1]), axis=0)
    values = np.array([_trajectory(evaluate(p)) for p in points])
    hulls = [result["hull"].sel(alpha=alpha).to_numpy() for alpha in alphas]  # (bound, time) each
    inside = [params.domain(alpha).contains(points, tol=1e-12 * float(np.max(np.abs(points)))) for alpha in alphas]
    sizes = []
    for tolerance in tolerances:
        covers = []  # per point: which (α, bound, node) hull values it attains within tolerance
        for hull, admissible in zip(hulls, inside, strict=True):
            slack = tolerance * float(np.max(hull[1] - hull[0]))
            covers.append(admissible[:, None] & (values <= hull[0] + slack))
            covers.append(admissible[:, None] & (values >= hull[1] - slack))
        sizes.append(_cover_sizes(np.concatenate(covers, axis=1)))
    return points.shape[0], sizes


def _trajectory(output: object) -> np.ndarray:
    """A trajectory from ``evaluate``'s output: an array, or an Evaluation's values."""
    values = getattr(output, "values", output)
    return np.asarray(values, dtype=float)


def _cover_sizes(cover: np.ndarray) -> tuple[int, int]:
    """LP lower bound and greedy size of a set cover; ``cover[i, j]``: set i covers item j
    (items no set covers are ignored)."""
    cover = np.unique(cover[:, cover.any(axis=0)], axis=1)  # coverable items; identical columns once
    uncovered, greedy = np.ones(cover.shape[1], dtype=bool), 0
    while uncovered.any():
        best = int(np.argmax((cover & uncovered).sum(axis=1)))
        uncovered &= ~cover[best]
        greedy += 1
    from scipy.optimize import linprog  # here: scipy.optimize costs a worker process 0.25 s to import

    relaxed = linprog(np.ones(cover.shape[0]), A_ub=-cover.T.astype(float), b_ub=-np.ones(cover.shape[1]),
                      bounds=(0.0, 1.0), method="highs")  # fmt: skip
    bound = int(np.ceil(relaxed.fun - 1e-9)) if relaxed.status == 0 else 1
    return bound, greedy
