"""Least-squares rigid fit of a marker cluster against known poses and a second method
(scipy's Kabsch, ``Rotation.align_vectors``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from fuzzygait.kinematics.rigid import fit_rigid

RNG = np.random.default_rng(7)
CLUSTER = np.array([[0.0, 0.0, 0.0], [120.0, 5.0, -3.0], [30.0, 80.0, 10.0], [60.0, 20.0, 55.0]])


def _poses(n: int) -> tuple[np.ndarray, np.ndarray]:
    return Rotation.random(n, random_state=3).as_matrix(), RNG.normal(0.0, 500.0, (n, 3))


def _observe(rotations: np.ndarray, origins: np.ndarray, local: np.ndarray = CLUSTER) -> np.ndarray:
    return origins[:, None, :] + np.einsum("nij,mj->nmi", rotations, local)


def test_noise_free_poses_are_recovered_exactly() -> None:
    rotations, origins = _poses(200)
    fit = fit_rigid(CLUSTER, _observe(rotations, origins))
    assert np.abs(fit.rotation - rotations).max() < 1e-12
    assert np.abs(fit.origin - origins).max() < 1e-9
    assert fit.residual.max() < 1e-9


def test_a_hidden_marker_leaves_three_to_fix_the_pose() -> None:
    rotations, origins = _poses(50)
    observed = _observe(rotations, origins)
    observed[::2, 1] = np.nan
    fit = fit_rigid(CLUSTER, observed)
    assert np.abs(fit.rotation - rotations).max() < 1e-12
    assert fit.visible[::2, 1].sum() == 0 and fit.visible[1::2].all()


def test_fewer_than_three_or_collinear_markers_give_nan() -> None:
    rotations, origins = _poses(4)
    observed = _observe(rotations, origins)
    observed[0, :2] = np.nan  # two left
    line = np.array([[0.0, 0.0, 0.0], [50.0, 0.0, 0.0], [100.0, 0.0, 0.0]])
    fit = fit_rigid(CLUSTER, observed)
    assert np.isnan(fit.rotation[0]).all() and np.isfinite(fit.rotation[1:]).all()
    assert np.isnan(fit_rigid(line, _observe(rotations, origins, line)).rotation).all()


def test_noisy_weighted_fit_equals_scipy_kabsch() -> None:
    """With noise the optimum is not the truth; it is the same as scipy's weighted one."""
    rotations, origins = _poses(30)
    observed = _observe(rotations, origins) + RNG.normal(0.0, 2.0, (30, 4, 3))
    weights = np.array([1.0, 2.0, 0.5, 3.0])
    fit = fit_rigid(CLUSTER, observed, weights)
    for k in range(30):
        x_bar = weights @ observed[k] / weights.sum()
        r_bar = weights @ CLUSTER / weights.sum()
        expected, _ = Rotation.align_vectors(observed[k] - x_bar, CLUSTER - r_bar, weights=weights)
        assert np.abs(fit.rotation[k] - expected.as_matrix()).max() < 1e-10
    assert np.all(fit.residual > 0.5)


def test_a_mirrored_cluster_gives_a_rotation_not_a_reflection() -> None:
    rotations, origins = _poses(10)
    observed = _observe(rotations, origins, CLUSTER * [1.0, 1.0, -1.0])
    fit = fit_rigid(CLUSTER, observed)
    assert np.allclose(np.linalg.det(fit.rotation), 1.0)


def test_bad_shapes_and_weights_are_refused() -> None:
    with pytest.raises(ValueError, match="do not match"):
        fit_rigid(CLUSTER, np.zeros((5, 3, 3)))
    with pytest.raises(ValueError, match="non-negative"):
        fit_rigid(CLUSTER, np.zeros((5, 4, 3)), weights=np.array([1.0, -1.0, 1.0, 1.0]))


def test_polar_rotation_equals_the_svd_rotation() -> None:
    """Second method: the SVD formula on random, ill-conditioned, reflecting and singular
    matrices (the Newton path where det > 0, the SVD fallback elsewhere)."""
    from fuzzygait.kinematics.rigid import polar_rotation

    rng = np.random.default_rng(11)
    matrices = rng.normal(size=(400, 3, 3))
    u, _, vt = np.linalg.svd(matrices)
    spread = np.array([[300.0, 40.0, 1.0], [1e3, 1.0, 1e-3], [5.0, 5.0, 5.0], [1.0, 1.0, 0.0]])
    scaled = np.concatenate([u[k::4] @ (np.diag(spread[k])[None] @ vt[k::4]) for k in range(4)])
    for case in (matrices, scaled):
        u, _, vt = np.linalg.svd(case)
        d = np.sign(np.linalg.det(u @ vt))
        u[:, :, 2] *= d[:, None]
        expected = u @ vt
        got = polar_rotation(case)
        rank_deficient = np.linalg.matrix_rank(case) < 2  # no unique rotation
        assert np.abs(got - expected)[~rank_deficient].max() < 1e-9
        assert np.abs(np.linalg.det(got) - 1.0).max() < 1e-12
    assert (np.linalg.det(matrices) < 0).sum() > 100  # the reflection case was exercised
