"""Plug-in Gait lower-body kinetics: joint forces, moments and powers, and the ground
reaction, as Vicon Nexus names, expresses and normalises them.

=====================  ==========================================================
output                 content
=====================  ==========================================================
``LAnkleMoment``       N·mm/kg, the joint moment in the distal segment's frame,
``LKneeMoment``        components X (sagittal), Y (frontal), Z (transverse) taken
``LHipMoment``         and signed like the joint's angles (:data:`MOMENT_AXES`)
``LAnkleForce`` ...    N/kg, the joint force in the distal segment's frame
                       (:data:`FORCE_AXES`)
``LAnklePower`` ...    W/kg in Z (X = Y = 0)
``LGroundReactionForce``  N/kg, laboratory frame
``LNormalisedGRF``     % body weight (g = 9.81), X forward, Y medial, Z up
=====================  ==========================================================

"Distal frame": the anatomical foot for the ankle, the untorsioned tibia for the knee,
the thigh for the hip.  The joint load is the load of the proximal segment on the
distal one (:mod:`fuzzygait.kinetics.inverse_dynamics`); with the signs of
:data:`MOMENT_AXES` a positive X is an internal ankle plantarflexor, knee extensor and
hip extensor moment (Nexus' clinical convention).  Power is the moment times the
angular velocity of the distal segment relative to the proximal one (the pelvis for the
hip): positive when energy is generated.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.core.subject import SubjectParameters
from fuzzygait.core.trial import Trial
from fuzzygait.kinematics.model import CGMResult
from fuzzygait.kinematics.virtual_markers import foot_bone_length
from fuzzygait.kinetics.ground import no_load
from fuzzygait.kinetics.inverse_dynamics import (
    ComDerivative,
    Load,
    SegmentMotion,
    angular_velocity,
    chain_inverse_dynamics,
    com_accelerations,
    joint_power,
)
from fuzzygait.kinetics.segments import MM, leg_segments

Array = NDArray[np.float64]

#: The leg joints, distal first.
JOINTS: tuple[str, ...] = ("Ankle", "Knee", "Hip")

#: Nexus component (X, Y, Z) -> (axis of the distal segment's frame, sign) of the joint
#: moment, per joint and side; found on ``Movement_trial.c3d``, where every component
#: then agrees with Nexus' to <= 0.01 N·m/kg.  The frames: foot (z backwards along the
#: foot, x dorsal), tibia and thigh (z up the segment, y the flexion axis).
MOMENT_AXES: dict[tuple[str, Side], tuple[tuple[int, float], ...]] = {
    ("Ankle", Side.LEFT): ((1, 1.0), (2, -1.0), (0, 1.0)),
    ("Ankle", Side.RIGHT): ((1, 1.0), (2, 1.0), (0, -1.0)),
    ("Knee", Side.LEFT): ((1, -1.0), (0, 1.0), (2, 1.0)),
    ("Knee", Side.RIGHT): ((1, -1.0), (0, -1.0), (2, -1.0)),
    ("Hip", Side.LEFT): ((1, 1.0), (0, 1.0), (2, 1.0)),
    ("Hip", Side.RIGHT): ((1, 1.0), (0, -1.0), (2, -1.0)),
}
#: The same for the joint force (both sides alike): the knee and hip force are the
#: tibia/thigh components as they are, the ankle force the foot's turned half a turn
#: about its y axis.
FORCE_AXES: dict[str, tuple[tuple[int, float], ...]] = {
    "Ankle": ((0, -1.0), (1, 1.0), (2, -1.0)),
    "Knee": ((0, 1.0), (1, 1.0), (2, 1.0)),
    "Hip": ((0, 1.0), (1, 1.0), (2, 1.0)),
}
#: g of the body weight in ``NormalisedGRF`` (Nexus: 9.81 m/s²).
STANDARD_G = 9.81


@dataclass
class KineticsResult:
    """Output of :func:`plug_in_gait_kinetics`.

    Attributes:
        outputs: Nexus names (``LAnkleMoment``, ``LAnklePower``, ``LAnkleForce``,
            ``LGroundReactionForce``, ``LNormalisedGRF``, ...) -> ``(n, 3)`` in Nexus' units
            (see the module docstring); NaN where the derivatives are not defined (the
            first and last four frames) or an input is missing.
        loads: ``"LAnkle"`` ... -> the joint :class:`Load` (SI, laboratory frame, about
            the joint centre).
        unavailable: side -> why its kinetics were not computed.
    """

    outputs: dict[str, Array] = field(default_factory=dict)
    loads: dict[str, Load] = field(default_factory=dict)
    unavailable: dict[Side, str] = field(default_factory=dict)


def in_frame(frame: Array, vector: Array, axes: tuple[tuple[int, float], ...]) -> Array:
    """``(n, 3)``: ``vector`` (laboratory) in the ``(n, 3, 3)`` ``frame``, its components
    picked and signed by ``axes`` (one ``(axis, sign)`` per output component)."""
    local = np.einsum("nji,nj->ni", frame, vector)
    return np.stack([sign * local[:, axis] for axis, sign in axes], axis=1)


def foot_length(trial: Trial, side: Side, marker_radius: float) -> float:
    """Nexus' foot length (mm): the mean HEE-TOE distance minus the marker radius.

    Raises:
        ParameterError: HEE or TOE missing or never seen together.
    """
    hee, toe = side.value + "HEE", side.value + "TOE"
    missing = [m for m in (hee, toe) if not trial.has_marker(m)]
    if missing:
        raise ParameterError(f"no kinetics for the {side.word.lower()} leg: {' and '.join(missing)} "
                             f"{'is' if len(missing) == 1 else 'are'} not in the trial (the foot length is the "
                             f"{hee}-{toe} distance)")  # fmt: skip
    length = foot_bone_length(trial.marker(hee), trial.marker(toe), marker_radius)
    if not np.isfinite(length):
        raise ParameterError(f"no kinetics for the {side.word.lower()} leg: {hee} and {toe} are never seen together")
    return length


def normalised_grf(force: Array, progression: Array, side: Side, body_mass: float) -> Array:
    """``(n, 3)`` % body weight: the ground reaction ``force`` (N, laboratory) along the
    progression frame's forward axis, towards the midline (medial) and up."""
    medial = -progression[:, 1] if side is Side.LEFT else progression[:, 1]
    axes = np.stack([progression[:, 0], medial, progression[:, 2]], axis=1)
    return force @ axes * (100.0 / (body_mass * STANDARD_G))


