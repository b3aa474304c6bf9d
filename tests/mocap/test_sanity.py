"""Content sanity (issue 17 Deliver 2): every check fires on the bad input built from the
sample / reference data, with the note or one-line error it promises, and on none of the
good recordings."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import C3DError, MarkerError
from fuzzygait.core.findings import Finding, FindingKind, Severity
from fuzzygait.io import read_c3d
from fuzzygait.mocap import sanity
from fuzzygait.workflows.angles import Preprocessing
from support import SAMPLE_DATA, SHARED_DATA, needs_shared

WALKING = SAMPLE_DATA / "walking.c3d"
STATIC = SAMPLE_DATA / "static.c3d"


@pytest.fixture(scope="module")
def walking():
    return read_c3d(WALKING)


def _good_trials() -> list[Path]:
    files = sorted(SAMPLE_DATA.glob("*.c3d"))
    for folder in ("vicon", "pig-options", "cgm2"):
        files += sorted((SHARED_DATA / folder).rglob("*.c3d")) if (SHARED_DATA / folder).is_dir() else []
    return files


def _is_static(path: Path) -> bool:
    return any(word in path.name.lower() for word in ("static", "calibration"))


def test_no_check_fires_on_the_good_trials():
    """Every trial of sample_data and ../shared/data/{vicon,pig-options,cgm2}: no note, no
    error; static trials are motionless and pass the static check, walking trials move."""
    files = _good_trials()
    assert len(files) >= 5
    notes = {}
    for path in files:
        trial = read_c3d(path)
        checked = sanity.check_trial(trial, static=_is_static(path))
        notes[path.name] = checked.notes[len(trial.notes) :]
        assert checked is trial  # nothing blanked, nothing copied
        assert (sanity.motionless(trial) is not None) == _is_static(path) or path.name.startswith("Static - CGM2")
    assert notes == {name: [] for name in notes}
    if SHARED_DATA.is_dir():
        assert len(files) >= 17


# --------------------------------------------------------------------------- rate
@pytest.mark.parametrize("rate", [1e6, 4e-23, 0.5, 10_001.0])
def test_absurd_rates_are_refused_naming_the_file_and_rate(walking, rate):
    with pytest.raises(C3DError, match=re.escape(f"walking.c3d: point rate {rate:g} Hz is implausible")):
        sanity.check_trial(replace(walking, rate=rate))


@pytest.mark.parametrize("rate", [1.0, 50.0, 2000.0, 10_000.0])
def test_plausible_rates_pass(walking, rate):
    sanity.check_rate(replace(walking, rate=rate))


# --------------------------------------------------------------------------- units
@pytest.mark.parametrize(
    ("factor", "unit", "text"),
    [(1e-3, "metres", "about 1000 times too small"), (0.1, "centimetres", "about 10 times too small"),
     (1 / 25.4, "inches", "about 25.4 times too small"), (1e3, "millimetres read as metres", "1000 times too large")],
)  # fmt: skip
def test_unit_mismatch_is_refused_naming_the_likely_unit(walking, factor, unit, text):
    scaled = walking.with_markers(walking.markers * factor)
    with pytest.raises(C3DError) as caught:
        sanity.check_trial(scaled)
    message = str(caught.value)
    assert message.startswith("walking.c3d: marker distances are ") and text in message and unit in message
    assert f"LASI-RASI {250 * factor:.3g} mm" in message  # the sample subject's ASIS are 250 mm apart
    assert "POINT:UNITS" in message


def test_body_scale_of_the_sample_is_one_within_its_proportions(walking):
    scale, lengths = sanity.body_scale(walking)
    assert lengths["LASI-RASI"] == pytest.approx(250.0, abs=0.5)
    assert 0.9 < scale < 1.2


# --------------------------------------------------------------------------- spikes
def test_a_1e30_coordinate_is_blanked_and_noted(walking):
    markers = walking.markers.copy()
    knee = walking.marker_labels.index("LKNE")
    markers[200, knee, 0] = 1e30
    bad = walking.with_markers(markers)
    checked = sanity.check_trial(bad)
    spike = checked.notes[-1]
    assert spike.message.startswith(f"LKNE: 1 implausible sample blanked (frame {walking.first_frame + 200}:")
    assert (spike.kind, spike.marker) == (FindingKind.SPIKES, "LKNE")
    assert np.isnan(checked.markers[200, knee]).all()
    # every other sample as read
    keep = np.ones(walking.n_frames, bool)
    keep[200] = False
    np.testing.assert_array_equal(checked.markers[keep], walking.markers[keep])
    # without the check the low-pass filter spreads the spike over the whole trajectory
    spread, _ = Preprocessing().apply(bad)
    assert np.nanmax(np.abs(spread.marker("LKNE")[:100] - walking.marker("LKNE")[:100])) > 1e6


@pytest.mark.parametrize(("start", "length"), [(100, 1), (100, 3), (0, 2), (509, 3)])
def test_spike_runs_up_to_three_frames_and_at_the_ends(walking, start, length):
    markers = walking.markers.copy()
    ankle = walking.marker_labels.index("RANK")
    markers[start : start + length, ankle, 2] += 2000.0  # 2 m off the path, 200 m/s at 100 Hz
    spikes = sanity.find_spikes(walking.with_markers(markers))
    assert list(spikes) == ["RANK"]
    np.testing.assert_array_equal(spikes["RANK"], np.arange(start, start + length))


def test_a_spike_beside_a_gap_is_found(walking):
    markers = walking.markers.copy()
    toe = walking.marker_labels.index("LTOE")
    markers[300:305, toe] = np.nan
    markers[305, toe, 1] -= 5000.0
    assert sanity.find_spikes(walking.with_markers(markers)) == {"LTOE": pytest.approx([305])}


def test_a_fast_but_human_movement_is_no_spike(walking):
    """A marker moving at 20 m/s (a kicking foot) for 10 frames is not blanked."""
    markers = walking.markers.copy()
    toe = walking.marker_labels.index("RTOE")
    markers[200:210, toe, 0] += np.cumsum(np.full(10, 200.0))  # 200 mm a frame at 100 Hz
    markers[210:, toe, 0] += 2000.0
    assert sanity.find_spikes(walking.with_markers(markers)) == {}


def test_too_many_implausible_samples_refuse_the_marker(walking):
    markers = walking.markers.copy()
    heel = walking.marker_labels.index("LHEE")
    markers[::10, heel, 0] = 1e30  # 10 % of the samples
    with pytest.raises(MarkerError, match=r"walking\.c3d: marker LHEE has 52 implausible samples of 512"):
        sanity.check_trial(walking.with_markers(markers))


# --------------------------------------------------------------------------- motion
def test_motion_measure_is_the_session_rule_s(walking):
    """pelvis_range is the measure of the session discovery's motion rule (one measure):
    the ASIS midpoint's bounding-box diagonal, 6388 mm over the sample walk, 0 standing."""
    from fuzzygait.workflows import session

    assert session.pelvis_range is sanity.pelvis_range
    assert sanity.MOTIONLESS_TRAVEL == session.STATIC_TRAVEL
    assert sanity.STATIC_MAX_TRAVEL == session.STATIC_MARKERS_TRAVEL
    mid = (walking.marker("LASI") + walking.marker("RASI")) / 2
    ok = np.isfinite(mid).all(axis=1)
    assert sanity.pelvis_range(walking) == pytest.approx(np.linalg.norm(np.ptp(mid[ok], axis=0)))
    assert sanity.pelvis_range(walking) == pytest.approx(6388, abs=1)
    assert sanity.pelvis_range(read_c3d(STATIC)) < 1.0


