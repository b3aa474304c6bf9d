"""Newton–Euler inverse dynamics of a chain of rigid segments, vectorised over frames.

Conventions (SI units, laboratory frame):

* a :class:`Load` is a force (N) and a moment (N·m) about a point (m), acting **on** the
  segment being solved;
* the ground load on the foot is the ground's reaction on the body (force and free
  moment about the centre of pressure, or equivalently force and moment about any
  point);
* the load at a joint is the load of the proximal segment on the distal one, about the
  joint centre (the "internal" joint load); the distal segment gets its reaction.

Each segment obeys ``F_p + F_d + m g = m a`` and, about its centre of mass ``c``,
``M_p + (p - c) x F_p + M_d + (d - c) x F_d = I α + ω x (I ω)`` with ``I`` the principal
inertia in the segment's frame.

Derivatives as Nexus' Plug-in Gait takes them (found on the shared Nexus trials, see
``docs/kinetics.md``): the centre-of-mass acceleration as the second derivative of a
quintic smoothing spline, its smoothing chosen by generalised cross-validation
(:attr:`ComDerivative.GCV_SPLINE`, :mod:`fuzzygait.kinetics.gcv_spline`), or by the
five-point central difference of :func:`derivative` applied twice
(:attr:`ComDerivative.FIVE_POINT`, these functions' default, as the fuzzy kinetics'
nine-frame windows: the same to 0.003 m/s² on filtered markers, local, and 0.2-1 m/s²
apart on unfiltered ones; :func:`fuzzygait.kinetics.plug_in_gait.plug_in_gait_kinetics`
defaults to the spline); the angular velocity from the
rotations two frames either side (:func:`angular_velocity`) and the angular acceleration
by the same two-frame central difference of the angular velocity (:func:`wide_difference`).
Four frames are lost at each end, as Nexus does.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from fuzzygait.kinetics.gcv_spline import spline_second_derivative, spline_second_derivatives
from fuzzygait.kinetics.segments import Segment

#: Gravity (m/s²) along the laboratory's vertical (z up): Plug-in Gait's 9.81.
GRAVITY: NDArray[np.float64] = np.array([0.0, 0.0, -9.81])

Array = NDArray[np.float64]


class ComDerivative(enum.Enum):
    """How a segment's centre-of-mass acceleration is taken from its positions."""

    #: The five-point central difference applied twice (:func:`derivative`): local (nine
    #: frames), NaN on the first and last four frames.
    FIVE_POINT = "five_point"
    #: Nexus' Plug-in Gait: the second derivative of the quintic GCV smoothing spline
    #: through the whole trajectory (:func:`fuzzygait.kinetics.gcv_spline.spline_second_derivative`).
    GCV_SPLINE = "gcv_spline"


@dataclass(frozen=True)
class Load:
    """A force and a moment acting on a segment, laboratory frame.

    Attributes:
        point: ``(n, 3)`` m, where the moment is taken.
        force: ``(n, 3)`` N.
        moment: ``(n, 3)`` N·m about ``point``.
    """

    point: Array
    force: Array
    moment: Array

    def reaction(self) -> Load:
        """The equal and opposite load (on the other segment of a joint)."""
        return Load(self.point, -self.force, -self.moment)

    def moved_to(self, point: Array) -> Load:
        """The same load with its moment about ``point`` (``(n, 3)`` m)."""
        return Load(point, self.force, self.moment + np.cross(self.point - point, self.force))


@dataclass(frozen=True)
class SegmentMotion:
    """A segment's derivatives, laboratory frame.

    Attributes:
        acceleration: ``(n, 3)`` m/s², of the centre of mass.
        omega: ``(n, 3)`` rad/s, angular velocity.
        alpha: ``(n, 3)`` rad/s², angular acceleration.
    """

    acceleration: Array
    omega: Array
    alpha: Array


def derivative(x: Array, rate: float) -> Array:
    """Time derivative along axis 0 of samples at ``rate`` Hz: the five-point central
    difference ``(x[i-2] - 8 x[i-1] + 8 x[i+1] - x[i+2]) / (12 dt)``; NaN on the first
    and last two samples (and fewer than five samples: all NaN)."""
    out = np.full(x.shape, np.nan)
    if len(x) >= 5:
        out[2:-2] = (x[:-4] - 8.0 * x[1:-3] + 8.0 * x[3:-1] - x[4:]) * (rate / 12.0)
    return out


def wide_difference(x: Array, rate: float) -> Array:
    """Time derivative along axis 0: the central difference over two frames either side,
    ``(x[i+2] - x[i-2]) / (4 dt)``; NaN on the first and last two samples."""
    out = np.full(x.shape, np.nan)
    if len(x) >= 5:
        out[2:-2] = (x[4:] - x[:-4]) * (rate / 4.0)
    return out


