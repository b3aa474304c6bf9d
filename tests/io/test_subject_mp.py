""".mp subject files of both kinds: pyCGM2 (YAML groups MandatoryParameters / OptionalParameters, or
the older JSON) and Vicon Nexus (``$Name = value`` lines, angles in degrees); what 0 means; one-line errors."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.subject import read_subject

MP = """MandatoryParameters:
  Bodymass: 71.0
  Height: 1780.0
  LeftLegLength: 860.0
  LeftKneeWidth: 102.0
  RightLegLength: 865.0
  RightKneeWidth: 103.4
  LeftAnkleWidth: 75.3
  RightAnkleWidth: 72.9
  LeftSoleDelta: 0
  RightSoleDelta: 0
OptionalParameters:
  InterAsisDistance: 245.0   # mm
  LeftAsisTrocanterDistance: 0
  RightAsisTrocanterDistance: 81.5
  LeftTibialTorsion: 0
"""


def test_mp_file_reads_the_anthropometry(tmp_path: Path) -> None:
    path = tmp_path / "Patient01.mp"
    path.write_text(MP, encoding="utf-8")
    subject = read_subject(path)
    assert (subject.body_mass, subject.height, subject.inter_asis_distance) == (71.0, 1780.0, 245.0)
    assert (subject.left.leg_length, subject.left.knee_width, subject.left.ankle_width) == (860.0, 102.0, 75.3)
    assert (subject.right.leg_length, subject.right.knee_width, subject.right.ankle_width) == (865.0, 103.4, 72.9)
    assert subject.left.asis_trochanter_distance is None  # 0: pyCGM2's "not measured"
    assert subject.right.asis_trochanter_distance == 81.5


def test_mp_json_form_and_bad_files(tmp_path: Path) -> None:
    path = tmp_path / "old.mp"
    path.write_text('{"MandatoryParameters": {"LeftLegLength": 860, "RightLegLength": 865, "LeftKneeWidth": 100, '
                    '"RightKneeWidth": 100, "LeftAnkleWidth": 70, "RightAnkleWidth": 70}}', encoding="utf-8")
    assert read_subject(path).right.leg_length == 865.0
    path.write_text("MandatoryParameters:\n  LeftLegLength: long\n", encoding="utf-8")
    with pytest.raises(ParameterError, match=r"old\.mp: parameter LeftLegLength has non-numeric value 'long'"):
        read_subject(path)
    path.write_text("MandatoryParameters:\n  LeftLegLength: 860\n", encoding="utf-8")
    with pytest.raises(ParameterError, match="missing subject parameters"):
        read_subject(path)


# ----------------------------------------------------------------- Vicon Nexus .mp
NEXUS_MP = """$Bodymass = 75
$Height = 1800
$InterAsisDistance = 0
$LeftLegLength = 900
$LeftAsisTrocanterDistance = 0
$LeftKneeWidth = 100
$LeftAnkleWidth = 70
$LeftTibialTorsion = 15
$LeftSoleDelta = 0
$LeftThighRotation = 0
$LeftShankRotation = -4.5
$LeftStaticPlantFlex = 10
$LeftStaticRotOff = 0
$LeftAnkleAbAdd = 0
$LeftShoulderOffset = 50
$LeftElbowWidth = 80
$LeftWristWidth = 55
$LeftHandThickness = 30
$RightLegLength = 905
$RightAsisTrocanterDistance = 82
$RightKneeWidth = 101
$RightAnkleWidth = 71
$RightTibialTorsion = 0
$RightSoleDelta = 3
$HeadOffset = 0
$MarkerDiameter = 14
"""


def _write(tmp_path: Path, text: str, name: str = "Patient01.mp", encoding: str = "utf-8") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding=encoding)
    return path


@pytest.mark.parametrize("encoding", ["utf-8", "utf-16", "latin-1"])
def test_nexus_mp_is_read(tmp_path: Path, encoding: str) -> None:
    subject = read_subject(_write(tmp_path, NEXUS_MP, encoding=encoding))
    assert (subject.body_mass, subject.height, subject.marker_diameter) == (75.0, 1800.0, 14.0)
    assert (subject.left.leg_length, subject.left.knee_width, subject.left.ankle_width) == (900.0, 100.0, 70.0)
    assert (subject.right.leg_length, subject.right.knee_width, subject.right.ankle_width) == (905.0, 101.0, 71.0)
    assert subject.left.tibial_torsion == pytest.approx(math.radians(15.0))  # degrees in the file
    assert subject.left.shank_rotation == pytest.approx(math.radians(-4.5))
    assert subject.left.static_plant_flex == pytest.approx(math.radians(10.0))
    assert subject.right.sole_delta == 3.0 and subject.right.asis_trochanter_distance == 82.0


def test_nexus_mp_zeros(tmp_path: Path) -> None:
    """0 of a measured length is "compute it"; 0 of an offset or a sole delta is 0."""
    subject = read_subject(_write(tmp_path, NEXUS_MP.replace("$MarkerDiameter = 14", "$MarkerDiameter = 0")))
    assert subject.inter_asis_distance is None  # measured from LASI/RASI
    assert subject.left.asis_trochanter_distance is None  # the leg-length regression
    assert subject.left.asis_trochanter == pytest.approx(0.1288 * 900 - 48.56)
    assert subject.marker_diameter == 14.0  # the default
    assert (subject.left.thigh_rotation, subject.left.static_rot_off, subject.left.sole_delta) == (0.0, 0.0, 0.0)
    unmeasured = NEXUS_MP.replace("$RightKneeWidth = 101", "$RightKneeWidth = 0")
    with pytest.raises(ParameterError, match=r"Patient01\.mp: missing subject parameters RKneeWidth"):
        read_subject(_write(tmp_path, unmeasured))


def test_nexus_mp_short_names_and_other_models(tmp_path: Path) -> None:
    """Older Vicon tools spell the sides L/R ($LLegLength); other models' names, even
    non-numeric, are ignored; the same parameter twice must agree."""
    text = NEXUS_MP.replace("$LeftLegLength", "$LLegLength") + "$MyModelOption = on\n$LLegLength = 900.0\n"
    assert read_subject(_write(tmp_path, text)).left.leg_length == 900.0
    with pytest.raises(ParameterError, match=r"Patient01\.mp: parameter LLegLength is given twice"):
        read_subject(_write(tmp_path, NEXUS_MP + "$LLegLength = 901\n"))


@pytest.mark.parametrize(
    "text, message",
    [
        (NEXUS_MP.replace("$LeftKneeWidth = 100", "$LeftKneeWidth = wide"),
         r"Patient01\.mp: parameter LeftKneeWidth has non-numeric value 'wide'"),
        (NEXUS_MP + "LeftKneeWidth 100\n", r"Patient01\.mp: line 27 'LeftKneeWidth 100' of this Vicon Nexus \.mp "
                                           r"is not '\$Name = value'"),
        (NEXUS_MP.replace("$LeftTibialTorsion = 15", "$LeftTibialTorsion = 250"),
         r"Patient01\.mp: implausible subject parameters: LTibialTorsion=4\.36"),
        ("just some notes\n", r"Patient01\.mp: neither a Vicon Nexus nor a pyCGM2 \.mp file .*expected Vicon "
                              r"Nexus' '\$Name = value' lines .* or pyCGM2's 'MandatoryParameters:'"),
        ("Patient: Jane\nVisit: 2\n", r"Patient01\.mp: neither a Vicon Nexus nor a pyCGM2 \.mp file \(no subject "
                                      r"parameter in it\); expected"),
        ("\n  \n", r"Patient01\.mp: the \.mp file is empty; expected Vicon Nexus'"),
    ],
)  # fmt: skip
def test_bad_mp_files_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ParameterError, match=message) as caught:
        read_subject(_write(tmp_path, text))
    assert "\n" not in str(caught.value)
