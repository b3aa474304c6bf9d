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


#: A Nexus-like subject file: parameters with and without VALUE, and a skeleton.
TEMPLATE = """<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<KinematicModel MODEL="PlugInGait FullBody Ai" VERSION="3.2">
\t<Parameters>
\t\t<StaticParameter NAME="Bodymass" VALUE="1" PRIOR="65" REQUIRED="true" QUANTITY="mass"/>
\t\t<StaticParameter NAME="LeftTibialTorsion" PRIOR="0" HIDDEN="false" QUANTITY="angle"/>
\t\t<StaticParameter NAME="RightLegLength" QUANTITY="length" VALUE="2"/>
\t\t<StaticParameter NAME="HeadOffset" VALUE="0.25" PRIOR="0" QUANTITY="angle"/>
\t</Parameters>
\t<Skeleton><Segment NAME="Pelvis"/></Skeleton>
\t<MarkerSet><Markers><Marker NAME="LASI"/></Markers></MarkerSet>
</KinematicModel>
"""


def test_vsk_from_a_template_keeps_it_and_sets_every_value(tmp_path: Path) -> None:
    """Nexus' own file, values updated: what it does not know (the skeleton, marker set,
    other parameters, attribute order) is kept byte for byte."""
    (tmp_path / "nexus.vsk").write_text(TEMPLATE)
    subject = _awkward_subject()
    path = write_subject(subject, tmp_path / "cal.vsk", comments=["calibrated"], vsk_template=tmp_path / "nexus.vsk")
    text = path.read_text()
    assert read_vsk(path) == subject
    root = ET.fromstring(text.encode())
    values = {e.attrib["NAME"]: e.attrib for e in root.iter("StaticParameter")}
    assert float(values["LeftTibialTorsion"]["VALUE"]) == -math.pi / 7 and values["LeftTibialTorsion"]["PRIOR"] == "0"
    assert float(values["RightLegLength"]["VALUE"]) == subject.right.leg_length
    assert values["HeadOffset"]["VALUE"] == "0.25"  # not ours: kept
    assert set(subject_vsk_text(subject)) and len(values) == len(subject_values(subject)) + 1
    for kept in ('<Skeleton><Segment NAME="Pelvis"/></Skeleton>', '<Marker NAME="LASI"/>',
                 'NAME="Bodymass" VALUE="', '" PRIOR="65" REQUIRED="true" QUANTITY="mass"/>'):  # fmt: skip
        assert kept in text
    assert "<!-- calibrated -->" in text


def test_a_template_without_parameters_is_refused(tmp_path: Path) -> None:
    (tmp_path / "bad.vsk").write_text("<KinematicModel/>")
    with pytest.raises(ParameterError, match="bad.vsk.*no <Parameters>|no <Parameters>"):
        write_subject(_awkward_subject(), tmp_path / "cal.vsk", vsk_template=tmp_path / "bad.vsk")
    assert not (tmp_path / "cal.vsk").exists()


@needs_shared
def test_nexus_vsk_template_calibrated_keeps_its_model(tmp_path: Path) -> None:
    """Test.vsk (Nexus' Plug-in Gait FullBody Ai) with new offsets: same elements, in the
    same order, every non-parameter line unchanged, our values read back."""
    source = shared_file("vicon", "Test.vsk")
    nexus = read_vsk(source)
    changed = nexus.with_side("L", thigh_rotation=0.125, tibial_torsion=-0.25)
    path = write_subject(changed, tmp_path / "cal.vsk", vsk_template=source)
    assert read_vsk(path) == changed
    old, new = ET.parse(source).getroot(), ET.parse(path).getroot()
    names = [{e.attrib["NAME"] for e in root.iter("StaticParameter")} for root in (old, new)]
    assert names[1] - names[0] == {"MarkerDiameter"}  # the one parameter Test.vsk lacks, added
    assert [e.tag for e in old.iter() if e.tag != "StaticParameter"] == [
        e.tag for e in new.iter() if e.tag != "StaticParameter"
    ]
    old_lines, new_lines = source.read_text().splitlines(), path.read_text().splitlines()
    assert [x for x in old_lines if "StaticParameter" not in x] == [x for x in new_lines if "StaticParameter" not in x]


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
