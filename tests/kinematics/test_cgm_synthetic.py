"""The Plug-in Gait lower body on the synthetic walker, plus analytic unit checks.

The synthetic truth (sample_data, :mod:`fuzzygait.synthetic`) is built independently of
``fuzzygait.kinematics``: forward kinematics from known angles with the generator's own
rotation code.  Measured: every angle within 3e-4 deg (float32 marker storage), joint
centres within 3.2e-4 mm, static offsets within 1e-8 rad.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from support import SAMPLE_DATA
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics import (
    ANGLE_NAMES,
    angles_from_virtual_markers,
    compute_lower_body,
    static_calibration,
)
from fuzzygait.kinematics.angles import ANGLE_TABLE, cardan_yxz, joint_angles
from fuzzygait.kinematics.joint_centres import chord_joint_centre, davis_hjc_local
from fuzzygait.kinematics.progression import progression_frame
from fuzzygait.kinematics.vectors import axis_rotation, cross, dot, norm, unit
from fuzzygait.synthetic import SubjectGeometry, davis_hjc, joint_rotation, make_static_trial

TRUTH_JOINTS = ("Pelvis", "Hip", "Knee", "Ankle")
#: Plug-in Gait foot frame = anatomical foot (x along the foot, z dorsal) turned by -90
#: degrees about y (z along the foot backwards, x dorsal).
PIG_FOOT = axis_rotation(1, -math.pi / 2)


@pytest.fixture(scope="module")
def static() -> Trial:
    return read_c3d(SAMPLE_DATA / "static.c3d")


@pytest.fixture(scope="module")
def calibrated(static, subject):
    bare = subject
    for side in "LR":
        bare = bare.with_side(side, static_plant_flex=0.0, static_rot_off=0.0)
    return static_calibration(static, bare)


# ----------------------------------------------------------------------- acceptance
def test_static_calibration_recovers_the_synthetic_offsets(calibrated):
    for side in "LR":
        params = calibrated.side(side)
        assert params.static_plant_flex == pytest.approx(math.atan2(60, 140), abs=1e-7)
        assert params.static_rot_off == pytest.approx(0.0, abs=1e-7)


@pytest.mark.parametrize("source", ["static calibration", "subject.toml"])
def test_walking_angles_recover_the_truth(walking, calibrated, subject, truth, source):
    result = compute_lower_body(walking, calibrated if source == "static calibration" else subject)
    assert result.unavailable == {}
    worst = 0.0
    for side, joint in itertools.product("LR", TRUTH_JOINTS):
        name = f"{side}{joint}Angles"
        expected = truth[[f"{name}_{a}" for a in "XYZ"]].to_numpy()
        err = np.abs(result.angles[name] - expected).max()
        assert err <= 0.01, (name, err)
        worst = max(worst, err)
    assert worst > 1e-6  # float32 markers: the bound is measured, not trivial


def test_joint_centres_recover_the_truth(walking, subject):
    truth = pd.read_csv(SAMPLE_DATA / "walking_truth_joint_centres.csv")
    result = compute_lower_body(walking, subject)
    for side, jc in itertools.product("LR", ("HJC", "KJC", "AJC")):
        expected = truth[[f"{side}{jc}_{a}" for a in "XYZ"]].to_numpy()
        assert np.abs(result.joint_centres[side + jc] - expected).max() < 1e-3


def test_static_trial_angles_are_zero_with_chord_and_medial_markers(static, calibrated):
    """All angles of the standing trial are 0; with medial markers KJC/AJC are midpoints."""
    chord = compute_lower_body(static, calibrated)
    medial = compute_lower_body(static, calibrated, use_medial_markers=True)
    for result in (chord, medial):
        for side, joint in itertools.product("LR", TRUTH_JOINTS):
            np.testing.assert_allclose(result.angles[f"{side}{joint}Angles"], 0.0, atol=1e-3)
    for side in "LR":
        mid = 0.5 * (static.marker(side + "KNE") + static.marker(side + "KNM"))
        np.testing.assert_allclose(medial.joint_centres[side + "KJC"], mid, atol=1e-12)
        np.testing.assert_allclose(chord.joint_centres[side + "KJC"], mid, atol=1e-3)
    assert any("medial" in note for note in messages(medial.notes))


def test_exported_virtual_markers_give_back_the_angles(walking, subject):
    result = compute_lower_body(walking, subject)
    again = angles_from_virtual_markers(result.virtual_markers)
    for name in ANGLE_NAMES:
        np.testing.assert_allclose(again[name], result.angles[name], atol=1e-9)
    # Nexus's axis lengths: segment lengths, not a fixed 100 mm
    vm = result.virtual_markers
    np.testing.assert_allclose(norm(vm["LFEP"] - vm["LFEO"]), 410.0, atol=1e-3)
    np.testing.assert_allclose(norm(vm["LTIA"] - vm["LTIO"]), 395.0 - 105.0 / 5, atol=1e-3)
    np.testing.assert_allclose(norm(vm["LFOA"] - vm["LFOO"]), 190.0 - 7.0, atol=1e-3)


# ----------------------------------------------------------------------- decomposition
def _pig_angles_from_generator(side: str, joint: str, angles: np.ndarray) -> np.ndarray:
    """Build the joint rotation with the synthetic generator's own (independent) code and
    decompose it with ours."""
    rel = joint_rotation(angles[:, 0], angles[:, 1], angles[:, 2], side, joint.lower())
    if joint == "Ankle":
        rel = rel @ PIG_FOOT
    return joint_angles(np.eye(3), rel, joint, side)


@pytest.mark.parametrize(("side", "joint"), list(itertools.product("LR", TRUTH_JOINTS)))
def test_decomposition_round_trips_known_rotations(side, joint):
    rng = np.random.default_rng(7)
    angles = rng.uniform([-70, -40, -60], [70, 40, 60], size=(200, 3))
    np.testing.assert_allclose(_pig_angles_from_generator(side, joint, angles), angles, atol=1e-9)


def test_angle_table_mirrors_left_and_right():
    for joint, (order, signs, offsets) in ANGLE_TABLE.items():
        assert sorted(order) == [0, 1, 2] and offsets[1:] == (0.0, 0.0)
        rng = np.random.default_rng(1)
        frames = axis_rotation(2, rng.uniform(-1, 1, 20)) @ axis_rotation(0, rng.uniform(-1, 1, 20))
        left, right = joint_angles(np.eye(3), frames, joint, "L"), joint_angles(np.eye(3), frames, joint, "R")
        np.testing.assert_allclose(left[:, 0], right[:, 0])
        np.testing.assert_allclose(left[:, 1:], -right[:, 1:], atol=1e-12)


def test_cardan_yxz_of_a_known_product():
    a, b, c = np.radians([25.0, -12.0, 140.0])
    rotation = (axis_rotation(1, a) @ axis_rotation(0, b) @ axis_rotation(2, c))[None]
    np.testing.assert_allclose(cardan_yxz(rotation), [[25.0, -12.0, 140.0]], atol=1e-12)


@pytest.mark.parametrize("side", ["L", "R"])
def test_clinical_sign_meanings(side):
    """Positive outputs mean flexion, adduction, internal rotation on both sides."""
    s = 1.0 if side == "L" else -1.0  # +y is the left side: lateral for L, medial for R
    ten = math.radians(10)
    one = np.eye(3)

    def angle(joint, distal):
        return joint_angles(one, distal[None], joint, side)[0]

    # hip: knee forward (flexion), knee towards the midline (adduction), anterior face
    # of the thigh turned medially (internal rotation)
    np.testing.assert_allclose(angle("Hip", axis_rotation(1, -ten)), [10, 0, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Hip", axis_rotation(0, -s * ten)), [0, 10, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Hip", axis_rotation(2, -s * ten)), [0, 0, 10], atol=1e-9)
    # knee: ankle backwards (flexion); ankle towards the midline (varus)
    np.testing.assert_allclose(angle("Knee", axis_rotation(1, ten)), [10, 0, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Knee", axis_rotation(0, -s * ten)), [0, 10, 0], atol=1e-9)
    # ankle: toe up (dorsiflexion), toe medial (internal rotation), and Nexus's "Y+":
    # foot turned about its long axis with the lateral border up
    np.testing.assert_allclose(angle("Ankle", axis_rotation(1, -ten) @ PIG_FOOT), [10, 0, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Ankle", axis_rotation(2, -s * ten) @ PIG_FOOT), [0, 0, 10], atol=1e-9)
    np.testing.assert_allclose(angle("Ankle", axis_rotation(0, s * ten) @ PIG_FOOT), [0, 10, 0], atol=1e-9)
    # pelvis: anterior tilt, own side up, own side forward
    np.testing.assert_allclose(angle("Pelvis", axis_rotation(1, ten)), [10, 0, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Pelvis", axis_rotation(0, s * ten)), [0, 10, 0], atol=1e-9)
    np.testing.assert_allclose(angle("Pelvis", axis_rotation(2, -s * ten)), [0, 0, 10], atol=1e-9)


# ----------------------------------------------------------------------- joint centres
def test_chord_joint_centre_satisfies_its_definition():
    rng = np.random.default_rng(3)
    n = 500
    hip = rng.normal(0, 50, (n, 3)) + [0, 0, 900]
    knee_marker = rng.normal(0, 50, (n, 3)) + [0, 80, 500]
    wand = rng.normal(0, 50, (n, 3)) + [0, 120, 700]
    offset = 59.5
    centre = chord_joint_centre(wand, hip, knee_marker, offset)
    np.testing.assert_allclose(norm(centre - knee_marker), offset, rtol=1e-12)
    assert np.abs(dot(unit(centre - knee_marker), unit(hip - centre))).max() < 1e-12
    normal = unit(cross(wand - knee_marker, hip - knee_marker))
    assert np.abs(dot(normal, centre - knee_marker)).max() < 1e-9  # in the plane
    # the rotation from the marker-to-hip line towards the centre is +normal (the side
    # Plug-in Gait picks)
    turn = dot(cross(unit(hip - knee_marker), unit(centre - knee_marker)), normal)
    assert np.all(turn > 0)
    # impossible offsets (longer than the marker-to-hip distance) give NaN, not garbage
    far = chord_joint_centre(wand[:1], hip[:1], hip[:1] + [0, 0, -10], offset)
    assert np.all(np.isnan(far))


def test_davis_hip_joint_centre():
    local = davis_hjc_local(900.0, 67.36, 250.0, 7.0, "L")
    np.testing.assert_allclose(local, [-46.817171, 82.714667, -96.585469], atol=1e-6)
    for side in "LR":  # the synthetic generator's independent implementation
        expected = davis_hjc(250.0, 880.0, 860.0, 60.0, 16.0, side)
        np.testing.assert_allclose(davis_hjc_local(870.0, 60.0, 250.0, 8.0, side), expected, atol=1e-12)
    c = 0.115 * 900 - 15.3
    assert local[1] == pytest.approx(125.0 - c * math.sin(0.5))


def test_tibial_torsion_turns_the_knee_tibia_and_the_foot_axis(walking, subject):
    torsion = math.radians(12)
    plain = compute_lower_body(walking, subject)
    for side in "LR":
        twisted = compute_lower_body(walking, subject.with_side(side, tibial_torsion=torsion))
        long = "left" if side == "L" else "right"
        # Nexus' sign: untorsioned = torsioned @ R_z(s * torsion), a positive torsion
        # shows as knee external (negative) rotation on either side
        delta = twisted.angles[side + "KneeAngles"] - plain.angles[side + "KneeAngles"]
        np.testing.assert_allclose(delta, np.tile([0.0, 0.0, -12.0], (walking.n_frames, 1)), atol=1e-9)
        np.testing.assert_array_equal(
            twisted.segment_frames[long + "_tibia_torsioned"], plain.segment_frames[long + "_tibia_torsioned"]
        )
        # the foot's ankle axis is the untorsioned tibia's y axis: the foot turns too
        assert not np.allclose(twisted.segment_frames[long + "_foot"], plain.segment_frames[long + "_foot"])
        for name in ANGLE_NAMES:
            if name[0] != side or name[1:4] in ("Pel", "Hip"):
                np.testing.assert_array_equal(twisted.angles[name], plain.angles[name])
        assert twisted.notes == plain.notes


def _dihedral(axis_from: np.ndarray, axis_to: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Right-handed angle (rad) about ``axis_from -> axis_to`` from ``start`` to ``end``."""
    k = unit(axis_to - axis_from)
    a = start - axis_from
    b = end - axis_from
    a -= k * np.sum(k * a, axis=1)[:, None]
    b -= k * np.sum(k * b, axis=1)[:, None]
    return np.arctan2(np.sum(k * np.cross(a, b), axis=1), np.sum(a * b, axis=1))


