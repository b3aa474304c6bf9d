"""Typed names of the joint-angle outputs: side, axis and angle component.

A component's label (``"LKneeAngles_X"``, Plug-in Gait's output name and an axis) is
parsed once, by :meth:`AngleComponent.parse`, where it comes in (a user's ``--angles``,
a dataset's ``component`` coordinate, a table's column); code below that carries an
:class:`AngleComponent` and reads its fields. Labels are made from components with
:attr:`AngleComponent.label`, never split again.

    >>> c = AngleComponent.parse("LKneeAngles_X")
    >>> c.angle, c.axis, c.side, c.joint, c.is_flexion
    ('LKneeAngles', <Axis.X: 'X'>, <Side.LEFT: 'L'>, 'KneeAngles', True)
    >>> c.label
    'LKneeAngles_X'
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from enum import StrEnum

from fuzzygait.core.errors import ParameterError


class Side(StrEnum):
    """A body side, as Plug-in Gait's output names begin (``L``/``R``)."""

    LEFT = "L"
    RIGHT = "R"

    @property
    def word(self) -> str:
        """``"Left"`` or ``"Right"``."""
        return "Left" if self is Side.LEFT else "Right"


class Axis(StrEnum):
    """A component of a Plug-in Gait angle: X (sagittal: flexion), Y (frontal), Z
    (transverse), in the order of the Cardan sequence."""

    X = "X"
    Y = "Y"
    Z = "Z"

    @property
    def column(self) -> int:
        """0, 1 or 2: the component's column in an angle's ``(frames, 3)`` array."""
        return "XYZ".index(self.value)

    @classmethod
    def of(cls, index: int) -> Axis:
        """The axis of column ``index`` (0, 1, 2)."""
        return (cls.X, cls.Y, cls.Z)[index]


#: The axes' labels by column (0, 1, 2 of an angle's ``(frames, 3)`` array).
AXES: tuple[str, ...] = tuple(axis.value for axis in Axis)

#: The angles whose X component is a flexion (hip, knee) or dorsiflexion (ankle).
FLEXION_JOINTS = frozenset({"HipAngles", "KneeAngles", "AnkleAngles"})


@dataclass(frozen=True, order=True)
class AngleComponent:
    """One component of one joint angle output.

    Attributes:
        angle: the output's name with its side, as Plug-in Gait writes it
            (``"LKneeAngles"``); the unit of every component is degrees.
        axis: the component.
    """

    angle: str
    axis: Axis

    @classmethod
    def parse(cls, label: str) -> AngleComponent:
        """``"LKneeAngles_X"`` -> ``AngleComponent("LKneeAngles", Axis.X)``.

        Raises:
            ParameterError: ``label`` is not ``<angle>_<X|Y|Z>``.
        """
        angle, sep, axis = str(label).rpartition("_")
        if not sep or not angle or axis not in ("X", "Y", "Z"):
            raise ParameterError(f"{label!r} is not an angle component (an angle output and _X, _Y or _Z, "
                                 "e.g. LKneeAngles_X)")  # fmt: skip
        return cls(angle, Axis(axis))

    @classmethod
    def maybe(cls, label: str) -> AngleComponent | None:
        """:meth:`parse`, or None for a label that is not an angle component."""
        try:
            return cls.parse(label)
        except ParameterError:
            return None

    @property
    def label(self) -> str:
        """``"LKneeAngles_X"``."""
        return f"{self.angle}_{self.axis.value}"

    @property
    def side(self) -> Side | None:
        """The side the angle's name begins with, or None (an angle of no side)."""
        first, rest = self.angle[:1], self.angle[1:2]
        return Side(first) if first in ("L", "R") and rest.isupper() else None

    @property
    def joint(self) -> str:
        """The angle's name without its side: ``"KneeAngles"``."""
        return self.angle[1:] if self.side is not None else self.angle

    @property
    def is_flexion(self) -> bool:
        """Whether this is hip or knee flexion or ankle dorsiflexion (X of a side's
        hip, knee or ankle angles)."""
        return self.axis is Axis.X and self.side is not None and self.joint in FLEXION_JOINTS

    def __str__(self) -> str:
        return self.label


def angle_of(text: str) -> str:
    """The angle a user's ``text`` names: ``"LKneeAngles_X"`` and ``"LKneeAngles"`` both
    give ``"LKneeAngles"``."""
    component = AngleComponent.maybe(text)
    return component.angle if component is not None else str(text)


def angle_names(labels: Iterable[str]) -> list[str]:
    """The angles of component ``labels``, each once, in order of first appearance."""
    return list(dict.fromkeys(AngleComponent.parse(label).angle for label in labels))


def is_flexion(label: str) -> bool:
    """Whether ``label`` names hip or knee flexion or ankle dorsiflexion (False for a
    label that is no angle component)."""
    component = AngleComponent.maybe(label)
    return component is not None and component.is_flexion


__all__ = ["FLEXION_JOINTS", "AngleComponent", "Axis", "Side", "angle_names", "angle_of", "is_flexion"]