def side_kinetics(result: CGMResult, trial: Trial, subject: SubjectParameters, side: Side, ground: Load,
                  out: KineticsResult, method: ComDerivative = ComDerivative.GCV_SPLINE,
                  accelerations: tuple[Array, ...] | None = None) -> None:  # fmt: skip
    """One side's outputs into ``out`` (see :func:`plug_in_gait_kinetics`); its foot's,
    tibia's and thigh's centre-of-mass ``accelerations`` (m/s²) when already made."""
    mass = subject.body_mass
    segments = leg_segments(result, side, mass, foot_length(trial, side, subject.marker_radius))
    joints = tuple(result.joint_centres[side.value + name] * MM for name in ("AJC", "KJC", "HJC"))
    loads, motions = chain_inverse_dynamics(segments, joints, ground, trial.rate, method=method,
                                            accelerations=accelerations)  # fmt: skip
    pelvis = SegmentMotion(np.zeros(0), angular_velocity(result.segment_frames["pelvis"], trial.rate), np.zeros(0))
    proximal = [*motions[1:], pelvis]
    for joint, segment, load, motion, above in zip(JOINTS, segments, loads, motions, proximal, strict=True):
        name = side.value + joint
        out.loads[name] = load
        out.outputs[name + "Moment"] = in_frame(segment.frame, load.moment, MOMENT_AXES[(joint, side)]) * (1e3 / mass)
        out.outputs[name + "Force"] = in_frame(segment.frame, load.force, FORCE_AXES[joint]) / mass
        power = np.zeros((len(load.force), 3))
        power[:, 2] = joint_power(load, motion.omega, above.omega) / mass
        out.outputs[name + "Power"] = power
    out.outputs[side.value + "GroundReactionForce"] = ground.force / mass
    if np.all(np.isfinite(result.progression)):
        out.outputs[side.value + "NormalisedGRF"] = normalised_grf(ground.force, result.progression, side, mass)


def plug_in_gait_kinetics(result: CGMResult, trial: Trial, subject: SubjectParameters, ground: Mapping[Side, Load],
                          com_derivative: ComDerivative = ComDerivative.GCV_SPLINE) -> KineticsResult:  # fmt: skip
    """Plug-in Gait joint kinetics of both legs.

    Args:
        result: :func:`~fuzzygait.kinematics.compute_lower_body` of ``trial``.
        trial: the trial (its rate; HEE and TOE give the foot length).
        subject: ``body_mass`` (kg) and the marker radius.
        ground: per side, the ground's load on that foot at the trial's frames (see
            :func:`fuzzygait.kinetics.ground.plate_load`; zero off the ground); a side
            absent here is taken as never on a plate (swing-only kinetics).
        com_derivative: how the segments' centres of mass are differentiated:
            :attr:`~fuzzygait.kinetics.inverse_dynamics.ComDerivative.GCV_SPLINE` (the
            default) as Nexus (the quintic GCV smoothing spline through each trajectory;
            agrees with Nexus on unfiltered markers too), ``FIVE_POINT`` (local, nine
            frames, as the fuzzy kinetics' windows; the same within 0.003 m/s² on filtered
            markers, 0.2-1 m/s² apart on unfiltered ones).

    Returns:
        The outputs in Nexus' names and units; a side whose segments are not computed
        (markers missing) is in ``unavailable`` instead.

    Raises:
        ParameterError: a body mass that is not positive, a ground load of another length
            than the trial.
    """
    if not np.isfinite(subject.body_mass) or subject.body_mass <= 0:
        raise ParameterError(f"body mass must be positive (kg) for kinetics; got {subject.body_mass}")
    for side, load in ground.items():
        if load.force.shape != (trial.n_frames, 3):
            raise ParameterError(f"the {side.word.lower()} foot's ground load has {len(load.force)} frames; "
                                 f"the trial has {trial.n_frames}")  # fmt: skip
    out = KineticsResult()
    coms: dict[Side, list[Array]] = {}
    for side in Side:  # both legs' six centres of mass differentiated together (the spline's search shared)
        try:
            segments = leg_segments(result, side, subject.body_mass, foot_length(trial, side, subject.marker_radius))
        except ParameterError as exc:
            out.unavailable[side] = str(exc)
            continue
        coms[side] = [segment.com for segment in segments]
    accelerations = iter(com_accelerations([com for side in coms for com in coms[side]], trial.rate, com_derivative))
    for side in coms:
        made = tuple(next(accelerations) for _ in coms[side])
        try:
            side_kinetics(result, trial, subject, side, ground.get(side, no_load(trial.n_frames)), out,
                          com_derivative, made)  # fmt: skip
        except ParameterError as exc:
            out.unavailable[side] = str(exc)
    return out
