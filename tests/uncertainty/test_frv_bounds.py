"""FRV hulls never leave the range the model produced (issue 37.3): every stored hull
value — α < 1 interval and box hulls, α = 1 at a sample's own peak, and what the nesting
repair moves between levels — lies within the smallest and largest library value (the
forward simulations) it is made from, and within the bounds the model declares for its
output (an energy ≥ 0), for an :class:`FRVStudy` of one FRV parameter and of two, on
an "energy" whose cubic Hermite interpolant between the grid
points dips below zero (what the stance study's maximum element energy did)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import zarr

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import (
    FRVSpec,
    FRVStudy,
    MultiStudyOptions,
    StudyOptions,
    hermite_values,
    interval_hulls,
)
from fuzzygait.uncertainty.frv.peaks import RESOLUTION, cell_keys
from fuzzygait.uncertainty.protocol import Output

TIMES = np.linspace(0.0, 2.0, 11)
ALPHAS = (0.0, 0.5, 1.0)
OMEGA = 15.0  # the phase turns by ~2.6 rad per spacing of an 8-point grid at t = 2: the grid cannot follow it
ENERGY = Output("energy", "J", bounds=(0.0, math.inf))


def energy_model(offset: float = 0.0, weights: tuple[float, ...] = (1.0,)) -> FunctionModel:
    """f(p, t) = sin²(ω·(w·p)·t) + offset, with its gradient: ≥ 0 (declared) for offset 0;
    a negative offset makes the simulations themselves leave the declared bounds slightly."""
    w = np.asarray(weights)

    def function(p: np.ndarray) -> np.ndarray:
        return np.sin(OMEGA * (p[..., : w.size] @ w)[..., None] * TIMES) ** 2 + offset

    def jacobian(p: np.ndarray) -> np.ndarray:
        return (OMEGA * TIMES * np.sin(2 * OMEGA * (p[: w.size] @ w) * TIMES))[:, None] * w

    return FunctionModel(function, TIMES, jacobian, output=ENERGY)


def assert_within(hull: np.ndarray, low: np.ndarray, high: np.ndarray) -> None:
    """``hull (n, n_alpha, 2, n_time)`` within ``low``/``high (n, n_alpha, 1, n_time)`` (the
    simulated range moved into the declared bounds) and ≥ 0."""
    assert np.all(hull >= low - 1e-12) and np.all(hull <= high + 1e-12)
    assert np.all(hull >= 0.0)


def nested(bins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per α-level the bins of that level's α-cut and every higher one's (``(..., n_alpha)``)."""
    left = np.minimum.accumulate(bins[..., ::-1, 0], axis=-1)[..., ::-1]
    right = np.maximum.accumulate(bins[..., ::-1, 1], axis=-1)[..., ::-1]
    return left, right


def test_the_energy_targets_declare_their_lower_bound() -> None:
    from types import SimpleNamespace

    from fuzzygait.mechanics.targets import TARGETS, LegTargetModel

    def output(target: str) -> Output:
        return LegTargetModel.output.fget(SimpleNamespace(target=target))  # type: ignore[attr-defined]

    assert output("max_element_energy") == Output("max_element_energy", "J", bounds=(0.0, math.inf))
    assert output("total_deformation_energy").bounds == (0.0, math.inf)
    assert all(output(t).bounds == (-math.inf, math.inf) for t in TARGETS if t.startswith("last_node_"))
    assert Output("x").bounds == (-math.inf, math.inf)  # undeclared: unbounded, as before
    with pytest.raises(ParameterError, match="lower <= upper"):
        Output("x", bounds=(1.0, 0.0))
    with pytest.raises(ParameterError, match="two numbers"):
        Output("x", bounds=(0.0,))  # type: ignore[arg-type]


