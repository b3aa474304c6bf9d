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
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import ANGLE_NAMES, compute_lower_body
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