def test_a_walking_trial_as_static_is_refused(walking):
    with pytest.raises(C3DError) as caught:
        sanity.check_trial(walking, static=True)
    message = str(caught.value)
    assert message.startswith("walking.c3d: given as the static trial but it moves (pelvis 6388 mm")
    assert "give the standing calibration trial" in message


@needs_shared
def test_the_real_walking_trial_as_static_is_refused():
    trial = read_c3d(SHARED_DATA / "vicon" / "Movement_trial.c3d")
    with pytest.raises(C3DError, match=r"Movement_trial\.c3d: given as the static trial but it moves \(pelvis 1638 mm"):
        sanity.check_static(trial)


def test_motionless_needs_the_feet_still_too(walking):
    """A treadmill walk (pelvis held in place, feet swinging) is not motionless; the
    standing trial is."""
    centre = np.nanmean([walking.marker("LASI"), walking.marker("RASI")], axis=0)
    treadmill = walking.with_markers(walking.markers - (centre - centre[0])[:, None, :])
    ranges = sanity.motion_ranges(treadmill)
    assert ranges["pelvis"] < 1.0 and ranges["LHEE"] > 500.0
    assert sanity.motionless(treadmill) is None
    standing = read_c3d(STATIC)
    assert sanity.motionless(standing).startswith("the trial is motionless (ranges over the trial: pelvis 0 mm")


