"""Newton–Euler inverse dynamics against closed-form truth.

The synthetic chain: a foot, a tibia and a femur held rigidly together and turning at a
constant rate about the vertical axis through the hip (a static chain when the rate is
zero), a known ground force and free moment on the foot.  For the part of the chain
below a joint ``j`` the load of the proximal segment at ``j`` is, independently of any
recursion, ``F_j = Σ m_i (a_i - g) - F_g`` and
``M_j = Σ [R_i (ω_b × I_b ω_b) + (c_i - p_j) × m_i (a_i - g)] - (q - p_j) × F_g - T``
with ``a_i = ω × (ω × c_i)`` (uniform rotation about an axis through the origin) and
``ω_b = R_iᵀ ω`` constant in each segment.
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.kinetics.inverse_dynamics import (
    GRAVITY,
    Load,
    angular_velocity,
    chain_inverse_dynamics,
    derivative,
    joint_power,
)
from fuzzygait.kinetics.segments import MM, Segment, foot_segment, long_segment

RATE = 20000.0  # the two-frame angular differences are exact to (2 ω / RATE)² / 6 < 1e-7 here
N = 200
BODY_MASS = 72.0


def rz(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((len(angle), 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


def frame_from(z_axis: np.ndarray, x_hint: np.ndarray) -> np.ndarray:
    z = z_axis / np.linalg.norm(z_axis)
    y = np.cross(z, x_hint)
    y /= np.linalg.norm(y)
    return np.stack([np.cross(y, z), y, z], axis=1)


def chain(omega: float) -> tuple[tuple[Segment, ...], tuple[np.ndarray, ...], np.ndarray]:
    """The turning chain: segments (foot, tibia, femur), joint centres (AJC, KJC, HJC, m)
    and the turn ``(n, 3, 3)``; positions in mm at t = 0, a bent and twisted leg."""
    hjc0, kjc0, ajc0 = np.array([0.0, 0.0, 0.0]), np.array([60.0, 30.0, -420.0]), np.array([-20.0, 50.0, -820.0])
    femur0 = frame_from(hjc0 - kjc0, np.array([1.0, 0.2, 0.0]))
    tibia0 = frame_from(kjc0 - ajc0, np.array([1.0, -0.3, 0.1]))
    foot0 = frame_from(np.array([-1.0, -0.1, 0.25]), np.array([0.2, 0.0, 1.0]))
    turn = rz(omega * np.arange(N) / RATE)

    def moving(point: np.ndarray) -> np.ndarray:
        return turn @ point

    hjc, kjc, ajc = moving(hjc0), moving(kjc0), moving(ajc0)
    femur = long_segment("femur", hjc, kjc, turn @ femur0, BODY_MASS)
    tibia = long_segment("tibia", kjc, ajc, turn @ tibia0, BODY_MASS)
    foot = foot_segment(ajc, turn @ foot0, 240.0, BODY_MASS)
    return (foot, tibia, femur), (ajc * MM, kjc * MM, hjc * MM), turn


def expected(segments: tuple[Segment, ...], joint: np.ndarray, omega: float,
             ground: Load) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The closed-form load at ``joint`` on the segments ``segments`` below it."""
    w = np.array([0.0, 0.0, omega])
    force = -ground.force.copy()
    moment = -ground.moment - np.cross(ground.point - joint, ground.force)
    for s in segments:
        acc = np.cross(w, np.cross(w, s.com))
        w_body = np.einsum("nji,j->ni", s.frame, w)
        h_dot = np.einsum("nij,nj->ni", s.frame, np.cross(w_body, s.inertia * w_body))
        force += s.mass * (acc - GRAVITY)
        moment += h_dot + np.cross(s.com - joint, s.mass * (acc - GRAVITY))
    return force, moment