# ============================================================================ one parameter
def one_parameter_ranges(study: FRVStudy) -> tuple[np.ndarray, np.ndarray]:
    """The smallest and largest library value each stored hull value is made from — over the
    bins of its α-cut and the higher ones' (nesting repair), and the α = 1 cell's two —
    moved into the declared bounds (≥ 0)."""
    lib = study.library()
    values, first = lib["value"].to_numpy(), int(lib["bin"][0])
    samples = study.samples()
    bins, peaks = samples["bin"].to_numpy(), samples["cut"].to_numpy()[:, -1, 0]
    grid = study.grid
    cell = np.clip(np.floor((peaks - grid.origin) / grid.spacing - 0.5).astype(int), grid.first_bin,
                   grid.last_bin - 1)  # fmt: skip
    left, right = nested(bins)
    left, right = np.minimum(left, cell[:, None]) - first, np.maximum(right, cell[:, None] + 1) - first
    spans = [[values[a : b + 1] for a, b in zip(lo, hi, strict=True)] for lo, hi in zip(left, right, strict=True)]
    low = np.stack([[span.min(axis=0) for span in row] for row in spans])
    high = np.stack([[span.max(axis=0) for span in row] for row in spans])
    return np.maximum(low, 0.0)[:, :, None], np.maximum(high, 0.0)[:, :, None]


@pytest.mark.parametrize("offset", [0.0, -1e-3])
def test_one_parameter_hulls_stay_within_the_simulations_and_the_declared_bounds(tmp_path, offset: float) -> None:
    model, spec = energy_model(offset), FRVSpec("p", 1.0, alphas=ALPHAS)
    study = FRVStudy.create(model, spec, 300, StudyOptions(n_disc=8, seed=2, chunk=128), store=tmp_path / "s.zarr")
    assert study.refine is True
    lib = study.library()
    values, slopes = lib["value"].to_numpy(), lib["slope"].to_numpy()
    # the cubic Hermite interpolant between the library entries dips below zero here
    table = study.intervals()
    left, right = table["left"].to_numpy() - int(lib["bin"][0]), table["right"].to_numpy() - int(lib["bin"][0])
    hermite_lower, _ = interval_hulls(values, left, right, slopes=slopes, spacing=study.grid.spacing)
    assert hermite_lower.min() < -0.05
    # the interval dictionary holds the extreme library values, clipped to the declared bound
    np.testing.assert_array_equal(table["lower"].to_numpy(), np.maximum(interval_hulls(values, left, right)[0], 0))
    np.testing.assert_array_equal(table["upper"].to_numpy(), np.maximum(interval_hulls(values, left, right)[1], 0))
    assert_within(study.hulls()["hull"].to_numpy(), *one_parameter_ranges(study))
    # extended beyond the first grid (new bins, new intervals): still within
    grown = FRVStudy.open(tmp_path / "s.zarr", model).add_samples(700)
    assert grown.grid.n_points > study.grid.n_points
    assert_within(grown.hulls()["hull"].to_numpy(), *one_parameter_ranges(grown))
    if offset < 0:  # simulations below the declared bound: the hulls stop at it
        assert values.min() < 0 and np.any(grown.hulls()["hull"].to_numpy() == 0.0)


