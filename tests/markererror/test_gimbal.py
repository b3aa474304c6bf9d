"""The Cardan-singularity rule of the undetermined mask
(:func:`fuzzygait.markererror.undetermined.gimbal_undetermined`)."""

from __future__ import annotations

import numpy as np

from fuzzygait.kinematics.angles import cardan_yxz
from fuzzygait.kinematics.vectors import axis_rotation
from fuzzygait.markererror.undetermined import (
    GIMBAL_MARGIN_DEG,
    gimbal_undetermined,
    middle_component,
    near_gimbal_lock,
)


def test_middle_component_per_joint() -> None:
    assert [middle_component(f"L{j}Angles") for j in ("Pelvis", "Hip", "Knee")] == [1, 1, 1]
    assert [middle_component(f"R{j}Angles") for j in ("Ankle", "FootProgress", "ForeFoot")] == [2, 2, 2]


def test_first_and_third_components_are_undetermined_near_the_singularity() -> None:
    """Frames 0-3 at two α-levels (0, 1): the middle band reaches 70°, 76°, −80°, NaN at
    α = 0; every component is flagged where it passes 90° − 15° only, never at α = 1,
    and the middle band is closed at ±90° there (the asin's range: a sound bound)."""
    middle = np.full((2, 2, 4), 0.0)
    middle[0, 0] = [-10.0, -20.0, -80.0, np.nan]
    middle[0, 1] = [70.0, 76.0, 5.0, np.nan]
    middle[1] = [[60.0, 80.0, -77.0, np.nan]] * 2  # α = 1: measured
    other = np.zeros((2, 2, 4))
    hulls = {"LFootProgressAngles_X": other, "LFootProgressAngles_Y": other.copy(), "LFootProgressAngles_Z": middle}
    flags = {c: np.zeros((2, 4), dtype=bool) for c in hulls}
    gimbal_undetermined(hulls, flags, measured_index=1)
    expected = np.array([[False, True, True, False], [False, False, False, False]])
    np.testing.assert_array_equal(flags["LFootProgressAngles_X"], expected)
    np.testing.assert_array_equal(flags["LFootProgressAngles_Y"], expected)
    np.testing.assert_array_equal(flags["LFootProgressAngles_Z"], expected)
    np.testing.assert_array_equal(middle[0, 1], [70.0, 90.0, 5.0, np.nan])
    np.testing.assert_array_equal(middle[0, 0], [-10.0, -20.0, -90.0, np.nan])
    np.testing.assert_array_equal(middle[1, 1], [60.0, 80.0, -77.0, np.nan])  # measured: untouched
    assert 90.0 - GIMBAL_MARGIN_DEG == 75.0


def test_incomplete_angles_flag_what_is_there() -> None:
    middle = np.full((2, 2, 1), 89.0)
    middle[1] = 10.0
    hulls = {"LKneeAngles_X": np.zeros((2, 2, 1)), "LKneeAngles_Y": middle}
    flags = {c: np.zeros((2, 1), dtype=bool) for c in hulls}
    gimbal_undetermined(hulls, flags, measured_index=1)
    assert flags["LKneeAngles_X"][0, 0] and flags["LKneeAngles_Y"][0, 0]
    assert not flags["LKneeAngles_X"][1, 0] and not flags["LKneeAngles_Y"][1, 0]
    assert middle[0, 1, 0] == 90.0
    hulls = {"LKneeAngles_X": np.full((2, 2, 1), 80.0)}  # no middle component: nothing to go by
    flags = {"LKneeAngles_X": np.zeros((2, 1), dtype=bool)}
    gimbal_undetermined(hulls, flags, measured_index=1)
    assert not flags["LKneeAngles_X"].any() and hulls["LKneeAngles_X"][0, 1, 0] == 80.0


def test_near_the_singularity_a_small_turn_moves_the_outer_angles_far() -> None:
    """Why the rule: with the middle angle at 85°, turning the distal frame by 3° about
    any axis moves the first Cardan angle by up to about 3°/cos(85°) ≈ 34° (dense sampling
    of turn axes), at 45° by at most about 4°."""
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(2000, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    turn = np.radians(3.0)
    k = np.zeros((axes.shape[0], 3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -axes[:, 2], axes[:, 1], -axes[:, 0]
    k -= np.swapaxes(k, 1, 2)
    small = np.eye(3) + np.sin(turn) * k + (1 - np.cos(turn)) * k @ k  # Rodrigues
    spread = {}
    for middle in (45.0, 85.0):
        rotation = axis_rotation(1, np.radians(20.0)) @ axis_rotation(0, np.radians(middle)) @ axis_rotation(2, 0.3)
        first = cardan_yxz(rotation @ small)[:, 0]
        spread[middle] = float(np.max(np.abs(first - 20.0)))
    assert spread[45.0] < 5.0
    assert spread[85.0] > 25.0
    flagged = near_gimbal_lock(np.zeros(2), np.array([85.0, 45.0]))
    np.testing.assert_array_equal(flagged, [True, False])
