"""Reverse sweeps of indexing a traced array (:mod:`fuzzygait.core.arrays`): a basic
index (integers, slices, ``None``, ``...``) adds the gradient in place, a fancy one keeps
autograd's ``add.at``.

Independent truth: the analytic gradient of a function of a few entries and central
finite differences; a repeated fancy index counts its element twice.
"""

from __future__ import annotations

import autograd.numpy as anp
import numpy as np
import pytest
from autograd import grad

import fuzzygait.core.arrays  # noqa: F401  (registers the reverse sweep)
from fuzzygait.core.arrays import _basic


def positions_function(positions: np.ndarray) -> float:
    """A function of two markers' columns of ``(k, n, 3)`` positions, as the kinematic
    chain reads them (``positions[:, i]``), plus a strided slice and a new axis."""
    first, third = positions[:, 0], positions[:, 2]
    every_other = positions[..., ::2]
    return anp.sum(anp.sin(first) * third) + anp.sum(every_other[None, :, 1] ** 2)


def test_basic_indices_give_the_analytic_gradient() -> None:
    rng = np.random.default_rng(0)
    positions = rng.normal(size=(4, 3, 3))
    gradient = grad(positions_function)(positions)
    expected = np.zeros_like(positions)
    expected[:, 0] += np.cos(positions[:, 0]) * positions[:, 2]
    expected[:, 2] += np.sin(positions[:, 0])
    expected[:, 1, ::2] += 2 * positions[:, 1, ::2]
    np.testing.assert_allclose(gradient, expected, rtol=1e-12, atol=1e-12)
    h = 1e-6
    differences = np.zeros_like(positions)
    for index in np.ndindex(positions.shape):
        step = np.zeros_like(positions)
        step[index] = h
        differences[index] = (positions_function(positions + step) - positions_function(positions - step)) / (2 * h)
    np.testing.assert_allclose(gradient, differences, rtol=0, atol=1e-7)


def test_a_repeated_fancy_index_still_counts_twice() -> None:
    x = np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(grad(lambda v: anp.sum(v[np.array([0, 0, 2])] ** 2))(x), [4.0, 0.0, 6.0])
    np.testing.assert_allclose(grad(lambda v: anp.sum(v[[1, 1]]))(x), [0.0, 2.0, 0.0])


@pytest.mark.parametrize("index, basic", [((slice(None), 0), True), (2, True), ((Ellipsis, None, slice(1, 3)), True),
                                          (np.array([0, 0]), False), ([1, 1], False), (True, False),
                                          ((slice(None), np.int64(1)), False)])  # fmt: skip
def test_what_counts_as_a_basic_index(index: object, basic: bool) -> None:
    assert _basic(index) is basic
