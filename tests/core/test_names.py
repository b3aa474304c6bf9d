"""Typed angle names (``fuzzygait.core.names``): one parser of component labels, and no
code below the command line that splits labels itself."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent, Axis, Side, angle_names, angle_of, is_flexion
from fuzzygait.kinematics.labels import component_label, parse_component

SRC = Path(__file__).resolve().parents[2] / "src" / "fuzzygait"


@pytest.mark.parametrize(
    ("label", "angle", "axis", "side", "joint", "flexion"),
    [
        ("LKneeAngles_X", "LKneeAngles", Axis.X, Side.LEFT, "KneeAngles", True),
        ("RAnkleAngles_X", "RAnkleAngles", Axis.X, Side.RIGHT, "AnkleAngles", True),
        ("RHipAngles_Z", "RHipAngles", Axis.Z, Side.RIGHT, "HipAngles", False),
        ("LPelvisAngles_X", "LPelvisAngles", Axis.X, Side.LEFT, "PelvisAngles", False),
        ("LFootProgressAngles_Y", "LFootProgressAngles", Axis.Y, Side.LEFT, "FootProgressAngles", False),
        ("LKneeAngles_CGM_2.3_X", "LKneeAngles_CGM_2.3", Axis.X, Side.LEFT, "KneeAngles_CGM_2.3", False),
        ("SpineAngles_X", "SpineAngles", Axis.X, None, "SpineAngles", False),
    ],
)
def test_a_label_parses_into_its_fields_and_back(label, angle, axis, side, joint, flexion) -> None:
    component = AngleComponent.parse(label)
    assert (component.angle, component.axis, component.side, component.joint) == (angle, axis, side, joint)
    assert component.is_flexion is flexion and is_flexion(label) is flexion
    assert component.label == str(component) == label
    assert AngleComponent(angle, Axis.of(component.axis.column)) == component


@pytest.mark.parametrize("label", ["LKneeAngles", "LKneeAngles_W", "_X", "LKneeAngles_x", ""])
def test_what_is_no_component_is_one_clear_error(label) -> None:
    with pytest.raises(ParameterError, match="is not an angle component"):
        AngleComponent.parse(label)
    assert AngleComponent.maybe(label) is None and not is_flexion(label)


def test_helpers_of_the_edge() -> None:
    assert angle_of("LKneeAngles_Y") == angle_of("LKneeAngles") == "LKneeAngles"
    assert angle_names(["LKneeAngles_X", "LKneeAngles_Y", "RHipAngles_X", "LKneeAngles_Z"]) == [
        "LKneeAngles", "RHipAngles"]  # fmt: skip
    assert [Axis.of(i) for i in range(3)] == [Axis.X, Axis.Y, Axis.Z] and Axis.Z.column == 2
    assert Side.LEFT.word == "Left" and Side("R") is Side.RIGHT


def test_labels_module_reads_names_through_the_one_parser() -> None:
    """The clinical labels and the report grid's parse agree with the typed fields."""
    assert parse_component("LKneeAngles_X") == ("L", "KneeAngles", "X")
    assert parse_component("SpineAngles_X") is None and parse_component("LKneeAngles") is None
    assert component_label("RAnkleAngles_X") == "Right ankle, sagittal (+ dorsiflexion)"


#: Ways code split an angle component's label itself: rsplit/rpartition on "_", a regex of
#: the axis letters or of the side, or slicing off the "_X".
_SPLITTING = re.compile(r"""(r(split|partition)\(\s*["']_["'])|\[XYZ\]|\[LR\]|endswith\(\s*["']_[XYZ]["']|"""
                        r"""(\bstr|\bc|\bcolumn|\bname|\blabel)\[:-2\]""")  # fmt: skip


def test_no_module_below_the_command_line_splits_angle_labels_itself() -> None:
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        relative = path.relative_to(SRC).as_posix()
        if relative.startswith("cli/") or relative == "core/names.py":
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            if _SPLITTING.search(line) and "component" in _context(path, number):
                offenders.append(f"{relative}:{number}: {line.strip()}")
    assert offenders == [], "\n".join(offenders)


def _context(path: Path, number: int) -> str:
    """The lines around ``number`` (1-based), lower case: the split must be of an angle
    name (``component``, ``angle``, ``column`` of an angle table)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    text = " ".join(lines[max(0, number - 8) : number + 2]).lower()
    return "component" if any(word in text for word in ("component", "angle", "column", "flexion")) else ""