def test_in_a_five_frame_trial_the_majority_stays():
    """Static - CGM2 1.c3d has 5 frames: a spike in the middle frame is the one blanked,
    not the two frames on either side of it."""
    static = read_c3d(SAMPLE_DATA / "static.c3d")
    short = replace(static, markers=static.markers[:5].copy(), outputs={})
    knee = short.marker_labels.index("LKNE")
    short.markers[2, knee, 1] += 3000.0
    assert {k: list(v) for k, v in sanity.find_spikes(short).items()} == {"LKNE": [2]}


def test_a_held_label_swap_blanks_nothing(walking):
    """A jump to another place held for 50 frames is not a spike (two long pieces)."""
    markers = walking.markers.copy()
    markers[100:150, walking.marker_labels.index("LKNE"), 0] += 2000.0  # 2 m away for 0.5 s
    assert sanity.find_spikes(walking.with_markers(markers)) == {}
    markers[160:162, walking.marker_labels.index("LKNE"), 0] += 2000.0  # and for 2 frames later: a spike
    assert {k: list(v) for k, v in sanity.find_spikes(walking.with_markers(markers)).items()} == {"LKNE": [160, 161]}


@pytest.mark.filterwarnings("error")
def test_degenerate_content_gives_one_line_and_no_warning(walking):
    """Infinite samples are blanked like 1e30; markers all at the origin, or every
    sample infinite, are one error line; no RuntimeWarning is printed before it."""
    markers = walking.markers.copy()
    markers[5, walking.marker_labels.index("RTOE")] = np.inf
    checked = sanity.check_trial(walking.with_markers(markers))
    assert checked.notes[-1].message.startswith("RTOE: 1 implausible sample blanked (frame 6:")
    with pytest.raises(C3DError, match=r"walking\.c3d: the body's markers all sit at one point"):
        sanity.check_trial(walking.with_markers(np.zeros_like(walking.markers)))
    with pytest.raises(MarkerError, match=r"walking\.c3d: marker LASI has 512 implausible samples of 512"):
        sanity.check_trial(walking.with_markers(np.full_like(walking.markers, -np.inf)))
    for n in (0, 1):
        short = replace(walking, markers=walking.markers[:n], outputs={}, events=[])
        assert sanity.check_trial(short, static=True) is short


# --------------------------------------------------------------------------- static vs walking
_SESSIONS = (  # (static, walking): the reference sessions whose markers stayed put
    (STATIC, WALKING),
    (STATIC, SAMPLE_DATA / "walking_noisy.c3d"),
    (SAMPLE_DATA / "cgm24_static.c3d", SAMPLE_DATA / "cgm24_walking.c3d"),
    (SHARED_DATA / "vicon" / "Static_trial.c3d", SHARED_DATA / "vicon" / "Movement_trial.c3d"),
    (SHARED_DATA / "pig-options" / "PiGKad_Calibration.c3d", SHARED_DATA / "pig-options" / "PiGKad_Motion.c3d"),
    (SHARED_DATA / "pig-options" / "PiGKadMed_Calibration.c3d", SHARED_DATA / "pig-options" / "PiGKadMed_Motion.c3d"),
    (SHARED_DATA / "pig-options" / "PiG_Calibration-FlatFoot-Full.c3d",
     SHARED_DATA / "pig-options" / "PiG_Motion-FlatFoot-Full.c3d"),
)


@pytest.mark.parametrize("static, walking_path", _SESSIONS, ids=lambda p: p.stem)
def test_no_marker_moved_in_the_good_sessions(static, walking_path):
    """Every segment's marker pairs (Plug-in Gait wands, CGM 2.x clusters, the CGM 2.4
    forefoot) keep their static distances within the rule on the reference sessions
    (they differ by at most 12 mm and 7 % there: soft tissue)."""
    if not walking_path.is_file():
        pytest.skip(f"reference data {walking_path} is absent (it sits beside the clone in CI)")
    assert sanity.moved_markers(read_c3d(static), read_c3d(walking_path)) == []


