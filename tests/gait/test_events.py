"""Gait-event detection (Zeni et al. 2008) against independent truth.

Measured offsets (detected - reference, frames; negative = detected early):

* synthetic ``walking.c3d`` (100 Hz) vs its exact events: Foot Strike (heel) -5.20 on
  every strike, Foot Off (toe) -0.06.  The strike bias is the synthetic walker's, not
  the detector's: on a 1 kHz rendering of the same walk the heel is furthest in front of
  the pelvis exactly 52 ms before the defined strike (terminal-swing retraction; the
  walker has no contact model), and the detector finds those extrema within 0.06 frame.
  Toe-based strikes (heel markers removed): -5.35.  With 0.5 mm noise + gaps
  (``walking_noisy.c3d``) the extrema move by <= 0.1 frame, with 2 mm noise <= 0.34.
* ``gait-pig.c3d`` (50 Hz, no heel markers, so strikes come from the toe) vs its Vicon
  events: Foot Strike -0.36 .. -1.54 (mean -1.13 frames = -23 ms), Foot Off -0.42,
  -0.03, +0.91 frame; the right Foot Off at frame 131 lies in an RTOE gap and is not
  detected.  Two more Foot Offs before Vicon's first event are found (real events Vicon
  did not label).
* ``Movement_trial.c3d`` (120 Hz, no events; a *stair descent*: the pelvis drops 0.95 m
  while each foot lands ~185 mm lower): strides 1.04-1.14 s, Foot Off at 67-73 % of the
  cycle.  Against contact from foot speed (< 300 mm/s) the strikes are 16-18 frames
  (0.13-0.15 s) early -- the heel is furthest forward while the foot is still above the
  lower step -- and Foot Offs 2-4 frames late, so Zeni's method overestimates stance on
  stairs.
"""

from __future__ import annotations

import numpy as np
import pytest

from support import SAMPLE_DATA, shared_file
from fuzzygait.core.errors import MarkerError
from fuzzygait.io import Event, Trial, read_c3d
from fuzzygait.gait.events import (
    SOURCE_DETECTED,
    SOURCE_FILE,
    detect_gait_events,
    trial_gait_events,
)
from fuzzygait.synthetic import make_walking_trial

KINDS = [(lbl, ctx) for lbl in ("Foot Strike", "Foot Off") for ctx in ("Left", "Right")]


def _indices(trial: Trial, events: list[Event], label: str, context: str) -> np.ndarray:
    return np.array(
        [trial.event_index(e) for e in events if e.label == label and e.context == context]
    )


def _offsets(trial: Trial, detected: list[Event], reference: list[Event]) -> dict:
    """Per (label, context): detected - nearest reference event, frames."""
    out = {}
    for label, context in KINDS:
        ref = _indices(trial, reference, label, context)
        det = _indices(trial, detected, label, context)
        out[label, context] = np.array([d - ref[np.argmin(np.abs(ref - d))] for d in det])
    return out


def _without_events(trial: Trial, drop: tuple[str, ...] = ()) -> Trial:
    keep = [m for m in trial.marker_labels if m not in drop]
    stripped = trial.select_markers(keep)
    stripped.events = []
    return stripped


# ----------------------------------------------------------------- synthetic truth
def test_detected_events_are_the_signal_extrema(walking: Trial) -> None:
    """The detector finds the heel maxima / toe minima (relative to the pelvis, along
    +X) of a 1 kHz rendering of the same walk within 0.15 frame (at 100 Hz)."""
    dense, _ = make_walking_trial(rate=1000.0)
    centre = 0.5 * (dense.marker("LASI") + dense.marker("RASI"))
    detected = detect_gait_events(_without_events(walking))
    for event in detected:
        marker = ("HEE" if event.label == "Foot Strike" else "TOE")
        relative = dense.marker(event.context[0] + marker)[:, 0] - centre[:, 0]
        sign = 1.0 if event.label == "Foot Strike" else -1.0
        guess = int(round(dense.event_index(event)))
        window = slice(guess - 100, guess + 101)  # +-0.1 s around the detection
        extremum = window.start + int(np.argmax(sign * relative[window]))
        assert extremum not in (window.start, window.stop - 1)
        assert abs(dense.event_index(event) - extremum) / 10.0 <= 0.15


