"""Post-processing of fuzzy outputs — nesting repair (Fig. 2.11), combined envelope
(Fig. 5.3), failure probability (Eq. 5.4) — and storage of results."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.uncertainty import (
    FunctionModel,
    FuzzyBalls,
    FuzzyNumber,
    FuzzyVector,
    combined_envelope,
    failure_probability,
    graph_follower,
    load_result,
    repair_nesting,
    save_result,
    sufficient_runs,
    triangular,
)


# numpy >= 2 renamed trapz to trapezoid (the project supports numpy >= 1.26)
trapezoid = getattr(np, "trapezoid", None) or getattr(np, "trapz")


def dataset(alphas, lower, upper, deterministic) -> xr.Dataset:
    """A hand-made result with the layout of :func:`graph_follower`'s."""
    lower, upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    times = np.arange(lower.shape[1], dtype=float)
    return xr.Dataset(
        {
            "hull": (("alpha", "bound", "time"), np.stack([lower, upper], axis=1)),
            "deterministic": (("time",), np.asarray(deterministic, dtype=float)),
        },
        coords={"alpha": np.asarray(alphas, dtype=float), "bound": ["lower", "upper"], "time": times},
    )


# --------------------------------------------------------------------- nesting repair
def test_repair_nesting_on_crossing_hulls() -> None:
    hull = np.array(
        [
            [[0.0, 0.0, 0.0, 0.0], [5.0, 5.0, 5.0, 5.0]],  # α = 0
            [[1.0, -1.0, 1.0, 2.0], [4.0, 6.0, 4.0, 3.0]],  # α = 0.5: pokes out of α = 0 at t1
            [[2.0, 2.0, 0.5, 2.5], [2.0, 2.0, 0.5, 2.5]],  # α = 1: below α = 0.5's lower at t2
        ]
    )
    original = hull.copy()
    repaired = repair_nesting(hull)
    expected = np.array(
        [
            [[0.0, -1.0, 0.0, 0.0], [5.0, 6.0, 5.0, 5.0]],
            [[1.0, -1.0, 0.5, 2.0], [4.0, 6.0, 4.0, 3.0]],
            [[2.0, 2.0, 0.5, 2.5], [2.0, 2.0, 0.5, 2.5]],
        ]
    )
    np.testing.assert_array_equal(repaired, expected)
    np.testing.assert_array_equal(hull, original)  # the input is left alone
    np.testing.assert_array_equal(repair_nesting(repaired), repaired)  # nested hulls stay


def test_repair_nesting_is_the_running_extreme_from_the_top() -> None:
    rng = np.random.default_rng(5)
    hull = rng.normal(size=(5, 2, 3, 7))  # extra trailing axes are carried along
    repaired = repair_nesting(hull)
    # closed form: lower_α = min over levels ≥ α, upper_α = max over levels ≥ α
    np.testing.assert_array_equal(repaired[:, 0], np.minimum.accumulate(hull[::-1, 0], axis=0)[::-1])
    np.testing.assert_array_equal(repaired[:, 1], np.maximum.accumulate(hull[::-1, 1], axis=0)[::-1])
    for a in range(4):
        assert np.all(repaired[a, 0] <= repaired[a + 1, 0])
        assert np.all(repaired[a, 1] >= repaired[a + 1, 1])


# --------------------------------------------------------------------- combined envelope
def test_combined_envelope_is_min_max_over_levels() -> None:
    lower = [[0.0, 1.0, -2.0], [0.5, 0.2, -1.0], [1.0, 1.5, -1.5]]  # deliberately not nested
    upper = [[3.0, 2.0, 0.0], [2.0, 4.0, -0.5], [1.0, 1.5, 0.5]]
    result = dataset([0.0, 0.5, 1.0], lower, upper, [1.0, 1.5, -1.5])
    envelope = combined_envelope(result)
    np.testing.assert_array_equal(envelope["lower"], [0.0, 0.2, -2.0])
    np.testing.assert_array_equal(envelope["upper"], [3.0, 4.0, 0.5])
    np.testing.assert_array_equal(envelope["deterministic"], [1.0, 1.5, -1.5])
    assert set(envelope.data_vars) == {"lower", "upper", "deterministic"}


def test_combined_envelope_of_a_nested_result_is_the_support_hull() -> None:
    times = np.linspace(0.0, 1.0, 11)
    result = graph_follower(
        FunctionModel(lambda p: np.sin(3.0 * p[0] * times) + p[1] * times, times),
        FuzzyVector([triangular(0.5, 1.0, 2.0), triangular(-1.0, 0.0, 1.0)]),
        (0.0, 0.5),
    )
    envelope = combined_envelope(result)
    np.testing.assert_array_equal(envelope["lower"], result.hull.sel(alpha=0.0, bound="lower"))
    np.testing.assert_array_equal(envelope["upper"], result.hull.sel(alpha=0.0, bound="upper"))