def _moved(trial, label: str, shift: np.ndarray):
    markers = trial.markers.copy()
    markers[:, trial.marker_labels.index(label), :] += shift
    return replace(trial, markers=markers)


def _foot_axis(trial, side: str) -> np.ndarray:
    """Unit vector HEE -> TOE of ``side`` per frame, (n, 3)."""
    axis = trial.marker(side + "TOE") - trial.marker(side + "HEE")
    return axis / np.linalg.norm(axis, axis=1, keepdims=True)


@pytest.mark.parametrize("distance, noted", [(30.0, True), (-25.0, True), (12.0, False)])
def test_a_toe_marker_moved_along_the_foot_is_noted_on_its_side(walking, distance, noted):
    """LTOE moved along the foot in the walking trial (as if re-placed after the static
    trial): beyond 15 mm and 10 % one note, naming the left foot, the pair, both
    distances (the synthetic foot: HEE-TOE 190 mm), the angles it makes unreliable and
    what to do; 12 mm is within the rule (a real session's static/walking difference is
    at most 7 mm on the foot)."""
    static = read_c3d(STATIC)
    moved = _moved(walking, "LTOE", distance * _foot_axis(walking, "L"))
    notes = sanity.moved_markers(static, moved)
    if not noted:
        assert notes == []
        return
    assert len(notes) == 1
    (finding,) = notes
    assert (finding.kind, finding.severity) == (FindingKind.MOVED_MARKERS, Severity.WARNING)
    assert (finding.segment, finding.side) == ("left foot", "left")
    note = finding.message
    assert str(finding) == note
    assert note.startswith("left foot markers sit elsewhere than in the static trial static.c3d "
                           f"(LHEE-LTOE {190 + distance:.0f} mm, static 190 mm)")  # fmt: skip
    assert "left ankle and foot angles are unreliable" in note and "RHEE" not in note
    assert " moved)" not in note  # two foot markers: either may have moved
    others = [Finding(FindingKind.EVENTS, "left side done"), Finding(FindingKind.GAP_FILLING, "gap filling: 0 of 0")]
    assert sanity.moved_segments([others[0], finding, others[1]]) == ["left foot"]


def _cgm24_moved(label: str, mm: float, direction: tuple[str, str]):
    """The synthetic CGM 2.4 static trial, and its walking trial with ``label`` moved
    ``mm`` along the unit vector from marker ``direction[0]`` to ``direction[1]`` (per
    frame)."""
    static = read_c3d(SAMPLE_DATA / "cgm24_static.c3d")
    walking = read_c3d(SAMPLE_DATA / "cgm24_walking.c3d")
    along = walking.marker(direction[1]) - walking.marker(direction[0])
    along /= np.linalg.norm(along, axis=1, keepdims=True)
    return static, _moved(walking, label, mm * along)


def test_a_moved_forefoot_marker_of_the_cgm24_set_is_named():
    """RVMH moved 40 mm towards the heel on the synthetic CGM 2.4 session: the right
    foot's note names RVMH as the marker every changed pair contains (RHEE-RVMH 191 mm
    there, now 40 mm shorter, less 1 mm for the heel's off-axis offset); the left side
    is silent."""
    (finding,) = sanity.moved_markers(*_cgm24_moved("RVMH", 40.0, ("RVMH", "RHEE")))
    assert (finding.segment, finding.side) == ("right foot", "right")
    note = finding.message
    assert note.startswith("right foot markers")
    assert "RHEE-RVMH 152 mm, static 191 mm" in note
    assert "; RVMH moved):" in note and "sits where" not in note


def _rigid_map(source: np.ndarray, target: np.ndarray, point: np.ndarray) -> np.ndarray:
    """``point`` carried by the least-squares rigid motion of ``source`` onto ``target``
    (Kabsch; ``(k, 3)`` marker positions, mm)."""
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    u, _, vt = np.linalg.svd((source - cs).T @ (target - ct))
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(vt.T @ u.T))])
    return vt.T @ d @ u.T @ (point - cs) + ct


