"""The synthetic CGM 2.4 session with a known tibial torsion (issue 36), checked against
reconstructions independent of the generator's own formulas and of fuzzygait.kinematics."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.synthetic.cgm24 import (
    Cgm24Geometry,
    cgm23_foot_rotation,
    cgm24_static_pose,
    cgm24_walking_state,
    make_cgm24_static,
    make_cgm24_walking,
)
from fuzzygait.synthetic.leg_model import PIG_FOOT_AXES, joint_rotation, rot_z

TORSION = (-0.35, 0.15)  # rad, left external, right internal
GEOMETRY = Cgm24Geometry(tibial_torsion=TORSION)


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def uncorrected(ajc: np.ndarray, toe: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Plug-in Gait's uncorrected foot (its axes: z TOE -> AJC, x = axis × z, y = z × x)."""
    z = unit(ajc - toe)
    x = unit(np.cross(axis, z))
    return np.stack([x, np.cross(z, x), z], axis=-1)


@pytest.fixture(scope="module")
def walking_pose():
    times = np.arange(0, 1.2, 0.01)
    return cgm24_walking_state(times, GEOMETRY)


@pytest.mark.parametrize("side", ["L", "R"])
def test_static_markers_give_the_torsion(side: str) -> None:
    """From the static markers alone: the knee axis (KNE - KNM) seen from the ankle axis
    (ANK - MED) about AJC -> KJC is at ``90° + s τ`` (pyCGM2's torsion ``s (φ - 90°)``)."""
    s = 1.0 if side == "L" else -1.0
    pose = cgm24_static_pose(geometry=GEOMETRY)
    m = pose.markers
    z = unit(pose.joint_centres[side + "KJC"] - pose.joint_centres[side + "AJC"])
    y = unit(s * (m[side + "ANK"] - m[side + "MED"]))
    x = np.cross(y, z)
    knee = s * (m[side + "KNE"] - m[side + "KNM"])
    phi = np.arctan2(np.sum(knee * y, axis=1), np.sum(knee * x, axis=1))
    torsion = s * (phi - np.pi / 2)
    assert torsion == pytest.approx(np.full(len(torsion), TORSION["LR".index(side)]), abs=1e-12)
    # the medial markers still straddle the centres; the soles stay on the floor
    assert np.abs(0.5 * (m[side + "ANK"] + m[side + "MED"]) - pose.joint_centres[side + "AJC"]).max() < 1e-9
    assert np.abs(0.5 * (m[side + "KNE"] + m[side + "KNM"]) - pose.joint_centres[side + "KJC"]).max() < 1e-9
    assert np.abs(pose.sole_points[side + "HeelSole"][:, 2]).max() < 1e-9


@pytest.mark.parametrize("side", ["L", "R"])
def test_shank_is_the_knee_frame_turned_by_the_torsion(walking_pose, side: str) -> None:
    """``R_shank = R_thigh @ R_knee(curves) @ R_z(-s τ)``: the knee curves carry the knee
    axis, the posed shank (truth knee angles) the ankle axis."""
    pose, angles, _, _ = walking_pose
    s, torsion = (1.0 if side == "L" else -1.0), TORSION["LR".index(side)]
    knee = angles[(side, "knee")].copy()
    knee[:, 2] -= np.degrees(torsion)  # the curves before the torsion
    expected = pose.rotations[side + "Thigh"] @ joint_rotation(*knee.T, side, "knee") @ rot_z(-s * torsion)
    assert np.abs(pose.rotations[side + "Shank"] - expected).max() < 1e-12


@pytest.mark.parametrize("side", ["L", "R"])
def test_cgm23_foot_is_pycgm2s_construction(walking_pose, side: str) -> None:
    """The generator's CGM 2.3 foot = ``U(TOE, AJC, y_knee) R_z(δ) C`` built step by step as
    pyCGM2 does: static ``R_z(δ) = U(y_knee)^T U(y_shank)`` and ``C = U(y_shank)^T F`` (the
    static foot), dynamic ``y_knee`` the knee frame's y axis; in Plug-in Gait's foot axes."""
    s = 1.0 if side == "L" else -1.0
    turn = rot_z(s * TORSION["LR".index(side)])[0]
    static = cgm24_static_pose(geometry=GEOMETRY)
    shank, ajc, toe = static.rotations[side + "Shank"], static.joint_centres[side + "AJC"], static.markers[side + "TOE"]
    plain, turned = uncorrected(ajc, toe, shank[:, :, 1]), uncorrected(ajc, toe, (shank @ turn)[:, :, 1])
    delta = np.swapaxes(turned, 1, 2) @ plain
    correction = np.swapaxes(plain, 1, 2) @ static.rotations[side + "Foot"] @ PIG_FOOT_AXES
    assert abs(correction[0][1, 1] - 1.0) < 1e-12  # C = R_y(-StaticPlantFlex): no StaticRotOff
    pose = walking_pose[0]
    shank = pose.rotations[side + "Shank"]
    foot = uncorrected(pose.joint_centres[side + "AJC"], pose.markers[side + "TOE"], (shank @ turn)[:, :, 1])
    expected = foot @ delta[0] @ correction[0] @ PIG_FOOT_AXES.T
    assert np.abs(cgm23_foot_rotation(pose, GEOMETRY, side) - expected).max() < 1e-12
    assert np.degrees(np.abs(expected - pose.rotations[side + "Foot"]).max()) > 0.5  # not the hindfoot


def test_the_cgm23_truth_shares_the_markers_and_all_but_the_foot() -> None:
    trial, cgm23 = make_cgm24_walking(n_cycles=1, geometry=GEOMETRY, foot_truth="cgm2.3")
    again, hindfoot = make_cgm24_walking(n_cycles=1, geometry=GEOMETRY)
    assert np.array_equal(trial.markers, again.markers)
    assert trial.parameters == again.parameters and trial.parameters["LTibialTorsion"] == 0.0
    foot = [c for c in cgm23.columns if c[1:].startswith(("AnkleAngles", "FootProgressAngles"))]
    assert len(foot) == 12
    others = [c for c in cgm23.columns if c not in foot]
    assert cgm23[others].equals(hindfoot[others])
    assert np.abs(cgm23[foot].to_numpy() - hindfoot[foot].to_numpy()).max() > 1.0


def test_twisted_static_moves_only_the_shank_and_foot() -> None:
    """The static trial: pelvis and thigh markers as without torsion; shank and foot
    markers turned about the vertical through the KJC (the knee rotation ``τ``)."""
    plain, twisted = make_cgm24_static(), make_cgm24_static(geometry=GEOMETRY)
    assert twisted.marker_labels == plain.marker_labels
    for label in plain.marker_labels:
        moved = np.abs(twisted.marker(label) - plain.marker(label)).max()
        still = label[1:] in ("ASI", "PSI", "THAP", "THAD", "THI", "KNE", "KNM")
        assert (moved < 1e-9) == still, label


def test_bad_torsion_and_foot_truth_are_refused() -> None:
    with pytest.raises(ParameterError, match="tibial_torsion must be"):
        Cgm24Geometry(tibial_torsion=(0.1,))  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="tibial_torsion must be"):
        Cgm24Geometry(tibial_torsion=(20.0, 0.0))  # degrees instead of rad
    with pytest.raises(ParameterError, match="foot_truth must be one of"):
        make_cgm24_walking(n_cycles=1, foot_truth="cgm2.5")
