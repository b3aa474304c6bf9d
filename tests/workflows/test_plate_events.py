"""Gait events from force plates (workflows/plate_events.py): the synthetic sample walker's
plate loads start and end at the generator's own foot strikes and foot offs, so the events
the plates give must be those, less the moment the load takes to pass the 10 N threshold;
on a Nexus trial they sit on the analog contact's edges; a file's own events are kept, and
one far from a plate's is named."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.findings import FindingKind, Severity
from fuzzygait.core.trial import Event
from fuzzygait.io import read_c3d
from fuzzygait.workflows.angles import run_angles
from fuzzygait.workflows.plate_events import plate_events

SAMPLE = Path(__file__).resolve().parents[2] / "sample_data"
SHARED = Path(__file__).resolve().parents[3] / "shared" / "data"


def _run(events: list[Event] | None):  # noqa: ANN202 - an AnglesRun
    original = read_c3d(SAMPLE / "walking.c3d")
    trial = original if events is None else dataclasses.replace(original, events=events)
    return original, run_angles(trial, static=SAMPLE / "static.c3d", subject_file=SAMPLE / "subject.toml")


def test_detected_events_take_the_plates_where_a_foot_was_on_one() -> None:
    truth, run = _run([])
    rate = truth.rate
    from_plates = [e for e in run.events if e.description.startswith("force plate")]
    assert len(from_plates) == 4  # a strike and an off per plate, both inside the trial
    for event in from_plates:
        known = min((abs(e.frame(rate) - event.frame(rate)), e) for e in truth.events
                    if (e.label, e.context) == (event.label, event.context))[1]  # fmt: skip
        # the plate sees the strike (off) when the force passes its 10 N contact threshold: a
        # fraction of a frame after (before) the generator's event, as the loads rise from 0
        late = (event.frame(rate) - known.frame(rate)) * (1 if event.label == "Foot Strike" else -1)
        assert 0.0 <= late <= 0.25
    assert "force plates 1, 2" in run.event_source and "Zeni" in run.event_source
    assert any(n.kind is FindingKind.EVENTS and "taken from the force plates" in n.message for n in run.notes)
    # the detected foot strikes the plates replaced were 5 frames early: not kept beside them
    strikes = [e.frame(rate) for e in run.events if (e.label, e.context) == ("Foot Strike", "Left")]
    assert len([f for f in strikes if abs(f - 122.0) < 10]) == 1


def test_a_files_events_are_kept_and_a_far_one_is_named() -> None:
    truth, run = _run(None)
    assert run.events == [e for e in run.events if not e.description.startswith("force plate")]
    assert not any(n.kind is FindingKind.EVENTS and n.severity is Severity.WARNING for n in run.notes)
    shifted = [dataclasses.replace(e, time=e.time + 4 / truth.rate) if abs(e.frame(truth.rate) - 122) < 0.5 and
               e.context == "Left" and e.label == "Foot Strike" else e for e in truth.events]  # fmt: skip
    _, moved = _run(shifted)
    warnings = [n.message for n in moved.notes if n.kind is FindingKind.EVENTS and n.severity is Severity.WARNING]
    assert warnings == ["the file's Left Foot Strike at frame 126.0 is +3.9 frames from force plate 1's"]  # 4 - 0.15


@pytest.mark.skipif(not (SHARED / "vicon" / "Movement_trial.c3d").is_file(), reason="needs ../shared/data/vicon")
def test_movement_trial_events_are_the_analog_contact_edges() -> None:
    """Each plate event lies within a sample and a half of where the plate's analog
    contact (read independently at the analog rate) begins or ends."""
    from fuzzygait.kinetics.plates import read_force_plates

    path = SHARED / "vicon" / "Movement_trial.c3d"
    run = run_angles(path)
    assert run.kinetics is not None
    seen = plate_events(run.kinetics)
    assert len(seen) == 7 and sum(e.description.startswith("force plate") for e in run.events) == 7
    plates = {p.number: p for p in read_force_plates(path)}
    start = (run.trial.first_frame - 1) / run.trial.rate  # C3D time of the first analog sample
    for event in seen:
        plate = plates[event.plate]
        edges = np.flatnonzero(np.diff(np.asarray(plate.contact, dtype=np.int8)))  # sample k: contact changes after k
        times = start + (edges + 0.5) / plate.rate
        assert np.min(np.abs(times - event.time)) <= 1e-9