def test_a_static_only_marker_left_on_and_labelled_toe_is_recognised():
    """The synthetic CGM 2.4 walking trial with LTOE replaced by where the static
    trial's medial malleolus marker LMED is carried by the shank cluster (as in a
    session where MED stayed on and was labelled TOE): the note says LTOE moved (its
    distance to every other foot marker changed) and sits where LMED was; the right
    foot and every other segment are silent."""
    static = read_c3d(SAMPLE_DATA / "cgm24_static.c3d")
    walking = read_c3d(SAMPLE_DATA / "cgm24_walking.c3d")
    shank = ["LTIAP", "LTIAD", "LTIB", "LANK"]
    source = np.array([static.marker(m).mean(axis=0) for m in shank])
    med = static.marker("LMED").mean(axis=0)
    markers = walking.markers.copy()
    toe = walking.marker_labels.index("LTOE")
    for k in range(walking.n_frames):
        markers[k, toe] = _rigid_map(source, np.array([walking.marker(m)[k] for m in shank]), med)
    (finding,) = sanity.moved_markers(static, replace(walking, markers=markers))
    note = finding.message
    assert note.startswith("left foot markers sit elsewhere")
    assert re.search(r"LTOE moved and sits where the static trial's LMED was \(its distances to the other left foot "
                     r"markers agree within [0-5] mm median\): LMED labelled LTOE\?", note)  # fmt: skip


def test_a_moved_cluster_marker_names_its_segment_and_angles():
    """LTHAD moved 60 mm along the thigh in the synthetic CGM 2.4 walking trial: one
    note, on the left thigh, saying its hip and knee angles are unreliable; the
    report's words for it."""
    (finding,) = sanity.moved_markers(*_cgm24_moved("LTHAD", 60.0, ("LKNE", "LTHAP")))
    assert finding.message.startswith("left thigh markers sit elsewhere than in the static trial cgm24_static.c3d (")
    assert "the left hip and knee angles are unreliable" in finding.message
    pelvis = Finding(FindingKind.MOVED_MARKERS, "x", Severity.WARNING, segment="pelvis")
    # the segments come from the findings' typed field; a message that merely reads like one is not one
    lookalike = Finding(FindingKind.STATIC_TRIAL, "right foot markers sit elsewhere than in the static trial s.c3d")
    segments = sanity.moved_segments([finding, lookalike, pelvis])
    assert segments == ["left thigh", "pelvis"]
    assert sanity.moved_angles(segments) == "pelvis, hip and knee angles"
    assert sanity.moved_angles(["right foot"]) == "ankle and foot angles"


def test_a_trial_without_foot_markers_gives_no_note(walking):
    static = read_c3d(STATIC)
    keep = [i for i, label in enumerate(walking.marker_labels) if not label.endswith(("HEE", "TOE"))]
    bare = replace(walking, markers=walking.markers[:, keep, :], marker_labels=[walking.marker_labels[i] for i in keep])
    assert sanity.moved_markers(static, bare) == []


@needs_shared
def test_the_qualisys_sessions_markers_moved_between_its_trials():
    """The shared CGM 2.4 session: its thigh and shank cluster markers and its TOE and
    forefoot markers sit 17-98 mm from where the static trial has them (the cause of
    its undetermined bands), and on both feet the walking trial's TOE is the static
    trial's medial malleolus marker MED (distances measured independently: LTOE-LHEE
    96 mm walking, LMED-LHEE 97 mm static); the angle workflow says so in its notes."""
    from fuzzygait.workflows.angles import run_angles

    folder = SHARED_DATA / "cgm2" / "qualisys-cgm24-input"
    run = run_angles(folder / "Gait - CGM2 1.c3d", static=folder / "Static - CGM2 1.c3d",
                     subject_file=folder / "session.xml", model="auto")  # fmt: skip
    segments = sanity.moved_segments(run.notes)
    assert segments == ["left thigh", "left shank", "left foot", "right thigh", "right shank", "right foot"]
    moved = {f.segment: f.message for f in run.notes if f.kind is FindingKind.MOVED_MARKERS}
    assert list(moved) == segments and all(m.startswith(s + " markers sit") for s, m in moved.items())
    assert "LHEE-LTOE 96 mm, static 123 mm" in moved["left foot"]
    assert "RTOE-RVMH 137 mm, static 69 mm" in moved["right foot"]
    assert "LMED labelled LTOE?" in moved["left foot"] and "RMED labelled RTOE?" in moved["right foot"]
    assert "; LTHAD moved):" in moved["left thigh"]
    assert "RTIAP-RTIAD 240 mm, static 141 mm" in moved["right shank"]
