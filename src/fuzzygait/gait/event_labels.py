"""Gait event labels of a file: which of a file's events are Foot Strike / Foot Off, of
which side.

Each of a file's events is read **once**, at the edge (:func:`gait_events`), into a
typed :class:`GaitEvent` (:class:`GaitEventKind` and side ``"L"``/``"R"``); the cycles
and the spatio-temporal parameters use those values, never the label text.  A label is
matched ignoring case, whitespace, ``_`` and ``-`` (``foot strike``, ``FOOT_STRIKE``,
``Foot-Off`` ...).  The spellings recognised, and where each was seen:

=================================  ===================  ==================================
label (context)                    read as              source
=================================  ===================  ==================================
``Foot Strike`` / ``Foot Off``     strike / off, side   Vicon Nexus: ``EVENT:LABELS`` of
(``Left`` / ``Right``)             from the context     ``PiG_Motion-FlatFoot-Full.c3d``
                                                        (Nexus 1.4) and ``gait-pig.c3d``
                                                        (c3d.org sample 03, Vicon
                                                        Workstation era: it too is spelled
                                                        ``Foot Strike``, title case); the
                                                        same in QTM sessions processed by
                                                        pyCGM2 (``Gait - CGM2 3 (pyCGM2
                                                        CGM2.3 output).c3d``; repository
                                                        qualisys/cgm2-web-report-uploader,
                                                        ``TestFiles/*/processed/*.c3d``)
``foot strike`` / ``foot off``     the same             Vicon Workstation in lower case
                                                        (issue 36; no public file with
                                                        this spelling was found -- the
                                                        case-blind match covers it)
``Left Foot Strike``,              strike / off, side   Qualisys' gait report tool names
``Left Foot Off``,                 from the label       QTM's events so (qualisys/cgm2-
``Right Foot Strike``,                                  web-report-uploader,
``Right Foot Off``                                      ``qtmWebGaitReport/signalMapping.py``
                                                        ``eventNameMap``)
``LHS`` / ``RHS`` (heel strike),   strike / off, side   Visual3D's gait-event acronyms
``LTO`` / ``RTO`` (toe off)        from the label       (HAS-Motion wiki, Visual3D
                                                        tutorial "Gait Events", "Gait
                                                        Event Acronyms"); Qualisys' tool
                                                        maps QTM's events to them too
``LON`` / ``RON`` (foot on a       strike / off, side   the same Visual3D page: contact
force plate), ``LOFF`` / ``ROFF``  from the label;      with a force platform; "all RON
                                   plate events         events are also RHS events"
=================================  ===================  ==================================

The side comes from the label when the label carries it (``LHS``, ``Left Foot
Strike``), else from the context (``Left``/``Right``, any case).  A context naming the
other side than the label contradicts it: the event is not used.  QTM may export a C3D
without ``EVENT:CONTEXTS`` (issue 18 of u0078867/ulema-ul-analyzer); the C3D reader then
gives ``General`` and only a label carrying the side is a gait event.  Force-plate
events (``LON``, ``LOFF``, ...) are used only for a side and kind the file has no other
event of (they duplicate the heel strikes / toe offs Visual3D writes with them).  Any
other label -- ``Event``, ``Left-FP``/``Right-FP`` (pyCGM2's force-plate assignment,
context ``General``), ``Foot Strike`` with context ``General`` -- is not a gait event.
Events of the same kind, side and time are kept once.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass
from enum import Enum

from fuzzygait.core.trial import Event


class GaitEventKind(Enum):
    """What a gait event marks; the value is Vicon Nexus' label of it."""

    FOOT_STRIKE = "Foot Strike"
    FOOT_OFF = "Foot Off"


#: Event labels and contexts, exactly as Vicon Nexus writes them (and as fuzzygait
#: writes its events).
FOOT_STRIKE = GaitEventKind.FOOT_STRIKE.value
FOOT_OFF = GaitEventKind.FOOT_OFF.value
GAIT_LABELS = (FOOT_STRIKE, FOOT_OFF)
SIDE_CONTEXTS = {"L": "Left", "R": "Right"}


@dataclass(frozen=True)
class GaitLabel:
    """An event label (and context) read as a gait event (module docstring).

    Attributes:
        kind: foot strike or foot off.
        side: ``"L"`` or ``"R"``.
        plate: Visual3D's force-platform spelling (``LON``, ``LOFF``, ``RON``, ``ROFF``).
    """

    kind: GaitEventKind
    side: str
    plate: bool = False


