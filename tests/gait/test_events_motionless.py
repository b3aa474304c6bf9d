"""A motionless trial does not "find" foot strikes (issue 17): standing still, the heel
and toe signals are noise, whose peaks the detector used to report as events."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support import SAMPLE_DATA, VICON, needs_shared

from fuzzygait.gait.events import SOURCE_DETECTED, SOURCE_MOTIONLESS, detect_gait_events, trial_gait_events
from fuzzygait.io import read_c3d


def _standing_with_noise(trial, seed=17, sd=0.5):
    """``trial``'s first frame held for every frame, plus ``sd`` mm of noise: a walking
    trial whose pelvis does not move."""
    rng = np.random.default_rng(seed)
    held = np.repeat(trial.markers[:1], trial.n_frames, axis=0)
    return trial.with_markers(held + rng.normal(0.0, sd, held.shape))


def test_a_frozen_walking_trial_has_no_events():
    walking = replace(read_c3d(SAMPLE_DATA / "walking.c3d"), events=[])  # detect, not the file's
    frozen = _standing_with_noise(walking)
    events, source = trial_gait_events(frozen)
    assert events == [] and detect_gait_events(frozen) == []
    assert source.startswith(f"{SOURCE_MOTIONLESS}: the trial is motionless (ranges over the trial: pelvis ")
    # the same trial walking still gets its events: 2 strikes a foot at least
    events, source = trial_gait_events(walking)
    assert source == SOURCE_DETECTED
    assert sum(e.label == "Foot Strike" and e.context == "Left" for e in events) >= 2


def test_a_treadmill_walk_still_gets_its_events():
    """Pelvis held in place (a treadmill), feet swinging: the same events as overground."""
    walking = replace(read_c3d(SAMPLE_DATA / "walking.c3d"), events=[])
    centre = np.nanmean([walking.marker("LASI"), walking.marker("RASI")], axis=0)
    treadmill = walking.with_markers(walking.markers - (centre - centre[0])[:, None, :])
    events, source = trial_gait_events(treadmill)
    assert source == SOURCE_DETECTED
    reference = detect_gait_events(walking)
    assert [(e.label, e.context) for e in events] == [(e.label, e.context) for e in reference]
    np.testing.assert_allclose([e.time for e in events], [e.time for e in reference], atol=0.02)


@needs_shared
def test_the_real_static_trial_as_walking_has_no_events():
    events, source = trial_gait_events(read_c3d(VICON / "Static_trial.c3d"))
    assert events == []
    assert source.startswith("none detected: the trial is motionless (ranges over the trial: pelvis 7 mm")


@pytest.mark.parametrize("sd", [0.5, 3.0])
def test_noise_alone_never_gives_events(sd):
    static = replace(read_c3d(SAMPLE_DATA / "static.c3d"), events=[])
    assert trial_gait_events(_standing_with_noise(static, sd=sd))[0] == []


def test_a_one_frame_trial_has_no_events_and_says_why():
    walking = replace(read_c3d(SAMPLE_DATA / "walking.c3d"), events=[])
    one = replace(walking, markers=walking.markers[100:101], outputs={})
    events, source = trial_gait_events(one)
    assert events == [] and source == f"{SOURCE_MOTIONLESS}: the trial has 1 frame: no motion to tell events from"


def test_a_spiked_heel_does_not_move_the_detected_events():
    """A 1e30 heel sample: detection ignores it (the same events as the clean trial)."""
    walking = replace(read_c3d(SAMPLE_DATA / "walking.c3d"), events=[])
    markers = walking.markers.copy()
    markers[200, walking.marker_labels.index("LHEE"), 0] = 1e30
    spiked = detect_gait_events(walking.with_markers(markers))
    clean = detect_gait_events(walking)
    assert [(e.label, e.context) for e in spiked] == [(e.label, e.context) for e in clean]
    np.testing.assert_allclose([e.time for e in spiked], [e.time for e in clean], atol=1e-3)
