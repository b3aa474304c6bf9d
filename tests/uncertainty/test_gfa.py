"""The Graph Follower algorithm against independent truth: closed-form hulls of monotone
and oscillating models, a dense grid (refined by a local polish) for a coupled
2-parameter model, the analytic hull of fuzzy balls, and dense sampling of the pendulum.

Errors are measured relative to the output scale (the largest |value| of the true
hulls), printed (run with ``-s`` to see them) and asserted. Direct mode reaches 1e-6;
linearised mode is exact for monotone models and is held to what it was measured to
reach elsewhere (a local, Frank-Wolfe-like ascent from the library's best entry)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.pendulum import Pendulum
from fuzzygait.uncertainty import (
    CountedModel,
    Direct,
    Evaluation,
    FunctionModel,
    FuzzyBalls,
    FuzzyVector,
    Linearised,
    Output,
    graph_follower,
    optimisation_nodes,
    triangular,
    triangular_relative,
)

MODES = ("linearised", "side-by-side", "direct")


def strategy_for(mode: str, **options: object) -> Linearised | Direct:
    """The strategy called ``mode`` with those of ``options`` it has ("side-by-side": the
    linearised strategy with its (α, bound) tracks followed side by side)."""
    kind = Direct if mode == "direct" else Linearised
    if mode == "side-by-side":
        options = {**options, "tracks": "side-by-side"}
    return kind(**{k: v for k, v in options.items() if k in kind.__dataclass_fields__})  # type: ignore[arg-type]


# --------------------------------------------------------------------- helpers
def sin_max(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """max of sin over [lo, hi]: 1 if π/2 + 2πk lies inside, else the larger end value."""
    k = np.ceil((lo - np.pi / 2) / (2 * np.pi))
    crosses = np.pi / 2 + 2 * np.pi * k <= hi
    return np.where(crosses, 1.0, np.maximum(np.sin(lo), np.sin(hi)))


def sin_min(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """min of sin over [lo, hi] (sin(x + π) = −sin x)."""
    return -sin_max(lo + np.pi, hi + np.pi)


def hull_error(result, truth: dict[float, tuple[np.ndarray, np.ndarray]]) -> tuple[float, float]:
    """(relative error, relative overshoot) of the hulls against ``truth[α] = (lower,
    upper)``. Overshoot > 0 means a hull lies outside the true range — impossible for the
    algorithm, whose hull values are simulations of admissible parameters."""
    scale = max(float(np.max(np.abs(np.concatenate(v)))) for v in truth.values())
    err = over = 0.0
    for alpha, (lower, upper) in truth.items():
        lo = result.hull.sel(alpha=alpha, bound="lower").to_numpy()
        up = result.hull.sel(alpha=alpha, bound="upper").to_numpy()
        err = max(err, np.max(np.abs(lo - lower)), np.max(np.abs(up - upper)))
        over = max(over, np.max(lower - lo), np.max(up - upper))
    return err / scale, over / scale


def report(label: str, result, err: float) -> None:
    print(f"\n{label}: relative error {err:.1e}, {result.attrs['forward_simulations']} model evaluations")


# --------------------------------------------------------------------- monotone model
T_MONO = np.linspace(0.0, 2.0, 21)
P_MONO = triangular(0.5, 1.0, 1.8, "p")


def mono(p: np.ndarray) -> np.ndarray:
    """Increasing in p for every t (∂f/∂p = e^p (1 + t) − t ≥ 1)."""
    return np.exp(p[0]) * (1.0 + T_MONO) - p[0] * T_MONO


def mono_jac(p: np.ndarray) -> np.ndarray:
    return (np.exp(p[0]) * (1.0 + T_MONO) - T_MONO)[:, None]


@pytest.mark.parametrize(("mode", "jacobian"), [("linearised", mono_jac), ("linearised", None), ("direct", None)])
def test_monotone_model_hulls_are_the_cut_ends(mode, jacobian) -> None:
    alphas = (0.0, 0.3, 0.7, 1.0)
    model = FunctionModel(mono, T_MONO, jacobian)
    result = graph_follower(model, FuzzyVector([P_MONO]), alphas, strategy=strategy_for(mode, starts=3))
    truth = {}
    for alpha in alphas:
        lo, hi = P_MONO.alpha_cut(alpha)
        truth[alpha] = (mono(np.array([lo])), mono(np.array([hi])))
    err, over = hull_error(result, truth)
    report(f"monotone 1-p {mode} jac={jacobian is not None}", result, err)
    if mode == "linearised":
        # the linear step lands on the cut end itself: bit-identical hulls
        for alpha, (lower, upper) in truth.items():
            np.testing.assert_array_equal(result.hull.sel(alpha=alpha, bound="lower"), lower)
            np.testing.assert_array_equal(result.hull.sel(alpha=alpha, bound="upper"), upper)
        # one simulation per cut end, reused at every node (novelty check, Eq. 2.24)
        assert result.attrs["library_size"] == 1 + 2 * 3
    assert err <= 1e-12
    assert over <= 1e-15


T_MONO2 = np.linspace(0.0, 1.0, 11)
P_MONO2 = (triangular(1.0, 2.0, 2.5, "a"), triangular(-1.0, -0.5, 0.5, "b"))


def mono2(p: np.ndarray) -> np.ndarray:
    """Increasing in a, decreasing in b at every t."""
    return p[0] * (1.0 + T_MONO2) - np.exp(p[1]) * T_MONO2 + p[0] ** 3


@pytest.mark.parametrize("mode", MODES)
def test_monotone_two_parameter_model_hulls_are_box_vertices(mode) -> None:
    model = FunctionModel(mono2, T_MONO2)
    result = graph_follower(model, FuzzyVector(P_MONO2), (0.0, 0.5), strategy=strategy_for(mode, starts=3))
    truth = {}
    for alpha in (0.0, 0.5, 1.0):
        (a_lo, a_hi), (b_lo, b_hi) = (n.alpha_cut(alpha) for n in P_MONO2)
        truth[alpha] = (mono2(np.array([a_lo, b_hi])), mono2(np.array([a_hi, b_lo])))
    err, over = hull_error(result, truth)
    report(f"monotone 2-p {mode}", result, err)
    if mode == "linearised":
        for alpha, (lower, upper) in truth.items():
            np.testing.assert_array_equal(result.hull.sel(alpha=alpha, bound="lower"), lower)
            np.testing.assert_array_equal(result.hull.sel(alpha=alpha, bound="upper"), upper)
    assert err <= 1e-12
    assert over <= 1e-15


# --------------------------------------------------------------------- sin(ω p t)
OMEGA = 2.0 * np.pi
T_SIN = np.linspace(0.0, 2.0, 41)
P_SIN = triangular(0.8, 1.0, 1.3, "p")
SIN_ALPHAS = (0.0, 0.5, 1.0)


def sin_model(p: np.ndarray) -> np.ndarray:
    return np.sin(OMEGA * p[0] * T_SIN)


def sin_jac(p: np.ndarray) -> np.ndarray:
    return (OMEGA * T_SIN * np.cos(OMEGA * p[0] * T_SIN))[:, None]


def sin_truth() -> dict[float, tuple[np.ndarray, np.ndarray]]:
    truth = {}
    for alpha in SIN_ALPHAS:
        lo, hi = P_SIN.alpha_cut(alpha)
        a, b = OMEGA * lo * T_SIN, OMEGA * hi * T_SIN
        truth[alpha] = (sin_min(a, b), sin_max(a, b))
    return truth


def test_sin_truth_has_interior_extrema() -> None:
    """The case is non-monotone: at many nodes the true hull is ±1 from inside the cut."""
    lower, upper = sin_truth()[0.0]
    lo, hi = P_SIN.support
    ends = np.stack([sin_model(np.array([lo])), sin_model(np.array([hi]))])
    interior = (upper > ends.max(axis=0) + 1e-3) | (lower < ends.min(axis=0) - 1e-3)
    assert interior.sum() >= 10


@pytest.mark.parametrize(
    ("mode", "jacobian", "options", "tolerance"),
    [
        ("direct", None, {"starts": 4}, 1e-6),
        # measured 4.5e-4 with the defaults: a secant search limited to 4 steps per node
        ("linearised", sin_jac, {}, 2e-3),
        ("side-by-side", sin_jac, {}, 2e-3),
        ("linearised", None, {}, 2e-3),
        ("side-by-side", None, {}, 2e-3),
        # more steps and a finer novelty tolerance close the gap (measured 1.3e-8)
        ("linearised", sin_jac, {"max_iterations": 20, "novelty_tol": 1e-7}, 1e-6),
    ],
)
def test_sin_model_interior_extrema(mode, jacobian, options, tolerance) -> None:
    result = graph_follower(FunctionModel(sin_model, T_SIN, jacobian), FuzzyVector([P_SIN]), SIN_ALPHAS,
                            strategy=strategy_for(mode, **options))  # fmt: skip
    err, over = hull_error(result, sin_truth())
    report(f"sin(ωpt) {mode} jac={jacobian is not None} {options}", result, err)
    assert err <= tolerance
    assert over <= 1e-12


# --------------------------------------------------------------------- 2 parameters, analytic
T_PROD = np.linspace(0.0, 2.0, 21)
P_PROD = (triangular(0.7, 1.0, 1.2, "amp"), triangular(2.0, 3.0, 3.5, "freq"))


def prod_model(p: np.ndarray) -> np.ndarray:
    return p[0] * np.sin(p[1] * T_PROD)


def prod_jac(p: np.ndarray) -> np.ndarray:
    return np.stack([np.sin(p[1] * T_PROD), p[0] * T_PROD * np.cos(p[1] * T_PROD)], axis=1)


def prod_truth(alphas) -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """amp > 0, so max = amp_hi·max sin if that is positive, else amp_lo·max sin."""
    truth = {}
    for alpha in alphas:
        (a1, b1), (a2, b2) = (n.alpha_cut(alpha) for n in P_PROD)
        smax, smin = sin_max(a2 * T_PROD, b2 * T_PROD), sin_min(a2 * T_PROD, b2 * T_PROD)
        truth[alpha] = (np.where(smin < 0, b1 * smin, a1 * smin), np.where(smax > 0, b1 * smax, a1 * smax))
    return truth


@pytest.mark.parametrize(
    ("mode", "jacobian", "options", "tolerance"),
    [
        ("direct", None, {"starts": 4}, 1e-6),
        ("linearised", prod_jac, {}, 1.5e-3),  # measured 3.1e-4
        ("side-by-side", prod_jac, {}, 1.5e-3),
        ("linearised", None, {}, 1.5e-3),
        ("side-by-side", None, {}, 1.5e-3),
        ("linearised", prod_jac, {"max_iterations": 20, "novelty_tol": 1e-7}, 1e-6),  # measured ~3e-8
    ],
)
def test_two_parameter_product_model(mode, jacobian, options, tolerance) -> None:
    alphas = (0.0, 0.5, 1.0)
    result = graph_follower(FunctionModel(prod_model, T_PROD, jacobian), FuzzyVector(P_PROD), alphas,
                            strategy=strategy_for(mode, **options))  # fmt: skip
    err, over = hull_error(result, prod_truth(alphas))
    report(f"amp·sin(freq·t) {mode} jac={jacobian is not None} {options}", result, err)
    assert err <= tolerance
    assert over <= 1e-12


# --------------------------------------------------------------------- 2 parameters, dense grid
T_GRID = np.linspace(0.0, 3.0, 21)
P_GRID = (triangular(1.0, 1.5, 2.2, "u"), triangular(-1.0, 0.3, 1.5, "v"))
GRID_ALPHAS = (0.0, 0.5)


def grid_model(p: np.ndarray) -> np.ndarray:
    return np.sin(p[0] * T_GRID) * np.cos(p[1] * T_GRID) + 0.2 * p[0] * p[1]


@pytest.fixture(scope="module")
def grid_reference() -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """2001 × 2001 grid per α-level and node, its best point polished by L-BFGS-B (the
    grid alone is only good to ~1e-6 at interior optima)."""
    truth, interior = {}, 0
    for alpha in GRID_ALPHAS:
        (a1, b1), (a2, b2) = (n.alpha_cut(alpha) for n in P_GRID)
        u, v = np.linspace(a1, b1, 2001), np.linspace(a2, b2, 2001)
        lower, upper = np.empty(T_GRID.size), np.empty(T_GRID.size)
        for j, t in enumerate(T_GRID):
            values = np.outer(np.sin(u * t), np.cos(v * t)) + 0.2 * np.outer(u, v)
            for sense, out, k in ((1.0, upper, values.argmax()), (-1.0, lower, values.argmin())):
                iu, iv = np.unravel_index(k, values.shape)
                interior += int(0 < iu < 2000) + int(0 < iv < 2000)

                def node(p: np.ndarray, t: float = t, s: float = sense) -> float:
                    return -s * (np.sin(p[0] * t) * np.cos(p[1] * t) + 0.2 * p[0] * p[1])

                polished = minimize(node, [u[iu], v[iv]], method="L-BFGS-B", bounds=[(a1, b1), (a2, b2)],
                                    options={"ftol": 1e-15, "gtol": 1e-12})  # fmt: skip
                out[j] = sense * max(sense * values.flat[k], -polished.fun)
        truth[alpha] = (lower, upper)
    assert interior >= 20  # many optima are inside the box in at least one coordinate
    truth[1.0] = (grid_model(np.array([1.5, 0.3])),) * 2
    return truth


@pytest.mark.parametrize(
    ("mode", "tolerance"),
    [
        ("direct", 1e-6),
        # measured 4.2e-3 (7e-3 absolute on a scale of 1.66) with the default 4 linearised
        # steps per node: the per-coordinate secant reaches an optimum inside the box in
        # one coordinate within a few steps, and from the library's best entry the
        # search can stay in a neighbouring local optimum (8 steps: 1.1e-4)
        ("linearised", 1e-2),
        ("side-by-side", 1e-2),
    ],
)
def test_two_parameter_coupled_model_against_grid(grid_reference, mode, tolerance) -> None:
    result = graph_follower(FunctionModel(grid_model, T_GRID), FuzzyVector(P_GRID), GRID_ALPHAS, strategy=strategy_for(mode))
    err, over = hull_error(result, grid_reference)
    report(f"coupled 2-p grid {mode}", result, err)
    assert err <= tolerance
    assert over <= 1e-9  # the polished reference is exact to ~1e-12


# --------------------------------------------------------------------- fuzzy balls
T_BALL = np.linspace(0.0, 1.0, 11)
X_BALL = np.stack([np.cos(T_BALL), np.sin(T_BALL), 0.3 * T_BALL], axis=1)  # a moving point
C_BALL, E_BALL = np.array([3.0, 1.0, -0.5]), np.array([-2.0, 0.5, 1.0])
R_BALL = np.array([0.4, 0.25])


def ball_model(p: np.ndarray) -> np.ndarray:
    """|c − (x + d1)| + |(x + d2) − e|: deviation d1 of one point, d2 of the other."""
    return np.linalg.norm(C_BALL - (X_BALL + p[:3]), axis=1) + np.linalg.norm(X_BALL + p[3:] - E_BALL, axis=1)


@pytest.mark.parametrize(("mode", "tolerance"), [("direct", 1e-6), ("linearised", 1e-6), ("side-by-side", 1e-6)])
def test_fuzzy_balls_match_the_analytic_hull(mode, tolerance) -> None:
    balls = FuzzyBalls(np.zeros((2, 3)), R_BALL, ("A", "B"))
    result = graph_follower(FunctionModel(ball_model, T_BALL), balls, (0.0, 0.5), strategy=strategy_for(mode, starts=4))
    distance = np.linalg.norm(C_BALL - X_BALL, axis=1) + np.linalg.norm(X_BALL - E_BALL, axis=1)
    truth = {alpha: (distance - (1 - alpha) * R_BALL.sum(), distance + (1 - alpha) * R_BALL.sum())
             for alpha in (0.0, 0.5, 1.0)}  # fmt: skip
    err, over = hull_error(result, truth)
    report(f"fuzzy balls {mode}", result, err)
    assert err <= tolerance
    assert over <= 1e-12
    assert list(result.parameter.values) == ["A_x", "A_y", "A_z", "B_x", "B_y", "B_z"]
    # the extremisers sit on the ball surfaces, along the line to the fixed points
    ex = result.extremiser.sel(alpha=0.0, bound="upper").to_numpy()
    np.testing.assert_allclose(np.linalg.norm(ex[:, :3], axis=1), R_BALL[0], rtol=1e-4)
    np.testing.assert_allclose(np.linalg.norm(ex[:, 3:], axis=1), R_BALL[1], rtol=1e-4)


# --------------------------------------------------------------------- pendulum
PENDULUM_LENGTH = triangular_relative(1.0, 0.1, "L")


@pytest.fixture(scope="module")
def pendulum_reference() -> dict[str, object]:
    """Dense sampling: 201 lengths across each α-cut (α = 0, 0.5), min/max per node."""
    model = Pendulum()
    truth, runs = {}, 0
    for alpha in (0.0, 0.5):
        lo, hi = PENDULUM_LENGTH.alpha_cut(alpha)
        runs_alpha = np.array([model.evaluate(np.array([length])).values for length in np.linspace(lo, hi, 201)])
        truth[alpha] = (runs_alpha.min(axis=0), runs_alpha.max(axis=0))
        runs += runs_alpha.shape[0]
    deterministic = model.evaluate(np.array([1.0])).values
    truth[1.0] = (deterministic, deterministic)
    return {"truth": truth, "runs": runs}


def test_pendulum_against_dense_sampling(pendulum_reference) -> None:
    model = Pendulum()
    assert model.times.size == 201 and model.times[-1] == 2.0
    result = graph_follower(model, FuzzyVector([PENDULUM_LENGTH]), (0.0, 0.5, 1.0))
    truth = pendulum_reference["truth"]
    worst = max(
        float(np.max(np.abs(result.hull.sel(alpha=a, bound=b).to_numpy() - truth[a][k])))
        for a in truth for k, b in enumerate(("lower", "upper"))
    )  # fmt: skip
    evaluations, dense = result.attrs["forward_simulations"], pendulum_reference["runs"]
    print(
        f"\npendulum: GFA {evaluations} evaluations vs dense {dense}; max |GFA − dense| = {worst:.2e} rad "
        f"= {100 * worst / model.theta0:.1e} % of the amplitude"
    )
    assert worst <= 0.005 * model.theta0
    assert evaluations <= 0.25 * dense
    # the fuzziness is real: the α = 0 band is wide, so the comparison means something
    lower, upper = truth[0.0]
    assert float(np.max(upper - lower)) > 0.2


def test_pendulum_alpha_one_is_the_deterministic_run() -> None:
    model = Pendulum()
    result = graph_follower(model, FuzzyVector([PENDULUM_LENGTH]), (0.0, 1.0))
    # linearised mode simulates with sensitivities: the deterministic run is that solve
    # (θ and ∂θ/∂L integrated together), bit for bit
    run = model.evaluate(np.array([1.0]), sensitivities=True).values
    np.testing.assert_array_equal(result.deterministic, run)
    for bound in ("lower", "upper"):
        np.testing.assert_array_equal(result.hull.sel(alpha=1.0, bound=bound), run)
    # and the plain solve agrees to the integrator's tolerance
    np.testing.assert_allclose(run, model.evaluate(np.array([1.0])).values, rtol=0, atol=1e-9)


# --------------------------------------------------------------------- α = 1
@pytest.mark.parametrize("mode", MODES)
def test_alpha_one_hull_is_the_deterministic_run(mode) -> None:
    result = graph_follower(FunctionModel(sin_model, T_SIN), FuzzyVector([P_SIN]), (0.0, 0.5), strategy=strategy_for(mode, starts=2, stride=5))  # fmt: skip
    run = sin_model(np.array([P_SIN.peak]))
    np.testing.assert_array_equal(result.deterministic, run)
    for bound in ("lower", "upper"):
        np.testing.assert_array_equal(result.hull.sel(alpha=1.0, bound=bound), run)
        np.testing.assert_array_equal(result.extremiser.sel(alpha=1.0, bound=bound), [[P_SIN.peak]] * T_SIN.size)
    np.testing.assert_array_equal(result.alpha, [0.0, 0.5, 1.0])  # 1 is always added


# --------------------------------------------------------------------- nesting property
def random_model(rng: np.random.Generator):
    """A random smooth model: a sum of sin/cos of linear forms in p and t."""
    n_p = int(rng.integers(1, 4))
    times = np.linspace(0.0, 1.0, 5)
    terms = int(rng.integers(1, 4))
    amp = rng.normal(size=terms)
    freq_p = rng.normal(scale=3.0, size=(terms, n_p))
    freq_t = rng.normal(scale=4.0, size=terms)
    phase = rng.uniform(0, 2 * np.pi, size=terms)
    cosine = rng.random(terms) < 0.5

    def f(p: np.ndarray) -> np.ndarray:
        arg = (freq_p @ p)[:, None] + freq_t[:, None] * times + phase[:, None]
        return np.sum(amp[:, None] * np.where(cosine[:, None], np.cos(arg), np.sin(arg)), axis=0)

    numbers = []
    for i in range(n_p):
        peak = rng.normal()
        left, right = rng.uniform(0.05, 1.0, size=2)
        numbers.append(triangular(peak - left, peak, peak + right, f"q{i}"))
    alphas = np.sort(rng.choice(np.round(np.linspace(0, 0.9, 10), 1), size=int(rng.integers(1, 4)), replace=False))
    return FunctionModel(f, times), FuzzyVector(numbers), alphas


def test_nesting_and_attainability_over_random_models() -> None:
    rng = np.random.default_rng(20240611)
    for case in range(30):
        model, params, alphas = random_model(rng)
        for mode in MODES:
            result = graph_follower(model, params, alphas, strategy=strategy_for(mode, starts=1, max_iterations=2))
            hull = result.hull.to_numpy()
            levels = result.alpha.to_numpy()
            for a in range(levels.size - 1):  # every lower level contains every higher one
                for b in range(a + 1, levels.size):
                    assert np.all(hull[a, 0] <= hull[b, 0]), (case, mode, levels[a], levels[b])
                    assert np.all(hull[a, 1] >= hull[b, 1]), (case, mode, levels[a], levels[b])
            # every hull value is a simulation of an admissible parameter (inner bound)
            for a, alpha in enumerate(levels):
                domain = params.domain(float(alpha))
                for b in range(2):
                    ex = result.extremiser.to_numpy()[a, b]
                    assert np.all(domain.contains(ex, tol=1e-12)), (case, mode, alpha)
                    values = np.array([model.evaluate(p).values[j] for j, p in enumerate(ex)])
                    np.testing.assert_array_equal(hull[a, b], values)


# --------------------------------------------------------------------- model protocol
def test_finite_differences_match_analytic_sensitivities() -> None:
    p = np.array([0.9, 3.2])
    counted = CountedModel(FunctionModel(prod_model, T_PROD), scale=np.array([1.0, 3.0]))
    f, jac = counted.trajectory_and_sensitivities(p)
    np.testing.assert_array_equal(f, prod_model(p))
    np.testing.assert_allclose(jac, prod_jac(p), rtol=0, atol=2e-5)
    assert counted.evaluations == 1 + 2
    exact = CountedModel(FunctionModel(prod_model, T_PROD, prod_jac), scale=np.array([1.0, 3.0]))
    f, jac = exact.trajectory_and_sensitivities(p)
    np.testing.assert_array_equal(jac, prod_jac(p))
    assert exact.evaluations == 1


class Calls:
    """Counts calls of a function independently of the engine."""

    def __init__(self, function) -> None:
        self.function, self.calls = function, 0

    def __call__(self, p: np.ndarray) -> np.ndarray:
        self.calls += 1
        return self.function(p)


@pytest.mark.parametrize("with_jacobian", [False, True])
def test_linearised_evaluations_are_counted(with_jacobian) -> None:
    function, jacobian = Calls(prod_model), Calls(prod_jac)
    model = FunctionModel(function, T_PROD, jacobian if with_jacobian else None)
    result = graph_follower(model, FuzzyVector(P_PROD), (0.0, 0.5))
    size = result.attrs["library_size"]
    assert result.attrs["forward_simulations"] == function.calls
    if with_jacobian:  # one simulation with sensitivities per library entry
        assert function.calls == jacobian.calls == size
    else:  # finite differences: 1 + n_p simulations per library entry
        assert function.calls == (1 + 2) * size
    assert result.attrs["optimisations"] == 2 * 2 * T_PROD.size


def test_direct_evaluations_are_counted_and_node_models_used() -> None:
    function = Calls(sin_model)
    strategy = Direct(starts=3, stride=4)
    result = graph_follower(FunctionModel(function, T_SIN), FuzzyVector([P_SIN]), (0.0,), strategy=strategy)
    assert result.attrs["forward_simulations"] == function.calls > 0
    assert result.attrs["node_evaluations"] == 0

    class NodeModel:
        times = T_SIN
        parameter_names = ()
        output = Output()
        capabilities = frozenset({"nodes"})

        def __init__(self) -> None:
            self.full = self.nodes = 0

        def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
            self.full += 1
            return Evaluation(sin_model(p))

        def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
            self.nodes += len(nodes)
            return np.sin(OMEGA * P[:, 0] * T_SIN[nodes])

    node_model = NodeModel()
    fast = graph_follower(node_model, FuzzyVector([P_SIN]), (0.0,), strategy=strategy)
    assert fast.attrs["node_evaluations"] == node_model.nodes > 0
    assert fast.attrs["forward_simulations"] == node_model.full < result.attrs["forward_simulations"]
    # at the optimised nodes the single-node optimisation finds the analytic hull
    nodes = optimisation_nodes(T_SIN.size, 4)
    lower, upper = sin_truth()[0.0]
    np.testing.assert_allclose(fast.hull.sel(alpha=0.0, bound="upper")[nodes], upper[nodes], rtol=0, atol=1e-6)
    np.testing.assert_allclose(fast.hull.sel(alpha=0.0, bound="lower")[nodes], lower[nodes], rtol=0, atol=1e-6)


@pytest.mark.parametrize("mode", MODES)
def test_nan_output_is_rejected(mode) -> None:
    def bad(p: np.ndarray) -> np.ndarray:
        out = sin_model(p)
        if p[0] != P_SIN.peak:
            out[3] = np.nan
        return out

    with pytest.raises(ParameterError, match="non-finite"):
        graph_follower(FunctionModel(bad, T_SIN), FuzzyVector([P_SIN]), strategy=strategy_for(mode, starts=1))


def test_wrong_output_length_is_rejected() -> None:
    model = FunctionModel(lambda p: np.zeros(T_SIN.size - 1), T_SIN)
    with pytest.raises(ParameterError, match=f"{T_SIN.size - 1} values for {T_SIN.size} time nodes"):
        graph_follower(model, FuzzyVector([P_SIN]))


def test_model_without_times_is_rejected() -> None:
    class NoTimes:
        def evaluate(self, p: np.ndarray) -> np.ndarray:
            return p

    with pytest.raises(ParameterError, match="lacks times.*FunctionModel"):
        graph_follower(NoTimes(), FuzzyVector([P_SIN]))


def test_plain_function_with_times_is_wrapped() -> None:
    """A plain callable and a list of fuzzy numbers: the same result as the explicit
    FunctionModel and FuzzyVector."""
    plain = graph_follower(lambda p: mono(p), [P_MONO], (0.0, 0.5), times=T_MONO)
    explicit = graph_follower(FunctionModel(mono, T_MONO), FuzzyVector([P_MONO]), (0.0, 0.5))
    np.testing.assert_array_equal(plain.hull.values, explicit.hull.values)
    lo, hi = P_MONO.alpha_cut(0.0)
    np.testing.assert_array_equal(plain.hull.sel(alpha=0.0, bound="upper"), mono(np.array([hi])))


def test_plain_function_without_times_says_what_to_pass() -> None:
    with pytest.raises(ParameterError, match=r"pass times=\.\.\. as well.*FunctionModel"):
        graph_follower(lambda p: mono(p), [P_MONO])


def test_misnamed_parameter_is_rejected() -> None:
    with pytest.raises(ParameterError, match=r"named \['length'\].*takes \['L'\]"):
        graph_follower(Pendulum(), [triangular_relative(1.0, 0.1, "length")])
    with pytest.raises(ParameterError, match="takes 1 parameters"):
        graph_follower(Pendulum(), [triangular_relative(1.0, 0.1, "L"), triangular_relative(1.0, 0.1, "x")])
    # unnamed fuzzy numbers are matched by position
    result = graph_follower(Pendulum(times=np.linspace(0.0, 0.2, 5)), [triangular_relative(1.0, 0.1)], (0.0,))
    assert list(result["parameter"].values) == ["p0"]


def test_batched_direct_needs_nodes() -> None:
    from fuzzygait.uncertainty import BatchedDirect

    with pytest.raises(ParameterError, match="'nodes' capability.*Direct"):
        graph_follower(FunctionModel(mono, T_MONO), [P_MONO], strategy=BatchedDirect())


# --------------------------------------------------------------------- arguments
@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"alphas": (-0.1, 0.5)}, "alphas"),
        ({"alphas": (0.0, 1.5)}, "alphas"),
        ({"alphas": ()}, "alphas"),
        ({"strategy": "linearized"}, "strategy"),
    ],
)
def test_bad_arguments_name_the_argument(kwargs, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        graph_follower(FunctionModel(sin_model, T_SIN), FuzzyVector([P_SIN]), **kwargs)


@pytest.mark.parametrize(
    ("build", "needle"),
    [
        (lambda: Linearised(stride=0), "stride"),
        (lambda: Linearised(stride=1.5), "stride"),  # type: ignore[arg-type]
        (lambda: Linearised(max_iterations=0), "max_iterations"),
        (lambda: Linearised(novelty_tol=-1.0), "novelty_tol"),
        (lambda: Direct(starts=0), "starts"),
    ],
)
def test_bad_strategy_options_name_the_option(build, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        build()


def test_stride_and_progress() -> None:
    np.testing.assert_array_equal(optimisation_nodes(10, 4), [0, 4, 8, 9])
    np.testing.assert_array_equal(optimisation_nodes(5, 1), [0, 1, 2, 3, 4])
    calls: list[tuple[int, int]] = []
    result = graph_follower(FunctionModel(mono, T_MONO, mono_jac), FuzzyVector([P_MONO]), (0.0, 0.5),
                            strategy=Linearised(stride=5),
                            progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    nodes = optimisation_nodes(T_MONO.size, 5).size
    assert calls == [(k, 2 * 2 * nodes) for k in range(1, 2 * 2 * nodes + 1)]
    assert result.attrs["optimisations"] == 2 * 2 * nodes
    # the hulls come from whole trajectories, so every node is exact, optimised or not
    lo, hi = P_MONO.alpha_cut(0.0)
    np.testing.assert_array_equal(result.hull.sel(alpha=0.0, bound="upper"), mono(np.array([hi])))
    np.testing.assert_array_equal(result.hull.sel(alpha=0.0, bound="lower"), mono(np.array([lo])))


# --------------------------------------------------------------------- inert parameters
T_INERT = np.linspace(0.0, 2.0, 201)
# Hash-like round-off "sensitivities" of an inert parameter: a sign that flips from node
# to node, as an inertia about an axis the motion never turns about shows in a simulator.
ROUND_OFF = 1e-20 * np.sign(np.sin(37.0 * np.arange(T_INERT.size) ** 1.3))


def active(p: np.ndarray) -> np.ndarray:
    return np.sin(p[0] * T_INERT) + 0.5 * p[0]


def active_jac(p: np.ndarray) -> np.ndarray:
    return (T_INERT * np.cos(p[0] * T_INERT) + 0.5)[:, None]


def with_inert(p: np.ndarray) -> np.ndarray:
    return active(p[:1])


def with_inert_jac(p: np.ndarray) -> np.ndarray:
    return np.column_stack([active_jac(p[:1])[:, 0], ROUND_OFF, -ROUND_OFF])


def test_inert_parameters_cost_no_extra_simulations() -> None:
    """Parameters whose sensitivity is round-off (an inertia about an axis the motion never
    turns about) must not make otherwise known parameter sets "new": the same number of
    simulations and the same hull as without them (before the linear step left such
    coordinates in place, their round-off signs flipped them from vertex to vertex)."""
    p_active = triangular_relative(2.0, 0.3, "omega")
    alone = graph_follower(FunctionModel(active, T_INERT, active_jac), FuzzyVector([p_active]), (0.0, 0.5))
    params = FuzzyVector([p_active, triangular_relative(1.0, 0.1, "J2"), triangular_relative(3.0, 0.1, "J3")])
    both = graph_follower(FunctionModel(with_inert, T_INERT, with_inert_jac), params, (0.0, 0.5))
    print(f"\nevaluations: 1 parameter {alone.attrs['forward_simulations']}, "
          f"with 2 inert {both.attrs['forward_simulations']}")  # fmt: skip
    assert alone.attrs["forward_simulations"] > 3  # interior extrema: the follower does work
    assert both.attrs["forward_simulations"] == alone.attrs["forward_simulations"]
    np.testing.assert_array_equal(both.hull.values, alone.hull.values)


@pytest.mark.parametrize("strategy", [Linearised(stride=5), Direct(stride=5, starts=2)], ids=["linearised", "direct"])
def test_every_strategy_returns_the_result_schema(strategy) -> None:
    from fuzzygait.core.schema import schema_problems

    model = FunctionModel(sin_model, T_SIN, output=Output("angle", "rad"))
    result = graph_follower(model, [P_SIN], (0.0, 0.5), strategy=strategy)
    assert schema_problems(result) == []
    assert result.attrs["strategy"] == strategy.name and result.attrs["units"] == "rad"
    assert result["hull"].attrs["units"] == result["deterministic"].attrs["units"] == "rad"
    assert {k: result.attrs[k] for k in strategy.options()} == strategy.options()
    broken = result.drop_vars("extremiser")
    broken.attrs.pop("forward_simulations")
    assert schema_problems(broken) == ["variable 'extremiser' missing", "attribute 'forward_simulations' missing"]
