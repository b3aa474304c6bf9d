"""pyCGM2 ``.mp`` subject files (YAML groups MandatoryParameters / OptionalParameters)."""

from __future__ import annotations

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
