"""The FRV-GFA of several independent fuzzy random parameters (thesis §2.7.4, the
multi-parameter case after Eq. 2.33): per-parameter sample streams, boxes of grouped
intervals, the product count of possible boxes, box hulls over the grid-point library,
extension by samples and execution on workers — checked against independent truths
(closed-form hulls of an analytic model, brute-force enumeration, the one-parameter
study, a Monte Carlo of the deterministic model)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy import stats
from test_frv import CountingEvaluator  # the serial evaluator, counting rows and calls

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import (
    FRVSpec,
    FRVStudy,
    Grid,
    MultiStudyOptions,
    StudyOptions,
    box_extrema,
    generate_box_samples,
    generate_samples,
    group,
    occurring_boxes,
    possible_boxes,
)

TIMES = np.linspace(0.0, 2.0, 9)
A, B = 2.0, 3.0
ALPHAS = (0.0, 0.5, 1.0)


def analytic_model() -> FunctionModel:
    """f(p, t) = (A·p1 + B·p2²)·t: increasing in p1, convex in p2 with its minimum at 0,
    for every t ≥ 0 — so every box hull is known in closed form."""
    return FunctionModel(lambda p: (A * p[..., :1] + B * p[..., 1:2] ** 2) * TIMES, TIMES)


def specs() -> list[FRVSpec]:
    """p1 about 1 (positive); p2 with its peak ~ N(0, 1) so its boxes straddle 0."""
    return [FRVSpec("p1", 1.0, alphas=ALPHAS), FRVSpec("p2", 1.0, relative_scale=1.0, mean=-1.0, alphas=ALPHAS)]


def closed_form_hull(grids: tuple[Grid, ...], bins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper hull of the analytic model over the grid points of the box with
    per-parameter bins ``bins (2, 2)`` (``[[l1, r1], [l2, r2]]``): p1 at its left / right
    end; p2² smallest at the grid point nearest 0 inside the box, largest at the end
    farther from 0."""
    g1, g2 = grids
    c1l, c1r = g1.centres(bins[0])
    nearest_zero = int(np.clip(np.floor(-g2.origin / g2.spacing), bins[1, 0], bins[1, 1]))
    c2_min = float(g2.centres(nearest_zero))
    c2l, c2r = g2.centres(bins[1])
    c2_max = c2l if abs(c2l) >= abs(c2r) else c2r
    f = analytic_model().function
    return f(np.array([c1l, c2_min])), f(np.array([c1r, c2_max]))


# ============================================================================ samples, grouping
def test_parameter_zero_is_the_one_parameter_stream_and_the_others_are_independent() -> None:
    s = specs()
    cuts = generate_box_samples(s, 3000, seed=4)
    assert cuts.shape == (3000, 2, 3, 2)
    np.testing.assert_array_equal(cuts[:, 0], generate_samples(s[0], 3000, seed=4))
    np.testing.assert_array_equal(cuts[:, 1], generate_samples(s[1], 3000, seed=4, stream=1))
    assert not np.array_equal(cuts[:, 1], generate_samples(s[1], 3000, seed=4))
    # whatever the split; peaks of the two parameters uncorrelated
    halves = [generate_box_samples(s, 1500, 4), generate_box_samples(s, 1500, 4, 1500)]
    np.testing.assert_array_equal(np.concatenate(halves), cuts)
    assert abs(stats.pearsonr(cuts[:, 0, -1, 0], cuts[:, 1, -1, 0])[0]) < 4 / np.sqrt(3000)
    # each parameter's peak has its own distribution (Eq. 2.28)
    assert stats.kstest(cuts[:, 1, -1, 0], s[1].peak_distribution().cdf).pvalue > 0.01


def test_specs_must_share_alphas_and_have_distinct_names() -> None:
    with pytest.raises(ParameterError, match="same α-levels"):
        generate_box_samples([FRVSpec("a", 1.0), FRVSpec("b", 1.0, alphas=(0.0, 0.25, 1.0))], 3)
    with pytest.raises(ParameterError, match="distinct names"):
        generate_box_samples([FRVSpec("a", 1.0), FRVSpec("a", 2.0)], 3)