def ground_load(foot: Segment, turn: np.ndarray) -> Load:
    """A ground force under the foot, turning with it, and a free moment."""
    point = foot.com + turn @ np.array([0.03, -0.01, -0.06])
    force = turn @ np.array([40.0, -25.0, 650.0])
    return Load(point, force, turn @ np.array([0.0, 0.0, 3.5]))


@pytest.mark.parametrize("omega", [0.0, 1.5, -4.0])
def test_turning_chain_matches_closed_form(omega: float) -> None:
    segments, joints, turn = chain(omega)
    ground = ground_load(segments[0], turn)
    loads, motions = chain_inverse_dynamics(segments, joints, ground, RATE)
    inner = slice(4, N - 4)
    for k, (load, joint) in enumerate(zip(loads, joints, strict=True)):
        force, moment = expected(segments[: k + 1], joint, omega, ground)
        assert np.all(np.isnan(load.moment[:4])) and np.all(np.isfinite(load.moment[inner]))
        scale_f, scale_m = np.abs(force).max(), np.abs(moment).max()
        np.testing.assert_allclose(load.force[inner], force[inner], rtol=0, atol=1e-6 * scale_f)
        np.testing.assert_allclose(load.moment[inner], moment[inner], rtol=0, atol=1e-6 * scale_m)
    for motion in motions:
        np.testing.assert_allclose(motion.omega[2:-2], np.tile([0.0, 0.0, omega], (N - 4, 1)), atol=1e-9)


def test_a_wrong_inertia_is_seen() -> None:
    """The check above notices the gyroscopic term: doubling one inertia breaks it."""
    segments, joints, turn = chain(4.0)
    ground = ground_load(segments[0], turn)
    foot = segments[0]
    heavier = Segment(foot.name, foot.mass, foot.com, foot.frame, foot.inertia * 2.0)
    loads, _ = chain_inverse_dynamics((heavier, *segments[1:]), joints, ground, RATE)
    _, moment = expected(segments[:1], joints[0], 4.0, ground)
    assert np.abs(loads[0].moment[4:-4] - moment[4:-4]).max() > 1e-4 * np.abs(moment).max()


def test_derivative_is_exact_for_quartics_and_nan_at_the_ends() -> None:
    t = np.arange(12) / RATE
    x = 3.0 * t**4 - t**3 + 2.0 * t
    d = derivative(x, RATE)
    assert np.all(np.isnan(d[:2])) and np.all(np.isnan(d[-2:]))
    np.testing.assert_allclose(d[2:-2], (12.0 * t**3 - 3.0 * t**2 + 2.0)[2:-2], rtol=1e-9)


def test_angular_velocity_of_a_tilted_spin() -> None:
    """A frame spinning at 2 rad/s about a fixed tilted axis."""
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    angles = 2.0 * np.arange(50) / RATE
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    frames = np.eye(3) + np.sin(angles)[:, None, None] * k + (1 - np.cos(angles))[:, None, None] * (k @ k)
    np.testing.assert_allclose(angular_velocity(frames, RATE)[2:-2], np.tile(2.0 * axis, (46, 1)), atol=1e-9)


def test_joint_power_is_moment_times_relative_rate() -> None:
    n = 3
    load = Load(np.zeros((n, 3)), np.zeros((n, 3)), np.tile([10.0, -4.0, 2.0], (n, 1)))
    power = joint_power(load, np.tile([1.0, 0.5, 0.0], (n, 1)), np.tile([0.5, 0.5, 1.0], (n, 1)))
    np.testing.assert_allclose(power, 10.0 * 0.5 - 2.0)


@pytest.mark.parametrize("mass", [0.0, -70.0, float("nan")])
def test_a_body_mass_that_is_not_positive_is_refused(mass: float) -> None:
    joint = np.zeros((5, 3))
    with pytest.raises(ParameterError, match="body mass must be positive"):
        long_segment("tibia", joint + 1.0, joint, np.tile(np.eye(3), (5, 1, 1)), mass)
