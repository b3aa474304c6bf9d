"""One subject in every subject-file format fuzzygait reads gives the same parameters.

The same subject is written as a Vicon ``.vsk``, a TOML file, a C3D ``PROCESSING`` group,
a Vicon Nexus ``.mp`` (long ``$LeftLegLength`` and short ``$LLegLength`` names, angles in
degrees), a pyCGM2 ``.mp`` (YAML and the older JSON) and a QTM ``session.xml`` (UTF-16,
metres); each read back equals it on the fields the format can hold, and leaves the
others to the model (offsets 0, ASIS distances measured or from the regression).
Everything is written in ``tmp_path``: no reference data needed.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest

from fuzzygait.io import read_c3d
from fuzzygait.io.c3d import write_c3d
from fuzzygait.io.subject import (
    SideParameters,
    SubjectParameters,
    read_subject,
    subject_from_processing,
    subject_values,
    write_subject,
)
from support import SAMPLE_DATA

#: Offsets in degrees (left, right), as a clinician enters them in Nexus.
DEGREES = {"TibialTorsion": (12.0, -8.0), "ThighRotation": (-5.0, 4.0), "ShankRotation": (3.0, -2.5),
           "AnkleAbAdd": (1.5, -1.0), "StaticPlantFlex": (14.5, 9.25), "StaticRotOff": (-3.2, 2.75)}  # fmt: skip
_FIELDS = {"TibialTorsion": "tibial_torsion", "ThighRotation": "thigh_rotation", "ShankRotation": "shank_rotation",
           "AnkleAbAdd": "ankle_abadd", "StaticPlantFlex": "static_plant_flex", "StaticRotOff": "static_rot_off"}  # fmt: skip


def _side(index: int, **lengths: float | None) -> SideParameters:
    angles = {_FIELDS[name]: math.radians(pair[index]) for name, pair in DEGREES.items()}
    return SideParameters(**lengths, **angles)  # type: ignore[arg-type]


#: Right AsisTrocanterDistance left to the regression (0 / absent in the files).
SUBJECT = SubjectParameters(
    left=_side(0, leg_length=905.0, knee_width=102.5, ankle_width=72.0, asis_trochanter_distance=80.5,
               sole_delta=0.0),
    right=_side(1, leg_length=910.0, knee_width=103.0, ankle_width=71.0, asis_trochanter_distance=None,
                sole_delta=5.0),
    body_mass=70.0, height=1780.0, marker_diameter=16.0, inter_asis_distance=245.0,
)  # fmt: skip
VALUES = subject_values(SUBJECT)
_SIDE_LENGTHS = ("LegLength", "KneeWidth", "AnkleWidth", "SoleDelta")
#: The PROCESSING names each format can hold.
EVERYTHING = set(VALUES)
PYCGM2 = {"Bodymass", "Height", "InterAsisDistance"} | {
    side + name for side in "LR" for name in (*_SIDE_LENGTHS, "AsisTrocanterDistance")}  # fmt: skip
QTM = {"Bodymass", "Height", "MarkerDiameter"} | {side + name for side in "LR" for name in _SIDE_LENGTHS}


def _nexus_mp(path: Path, short_names: bool = False) -> Path:
    """A Vicon Nexus ``.mp``: ``$Name = value`` lines, angles in degrees, 0 for the
    unmeasured ASIS-trochanter distance, the upper-body parameters too."""
    lines = [f"$Bodymass = {SUBJECT.body_mass:g}", f"$Height = {SUBJECT.height:g}",
             f"$InterAsisDistance = {SUBJECT.inter_asis_distance:g}", "$HeadOffset = 0"]  # fmt: skip
    for index, side in enumerate(("Left", "Right")):
        prefix = side[0] if short_names else side
        for name in (*_SIDE_LENGTHS, "AsisTrocanterDistance"):
            lines.append(f"${prefix}{name} = {VALUES.get(side[0] + name, 0.0):g}")
        lines += [f"${prefix}{name} = {pair[index]:g}" for name, pair in DEGREES.items()]
        lines += [f"${prefix}ShoulderOffset = 50", f"${prefix}ElbowWidth = 80", f"${prefix}WristWidth = 55",
                  f"${prefix}HandThickness = 30"]  # fmt: skip
    lines.append(f"$MarkerDiameter = {SUBJECT.marker_diameter:g}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _long(name: str) -> str:
    return {"L": "Left", "R": "Right"}[name[0]] + name[1:] if name[0] in "LR" and name[1:2].isupper() else name


def _pycgm2_groups() -> dict[str, dict[str, float]]:
    mandatory = ["Bodymass", "Height"] + [side + name for side in "LR" for name in _SIDE_LENGTHS]
    optional = ["InterAsisDistance"] + [side + "AsisTrocanterDistance" for side in "LR"]
    return {"MandatoryParameters": {_long(n): VALUES.get(n, 0.0) for n in mandatory},
            "OptionalParameters": {_long(n): VALUES.get(n, 0.0) for n in optional}}  # fmt: skip


def _pycgm2_yaml(path: Path) -> Path:
    lines = []
    for group, values in _pycgm2_groups().items():
        lines += [f"{group}:", *(f"  {name}: {value:g}" for name, value in values.items())]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _pycgm2_json(path: Path) -> Path:
    path.write_text(json.dumps(_pycgm2_groups(), indent=4), encoding="utf-8")
    return path


def _qtm_session(path: Path) -> Path:
    """A QTM session.xml as QTM writes it (UTF-16, lengths in metres as float32 text)."""
    fields = {"Height": VALUES["Height"] / 1000, "Weight": VALUES["Bodymass"],
              "Marker_diameter": VALUES["MarkerDiameter"] / 1000, "Elbow_width_left": 0.0}  # fmt: skip
    for side, word in (("L", "left"), ("R", "right")):
        for name, field in (("LegLength", "Leg_length"), ("KneeWidth", "Knee_width"), ("AnkleWidth", "Ankle_width"),
                            ("SoleDelta", "Sole_delta")):  # fmt: skip
            fields[f"{field}_{word}"] = VALUES[side + name] / 1000
    visit = "".join(f"            <{k}>{v:.9f}</{k}>\n" for k, v in fields.items())
    path.write_text('<?xml version="1.0"?>\n<Subject Type="Patient" Filename="Doe_Jane">\n'
                    "    <Fields><First_name>Jane</First_name><Last_name>Doe</Last_name></Fields>\n"
                    '    <Session Type="Clinical Gait Session" Filename="2024-01-01">\n        <Fields>\n'
                    f"{visit}        </Fields>\n"
                    '        <Subsession Type="CGM2"><Fields/></Subsession>\n    </Session>\n</Subject>\n',
                    encoding="utf-16")  # fmt: skip
    return path


def _c3d_processing(path: Path) -> SubjectParameters:
    """The subject written to a C3D file's PROCESSING group (float32) and read back."""
    trial = replace(read_c3d(SAMPLE_DATA / "static.c3d"), parameters=dict(VALUES))
    write_c3d(trial, path)
    return subject_from_processing(read_c3d(path).parameters, source=f"{path} PROCESSING group")