def angular_velocity(frames: Array, rate: float) -> Array:
    """``(n, 3)`` rad/s, laboratory frame: the axial vector of ``dR/dt Rᵀ`` (its
    antisymmetric part) of the ``(n, 3, 3)`` rotations ``frames``, ``dR/dt`` by
    :func:`wide_difference`."""
    w = wide_difference(frames, rate) @ np.swapaxes(frames, 1, 2)
    return 0.5 * np.stack([w[:, 2, 1] - w[:, 1, 2], w[:, 0, 2] - w[:, 2, 0], w[:, 1, 0] - w[:, 0, 1]], axis=1)


def com_acceleration(com: Array, rate: float, method: ComDerivative = ComDerivative.FIVE_POINT) -> Array:
    """``(n, 3)``: the acceleration of the ``(n, 3)`` positions ``com`` sampled at ``rate`` Hz
    (their units per s²) by ``method``."""
    if method is ComDerivative.GCV_SPLINE:
        return spline_second_derivative(com, rate)
    return derivative(derivative(com, rate), rate)


def com_accelerations(coms: list[Array], rate: float, method: ComDerivative = ComDerivative.FIVE_POINT) -> list[Array]:
    """:func:`com_acceleration` of each of the ``(n, 3)`` positions ``coms``; by the spline,
    their runs of one length searched together
    (:func:`fuzzygait.kinetics.gcv_spline.spline_second_derivatives`: the same values)."""
    if method is ComDerivative.GCV_SPLINE:
        return spline_second_derivatives(coms, rate)
    return [com_acceleration(com, rate, method) for com in coms]


def segment_motion(segment: Segment, rate: float, method: ComDerivative = ComDerivative.FIVE_POINT,
                   acceleration: Array | None = None) -> SegmentMotion:  # fmt: skip
    """Centre-of-mass acceleration (``acceleration`` when given, else by ``method``),
    angular velocity and acceleration of ``segment``."""
    omega = angular_velocity(segment.frame, rate)
    if acceleration is None:
        acceleration = com_acceleration(segment.com, rate, method)
    return SegmentMotion(acceleration, omega, wide_difference(omega, rate))


def _local(frame: Array, v: Array) -> Array:
    return np.einsum("nji,nj->ni", frame, v)


def _lab(frame: Array, v: Array) -> Array:
    return np.einsum("nij,nj->ni", frame, v)


def newton_euler(segment: Segment, motion: SegmentMotion, distal: Load, proximal: Array,
                 gravity: Array = GRAVITY) -> Load:  # fmt: skip
    """The load on ``segment`` at its proximal joint centre (``proximal``, ``(n, 3)`` m)
    that, with the ``distal`` load and gravity, gives the segment its ``motion``."""
    force = segment.mass * (motion.acceleration - gravity) - distal.force
    w_local, a_local = _local(segment.frame, motion.omega), _local(segment.frame, motion.alpha)
    inertia = segment.inertia
    h_dot = _lab(segment.frame, inertia * a_local + np.cross(w_local, inertia * w_local))
    com = segment.com
    moment = h_dot - distal.moment - np.cross(distal.point - com, distal.force) - np.cross(proximal - com, force)
    return Load(proximal, force, moment)


def chain_inverse_dynamics(segments: tuple[Segment, ...], joints: tuple[Array, ...], ground: Load, rate: float,
                           gravity: Array = GRAVITY, method: ComDerivative = ComDerivative.FIVE_POINT,
                           accelerations: tuple[Array, ...] | None = None,
                           ) -> tuple[list[Load], list[SegmentMotion]]:  # fmt: skip
    """Inverse dynamics from the distal end up.

    Args:
        segments: distal first (foot, tibia, femur).
        joints: the proximal joint centre of each segment, ``(n, 3)`` m (AJC, KJC, HJC).
        ground: the external load on the first segment (zero force when it is off the
            ground).
        rate: frames per second.
        gravity: ``(3,)`` m/s².
        method: how the centres of mass are differentiated (:class:`ComDerivative`).
        accelerations: the centres of mass' accelerations (``(n, 3)`` m/s² per segment)
            when already made (as both legs' together, :func:`com_accelerations`); else
            by ``method``, the chain's together.

    Returns:
        The load at each joint (of the proximal segment on the distal one, about the
        joint centre) and each segment's motion, in the order of ``segments``.
    """
    loads: list[Load] = []
    motions: list[SegmentMotion] = []
    distal = ground
    if accelerations is None:
        accelerations = tuple(com_accelerations([segment.com for segment in segments], rate, method))
    for segment, joint, acceleration in zip(segments, joints, accelerations, strict=True):
        motion = segment_motion(segment, rate, method, acceleration)
        load = newton_euler(segment, motion, distal, joint, gravity)
        loads.append(load)
        motions.append(motion)
        distal = load.reaction()
    return loads, motions


def joint_power(load: Load, omega_distal: Array, omega_proximal: Array) -> Array:
    """``(n,)`` W: the power of the joint moment, ``M · (ω_distal - ω_proximal)`` (positive:
    the muscles generate energy)."""
    return np.einsum("ni,ni->n", load.moment, omega_distal - omega_proximal)