def test_possible_boxes_is_the_product_of_eq_2_32_on_a_hand_sized_example() -> None:
    grids = (Grid(0.0, 1.0, 4), Grid(0.0, 1.0, 3))  # 3 and 2 bins
    every = [(l1, r1, l2, r2) for l1, r1 in itertools.combinations_with_replacement(range(3), 2)
             for l2, r2 in itertools.combinations_with_replacement(range(2), 2)]  # fmt: skip
    assert possible_boxes(grids) == len(every) == 6 * 3 == 18
    # two samples, two α-levels below 1 each: boxes (sample, parameter, alpha, [l, r])
    bins = np.array([[[[0, 2], [1, 1], [1, 1]], [[0, 1], [0, 1], [1, 1]]],
                     [[[0, 2], [1, 2], [2, 2]], [[0, 1], [1, 1], [1, 1]]]])  # fmt: skip
    occurring = occurring_boxes(bins)
    expected = {(0, 2, 0, 1), (1, 1, 0, 1), (1, 2, 1, 1)}  # sample 0 α=0 equals sample 1 α=0
    assert {tuple(k) for k in occurring.tolist()} == expected and len(occurring) == 3 <= 18
    assert set(expected) <= set(every)


def test_box_extrema_match_brute_force() -> None:
    rng = np.random.default_rng(3)
    values = rng.normal(size=(7, 5, 4, 3))  # three parameters, three columns
    first = np.stack([rng.integers(0, m, 200) for m in (7, 5, 4)], axis=1)
    last = np.stack([rng.integers(f, m) for f, m in zip(first.T, (7, 5, 4), strict=True)], axis=1)
    low, high = box_extrema(values, values, first, last)
    for q in range(200):
        window = values[first[q, 0] : last[q, 0] + 1, first[q, 1] : last[q, 1] + 1, first[q, 2] : last[q, 2] + 1]
        np.testing.assert_array_equal(low[q], window.min(axis=(0, 1, 2)))
        np.testing.assert_array_equal(high[q], window.max(axis=(0, 1, 2)))
    with pytest.raises(ParameterError):
        box_extrema(values, values, first[:, :2], last[:, :2])


# ============================================================================ the study
def test_study_hulls_are_the_closed_form_box_hulls(tmp_path) -> None:
    model, counter = analytic_model(), CountingEvaluator(analytic_model())
    study = FRVStudy.create(model, specs(), 800, StudyOptions(n_disc=(12, 15), seed=1, chunk=200),
                            store=tmp_path / "s.zarr", evaluator=counter)  # fmt: skip
    counts, grids = study.counts, study.grids
    cuts = study.samples()["cut"].to_numpy()
    bins = study.samples()["bin"].to_numpy()
    np.testing.assert_array_equal(cuts, generate_box_samples(specs(), 800, 1))
    np.testing.assert_array_equal(bins[:, 1], group(cuts[:, 1], grids[1]))
    # only occurring boxes, out of the product of the per-parameter possible intervals
    occurring = {tuple(np.concatenate(bins[i, :, a, :]).tolist()) for i in range(800) for a in range(2)}
    assert counts["occurring_intervals"] == len(occurring) == study.interval_rows
    assert counts["possible_intervals"] == 11 * 12 // 2 * (14 * 15 // 2) == possible_boxes(grids)
    assert counts["occurring_intervals"] < counts["possible_intervals"]
    assert counts["worst_case_optimisations"] == 2 * TIMES.size * counts["possible_intervals"]
    # one simulation per grid point inside some occurring box, in one evaluator call
    inside = set()
    for key in occurring:
        inside.update(itertools.product(range(key[0], key[1] + 1), range(key[2], key[3] + 1)))
    assert counter.calls == 1 and counter.rows == counts["forward_simulations"] == len(inside)
    assert {tuple(p) for p in study.library()["point"].to_numpy().tolist()} == inside
    hull = study.hulls()["hull"].to_numpy()
    assert hull.shape == (800, 3, 2, TIMES.size)
    for i in range(0, 800, 7):
        for a in range(2):
            lower, upper = closed_form_hull(grids, bins[i, :, a, :])
            np.testing.assert_allclose(hull[i, a, 0], lower, rtol=1e-13, atol=1e-15)
            np.testing.assert_allclose(hull[i, a, 1], upper, rtol=1e-13, atol=1e-15)
        peak = np.array([grids[d].centres(bins[i, d, -1, 0]) for d in range(2)])
        np.testing.assert_array_equal(hull[i, -1, 0], model.function(peak))  # α = 1: the peak grid point
    assert counts["repaired_values"] == 0  # box hulls of nested boxes nest


def test_one_parameter_equals_the_one_parameter_study(tmp_path) -> None:
    model = FunctionModel(lambda p: np.sin(p[..., :1] * TIMES), TIMES)  # no sensitivities: no refinement
    spec = FRVSpec("p", 1.0, alphas=(0.0, 0.25, 0.5, 0.75, 1.0))
    single = FRVStudy.create(model, spec, 600, StudyOptions(n_disc=20, seed=3, chunk=128), store=tmp_path / "a.zarr")
    multi = FRVStudy.create(model, [spec], 600, MultiStudyOptions(n_disc=20, seed=3, chunk=128),
                            store=tmp_path / "b.zarr")  # the several-parameter way, of one parameter
    assert multi.several and not single.several and multi.n_params == single.n_params == 1
    assert multi.grids == (single.grid,) and single.refine is False
    np.testing.assert_array_equal(multi.hulls()["hull"].to_numpy(), single.hulls()["hull"].to_numpy())
    assert multi.counts["occurring_intervals"] == single.counts["occurring_intervals"]
    assert multi.counts["possible_intervals"] == single.counts["possible_intervals"]


