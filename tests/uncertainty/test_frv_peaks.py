"""The α = 1 lattice of a refined FRV study with several parameters
(:mod:`fuzzygait.uncertainty.frv.peaks`): its geometry against the grouping grid, and a
study on a model whose output turns faster than the grouping grid can follow, whose
α = 1 outputs are checked against the model at every sample's own peak (closed form)."""

from __future__ import annotations

import numpy as np
import pytest
from test_frv_multi import TIMES, specs  # the two-parameter study of the unrefined tests

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import FRVStudy, MultiStudyOptions, StudyOptions, hermite_cells
from fuzzygait.uncertainty.frv.grouping import Grid
from fuzzygait.uncertainty.frv.peaks import RESOLUTION, cell_keys, interpolation_error, key_centres, lattice

GRIDS = (Grid.from_range(0.0, 3.0, 7), Grid.from_range(-1.0, 1.0, 5))  # spacings 0.5 and 0.5


def test_the_lattice_of_factor_one_is_the_grid() -> None:
    rng = np.random.default_rng(0)
    x = rng.uniform([0.0, -1.0], [3.0, 1.0], size=(50, 2))
    keys, t = cell_keys(GRIDS, (1, 1), x)
    origins, spacings = np.array([g.origin for g in GRIDS]), np.array([g.spacing for g in GRIDS])
    first, last = np.array([g.first_bin for g in GRIDS]), np.array([g.last_bin for g in GRIDS])
    k, t_grid = hermite_cells(origins, spacings, first, last, x)
    np.testing.assert_array_equal(keys[:, 0], RESOLUTION * k)
    np.testing.assert_array_equal(keys[:, -1], RESOLUTION * (k + 1))
    np.testing.assert_array_equal(t, t_grid)
    np.testing.assert_allclose(key_centres(GRIDS, keys[:, 0]), origins + (k + 0.5) * spacings, rtol=0, atol=1e-15)


