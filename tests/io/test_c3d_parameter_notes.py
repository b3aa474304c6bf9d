"""Parameter disagreements a reader cannot repair but must not hide (issue 17's last two
silent variants of the fault campaign): a subject measurement whose record moved to
another group, ``EVENT:USED`` lower than the events the group stores, and header event
slots used beyond the header's event count."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
from support import SAMPLE_DATA, needs_shared, shared_file

from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d
from fuzzygait.io.c3d_backends import header_event_slots

WALKING = SAMPLE_DATA / "walking.c3d"


def _copy_with(tmp_path: Path, change) -> Path:
    c3d = ezc3d.c3d(str(WALKING))
    change(c3d)
    out = tmp_path / "changed.c3d"
    c3d.write(str(out))
    return out


def test_the_untouched_sample_file_has_neither_note() -> None:
    notes = " ".join(read_c3d(WALKING).notes)
    assert "EVENT:USED" not in notes and "outside the PROCESSING" not in notes


def test_event_used_below_the_stored_events_reads_the_used_ones_with_a_note(tmp_path: Path) -> None:
    original = read_c3d(WALKING)
    assert len(original.events) > 2

    def lower_used(c3d) -> None:
        c3d["parameters"]["EVENT"]["USED"]["value"] = np.array([2])

    trial = read_c3d(_copy_with(tmp_path, lower_used))
    assert [(e.label, e.context, e.time) for e in trial.events] == [
        (e.label, e.context, e.time) for e in original.events[:2]
    ]
    note = [n for n in messages(trial.notes) if "EVENT:USED" in n]
    assert note == [f"EVENT:USED says 2 events but EVENT:TIMES holds {len(original.events)}; only the first 2 "
                    "are read (set EVENT:USED in the file if the others are real events)"]


def test_a_subject_measurement_in_another_group_is_named_and_not_used(tmp_path: Path) -> None:
    original = read_c3d(WALKING)
    assert "RAnkleWidth" in original.parameters

    def move(c3d) -> None:
        value = c3d["parameters"]["PROCESSING"].pop("RAnkleWidth")["value"]
        c3d.add_parameter("POINT", "RAnkleWidth", value)

    trial = read_c3d(_copy_with(tmp_path, move))
    assert "RAnkleWidth" not in trial.parameters
    assert {k: v for k, v in original.parameters.items() if k != "RAnkleWidth"} == trial.parameters
    assert [n for n in messages(trial.notes) if "PROCESSING" in n] == [
        "parameter POINT:RAnkleWidth is a subject measurement outside the PROCESSING group; "
        "it is not used (give it in a subject file if it is needed)"
    ]


def test_files_of_other_software_keep_their_subject_group_without_a_note(tmp_path: Path) -> None:
    """No PROCESSING group: a SUBJECT:HEIGHT (as other systems write) is simply another group."""

    def other_software(c3d) -> None:
        del c3d["parameters"]["PROCESSING"]
        c3d.add_parameter("SUBJECT", "HEIGHT", np.array([1.8]))

    trial = read_c3d(_copy_with(tmp_path, other_software))
    assert trial.parameters == {} and len(trial.events) == len(read_c3d(WALKING).events)
    assert not [n for n in messages(trial.notes) if "PROCESSING" in n]


def test_header_event_slots_follow_the_header_count_and_note_labels_beyond_it() -> None:
    labels = ["RHS ", "LHS ", "    ", "X\x1a  "] + ["    "] * 14
    times = [0.38, 0.84, 0.0, 0.0] + [0.0] * 14
    notes: list[str] = []
    assert header_event_slots(labels, times, 2, notes) == [("RHS", 0.38), ("LHS", 0.84)]
    assert notes == ["the header declares 2 events but event slot(s) 4 also hold labels; those are not read"]
    notes.clear()
    assert header_event_slots(labels[:2] + ["    "] * 16, times, 2, notes) == [("RHS", 0.38), ("LHS", 0.84)]
    assert notes == []
    assert header_event_slots(labels, times, 300, notes) == [("RHS", 0.38), ("LHS", 0.84), ("X\x1a", 0.0)]
    assert notes == ["the header declares 300 events but has 18 event slots; reading 18"]


@needs_shared
def test_a_label_written_into_an_unused_header_event_slot_is_noted_not_read(tmp_path: Path) -> None:
    """pc_int.c3d keeps its 9 events in the header; a byte of slot 18's label set (byte 467)."""
    source = shared_file("c3d-formats/pc_int.c3d")
    data = bytearray(source.read_bytes())
    data[467] = 0x1A
    changed = tmp_path / "pc_int_slot18.c3d"
    changed.write_bytes(bytes(data))
    original, trial = read_c3d(source), read_c3d(changed)
    assert [(e.label, e.time) for e in trial.events] == [(e.label, e.time) for e in original.events]
    assert len(trial.events) == 9
    expected = "the header declares 9 events but event slot(s) 18 also hold labels; those are not read"
    assert expected in messages(trial.notes)