def test_synthetic_detection_vs_true_events(walking: Trial) -> None:
    detected = detect_gait_events(_without_events(walking))
    offsets = _offsets(walking, detected, walking.events)
    for context in ("Left", "Right"):
        # Zeni's strike = heel furthest forward: 52 ms before this walker's strike
        np.testing.assert_allclose(offsets["Foot Strike", context], -5.2, atol=0.15)
        np.testing.assert_allclose(offsets["Foot Off", context], 0.0, atol=0.15)
    # every event more than 0.15 s from the trial's ends is found, and nothing else;
    # the first left and the last right strike (0.11 s / 0.06 s from an end) are not
    interior = [
        e for e in walking.events if 0.15 < e.time < walking.times[-1] - 0.15
    ]
    assert len(detected) == len(interior) == 17
    for label, context in KINDS:
        assert len(_indices(walking, detected, label, context)) == len(
            _indices(walking, interior, label, context)
        )
    for event in detected:
        assert event.subject == walking.subject
        assert "detected (Zeni et al. 2008)" in event.description
        assert f"{event.context[0]}{'HEE' if event.label == 'Foot Strike' else 'TOE'}" in (
            event.description
        )


def test_toe_fallback_when_heel_absent_or_never_visible(walking: Trial) -> None:
    truth = walking.events
    absent = _without_events(walking, drop=("LHEE", "RHEE"))
    hidden = _without_events(walking)
    markers = hidden.markers.copy()
    for label in ("LHEE", "RHEE"):
        markers[:, hidden.marker_labels.index(label)] = np.nan
    hidden = hidden.with_markers(markers)
    for trial in (absent, hidden):
        detected = detect_gait_events(trial)
        offsets = _offsets(walking, detected, truth)
        for context in ("Left", "Right"):
            np.testing.assert_allclose(offsets["Foot Strike", context], -5.35, atol=0.15)
        strikes = [e for e in detected if e.label == "Foot Strike"]
        assert strikes and all("no visible" in e.description for e in strikes)


def test_noise_and_gaps_barely_move_the_events(walking: Trial) -> None:
    clean = detect_gait_events(_without_events(walking))
    noisy_file = read_c3d(SAMPLE_DATA / "walking_noisy.c3d")  # 0.5 mm + gaps
    trials = [_without_events(noisy_file)]
    for seed in range(3):
        rng = np.random.default_rng(seed)
        trials.append(_without_events(walking).with_markers(
            walking.markers + rng.normal(0.0, 2.0, walking.markers.shape)
        ))
    for trial, bound in zip(trials, (0.15, 0.5, 0.5, 0.5), strict=True):
        detected = detect_gait_events(trial)
        assert [(e.label, e.context) for e in detected] == [
            (e.label, e.context) for e in clean
        ]
        shifts = [abs(a.time - b.time) * walking.rate for a, b in zip(detected, clean)]
        assert max(shifts) <= bound


# ----------------------------------------------------------------- sources and errors
def test_trial_gait_events_prefers_the_file(walking: Trial) -> None:
    general = Event("Event", "General", 1.0)
    with_general = _without_events(walking)
    with_general.events = [*walking.events, general]
    events, source = trial_gait_events(with_general)
    assert source == SOURCE_FILE == "file"
    assert events == walking.events

    only_general = _without_events(walking)
    only_general.events = [general]
    events, source = trial_gait_events(only_general)
    assert source == SOURCE_DETECTED == "detected from heel/toe markers (Zeni 2008)"
    assert len(events) == 17


def test_missing_markers_raise_marker_error(walking: Trial) -> None:
    feetless = _without_events(walking, drop=("LHEE", "LTOE", "RHEE", "RTOE"))
    with pytest.raises(MarkerError, match="LHEE/LTOE .*RHEE/RTOE"):
        trial_gait_events(feetless)
    left_only = _without_events(walking, drop=("LHEE", "LTOE"))
    with pytest.raises(MarkerError, match="LHEE/LTOE") as info:
        trial_gait_events(left_only)
    assert "RHEE" not in str(info.value).split("label")[0]
    pelvis = ("LASI", "RASI", "LPSI", "RPSI", "SACR")
    with pytest.raises(MarkerError, match="LASI"):
        detect_gait_events(_without_events(walking, drop=pelvis))


def test_psis_fill_the_pelvis_centre(walking: Trial) -> None:
    """Without ASIS samples near the end (like gait-pig), the PSIS keep every event."""
    trial = _without_events(walking)
    markers = trial.markers.copy()
    for label in ("LASI", "RASI"):
        markers[-120:, trial.marker_labels.index(label)] = np.nan
    reference = detect_gait_events(_without_events(walking))
    detected = detect_gait_events(trial.with_markers(markers))
    assert len(detected) == len(reference)
    assert max(abs(a.time - b.time) for a, b in zip(detected, reference)) * 100 < 0.05


