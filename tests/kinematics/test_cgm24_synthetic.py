"""Every model version on the synthetic CGM 2.4 session of :mod:`fuzzygait.synthetic.cgm24`
(truth angles, joint centres and ForeFootAngles from the posed skeleton), and the CGM 2.4
forefoot's behaviour with missing markers."""

from __future__ import annotations

import numpy as np
import pytest
from support import rot_pelvis_truth

from fuzzygait.core.errors import MarkerError, ParameterError
from fuzzygait.core.findings import messages
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.synthetic.cgm24 import make_cgm24_static, make_cgm24_walking
from fuzzygait.workflows.angles import Preprocessing, calibrate_static, resolve_subject, run_angles

BOUND_DEG = 0.01
NO_FILTER = Preprocessing(filter=False)


@pytest.fixture(scope="module")
def sessions():
    out = {}
    for hjc in ("davis", "hara"):
        walking, truth = make_cgm24_walking(hjc=hjc)
        out[hjc] = (make_cgm24_static(hjc=hjc), walking, truth)
    return out


def _expected(truth, name: str, model: str) -> np.ndarray | None:
    if name.endswith("PelvisAngles") and model != "cgm1.0":
        return rot_pelvis_truth(truth, name[0])
    if f"{name}_X" not in truth:
        return None
    return truth[[f"{name}_{a}" for a in "XYZ"]].to_numpy()


# Davis-hip versions on the session whose true hips are Davis', Hara-hip ones on Hara's.
@pytest.mark.parametrize(
    ("model", "hjc"),
    [("cgm1.0", "davis"), ("cgm1.1", "davis"), ("cgm2.1", "hara"), ("cgm2.3", "hara"), ("cgm2.4", "hara")],
)
def test_every_version_recovers_every_angle(sessions, model: str, hjc: str) -> None:
    static, walking, truth = sessions[hjc]
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model=model)
    assert run.result.model == model and run.result.unavailable == {}
    no_truth = []
    for name, values in run.result.angles.items():
        expected = _expected(truth, name, model)
        if expected is None:
            no_truth.append(name)
        else:
            assert np.abs(values - expected).max() <= BOUND_DEG, name
    assert set(no_truth) <= {"LFootProgressAngles", "RFootProgressAngles"}  # checked against Nexus elsewhere
    assert ("LForeFootAngles" in run.result.angles) == (model == "cgm2.4")
    centres = ("HJC", "KJC", "AJC") + (("FJC",) if model == "cgm2.4" else ())
    for centre in (side + c for side in "LR" for c in centres):
        expected = truth[[f"{centre}_{a}" for a in "XYZ"]].to_numpy()
        assert np.abs(run.result.joint_centres[centre] - expected).max() < 1e-6, centre


def test_auto_picks_cgm24_on_the_full_marker_set(sessions) -> None:
    static, walking, _ = sessions["hara"]
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model="auto")
    assert run.result.model == "cgm2.4"
    assert "LForeFootAngles" in run.result.angles and "RForeFootAngles" in run.result.angles
    assert any(note.startswith("model cgm2.4 (") for note in messages(run.notes))


def test_forefoot_angles_follow_a_known_forefoot_turn(sessions) -> None:
    """Second method: turning the left forefoot markers of every frame by a further 5 deg
    about the hindfoot's flexion (y) axis through TOE raises LForeFootAngles X by 5 deg
    (dorsiflexion +) and leaves every other angle alone."""
    static, walking, _ = sessions["hara"]
    base = run_angles(walking, static=static, preprocessing=NO_FILTER, model="cgm2.4")
    foot = base.result.segment_frames["left_foot"]
    toe = walking.marker("LTOE")
    angle = np.radians(5.0)
    axis = foot[:, :, 1]  # the hindfoot's y axis (to the left)
    markers = walking.markers.copy()
    turned = {}
    for sign in (1.0, -1.0):
        for label in ("LFMH", "LSMH", "LVMH"):
            v = walking.marker(label) - toe
            k = sign * axis
            cos, sin = np.cos(angle), np.sin(angle)
            rotated = v * cos + np.cross(k, v) * sin + k * np.sum(k * v, axis=1, keepdims=True) * (1 - cos)
            markers[:, walking.marker_labels.index(label)] = toe + rotated
        run = run_angles(walking.with_markers(markers), static=static, preprocessing=NO_FILTER, model="cgm2.4")
        turned[sign] = run.result.angles["LForeFootAngles"] - base.result.angles["LForeFootAngles"]
        assert np.abs(run.result.angles["RForeFootAngles"] - base.result.angles["RForeFootAngles"]).max() < 1e-9
        assert np.abs(run.result.angles["LAnkleAngles"] - base.result.angles["LAnkleAngles"]).max() < 1e-9
    # the hindfoot's y axis points left: a right-hand turn about it lowers the toes
    np.testing.assert_allclose(turned[-1.0][:, 0], 5.0, atol=1e-9)
    np.testing.assert_allclose(turned[1.0][:, 0], -5.0, atol=1e-9)
    assert np.abs(turned[1.0][:, 1:]).max() < 1e-9