def test_add_samples_equals_one_shot_bit_for_bit(tmp_path) -> None:
    model, counter = analytic_model(), CountingEvaluator(analytic_model())
    grown = FRVStudy.create(model, specs(), 30, StudyOptions(n_disc=8, seed=2, chunk=64),
                            store=tmp_path / "g.zarr", evaluator=counter)  # fmt: skip
    grids0, sims0, boxes0 = grown.grids, grown.counts["forward_simulations"], grown.interval_rows
    grown.add_samples(700)
    assert any(g.n_bins > g0.n_bins for g, g0 in zip(grown.grids, grids0, strict=True))  # the grids grew
    assert all((g.origin, g.spacing) == (g0.origin, g0.spacing) for g, g0 in zip(grown.grids, grids0, strict=True))
    # only new grid points simulated, only new boxes computed
    assert counter.calls == 2 and counter.rows == grown.counts["forward_simulations"] == grown.library_rows
    assert grown.counts["last_forward_simulations"] == grown.library_rows - sims0 > 0
    assert grown.counts["last_new_intervals"] == grown.interval_rows - boxes0 > 0
    one_shot = FRVStudy.create(model, specs(), 730,
                               MultiStudyOptions(seed=2, chunk=64, grids=grown.grids),
                               store=tmp_path / "o.zarr")
    for name in ("hull",):
        np.testing.assert_array_equal(grown.hulls()[name].to_numpy(), one_shot.hulls()[name].to_numpy())
    for name in ("cut", "bin"):
        np.testing.assert_array_equal(grown.samples()[name].to_numpy(), one_shot.samples()[name].to_numpy())
    for key in ("forward_simulations", "occurring_intervals", "interval_optimisations", "possible_intervals"):
        assert grown.counts[key] == one_shot.counts[key], key
    # reopened from disk and grown again: identical to growing in memory
    again = FRVStudy.open(tmp_path / "g.zarr", model)
    assert again.several and again.specs == tuple(specs()) and again.counts == grown.counts
    again.add_samples(100)
    direct = FRVStudy.create(model, specs(), 830,
                             MultiStudyOptions(seed=2, chunk=64, grids=again.grids),
                             store=tmp_path / "d.zarr")
    np.testing.assert_array_equal(again.hulls()["hull"].to_numpy(), direct.hulls()["hull"].to_numpy())
    with pytest.raises(ParameterError, match=r"2 FRV parameters \(p1, p2\) has one spec each; use specs"):
        again.spec  # noqa: B018 - the property raises
    with pytest.raises(ParameterError, match="has one grid each; use grids"):
        again.grid  # noqa: B018
    linear = FunctionModel(lambda p: p[..., :1] * TIMES, TIMES)
    FRVStudy.create(linear, FRVSpec("q", 1.0), 20, store=tmp_path / "one.zarr")
    one = FRVStudy.open(tmp_path / "one.zarr", linear)  # the same type opens the one-parameter layout
    assert not one.several and one.spec == FRVSpec("q", 1.0) and one.grids == (one.grid,)
    assert one.peak_refine == [1] and one.peak_tolerance is None


def test_alpha_one_outputs_follow_the_deterministic_model_at_the_peaks(tmp_path) -> None:
    """The α = 1 output (the model at the grouped peak) against a Monte Carlo of the
    deterministic model at the same raw peak samples: one distribution (two-sample KS)."""
    model = analytic_model()
    study = FRVStudy.create(model, specs(), 3000, StudyOptions(n_disc=40, seed=5, chunk=1000),
                            store=tmp_path / "s.zarr")
    peaks = study.samples()["cut"].to_numpy()[:, :, -1, 0]  # (n, 2) raw peaks
    monte_carlo = model.function(peaks)  # (n, n_time), vectorised
    alpha_one = study.hulls()["hull"].to_numpy()[:, -1, 0]
    for node in (2, 5, TIMES.size - 1):
        assert stats.ks_2samp(alpha_one[:, node], monte_carlo[:, node]).pvalue > 0.01, node


