"""Event labels as Vicon Nexus, Vicon Workstation, QTM and Visual3D write them (issue 36).

Every spelling of :mod:`fuzzygait.gait.events`' table is read as the same foot strike or
foot off; a trial respelled in any of them gives the file's own events (source
``"file"``) and the same cycles and spatio-temporal parameters as Nexus' spelling; a
label that is not one of them is never a gait event.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.core.trial import Event, Trial
from fuzzygait.gait.cycles import gait_cycles, normalised_angle_table
from fuzzygait.gait.events import (
    SOURCE_DETECTED,
    SOURCE_FILE,
    GaitEvent,
    GaitEventKind,
    GaitLabel,
    gait_events,
    gait_label,
    trial_gait_events,
)
from fuzzygait.gait.spatiotemporal import spatiotemporal_parameters
from fuzzygait.io import read_c3d
from support import shared_file

STRIKE, OFF = GaitEventKind.FOOT_STRIKE, GaitEventKind.FOOT_OFF
CODES = {("Foot Strike", "Left"): "LHS", ("Foot Strike", "Right"): "RHS",
         ("Foot Off", "Left"): "LTO", ("Foot Off", "Right"): "RTO"}  # fmt: skip
PLATES = {("Foot Strike", "Left"): "LON", ("Foot Strike", "Right"): "RON",
          ("Foot Off", "Left"): "LOFF", ("Foot Off", "Right"): "ROFF"}  # fmt: skip


@pytest.mark.parametrize(
    "label, context, expected",
    [
        ("Foot Strike", "Left", GaitLabel(STRIKE, "L")),  # Vicon Nexus
        ("Foot Off", "Right", GaitLabel(OFF, "R")),
        ("foot strike", "Left", GaitLabel(STRIKE, "L")),  # Vicon Workstation
        ("foot off", "right", GaitLabel(OFF, "R")),
        ("FOOT_STRIKE", " RIGHT ", GaitLabel(STRIKE, "R")),  # separators and case ignored
        (" Foot-Off ", "left", GaitLabel(OFF, "L")),
        ("Left Foot Strike", "General", GaitLabel(STRIKE, "L")),  # QTM (Qualisys' naming)
        ("Right Foot Off", "", GaitLabel(OFF, "R")),
        ("Left Foot Off", "Left", GaitLabel(OFF, "L")),
        ("LHS", "General", GaitLabel(STRIKE, "L")),  # Visual3D
        ("RHS", "", GaitLabel(STRIKE, "R")),
        ("LTO", "Left", GaitLabel(OFF, "L")),
        ("rto", "Right", GaitLabel(OFF, "R")),
        ("LON", "General", GaitLabel(STRIKE, "L", plate=True)),
        ("RON", "", GaitLabel(STRIKE, "R", plate=True)),
        ("LOFF", "", GaitLabel(OFF, "L", plate=True)),
        ("ROFF", "Right", GaitLabel(OFF, "R", plate=True)),
    ],
)
def test_each_spelling_is_recognised(label: str, context: str, expected: GaitLabel) -> None:
    assert gait_label(label, context) == expected


@pytest.mark.parametrize(
    "label, context",
    [
        ("Event", "General"),
        ("Left-FP", "General"),  # pyCGM2's force-plate assignment
        ("Right-FP", "General"),
        ("Foot Strike", "General"),  # no side anywhere
        ("Foot Off", ""),
        ("Foot Strikes", "Left"),
        ("Heel Strike", "Left"),  # no tool of the table writes it
        ("LHS", "Right"),  # label and context disagree
        ("Left Foot Strike", "Right"),
        ("", "Left"),
    ],
)
def test_other_labels_are_not_gait_events(label: str, context: str) -> None:
    assert gait_label(label, context) is None
    assert gait_events([Event(label, context, 1.0)]) == []


def _respelled(trial: Trial, spell: Callable[[Event], list[Event]]) -> Trial:
    return replace(trial, events=[new for event in trial.events for new in spell(event)])


SPELLINGS: dict[str, Callable[[Event], list[Event]]] = {
    "workstation lower case": lambda e: [replace(e, label=e.label.lower(), context=e.context.lower())],
    "qtm side in the label": lambda e: [replace(e, label=f"{e.context} {e.label}", context="General")],
    "visual3d": lambda e: [replace(e, label=CODES[e.label, e.context], context="")],
    "visual3d with plate events": lambda e: [replace(e, label=CODES[e.label, e.context], context="General"),
                                             replace(e, label=PLATES[e.label, e.context], context="General")],
    "visual3d plate events only": lambda e: [replace(e, label=PLATES[e.label, e.context], context="")],
    "nexus and visual3d twice": lambda e: [e, replace(e, label=CODES[e.label, e.context], context="General")],
}  # fmt: skip


@pytest.mark.parametrize("name", SPELLINGS)
def test_respelled_trial_gives_the_files_events_and_cycles(walking: Trial, name: str) -> None:
    respelled = _respelled(walking, SPELLINGS[name])
    events, source = trial_gait_events(respelled)
    assert source == SOURCE_FILE
    assert [(e.label, e.context, e.time) for e in events] == [(e.label, e.context, e.time) for e in walking.events]
    for side in "LR":
        assert gait_cycles(respelled, respelled.events, side) == gait_cycles(walking, walking.events, side)
    ours, nexus = spatiotemporal_parameters(respelled), spatiotemporal_parameters(walking)
    assert ours.event_source == nexus.event_source == "file"
    for side in "LR":
        np.testing.assert_equal([c.values for c in ours.sides[side].cycles],
                                [c.values for c in nexus.sides[side].cycles])  # fmt: skip


def test_lower_case_trial_is_not_redetected(walking: Trial) -> None:
    """The bug of issue 36: lower-case labels were ignored and the events re-detected
    (Zeni's strikes are 5 frames early on this walker), so the cycles moved."""
    lower = _respelled(walking, SPELLINGS["workstation lower case"])
    assert trial_gait_events(lower)[1] == SOURCE_FILE
    detected, source = trial_gait_events(replace(walking, events=[]))
    assert source == SOURCE_DETECTED
    assert gait_cycles(lower, lower.events, "L") != gait_cycles(walking, detected, "L")
    angles = {"LKneeAngles": walking.markers[:, 0, :]}  # any (n, 3) signal
    assert normalised_angle_table(angles, lower, lower.events).equals(
        normalised_angle_table(angles, walking, walking.events))


def test_unknown_labels_are_left_out(walking: Trial) -> None:
    middle = walking.events[len(walking.events) // 2].time + 0.01
    noise = [Event("Left-FP", "General", middle), Event("Foot Strike", "General", middle),
             Event("Event", "Left", middle), Event("LHS", "Right", middle)]  # fmt: skip
    noisy = replace(walking, events=[*walking.events, *noise])
    events, source = trial_gait_events(noisy)
    assert source == SOURCE_FILE and events == walking.events
    for side in "LR":
        assert gait_cycles(noisy, noisy.events, side) == gait_cycles(walking, walking.events, side)
    only_noise = replace(walking, events=noise)
    assert trial_gait_events(only_noise)[1] == SOURCE_DETECTED


def test_labels_are_read_once_into_typed_values(walking: Trial) -> None:
    typed = gait_events(_respelled(walking, SPELLINGS["visual3d"]).events)
    assert all(isinstance(g, GaitEvent) and g.side in "LR" for g in typed)
    assert {(g.kind, g.side) for g in typed} == {(k, s) for k in GaitEventKind for s in "LR"}
    again = gait_events(typed)  # typed values are passed through, not read again
    assert all(a is b for a, b in zip(again, typed, strict=True))
    assert [g.as_event().label for g in typed] == [e.label for e in walking.events]
    assert typed[0].event.label in CODES.values()  # the file's own event is kept


def test_gait_pig_lower_case_keeps_the_files_foot_off() -> None:
    """``gait-pig.c3d`` (Vicon Workstation era) is spelled ``Foot Strike``/``Foot Off``;
    respelled in lower case it keeps its events (right Foot Off 59.66 %, as the file's
    ANALYSIS group) instead of detected ones (64.33 %)."""
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    assert {(e.label, e.context) for e in trial.events} == {(k.value, c) for k in GaitEventKind
                                                            for c in ("Left", "Right")}  # fmt: skip
    lower = _respelled(trial, SPELLINGS["workstation lower case"])
    ours, nexus = spatiotemporal_parameters(lower), spatiotemporal_parameters(trial)
    assert ours.event_source == "file"
    for side in "LR":
        first, reference = ours.sides[side].first, nexus.sides[side].first
        assert first is not None and reference is not None
        np.testing.assert_equal(first.workstation, reference.workstation)  # NaN equal to NaN
    assert ours.sides["R"].first.workstation["Foot Off"] == pytest.approx(59.66, abs=0.01)  # type: ignore[union-attr]
