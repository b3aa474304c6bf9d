"""Writing subject files (TOML and Vicon-style .vsk) that read back to the same parameters."""

from __future__ import annotations

import math
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import pytest
from support import SAMPLE_DATA, needs_shared, shared_file

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.subject import read_subject, read_vsk, subject_values, subject_vsk_text, write_subject
from fuzzygait.io.tomlfile import toml_text


def _awkward_subject():
    """Sample subject with floats that need all 17 digits, a regression left to itself
    (no AsisTrocanterDistance) and every offset non-zero."""
    subject = replace(read_subject(SAMPLE_DATA / "subject.toml"), marker_diameter=16.0, inter_asis_distance=None)
    subject = subject.with_side("L", asis_trochanter_distance=None, thigh_rotation=0.1 + 0.2, shank_rotation=-1e-7,
                                tibial_torsion=-math.pi / 7, ankle_abadd=1 / 3, static_rot_off=-2.5e-17)  # fmt: skip
    return subject.with_side("R", thigh_rotation=-0.3, sole_delta=4.25, static_plant_flex=math.e / 10)


@pytest.mark.parametrize("suffix", [".toml", ".vsk"])
def test_written_subject_reads_back_equal(tmp_path: Path, suffix: str) -> None:
    subject = _awkward_subject()
    path = write_subject(subject, tmp_path / f"s{suffix}", comments=["a comment -- with dashes"],
                         metadata={"method": "KAD+MED", "flat_foot": True})  # fmt: skip
    back = read_subject(path)
    assert back == subject
    assert back.left.asis_trochanter_distance is None and back.inter_asis_distance is None
    assert subject_values(back) == subject_values(subject)


def test_toml_file_carries_the_comments_and_the_calibration_table(tmp_path: Path) -> None:
    path = write_subject(_awkward_subject(), tmp_path / "s.toml", comments=["calibrated"],
                         metadata={"method": "KAD", "flat_foot": False, "static": 'odd "name".c3d'})  # fmt: skip
    text = path.read_text()
    assert text.startswith("# calibrated\n")
    document = tomllib.loads(text)
    assert document["calibration"] == {"method": "KAD", "flat_foot": False, "static": 'odd "name".c3d'}
    assert document["LThighRotation"] == 0.1 + 0.2 and "LAsisTrocanterDistance" not in document


def test_vsk_uses_nexus_names_and_radians() -> None:
    subject = _awkward_subject()
    root = ET.fromstring(subject_vsk_text(subject, ["note"]))
    values = {e.attrib["NAME"]: e.attrib for e in root.iter("StaticParameter")}
    assert float(values["LeftTibialTorsion"]["VALUE"]) == -math.pi / 7
    assert values["LeftTibialTorsion"]["QUANTITY"] == "angle" and values["RightLegLength"]["QUANTITY"] == "length"
    assert {"Bodymass", "Height", "MarkerDiameter", "RightStaticPlantFlex", "LeftAnkleAbAdd"} <= set(values)
    assert not any(name.startswith(("L", "R")) and name[1].isupper() for name in values)  # Left/Right, not L/R


@needs_shared
def test_nexus_vsk_rewritten_reads_back_equal(tmp_path: Path) -> None:
    nexus = read_vsk(shared_file("vicon", "Test.vsk"))
    assert read_vsk(write_subject(nexus, tmp_path / "again.vsk")) == nexus


def test_bad_output_is_refused_and_nothing_written(tmp_path: Path) -> None:
    subject = read_subject(SAMPLE_DATA / "subject.toml")
    with pytest.raises(ParameterError, match=r"\.toml or \.vsk"):
        write_subject(subject, tmp_path / "s.json")
    with pytest.raises(ParameterError, match="LLegLength"):
        write_subject(subject.with_side("L", leg_length=0.9), tmp_path / "s.toml")
    assert list(tmp_path.iterdir()) == []


def test_toml_text_refuses_what_toml_cannot_hold() -> None:
    assert toml_text({"a": 1, "b": "x", "t": {"c": 2.5}}) == 'a = 1\nb = "x"\n\n[t]\nc = 2.5\n'
    with pytest.raises(ParameterError, match="a: cannot write nan"):
        toml_text({"a": float("nan")})
