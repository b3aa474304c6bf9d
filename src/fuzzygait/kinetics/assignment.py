"""Which plate's load acts on which foot, frame by frame.

:func:`stored_assignment` reads the assignment Nexus made from the ground reaction it
stored (``L/RGroundReactionForce``, N/kg): on each frame where Nexus has a value, the
plate whose frame load (:func:`fuzzygait.kinetics.ground.plate_load`) equals it is the
one on that foot.  It reproduces Nexus' ground load to recompute its kinetics, and shows
where Nexus changed plates within one of its windows (``PiGKadMed_Motion.c3d``: the left
foot's window holds the end of one contact on plate 2 and a whole contact on plate 1).
"""

from __future__ import annotations

import enum
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.core.names import Side
from fuzzygait.kinetics.ground import PlateSignals, frame_means, no_load, plate_load, samples_per_frame
from fuzzygait.kinetics.inverse_dynamics import Load

#: How far (N/kg) a plate's frame force may be from the stored ground reaction and still
#: be the plate Nexus used (the stored values are single-precision floats).
MATCH_TOLERANCE = 1e-3


@dataclass(frozen=True)
class StoredAssignment:
    """Nexus' plate assignment of one side.

    Attributes:
        plate: ``(n,)`` int, the 1-based plate number on each frame, 0 where Nexus has no
            ground reaction for this foot.
        unmatched: ``(n,)`` bool, frames where Nexus has a ground reaction that no single
            plate's load matches (``plate`` is then the nearest).
    """

    plate: NDArray[np.int_]
    unmatched: NDArray[np.bool_]


def stored_assignment(plates: Sequence[PlateSignals], outputs: Mapping[str, NDArray[np.float64]], side: Side,
                      body_mass: float, rate: float) -> StoredAssignment:  # fmt: skip
    """The plates Nexus put under the ``side`` foot, from its stored ground reaction.

    Args:
        plates: the trial's plates at their own rate (their first sample at the first
            frame), read with every sample in contact (threshold 0 N): Nexus' ground
            reaction includes the noise of a plate before and after the foot's contact.
        outputs: the trial's stored outputs (``L/RGroundReactionForce`` in N/kg).
        side: the foot.
        body_mass: kg, the mass Nexus normalised with.
        rate: marker frames per second.
    """
    stored = outputs[side.value + "GroundReactionForce"] * body_mass
    n = len(stored)
    window = np.all(np.isfinite(stored), axis=1)
    if not plates:
        return StoredAssignment(np.zeros(n, dtype=int), window.copy())
    loads = [plate_load(p, n, rate) for p in plates]
    distance = np.stack([np.linalg.norm(load.force - np.nan_to_num(stored), axis=1) for load in loads], axis=1)
    best = np.argmin(distance, axis=1)
    unmatched = window & (distance[np.arange(n), best] > MATCH_TOLERANCE * body_mass)
    return StoredAssignment(np.where(window, np.array([p.number for p in plates])[best], 0), unmatched)


def assigned_ground(plates: Sequence[PlateSignals], plate: NDArray[np.int_], rate: float) -> Load:
    """The ground's load on a foot whose plate on each frame is ``plate`` (``(n,)``
    1-based numbers, 0: off the plates)."""
    n = len(plate)
    force, moment = np.zeros((n, 3)), np.zeros((n, 3))
    for p in plates:
        on = plate == p.number
        if on.any():
            load = plate_load(p, n, rate)
            force[on], moment[on] = load.force[on], load.moment[on]
    return Load(np.zeros((n, 3)), force, moment) if plates else no_load(n)


# ------------------------------------------------------------------------ automatic
#: Contacts shorter than this (s) or peaking below MIN_PEAK x the contact threshold are
#: noise, not a foot (a step lasts several tenths of a second).
MIN_CONTACT_S = 0.05
MIN_PEAK = 5.0
#: How far (mm, horizontally) the centre of pressure may lie from a foot's heel-toe line
#: for the load to be that foot's: half a foot's width and the markers' offsets.
REACH_MM = 60.0
#: How far (mm) the heel and ankle markers may lie outside the plate's outline in the
#: middle third of a contact (foot flat): the heel marker sits behind the point of the
#: heel that touches, by its radius and more.
EDGE_MARGIN_MM = 25.0


