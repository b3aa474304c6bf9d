"""Body-segment parameters of the Plug-in Gait lower limb: masses, centres of mass and
moments of inertia, as Vicon's Plug-in Gait takes them.

Plug-in Gait's kinetic model (Vicon, *Plug-in Gait Reference Guide*, "Kinetic modeling";
the values are Dempster's (1955) cadaver data as tabulated by Winter) gives each segment

* a mass, a fraction of the body mass;
* a centre of mass on the line from the segment's **distal** joint centre (its origin)
  towards its proximal joint centre, at a fraction of the segment length from the distal
  end;
* a radius of gyration, a fraction of the segment length, for the two principal axes
  across the segment; the moment of inertia about the segment's long axis (its z axis)
  is zero.

=======  ===========  ===============  ===================  ==========================
segment  mass / body  COM from distal  radius of gyration   distal -> proximal
=======  ===========  ===============  ===================  ==========================
femur    0.100        0.567            0.540                KJC -> HJC
tibia    0.0465       0.567            0.528                AJC -> KJC
foot     0.0145       0.5              0.690                (toe end) -> AJC
=======  ===========  ===============  ===================  ==========================

The radii are the ones Vicon's table lists (Dempster/Winter's radii about the proximal
end), used by Plug-in Gait about the centre of mass; Dempster/Winter's radii about the
centre of mass (0.323, 0.302, 0.475) give moments 3-4 times further from Nexus's on
``Movement_trial.c3d`` (see ``docs/kinetics.md``).  The segment lengths: femur and tibia
the distance between their joint centres, frame by frame; the foot the length Nexus
gives its foot "bone" (mean HEE-TOE distance minus the marker radius,
:func:`~fuzzygait.kinematics.virtual_markers.foot_bone_length`), its centre of mass on
the foot's own z axis (the long axis of the anatomical foot frame, pointing backwards)
half that length in front of the AJC.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.kinematics.model import CGMResult

MM = 1e-3  #: metres per millimetre


@dataclass(frozen=True)
class SegmentTable:
    """One row of an anthropometric table.

    Attributes:
        mass_fraction: segment mass / body mass.
        com_from_distal: centre of mass, as a fraction of the segment length from the
            distal joint centre towards the proximal one.
        gyration: radius of gyration about the transverse principal axes / segment length.
    """

    mass_fraction: float
    com_from_distal: float
    gyration: float


#: Plug-in Gait's lower-limb table (Vicon Plug-in Gait Reference Guide; Dempster 1955).
PLUG_IN_GAIT_TABLE: dict[str, SegmentTable] = {
    "femur": SegmentTable(0.100, 0.567, 0.540),
    "tibia": SegmentTable(0.0465, 0.567, 0.528),
    "foot": SegmentTable(0.0145, 0.5, 0.690),
}


@dataclass(frozen=True)
class Segment:
    """A rigid segment's inertial parameters and motion, SI units, laboratory frame.

    Attributes:
        name: ``"foot"``, ``"tibia"`` or ``"femur"``.
        mass: kg.
        com: ``(n, 3)`` m, centre of mass in the laboratory frame.
        frame: ``(n, 3, 3)`` rotations whose columns are the segment axes in laboratory
            coordinates (the principal axes of inertia).
        inertia: ``(n, 3)`` kg·m², principal moments of inertia about the centre of
            mass along the frame's x, y, z axes (frame by frame: the length of a long
            segment is measured on each frame).
    """

    name: str
    mass: float
    com: NDArray[np.float64]
    frame: NDArray[np.float64]
    inertia: NDArray[np.float64]


def long_segment(name: str, proximal: NDArray[np.float64], distal: NDArray[np.float64], frame: NDArray[np.float64],
                 body_mass: float, table: dict[str, SegmentTable] = PLUG_IN_GAIT_TABLE) -> Segment:  # fmt: skip
    """A segment between two joint centres (``proximal``, ``distal``: ``(n, 3)`` mm, lab
    frame) with the axes ``frame``; the length is the joint-centre distance of each frame.

    Raises:
        ParameterError: a body mass that is not positive.
    """
    row = table[name]
    mass = _segment_mass(row, body_mass)
    com = (distal + row.com_from_distal * (proximal - distal)) * MM
    length = np.linalg.norm(proximal - distal, axis=1) * MM
    return Segment(name, mass, com, frame, _inertia(mass, row.gyration * length))


def foot_segment(ajc: NDArray[np.float64], frame: NDArray[np.float64], foot_length: float, body_mass: float,
                 table: dict[str, SegmentTable] = PLUG_IN_GAIT_TABLE) -> Segment:  # fmt: skip
    """The foot: centre of mass ``foot_length`` (mm) x COM fraction in front of the AJC
    (``ajc``, ``(n, 3)`` mm) along the foot frame's long axis (z, pointing backwards).

    Raises:
        ParameterError: a body mass or a foot length that is not positive.
    """
    if not np.isfinite(foot_length) or foot_length <= 0:
        raise ParameterError(f"foot length must be positive (mm); got {foot_length}")
    row = table["foot"]
    mass = _segment_mass(row, body_mass)
    com = (ajc - (1.0 - row.com_from_distal) * foot_length * frame[:, :, 2]) * MM
    return Segment("foot", mass, com, frame, _inertia(mass, np.full(len(ajc), row.gyration * foot_length * MM)))


def _segment_mass(row: SegmentTable, body_mass: float) -> float:
    if not np.isfinite(body_mass) or body_mass <= 0:
        raise ParameterError(f"body mass must be positive (kg) for kinetics; got {body_mass}")
    return row.mass_fraction * body_mass


def _inertia(mass: float, radius: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(n, 3)`` kg·m²: ``m r²`` about x and y, zero about the long axis z."""
    across = mass * radius**2
    return np.stack([across, across, np.zeros_like(across)], axis=1)


def leg_segments(result: CGMResult, side: Side, body_mass: float,
                 foot_length: float) -> tuple[Segment, Segment, Segment]:  # fmt: skip
    """Foot, tibia and femur of one side of a Plug-in Gait result (its joint centres and
    frames: the anatomical foot, the untorsioned tibia, the thigh).

    Raises:
        ParameterError: a segment of the side not computed (markers missing), a body
            mass or foot length that is not positive.
    """
    long = "left" if side is Side.LEFT else "right"
    needed = [f"{long}_foot", f"{long}_tibia", f"{long}_thigh"]
    missing = [name for name in needed if name not in result.segment_frames]
    if missing:
        raise ParameterError(f"no kinetics for the {long} leg: segment {', '.join(missing)} not computed")
    hjc, kjc, ajc = (result.joint_centres[side.value + j] for j in ("HJC", "KJC", "AJC"))
    foot = foot_segment(ajc, result.segment_frames[needed[0]], foot_length, body_mass)
    tibia = long_segment("tibia", kjc, ajc, result.segment_frames[needed[1]], body_mass)
    femur = long_segment("femur", hjc, kjc, result.segment_frames[needed[2]], body_mass)
    return foot, tibia, femur