@pytest.mark.parametrize(
    ("model", "hidden", "angle"),
    [("cgm2.3", "LTHAP", "LHipAngles"), ("cgm2.4", "LTHAP", "LHipAngles"), ("cgm2.4", "RSMH", "RForeFootAngles")],
)
def test_a_hidden_cluster_marker_is_tracked_by_the_others(sessions, model: str, hidden: str, angle: str) -> None:
    static, walking, truth = sessions["hara"]
    markers = walking.markers.copy()
    markers[40:120, walking.marker_labels.index(hidden)] = np.nan
    run = run_angles(walking.with_markers(markers), static=static, preprocessing=Preprocessing(filter=False, max_gap=0),
                     model=model)  # fmt: skip
    expected = truth[[f"{angle}_{a}" for a in "XYZ"]].to_numpy()
    assert np.abs(run.result.angles[angle] - expected).max() <= BOUND_DEG


def test_a_forefoot_with_two_markers_is_not_computed_and_named(sessions) -> None:
    static, walking, _ = sessions["hara"]
    kept = [m for m in walking.marker_labels if m not in ("LFMH", "LVMH")]
    run = run_angles(walking.select_markers(kept), static=static, preprocessing=NO_FILTER, model="cgm2.4")
    reason = run.result.unavailable["LForeFootAngles"]
    assert "LFMH" in reason and "LVMH" in reason
    assert {"LAnkleAngles", "RForeFootAngles", "LKneeAngles"} <= set(run.result.angles)
    assert "LFJC" not in run.result.joint_centres


def test_static_without_a_forefoot_marker_names_it(sessions) -> None:
    static, walking, _ = sessions["hara"]
    kept = [m for m in static.marker_labels if m != "RVMH"]
    with pytest.raises(MarkerError, match="RVMH missing"):
        calibrate_static(static.select_markers(kept), resolve_subject(walking, None), model="cgm2.4")


def test_cgm24_without_a_forefoot_calibration_is_one_clear_error(sessions) -> None:
    static, walking, _ = sessions["hara"]
    calibrated = calibrate_static(static, resolve_subject(walking, None), model="cgm2.3")
    assert calibrated.clusters is not None and not calibrated.clusters.has_forefoot
    with pytest.raises(ParameterError, match="forefoot"):
        compute_lower_body(walking, calibrated.subject, model="cgm2.4", clusters=calibrated.clusters)


def test_tracking_by_fewer_markers_is_noted_per_frame_range(sessions) -> None:
    static, walking, _ = sessions["hara"]
    markers = walking.markers.copy()
    markers[40:90, walking.marker_labels.index("RSMH")] = np.nan  # C3D frames 41-90
    for label in ("LTIAP", "LTIAD"):
        markers[200:205, walking.marker_labels.index(label)] = np.nan  # two of four: no pose in 201-205
    run = run_angles(walking.with_markers(markers), static=static, preprocessing=Preprocessing(filter=False, max_gap=0),
                     model="cgm2.4")  # fmt: skip
    assert "right forefoot: RSMH not seen in frames 41-90; tracked by the other markers there" in messages(run.notes)
    assert "left tibia: fewer than 3 markers seen in frames 201-205; no pose there (NaN)" in messages(run.notes)
    knee = run.result.angles["LKneeAngles"]
    assert np.isnan(knee[200:205]).all() and np.isfinite(knee[:200]).all() and np.isfinite(knee[205:]).all()
    assert np.isfinite(run.result.angles["LHipAngles"]).all()