FORMATS: dict[str, tuple[Callable[[Path], SubjectParameters], set[str]]] = {
    "vsk": (lambda tmp: read_subject(write_subject(SUBJECT, tmp / "Jane.vsk")), EVERYTHING),
    "toml": (lambda tmp: read_subject(write_subject(SUBJECT, tmp / "Jane.toml")), EVERYTHING),
    "c3d PROCESSING": (lambda tmp: _c3d_processing(tmp / "Jane.c3d"), EVERYTHING),
    "nexus mp": (lambda tmp: read_subject(_nexus_mp(tmp / "Jane.mp")), EVERYTHING),
    "nexus mp, short names": (lambda tmp: read_subject(_nexus_mp(tmp / "Jane.mp", short_names=True)), EVERYTHING),
    "pycgm2 mp (yaml)": (lambda tmp: read_subject(_pycgm2_yaml(tmp / "Jane.mp")), PYCGM2),
    "pycgm2 mp (json)": (lambda tmp: read_subject(_pycgm2_json(tmp / "Jane.mp")), PYCGM2),
    "qtm session.xml": (lambda tmp: read_subject(_qtm_session(tmp / "session.xml")), QTM),
}


@pytest.mark.parametrize("name", FORMATS)
def test_every_format_gives_the_same_subject(tmp_path: Path, name: str) -> None:
    read, holds = FORMATS[name]
    subject = read(tmp_path)
    got = subject_values(subject)
    expected = {k: VALUES[k] for k in holds if k in VALUES}
    assert {k: got[k] for k in holds if k in got} == pytest.approx(expected, rel=1e-6, abs=1e-9)
    assert subject.right.asis_trochanter_distance is None  # 0 or absent everywhere: the regression
    assert subject.right.asis_trochanter == pytest.approx(SUBJECT.right.asis_trochanter)
    if holds == EVERYTHING:
        assert subject == SUBJECT if name in ("vsk", "toml") else set(got) == set(VALUES)
    else:  # what the format cannot hold is left to the static calibration / the trial
        missing = EVERYTHING - holds
        assert all(got.get(k, 0.0) == 0.0 for k in missing if k[1:] in _FIELDS)
        if "InterAsisDistance" in missing:
            assert subject.inter_asis_distance is None
        if "MarkerDiameter" in missing:
            assert subject.marker_diameter == 14.0


def test_nexus_mp_angles_are_degrees(tmp_path: Path) -> None:
    subject = read_subject(_nexus_mp(tmp_path / "Jane.mp"))
    assert math.degrees(subject.left.static_plant_flex) == pytest.approx(14.5)
    assert math.degrees(subject.right.tibial_torsion) == pytest.approx(-8.0)
    assert subject.validate() is subject  # radians, inside -pi..pi
