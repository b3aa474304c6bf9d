"""Deterministic synthetic Plug-in Gait (CGM 1.0 lower body) trials with known angles.

* :mod:`~fuzzygait.synthetic.gait_curves` -- the known angle curves (Fourier series of
  gait phase, degrees);
* :mod:`~fuzzygait.synthetic.leg_model` -- kinematic chain, sign conventions, Davis hip
  joint centre, marker placement;
* :mod:`~fuzzygait.synthetic.generate` -- trials, noise/gaps, the text of their files;
* :mod:`~fuzzygait.synthetic.sample_data` -- the ``sample_data`` folder and its README;
* :mod:`~fuzzygait.synthetic.force_plates` -- two type-2 force plates under the sample
  walking trial's feet (synthetic, plausible loads, not measured) and the writer that adds
  plates to a C3D file;
* :mod:`~fuzzygait.synthetic.pig_options` -- opt-in knee alignment device, medial
  malleoli, misplaced wands and tibial torsion with known values;
* :mod:`~fuzzygait.synthetic.cgm24` -- CGM 2.4 sessions (thigh/shank clusters, medial
  markers, Hara or Davis HJC, a forefoot with known ForeFootAngles);
  :mod:`~fuzzygait.synthetic.cgm24_sample` -- the one in ``sample_data`` (``cgm24_*``).

Regenerate the bundled data with ``python -m fuzzygait.synthetic [OUT_DIR]``.
"""

from fuzzygait.synthetic.cgm24 import (
    CGM24_DYNAMIC_LABELS,
    CGM24_STATIC_LABELS,
    Cgm24Geometry,
    cgm24_static_pose,
    cgm24_walking_state,
    hara_hjc,
    make_cgm24_static,
    make_cgm24_walking,
)
from fuzzygait.synthetic.gait_curves import (
    FOOT_OFF_PHASE,
    RIGHT_PHASE_SHIFT,
    STRIDE_TIME_S,
    FourierCurve,
    joint_angle_curves,
    limb_phase,
    pelvis_angle_curves,
    pelvis_translation_curves,
    plug_in_gait_ankle_y,
)
from fuzzygait.synthetic.generate import (
    DEFAULT_GAPS,
    CutGap,
    angle_columns,
    gait_events,
    joint_centre_columns,
    make_noisy_gapped,
    make_static_trial,
    make_walking_trial,
    walking_state,
)
from fuzzygait.synthetic.leg_model import (
    DYNAMIC_LABELS,
    SIGNS,
    STATIC_LABELS,
    Pose,
    SubjectGeometry,
    davis_hjc,
    euler_yxz,
    joint_angles_from_rotation,
    joint_rotation,
    pose_lower_body,
    static_offsets,
)
from fuzzygait.synthetic.pig_options import LegOffsets, PigOptions
from fuzzygait.synthetic.sample_data import write_sample_data

__all__ = [
    "CGM24_DYNAMIC_LABELS",
    "CGM24_STATIC_LABELS",
    "Cgm24Geometry",
    "cgm24_static_pose",
    "cgm24_walking_state",
    "hara_hjc",
    "make_cgm24_static",
    "make_cgm24_walking",
    "DEFAULT_GAPS",
    "DYNAMIC_LABELS",
    "FOOT_OFF_PHASE",
    "RIGHT_PHASE_SHIFT",
    "SIGNS",
    "STATIC_LABELS",
    "STRIDE_TIME_S",
    "FourierCurve",
    "LegOffsets",
    "PigOptions",
    "CutGap",
    "Pose",
    "SubjectGeometry",
    "angle_columns",
    "davis_hjc",
    "euler_yxz",
    "gait_events",
    "joint_angle_curves",
    "joint_angles_from_rotation",
    "joint_centre_columns",
    "joint_rotation",
    "limb_phase",
    "make_noisy_gapped",
    "make_static_trial",
    "make_walking_trial",
    "pelvis_angle_curves",
    "pelvis_translation_curves",
    "plug_in_gait_ankle_y",
    "pose_lower_body",
    "static_offsets",
    "walking_state",
    "write_sample_data",
]
