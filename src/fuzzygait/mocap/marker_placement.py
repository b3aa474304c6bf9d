"""Whether the markers of a walking trial sit where they sat in its static trial.

:func:`moved_markers` compares the median distances between the markers fixed on one body
segment (:data:`SEGMENT_MARKERS`) in a static/walking pair: markers moved or relabelled
between the two make the static calibration describe another marker layout, and the
angles that segment enters (:data:`SEGMENT_ANGLES`) unreliable.  Of the reference sessions
it fires on the shared Qualisys CGM 2.4 session only, on every segment but the pelvis: its
thigh and shank cluster markers sit 17-98 mm from their static places, and on both feet
the marker labelled TOE in the walking trial sits where the static trial's medial
malleolus marker MED was.  One of the content checks of :mod:`fuzzygait.mocap.sanity`
(run by the angle workflow on every static/walking pair).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fuzzygait.core.findings import Finding, FindingKind, Severity, of_kind
from fuzzygait.core.trial import Trial
from fuzzygait.mocap.gaps import labelled_markers

#: The markers fixed on one body segment (after the side letter; the pelvis has none),
#: every marker set of :mod:`fuzzygait.kinematics` together: Plug-in Gait's wands and
#: joint markers, the CGM 2.x clusters and the CGM 2.4 forefoot.  A static calibration
#: stores where they sit on their segment, so the distance between two of them in a
#: walking trial is that of its static trial unless a marker moved between the two (soft
#: tissue moves skin markers a few mm).  Measured static/walking medians on the reference
#: sessions: at most 12 mm and 7 % (Movement_trial LTIB-LANK 293/282 mm, the pig-options
#: KAD sessions LTHI-LKNE 181/193 mm, HEE-TOE within 1-7 mm on every Plug-in Gait
#: session); within 1 mm on the synthetic sessions.
SEGMENT_MARKERS: dict[str, tuple[str, ...]] = {
    "pelvis": ("LASI", "RASI", "LPSI", "RPSI", "SACR"),
    "thigh": ("THAP", "THAD", "THI", "KNE"),
    "shank": ("TIAP", "TIAD", "TIB", "ANK"),
    "foot": ("HEE", "TOE", "FMH", "SMH", "VMH"),
}
#: The angles a segment's static calibration enters (the sentence of a moved-marker note).
SEGMENT_ANGLES: dict[str, str] = {
    "pelvis": "pelvis and hip angles",
    "thigh": "hip and knee angles",
    "shank": "knee and ankle angles",
    "foot": "ankle and foot angles",
}
#: A marker pair whose walking-trial median distance differs from the static trial's by
#: more than this (mm) *and* by more than :data:`MOVED_MARKER_FRACTION` of it is reported.
MOVED_MARKER_MM = 15.0
#: Relative part of the moved-marker rule (a long foot's 7 mm is 3 %).
MOVED_MARKER_FRACTION = 0.10
#: A moved marker "sits where the static trial's Y was" when the median over the
#: segment's other markers of |walking distance to it - static distance of Y to it| is
#: at most this (mm; the shared Qualisys session's TOE against its static MED: 1.5-2 mm).
SAME_PLACE_MM = 5.0
#: The words of a moved-marker finding's message after its segment ("left foot", "pelvis").
MOVED_NOTE = "markers sit elsewhere than in the static trial"
#: At most this many changed pairs are listed in a note (the largest changes first).
MAX_PAIRS_SHOWN = 4


def median_distance(trial: Trial, a: str, b: str) -> float | None:
    """Median over the frames of the distance (mm) between markers ``a`` and ``b``."""
    if not (trial.has_marker(a) and trial.has_marker(b)):
        return None
    with np.errstate(invalid="ignore", over="ignore"):  # inf - inf: not finite, dropped
        distance = np.linalg.norm(trial.marker(a) - trial.marker(b), axis=1)
    distance = distance[np.isfinite(distance)]
    return float(np.median(distance)) if distance.size else None


def _visible(trial: Trial, marker: str) -> bool:
    """Whether ``trial`` has ``marker`` with at least one visible sample."""
    return trial.has_marker(marker) and bool(np.isfinite(trial.marker(marker)).all(axis=1).any())


def _segment_groups() -> list[tuple[str, tuple[str, ...]]]:
    """``(segment name, marker labels)``: the pelvis, then each side's thigh, shank, foot."""
    groups: list[tuple[str, tuple[str, ...]]] = [("pelvis", SEGMENT_MARKERS["pelvis"])]
    for side, long in (("L", "left"), ("R", "right")):
        for segment in ("thigh", "shank", "foot"):
            groups.append((f"{long} {segment}", tuple(side + m for m in SEGMENT_MARKERS[segment])))
    return groups


def _same_place(static: Trial, walking: Trial, marker: str, others: Sequence[str]) -> tuple[str, float] | None:
    """The static trial's marker (not ``marker``) whose distances to ``others`` the
    walking trial's ``marker`` has (median |difference| ≤ :data:`SAME_PLACE_MM`, at least
    three of ``others`` in both trials), with that median; None when none has."""
    walking_distances = {o: median_distance(walking, marker, o) for o in others}
    best: tuple[str, float] | None = None
    for candidate in labelled_markers(static.marker_labels):
        if candidate == marker or candidate in others:
            continue
        differences = []
        for other, now in walking_distances.items():
            before = median_distance(static, candidate, other)
            if now is not None and before is not None:
                differences.append(abs(now - before))
        if len(differences) >= 3 and np.median(differences) <= SAME_PLACE_MM:
            if best is None or np.median(differences) < best[1]:
                best = (candidate, float(np.median(differences)))
    return best


