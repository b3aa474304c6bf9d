"""Fuzzy numbers (thesis §2.5), α-level domains and the fuzzy parameter sets.

Every expectation is worked out by hand from the definitions (Eq. 2.14–2.21) or checked
against dense random samples, never against the code under test."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import (
    BallsDomain,
    BoxDomain,
    FuzzyBalls,
    FuzzyNumber,
    FuzzyVector,
    from_increments,
    triangular,
    triangular_relative,
)

LEVELS = np.linspace(0.0, 1.0, 41)


def general_number() -> FuzzyNumber:
    """Four levels, strictly monotone flanks, an interval [0, 0.5] at α = 1."""
    return FuzzyNumber(
        np.array([0.0, 0.3, 0.7, 1.0]),
        np.array([-2.0, -1.0, -0.8, 0.0]),
        np.array([3.0, 1.5, 1.0, 0.5]),
        name="g",
    )


# --------------------------------------------------------------------- α-cuts, membership
def test_triangular_alpha_cuts_and_membership() -> None:
    fn = triangular(1.0, 2.0, 4.0, "k")
    for alpha in LEVELS:
        lo, hi = fn.alpha_cut(alpha)
        assert lo == pytest.approx(1.0 + alpha, abs=1e-15)
        assert hi == pytest.approx(4.0 - 2.0 * alpha, abs=1e-15)
    x = np.array([-5.0, 0.999, 1.0, 1.5, 2.0, 3.0, 3.5, 4.0, 4.001, 9.0])
    expected = np.array([0.0, 0.0, 0.0, 0.5, 1.0, 0.5, 0.25, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(fn.membership(x), expected, atol=1e-15)
    assert fn.peak == 2.0
    assert fn.support == (1.0, 4.0)


@pytest.mark.parametrize("fn", [triangular(1.0, 2.0, 4.0), triangular(-3.0, -3.0, 1.0), general_number()])
def test_membership_of_cut_ends_is_alpha(fn: FuzzyNumber) -> None:
    top = (fn.lower[-1], fn.upper[-1])
    for alpha in LEVELS:
        for end in fn.alpha_cut(alpha):
            if end in top:  # a vertical flank reaching the top: μ is 1 there
                continue
            assert fn.membership(end) == pytest.approx(alpha, abs=1e-12)
    np.testing.assert_array_equal(fn.membership(np.array(top)), [1.0, 1.0])


def test_general_number_interpolates_between_levels() -> None:
    fn = general_number()
    for k, alpha in enumerate(fn.alphas):  # the stored levels come back exactly
        assert fn.alpha_cut(alpha) == (fn.lower[k], fn.upper[k])
    # halfway between 0.3 and 0.7 both ends are halfway too
    assert fn.alpha_cut(0.5) == pytest.approx((-0.9, 1.25), abs=1e-15)
    assert fn.peak == 0.25
    assert fn.support == (-2.0, 3.0)
    # membership: inside the α = 1 cut it is 1; on the left flank between l_0.3 = −1 and
    # l_0.7 = −0.8 it rises linearly from 0.3 to 0.7
    np.testing.assert_allclose(fn.membership([0.0, 0.2, 0.5]), 1.0)
    assert fn.membership(-0.9) == pytest.approx(0.5, abs=1e-12)
    assert fn.membership(-1.5) == pytest.approx(0.15, abs=1e-12)
    assert fn.membership(2.25) == pytest.approx(0.15, abs=1e-12)
    assert fn.membership(0.75) == pytest.approx(0.85, abs=1e-12)
    np.testing.assert_array_equal(fn.membership([-2.5, 3.5]), [0.0, 0.0])


def test_vertical_flank_takes_the_highest_level() -> None:
    # α-cuts [0, 2] at α = 0 and 0.5, then the peak 1: the flank at x = 0 is vertical
    fn = FuzzyNumber(np.array([0.0, 0.5, 1.0]), np.array([0.0, 0.0, 1.0]), np.array([2.0, 2.0, 1.0]))
    assert fn.membership(0.0) == 0.5  # μ(0) = sup{α: 0 ∈ P_α} (Eq. 2.14)
    assert fn.membership(2.0) == 0.5
    assert fn.membership(0.5) == pytest.approx(0.75)
    assert fn.membership(-1e-9) == 0.0


def test_alpha_cut_outside_unit_interval_is_rejected() -> None:
    with pytest.raises(ParameterError, match="alpha"):
        triangular(0.0, 1.0, 2.0).alpha_cut(1.2)


def test_rescaled_keeps_the_membership_function() -> None:
    fn = triangular(-1.0, 0.5, 3.0, "r")
    fine = fn.rescaled([0.0, 0.1, 0.25, 0.6, 1.0])
    np.testing.assert_allclose(fine.lower, -1.0 + 1.5 * fine.alphas, atol=1e-15)
    np.testing.assert_allclose(fine.upper, 3.0 - 2.5 * fine.alphas, atol=1e-15)
    x = np.linspace(-2.0, 4.0, 1201)
    np.testing.assert_allclose(fine.membership(x), fn.membership(x), atol=1e-12)
    assert fine.name == "r"


def test_triangular_relative() -> None:
    fn = triangular_relative(1.0, 0.1, "L")
    assert fn.support == pytest.approx((0.9, 1.1), abs=1e-15)
    assert fn.peak == 1.0 and fn.name == "L"
    neg = triangular_relative(-2.0, 0.25)
    assert neg.support == pytest.approx((-2.5, -1.5), abs=1e-15)
    assert neg.peak == -2.0
    with pytest.raises(ParameterError, match="spread"):
        triangular_relative(1.0, -0.1, "L")


# --------------------------------------------------------------------- increments (Eq. 2.20)
def test_increments_by_hand() -> None:
    fn = triangular(1.0, 2.0, 4.0).rescaled([0.0, 0.5, 1.0])
    dl, dr = fn.increments()
    np.testing.assert_allclose(dl, [0.5, 0.5])
    np.testing.assert_allclose(dr, [1.0, 1.0, 0.0])
    built = from_increments(2.0, [1.0, 0.5], [0.5, 1.0, 0.0], [0.0, 0.5, 1.0])
    np.testing.assert_allclose(built.lower, [0.5, 1.5, 2.0])
    np.testing.assert_allclose(built.upper, [3.5, 3.0, 2.0])


@pytest.mark.parametrize(
    "fn",
    [
        triangular(1.0, 2.0, 4.0).rescaled([0.0, 0.2, 0.5, 0.9, 1.0]),
        general_number(),  # interval top: the last right increment is its width
        FuzzyNumber(np.array([0.0, 0.5, 1.0]), np.array([0.0, 0.0, 1.0]), np.array([2.0, 2.0, 1.0])),
    ],
)
def test_increments_round_trip(fn: FuzzyNumber) -> None:
    dl, dr = fn.increments()
    assert np.all(dl >= 0) and np.all(dr >= 0)  # convexity, Eq. 2.21
    # `peak` of from_increments is the left end of the α = 1 cut
    back = from_increments(fn.lower[-1], dl, dr, fn.alphas, fn.name)
    np.testing.assert_allclose(back.lower, fn.lower, rtol=0, atol=1e-14)
    np.testing.assert_allclose(back.upper, fn.upper, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(back.alphas, fn.alphas)


def test_increments_round_trip_with_peak_property() -> None:
    fn = triangular(-0.3, 0.2, 1.7).rescaled([0.0, 0.4, 0.8, 1.0])
    back = from_increments(fn.peak, *fn.increments(), fn.alphas)
    np.testing.assert_allclose(back.lower, fn.lower, atol=1e-14)
    np.testing.assert_allclose(back.upper, fn.upper, atol=1e-14)


def test_negative_increment_is_named() -> None:
    with pytest.raises(ParameterError, match=r"left increment at α=0\.5 is -0\.5"):
        from_increments(2.0, [1.0, -0.5], [0.5, 1.0, 0.0], [0.0, 0.5, 1.0], name="E")
    with pytest.raises(ParameterError, match=r"right increment at α=0 is -0\.25") as info:
        from_increments(2.0, [1.0, 0.5], [-0.25, 1.0, 0.0], [0.0, 0.5, 1.0], name="E")
    assert "'E'" in str(info.value)
    with pytest.raises(ParameterError, match=r"right increment at α=1 is -1"):
        from_increments(2.0, [1.0, 0.5], [0.25, 1.0, -1.0], [0.0, 0.5, 1.0])
    with pytest.raises(ParameterError, match="2 left and 3 right"):
        from_increments(2.0, [1.0], [0.5, 1.0, 0.0], [0.0, 0.5, 1.0])


# --------------------------------------------------------------------- invalid numbers
@pytest.mark.parametrize(
    ("alphas", "lower", "upper", "needle"),
    [
        ([0.0, 0.5, 1.0], [0.0, -1.0, 1.0], [3.0, 2.0, 1.0], "not convex"),  # lower flank goes back
        ([0.0, 0.5, 1.0], [0.0, 0.5, 1.0], [3.0, 3.5, 1.0], "not convex"),  # upper flank goes out
        ([0.0, 0.5, 1.0], [0.0, 2.5, 1.0], [3.0, 2.0, 1.0], "lower > upper"),
        ([0.1, 0.5, 1.0], [0.0, 0.5, 1.0], [3.0, 2.0, 1.0], "from 0 to 1"),
        ([0.0, 0.5, 0.9], [0.0, 0.5, 1.0], [3.0, 2.0, 1.0], "from 0 to 1"),
        ([0.0, 0.6, 0.5, 1.0], [0.0, 0.1, 0.5, 1.0], [3.0, 2.5, 2.0, 1.0], "strictly increasing"),
        ([0.0, 1.0, 1.5], [0.0, 0.5, 1.0], [3.0, 2.0, 1.0], r"\[0, 1\]"),
        ([0.0, 1.0], [0.0, np.nan], [3.0, 1.0], "finite"),
        ([0.0, 1.0], [0.0, 0.5, 1.0], [3.0, 1.0], "one lower and one upper"),
    ],
)
def test_invalid_cut_lists_are_rejected(alphas, lower, upper, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        FuzzyNumber(np.array(alphas), np.array(lower), np.array(upper), name="x")


def test_triangular_order_is_checked() -> None:
    with pytest.raises(ParameterError, match="'m'"):
        triangular(1.0, 0.5, 2.0, "m")


# --------------------------------------------------------------------- domains
def _box() -> BoxDomain:
    return BoxDomain(np.array([-1.0, 0.5, 2.0, -0.2]), np.array([1.0, 0.9, 5.0, -0.1]))


def _balls() -> BallsDomain:
    return BallsDomain(np.array([[0.0, 1.0, -2.0], [3.0, 0.0, 0.5]]), np.array([0.4, 1.5]))


@pytest.mark.parametrize("make", [_box, _balls])
def test_linear_argmax_beats_dense_samples(make) -> None:
    domain = make()
    rng = np.random.default_rng(1)
    samples = domain.sample(rng, 100_000)
    for _ in range(20):
        g = rng.standard_normal(domain.dim)
        g[rng.random(domain.dim) < 0.2] = 0.0  # zero components / blocks happen too
        best = domain.linear_argmax(g)
        assert domain.contains(best, tol=1e-12)
        value = float(g @ best)
        sampled = float(np.max(samples @ g))
        assert value >= sampled - 1e-12
        # independent closed form of max g·p
        if isinstance(domain, BoxDomain):
            exact = float(np.sum(np.maximum(g * domain.lower, g * domain.upper)))
        else:
            blocks = g.reshape(domain.centres.shape)
            exact = float(np.sum(domain.centres * blocks) + domain.radii @ np.linalg.norm(blocks, axis=1))
        assert value == pytest.approx(exact, rel=1e-12, abs=1e-12)
        # the dense samples come close from below (the optimum is not a fluke)
        assert sampled >= exact - 0.05 * np.sum(np.abs(g))


@pytest.mark.parametrize("make", [_box, _balls])
def test_project_lands_inside_and_is_idempotent(make) -> None:
    domain = make()
    rng = np.random.default_rng(2)
    far = domain.centre + 4.0 * rng.standard_normal((500, domain.dim))
    projected = domain.project(far)
    assert np.all(domain.contains(projected, tol=1e-12))
    np.testing.assert_allclose(domain.project(projected), projected, rtol=0, atol=1e-14)
    inside = domain.sample(rng, 500)
    np.testing.assert_array_equal(domain.project(inside), inside)
    # the projection is the nearest point of the domain: no sample is closer
    for p, q in zip(far[:20], projected[:20]):
        d = np.linalg.norm(inside - p, axis=1)
        assert np.linalg.norm(q - p) <= d.min() + 1e-12


def test_balls_projection_is_radial() -> None:
    domain = _balls()
    p = np.array([0.0, 1.0, 0.0, 3.0, 3.0, 4.5])  # ball 0: distance 2 along z; ball 1: 5 away
    expected = np.array([0.0, 1.0, -1.6, 3.0, 0.9, 1.7])
    np.testing.assert_allclose(domain.project(p), expected, atol=1e-15)


@pytest.mark.parametrize("make", [_box, _balls])
def test_sample_lands_inside(make) -> None:
    domain = make()
    samples = domain.sample(np.random.default_rng(3), 20_000)
    assert samples.shape == (20_000, domain.dim)
    assert np.all(domain.contains(samples))
    if isinstance(domain, BallsDomain):  # uniform in volume: 1/8 within half the radius
        r = np.linalg.norm(samples.reshape(-1, 2, 3) - domain.centres, axis=2) / domain.radii
        assert np.mean(r < 0.5) == pytest.approx(0.125, abs=0.01)
    else:  # uniform in the box: every coordinate's mean is the centre
        span = domain.upper - domain.lower
        np.testing.assert_allclose((samples.mean(axis=0) - domain.centre) / span, 0.0, atol=0.01)


def test_scipy_bounds_and_ball_constraints() -> None:
    box = _box()
    assert box.scipy_bounds() == [(-1.0, 1.0), (0.5, 0.9), (2.0, 5.0), (-0.2, -0.1)]
    assert box.scipy_constraints() == []
    balls = _balls()
    lo, hi = np.array(balls.scipy_bounds()).T
    np.testing.assert_allclose(lo, [-0.4, 0.6, -2.4, 1.5, -1.5, -1.0])
    np.testing.assert_allclose(hi, [0.4, 1.4, -1.6, 4.5, 1.5, 2.0])
    (constraint,) = balls.scipy_constraints()
    p = np.array([0.1, 1.2, -2.0, 3.0, 1.0, 0.5])
    np.testing.assert_allclose(constraint.fun(p), [0.05, 1.0])
    np.testing.assert_allclose(constraint.ub, [0.16, 2.25])
    h = 1e-7
    numeric = np.array([(constraint.fun(p + h * e) - constraint.fun(p - h * e)) / (2 * h) for e in np.eye(6)]).T
    np.testing.assert_allclose(constraint.jac(p), numeric, atol=1e-6)


# --------------------------------------------------------------------- fuzzy parameter sets
def test_fuzzy_vector_domain_is_the_box_of_cuts() -> None:
    params = FuzzyVector([triangular(1.0, 2.0, 4.0, "a"), triangular(-1.0, 0.0, 0.5), triangular(3.0, 3.0, 3.0)])
    assert params.names == ["a", "p1", "p2"]
    np.testing.assert_array_equal(params.deterministic, [2.0, 0.0, 3.0])
    np.testing.assert_array_equal(params.scale, [2.0, 1.5, 3.0])  # |peak|, else the support width
    box = params.domain(0.5)
    np.testing.assert_allclose(box.lower, [1.5, -0.5, 3.0])
    np.testing.assert_allclose(box.upper, [3.0, 0.25, 3.0])
    top = params.domain(1.0)
    np.testing.assert_array_equal(top.lower, top.upper)
    with pytest.raises(ParameterError, match="at least one"):
        FuzzyVector([])


def test_fuzzy_balls_radius_shrinks_linearly() -> None:
    balls = FuzzyBalls(np.zeros((2, 3)), np.array([0.01, 0.02]), ("LASI", "RASI"))
    assert balls.names == ["LASI_x", "LASI_y", "LASI_z", "RASI_x", "RASI_y", "RASI_z"]
    assert balls.dim == 6
    for alpha in (0.0, 0.3, 1.0):
        np.testing.assert_allclose(balls.domain(alpha).radii, (1 - alpha) * np.array([0.01, 0.02]), atol=1e-18)
    np.testing.assert_array_equal(balls.scale, [0.01] * 3 + [0.02] * 3)
    with pytest.raises(ParameterError, match="one radius per ball"):
        FuzzyBalls(np.zeros((2, 3)), np.array([0.01]))
    with pytest.raises(ParameterError, match="radii"):
        FuzzyBalls(np.zeros((1, 3)), np.array([-0.01]))
    with pytest.raises(ParameterError, match="alpha"):
        balls.domain(-0.1)
