"""The tip-loaded layered blade with fuzzy face/core moduli and face thickness (§5.4)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.layered_blade import LayeredBladeModel
from fuzzygait.uncertainty import FuzzyVector, Linearised, graph_follower, triangular_relative


@pytest.fixture(scope="module")
def model() -> LayeredBladeModel:
    return LayeredBladeModel(target="toe_z", nodes=8, duration=0.1, dt=1e-3, tip_force=(0.0, 0.0, 100.0))


def test_stiffer_layers_deflect_less(model):
    base = model.base
    lift = model.evaluate(base).values[-1] - model.evaluate(base).values[0]
    assert lift > 0  # the toe is pushed up
    for k in range(3):
        stiffer = base.copy()
        stiffer[k] *= 1.2
        assert model.evaluate(stiffer).values[-1] - model.evaluate(stiffer).values[0] < lift


def test_hulls_are_the_box_corners_for_this_monotone_response(model):
    """Toe lift falls monotonically with each layer parameter, so the α = 0 hull at the end
    is spanned by the corners of the parameter box (8 independent runs)."""
    numbers = [triangular_relative(v, 0.1, n) for v, n in zip(model.base, model.names)]
    result = graph_follower(model, FuzzyVector(numbers), (0.0, 1.0), strategy=Linearised(stride=10))
    corners = [model.evaluate(np.array(c)).values for c in itertools.product(*[(0.9 * v, 1.1 * v) for v in model.base])]
    end = np.array([c[-1] for c in corners])
    hull = result["hull"].sel(alpha=0.0).isel(time=-1)
    scale = np.ptp(end)
    assert float(hull.sel(bound="upper")) == pytest.approx(end.max(), abs=1e-3 * scale)
    assert float(hull.sel(bound="lower")) == pytest.approx(end.min(), abs=1e-3 * scale)


def test_bad_layer_input():
    with pytest.raises(ParameterError, match="target"):
        LayeredBladeModel(target="foo")
    with pytest.raises(ParameterError, match="face_thickness"):
        LayeredBladeModel(nodes=4, duration=0.004, dt=2e-3).evaluate(np.array([6e10, 6e9, -1e-3]))