def test_a_finer_lattice_halves_the_spacing_through_the_grid_centres() -> None:
    # grid 0: centres 0.25, 0.75, ...; a point a quarter of a bin above centre 1 (0.75)
    x = np.array([[0.875, 0.0]])
    keys, t = cell_keys(GRIDS, (2, 1), x)
    assert keys[0, 0].tolist() == [RESOLUTION, RESOLUTION]  # lower corner: centre of bin 1, bin 1
    assert keys[0, 2].tolist() == [RESOLUTION + RESOLUTION // 2, RESOLUTION]  # half a bin up along p1
    np.testing.assert_allclose(t[0], [0.5, 0.5])
    np.testing.assert_allclose(key_centres(GRIDS, keys[0, 2]), [[1.0, -0.25]])


def test_interpolation_error_is_the_median_miss_over_the_spread() -> None:
    library = np.array([[0.0, 0.0, 0.0], [0.0, 4.0, 10.0]])  # spreads 0 (left out), 4, 10
    exact = np.zeros((3, 3))
    predicted = np.array([[5.0, 0.1, 1.0], [5.0, 0.2, 0.1], [5.0, 0.3, 0.2]])
    assert interpolation_error(predicted, exact, library) == pytest.approx(max(0.2 / 4, 0.2 / 10))
    assert interpolation_error(predicted, exact, np.zeros((2, 3))) == 0.0


OMEGA = 8.0  # rad per unit of p1 at t = 1: 3.2 rad per grouping bin (0.2) at t = 2
SLOPE = 0.1  # of p2


def turning_model() -> FunctionModel:
    """f(p, t) = sin(ω·p1·t) + 0.1·p2·t: the phase in p1 turns faster than 6 grid points
    can follow at late t; linear in p2 (the grid's Hermite interpolant is exact there)."""
    return FunctionModel(lambda p: np.sin(OMEGA * p[..., :1] * TIMES) + SLOPE * p[..., 1:2] * TIMES, TIMES,
                         jacobian=lambda p: np.stack([OMEGA * TIMES * np.cos(OMEGA * p[0] * TIMES), SLOPE * TIMES],
                                                     axis=1))  # fmt: skip


def alpha_one_error(study: FRVStudy, model: FunctionModel) -> float:
    """The α = 1 outputs of every sample against the model at its own peak (closed form),
    as :func:`interpolation_error` measures it."""
    peaks = study.samples()["cut"].to_numpy()[:, :, -1, 0]
    alpha_one = study.hulls()["hull"].to_numpy()[:, -1, 0]
    return interpolation_error(alpha_one, model.function(peaks), study.library()["value"].to_numpy())


def test_the_alpha_one_lattice_is_refined_until_the_peaks_are_met(tmp_path) -> None:
    model = turning_model()
    auto = FRVStudy.create(model, specs(), 400, StudyOptions(n_disc=6, seed=5, chunk=128),
                           store=tmp_path / "a.zarr")
    grid_only = FRVStudy.create(model, specs(), 400,
                                MultiStudyOptions(n_disc=6, seed=5, chunk=128, peak_refine=1),
                                store=tmp_path / "g.zarr")  # fmt: skip
    assert grid_only.peak_refine == [1, 1]
    assert auto.peak_refine == [2, 1]  # measured: the grid misses by 3.7 %, half its spacing by 0.3 %
    checks = auto.counts["peak_checks"]
    assert [c["factor"] for c in checks if c["parameter"] == "p1"][-1] == auto.peak_refine[0]
    assert checks[0]["error"] > auto.peak_tolerance >= [c for c in checks if c["parameter"] == "p1"][-1]["error"]
    # the grid alone misses the model at the raw peaks; the refined lattice meets it
    assert alpha_one_error(grid_only, model) > auto.peak_tolerance
    assert alpha_one_error(auto, model) <= auto.peak_tolerance / 4
    # the boxes and their hulls are the grouping grid's either way (the samples' α < 1
    # hulls then widen to hold their α = 1 value, the nesting repair)
    for bound in ("lower", "upper"):
        np.testing.assert_array_equal(auto.boxes()[bound].to_numpy(), grid_only.boxes()[bound].to_numpy())
    assert auto.counts["occurring_intervals"] == grid_only.counts["occurring_intervals"]
    # the chosen factors given explicitly: the same α = 1 outputs; reopened and extended:
    # a one-shot run with those factors (to rounding: 11 of 32,400 values differ by an ulp)
    fixed = FRVStudy.create(model, specs(), 400,
                            MultiStudyOptions(n_disc=6, seed=5, chunk=128, peak_refine=auto.peak_refine),
                            store=tmp_path / "f.zarr")  # fmt: skip
    np.testing.assert_array_equal(fixed.hulls()["hull"].to_numpy(), auto.hulls()["hull"].to_numpy())
    grown = FRVStudy.open(tmp_path / "f.zarr", model).add_samples(200)
    assert grown.peak_refine == auto.peak_refine
    one_shot = FRVStudy.create(model, specs(), 600,
                               MultiStudyOptions(seed=5, chunk=128, grids=grown.grids,
                                                 peak_refine=auto.peak_refine),
                               store=tmp_path / "o.zarr")  # fmt: skip
    # ... except a first-batch sample whose peak lies beyond the first grids' outermost
    # lattice points: its α = 1 is extrapolated from the end cell and kept within that cell's
    # values, where the one-shot run's wider grid interpolates between simulations around it
    peaks = grown.samples()["cut"].to_numpy()[:400, :, -1, 0]
    t = hermite_cells(*lattice(fixed.grids, auto.peak_refine), peaks)[1]
    beyond = np.flatnonzero(np.any((t < 0) | (t > 1), axis=1))
    assert 0 < beyond.size <= 2
    keep = np.setdiff1d(np.arange(600), beyond)
    np.testing.assert_allclose(grown.hulls()["hull"].to_numpy()[keep], one_shot.hulls()["hull"].to_numpy()[keep],
                               rtol=1e-14, atol=1e-15)  # fmt: skip
    assert grown.counts["forward_simulations"] == one_shot.counts["forward_simulations"]


@pytest.mark.parametrize("factors, said", [(3, "each of 1, 2, 4, 8"), ((1, 2, 2), "one per parameter (2)"),
                                           ((16, 1), "each of 1, 2, 4, 8")])  # fmt: skip
def test_bad_lattice_factors_are_refused_in_one_line(tmp_path, factors, said) -> None:
    with pytest.raises(ParameterError, match=r"peak_refine: .*" + said.replace("(", r"\(").replace(")", r"\)")):
        FRVStudy.create(turning_model(), specs(), 20, MultiStudyOptions(n_disc=4, peak_refine=factors),
                        store=tmp_path / "b.zarr")
    with pytest.raises(ParameterError, match="peak_tolerance must lie between 0 and 1"):
        FRVStudy.create(turning_model(), specs(), 20, MultiStudyOptions(n_disc=4, peak_tolerance=1.5),
                        store=tmp_path / "c.zarr")
    assert not (tmp_path / "b.zarr").exists() and not (tmp_path / "c.zarr").exists()