# --------------------------------------------------------------------- failure probability
A, B, C = 1.0, 2.0, 4.0  # triangular fuzzy parameter (left, peak, right)
LIMIT = 2.5
TIMES = np.linspace(-2.5, 2.5, 51)  # f = p + t: the limit sits left of, inside and right of the triangle


def triangle_above(limit: np.ndarray) -> np.ndarray:
    """Share of the triangle (A, B, C)'s area right of ``limit``."""
    left = 1.0 - (limit - A) ** 2 / ((C - A) * (B - A))
    right = (C - limit) ** 2 / ((C - A) * (C - B))
    return np.select([limit <= A, limit <= B, limit < C], [1.0, left, right], 0.0)


@pytest.fixture(scope="module")
def triangle_result() -> xr.Dataset:
    model = FunctionModel(lambda p: p[0] + TIMES, TIMES)
    return graph_follower(model, FuzzyVector([triangular(A, B, C, "p")]), (0.0, 0.3, 0.5, 0.8))


def test_triangle_hulls_are_the_alpha_cuts(triangle_result) -> None:
    for alpha in triangle_result.alpha.values:
        lo, hi = triangular(A, B, C).alpha_cut(float(alpha))
        np.testing.assert_allclose(triangle_result.hull.sel(alpha=alpha, bound="lower"), lo + TIMES, atol=1e-14)
        np.testing.assert_allclose(triangle_result.hull.sel(alpha=alpha, bound="upper"), hi + TIMES, atol=1e-14)


@pytest.mark.parametrize("failure_above", [True, False])
def test_failure_probability_of_a_triangular_output(triangle_result, failure_above) -> None:
    relative = LIMIT - TIMES  # where the limit sits on the triangle at each node
    assert np.any(relative < A) and np.any((A < relative) & (relative < B))
    assert np.any((B < relative) & (relative < C)) and np.any(relative > C)
    v = failure_probability(triangle_result, LIMIT, failure_above=failure_above)
    above = triangle_above(relative)
    expected = above if failure_above else 1.0 - above
    np.testing.assert_allclose(v, expected, rtol=0, atol=1e-12)
    assert v.dims == ("time",) and v.name == "failure_probability"


@pytest.mark.parametrize(
    ("limit", "above"),
    [
        (0.0, 1.0),  # left of a
        (1.5, 1.0 - 0.25 / 3.0),  # between a and b: the safe part is a triangle of area 0.125
        (2.0, 2.0 / 3.0),  # at the peak
        (3.0, 1.0 / 6.0),  # between b and c: failure area 0.25 of 1.5
        (5.0, 0.0),  # right of c
    ],
)
def test_failure_probability_worked_values(triangle_result, limit, above) -> None:
    at_zero = {"time": 25}  # t = 0: the output is the parameter itself
    assert TIMES[25] == 0.0
    v = failure_probability(triangle_result, limit, failure_above=True).isel(at_zero)
    assert float(v) == pytest.approx(above, abs=1e-12)
    v = failure_probability(triangle_result, limit, failure_above=False).isel(at_zero)
    assert float(v) == pytest.approx(1.0 - above, abs=1e-12)


def test_failure_probability_of_a_general_output_matches_numeric_areas() -> None:
    """A four-level output with a flat top: the area ratio by dense numerical integration of
    the membership function."""
    alphas = np.array([0.0, 0.3, 0.7, 1.0])
    lower, upper = np.array([-2.0, -1.0, -0.8, 0.0]), np.array([3.0, 1.5, 1.0, 0.5])
    fn = FuzzyNumber(alphas, lower, upper)
    result = dataset(alphas, lower[:, None], upper[:, None], [0.25])
    x = np.linspace(-2.0, 3.0, 500_001)
    mu = fn.membership(x)
    total = trapezoid(mu, x)
    for limit in (-2.5, -1.7, -0.9, -0.3, 0.2, 0.75, 2.0, 3.5):
        right = x >= limit
        above = trapezoid(mu[right], x[right]) / total if right.sum() > 1 else 0.0
        v = float(failure_probability(result, limit, failure_above=True)[0])
        assert v == pytest.approx(above, abs=1e-6), limit
        v = float(failure_probability(result, limit, failure_above=False)[0])
        assert v == pytest.approx(1.0 - above, abs=1e-6), limit


