"""The foot-plate assignment's typed reasons, their findings and the subject file's override."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_ground import foot_at, loaded

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind, Severity
from fuzzygait.core.names import Side
from fuzzygait.io.subject import read_force_plate_assignment, read_subject
from fuzzygait.kinetics.assignment import (
    ContactUse,
    Foot,
    PlateContact,
    automatic_assignment,
    contact_findings,
    contact_ground,
)

SUBJECT = """Bodymass = 70.0
Height = 1750.0
LLegLength = 900.0
RLegLength = 900.0
LKneeWidth = 100.0
RKneeWidth = 100.0
LAnkleWidth = 70.0
RAnkleWidth = 70.0
"""


def subject_file(tmp_path: Path, table: str) -> Path:
    path = tmp_path / "subject.toml"
    path.write_text(SUBJECT + table, encoding="utf-8")
    return path


def test_the_table_maps_plates_to_feet_and_the_subject_still_reads(tmp_path: Path) -> None:
    path = subject_file(tmp_path, '\n[force_plates]\n1 = "left"\n2 = "None"\n3 = "auto"\n4 = "RIGHT"\n')
    assert read_force_plate_assignment(path) == {1: Side.LEFT, 2: None, 4: Side.RIGHT}
    assert read_subject(path).body_mass == 70.0


def test_no_table_and_other_subject_files_give_no_override(tmp_path: Path) -> None:
    assert read_force_plate_assignment(subject_file(tmp_path, "")) == {}
    vsk = tmp_path / "subject.vsk"
    vsk.write_text("<KinematicModel/>", encoding="utf-8")
    assert read_force_plate_assignment(vsk) == {}


@pytest.mark.parametrize(("table", "message"), [
    ('[force_plates]\nleft = "left"\n', r"force_plates.left: not a plate number; use 1, 2, \.\.\."),
    ('[force_plates]\n0 = "left"\n', "force_plates.0: not a plate number"),
    ('[force_plates]\n1 = "both"\n', "force_plates.1 = 'both'; use one of \"left\", \"right\", \"none\", \"auto\""),
    ('[force_plates]\n1 = 2\n', "force_plates.1 = 2; use one of"),
    ('force_plates = "left"\n', "force_plates must be a table"),
])  # fmt: skip
def test_a_bad_table_is_one_line(tmp_path: Path, table: str, message: str) -> None:
    path = subject_file(tmp_path, "\n" + table if not table.startswith("force_plates =") else "")
    if table.startswith("force_plates ="):
        path.write_text(table + SUBJECT, encoding="utf-8")
    with pytest.raises(ParameterError, match=message) as info:
        read_force_plate_assignment(path)
    assert "\n" not in str(info.value) and str(path) in str(info.value)


def test_the_override_assigns_a_plate_the_rule_leaves_unused() -> None:
    """A heel 100 mm behind the plate: the rule says off the edge; the subject file puts
    the plate under the left foot, and the foot gets the plate's 700 N."""
    feet = {Side.LEFT: foot_at((-100, 150))}
    plate = loaded(0.0, (50.0, 160.0))
    (auto,) = automatic_assignment([plate], feet, 100.0, 10.0)
    assert (auto.side, auto.reason) == (None, ContactUse.OFF_EDGE)
    (forced,) = automatic_assignment([plate], feet, 100.0, 10.0, override={1: Side.LEFT})
    assert forced == PlateContact(1, 20, 79, Side.LEFT, ContactUse.ASSIGNED)
    ground = contact_ground([plate], [forced], Side.LEFT, 100, 100.0)
    assert np.all(ground.force[21:79, 2] == 700.0) and np.all(ground.force[:20] == 0.0)
    assert forced.describe() == "used by the left foot, as the subject file assigns the plate"


def test_the_override_excludes_a_plate_and_leaves_the_others_to_the_rule() -> None:
    feet = {Side.LEFT: foot_at((100, 150)), Side.RIGHT: foot_at((650, 150))}
    plates = [loaded(0.0, (200, 160), number=1), loaded(500.0, (750, 155), number=2)]
    contacts = automatic_assignment(plates, feet, 100.0, 10.0, override={1: None})
    assert [(c.plate, c.side, c.reason) for c in contacts] == [(1, None, ContactUse.EXCLUDED),
                                                               (2, Side.RIGHT, ContactUse.USED)]  # fmt: skip
    assert contact_ground(plates, contacts, Side.LEFT, 100, 100.0).force.max() == 0.0


def test_a_foot_assigned_two_plates_at_once_uses_neither() -> None:
    feet = {Side.LEFT: foot_at((100, 150))}
    plates = [loaded(0.0, (200, 160), number=1), loaded(500.0, (750, 155), number=2)]
    contacts = automatic_assignment(plates, feet, 100.0, 10.0, override={1: Side.LEFT, 2: Side.LEFT})
    assert [(c.side, c.reason, c.foot) for c in contacts] == [(None, ContactUse.TWO_PLATES, Side.LEFT)] * 2


def test_an_override_of_a_plate_the_trial_lacks_is_one_line() -> None:
    with pytest.raises(ParameterError, match=r"names plate 3, but the trial has plates 1$"):
        automatic_assignment([loaded(0.0, (200, 160))], {Side.LEFT: foot_at((100, 150))}, 100.0, 10.0,
                             override={3: Side.LEFT})  # fmt: skip


def test_each_contact_is_a_finding_with_its_frames_and_foot() -> None:
    contacts = [PlateContact(1, 20, 79, Side.LEFT), PlateContact(2, 5, 30, None, ContactUse.OFF_EDGE, Side.RIGHT),
                PlateContact(3, 0, 9, None, ContactUse.NO_FOOT),
                PlateContact(4, 1, 2, None, ContactUse.EXCLUDED)]  # fmt: skip
    findings = contact_findings(contacts, first_frame=101)
    assert {f.kind for f in findings} == {FindingKind.FORCE_PLATE_ASSIGNMENT}
    assert [f.message for f in findings] == [
        "force plate 1, frames 121-180: used by the left foot",
        "force plate 2, frames 106-131: not used: right foot off the plate's edge",
        "force plate 3, frames 101-110: not used: no foot over the centre of pressure",
        "force plate 4, frames 102-103: not used: the subject file assigns the plate to no foot",
    ]
    assert [f.severity for f in findings] == [Severity.INFO, Severity.WARNING, Severity.INFO, Severity.INFO]
    assert [f.side for f in findings] == ["left", "right", None, None]


def test_foot_markers_missing_on_one_side_leave_the_contact_to_the_other() -> None:
    """Only the feet given take part (a side without foot markers is absent)."""
    heel = np.tile([100.0, 150.0, 30.0], (100, 1))
    feet = {Side.RIGHT: Foot(heel, heel + [200.0, 0, 0], heel + [50.0, 0, 50.0])}
    (contact,) = automatic_assignment([loaded(0.0, (200, 160))], feet, 100.0, 10.0)
    assert (contact.side, contact.reason) == (Side.RIGHT, ContactUse.USED)