@pytest.mark.slow  # starts a local process pool
def test_one_and_two_workers_are_bit_identical(tmp_path) -> None:
    pytest.importorskip("distributed")
    from fuzzygait.testing import AnalyticRecipe
    from fuzzygait.uncertainty.execution import Evaluator

    recipe = AnalyticRecipe("sin", n_time=21, t_end=3.0)
    model = recipe.build()
    s = [FRVSpec("p1", 1.0, alphas=ALPHAS), FRVSpec("p2", 0.5, alphas=ALPHAS)]
    results = []
    for workers in (1, 2):
        with Evaluator(workers=workers) as pool:
            study = FRVStudy.create(model, s, 400, StudyOptions(n_disc=10, seed=6, chunk=128),
                                    store=tmp_path / f"w{workers}.zarr",
                                    evaluator=pool.batch(recipe))  # fmt: skip
            study.add_samples(100)
        results.append((study.hulls()["hull"].to_numpy(), study.library()["value"].to_numpy(), dict(study.counts)))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])
    assert results[0][2]["forward_simulations"] == results[1][2]["forward_simulations"]


# ============================================================================ Latin-hypercube peaks (§2.7.5)
def test_latin_hypercube_peaks_fill_every_stratum_once_per_block() -> None:
    from fuzzygait.uncertainty.frv import BLOCK

    s = [FRVSpec("p1", 1.0, alphas=ALPHAS, sampling="lhs"), FRVSpec("p2", 2.0, alphas=ALPHAS, sampling="lhs")]
    cuts = generate_box_samples(s, 2 * BLOCK + 100, seed=9)
    for d, spec in enumerate(s):
        u = spec.peak_distribution().cdf(cuts[:, d, -1, 0])
        for block in range(2):  # each full block: exactly one peak per equal-probability stratum
            strata = np.floor(u[block * BLOCK : (block + 1) * BLOCK] * BLOCK).astype(int)
            np.testing.assert_array_equal(np.sort(strata), np.arange(BLOCK))
        assert stats.kstest(cuts[:, d, -1, 0], spec.peak_distribution().cdf).pvalue > 0.01
    # the strata of the two parameters are permuted independently (a hypercube, not a diagonal)
    assert abs(stats.spearmanr(cuts[:BLOCK, 0, -1, 0], cuts[:BLOCK, 1, -1, 0])[0]) < 4 / np.sqrt(BLOCK)
    # still a function of the sample index: any split gives the same samples
    halves = [generate_box_samples(s, 700, 9), generate_box_samples(s, 2 * BLOCK + 100 - 700, 9, 700)]
    np.testing.assert_array_equal(np.concatenate(halves), cuts)
    # the option is part of the spec (stored and read back)
    assert FRVSpec.from_dict(s[0].to_dict()) == s[0]
    with pytest.raises(ParameterError, match="sampling"):
        FRVSpec("p", 1.0, sampling="sobol")


def test_a_latin_hypercube_study_extends_bit_for_bit(tmp_path) -> None:
    model = analytic_model()
    s = [FRVSpec(x.name, x.deterministic, x.relative_scale, x.alphas, mean=x.mean, sampling="lhs") for x in specs()]
    grown = FRVStudy.create(model, s, 200, StudyOptions(n_disc=10, seed=3), store=tmp_path / "g.zarr")
    grown.add_samples(300)
    one_shot = FRVStudy.create(model, s, 500, MultiStudyOptions(seed=3, grids=grown.grids),
                               store=tmp_path / "o.zarr")
    np.testing.assert_array_equal(grown.hulls()["hull"].to_numpy(), one_shot.hulls()["hull"].to_numpy())
    assert FRVStudy.open(tmp_path / "g.zarr", model).specs == tuple(s)


def test_figures_per_parameter_and_of_the_output(tmp_path) -> None:
    from fuzzygait.viz import frv as figures

    study = FRVStudy.create(analytic_model(), specs(), 300, StudyOptions(n_disc=10, seed=2),
                            store=tmp_path / "s.zarr")
    made = figures.parameter_figures(study.specs, seed=2, n_samples=300, grids=study.grids, units={"p2": "kg/m³"})
    assert made["p2"][0].axes[0].get_xlabel() == "p2 (kg/m³)" and made["p1"][1].axes[1].get_xlabel() == "p1"
    assert list(made) == ["p1", "p2"] and all(len(a.axes) == 4 and len(b.axes) == 2 for a, b in made.values())
    # each parameter's figure shows its own stream: the grouping figure's points are its grid's
    points = made["p2"][1].axes[1].lines[-1].get_xdata()
    np.testing.assert_array_equal(points, study.grids[1].extended(study.samples()["cut"][:100, 1].to_numpy()).points())
    out = [figures.output_distribution_figure(study, 4), figures.temporal_evolution_figure(study),
           figures.fuzzy_random_output_figure(study, -1)]  # fmt: skip
    assert [len(f.axes) for f in out] == [3, 3, 2]
