"""More than 255 events (a long treadmill trial): a C3D parameter's dimensions are single
bytes, so the writer stores events 256... in ``EVENT:TIMES2``, ``LABELS2``, ... (C3D's
``POINT:LABELS2`` convention, ``EVENT:USED`` the total) and the reader concatenates them.
ezc3d's ``add_event`` wrote the count modulo 256: ezc3d refused the file and the ``c3d``
package fallback read 111 of 367 events. Up to 255 events the file is byte for byte what
``add_event`` wrote.
"""

from __future__ import annotations

import struct
from dataclasses import replace
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import messages
from fuzzygait.core.trial import Event, Trial
from fuzzygait.io import c3d as c3d_module
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.c3d_backends import _decode_c3d
from fuzzygait.io.c3d_groups import read_events
from fuzzygait.io.c3d_params import Parameter, read_section
from fuzzygait.io.c3d_writeback import splice
from fuzzygait.synthetic.generate import make_walking_trial

EVENT_NAMES = ("TIMES", "CONTEXTS", "LABELS", "DESCRIPTIONS", "SUBJECTS", "ICON_IDS", "GENERIC_FLAGS")


@pytest.fixture(scope="module")
def walk() -> Trial:
    return make_walking_trial(n_cycles=2)[0]


def many_events(n: int) -> list[Event]:
    """``n`` events over about 2.5 minutes (minutes and seconds both used), labels,
    contexts and subjects of several widths, descriptions only past the 255th event."""
    labels = ("Foot Strike", "Foot Off", "Event", "General Event X")
    contexts = ("Left", "Right", "General")
    return [
        Event(
            label=labels[i % 4],
            context=contexts[i % 3],
            time=0.013 + i * (150.0 / n),
            subject="Synthetic" if i % 5 else "Other Subject",
            description=f"note {i}" if i >= 260 and i % 7 == 0 else "",
        )
        for i in range(n)
    ]


def assert_same_events(got: list[Event], expected: list[Event]) -> None:
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        assert (a.label, a.context, a.subject, a.description) == (b.label, b.context, b.subject, b.description)
        assert a.time == pytest.approx(b.time, abs=1e-5)


