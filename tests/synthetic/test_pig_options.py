"""The synthetic KAD / medial-malleolus / misplaced-wand / tibial-torsion subject
(:mod:`fuzzygait.synthetic.pig_options`), checked on its own geometry."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from fuzzygait.synthetic import DYNAMIC_LABELS, make_static_trial, make_walking_trial, static_offsets
from fuzzygait.synthetic.gait_curves import plug_in_gait_ankle_y
from fuzzygait.synthetic.pig_options import KAD_ARM_MM, PigOptions, torsioned_ankle_y


@pytest.mark.parametrize("side", ["L", "R"])
def test_torsioned_ankle_y_without_torsion_is_the_plain_one(side):
    flexion, rotation = np.linspace(-20, 15, 11), np.linspace(-15, 10, 11)
    beta = static_offsets()["plantarflexion"]
    got = torsioned_ankle_y(flexion, rotation, 0.0, side, beta)
    np.testing.assert_allclose(got, plug_in_gait_ankle_y(rotation, beta), atol=1e-12)


def test_static_labels_and_kad_shape():
    static = make_static_trial(options=PigOptions())
    assert static.marker_labels[:5] == ["LASI", "RASI", "LPSI", "RPSI", "LTHI"]
    assert {"LKAX", "LKD1", "LKD2", "RKAX", "RKD1", "RKD2", "LMED", "RMED"} <= set(static.marker_labels)
    assert not {"LKNE", "RKNE", "LKNM", "RKNM"} & set(static.marker_labels)
    for side in "LR":
        for a, b in itertools.combinations(("KAX", "KD1", "KD2"), 2):
            d = np.linalg.norm(static.marker(side + a) - static.marker(side + b), axis=1)
            np.testing.assert_allclose(d, KAD_ARM_MM * np.sqrt(2.0), atol=1e-9)
    plain = make_static_trial(options=PigOptions(kad=False, medial_malleoli=False))
    assert plain.marker_labels == list(DYNAMIC_LABELS)


def test_walking_markers_are_rigid_and_the_default_trial_unchanged():
    walking, _ = make_walking_trial(options=PigOptions())
    default, _ = make_walking_trial()
    assert walking.marker_labels == default.marker_labels
    for side in "LR":
        for a, b in (("THI", "KNE"), ("TIB", "ANK"), ("HEE", "TOE")):
            d = np.linalg.norm(walking.marker(side + a) - walking.marker(side + b), axis=1)
            assert np.ptp(d) < 1e-9, (side, a, b)
        # the wands moved, the pelvis did not
        assert np.abs(walking.marker(side + "THI") - default.marker(side + "THI")).max() > 5.0
    np.testing.assert_array_equal(walking.marker("LASI"), default.marker("LASI"))
