"""Plug-in Gait with a knee alignment device (KAD) and medial malleolus markers against
Vicon Nexus 2.3 (../shared/data/pig-options).

``PiGKad_Motion.c3d`` (219 frames) and ``PiGKadMed_Motion.c3d`` (275 frames) are walking
trials whose ``PROCESSING`` groups hold the offsets Nexus calibrated on the static
trials with the KAD (``ThighRotation``, ``ShankRotation``) and KAD + medial malleolus
(also ``TibialTorsion`` and ``AnkleAbAdd``); 14 mm markers.  Our dynamic model applies
them as :mod:`fuzzygait.kinematics.joint_centres` and :mod:`fuzzygait.kinematics.segments`
describe.

Measured (this implementation, worst component of any angle, either side; both trials):
every angle within 7.0e-6° max, 2.8e-6° RMS of Nexus' outputs with the trial's own
PROCESSING parameters; the joint centres and segment-frame virtual markers
(``L/RFE*``, ``L/RTI*``, ``L/RFO*``) within 3.1e-4 mm (float32 storage of ~1000 mm).
Before these offsets were applied the same comparison was 28° (KAD) and 46° (KAD + Med)
off.

Static calibration (:mod:`fuzzygait.kinematics.kad`) of ``PiGKad_Calibration.c3d`` and
``PiGKadMed_Calibration.c3d`` from the subject measurements alone (no offsets, no
inter-ASIS distance): every offset Nexus stored within 6.4e-9 rad, the inter-ASIS
distance within 7e-6 mm; the walking trials with that calibration within 7.1e-6° max,
2.8e-6° RMS.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.core.errors import MarkerError
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import ANGLE_NAMES, compute_lower_body, static_calibration
from fuzzygait.kinematics.kad import knee_method
from fuzzygait.kinematics.static import CALIBRATED_OFFSETS
from support import needs_shared, nexus_angle_errors, shared_file

pytestmark = needs_shared

RMS_BOUND_DEG = 0.001
MAX_BOUND_DEG = 0.01
#: Virtual markers compared with Nexus' (mm): float32 storage of lab positions ~1000 mm.
POSITION_BOUND_MM = 1e-3
SESSIONS = ("PiGKad", "PiGKadMed")


@pytest.fixture(scope="module", params=SESSIONS)
def motion(request):
    return read_c3d(shared_file("pig-options", f"{request.param}_Motion.c3d"))


def _assert_agreement(angles, trial):
    for name, (worst, rms) in nexus_angle_errors(angles, trial, ANGLE_NAMES).items():
        assert np.all(worst <= MAX_BOUND_DEG), (trial.name, name, worst)
        assert np.all(rms <= RMS_BOUND_DEG), (trial.name, name, rms)


def test_walking_angles_with_the_trial_processing_parameters(motion):
    subject = subject_from_processing(motion.parameters)
    assert subject.left.thigh_rotation != 0.0 and subject.right.shank_rotation != 0.0
    result = compute_lower_body(motion, subject)
    assert result.unavailable == {} and result.notes == []
    _assert_agreement(result.angles, motion)


def test_walking_segment_frames_follow_nexus(motion):
    result = compute_lower_body(motion, subject_from_processing(motion.parameters))
    for side in "LR":
        for segment in ("FE", "TI", "FO"):
            for suffix in "OALP":
                name = side + segment + suffix
                err = np.nanmax(np.abs(result.virtual_markers[name] - motion.outputs[name]))
                assert err < POSITION_BOUND_MM, (motion.name, name, err)


# ----------------------------------------------------------------------- static calibration


def _blank_subject(static):
    """The static trial's subject measurements with every offset (and the IAD) unknown."""
    subject = replace(subject_from_processing(static.parameters), inter_asis_distance=None)
    for side in "LR":
        subject = subject.with_side(side, **{name: 0.0 for name in CALIBRATED_OFFSETS})
    return subject


