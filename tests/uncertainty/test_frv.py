"""Fuzzy random variables and the FRV Graph Follower algorithm (thesis §2.7, §5.7):
sample generation (Eqs. 2.26–2.30), grouping (Eqs. 2.31–2.33), interval hulls, the
persistent study and distribution fitting — checked against independent truths
(closed-form distributions, brute-force sets, dense evaluation of analytic models)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.uncertainty import FunctionModel, frv
from fuzzygait.uncertainty.frv import (
    FRVSpec,
    FRVStudy,
    Grid,
    StudyOptions,
    fit_distributions,
    generate_samples,
    group,
    interval_hulls,
    occurring_intervals,
    serial_evaluator,
)
from fuzzygait.uncertainty.gfa import optimisation_nodes

ALPHAS5 = (0.0, 0.25, 0.5, 0.75, 1.0)
T_MAX = 10.0
TIMES = np.linspace(0.0, T_MAX, 41)


def sine_model(jacobian: bool = True) -> FunctionModel:
    """f(p, t) = sin(p t): several interior extrema in p at late times."""
    return FunctionModel(lambda p: np.sin(p[..., :1] * TIMES), TIMES,
                         (lambda p: (TIMES * np.cos(p[0] * TIMES))[:, None]) if jacobian else None)  # fmt: skip


def monotone_model(jacobian: bool = False) -> FunctionModel:
    """f(p, t) = (1 + t) exp(0.3 p t): increasing in p for every t > 0."""
    return FunctionModel(lambda p: (1 + TIMES) * np.exp(0.3 * p[..., :1] * TIMES), TIMES,
                         (lambda p: ((1 + TIMES) * 0.3 * TIMES * np.exp(0.3 * p[0] * TIMES))[:, None]) if jacobian else None)  # fmt: skip


class CountingEvaluator:
    """The serial evaluator, counting forward simulations (rows) and calls."""

    def __init__(self, model: FunctionModel) -> None:
        self.inner, self.rows, self.calls = serial_evaluator(model), 0, 0

    def __call__(self, P: np.ndarray):
        self.calls += 1
        self.rows += P.shape[0]
        return self.inner(P)


def dense_hull(model: FunctionModel, lo: float, hi: float, points: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """Extremes of the model over ``points`` equidistant parameters in ``[lo, hi]`` (ends included)."""
    values = model.function(np.linspace(lo, hi, points)[:, None])  # (points, n_time), one vectorised call
    return values.min(axis=0), values.max(axis=0)


# ============================================================================ samples
@pytest.mark.parametrize("distribution", ["normal", "beta"])
def test_samples_are_convex_fuzzy_numbers(distribution: str) -> None:
    spec = FRVSpec("E", 60e9, alphas=ALPHAS5, distribution=distribution)
    cuts = generate_samples(spec, 3000, seed=3)
    assert cuts.shape == (3000, 5, 2)
    np.testing.assert_array_equal(cuts[:, -1, 0], cuts[:, -1, 1])  # α = 1: degenerate
    assert np.all(np.diff(cuts[:, :, 0], axis=1) >= 0)  # left ends rise with α
    assert np.all(np.diff(cuts[:, :, 1], axis=1) <= 0)  # right ends fall with α
    if distribution == "normal":  # redrawn until positive: strictly convex
        assert np.all(np.diff(cuts[:, :, 0], axis=1) > 0) and np.all(np.diff(cuts[:, :, 1], axis=1) < 0)
    else:  # Δ = B·0.1·p_det/N_α with B in [0, 1]
        assert np.all(np.abs(np.diff(cuts, axis=1)) <= 0.1 * 60e9 / 4 * (1 + 1e-12))


def test_samples_are_reproducible_per_index_whatever_the_split() -> None:
    spec = FRVSpec("k", 3.0, alphas=ALPHAS5)
    whole = generate_samples(spec, 3000, seed=11)
    for cut in (1, 1023, 1024, 1025, 2500):
        split = np.concatenate([generate_samples(spec, cut, 11), generate_samples(spec, 3000 - cut, 11, start=cut)])
        np.testing.assert_array_equal(split, whole)
    np.testing.assert_array_equal(generate_samples(spec, 7, 11, start=1500), whole[1500:1507])
    assert not np.array_equal(generate_samples(spec, 10, seed=12), whole[:10])
    assert generate_samples(spec, 0, 11).shape == (0, 5, 2)


@pytest.mark.parametrize("mean, std", [(1.0, 1.0), (0.3, 0.5)])
def test_peak_distribution_is_eq_2_28_as_printed(mean: float, std: float) -> None:
    p_det = 59.958e9
    spec = FRVSpec("E", p_det, mean=mean, std=std)
    peaks = generate_samples(spec, 5000, seed=1)[:, -1, 0]
    # p_peak = p_det + X·0.1·p_det, X ~ N(mean, std)  =>  N(p_det(1 + 0.1 mean), (0.1 p_det std)²)
    assert stats.kstest(peaks, stats.norm(p_det * (1 + 0.1 * mean), 0.1 * p_det * std).cdf).pvalue > 0.01


def test_normal_increments_are_the_positive_truncation() -> None:
    spec = FRVSpec("E", 2.0, alphas=ALPHAS5)
    cuts = generate_samples(spec, 5000, seed=2)
    left = cuts[:, 1:, 0] - cuts[:, :-1, 0]
    right = cuts[:, :-1, 1] - cuts[:, 1:, 1]
    assert np.all(left > 0) and np.all(right > 0)
    # redrawing X ~ N(1, 1) while X <= 0 samples N(1, 1) truncated to X > 0; Δ = X·0.1·2/4
    c = 0.1 * 2.0 / 4
    truth = stats.truncnorm(-1.0, np.inf, loc=c, scale=c)
    for k in range(4):
        assert stats.kstest(left[:, k], truth.cdf).pvalue > 0.01
        assert stats.kstest(right[:, k], truth.cdf).pvalue > 0.01


def test_beta_increments_follow_the_scaled_beta() -> None:
    spec = FRVSpec("E", -5.0, alphas=(0.0, 0.5, 1.0), distribution="beta", beta_a=2.0, beta_b=5.0)
    cuts = generate_samples(spec, 4000, seed=4)
    c = 0.1 * 5.0 / 2  # |p_det| sets the scale
    truth = stats.beta(2.0, 5.0, scale=c)
    assert stats.kstest(cuts[:, 0, 1] - cuts[:, 1, 1], truth.cdf).pvalue > 0.01
    assert stats.kstest(cuts[:, 1, 0] - cuts[:, 0, 0], truth.cdf).pvalue > 0.01


def test_alpha_zero_width_does_not_depend_on_the_number_of_levels() -> None:
    """N_α in Eq. 2.29 = levels below 1: the expected α = 0 half-width is E[X | X > 0]·0.1·p_det."""
    truncated_mean = 1.0 + stats.norm.pdf(1.0) / stats.norm.cdf(1.0)  # E[X | X > 0], X ~ N(1, 1)
    for alphas in [(0.0, 1.0), (0.0, 0.5, 1.0), tuple(np.linspace(0, 1, 7))]:
        cuts = generate_samples(FRVSpec("p", 1.0, alphas=alphas), 8000, seed=5)
        half = cuts[:, -1, 0] - cuts[:, 0, 0]
        assert abs(half.mean() - 0.1 * truncated_mean) < 4 * half.std() / math.sqrt(half.size)


def test_spec_rejects_bad_input() -> None:
    with pytest.raises(ParameterError, match="end with 1"):
        FRVSpec("p", 1.0, alphas=(0.0, 0.5))
    with pytest.raises(ParameterError, match="non-zero"):
        FRVSpec("p", 0.0)
    with pytest.raises(ParameterError, match="'normal' or 'beta'"):
        FRVSpec("p", 1.0, distribution="uniform")
    with pytest.raises(ParameterError, match="hardly terminate"):
        FRVSpec("p", 1.0, mean=-5.0, std=1.0)
    spec = FRVSpec("p", 2.0, alphas=[0, 0.5, 1], distribution="beta")
    assert FRVSpec.from_dict(spec.to_dict()) == spec


# ============================================================================ grouping
def test_grouping_moves_every_value_by_at_most_half_a_spacing() -> None:
    cuts = generate_samples(FRVSpec("E", 60e9, alphas=ALPHAS5), 4000, seed=6)
    grid = Grid.from_samples(cuts, 100)
    assert grid.n_bins == 99 and grid.points()[0] == cuts.min()
    assert grid.points()[-1] == pytest.approx(cuts.max(), rel=1e-14)
    bins = group(cuts, grid)
    assert bins.min() == 0 and bins.max() == 98  # the largest value belongs to the last bin
    assert np.all(np.abs(grid.centres(bins) - cuts) <= grid.spacing / 2 * (1 + 1e-9))
    grouped = grid.centres(bins)  # grouping keeps the fuzzy numbers convex
    assert np.all(np.diff(grouped[:, :, 0], axis=1) >= 0) and np.all(np.diff(grouped[:, :, 1], axis=1) <= 0)


def test_possible_intervals_eq_2_32() -> None:
    for n_disc in (2, 30, 100, 121):
        grid = Grid.from_range(0.0, 1.0, n_disc)
        n = grid.n_bins
        assert grid.possible_intervals == n * (n + 1) // 2 == math.comb(n_disc, 2)
        left, right = np.triu_indices(n)  # every (l <= r) pair, brute force
        assert left.size == grid.possible_intervals
    assert Grid.from_range(0.0, 1.0, 30).possible_intervals == 435  # the thesis' Fig. 2.9 example


def test_occurring_intervals_are_the_unique_pairs_below_alpha_one() -> None:
    cuts = generate_samples(FRVSpec("p", 1.0, alphas=ALPHAS5), 500, seed=7)
    bins = group(cuts, Grid.from_samples(cuts, 15))
    brute = sorted({(int(l), int(r)) for s in bins for l, r in s[:-1]})
    np.testing.assert_array_equal(occurring_intervals(bins), np.array(brute))


def test_grid_extension_keeps_existing_bins() -> None:
    grid = Grid.from_range(1.0, 2.0, 11)
    with pytest.raises(ParameterError, match="outside the grid"):
        group(np.array([0.93, 1.5]), grid)
    wider = grid.extended(np.array([0.93, 2.26]))
    assert (wider.origin, wider.spacing) == (grid.origin, grid.spacing)
    assert (wider.first_bin, wider.last_bin) == (-1, 12) and wider.offset == 1 and wider.n_points == 15
    old = np.arange(grid.first_bin, grid.last_bin + 1)
    np.testing.assert_array_equal(wider.centres(old), grid.centres(old))
    np.testing.assert_array_equal(group(np.array([0.93, 1.55, 2.26]), wider), [-1, 5, 12])
    assert grid.extended(np.array([1.0, 2.0])) is grid  # the top point is inside


# ============================================================================ hulls
def test_range_extrema_match_brute_force() -> None:
    rng = np.random.default_rng(8)
    values = rng.normal(size=(37, 9))
    first = rng.integers(0, 37, 300)
    last = np.minimum(first + rng.integers(0, 37, 300), 36)
    low, high = frv.range_extrema(values, values, first, last, time_block=4)
    for q in range(300):
        np.testing.assert_array_equal(low[q], values[first[q] : last[q] + 1].min(axis=0))
        np.testing.assert_array_equal(high[q], values[first[q] : last[q] + 1].max(axis=0))


def _library_and_intervals(model: FunctionModel, n_disc: int, seed: int = 9):
    spec = FRVSpec("p", 1.0, alphas=ALPHAS5)
    cuts = generate_samples(spec, 2000, seed)
    grid = Grid.from_samples(cuts, n_disc)
    pairs = occurring_intervals(group(cuts, grid))
    centres = grid.centres()
    values = np.array([model.evaluate(np.array([c])).values for c in centres])
    slopes = np.array([model.jacobian(np.array([c]))[:, 0] for c in centres]) if model.jacobian else None
    return grid, pairs, centres, values, slopes


def test_interval_hulls_of_a_non_monotone_model_match_dense_evaluation() -> None:
    model = sine_model()
    grid, pairs, centres, values, slopes = _library_and_intervals(model, n_disc=60)
    rows = pairs - grid.first_bin
    lower, upper = interval_hulls(values, rows[:, 0], rows[:, 1], slopes=slopes, spacing=grid.spacing)
    plain_lower, plain_upper = interval_hulls(values, rows[:, 0], rows[:, 1])
    worst_plain = 0.0
    for q, (l, r) in enumerate(rows):
        true_lower, true_upper = dense_hull(model, centres[l], centres[r])
        # Tolerance: the cubic Hermite interpolant is within h⁴/384·max|∂⁴f/∂p⁴| = h⁴t⁴/384 of f,
        # and so are its extrema; the 2001-point "truth" misses an interior extremum by at most
        # δ²/8·max|∂²f/∂p²| = δ²t²/8 (δ its step).
        delta = (centres[r] - centres[l]) / 2000
        tol = grid.spacing**4 * TIMES**4 / 384 + delta**2 * TIMES**2 / 8 + 1e-12
        assert np.all(np.abs(upper[q] - true_upper) <= tol)
        assert np.all(np.abs(lower[q] - true_lower) <= tol)
        # the refinement only adds interior extrema to the library's own extremes
        assert np.all(upper[q] >= plain_upper[q]) and np.all(lower[q] <= plain_lower[q])
        worst_plain = max(worst_plain, float(np.max(true_upper - plain_upper[q])))
    assert tol.max() < 1e-5 and worst_plain > 100 * tol.max()  # interior extrema do occur


@pytest.mark.parametrize("jacobian", [False, True])
def test_interval_hulls_of_a_monotone_model_are_exact(jacobian: bool) -> None:
    model = monotone_model(jacobian)
    grid, pairs, centres, values, slopes = _library_and_intervals(model, n_disc=25)
    rows = pairs - grid.first_bin
    lower, upper = interval_hulls(values, rows[:, 0], rows[:, 1], slopes=slopes, spacing=grid.spacing)
    for q, (l, r) in enumerate(rows):
        true_lower, true_upper = dense_hull(model, centres[l], centres[r])
        np.testing.assert_array_equal(lower[q], true_lower)
        np.testing.assert_array_equal(upper[q], true_upper)


# ============================================================================ study
def hull_size(counts) -> int:
    return counts["samples"] * 5 * 2 * TIMES.size


def test_study_hulls_counts_and_truth(tmp_path) -> None:
    model, spec = sine_model(), FRVSpec("p", 1.0, alphas=ALPHAS5)
    counter = CountingEvaluator(model)
    study = FRVStudy.create(model, spec, 1500, StudyOptions(n_disc=25, seed=1, chunk=256),
                            store=tmp_path / "s.zarr", evaluator=counter)
    counts = study.counts
    bins = study.samples()["bin"].to_numpy()
    np.testing.assert_array_equal(bins, group(generate_samples(spec, 1500, 1), study.grid))
    pairs = occurring_intervals(bins)
    proper = int(np.count_nonzero(pairs[:, 1] > pairs[:, 0]))
    assert counter.calls == 1 and counter.rows == counts["forward_simulations"] == 24  # every bin centre once
    assert counts["samples"] == 1500 and counts["occurring_intervals"] == len(pairs) < counts["possible_intervals"] == 300
    assert counts["interval_optimisations"] == 2 * proper * TIMES.size
    assert counts["worst_case_optimisations"] == 2 * TIMES.size * 300  # Eq. 2.33
    # range hulls of nested intervals nest; only the α = 1 value at a sample's raw peak (which
    # may lie up to half a bin outside its grouped α-cuts) can widen a lower level
    assert study.refine is True and 0 <= counts["repaired_values"] < hull_size(counts)
    hull = study.hulls()["hull"]
    assert hull.dims == ("sample", "alpha", "bound", "time") and hull.shape == (1500, 5, 2, TIMES.size)
    centres = study.grid.centres(bins)
    peaks = generate_samples(spec, 1500, 1)[:, -1, 0]
    h = study.grid.spacing
    hermite = h**4 * TIMES**4 / 384 + 1e-12
    # the α = 1 cell: the library entries (bin centres) on either side of the raw peak
    k = np.clip(np.floor((peaks - study.grid.origin) / h - 0.5).astype(int), 0, study.grid.n_bins - 2)
    for i in (0, 77, 1499):  # each sample as if the GFA were applied to it alone (dense truth)
        sample = hull[i].to_numpy()
        cell = model.function(study.grid.centres(np.array([k[i], k[i] + 1]))[:, None])
        # α = 1: the model at the raw peak (Hermite interpolation of the library), kept within
        # the cell's two library values (clipping moves it no farther from the clipped model)
        truth = np.clip(model.evaluate(peaks[i : i + 1]).values, cell.min(axis=0), cell.max(axis=0))
        assert np.all(np.abs(sample[-1, 0] - truth) <= hermite)
        for a in range(4):
            lo, hi = centres[i, a, 0], centres[i, a, 1]
            true_lower, true_upper = dense_hull(model, lo, hi)
            wide_lower, wide_upper = dense_hull(model, min(lo, study.grid.centres(k[i])),
                                                max(hi, study.grid.centres(k[i] + 1)))  # fmt: skip
            tol = hermite + (hi - lo) ** 2 / 2000**2 * TIMES**2 / 8
            # the hull is the extreme library value: it misses an interior extremum of the
            # model by at most (h/2)²/2·max|∂²f/∂p²| = h²t²/8, and never leaves the model's range
            miss = h**2 * TIMES**2 / 8 + tol
            assert np.all(sample[a, 0] <= true_lower + miss) and np.all(sample[a, 1] >= true_upper - miss)
            assert np.all(sample[a, 0] >= wide_lower - tol) and np.all(sample[a, 1] <= wide_upper + tol)


@pytest.mark.parametrize("seed, new_intervals", [(5, 0), (0, 1)])
def test_add_samples_reuses_library_and_intervals(tmp_path, seed: int, new_intervals: int) -> None:
    """Seeds picked so the 300 added samples stay inside the first 2000's grid; with seed 5
    they bring no new interval either, with seed 0 exactly one."""
    model, spec = sine_model(), FRVSpec("p", 1.0)
    counter = CountingEvaluator(model)
    study = FRVStudy.create(model, spec, 2000, StudyOptions(n_disc=12, seed=seed, chunk=300),
                            store=tmp_path / "s.zarr", evaluator=counter)
    before = study.hulls()["hull"].to_numpy()
    counts = dict(study.counts)
    study.add_samples(300)
    assert counter.calls == 1 and study.counts["last_forward_simulations"] == 0  # no new forward simulation
    assert study.counts["forward_simulations"] == counts["forward_simulations"]
    assert study.counts["last_new_intervals"] == new_intervals
    assert study.counts["occurring_intervals"] == counts["occurring_intervals"] + new_intervals
    assert study.counts["interval_optimisations"] == counts["interval_optimisations"] + 2 * TIMES.size * new_intervals
    hull = study.hulls()["hull"]
    assert hull.shape[0] == 2300
    np.testing.assert_array_equal(hull[:2000].to_numpy(), before)  # bit-identical
    # the new samples are the ones a single run of 2300 would draw, grouped on the same grid
    np.testing.assert_array_equal(study.samples()["cut"].to_numpy(), generate_samples(spec, 2300, seed))


def test_add_samples_extends_the_grid_and_simulates_only_new_bins(tmp_path) -> None:
    model, spec = monotone_model(), FRVSpec("p", 1.0, alphas=ALPHAS5)
    counter = CountingEvaluator(model)
    study = FRVStudy.create(model, spec, 20, StudyOptions(n_disc=8, seed=3, chunk=512),
                            store=tmp_path / "s.zarr", evaluator=counter)
    grid0, sims0 = study.grid, study.counts["forward_simulations"]
    assert sims0 == 7 and study.refine is False
    study.add_samples(3000)
    grid = study.grid
    assert (grid.origin, grid.spacing) == (grid0.origin, grid0.spacing) and grid.n_bins > grid0.n_bins
    assert study.counts["forward_simulations"] == counter.rows == grid.n_bins  # old bins not simulated again
    assert study.counts["possible_intervals"] == grid.possible_intervals
    # truth: the model at every bin centre of the extended grid, brute-force extremes
    centres = grid.centres()
    library = np.array([model.evaluate(np.array([c])).values for c in centres])
    bins = study.samples()["bin"].to_numpy() - grid.first_bin
    hull = study.hulls()["hull"].to_numpy()
    for i in range(0, 3020, 97):
        for a in range(5):
            window = library[bins[i, a, 0] : bins[i, a, 1] + 1]
            np.testing.assert_array_equal(hull[i, a, 0], window.min(axis=0))
            np.testing.assert_array_equal(hull[i, a, 1], window.max(axis=0))


def test_open_from_disk_gives_identical_results(tmp_path) -> None:
    model, spec = sine_model(), FRVSpec("p", 1.0, alphas=ALPHAS5)
    direct = FRVStudy.create(model, spec, 700, StudyOptions(n_disc=20, seed=4, chunk=128), store=tmp_path / "a.zarr")
    direct.add_samples(500)
    written = FRVStudy.create(model, spec, 700, StudyOptions(n_disc=20, seed=4, chunk=128), store=tmp_path / "b.zarr")
    reopened = FRVStudy.open(tmp_path / "b.zarr", model)
    assert reopened.spec == spec and reopened.grid == written.grid and reopened.n_samples == 700
    assert reopened.counts == written.counts
    np.testing.assert_array_equal(reopened.hulls()["hull"].to_numpy(), direct.hulls()["hull"][:700].to_numpy())
    reopened.add_samples(500)
    np.testing.assert_array_equal(reopened.hulls()["hull"].to_numpy(), direct.hulls()["hull"].to_numpy())
    for key in ("forward_simulations", "interval_optimisations", "occurring_intervals", "samples"):
        assert reopened.counts[key] == direct.counts[key]
    again = FRVStudy.open(tmp_path / "b.zarr", model)
    np.testing.assert_array_equal(again.library()["value"].to_numpy(), direct.library()["value"].to_numpy())
    with pytest.raises(FuzzyGaitError, match="already exists"):
        FRVStudy.create(model, spec, 10, store=tmp_path / "a.zarr")
    with pytest.raises(ParameterError, match="time nodes"):
        FRVStudy.open(tmp_path / "a.zarr", FunctionModel(lambda p: np.zeros(3), np.arange(3.0)))


def test_hulls_are_written_block_by_block_in_chunks(tmp_path, monkeypatch) -> None:
    writes: list[tuple[str, int]] = []
    original = frv.study._append

    def spy(path, name, ds, dim, encoding=None):
        writes.append((name, ds.sizes[dim]))
        original(path, name, ds, dim, encoding)

    monkeypatch.setattr(frv.study, "_append", spy)
    times = np.linspace(0.0, 1.0, 400)  # 1000 samples x 5 α x 2 x 400 nodes = 32 MB; blocks of 64
    model = FunctionModel(lambda p: np.cos(p[0] * times), times)
    study = FRVStudy.create(model, FRVSpec("p", 1.0, alphas=ALPHAS5), 1000,
                            StudyOptions(n_disc=30, chunk=64), store=tmp_path / "s.zarr")
    study.add_samples(100)  # starts mid-chunk: the first block only fills the chunk
    output = [n for name, n in writes if name == "samples"]
    assert max(output) == 64 and sum(output) == 1100 and len(output) == 19
    assert output[15:] == [40, 24, 64, 12]  # 1000 = 15·64 + 40; then 1000…1023, 1024…1087, 1088…1099
    hull = study.hulls()["hull"]
    assert hull.encoding["chunks"] == (64, 5, 2, 400)


def test_interrupted_add_is_rolled_back(tmp_path, monkeypatch) -> None:
    model, spec = sine_model(), FRVSpec("p", 1.0)
    study = FRVStudy.create(model, spec, 300, StudyOptions(n_disc=15, seed=5, chunk=64), store=tmp_path / "s.zarr")
    reference = FRVStudy.create(model, spec, 300, StudyOptions(n_disc=15, seed=5, chunk=64), store=tmp_path / "r.zarr")
    reference.add_samples(200)
    calls = {"n": 0}
    original = FRVStudy._assemble

    def failing(self, bins, peaks):
        calls["n"] += 1
        if calls["n"] == 3:
            raise RuntimeError("disk full")
        return original(self, bins, peaks)

    monkeypatch.setattr(FRVStudy, "_assemble", failing)
    with pytest.raises(RuntimeError):
        study.add_samples(200)
    monkeypatch.setattr(FRVStudy, "_assemble", original)
    reopened = FRVStudy.open(tmp_path / "s.zarr", model)
    assert reopened.n_samples == 300 and reopened.hulls().sizes["sample"] == 300
    assert reopened.samples().sizes["sample"] == 300
    reopened.add_samples(200)
    np.testing.assert_array_equal(reopened.hulls()["hull"].to_numpy(), reference.hulls()["hull"].to_numpy())


def test_time_stride_and_study_errors(tmp_path) -> None:
    model, spec = sine_model(), FRVSpec("p", 1.0)
    study = FRVStudy.create(model, spec, 200, StudyOptions(n_disc=10, time_stride=7), store=tmp_path / "s.zarr")
    nodes = optimisation_nodes(TIMES.size, 7)
    np.testing.assert_array_equal(study.hulls()["time"].to_numpy(), TIMES[nodes])
    assert study.counts["interval_optimisations"] == 2 * study.counts["occurring_proper_intervals"] * nodes.size
    with pytest.raises(ParameterError, match="distinct names"):
        FRVStudy.create(model, [spec, FRVSpec("p", 2.0)], 10, store=tmp_path / "t.zarr")
    with pytest.raises(ParameterError, match="returned none"):
        FRVStudy.create(sine_model(jacobian=False), spec, 10, StudyOptions(refine=True), store=tmp_path / "u.zarr")


# ============================================================================ fitting
def test_fits_equal_the_statistics_of_the_fully_loaded_hulls(tmp_path) -> None:
    model, spec = sine_model(), FRVSpec("p", 1.0, alphas=ALPHAS5)
    study = FRVStudy.create(model, spec, 900, StudyOptions(n_disc=20, seed=6, chunk=128), store=tmp_path / "s.zarr")
    hull = study.hulls()["hull"].to_numpy()
    fit = fit_distributions(study)
    np.testing.assert_allclose(fit["mean"].to_numpy(), hull.mean(axis=0), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(fit["std"].to_numpy(), hull.std(axis=0), rtol=1e-9, atol=1e-13)
    increments = np.empty_like(hull)  # the output's l_α r_α-increments, computed here directly
    increments[:, :-1, 0] = hull[:, 1:, 0] - hull[:, :-1, 0]
    increments[:, :-1, 1] = hull[:, :-1, 1] - hull[:, 1:, 1]
    increments[:, -1] = hull[:, -1, 0][:, None]
    fit = fit_distributions(tmp_path / "s.zarr", "normal", "increments")
    np.testing.assert_allclose(fit["mean"].to_numpy(), increments.mean(axis=0), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(fit["std"].to_numpy(), increments.std(axis=0), rtol=1e-9, atol=1e-13)
    beta = fit_distributions(study, "beta", exact_nodes=[30])
    low, high = hull.min(axis=0), hull.max(axis=0)
    x = (hull[:, 0, 1, 30] - low[0, 1, 30]) / (high[0, 1, 30] - low[0, 1, 30])
    m, v = x.mean(), x.var()
    assert beta["a"].values[0, 1, 30] == pytest.approx(m * (m * (1 - m) / v - 1), rel=1e-9)
    assert beta["b"].values[0, 1, 30] == pytest.approx((1 - m) * (m * (1 - m) / v - 1), rel=1e-9)
    assert np.isnan(beta["a"].values[0, 0, 0])  # t = 0: the output is constant
    a_mle = beta["a_mle"].sel(exact_time=TIMES[30]).values[0, 1]
    x_sv = (x * (x.size - 1) + 0.5) / x.size
    assert a_mle == pytest.approx(stats.beta.fit(x_sv, floc=0, fscale=1)[0], rel=1e-6)


# ============================================================================ figures
def test_figures(tmp_path) -> None:
    from fuzzygait.viz import frv as figures

    spec = FRVSpec("E", 59.958e9, alphas=ALPHAS5)
    study = FRVStudy.create(sine_model(), FRVSpec("p", 1.0, alphas=ALPHAS5), 400, StudyOptions(n_disc=20),
                            store=tmp_path / "s.zarr")
    made = [
        figures.input_samples_figure(spec, n_samples=2000),
        figures.grouping_figure(spec, n_samples=2000, n_disc=30),
        figures.output_distribution_figure(study, 20),
        figures.output_distribution_figure(study, -1, data="increments", kind="beta"),
        figures.temporal_evolution_figure(study, max_nodes=20),
        figures.fuzzy_random_output_figure(study, 20),
    ]
    assert [len(f.axes) for f in made] == [6, 2, 5, 5, 5, 2]
    made[0].savefig(tmp_path / "fig.png", dpi=40)
    assert (tmp_path / "fig.png").stat().st_size > 0
    with pytest.raises(ParameterError, match="node"):
        figures.output_distribution_figure(study, 99)
