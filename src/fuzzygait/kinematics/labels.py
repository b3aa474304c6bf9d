"""What the angle outputs mean, in words: rows, planes and the positive direction of each
component, for tables, dataset attributes, reports and recordings."""

from __future__ import annotations

from fuzzygait.core.names import AngleComponent

#: Rows of the standard gait-report grid: (angle name without side, row title).
ANGLE_ROWS = (
    ("PelvisAngles", "Pelvis"),
    ("HipAngles", "Hip"),
    ("KneeAngles", "Knee"),
    ("AnkleAngles", "Ankle"),
    ("FootProgressAngles", "Foot progression"),
)
#: Every angle output's row title (the grid's and the CGM 2.4 forefoot's).
ROW_TITLES = {**dict(ANGLE_ROWS), "ForeFootAngles": "Forefoot"}
#: Columns of the grid: (component, plane, row title -> meaning of positive values).
PLANES = (
    ("X", "sagittal", {"Pelvis": "ant. tilt", "Hip": "flexion", "Knee": "flexion",
                       "Ankle": "dorsiflexion", "Foot progression": "", "Forefoot": "dorsiflexion"}),
    ("Y", "frontal", {"Pelvis": "up", "Hip": "adduction", "Knee": "varus",
                      "Ankle": "inversion", "Foot progression": "", "Forefoot": ""}),
    ("Z", "transverse", {"Pelvis": "int. rot.", "Hip": "int. rot.", "Knee": "int. rot.",
                         "Ankle": "int. rot.", "Foot progression": "internal", "Forefoot": ""}),
)  # fmt: skip
SIDE_NAMES = {"L": "Left", "R": "Right"}
_PLANE_INFO = {axis: (plane, meaning) for axis, plane, meaning in PLANES}


def parse_component(name: str) -> tuple[str, str, str] | None:
    """``"LKneeAngles_X"`` -> ``("L", "KneeAngles", "X")``; None for other names (and
    for an angle of no side). The fields of :meth:`AngleComponent.parse
    <fuzzygait.core.names.AngleComponent.parse>`, the one parser of component labels."""
    component = AngleComponent.maybe(name)
    if component is None or component.side is None:
        return None
    return component.side.value, component.joint, component.axis.value


def component_label(name: str) -> str:
    """Clinical label of an angle component: ``"LKneeAngles_X"`` -> ``"Left knee,
    sagittal (+ flexion)"``; unknown names are returned unchanged."""
    parsed = parse_component(name)
    if parsed is None:
        return name
    side, base, axis = parsed
    row = ROW_TITLES.get(base)
    plane, meaning = _PLANE_INFO[axis]
    if row is None:
        return f"{SIDE_NAMES[side]} {base}, {plane}"
    positive = meaning.get(row, "")
    label = f"{SIDE_NAMES[side]} {row.lower()}, {plane}"
    return label + (f" (+ {positive})" if positive else "")


__all__ = ["ANGLE_ROWS", "PLANES", "ROW_TITLES", "SIDE_NAMES", "component_label", "parse_component"]