@dataclass(frozen=True)
class GaitEvent:
    """One gait event, its label read once (:func:`gait_events`).

    Attributes:
        kind: foot strike or foot off.
        side: ``"L"`` or ``"R"``.
        time: s on the C3D clock (as :attr:`Event.time`).
        event: the event as the file (or the detector) holds it.
        plate: from a Visual3D force-platform label (``LON`` ...).
    """

    kind: GaitEventKind
    side: str
    time: float
    event: Event
    plate: bool = False

    def as_event(self) -> Event:
        """The event spelled as Vicon Nexus writes it (``Foot Strike``/``Foot Off``,
        context ``Left``/``Right``; time, subject and description kept): the file's own
        :class:`Event` when it is spelled so already."""
        label, context = self.kind.value, SIDE_CONTEXTS[self.side]
        if (self.event.label, self.event.context) == (label, context):
            return self.event
        return Event(label, context, self.event.time, self.event.subject, self.event.description)


#: Separators ignored in labels and contexts.
_SEPARATORS = re.compile(r"[\s_\-]+")
#: Labels without a side (the context gives it), compared without separators or case.
_KIND_KEYS = {"footstrike": GaitEventKind.FOOT_STRIKE, "footoff": GaitEventKind.FOOT_OFF}
#: Side words of contexts and of labels such as ``Left Foot Strike``.
_SIDE_KEYS = {"left": "L", "right": "R"}
#: Visual3D's acronyms: heel strike / toe off, force-platform on / off.
_CODES = {
    f"{side.lower()}{code}": GaitLabel(kind, side, plate)
    for side in SIDE_CONTEXTS
    for code, kind, plate in (
        ("hs", GaitEventKind.FOOT_STRIKE, False),
        ("to", GaitEventKind.FOOT_OFF, False),
        ("on", GaitEventKind.FOOT_STRIKE, True),
        ("off", GaitEventKind.FOOT_OFF, True),
    )
}


def _key(text: str) -> str:
    """``text`` lower case without whitespace, ``_`` or ``-``."""
    return _SEPARATORS.sub("", text).lower()


def gait_label(label: str, context: str = "") -> GaitLabel | None:
    """Read an event's label and context as a gait event (module docstring).

    Args:
        label: e.g. ``"Foot Strike"``, ``"foot off"``, ``"Left Foot Strike"``, ``"LHS"``.
        context: ``"Left"``/``"Right"`` (any case) or anything else (``"General"``, ``""``).

    Returns:
        The kind and side, or None: not a gait label, no side in label or context, or a
        context naming the other side than the label.
    """
    key, context_side = _key(label), _SIDE_KEYS.get(_key(context))
    found = _CODES.get(key)
    if found is None:
        sided = [(side, key[len(word):]) for word, side in _SIDE_KEYS.items() if key.startswith(word)]
        if sided and sided[0][1] in _KIND_KEYS:
            found = GaitLabel(_KIND_KEYS[sided[0][1]], sided[0][0])
        elif key in _KIND_KEYS and context_side is not None:
            found = GaitLabel(_KIND_KEYS[key], context_side)
    if found is None or (context_side is not None and context_side != found.side):
        return None
    return found


def gait_events(events: Iterable[Event | GaitEvent]) -> list[GaitEvent]:
    """The gait events among ``events``, each label read once (module docstring).

    Args:
        events: a file's events (any spelling), or values of this function (kept as
            they are, so that a caller may pass either).

    Returns:
        In the order given: one :class:`GaitEvent` per gait event; other labels left
        out; force-plate events (``LON`` ...) only for a side and kind without other
        events; an event of the same kind, side and time as an earlier one left out.
    """
    parsed: list[GaitEvent] = []
    for event in events:
        if isinstance(event, GaitEvent):
            parsed.append(event)
            continue
        label = gait_label(event.label, event.context)
        if label is not None:
            parsed.append(GaitEvent(label.kind, label.side, event.time, event, label.plate))
    unplated = {(g.kind, g.side) for g in parsed if not g.plate}
    seen: set[tuple[GaitEventKind, str, float]] = set()
    out = []
    for item in parsed:
        identity = (item.kind, item.side, item.time)
        if identity in seen or (item.plate and (item.kind, item.side) in unplated):
            continue
        seen.add(identity)
        out.append(item)
    return out