@pytest.mark.parametrize("side", ["L", "R"])
def test_wand_rotations_and_ankle_abadd_place_the_joint_centres(walking, subject, side):
    """The definitions of fuzzygait.kinematics.joint_centres, checked geometrically."""
    thigh, shank, abadd = math.radians(9), math.radians(-14), math.radians(7)
    changed = subject.with_side(side, thigh_rotation=thigh, shank_rotation=shank, ankle_abadd=abadd)
    result = compute_lower_body(walking, changed)
    s = 1.0 if side == "L" else -1.0
    hjc, kjc, ajc = (result.joint_centres[side + c] for c in ("HJC", "KJC", "AJC"))
    kne, thi, ank = (walking.marker(side + m) for m in ("KNE", "THI", "ANK"))
    params, radius = changed.side(side), changed.marker_radius
    np.testing.assert_allclose(np.linalg.norm(kne - kjc, axis=1), params.knee_width / 2 + radius, atol=1e-9)
    np.testing.assert_allclose(np.sum(unit(kne - kjc) * unit(hjc - kjc), axis=1), 0.0, atol=1e-12)
    np.testing.assert_allclose(_dihedral(kjc, hjc, kne, thi), s * thigh, atol=1e-10)
    # the ankle: the wand-rotated chord centre turned about ANK towards the KJC
    np.testing.assert_allclose(np.linalg.norm(ank - ajc, axis=1), params.ankle_width / 2 + radius, atol=1e-9)
    chord_angle = np.arccos((params.ankle_width / 2 + radius) / np.linalg.norm(kjc - ank, axis=1))
    at_ank = np.arccos(np.sum(unit(ajc - ank) * unit(kjc - ank), axis=1))
    np.testing.assert_allclose(chord_angle - at_ank, abadd, atol=1e-10)
    unabducted = compute_lower_body(walking, changed.with_side(side, ankle_abadd=0.0)).joint_centres[side + "AJC"]
    np.testing.assert_allclose(_dihedral(unabducted, kjc, ank, walking.marker(side + "TIB")), s * shank, atol=1e-10)
    assert result.notes == []


