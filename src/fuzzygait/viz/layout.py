"""The standard gait-report grid (joints x planes), shared by figures, reports and
Rerun blueprints. No plotting library is imported here."""

from __future__ import annotations

from fuzzygait.kinematics.labels import ANGLE_ROWS, PLANES

#: Side -> (name, matplotlib colour).
SIDE_STYLE = {"L": ("Left", "tab:red"), "R": ("Right", "tab:green")}

__all__ = ["ANGLE_ROWS", "PLANES", "SIDE_STYLE"]