def test_failure_probability_of_a_crisp_output_is_zero_or_one() -> None:
    times = np.linspace(-1.0, 1.0, 21)
    model = FunctionModel(lambda p: times.copy(), times)  # the parameter has no effect
    result = graph_follower(model, FuzzyVector([triangular(1.0, 2.0, 3.0)]), (0.0, 0.5))
    np.testing.assert_array_equal(result.hull.sel(bound="lower"), result.hull.sel(bound="upper"))
    limit = 0.25
    above = failure_probability(result, limit, failure_above=True).to_numpy()
    below = failure_probability(result, limit, failure_above=False).to_numpy()
    np.testing.assert_array_equal(above, (times > limit).astype(float))
    np.testing.assert_array_equal(below, (times < limit).astype(float))


def test_failure_probability_needs_levels_zero_and_one() -> None:
    result = dataset([0.5, 1.0], [[0.0], [1.0]], [[2.0], [1.0]], [1.0])
    with pytest.raises(ParameterError, match="α-levels 0 and 1"):
        failure_probability(result, 0.5)
    result = dataset([0.0, 0.5], [[0.0], [1.0]], [[2.0], [1.0]], [1.0])
    with pytest.raises(ParameterError, match="α-levels 0 and 1"):
        failure_probability(result, 0.5)


# --------------------------------------------------------------------- storage
@pytest.fixture(scope="module")
def small_result() -> xr.Dataset:
    times = np.linspace(0.0, 1.0, 6)
    balls = FuzzyBalls(np.zeros((1, 3)), np.array([0.1]), ("KNE",))
    path = np.array([1.0, 0.0, 0.0]) * times[:, None]
    model = FunctionModel(lambda p: np.linalg.norm(path - p, axis=1) + times, times)
    return graph_follower(model, balls, (0.0, 0.5))


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_storage_round_trip(small_result, tmp_path, suffix) -> None:
    path = tmp_path / f"result{suffix}"
    assert save_result(small_result, path) == path
    loaded = load_result(path)
    xr.testing.assert_identical(loaded, small_result)
    np.testing.assert_array_equal(loaded.hull.to_numpy(), small_result.hull.to_numpy())
    assert list(loaded.parameter.values) == ["KNE_x", "KNE_y", "KNE_z"]
    # saving again over an existing result replaces it
    changed = small_result.assign(hull=small_result.hull + 1.0)
    save_result(changed, path)
    xr.testing.assert_identical(load_result(path), changed)
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary left behind


@pytest.mark.parametrize("name", ["result.csv", "result.h5", "result"])
def test_storage_rejects_unknown_suffixes(small_result, tmp_path, name) -> None:
    with pytest.raises(FuzzyGaitError, match=r"\.nc .*\.zarr"):
        save_result(small_result, tmp_path / name)
    with pytest.raises(FuzzyGaitError, match=r"\.nc .*\.zarr"):
        load_result(tmp_path / name)
    assert not (tmp_path / name).exists()


def test_loading_a_missing_result_names_it(tmp_path) -> None:
    with pytest.raises(FuzzyGaitError, match="missing.nc"):
        load_result(tmp_path / "missing.nc")


# --------------------------------------------------------------------- sufficient runs
def test_sufficient_runs_counts_the_vertices_a_monotone_hull_needs() -> None:
    """Increasing in a, decreasing in b: each hull is one box vertex per α-level, so the
    hulls need exactly the 4 vertices (lower/upper × α = 0, 0.5); a tolerance as wide as
    the hull lets one vector of the inner α-level set (also inside the outer one) do."""
    times = np.linspace(0.0, 1.0, 11)
    params = FuzzyVector((triangular(1.0, 2.0, 2.5, "a"), triangular(-1.0, -0.5, 0.5, "b")))

    def model(p: np.ndarray) -> np.ndarray:
        return p[0] * (1.0 + times) - np.exp(p[1]) * times + p[0] ** 3

    result = graph_follower(FunctionModel(model, times), params, (0.0, 0.5))
    vertices = set()
    for alpha in (0.0, 0.5):
        (a_lo, a_hi), (b_lo, b_hi) = (n.alpha_cut(alpha) for n in params.numbers)
        vertices |= {(a_lo, b_hi), (a_hi, b_lo)}
    distinct, [(lower_bound, greedy), wide] = sufficient_runs(result, params, model, tolerances=(0.0, 0.999))
    assert len(vertices) == 4 and lower_bound == greedy == 4
    assert distinct >= greedy  # at t = 0 the output ignores b: ties add extremisers
    assert wide == (1, 1)
    with pytest.raises(ParameterError, match="tolerance"):
        sufficient_runs(result, params, model, tolerances=(1.5,))