@pytest.fixture(scope="module", params=SESSIONS)
def session(request):
    static = read_c3d(shared_file("pig-options", f"{request.param}_Calibration.c3d"))
    motion = read_c3d(shared_file("pig-options", f"{request.param}_Motion.c3d"))
    return request.param, static, motion, static_calibration(static, _blank_subject(static))


def test_static_calibration_detects_the_method(session):
    name, static, _, _ = session
    assert knee_method(static) == {"PiGKad": "KAD", "PiGKadMed": "KAD+MED"}[name]


def test_static_calibration_reproduces_nexus_offsets(session):
    _, static, _, calibrated = session
    for side in "LR":
        for field, vicon in CALIBRATED_OFFSETS.items():
            ours, nexus = getattr(calibrated.side(side), field), static.parameters[side + vicon]
            assert ours == pytest.approx(nexus, abs=1e-7), side + vicon
    assert calibrated.inter_asis_distance == pytest.approx(static.parameters["InterAsisDistance"], abs=1e-3)


def test_walking_angles_with_our_static_calibration(session):
    _, _, motion, calibrated = session
    result = compute_lower_body(motion, calibrated)
    assert result.notes == []
    _assert_agreement(result.angles, motion)


# ----------------------------------------------------------------------- the static trial itself
#: Measured: every angle Nexus stored in both static trials within 1.2e-6° (the KAD + MED
#: ankle angles 4.5e-7°: their tibia takes the walking model's azimuth with each frame's own
#: ShankRotation and AnkleAbAdd; with the marker-based tibia they were 0.0136° off).


def test_static_trial_outputs(session):
    _, static, _, calibrated = session
    result = compute_lower_body(static, calibrated, static_foot="heel")
    assert result.unavailable == {}
    for angle, (worst, rms) in nexus_angle_errors(result.angles, static, ANGLE_NAMES).items():
        assert np.all(worst <= MAX_BOUND_DEG) and np.all(rms <= RMS_BOUND_DEG), (angle, worst, rms)
    for side in "LR":  # the virtual knee marker, the segment frames
        for marker in [side + "KNE"] + [side + seg + s for seg in ("FE", "TI", "FO") for s in "OALP"]:
            err = np.max(np.abs(result.virtual_markers[marker] - static.outputs[marker]))
            assert err < POSITION_BOUND_MM, (marker, err)


# ----------------------------------------------------------------------- bad input
@pytest.fixture(scope="module")
def kad_med_static():
    return read_c3d(shared_file("pig-options", "PiGKadMed_Calibration.c3d"))


def _without(trial, label):
    return trial.select_markers([m for m in trial.marker_labels if m != label])


def test_a_missing_kad_marker_is_named(kad_med_static):
    static = _without(kad_med_static, "RKD2")
    with pytest.raises(MarkerError, match="RKD2 missing") as error:
        static_calibration(static, _blank_subject(static))
    assert "\n" not in str(error.value)


def test_a_kad_whose_markers_are_not_equidistant_is_refused(kad_med_static):
    markers = kad_med_static.markers.copy()
    markers[:, kad_med_static.marker_labels.index("LKD1")] += [0.0, 0.0, 40.0]
    static = kad_med_static.with_markers(markers)
    with pytest.raises(MarkerError, match="LKAX-LKD1-LKD2 distances"):
        static_calibration(static, _blank_subject(static))


def test_a_medial_marker_on_the_lateral_side_is_refused(kad_med_static):
    markers = kad_med_static.markers.copy()
    ank, med = (kad_med_static.marker_labels.index(m) for m in ("RANK", "RMED"))
    markers[:, med] = 2 * markers[:, ank] - markers[:, med]  # mirrored to the lateral side
    static = kad_med_static.with_markers(markers)
    with pytest.raises(MarkerError, match="RMED is on the lateral side"):
        static_calibration(static, _blank_subject(static))


def test_one_medial_marker_only_is_refused(kad_med_static):
    static = _without(kad_med_static, "LMED")
    with pytest.raises(MarkerError, match="LMED missing"):
        static_calibration(static, _blank_subject(static))
