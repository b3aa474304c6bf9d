"""Bad input to the Plug-in Gait model: implausible parameters, missing markers, gaps."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from support import SAMPLE_DATA
from fuzzygait.core.errors import MarkerError, ParameterError
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import ANGLE_NAMES, compute_lower_body, static_calibration


def _without(trial: Trial, *labels: str) -> Trial:
    return trial.select_markers([m for m in trial.marker_labels if m not in labels])


# ----------------------------------------------------------------------- parameters
@pytest.mark.parametrize(
    ("change", "named"),
    [
        (dict(knee_width=-105.0), "LKneeWidth"),
        (dict(leg_length=0.9), "LLegLength"),  # metres instead of mm
        (dict(ankle_width=0.0), "LAnkleWidth"),
        (dict(tibial_torsion=15.0), "LTibialTorsion"),  # degrees instead of rad
    ],
)
def test_implausible_parameters_are_named(walking, subject, change, named):
    bad = subject.with_side("L", **change)
    with pytest.raises(ParameterError, match=named):
        compute_lower_body(walking, bad)
    with pytest.raises(ParameterError, match=named):
        static_calibration(read_c3d(SAMPLE_DATA / "static.c3d"), bad)


def test_marker_diameter_is_checked(walking, subject):
    with pytest.raises(ParameterError, match="MarkerDiameter"):
        compute_lower_body(walking, replace(subject, marker_diameter=-14.0))


# ----------------------------------------------------------------------- missing markers
def test_missing_knee_marker_keeps_the_other_angles(walking, subject):
    result = compute_lower_body(_without(walking, "LKNE"), subject)
    lost = {"LHipAngles", "LKneeAngles", "LAnkleAngles", "LFootProgressAngles"}
    assert set(result.unavailable) == lost
    for name in lost:
        assert result.unavailable[name] == "marker LKNE missing"
        assert name not in result.angles
    full = compute_lower_body(walking, subject)
    for name in set(ANGLE_NAMES) - lost:
        np.testing.assert_array_equal(result.angles[name], full.angles[name])
    assert "LKJC" not in result.joint_centres and "LHJC" in result.joint_centres
    assert "LFEO" not in result.virtual_markers and "RFEO" in result.virtual_markers


def test_missing_toe_marker_only_loses_the_foot(walking, subject):
    result = compute_lower_body(_without(walking, "RTOE", "LTIB"), subject)
    assert result.unavailable == {
        "LKneeAngles": "marker LTIB missing",
        "LAnkleAngles": "marker LTIB missing",
        "LFootProgressAngles": "marker LTIB missing",
        "RAnkleAngles": "marker RTOE missing",
        "RFootProgressAngles": "marker RTOE missing",
    }
    assert {"LPelvisAngles", "RPelvisAngles", "LHipAngles", "RHipAngles", "RKneeAngles"} == set(result.angles)


def test_missing_pelvis_marker_loses_everything_and_names_it(walking, subject):
    result = compute_lower_body(_without(walking, "LPSI", "RASI"), subject)
    assert result.angles == {}
    assert set(result.unavailable) == set(ANGLE_NAMES)
    assert all(reason == "markers RASI, LPSI missing" for reason in result.unavailable.values())


def test_sacrum_marker_replaces_the_psis(walking, subject):
    sacr = 0.5 * (walking.marker("LPSI") + walking.marker("RPSI"))
    labels = [m for m in walking.marker_labels if m not in ("LPSI", "RPSI")]
    markers = np.concatenate([walking.select_markers(labels).markers, sacr[:, None, :]], axis=1)
    with_sacr = replace(walking, markers=markers, marker_labels=[*labels, "SACR"])
    a, b = compute_lower_body(with_sacr, subject), compute_lower_body(walking, subject)
    for name in ANGLE_NAMES:
        np.testing.assert_allclose(a.angles[name], b.angles[name], atol=1e-9)


def test_medial_option_names_missing_medial_markers(walking, subject):
    result = compute_lower_body(walking, subject, use_medial_markers=True)
    assert result.unavailable["LHipAngles"] == "marker LKNM missing"
    assert result.unavailable["RKneeAngles"] == "markers RKNM, RMED missing"
    assert set(result.angles) == {"LPelvisAngles", "RPelvisAngles"}


def test_static_calibration_names_missing_markers(subject):
    static = read_c3d(SAMPLE_DATA / "static.c3d")
    with pytest.raises(MarkerError, match="LHEE"):
        static_calibration(_without(static, "LHEE"), subject)


# ----------------------------------------------------------------------- gaps (NaN samples)
def test_nan_samples_give_nan_angles_only_where_needed(walking, subject):
    markers = walking.markers.copy()
    markers[10:13, walking.marker_labels.index("LKNE")] = np.nan
    markers[40, walking.marker_labels.index("RTOE")] = np.nan
    gappy = walking.with_markers(markers)
    result = compute_lower_body(gappy, subject)
    full = compute_lower_body(walking, subject)
    assert result.unavailable == {}
    for name in ("LHipAngles", "LKneeAngles", "LAnkleAngles", "LFootProgressAngles"):
        assert np.isnan(result.angles[name][10:13]).all(), name
    assert np.isnan(result.angles["RAnkleAngles"][40]).all()
    assert np.isnan(result.angles["RFootProgressAngles"][40]).all()
    keep = np.ones(walking.n_frames, dtype=bool)
    keep[[10, 11, 12, 40]] = False
    for name in ANGLE_NAMES:  # nothing interpolated, nothing else touched
        np.testing.assert_array_equal(result.angles[name][keep], full.angles[name][keep])
    for name in ("LPelvisAngles", "RHipAngles", "RKneeAngles"):
        assert np.isfinite(result.angles[name]).all()


def test_inter_asis_distance_is_measured_when_unknown(walking, subject):
    result = compute_lower_body(walking, replace(subject, inter_asis_distance=None))
    assert any("InterAsisDistance measured" in note and "250.00" in note for note in messages(result.notes))
    full = compute_lower_body(walking, subject)
    np.testing.assert_allclose(result.angles["LHipAngles"], full.angles["LHipAngles"], atol=1e-3)
