"""Subject parameters from TOML, Vicon .vsk and the C3D PROCESSING group."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from support import SAMPLE_DATA, needs_shared, shared_file

from fuzzygait.core.errors import ParameterError
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import (
    asis_trochanter_regression,
    read_subject,
    read_subject_toml,
    read_vsk,
    subject_from_processing,
)

MINIMAL = {
    "LLegLength": 900.0, "RLegLength": 905.0,
    "LKneeWidth": 100.0, "RKneeWidth": 101.0,
    "LAnkleWidth": 70.0, "RAnkleWidth": 71.0,
}  # fmt: skip


@needs_shared
def test_vsk_and_processing_group_agree() -> None:
    """Test.vsk is the subject file Vicon used for Movement_trial.c3d."""
    from_vsk = read_vsk(shared_file("vicon", "Test.vsk"))
    from_c3d = subject_from_processing(read_c3d(shared_file("vicon", "Movement_trial.c3d")).parameters)
    assert from_vsk == from_c3d
    assert from_vsk.left.leg_length == 877.0 and from_vsk.right.knee_width == 139.0
    assert from_vsk.inter_asis_distance == 306.0 and from_vsk.body_mass == 85.0
    assert from_vsk.left.static_plant_flex == pytest.approx(0.25269871950149536, abs=1e-12)
    # LeftTibialTorsion has no VALUE in the file: an unset optional parameter
    assert from_vsk.left.tibial_torsion == 0.0


@needs_shared
def test_asis_trochanter_regression_matches_vicon() -> None:
    subject = read_vsk(shared_file("vicon", "Test.vsk"))
    for side in (subject.left, subject.right):
        assert asis_trochanter_regression(side.leg_length) == pytest.approx(
            side.asis_trochanter_distance, abs=1e-4
        )


def test_regression_used_when_absent() -> None:
    subject = subject_from_processing(MINIMAL)
    assert subject.left.asis_trochanter_distance is None
    assert subject.left.asis_trochanter == pytest.approx(0.1288 * 900.0 - 48.56)
    assert subject.marker_diameter == 14.0 and subject.marker_radius == 7.0
    assert subject.inter_asis_distance is None


def test_sample_subject_toml() -> None:
    subject = read_subject(SAMPLE_DATA / "subject.toml")
    assert subject.left.leg_length == 900.0 and subject.right.ankle_width == 70.0
    assert subject.inter_asis_distance == 250.0


def test_missing_required_values_are_all_named(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text("LLegLength = 900.0\nRLegLength = 900.0\nLKneeWidth = 100.0\n")
    with pytest.raises(ParameterError) as info:
        read_subject_toml(path)
    message = str(info.value)
    for name in ("RKneeWidth", "LAnkleWidth", "RAnkleWidth"):
        assert name in message
    assert "LLegLength" not in message.split("missing")[1]
    assert str(path) in message


@pytest.mark.parametrize(
    ("name", "value"),
    [("LLegLength", 0.9), ("RKneeWidth", -100.0), ("LTibialTorsion", 15.0), ("MarkerDiameter", 0.0)],
)
def test_implausible_values_are_named(name: str, value: float) -> None:
    values = {**MINIMAL, name: value}
    with pytest.raises(ParameterError, match=name):
        subject_from_processing(values)


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="no such subject file"):
        read_subject(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("LLegLength = = 3")
    with pytest.raises(ParameterError, match="not a valid TOML"):
        read_subject(bad)
    vsk = tmp_path / "bad.vsk"
    vsk.write_text("<KinematicModel><Parameters>")
    with pytest.raises(ParameterError, match="not a valid Vicon"):
        read_subject(vsk)
    with pytest.raises(ParameterError, match="use .toml, .vsk, a Vicon Nexus or pyCGM2 .mp or a QTM session.xml"):
        read_subject(tmp_path / "s.json")


def test_processing_round_trip() -> None:
    subject = subject_from_processing({**MINIMAL, "LTibialTorsion": 0.1, "InterAsisDistance": 240.0})
    again = subject_from_processing(subject.to_processing())
    assert again == subject.with_side("L", asis_trochanter_distance=subject.left.asis_trochanter).with_side(
        "R", asis_trochanter_distance=subject.right.asis_trochanter
    )
    assert math.isclose(again.left.tibial_torsion, 0.1)