class PlateCorners(PlateSignals, Protocol):
    """A plate's signals and its outline: ``corners`` ``(4, 3)`` mm, laboratory frame, in
    order round the plate (a :class:`fuzzygait.io.force_plates.ForcePlate`)."""

    @property
    def corners(self) -> NDArray[np.float64]: ...


@dataclass(frozen=True)
class Foot:
    """A foot's markers, ``(n, 3)`` mm, laboratory frame."""

    heel: NDArray[np.float64]
    toe: NDArray[np.float64]
    ankle: NDArray[np.float64]


class ContactUse(enum.Enum):
    """Whether a plate contact is used, and why (not)."""

    #: The automatic rule gave it to the foot over the centre of pressure.
    USED = "used"
    #: The subject file puts the plate under this foot (``[force_plates]``).
    ASSIGNED = "assigned"
    #: The subject file puts no foot on the plate.
    EXCLUDED = "excluded"
    #: No foot's heel-toe line within reach of the centre of pressure.
    NO_FOOT = "no_foot"
    #: Both feet's heel-toe lines within reach of the centre of pressure (median).
    BOTH_FEET = "both_feet"
    #: The other foot came within reach of the centre of pressure during the contact.
    OTHER_FOOT = "other_foot"
    #: The foot's heel or ankle marker beyond the plate's outline in mid-stance.
    OFF_EDGE = "off_edge"
    #: The foot on another plate at the same time.
    TWO_PLATES = "two_plates"

    @property
    def used(self) -> bool:
        """The contact's load acts on a foot."""
        return self in (ContactUse.USED, ContactUse.ASSIGNED)


#: The text of each reason, ``{foot}`` the foot's word in lower case.
_REASON_TEXT = {
    ContactUse.USED: "used by the {foot} foot",
    ContactUse.ASSIGNED: "used by the {foot} foot, as the subject file assigns the plate",
    ContactUse.EXCLUDED: "not used: the subject file assigns the plate to no foot",
    ContactUse.NO_FOOT: "not used: no foot over the centre of pressure",
    ContactUse.BOTH_FEET: "not used: both feet over the centre of pressure",
    ContactUse.OTHER_FOOT: "not used: both feet on the plate during the contact",
    ContactUse.OFF_EDGE: "not used: {foot} foot off the plate's edge",
    ContactUse.TWO_PLATES: "not used: {foot} foot on two plates at once",
}


@dataclass(frozen=True)
class PlateContact:
    """One contact on one plate and the foot it went to.

    Attributes:
        plate: 1-based plate number.
        first, last: the contact's first and last frame (0-based indices of the trial).
        side: the foot whose load it is, or None when it is not used.
        reason: whether and why (not) it is used.
        foot: of an unused contact, the foot the reason is about (off the plate's edge,
            on two plates), else None.
        cut: the recording starts or ends while the plate is loaded: the contact is longer
            than its frames here.
    """

    plate: int
    first: int
    last: int
    side: Side | None
    reason: ContactUse = ContactUse.USED
    foot: Side | None = None
    cut: bool = False

    def cut_text(self) -> str:
        """``" (the recording ends during it)"`` or starts, for a :attr:`cut` contact; else ''."""
        if not self.cut:
            return ""
        return " (the recording starts during it)" if self.first == 0 else " (the recording ends during it)"

    def describe(self) -> str:
        """What became of the contact, e.g. ``"not used: left foot off the plate's edge"``."""
        foot = self.side or self.foot
        return _REASON_TEXT[self.reason].format(foot=foot.word.lower() if foot else "")

    def finding(self, first_frame: int = 1) -> Finding:
        """The contact as a :attr:`~fuzzygait.core.findings.FindingKind.FORCE_PLATE_ASSIGNMENT`
        finding; its frames numbered from ``first_frame`` (the trial's first C3D frame).
        A warning when a foot made it and it is not used (both feet, off the edge, two
        plates); ``side`` the foot it is about."""
        foot = self.side or self.foot
        warn = self.reason in (ContactUse.BOTH_FEET, ContactUse.OTHER_FOOT, ContactUse.OFF_EDGE, ContactUse.TWO_PLATES)
        frames = f"{first_frame + self.first}-{first_frame + self.last}"
        text = f"force plate {self.plate}, frames {frames}{self.cut_text()}: {self.describe()}"
        return Finding(FindingKind.FORCE_PLATE_ASSIGNMENT, text, Severity.WARNING if warn else Severity.INFO,
                       side=foot.word.lower() if foot else None)  # fmt: skip


