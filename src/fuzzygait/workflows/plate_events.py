"""Gait events from force plates.

Where a foot's whole contact is on a plate (a contact the assignment used,
:mod:`fuzzygait.kinetics.assignment`), the plate shows when the foot struck and left it:
where the plate's force rises above and falls below the contact threshold
(:data:`~fuzzygait.kinetics.plates.DEFAULT_THRESHOLD_N`, N), to the analog sample
(:func:`contact_edges`). Vicon Nexus' "detect events from force plates" does the same.

Events detected from the heel and toe markers (Zeni et al. 2008) run a few frames early
or late (on ``Movement_trial.c3d`` the detected foot strikes come 7-15 frames before the
plates' contacts), so a trial whose events were *detected* takes the plates' events
where a plate saw them: a detected event of the same foot and kind within
:data:`PAIR_WINDOW_S` of the plate's is replaced, a plate event without one is added.
Contacts that start with the trial (or end with it) give no foot strike (foot off): the
plate did not see it.  A trial with events *in the file* keeps them (the lab set them);
where one of them is more than :data:`AGREEMENT_FRAMES` frames from the plate's, a note
says so.

Times are seconds on the C3D clock (C3D frame ``n`` at ``(n - 1) / rate``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.trial import Event
from fuzzygait.gait.event_labels import SIDE_CONTEXTS, GaitEventKind
from fuzzygait.gait.events import SOURCE_DETECTED
from fuzzygait.kinetics.ground import samples_per_frame
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N

if TYPE_CHECKING:
    from collections.abc import Sequence

    from fuzzygait.io.force_plates import ForcePlate
    from fuzzygait.kinetics.assignment import PlateContact
    from fuzzygait.workflows.angles import AnglesRun
    from fuzzygait.workflows.kinetics import TrialKinetics

__all__ = ["AGREEMENT_FRAMES", "PAIR_WINDOW_S", "PlateEvent", "contact_edges", "plate_events", "with_plate_events"]

#: A detected event of the same foot and kind within this many seconds of a plate's
#: event is the same event (half the shortest stance of adult walking, about 0.4 s).
PAIR_WINDOW_S = 0.2
#: A file's event further than this many frames from the plate's gets a note.
AGREEMENT_FRAMES = 2.0
#: How many frames from a contact's first (last) frame its analog edge is looked for (the
#: contact's frames are those with most analog samples above the threshold).
SEARCH_FRAMES = 2


@dataclass(frozen=True)
class PlateEvent:
    """A foot strike or foot off seen by a force plate.

    Attributes:
        kind: foot strike or foot off.
        side: ``"L"`` or ``"R"``.
        time: s on the C3D clock.
        plate: the plate's 1-based number.
    """

    kind: GaitEventKind
    side: str
    time: float
    plate: int

    def as_event(self, subject: str = "") -> Event:
        """The event as Vicon Nexus writes it, described as the plate's."""
        return Event(self.kind.value, SIDE_CONTEXTS[self.side], self.time, subject, f"force plate {self.plate}")


def _edge(contact: NDArray[np.bool_], sample: int, rising: bool, window: int) -> float:
    """Fractional analog sample where ``contact`` (per analog sample) changes from off to
    on (``rising``) or on to off nearest ``sample``: half way between the two samples
    around the change; NaN without a change within ``window`` samples."""
    changes = np.flatnonzero(np.diff(contact.astype(np.int8)) == (1 if rising else -1))
    if changes.size == 0:
        return float("nan")
    nearest = int(changes[np.argmin(np.abs(changes - sample))])
    return nearest + 0.5 if abs(nearest - sample) <= window else float("nan")