def _moved_markers(present: Sequence[str], flagged: Sequence[tuple[str, str]]) -> list[str]:
    """The markers of ``present`` (at least three) that the changed pairs ``flagged``
    single out: the one marker every changed pair contains (when two or more changed),
    or each marker whose every pair changed."""
    if len(present) < 3:
        return []
    pairs = {frozenset(p) for p in flagged}
    common = set(present).intersection(*pairs) if len(pairs) >= 2 else set()
    every = {m for m in present if all(frozenset((m, o)) in pairs for o in present if o != m)}
    return [m for m in present if m in common | every]


def moved_markers(static: Trial, walking: Trial) -> list[Finding]:
    """Findings (:attr:`~fuzzygait.core.findings.FindingKind.MOVED_MARKERS`, the segment in
    ``segment``, its side in ``side``), one per segment (:data:`SEGMENT_MARKERS`, the pelvis and each side's
    thigh, shank and foot), on marker pairs whose distance differs between ``static``
    and ``walking`` by more than :data:`MOVED_MARKER_MM` mm and
    :data:`MOVED_MARKER_FRACTION` of the static distance (medians over the frames).

    Such markers were moved or relabelled between the trials: the static calibration
    (the foot offsets StaticPlantFlex/StaticRotOff, a cluster model's marker positions
    in its segment frames) describes another marker layout, and the angles of
    ``walking`` that segment enters (:data:`SEGMENT_ANGLES`) are off by the angle the
    markers moved through.  A note names the largest changes, the markers they single
    out as moved (:func:`_moved_markers`), and, when such a marker now sits where
    another marker of the static trial sat (:data:`SAME_PLACE_MM`; e.g. a static-only
    medial malleolus marker left on and labelled TOE), that marker.  An empty list when
    nothing moved.
    """
    notes: list[Finding] = []
    for segment, labels in _segment_groups():
        present = [m for m in labels if _visible(static, m) and _visible(walking, m)]
        changes: list[tuple[float, str, str, str]] = []
        for i, a in enumerate(present):
            for b in present[i + 1 :]:
                before, now = median_distance(static, a, b), median_distance(walking, a, b)
                if before is None or now is None:
                    continue
                change = now - before
                if abs(change) > MOVED_MARKER_MM and abs(change) > MOVED_MARKER_FRACTION * before:
                    changes.append((abs(change), a, b, f"{a}-{b} {now:.0f} mm, static {before:.0f} mm"))
        if not changes:
            continue
        changes.sort(key=lambda c: -c[0])
        shown = "; ".join(c[3] for c in changes[:MAX_PAIRS_SHOWN])
        if len(changes) > MAX_PAIRS_SHOWN:
            shown += f"; {len(changes) - MAX_PAIRS_SHOWN} more"
        which = ""
        for marker in _moved_markers(present, [(c[1], c[2]) for c in changes]):
            which += f"; {marker} moved"
            found = _same_place(static, walking, marker, [o for o in present if o != marker])
            if found is not None:
                which += (f" and sits where the static trial's {found[0]} was (its distances to the other {segment} "
                          f"markers agree within {found[1]:.0f} mm median): {found[0]} labelled {marker}?")  # fmt: skip
        angles = SEGMENT_ANGLES[segment.split()[-1]]
        if " " in segment:  # a side's segment: that side's angles
            angles = f"{segment.split()[0]} {angles}"
        message = (f"{segment} {MOVED_NOTE} {static.name} ({shown}{which}): moved or relabelled between the "
                   f"trials, so the static calibration of the {segment} does not fit this trial and the "
                   f"{angles} are unreliable; check the labels, or calibrate on a static trial with the "
                   "walking trial's marker placement")  # fmt: skip
        side = segment.split()[0] if " " in segment else None
        notes.append(Finding(FindingKind.MOVED_MARKERS, message, Severity.WARNING, side=side, segment=segment))
    return notes


def moved_segments(notes: Sequence[Finding]) -> list[str]:
    """The segments (``"pelvis"``, ``"left thigh"``, ``"right foot"`` ...) of the
    :func:`moved_markers` findings among ``notes``, in order."""
    return [f.segment for f in of_kind(notes, FindingKind.MOVED_MARKERS) if f.segment is not None]


def moved_angles(segments: Sequence[str]) -> str:
    """The angle families :func:`moved_segments` ``segments`` make unreliable, as words:
    ``"hip, knee, ankle and foot angles"``."""
    order = ("pelvis", "hip", "knee", "ankle", "foot")
    names = {word for s in segments for word in SEGMENT_ANGLES[s.split()[-1]].split() if word in order}
    listed = [n for n in order if n in names]
    text = ", ".join(listed[:-1]) + (" and " if len(listed) > 1 else "") + listed[-1] if listed else ""
    return f"{text} angles"
