"""Conventional Gait Model 1.0 (Vicon Plug-in Gait) lower body: joint centres, segment
frames and angles, vectorised over frames.

Public API::

    from fuzzygait.kinematics import (
        CGMResult, compute_lower_body, static_calibration, ANGLE_NAMES,
        angles_from_virtual_markers,
    )

Positions are in mm in the laboratory frame; frames are ``(n, 3, 3)`` rotation matrices
whose columns are the segment axes in lab coordinates; angles are in degrees (outputs)
or radians (subject parameters).  See :mod:`fuzzygait.kinematics.model` for the model,
:mod:`fuzzygait.kinematics.angles` for the angle conventions and
:mod:`fuzzygait.kinematics.virtual_markers` for Vicon's virtual segment markers.
"""

from fuzzygait.kinematics.model import ALL_ANGLE_NAMES, ANGLE_NAMES, FOREFOOT_ANGLE_NAMES, CGMResult, compute_lower_body
from fuzzygait.kinematics.progression import progression_frame
from fuzzygait.kinematics.static import static_calibration
from fuzzygait.kinematics.virtual_markers import angles_from_virtual_markers

__all__ = [
    "ALL_ANGLE_NAMES",
    "ANGLE_NAMES",
    "FOREFOOT_ANGLE_NAMES",
    "CGMResult",
    "angles_from_virtual_markers",
    "compute_lower_body",
    "progression_frame",
    "static_calibration",
]
