"""The quintic GCV smoothing spline's second derivative (Nexus' centre-of-mass
acceleration): exact on polynomials it cannot smooth away, accurate on smooth signals,
better than the five-point differences on noisy ones, and Nexus' own on PiGKad."""

from __future__ import annotations

import numpy as np

from fuzzygait.core.names import Side
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinetics.gcv_spline import MIN_FRAMES, gcv_log_lambda, spline_second_derivative
from fuzzygait.kinetics.inverse_dynamics import GRAVITY, derivative
from fuzzygait.kinetics.plug_in_gait import FORCE_AXES
from fuzzygait.kinetics.segments import PLUG_IN_GAIT_TABLE, long_segment
from support import shared_file

RATE = 100.0


def test_a_quadratic_is_not_smoothed_its_acceleration_exact_to_the_ends() -> None:
    """Quadratics are the penalty's null space: the spline is the data, s'' = 2c on every
    frame, the first and last included, whatever the noise-free data make GCV pick."""
    t = np.arange(150) / RATE
    x = np.stack([3.0 + 2.0 * t - 4.5 * t**2, -1.0 + 0.5 * t + 7.0 * t**2, np.full_like(t, 0.9)], axis=1)
    np.testing.assert_allclose(spline_second_derivative(x, RATE), np.tile([-9.0, 14.0, 0.0], (150, 1)), atol=1e-6)


def test_a_smooth_signal_is_all_but_interpolated() -> None:
    """A 1.5 Hz sine sampled at 100 Hz (float64, no noise): the acceleration -ω² sin
    within 1e-4 relative of its amplitude away from the ends, and GCV picks the
    smallest λ of its search."""
    t = np.arange(300) / RATE
    w = 2 * np.pi * 1.5
    x = np.sin(w * t)[:, None]
    a = spline_second_derivative(x, RATE)[:, 0]
    assert np.abs(a[10:-10] + w**2 * np.sin(w * t[10:-10])).max() < 1e-4 * w**2
    assert gcv_log_lambda(x) < -5


def test_noisy_positions_give_a_closer_acceleration_than_five_point_differences() -> None:
    """Positions with 0.05 mm white noise (a 1.2 Hz, 20 mm swing, in m): the spline's
    acceleration is at least 3 times closer to the true one than the five-point
    differences' (which pass the noise's 10-25 Hz band)."""
    rng = np.random.default_rng(7)
    t = np.arange(400) / RATE
    w = 2 * np.pi * 1.2
    truth = -(w**2) * 0.02 * np.sin(w * t)
    x = (0.02 * np.sin(w * t) + rng.normal(0.0, 5e-5, t.size))[:, None] * np.ones((1, 3))
    x[:, 1:] += rng.normal(0.0, 5e-5, (t.size, 2))
    inner = slice(20, -20)
    spline = spline_second_derivative(x, RATE)[inner, 0] - truth[inner]
    five = derivative(derivative(x, RATE), RATE)[inner, 0] - truth[inner]
    assert np.sqrt(np.mean(spline**2)) * 3 < np.sqrt(np.mean(five**2))


def test_runs_between_gaps_are_their_own_splines() -> None:
    t = np.arange(120) / RATE
    x = np.stack([np.sin(3 * t), np.cos(2 * t), t**3], axis=1)
    gappy = x.copy()
    gappy[50:55] = np.nan
    gappy[110] = np.nan  # leaves a 9-frame run: shorter than MIN_FRAMES
    out = spline_second_derivative(gappy, RATE)
    np.testing.assert_array_equal(out[:50], spline_second_derivative(x[:50], RATE))
    np.testing.assert_array_equal(out[55:110], spline_second_derivative(x[55:110], RATE))
    assert np.isnan(out[50:55]).all() and np.isnan(out[110:]).all() and 120 - 111 < MIN_FRAMES


def test_it_is_the_acceleration_nexus_used_on_pigkad() -> None:
    """The right tibia's centre-of-mass acceleration Nexus' stored knee and ankle forces
    imply, (F_knee - F_ankle) / m + g, equals the spline's to 0.002 m/s² RMS on every
    frame Nexus has (the five-point differences: 0.7)."""
    path = shared_file("pig-options", "PiGKad_Motion.c3d")
    trial = read_c3d(path)
    subject = subject_from_processing(trial.parameters)
    result = compute_lower_body(trial, subject)
    mass = subject.body_mass
    tibia = long_segment("tibia", result.joint_centres["RKJC"], result.joint_centres["RAJC"],
                         result.segment_frames["right_tibia"], mass)  # fmt: skip
    assert tibia.mass == PLUG_IN_GAIT_TABLE["tibia"].mass_fraction * mass

    def lab(joint: str, segment: str) -> np.ndarray:
        local = np.zeros((trial.n_frames, 3))
        for k, (axis, sign) in enumerate(FORCE_AXES[joint]):
            local[:, axis] = sign * trial.outputs[Side.RIGHT.value + joint + "Force"][:, k] * mass
        return np.einsum("nij,nj->ni", result.segment_frames[segment], local)

    implied = (lab("Knee", "right_tibia") - lab("Ankle", "right_foot")) / tibia.mass + GRAVITY
    frames = np.all(np.isfinite(implied), axis=1)
    spline = spline_second_derivative(tibia.com, trial.rate)
    five = derivative(derivative(tibia.com, trial.rate), trial.rate)
    assert np.sqrt(np.mean((spline[frames] - implied[frames]) ** 2)) < 0.002
    assert np.sqrt(np.mean((five[frames] - implied[frames]) ** 2)) > 0.5