def contact_edges(plates: Sequence[ForcePlate], contacts: Sequence[PlateContact], rate: float,
                  first_frame: int) -> list[tuple[float, float]]:  # fmt: skip
    """When each contact began and ended, s on the C3D clock: where its plate's analog
    contact (vertical force above the threshold) turns on and off nearest the contact's
    first and last frames (analog sample ``k`` of a plate at ``ratio`` samples per frame
    belongs to frame index ``k / ratio``, as the frame means take them); NaN where the
    contact begins with the trial's first frame or ends with its last (the plate did not
    see it), ``rate`` Hz the marker rate."""
    by_number = {p.number: p for p in plates}
    start = (first_frame - 1) / rate
    out = []
    for contact in contacts:
        plate = by_number[contact.plate]
        on = np.asarray(plate.contact, dtype=bool)
        ratio = samples_per_frame(plate.rate, rate)
        n_frames = int(np.ceil(on.size / ratio))
        window = SEARCH_FRAMES * ratio
        onset = _edge(on, contact.first * ratio, True, window) if contact.first > 0 else float("nan")
        offset = _edge(on, contact.last * ratio, False, window) if contact.last < n_frames - 1 else float("nan")
        out.append((start + onset / plate.rate, start + offset / plate.rate))
    return out


def plate_events(kinetics: TrialKinetics) -> list[PlateEvent]:
    """The foot strikes and foot offs of every used contact of ``kinetics`` (module
    docstring; :attr:`~fuzzygait.workflows.kinetics.TrialKinetics.edges`), sorted by time."""
    found = []
    for contact, (onset, offset) in zip(kinetics.contacts, kinetics.edges, strict=True):
        if contact.side is None or not contact.reason.used:
            continue
        side = contact.side.value
        if np.isfinite(onset):
            found.append(PlateEvent(GaitEventKind.FOOT_STRIKE, side, onset, contact.plate))
        if np.isfinite(offset):
            found.append(PlateEvent(GaitEventKind.FOOT_OFF, side, offset, contact.plate))
    return sorted(found, key=lambda e: e.time)


def _nearest(events: list[Event], plate: PlateEvent) -> int | None:
    """Index of the event of ``events`` of the plate event's foot and kind nearest it
    within :data:`PAIR_WINDOW_S`, or None."""
    label, context = plate.kind.value, SIDE_CONTEXTS[plate.side]  # the run's events are spelled as Nexus does
    gaps = [(abs(e.time - plate.time), i) for i, e in enumerate(events) if (e.label, e.context) == (label, context)]
    candidates = [(gap, i) for gap, i in gaps if gap <= PAIR_WINDOW_S]
    return min(candidates)[1] if candidates else None


def with_plate_events(run: AnglesRun) -> tuple[list[Event], str, list[Finding]]:
    """The run's events with the plates' (module docstring): ``(events, source, notes)``.

    Unchanged without kinetics or plate events; a detected set takes the plates' events
    (the source says so); a file's set is kept, with a note per event more than
    :data:`AGREEMENT_FRAMES` frames from a plate's."""
    if run.kinetics is None:
        return run.events, run.event_source, []
    seen = plate_events(run.kinetics)
    if not seen:
        return run.events, run.event_source, []
    events = list(run.events)
    if run.event_source != SOURCE_DETECTED:
        notes = []
        for plate in seen:
            index = _nearest(events, plate)
            if index is not None and abs(events[index].time - plate.time) * run.trial.rate > AGREEMENT_FRAMES:
                frames = (events[index].time - plate.time) * run.trial.rate
                notes.append(Finding(FindingKind.EVENTS, f"the file's {SIDE_CONTEXTS[plate.side]} {plate.kind.value} "
                                     f"at frame {events[index].frame(run.trial.rate):.1f} is {frames:+.1f} frames from "
                                     f"force plate {plate.plate}'s", Severity.WARNING))  # fmt: skip
        return events, run.event_source, notes
    for plate in seen:
        index = _nearest(events, plate)
        if index is None:
            events.append(plate.as_event(run.trial.subject))
        else:
            events[index] = plate.as_event(events[index].subject)
    events.sort(key=lambda e: (e.time, e.context, e.label))
    plates = sorted({p.plate for p in seen})
    source = (f"from force plate{'s' if len(plates) > 1 else ''} {', '.join(map(str, plates))} where a foot was on "
              f"one, elsewhere {SOURCE_DETECTED}")  # fmt: skip
    note = Finding(FindingKind.EVENTS, f"{len(seen)} foot strikes and foot offs taken from the force plates' contacts "
                   f"(threshold {DEFAULT_THRESHOLD_N:g} N)")  # fmt: skip
    return events, source, [note]
