"""The bundled CGM 2.4 session (sample_data/cgm24_*): it reads back, its truth tables say
what the README says, and each model version reproduces the columns the README says it
does (from the float32 C3D files, no low-pass)."""

from __future__ import annotations

import tomllib

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from fuzzygait.io import read_c3d
from fuzzygait.synthetic.cgm24 import CGM24_DYNAMIC_LABELS, CGM24_STATIC_LABELS
from fuzzygait.synthetic.cgm24_sample import (
    CGM24_SAMPLE_FILES,
    cgm24_joint_centre_columns,
    cgm24_session,
    cgm24_truth_angle_columns,
    rot_pelvis_angles,
)
from fuzzygait.workflows.angles import Preprocessing, run_angles
from support import SAMPLE_DATA

BOUND_DEG = 0.01  # the noise-free bound; float32 markers give ~3e-4 deg
BOUND_MM = 1e-3
NO_FILTER = Preprocessing(filter=False)


def _require() -> None:
    missing = [n for n in CGM24_SAMPLE_FILES if not (SAMPLE_DATA / n).exists()]
    if missing:
        pytest.skip(f"sample_data lacks {missing}; run python -m fuzzygait.synthetic sample_data")


@pytest.fixture(scope="module")
def files():
    _require()
    return (read_c3d(SAMPLE_DATA / "cgm24_static.c3d"), read_c3d(SAMPLE_DATA / "cgm24_walking.c3d"),
            pd.read_csv(SAMPLE_DATA / "cgm24_walking_truth_angles.csv"),
            pd.read_csv(SAMPLE_DATA / "cgm24_walking_truth_joint_centres.csv"))  # fmt: skip


@pytest.fixture(scope="module")
def generated():
    return cgm24_session()


def xyz(table: pd.DataFrame, name: str) -> np.ndarray:
    return table[[f"{name}_{a}" for a in "XYZ"]].to_numpy()


def test_files_read_back(files, generated) -> None:
    static, walking, angles, centres = files
    g_static, g_walking, _ = generated
    assert static.marker_labels == list(CGM24_STATIC_LABELS)
    assert walking.marker_labels == list(CGM24_DYNAMIC_LABELS)
    assert (walking.n_frames, walking.rate, static.n_frames) == (512, 100.0, 200)
    assert np.abs(static.markers - g_static.markers).max() < 1e-3
    assert np.abs(walking.markers - g_walking.markers).max() < 1e-3
    assert [(e.label, e.context) for e in walking.events] == [(e.label, e.context) for e in g_walking.events]
    subject = tomllib.loads((SAMPLE_DATA / "cgm24_subject.toml").read_text())
    assert subject == g_walking.parameters
    for name, value in subject.items():
        assert walking.parameters[name] == pytest.approx(value, rel=1e-6, abs=1e-6)
    assert list(angles.columns) == ["frame", "time_s", *cgm24_truth_angle_columns()]
    assert list(centres.columns) == ["frame", "time_s", *cgm24_joint_centre_columns()]
    assert angles["frame"].tolist() == list(walking.frames)


def test_truth_pelvis_is_the_plug_in_gait_pelvis_in_rot_order(files, generated) -> None:
    """Same rotation as walking_truth_angles.csv's pelvis (TOR), decomposed rotation first."""
    _, _, angles, _ = files
    _, _, truth = generated
    tor_csv = pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv")
    for side, s in (("L", 1.0), ("R", -1.0)):
        tor = np.radians(xyz(tor_csv, f"{side}PelvisAngles"))
        rot = np.radians(xyz(angles, f"{side}PelvisAngles"))
        r_tor = Rotation.from_euler("YXZ", tor * [1, s, -s]).as_matrix()  # R_y(X) R_x(sY) R_z(-sZ)
        r_rot = Rotation.from_euler("ZXY", rot[:, ::-1] * [-s, s, 1]).as_matrix()  # R_z(-sZ) R_x(sY) R_y(X)
        assert np.abs(r_tor - r_rot).max() < 1e-8
        assert np.abs(rot - tor).max() > np.radians(0.05)  # the orders do differ
        assert np.abs(xyz(truth, f"{side}PelvisAngles") - xyz(tor_csv, f"{side}PelvisAngles")).max() < 1e-8
        for name in ("Hip", "Knee", "Ankle", "FootProgress", "ForeFoot"):
            assert np.abs(xyz(angles, f"{side}{name}Angles") - xyz(truth, f"{side}{name}Angles")).max() < 1e-8


def test_rot_pelvis_of_zero_and_of_pure_rotation() -> None:
    assert np.abs(rot_pelvis_angles(np.zeros((1, 3)), "L")).max() == 0.0
    for side in "LR":  # a single rotation about one axis is the same in any order
        single = np.array([[7.0, 0, 0], [0, -3.0, 0], [0, 0, 11.0]])
        assert np.abs(rot_pelvis_angles(single, side) - single).max() < 1e-12


# version -> truth columns it reproduces (sample_data/README.md's table)
REPRODUCES = {
    "cgm1.0": ("Pelvis@PiG",),
    "cgm1.1": ("Pelvis",),
    "cgm2.1": ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress", "HJC", "KJC", "AJC"),
    "cgm2.3": ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress", "HJC", "KJC", "AJC"),
    "cgm2.4": ("Pelvis", "Hip", "Knee", "Ankle", "FootProgress", "ForeFoot", "HJC", "KJC", "AJC", "FJC"),
}


@pytest.mark.parametrize("model", list(REPRODUCES))
def test_model_reproduces_its_truth_columns(files, model: str) -> None:
    static, walking, angles, centres = files
    run = run_angles(walking, static=static, subject_file=SAMPLE_DATA / "cgm24_subject.toml",
                     preprocessing=NO_FILTER, model=model)  # fmt: skip
    result = run.result
    assert result.model == model and result.unavailable == {}
    pig = pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv")
    for side in "LR":
        for item in REPRODUCES[model]:
            name, _, order = item.partition("@")
            if name.endswith("JC"):
                error = np.abs(result.joint_centres[side + name] - xyz(centres, side + name)).max()
                assert error <= BOUND_MM, (model, side + name, error)
                continue
            truth = pig if order == "PiG" else angles
            error = np.abs(result.angles[f"{side}{name}Angles"] - xyz(truth, f"{side}{name}Angles")).max()
            assert error <= BOUND_DEG, (model, side + name, error)
    if "Hip" not in REPRODUCES[model]:  # Davis hips on a Hara session: degrees off
        assert np.abs(result.angles["LHipAngles"] - xyz(angles, "LHipAngles")).max() > 1.0
    if "ForeFoot" not in REPRODUCES[model]:
        assert "LForeFootAngles" not in result.angles


def test_auto_picks_the_richest_version(files) -> None:
    static, walking, _, _ = files
    run = run_angles(walking, static=static, preprocessing=NO_FILTER, model="auto")
    assert run.result.model == "cgm2.4"
