"""Gait events: the file's Foot Strike / Foot Off events, or detected ones.

The file's events are read once into typed :class:`~fuzzygait.gait.event_labels.GaitEvent`
values; the spellings recognised (Vicon Nexus, Vicon Workstation, Qualisys, Visual3D) and
how the side is found are in :mod:`fuzzygait.gait.event_labels`.

Detection (coordinate-based, Zeni et al. 2008)
----------------------------------------------
Zeni JA, Richards JG, Higginson JS (2008), "Two simple methods for determining gait
events during treadmill and overground walking using kinematic data", Gait & Posture
27:710-714.  Along the walking direction, relative to the pelvis,

* **Foot Strike** is a maximum of the heel marker's position (the foot is furthest in
  front of the pelvis at initial contact);
* **Foot Off** is a minimum of the toe marker's position (the foot is furthest behind).

Implementation:

1. *Pelvis centre*: the ASIS midpoint (``LASI``/``RASI``); where it is missing it is
   filled from the PSIS midpoint (``LPSI``/``RPSI``) or ``SACR`` plus their mean offset
   from it (in the lab frame, over the frames where both are seen).  Without ASIS the
   first available of those two is the centre.  Only the forward component is used, and
   that offset changes by < 1 mm over a straight walk (pelvis rotation of a few degrees),
   so the fill is harmless; it matters for files whose ASIS drop out near an end
   (``gait-pig.c3d`` loses them for the last 28 frames).
2. *Walking direction*: the forward axis of
   :func:`fuzzygait.kinematics.progression.progression_frame` (the lab axis ±X/±Y along
   which the pelvis travels; for a treadmill/static trial the one it faces, with the
   pelvis anterior axis approximated by ``(LASI - RASI) x up``).
3. *Signal*: ``(marker - pelvis centre) . forward`` in mm, low-pass filtered at
   :data:`SMOOTHING_CUTOFF_HZ` (4th-order zero-lag Butterworth, each run of visible
   samples on its own; runs too short to filter are kept raw).
4. *Peaks*: :func:`scipy.signal.find_peaks` with a prominence of at least
   :data:`PROMINENCE_FRACTION` of the signal's 5-95 % range and a separation of at least
   :data:`MIN_SEPARATION_STRIDES` of the stride (the stride is estimated as the median
   spacing of the prominent peaks of all the trial's signals).  NaN stretches are
   bridged by straight lines *only* for this search (so a one-frame dropout does not cut
   a peak's prominence); a peak is kept only if :data:`PEAK_HALF_WINDOW` samples on each
   side of it are visible, so no event is placed in or at the edge of a gap.  Hence
   events inside gaps and at the trial's very ends (where a peak's prominence cannot be
   established) are missing -- edge events may be missing.
5. *Sub-frame time*: a parabola through the peak sample and its two neighbours; its
   vertex ``i + (y[i-1] - y[i+1]) / (2 (y[i-1] - 2 y[i] + y[i+1]))`` (within ±0.5
   frame) is the event's fractional sample index.

When a side's heel marker is absent or never visible, its Foot Strike is taken from the
toe marker's maxima instead, and the event description says so ("no visible LHEE").
Foot Off needs the toe marker.

Measured accuracy (detected - reference, frames; ``tests/test_events.py``):

* synthetic walking trial (100 Hz) vs its exact events: Foot Strike from the heel -5.2
  (every strike), from the toe -5.35; Foot Off -0.06.  The strike bias belongs to the
  method on this walker: rendered at 1 kHz, its heel is furthest in front of the pelvis
  52 ms before the defined strike (the swing foot retracts before contact), and the
  detector finds the extrema within 0.06 frame (0.1 with 0.5 mm noise, 0.34 with 2 mm).
* ``gait-pig.c3d`` (50 Hz, no heel markers) vs its Vicon events: Foot Strike from the
  toe -0.4 .. -1.5 frames (mean -1.1 = -23 ms), Foot Off within 0.9 frame.
* ``Movement_trial.c3d`` (120 Hz, stair descent, no events): strikes 0.13-0.15 s before
  the foot stops (foot speed), foot offs 0.02-0.03 s after it starts to move -- on
  stairs the foot is furthest forward while still above the lower step, so stance is
  overestimated (foot off at 67-73 % instead of ~57 %).  Zeni's method assumes level
  walking; prefer file events or a velocity-based method for stairs.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.trial import Event, Trial
from fuzzygait.gait.event_labels import SIDE_CONTEXTS, GaitEvent, GaitEventKind, gait_events
from fuzzygait.gait.event_labels import GaitLabel as GaitLabel  # re-exported: tests use it
from fuzzygait.gait.event_labels import gait_label as gait_label  # re-exported: tests and docs use it
from fuzzygait.kinematics.progression import progression_frame
from fuzzygait.mocap.filtering import ShortRunWarning, butterworth_lowpass
from fuzzygait.mocap.sanity import find_spikes, motionless

#: Source string of :func:`trial_gait_events` for the file's own events.
SOURCE_FILE = "file"
#: Source string of :func:`trial_gait_events` for detected events.
SOURCE_DETECTED = "detected from heel/toe markers (Zeni 2008)"
#: Start of the source string of :func:`trial_gait_events` for a motionless trial.
SOURCE_MOTIONLESS = "none detected"



#: -3 dB cutoff (Hz) of the zero-lag low-pass applied to the relative marker signals.
SMOOTHING_CUTOFF_HZ = 6.0
#: Minimum peak prominence as a fraction of the signal's 5-95 percentile range.
PROMINENCE_FRACTION = 0.25
#: Minimum separation of two peaks of one signal, as a fraction of the stride.
MIN_SEPARATION_STRIDES = 0.35

#: Visible samples required on each side of a peak sample.
PEAK_HALF_WINDOW = 2

#: Pelvis markers, in order of preference, whose mean is a pelvis centre.
PELVIS_MARKER_SETS: tuple[tuple[str, ...], ...] = (
    ("LASI", "RASI"),
    ("LPSI", "RPSI"),
    ("SACR",),
)


@dataclass(frozen=True)
class _FootSignal:
    """One relative-position signal to search for maxima: which event and side."""

    kind: GaitEventKind
    side: str
    values: np.ndarray  # (n_frames,) mm, forward position relative to the pelvis
    description: str


def _visible(trial: Trial, label: str) -> bool:
    """Whether ``label`` exists and is seen in at least one frame."""
    return trial.has_marker(label) and bool(np.isfinite(trial.marker(label)).all(axis=1).any())


def _marker_mean(trial: Trial, labels: Sequence[str]) -> np.ndarray:
    """``(n_frames, 3)`` mean position of ``labels`` (NaN where any is missing), mm."""
    return np.mean([trial.marker(lbl) for lbl in labels], axis=0)


def _pelvis_centre(trial: Trial) -> np.ndarray:
    """Pelvis centre ``(n_frames, 3)`` in mm (see the module docstring, step 1).

    Raises:
        MarkerError: when none of the pelvis marker sets is visible.
    """
    sets = [s for s in PELVIS_MARKER_SETS if all(_visible(trial, m) for m in s)]
    if not sets:
        raise MarkerError(
            f"{trial.name}: cannot detect gait events: no visible pelvis markers "
            f"(need {' + '.join(PELVIS_MARKER_SETS[0])}, "
            f"{' + '.join(PELVIS_MARKER_SETS[1])} or {PELVIS_MARKER_SETS[2][0]})"
        )
    centre = _marker_mean(trial, sets[0])
    for other in sets[1:]:
        missing = ~np.isfinite(centre).all(axis=1)
        if not missing.any():
            break
        substitute = _marker_mean(trial, other)
        both = ~missing & np.isfinite(substitute).all(axis=1)
        if both.any():
            offset = np.mean(centre[both] - substitute[both], axis=0)
            centre[missing] = substitute[missing] + offset
    return centre


def _forward_axis(trial: Trial, centre: np.ndarray) -> np.ndarray:
    """Unit walking direction (lab, 3-vector) from the progression frame."""
    if trial.has_marker("LASI") and trial.has_marker("RASI"):
        left = trial.marker("LASI") - trial.marker("RASI")
        anterior = np.cross(left, [0.0, 0.0, 1.0])
        anterior /= np.linalg.norm(anterior, axis=1, keepdims=True)
    else:
        anterior = np.full_like(centre, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # nanmean of an all-NaN slice
        forward = progression_frame(centre, anterior)[:, 0]
    if not np.all(np.isfinite(forward)):
        raise MarkerError(
            f"{trial.name}: cannot find the walking direction: the pelvis does not travel "
            "and LASI/RASI (to tell where it faces) are missing"
        )
    return forward


def _foot_signals(trial: Trial) -> list[_FootSignal]:
    """The signals to search for Foot Strike maxima and Foot Off minima (negated)."""
    missing: list[str] = []
    pending: list[tuple[GaitEventKind, str, str, float, str]] = []  # kind, side, marker, sign, text
    for side, context in SIDE_CONTEXTS.items():
        heel, toe = f"{side}HEE", f"{side}TOE"
        has_heel, has_toe = _visible(trial, heel), _visible(trial, toe)
        if not (has_heel or has_toe):
            missing.append(f"{heel}/{toe} ({context.lower()} foot)")
            continue
        if has_heel:
            strike = (heel, f"maximum of {heel}")
        else:
            strike = (toe, f"maximum of {toe} (no visible {heel}; toe instead of heel)")
        pending.append((GaitEventKind.FOOT_STRIKE, side, strike[0], 1.0, strike[1]))
        if has_toe:
            pending.append((GaitEventKind.FOOT_OFF, side, toe, -1.0, f"minimum of {toe}"))
    if missing:
        raise MarkerError(
            f"{trial.name}: no Foot Strike/Foot Off events in the file and none can be "
            f"detected: marker(s) {', '.join(missing)} missing or never visible; "
            "label a heel (LHEE, RHEE) or toe (LTOE, RTOE) marker per foot, or add events"
        )
    centre = _pelvis_centre(trial)
    forward = _forward_axis(trial, centre)
    cutoff = min(SMOOTHING_CUTOFF_HZ, 0.4 * trial.rate)  # stay below Nyquist at low rates
    signals = []
    for kind, side, marker, sign, text in pending:
        relative = (trial.marker(marker) - centre) @ forward
        with warnings.catch_warnings():
            # runs too short to filter are too short to hold a stride's peak anyway
            warnings.simplefilter("ignore", ShortRunWarning)
            smooth = butterworth_lowpass(relative, trial.rate, cutoff)
        description = (
            f"detected (Zeni et al. 2008): {text} forward of the pelvis centre, "
            f"{cutoff:g} Hz low-pass, parabolic sub-frame peak"
        )
        signals.append(_FootSignal(kind, side, sign * smooth, description))
    return signals


def _peak_indices(values: np.ndarray, distance: float | None) -> np.ndarray:
    """Prominent maxima of ``values`` (sample indices) with :data:`PEAK_HALF_WINDOW`
    visible samples on both sides (see the module docstring, step 4)."""
    finite = np.isfinite(values)
    if finite.sum() < 2 * PEAK_HALF_WINDOW + 1:
        return np.empty(0, dtype=int)
    low, high = np.percentile(values[finite], [5.0, 95.0])
    prominence = PROMINENCE_FRACTION * max(high - low, np.finfo(float).tiny)
    samples = np.arange(values.size)
    bridged = np.interp(samples, samples[finite], values[finite])
    separation = None if distance is None else max(1.0, distance)
    peaks, _ = find_peaks(bridged, prominence=prominence, distance=separation)
    window = np.lib.stride_tricks.sliding_window_view(
        np.pad(finite, PEAK_HALF_WINDOW), 2 * PEAK_HALF_WINDOW + 1
    )
    return peaks[window[peaks].all(axis=1)]


def _stride_samples(signals: Sequence[_FootSignal]) -> float | None:
    """Stride estimate (samples): median spacing of prominent peaks of every signal."""
    spacings = [np.diff(_peak_indices(s.values, None)) for s in signals]
    spacings = [d for d in spacings if d.size]
    return float(np.median(np.concatenate(spacings))) if spacings else None


def _parabolic_vertex(values: np.ndarray, index: int) -> float:
    """Fractional index of the vertex of the parabola through ``index - 1 .. index + 1``."""
    left, centre, right = values[index - 1 : index + 2]
    curvature = left - 2.0 * centre + right
    if curvature >= 0.0:  # flat top: keep the sample
        return float(index)
    return index + float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))


def _without_spikes(trial: Trial) -> Trial:
    """``trial`` with the implausible samples of the markers the detection reads set
    missing (:func:`fuzzygait.mocap.sanity.find_spikes`; the NaN are bridged by the peak
    search), so that a 1e30 sample does not move every peak after the low-pass: the
    angle workflow blanks and notes them before (``check_trial``), this keeps the
    detection right for any caller."""
    used = [m for m in (*(m for s in PELVIS_MARKER_SETS for m in s), "LHEE", "RHEE", "LTOE", "RTOE")
            if trial.has_marker(m)]  # fmt: skip
    spikes = find_spikes(trial, used)
    if not spikes:
        return trial
    markers = trial.markers.copy()
    for label, samples in spikes.items():
        markers[samples, trial.marker_labels.index(label), :] = np.nan
    return trial.with_markers(markers)


def detect_gait_events(trial: Trial) -> list[Event]:
    """Foot Strike / Foot Off events of both feet from marker kinematics (Zeni 2008).

    See the module docstring for the method, its sub-frame interpolation, the heel ->
    toe fallback and the measured biases.  The trial's own events are ignored.

    Args:
        trial: markers in mm; needs ``LASI``+``RASI`` (or ``LPSI``+``RPSI``, or
            ``SACR``) and, per foot, ``?HEE`` and/or ``?TOE``.

    Returns:
        Events sorted by time (s on the C3D clock), labelled like Vicon Nexus
        (``"Foot Strike"``/``"Foot Off"``, context ``"Left"``/``"Right"``), subject
        ``trial.subject``; the ``description`` names the method and the marker used.
        Events at the very ends of the trial or of a marker's visible runs may be
        missing; none for a motionless trial
        (:func:`fuzzygait.mocap.sanity.motionless`: pelvis
        and feet within 100 mm over the trial), whose peaks are noise.

    Raises:
        MarkerError: naming the markers, when a foot has neither heel nor toe marker,
            no pelvis marker is visible, or the walking direction cannot be found.
    """
    return [g.event for g in _detected(trial)]


def _detected(trial: Trial) -> list[GaitEvent]:
    """:func:`detect_gait_events` as typed values, sorted by time."""
    if motionless(trial) is not None:
        return []
    signals = _foot_signals(_without_spikes(trial))
    stride = _stride_samples(signals)
    distance = None if stride is None else MIN_SEPARATION_STRIDES * stride
    events = []
    for sig in signals:
        for index in _peak_indices(sig.values, distance):
            sample = _parabolic_vertex(sig.values, int(index))
            time = (trial.first_frame + sample - 1.0) / trial.rate
            event = Event(sig.kind.value, SIDE_CONTEXTS[sig.side], time, trial.subject, sig.description)
            events.append(GaitEvent(sig.kind, sig.side, time, event))
    return sorted(events, key=lambda g: (g.time, g.event.context, g.event.label))


def file_gait_events(trial: Trial) -> list[Event]:
    """The trial's own foot strikes and foot offs of the left and right feet, in any
    spelling of :mod:`fuzzygait.gait.event_labels`, spelled as Vicon Nexus writes them
    (:meth:`GaitEvent.as_event`; a Nexus file's events are returned as they are)."""
    return [g.as_event() for g in gait_events(trial.events)]


def trial_gait_events_typed(trial: Trial) -> tuple[list[GaitEvent], str]:
    """:func:`trial_gait_events` as typed values (the file's labels read once)."""
    events = gait_events(trial.events)
    if events:
        return events, SOURCE_FILE
    still = motionless(trial)
    if still is not None:
        return [], f"{SOURCE_MOTIONLESS}: {still}"
    return _detected(trial), SOURCE_DETECTED


def trial_gait_events(trial: Trial) -> tuple[list[Event], str]:
    """The file's gait events, or detected ones when it has none.

    Returns:
        ``(events, source)``: ``source`` is :data:`SOURCE_FILE` (``"file"``) when the
        trial carries any left/right foot strike or foot off in a spelling of
        :mod:`fuzzygait.gait.event_labels` (``Foot Strike``, ``foot off``, ``LHS``, ``Right Foot Off`` ...; then
        only those are returned, spelled as Vicon Nexus writes them:
        :func:`file_gait_events`), else :data:`SOURCE_DETECTED` (``"detected from
        heel/toe markers (Zeni 2008)"``) with the events of :func:`detect_gait_events`
        -- report it; for a motionless trial no events and ``"none detected: the trial
        is motionless (...)"`` (:data:`SOURCE_MOTIONLESS`; its peaks would be noise).
        Times in s on the C3D clock.

    Raises:
        MarkerError: the file has no events and the markers needed for detection are
            missing (the message names them).
    """
    events, source = trial_gait_events_typed(trial)
    return [g.as_event() for g in events], source
