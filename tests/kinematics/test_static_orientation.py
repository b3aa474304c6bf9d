"""A static trial with the subject turned in the laboratory.

Turned about the vertical, the calibration is unchanged (every calibrated value is a
relative angle or a distance), so it is accepted; with another lab axis up the
foot-flat option (which levels HEE along lab Z) would give wrong foot offsets, so it
is refused in one line.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.io import read_c3d
from fuzzygait.kinematics import compute_lower_body, static_calibration
from support import SAMPLE_DATA

FIELDS = ("static_plant_flex", "static_rot_off")


@pytest.fixture(scope="module")
def static():
    return read_c3d(SAMPLE_DATA / "static.c3d")


@pytest.fixture(scope="module")
def blank(subject):
    subject = replace(subject, inter_asis_distance=None)
    for side in "LR":
        subject = subject.with_side(side, **{name: 0.0 for name in FIELDS})
    return subject


def _rotated(trial, axis, degrees):
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    i, j = [k for k in range(3) if k != axis]
    rotation = np.eye(3)
    rotation[i, i], rotation[i, j], rotation[j, i], rotation[j, j] = c, -s, s, c
    return trial.with_markers(trial.markers @ rotation.T)


def _values(subject):
    return [getattr(subject.side(side), name) for side in "LR" for name in FIELDS] + [subject.inter_asis_distance]


@pytest.mark.parametrize("flat_foot", [False, True])
@pytest.mark.parametrize("degrees", [45.0, 135.0])
def test_a_subject_turned_about_the_vertical_is_calibrated_as_facing_a_lab_axis(static, blank, degrees, flat_foot):
    reference = static_calibration(static, blank, flat_foot=flat_foot)
    turned = _rotated(static, 2, degrees)
    calibrated = static_calibration(turned, blank, flat_foot=flat_foot)
    np.testing.assert_allclose(_values(calibrated), _values(reference), atol=1e-9)
    # the static trial's own pelvis rotation is relative to the nearest lab axis
    result = compute_lower_body(turned, calibrated, static_foot="flat" if flat_foot else "heel")
    assert abs(np.nanmean(result.angles["LPelvisAngles"][:, 2])) == pytest.approx(45.0, abs=1e-6)


def test_another_axis_up_is_refused_with_foot_flat(static, blank):
    lying = _rotated(static, 0, 90.0)  # lab Y up
    refusal = r"static.*90 deg from the lab's \+Z axis.*export the static trial with Z up"
    with pytest.raises(ParameterError, match=refusal) as error:
        static_calibration(lying, blank, flat_foot=True)
    assert "\n" not in str(error.value)
    # without foot flat nothing refers to the lab vertical: the same calibration
    plain = static_calibration(lying, blank)
    np.testing.assert_allclose(_values(plain), _values(static_calibration(static, blank)), atol=1e-9)