# ----------------------------------------------------------------------- progression
@pytest.mark.parametrize(
    ("travel", "forward"), [((1, 0), (1, 0)), ((-1, 0.2), (-1, 0)), ((0.1, 1), (0, 1)), ((0, -1), (0, -1))]
)
def test_progression_axis_follows_the_walk(travel, forward):
    n = 50
    origin = np.zeros((n, 3))
    origin[:, :2] = np.linspace(0, 2000, n)[:, None] * np.array(travel)
    origin[:5] = np.nan  # unseen frames are skipped
    frame = progression_frame(origin, np.tile([0.0, 1.0, 0.0], (n, 1)))
    np.testing.assert_allclose(frame[:2, 0], forward)
    np.testing.assert_allclose(frame[:, 2], [0, 0, 1])
    np.testing.assert_allclose(frame[:, 1], np.cross([0, 0, 1], frame[:, 0]))


def test_standing_progression_uses_the_facing_direction():
    n = 10
    origin = np.zeros((n, 3)) + np.random.default_rng(0).normal(0, 2, (n, 3))
    facing = np.tile(unit(np.array([0.2, -1.0, 0.1])), (n, 1))
    np.testing.assert_allclose(progression_frame(origin, facing)[:, 0], [0, -1, 0])


def test_synthetic_static_trial_written_by_the_generator_is_calibrated_identically(subject):
    """The generator's in-memory static trial (float64) gives the same offsets."""
    exact = static_calibration(make_static_trial(), replace(subject))
    assert exact.left.static_plant_flex == pytest.approx(math.atan2(60, 140), abs=1e-12)
    assert exact.right.static_rot_off == pytest.approx(0.0, abs=1e-12)
    assert SubjectGeometry().parameters()["LStaticPlantFlex"] == pytest.approx(math.atan2(60, 140))


@pytest.mark.parametrize("sole_delta", [0.0, 10.0])
def test_flat_foot_option_uses_the_sole_delta(static, subject, sole_delta):
    """Feet flat on the floor with HEE and TOE 30 mm up: foot-flat with a heel raise of
    SoleDelta tilts the anatomical long axis (TOE->HEE, 190 mm) heel-up by
    atan(SoleDelta / 190)."""
    shod = subject.with_side("L", sole_delta=sole_delta).with_side("R", sole_delta=sole_delta)
    flat = static_calibration(static, shod, flat_foot=True)
    for side in "LR":
        expected = math.atan2(60, 140) - math.atan(sole_delta / 190.0)
        assert flat.side(side).static_plant_flex == pytest.approx(expected, abs=1e-7)
        assert flat.side(side).static_rot_off == pytest.approx(0.0, abs=1e-7)