# ----------------------------------------------------------------- Vicon files
def test_gait_pig_toe_detection_vs_vicon_events() -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    assert not trial.has_marker("LHEE")
    events, source = trial_gait_events(trial)
    assert source == SOURCE_FILE and len(events) == 9
    detected = detect_gait_events(_without_events(trial))
    assert all("no visible LHEE" in e.description or "no visible RHEE" in e.description
               for e in detected if e.label == "Foot Strike")
    toe_seen = np.isfinite(trial.markers).all(axis=2)
    matched = []
    for event in trial.events:
        ref = trial.event_index(event)
        det = _indices(trial, detected, event.label, event.context)
        column = trial.marker_labels.index(event.context[0] + "TOE")
        around = toe_seen[int(ref) - 2 : int(ref) + 3, column]
        if not around.all():  # right Foot Off at frame 131: RTOE gap from frame 127
            assert (event.label, event.context) == ("Foot Off", "Right")
            assert det.size == 0 or np.min(np.abs(det - ref)) > 10
            continue
        offset = det[np.argmin(np.abs(det - ref))] - ref
        matched.append((event.label, offset))
        assert abs(offset) <= 2.0  # frames at 50 Hz = 40 ms
    strikes = np.array([o for label, o in matched if label == "Foot Strike"])
    offs = np.array([o for label, o in matched if label == "Foot Off"])
    assert strikes.size == 5 and offs.size == 3
    assert -1.6 <= strikes.mean() <= -0.6  # toe strikes early by ~1 frame (measured -1.13)
    assert np.abs(offs).max() <= 1.0
    # between Vicon's first and last event of each kind nothing spurious is detected
    # (the right Foot Off at frame 34.8, before Vicon's first one, is real: RTOE starts
    # moving at frame ~33 -- Vicon did not label it)
    for label, context in KINDS:
        ref = _indices(trial, trial.events, label, context)
        det = _indices(trial, detected, label, context)
        inside = det[(det >= ref.min() - 2) & (det <= ref.max() + 2)]
        assert np.all(np.min(np.abs(inside[:, None] - ref[None, :]), axis=1) <= 2.0)


def test_movement_trial_gets_detected_events(movement: Trial) -> None:
    assert not movement.events
    events, source = trial_gait_events(movement)
    assert source == SOURCE_DETECTED
    strikes = [e for e in events if e.label == "Foot Strike"]
    assert len(strikes) == 5
    assert all(a.context != b.context for a, b in zip(strikes, strikes[1:]))
    for context in ("Left", "Right"):
        hits = _indices(movement, events, "Foot Strike", context)
        offs = _indices(movement, events, "Foot Off", context)
        strides = np.diff(hits) / movement.rate
        assert strides.size >= 1 and np.all((strides > 0.8) & (strides < 1.6))
        for start, end in zip(hits, hits[1:]):
            inside = offs[(offs > start) & (offs < end)]
            assert inside.size == 1
            # stairs: Zeni's early strikes push foot off to 67-73 % (level walking ~60 %)
            assert 55.0 <= 100 * (inside[0] - start) / (end - start) <= 75.0


def test_movement_trial_bias_against_foot_speed(movement: Trial) -> None:
    """Stair descent: strikes precede foot-speed contact by 0.1-0.2 s; foot off is
    within 0.05 s of the foot starting to move."""
    events, _ = trial_gait_events(movement)
    for side, context in (("L", "Left"), ("R", "Right")):
        speeds = [
            np.linalg.norm(np.gradient(movement.marker(side + m), axis=0), axis=1)
            for m in ("HEE", "TOE")
        ]
        still = np.minimum(*speeds) * movement.rate < 300.0  # mm/s
        change = np.diff(still.astype(int))
        contact, lift = np.flatnonzero(change == 1) + 1, np.flatnonzero(change == -1)
        for label, reference, low, high in (
            ("Foot Strike", contact, -0.2, -0.1),
            ("Foot Off", lift, -0.05, 0.05),
        ):
            for index in _indices(movement, events, label, context):
                nearest = reference[np.argmin(np.abs(reference - index))]
                offset = (index - nearest) / movement.rate
                assert low <= offset <= high, (label, context, offset)
