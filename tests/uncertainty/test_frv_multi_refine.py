"""Hermite refinement of the FRV-GFA with several parameters: the interpolant in ``D``
parameters (exact on the functions it is built for, third order otherwise, the
one-parameter interpolant for ``D = 1``), box hulls along the grid lines (against dense
sampling of the same interpolant, and the one-parameter refinement), and a refined study
whose α = 1 outputs are the model at each sample's own peak (closed form)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from test_frv_multi import TIMES, A, B, specs  # the two-parameter study of the unrefined tests

from fuzzygait.core.errors import ParameterError
from fuzzygait.uncertainty import FunctionModel
from fuzzygait.uncertainty.frv import (
    FRVSpec,
    FRVStudy,
    MultiStudyOptions,
    StudyOptions,
    hermite_box_extrema,
    hermite_cells,
    hermite_values,
    interval_hulls,
)
from fuzzygait.uncertainty.frv.hulls import _hermite_rows
from fuzzygait.uncertainty.frv.peaks import cell_keys, key_centres


def corners_of(f, grad, origins, spacings, first, last, x):
    """Values ``(n, 2^D, n_col)``, gradients ``(n, 2^D, n_col, D)`` at the cell corners of ``x`` and ``t``."""
    k, t = hermite_cells(origins, spacings, first, last, x)
    bits = np.array(list(itertools.product((0, 1), repeat=x.shape[1])))
    points = origins + (k[:, None, :] + bits[None] + 0.5) * spacings  # corner parameter values (n, 2^D, D)
    return f(points), grad(points), t


def cubic_with_coupling(p):
    """(n, m, 2) -> (n, m, 3): x³ − 2x² + y³ + 3xy + 1, scaled per column."""
    x, y = p[..., 0], p[..., 1]
    return (x**3 - 2 * x**2 + y**3 + 3 * x * y + 1)[..., None] * np.array([1.0, -0.5, 2.0])


def cubic_gradient(p):
    x, y = p[..., 0], p[..., 1]
    g = np.stack([3 * x**2 - 4 * x + 3 * y, 3 * y**2 + 3 * x], axis=-1)  # (n, m, 2)
    return g[..., None, :] * np.array([1.0, -0.5, 2.0])[:, None]


GRID = (np.array([-1.0, 0.5]), np.array([0.3, 0.2]), np.array([0, -2]), np.array([9, 12]))


def test_hermite_values_reproduce_cubics_with_bilinear_coupling_and_the_grid() -> None:
    rng = np.random.default_rng(0)
    origins, spacings, first, last = GRID
    low, high = origins + (first + 0.5) * spacings, origins + (last + 0.5) * spacings
    x = rng.uniform(low, high, size=(200, 2))
    values, slopes, t = corners_of(cubic_with_coupling, cubic_gradient, *GRID, x)
    assert np.all((t >= 0) & (t <= 1))
    got = hermite_values(values, slopes, spacings, t)
    np.testing.assert_allclose(got, cubic_with_coupling(x[:, None, :])[:, 0], rtol=1e-12, atol=1e-12)
    # at a grid point: its value, and (finite differences of the interpolant) its gradient
    centre = origins + (np.array([3, 4]) + 0.5) * spacings
    for d in range(2):
        step = np.zeros(2)
        step[d] = 1e-6
        pts = np.stack([centre + step, centre - step, centre])
        vals, grads, tt = corners_of(cubic_with_coupling, cubic_gradient, *GRID, pts)
        h = hermite_values(vals, grads, spacings, tt)
        np.testing.assert_allclose(h[2], cubic_with_coupling(centre[None, None])[0, 0], rtol=1e-14)
        np.testing.assert_allclose((h[0] - h[1]) / 2e-6, cubic_gradient(centre[None, None])[0, 0, :, d], rtol=1e-7)


def test_hermite_values_converge_at_third_order_and_are_the_one_parameter_interpolant() -> None:
    def f(p):
        return (np.sin(3 * p[..., 0]) * np.cos(2 * p[..., 1]))[..., None]

    def grad(p):
        x, y = p[..., 0], p[..., 1]
        return np.stack([3 * np.cos(3 * x) * np.cos(2 * y), -2 * np.sin(3 * x) * np.sin(2 * y)], axis=-1)[..., None, :]

    x = np.random.default_rng(1).uniform(0.2, 0.8, size=(500, 2))
    errors = []
    for h in (0.1, 0.05, 0.025):
        grid = (np.zeros(2), np.full(2, h), np.zeros(2, int), np.full(2, int(1 / h)))
        values, slopes, t = corners_of(f, grad, *grid, x)
        errors.append(np.abs(hermite_values(values, slopes, grid[1], t) - f(x[:, None, :])[:, 0]).max())
    assert errors[0] / errors[1] > 6 and errors[1] / errors[2] > 6, errors  # ≥ 2³ − margin
    # D = 1: the one-parameter study's interpolant
    rows = np.sin(np.arange(12.0))[:, None] * np.array([1.0, 2.0])
    slopes = np.cos(np.arange(12.0))[:, None] * np.array([1.0, 2.0])
    xs = np.random.default_rng(2).uniform(0.0, 11.0, size=40) * 0.7 + 4.0
    k, t = hermite_cells(np.array([4.0 - 0.35]), np.array([0.7]), np.array([0]), np.array([11]), xs[:, None])
    corner_values = np.stack([rows[k[:, 0]], rows[k[:, 0] + 1]], axis=1)
    corner_slopes = np.stack([slopes[k[:, 0]], slopes[k[:, 0] + 1]], axis=1)[..., None]
    got = hermite_values(corner_values, corner_slopes, np.array([0.7]), t)
    np.testing.assert_allclose(got, _hermite_rows(rows, slopes, 4.0, 0.7, xs), rtol=1e-13, atol=1e-14)


def test_hermite_box_extrema_against_dense_sampling_along_the_grid_lines() -> None:
    rng = np.random.default_rng(3)
    shape, spacings = (7, 6), np.array([0.4, 0.5])
    x, y = np.meshgrid(np.arange(shape[0]) * 0.4, np.arange(shape[1]) * 0.5, indexing="ij")
    values = np.stack([np.sin(2 * x) * np.cos(y), np.cos(3 * x + y)], axis=-1)
    slopes = np.stack([np.stack([2 * np.cos(2 * x) * np.cos(y), -np.sin(2 * x) * np.sin(y)], -1),
                       np.stack([-3 * np.sin(3 * x + y), -np.sin(3 * x + y)], -1)], axis=-2)  # fmt: skip
    first = np.stack([rng.integers(0, n, 40) for n in shape], axis=1)
    last = np.minimum(first + rng.integers(0, 4, (40, 2)), np.array(shape) - 1)
    lower, upper = hermite_box_extrema(values, slopes, spacings, first, last)
    s = np.linspace(0.0, 1.0, 401)[:, None]
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    for q in range(40):
        dense = [values[first[q, 0] : last[q, 0] + 1, first[q, 1] : last[q, 1] + 1].reshape(-1, 2)]
        for i, j in itertools.product(range(first[q, 0], last[q, 0] + 1), range(first[q, 1], last[q, 1] + 1)):
            for d, (di, dj) in enumerate(((1, 0), (0, 1))):
                if i + di <= last[q, 0] and j + dj <= last[q, 1]:
                    f0, f1 = values[i, j], values[i + di, j + dj]
                    m0, m1 = spacings[d] * slopes[i, j, :, d], spacings[d] * slopes[i + di, j + dj, :, d]
                    dense.append(h00 * f0 + h10 * m0 + h01 * f1 + h11 * m1)
        sampled = np.concatenate(dense)
        assert np.all(lower[q] <= sampled.min(axis=0) + 1e-12) and np.all(upper[q] >= sampled.max(axis=0) - 1e-12)
        np.testing.assert_allclose(lower[q], sampled.min(axis=0), atol=1e-4)
        np.testing.assert_allclose(upper[q], sampled.max(axis=0), atol=1e-4)
    # one parameter: the one-parameter refinement of interval_hulls
    one = hermite_box_extrema(values[:, 0], slopes[:, 0, :, :1], spacings[:1], first[:, :1], last[:, :1])
    ref = interval_hulls(values[:, 0], first[:, 0], last[:, 0], slopes=slopes[:, 0, :, 0], spacing=0.4)
    np.testing.assert_array_equal(one[0], ref[0])
    np.testing.assert_array_equal(one[1], ref[1])


def sensitive_model() -> FunctionModel:
    """f(p, t) = (A·p1 + B·p2²)·t with its gradient: linear in p1, quadratic in p2 — so the
    Hermite interpolant is exact and every refined hull is known in closed form."""
    return FunctionModel(lambda p: (A * p[..., :1] + B * p[..., 1:2] ** 2) * TIMES, TIMES,
                         jacobian=lambda p: np.stack([A * TIMES, 2 * B * p[1] * TIMES], axis=1))  # fmt: skip


def test_a_refined_study_gives_the_model_at_the_raw_peaks_and_the_closed_form_box_hulls(tmp_path) -> None:
    model = sensitive_model()
    study = FRVStudy.create(model, specs(), 600, StudyOptions(n_disc=(9, 11), seed=4, chunk=128),
                            store=tmp_path / "s.zarr")
    assert study.refine is True
    peaks = study.samples()["cut"].to_numpy()[:, :, -1, 0]
    hull = study.hulls()["hull"].to_numpy()
    # α = 1: the model at the sample's own peak (the interpolant is exact), kept within the
    # values at its lattice cell's corners — below them only where p2² turns inside the cell
    corners = model.function(key_centres(study.grids, cell_keys(study.grids, study.peak_refine, peaks)[0]))
    corners = corners.reshape(len(peaks), -1, TIMES.size)
    exact = model.function(peaks)
    np.testing.assert_allclose(hull[:, -1, 0], np.clip(exact, corners.min(axis=1), corners.max(axis=1)), rtol=1e-12,
                               atol=1e-12)  # fmt: skip
    assert 0 < np.count_nonzero(np.any(exact < corners.min(axis=1) - 1e-12, axis=1)) < len(peaks) / 4
    # box hulls: the extreme simulated values, p1 at its ends; p2² at the grid point of the
    # box nearest 0 (the interpolant's minimum between grid points, 0 itself when the box
    # straddles 0, is not stored), and at the end farther from 0
    boxes, (g1, g2) = study.boxes(), study.grids
    left, right = boxes["left"].to_numpy(), boxes["right"].to_numpy()
    c2l, c2r = g2.centres(left[:, 1]), g2.centres(right[:, 1])
    p2_min = g2.centres(np.clip(np.floor(-g2.origin / g2.spacing), left[:, 1], right[:, 1]))
    p2_max = np.where(np.abs(c2l) >= np.abs(c2r), c2l, c2r)
    lower = (A * g1.centres(left[:, 0]) + B * p2_min**2)[:, None] * TIMES
    upper = (A * g1.centres(right[:, 0]) + B * p2_max**2)[:, None] * TIMES
    np.testing.assert_allclose(boxes["lower"].to_numpy(), lower, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(boxes["upper"].to_numpy(), upper, rtol=1e-12, atol=1e-12)
    assert np.any((c2l < 0) & (c2r > 0) & (p2_min != 0))  # some boxes straddle 0 between grid points
    # every hull holds its box's closed form and the α = 1 value (nesting repair)
    assert np.all(hull[:, :-1, 0] <= hull[:, -1:, 0] + 1e-12) and np.all(hull[:, :-1, 1] >= hull[:, -1:, 1] - 1e-12)
    # slopes stored, read back, and extension bit-identical to a one-shot run
    again = FRVStudy.open(tmp_path / "s.zarr", model).add_samples(300)
    one_shot = FRVStudy.create(model, specs(), 900,
                               MultiStudyOptions(seed=4, chunk=128, grids=again.grids),
                               store=tmp_path / "o.zarr")  # fmt: skip
    np.testing.assert_array_equal(again.hulls()["hull"].to_numpy(), one_shot.hulls()["hull"].to_numpy())
    assert again.counts["forward_simulations"] == one_shot.counts["forward_simulations"]
    assert again.library()["slope"].shape == (again.library_rows, TIMES.size, 2)


def test_one_refined_parameter_is_the_refined_one_parameter_study(tmp_path) -> None:
    model = FunctionModel(lambda p: np.sin(3 * p[..., :1] * TIMES), TIMES,
                          jacobian=lambda p: (3 * TIMES * np.cos(3 * p[0] * TIMES))[:, None])  # fmt: skip
    spec = FRVSpec("p", 1.0, alphas=(0.0, 0.25, 0.5, 0.75, 1.0))
    single = FRVStudy.create(model, spec, 500, StudyOptions(n_disc=15, seed=3, chunk=128), store=tmp_path / "a.zarr")
    multi = FRVStudy.create(model, [spec], 500, MultiStudyOptions(n_disc=15, seed=3, chunk=128),
                            store=tmp_path / "b.zarr")  # the several-parameter way (peak lattice), of one
    assert multi.several and not single.several
    assert single.refine is True and multi.refine is True
    np.testing.assert_allclose(multi.hulls()["hull"].to_numpy(), single.hulls()["hull"].to_numpy(), rtol=1e-12,
                               atol=1e-14)  # fmt: skip


def test_refining_needs_sensitivities(tmp_path) -> None:
    model = FunctionModel(lambda p: p[..., :1] * TIMES + p[..., 1:2], TIMES)
    with pytest.raises(ParameterError, match="sensitivities"):
        FRVStudy.create(model, specs(), 50, StudyOptions(n_disc=5, refine=True), store=tmp_path / "u.zarr")
    assert not (tmp_path / "u.zarr").exists()
    assert FRVStudy.create(model, specs(), 50, StudyOptions(n_disc=5), store=tmp_path / "v.zarr").refine is False