def contact_findings(contacts: Sequence[PlateContact], first_frame: int = 1) -> list[Finding]:
    """One finding per contact (:meth:`PlateContact.finding`), in order."""
    return [c.finding(first_frame) for c in contacts]


def over_plate(points: NDArray[np.float64], corners: NDArray[np.float64], margin: float = 0.0) -> NDArray[np.bool_]:
    """``(n,)``: the points (``(n, 3)`` mm) whose projection on the plate lies inside its
    outline (``corners``, ``(4, 3)`` mm, in order round a rectangle) grown by ``margin`` mm
    on every side; NaN points are not."""
    origin, e1, e2 = corners[1], corners[0] - corners[1], corners[2] - corners[1]
    l1, l2 = np.linalg.norm(e1), np.linalg.norm(e2)
    s = (points - origin) @ (e1 / l1)
    t = (points - origin) @ (e2 / l2)
    with np.errstate(invalid="ignore"):
        return (s >= -margin) & (s <= l1 + margin) & (t >= -margin) & (t <= l2 + margin)


def frame_contacts(plate: PlateSignals, n_frames: int, rate: float, threshold_n: float) -> list[tuple[int, int]]:
    """The contacts of ``plate``: runs of frames (first, last) where most of a frame's
    samples are in contact, at least :data:`MIN_CONTACT_S` long and peaking above
    :data:`MIN_PEAK` x ``threshold_n`` (N)."""
    ratio = samples_per_frame(plate.rate, rate)
    on = frame_means(np.asarray(plate.contact, dtype=float), ratio, n_frames) > 0.5
    fz = np.abs(frame_means(np.nan_to_num(np.asarray(plate.force, dtype=float)[:, 2]), ratio, n_frames))
    edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(np.int8), [0]])))
    runs = [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    long_enough = MIN_CONTACT_S * rate
    return [(a, b) for a, b in runs if (b - a + 1) >= long_enough and fz[a : b + 1].max() > MIN_PEAK * threshold_n]


def cop_distance(foot: Foot, cop: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n,)`` mm: the horizontal distance (laboratory x, y) of the centre of pressure from
    the foot's heel-toe segment; NaN where a marker or the COP is missing."""
    heel, line, rel = foot.heel[:, :2], (foot.toe - foot.heel)[:, :2], (cop - foot.heel)[:, :2]
    along = np.clip(np.einsum("ni,ni->n", rel, line) / np.einsum("ni,ni->n", line, line), 0.0, 1.0)
    return np.linalg.norm(rel - along[:, None] * line, axis=1) + 0.0 * heel[:, 0]


def _contact_foot(plate: PlateCorners, feet: Mapping[Side, Foot], cop: NDArray[np.float64],
                  frames: slice) -> tuple[Side | None, ContactUse]:  # fmt: skip
    """The foot of one contact, or None and why none (off the edge: the foot is the
    side the contact is about, the one returned with :attr:`ContactUse.OFF_EDGE`)."""
    near = {side: cop_distance(foot, cop)[frames] for side, foot in feet.items()}
    loaded = [side for side, d in near.items() if np.nanmedian(d) <= REACH_MM]
    touching = [side for side, d in near.items() if np.nanmin(d) <= REACH_MM]
    if len(loaded) != 1:
        return None, ContactUse.NO_FOOT if not loaded else ContactUse.BOTH_FEET
    side = loaded[0]
    if len(touching) > 1:
        return None, ContactUse.OTHER_FOOT
    foot = feet[side]
    length = frames.stop - frames.start
    middle = slice(frames.start + length // 3, frames.stop - length // 3)
    rearfoot = (foot.heel[middle], foot.ankle[middle])
    if not all(over_plate(points, plate.corners, EDGE_MARGIN_MM).all() for points in rearfoot):
        return side, ContactUse.OFF_EDGE
    return side, ContactUse.USED


def automatic_assignment(plates: Sequence[PlateCorners], feet: Mapping[Side, Foot], rate: float,
                         threshold_n: float, *, override: Mapping[int, Side | None] | None = None,
                         ) -> list[PlateContact]:  # fmt: skip
    """Each contact of each plate to one foot: the foot whose heel-toe line the centre of
    pressure stays within :data:`REACH_MM` of (median over the contact), with its heel and
    ankle markers over the plate through the middle third of the contact, the foot flat
    (at heel strike the heel marker may still be behind the edge it lands on; the toes may
    overhang, as on a stair).  Not used: a contact no foot or both feet are over, a contact the other foot
    also comes within reach of, a foot off the plate's edge, and the contacts of a foot on
    two plates at once.

    Args:
        plates: the plates at their own rate (first sample at the first frame).
        feet: per side the foot markers (a side without them is absent).
        rate: marker frames per second; ``threshold_n`` the plates' contact threshold (N).
        override: plate number -> the foot on it, None for none (a subject file's
            ``[force_plates]``, :func:`fuzzygait.io.subject.read_force_plate_assignment`):
            each contact of such a plate goes to that foot (:attr:`ContactUse.ASSIGNED`)
            or to none (:attr:`ContactUse.EXCLUDED`) instead of the rule's choice; a foot
            on two plates at once is still not used.

    Raises:
        ParameterError: ``override`` names a plate the trial does not have.
    """
    override = dict(override or {})
    numbers = [p.number for p in plates]
    unknown = sorted(set(override) - set(numbers))
    if unknown:
        raise ParameterError(f"the subject file's [force_plates] names plate {', '.join(map(str, unknown))}, "
                             f"but the trial has plates {', '.join(map(str, numbers)) or 'none'}")  # fmt: skip
    contacts: list[PlateContact] = []
    n_frames = len(next(iter(feet.values())).heel) if feet else 0
    for plate in plates:
        ratio = samples_per_frame(plate.rate, rate)
        cop = frame_means(np.where(np.asarray(plate.contact)[:, None], plate.cop, 0.0), ratio, n_frames)
        weight = frame_means(np.asarray(plate.contact, dtype=float), ratio, n_frames)
        cop = np.where(weight[:, None] > 0, cop / np.maximum(weight, 1e-12)[:, None], np.nan)
        for first, last in frame_contacts(plate, n_frames, rate, threshold_n):
            cut = first == 0 or last == n_frames - 1  # loaded at the recording's first or last frame
            if plate.number in override:
                side = override[plate.number]
                reason = ContactUse.ASSIGNED if side is not None else ContactUse.EXCLUDED
                contacts.append(PlateContact(plate.number, first, last, side, reason, cut=cut))
                continue
            side, reason = _contact_foot(plate, feet, cop, slice(first, last + 1))
            contacts.append(PlateContact(plate.number, first, last, side, reason, cut=cut) if reason.used
                            else PlateContact(plate.number, first, last, None, reason, side, cut))  # fmt: skip
    return _one_plate_per_foot(contacts)


def _one_plate_per_foot(contacts: list[PlateContact]) -> list[PlateContact]:
    """Contacts of one foot on two plates at the same time become unused."""
    out = []
    for c in contacts:
        clash = c.side is not None and any(
            o is not c and o.side is c.side and o.first <= c.last and c.first <= o.last for o in contacts)
        out.append(replace(c, side=None, reason=ContactUse.TWO_PLATES, foot=c.side) if clash else c)
    return out


def contact_ground(plates: Sequence[PlateSignals], contacts: Sequence[PlateContact], side: Side, n_frames: int,
                   rate: float) -> Load:  # fmt: skip
    """The ground's load on the ``side`` foot: its used contacts' plate loads, on their frames."""
    plate = np.zeros(n_frames, dtype=int)
    for c in contacts:
        if c.side is side:
            plate[c.first : c.last + 1] = c.plate
    return assigned_ground(plates, plate, rate)