@pytest.mark.parametrize("n", [300, 600])
def test_more_than_255_events_round_trip(walk: Trial, n: int, tmp_path: Path) -> None:
    trial = replace(walk, events=many_events(n))
    out = tmp_path / "many.c3d"
    write_c3d(trial, out)
    back = read_c3d(out)
    assert back.notes == []  # ezc3d read it: no fallback to the c3d package, no event note
    assert_same_events(back.events, trial.events)
    params = ezc3d.c3d(str(out))["parameters"]["EVENT"]
    assert int(np.ravel(params["USED"]["value"])[0]) == n
    parts = -(-n // 255)
    for name in EVENT_NAMES:
        stored = [name] + [f"{name}{i}" for i in range(2, parts + 1)]
        assert [key for key in params if key.rstrip("0123456789") == name] == stored
        sizes = [np.shape(params[key]["value"])[-1] if name in ("TIMES", "ICON_IDS", "GENERIC_FLAGS")
                 else len(params[key]["value"]) for key in stored]  # fmt: skip
        assert sizes == [255] * (parts - 1) + [n - 255 * (parts - 1)]
    assert np.shape(params["TIMES"]["value"]) == (2, 255)
    raw = _decode_c3d(out)  # the c3d package (the reader's fallback) gives the same events
    notes: list[str] = []
    assert read_events(out, raw, notes) == back.events
    assert notes == []


def test_a_long_walking_trial_keeps_every_gait_event(tmp_path: Path) -> None:
    trial = make_walking_trial(n_cycles=91)[0]  # 367 events, 10082 frames: the report's trial
    assert len(trial.events) == 367
    write_c3d(trial, tmp_path / "long.c3d")
    back = read_c3d(tmp_path / "long.c3d")
    assert not any("c3d package" in note or "EVENT" in note for note in messages(back.notes))
    assert_same_events(back.events, trial.events)


def write_with_add_event(trial: Trial, out: Path) -> None:
    """The writer as it was: events through ezc3d's ``add_event``; then Vicon's icons
    (1 foot strike, 2 foot off, 0 else) stored as 16-bit integers and the flags as bytes."""
    c = c3d_module._ezc3d_trial(replace(trial, events=[]), None, None)
    for event in trial.events:
        minutes, seconds = divmod(event.time, 60.0)
        c.add_event(time=[float(minutes), float(seconds)], context=event.context, label=event.label,
                    description=event.description, subject=event.subject)  # fmt: skip
    if trial.events:
        icons = {"Foot Strike": 1, "Foot Off": 2}
        c["parameters"]["EVENT"]["ICON_IDS"]["value"] = np.array([icons.get(e.label, 0) for e in trial.events], float)
    c3d_module._write_with_ezc3d(c, out)
    data = out.read_bytes()
    section = read_section(data)
    event = section.get("EVENT")
    if event is not None:
        n = len(trial.events)
        icons_f = event.parameters["ICON_IDS"].numbers()
        event.parameters["ICON_IDS"] = Parameter("ICON_IDS", 2, (n,), struct.pack(f"<{n}h", *icons_f.astype(int)),
                                                 event.parameters["ICON_IDS"].description)  # fmt: skip
        event.parameters["GENERIC_FLAGS"] = Parameter("GENERIC_FLAGS", 1, (n,), bytes(n),
                                                      event.parameters["GENERIC_FLAGS"].description)  # fmt: skip
        out.write_bytes(splice(data, section))


@pytest.mark.parametrize("n", [0, 1, 43, 255])
def test_up_to_255_events_are_written_as_before(walk: Trial, n: int, tmp_path: Path) -> None:
    events = [replace(e, description="a description") if i == 3 else e for i, e in enumerate(many_events(n))]
    trial = replace(walk, events=events)
    write_c3d(trial, tmp_path / "now.c3d")
    write_with_add_event(trial, tmp_path / "before.c3d")
    assert (tmp_path / "now.c3d").read_bytes() == (tmp_path / "before.c3d").read_bytes()
    assert_same_events(read_c3d(tmp_path / "now.c3d").events, events)


def event_records(path: Path) -> dict[str, object]:
    group = read_section(path.read_bytes())["EVENT"]
    return {name: (p.kind, p.dims, p.data) for name, p in group.parameters.items()}


def test_write_back_carries_more_than_255_events(walk: Trial, tmp_path: Path) -> None:
    src = tmp_path / "input.c3d"
    write_c3d(replace(walk, events=many_events(600)), src)
    trial = read_c3d(src)
    out = tmp_path / "out.c3d"
    assert write_c3d(trial, out, source=src) == []
    assert event_records(out) == event_records(src)  # the input's EVENT group, record for record
    back = read_c3d(out)
    assert back.notes == []
    assert_same_events(back.events, trial.events)


def test_write_back_with_other_events_writes_them_all(walk: Trial, tmp_path: Path) -> None:
    src = tmp_path / "input.c3d"
    write_c3d(replace(walk, events=many_events(600)), src)
    trial = read_c3d(src)
    for events in (trial.events[:400], trial.events[:100]):  # TIMES3 of the input must not survive
        out = tmp_path / "out.c3d"
        assert write_c3d(replace(trial, events=events), out, source=src) == []
        back = read_c3d(out)
        assert back.notes == []
        assert_same_events(back.events, events)
        assert "TIMES3" not in event_records(out)


def test_events_beyond_the_parameter_section_are_refused(walk: Trial, tmp_path: Path) -> None:
    """About 3000 events fill the 255 blocks of 512 bytes a parameter section can have
    (its block count is one byte): no file rather than one that loses events."""
    out = tmp_path / "huge.c3d"
    with pytest.raises(C3DError, match=r"huge\.c3d: .*need \d+ blocks of 512 bytes and a C3D file holds at most 255"):
        write_c3d(replace(walk, events=many_events(4000)), out)
    assert not out.exists()
    with pytest.raises(C3DError, match="EVENT:USED counts at most 32767"):
        write_c3d(replace(walk, events=many_events(32768)), out)
