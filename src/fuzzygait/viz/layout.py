"""The standard gait-report grid (joints x planes), shared by figures, reports and
Rerun blueprints. No plotting library is imported here."""

from __future__ import annotations

#: Rows of the grid: (angle name without side, row title).
ANGLE_ROWS = (
    ("PelvisAngles", "Pelvis"),
    ("HipAngles", "Hip"),
    ("KneeAngles", "Knee"),
    ("AnkleAngles", "Ankle"),
    ("FootProgressAngles", "Foot progression"),
)
#: Columns of the grid: (component, plane, row title -> meaning of positive values).
PLANES = (
    ("X", "sagittal", {"Pelvis": "ant. tilt", "Hip": "flexion", "Knee": "flexion",
                       "Ankle": "dorsiflexion", "Foot progression": ""}),
    ("Y", "frontal", {"Pelvis": "up", "Hip": "adduction", "Knee": "varus",
                      "Ankle": "inversion", "Foot progression": ""}),
    ("Z", "transverse", {"Pelvis": "int. rot.", "Hip": "int. rot.", "Knee": "int. rot.",
                         "Ankle": "int. rot.", "Foot progression": "internal"}),
)  # fmt: skip
#: Side -> (name, matplotlib colour).
SIDE_STYLE = {"L": ("Left", "tab:red"), "R": ("Right", "tab:green")}