# ============================================================================ two parameters
def two_parameter_ranges(study: FRVStudy) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`one_parameter_ranges` for boxes: the library values at the grid points of
    each α-level's box (which holds the higher ones') and at the α = 1 lattice cell's
    corners."""
    lib = study.library()
    keys = lib["point"].to_numpy() * RESOLUTION + lib["offset"].to_numpy()
    row = {tuple(k): i for i, k in enumerate(keys.tolist())}
    values = lib["value"].to_numpy()
    samples = study.samples()
    bins, peaks = samples["bin"].to_numpy(), samples["cut"].to_numpy()[:, :, -1, 0]
    corners = cell_keys(study.grids, study.peak_refine, peaks)[0]
    n, n_params, n_alpha, _ = bins.shape
    low, high = np.empty((n, n_alpha, 1, TIMES.size)), np.empty((n, n_alpha, 1, TIMES.size))
    for i, a in itertools.product(range(n), range(n_alpha)):
        points = itertools.product(*(range(bins[i, d, a, 0], bins[i, d, a, 1] + 1) for d in range(n_params)))
        rows = [row[tuple(RESOLUTION * np.array(p))] for p in points] + [row[tuple(c)] for c in corners[i].tolist()]
        low[i, a, 0], high[i, a, 0] = values[rows].min(axis=0), values[rows].max(axis=0)
    return np.maximum(low, 0.0), np.maximum(high, 0.0)


def test_two_parameter_hulls_stay_within_the_simulations_and_the_declared_bounds(tmp_path) -> None:
    model = energy_model(weights=(1.0, 0.5))
    specs = [FRVSpec("p1", 1.0, alphas=ALPHAS), FRVSpec("p2", 1.0, alphas=ALPHAS)]
    study = FRVStudy.create(model, specs, 200,
                            MultiStudyOptions(n_disc=(7, 5), seed=3, chunk=128, peak_refine=(2, 1)),
                            store=tmp_path / "m.zarr")  # fmt: skip
    assert study.refine is True and study.peak_refine == [2, 1]
    hull = study.hulls()["hull"].to_numpy()
    assert_within(hull, *two_parameter_ranges(study))
    # α = 1 is the Hermite interpolant at the raw peak within its cell's corner values, which
    # unbounded would dip below zero
    corners, t = cell_keys(study.grids, study.peak_refine, study.samples()["cut"].to_numpy()[:, :, -1, 0])
    lib = study.library()
    row = {tuple(k): i for i, k in enumerate((lib["point"].to_numpy() * RESOLUTION + lib["offset"].to_numpy()).tolist())}
    rows = np.array([[row[tuple(c)] for c in cell] for cell in corners.tolist()])
    values, slopes = lib["value"].to_numpy()[rows], lib["slope"].to_numpy()[rows]
    spacings = np.array([g.spacing for g in study.grids]) / np.array(study.peak_refine)
    unbounded = hermite_values(values, slopes, spacings, t)
    assert unbounded.min() < -0.05
    np.testing.assert_array_equal(hull[:, -1, 0], np.clip(unbounded, values.min(axis=1), values.max(axis=1)))
    grown = FRVStudy.open(tmp_path / "m.zarr", model).add_samples(200)
    assert_within(grown.hulls()["hull"].to_numpy(), *two_parameter_ranges(grown))


# ============================================================================ older stores
@pytest.mark.parametrize("several", [False, True])
def test_a_store_made_before_recomputes_its_hulls_for_new_samples(tmp_path, several: bool) -> None:
    """A store without the ``hulls`` record held the Hermite extrema in its dictionary (here
    made unmistakable: −1 everywhere): extending it takes the library's extremes instead."""
    if several:
        model = energy_model(weights=(1.0, 0.5))
        specs = [FRVSpec("p1", 1.0, alphas=ALPHAS), FRVSpec("p2", 1.0, alphas=ALPHAS)]
        FRVStudy.create(model, specs, 100, MultiStudyOptions(n_disc=(6, 4), seed=1, peak_refine=1),
                        store=tmp_path / "o.zarr")
    else:
        model = energy_model()
        FRVStudy.create(model, FRVSpec("p", 1.0, alphas=ALPHAS), 100, StudyOptions(n_disc=8, seed=1),
                        store=tmp_path / "o.zarr")
    root = zarr.open_group(tmp_path / "o.zarr", mode="r+", zarr_format=2)
    attrs = dict(root.attrs)
    assert attrs.pop("hulls") == "simulated"
    root.attrs.clear()
    root.update_attributes(attrs)
    root["intervals"]["lower"][:] = -1.0
    grown = FRVStudy.open(tmp_path / "o.zarr", model).add_samples(300)
    assert grown.several is several
    ranges = two_parameter_ranges(grown) if several else one_parameter_ranges(grown)
    assert_within(grown.hulls()["hull"].to_numpy()[100:], *(r[100:] for r in ranges))
