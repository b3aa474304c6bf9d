"""The quintic GCV smoothing spline's second derivative (Nexus' centre-of-mass
acceleration): exact on polynomials it cannot smooth away, accurate on smooth signals,
better than the five-point differences on noisy ones, and Nexus' own on PiGKad.  The
banded O(n) implementation against an independent dense one (the B-spline penalty
diagonalised, ``O(n³)``: the module's former implementation, kept here only as the
reference), and a 10,000-frame trajectory in bounded memory."""

from __future__ import annotations

import tracemalloc
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import pytest
from scipy.interpolate import BSpline
from scipy.linalg import null_space

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinetics import gcv_spline
from fuzzygait.kinetics.gcv_spline import (
    MIN_FRAMES,
    gcv_log_lambda,
    gcv_log_lambdas,
    gcv_values,
    spline_second_derivative,
    spline_second_derivatives,
)
from fuzzygait.kinetics.inverse_dynamics import GRAVITY, derivative
from fuzzygait.kinetics.plug_in_gait import FORCE_AXES
from fuzzygait.kinetics.segments import PLUG_IN_GAIT_TABLE, long_segment
from support import shared_file

RATE = 100.0
#: The documented search grid: log10 λ from 8 down to -10 in steps of 0.05.
GRID = np.arange(gcv_spline.LOG_LAMBDA_RANGE[0], gcv_spline.LOG_LAMBDA_RANGE[1] - 1e-9, -gcv_spline.LOG_LAMBDA_STEP)


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


def test_trajectories_searched_together_give_each_ones_own_values() -> None:
    """Six trajectories of a trial at once (as the six centres of mass): three of one length
    (GCV's first minimum found at different depths of the grid, and none: a noise-free
    sine), one with a gap, one longer than the cached lengths, a 2-component one:
    bit-for-bit the values each gives alone."""
    rng = np.random.default_rng(5)
    t = np.arange(200) / RATE
    smooth = np.stack([np.sin(2 * t), np.cos(3 * t), t**2], axis=1)
    xs = [smooth + rng.normal(0.0, noise, smooth.shape) for noise in (1e-3, 1e-5)] + [smooth]
    gappy = xs[0].copy()
    gappy[90:95] = np.nan
    long_run = np.cumsum(np.cumsum(rng.normal(0.0, 1e-4, (900, 3)), axis=0), axis=0)
    xs += [gappy, long_run, xs[1][:, :2]]
    alone = [spline_second_derivative(x, RATE) for x in xs]
    for together, single in zip(spline_second_derivatives(xs, RATE), alone, strict=True):
        np.testing.assert_array_equal(together, single)
    lambdas = gcv_log_lambdas(xs[:3])
    assert lambdas == [gcv_log_lambda(x) for x in xs[:3]]
    assert lambdas[2] == GRID[-1] and len({round(v, 6) for v in lambdas}) == 3
    with pytest.raises(ParameterError, match="one shape"):
        gcv_log_lambdas([xs[0], xs[5]])


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


# --- the independent reference: dense, the penalty of the natural quintic B-spline basis diagonalised ---


@dataclass(frozen=True)
class DenseBasis:
    """The penalty's eigenvectors ``v``, eigenvalues ``lam`` and the second derivative at
    the frames (per frame²) of each eigenvector's node values, for ``n`` frames."""

    v: np.ndarray
    lam: np.ndarray
    second_v: np.ndarray


@lru_cache(maxsize=16)
def dense_basis(n: int) -> DenseBasis:
    """Natural quintic splines with a knot at every frame as B-splines of degree 5 whose
    third and fourth derivatives vanish at both ends; the penalty by 3-point
    Gauss–Legendre per frame interval (exact), in terms of the node values, diagonalised."""
    t = np.arange(n, dtype=float)
    spline = BSpline(np.r_[[0.0] * 5, t, [t[-1]] * 5], np.eye(n + 4), 5)
    ends = np.array([t[0], t[-1]])
    null = null_space(np.vstack([spline.derivative(3)(ends), spline.derivative(4)(ends)]))
    nodes, weights = np.polynomial.legendre.leggauss(3)
    third = spline.derivative(3)((t[:-1, None] + 0.5 + 0.5 * nodes[None, :]).ravel()) @ null
    penalty = third.T @ (np.tile(0.5 * weights, n - 1)[:, None] * third)
    to_nodes_inverse = np.linalg.inv(spline(t) @ null)
    k = to_nodes_inverse.T @ penalty @ to_nodes_inverse
    lam, v = np.linalg.eigh(0.5 * (k + k.T))
    return DenseBasis(v, np.clip(lam, 0.0, None), spline.derivative(2)(t) @ null @ to_nodes_inverse @ v)


def dense_gcv(x: np.ndarray, log_lambda: np.ndarray) -> np.ndarray:
    basis = dense_basis(len(x))
    lam = 10.0 ** np.asarray(log_lambda, dtype=float)[..., None] * basis.lam
    shrink = lam / (1.0 + lam)
    return ((shrink**2) @ ((basis.v.T @ x) ** 2).sum(axis=1)) / shrink.sum(axis=-1) ** 2


def dense_log_lambda(x: np.ndarray) -> float:
    """The documented search: the grid's first local minimum from the top, golden-section
    refined to 1e-3 between its neighbours; none: the grid's last λ."""
    grid = GRID
    values = dense_gcv(x, grid)
    minima = np.flatnonzero((values[1:-1] <= values[:-2]) & (values[1:-1] <= values[2:])) + 1
    if not len(minima):
        return float(grid[-1])
    lo, hi = float(grid[minima[0] + 1]), float(grid[minima[0] - 1])
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    while hi - lo > 1e-3:
        a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
        hi, lo = (b, lo) if dense_gcv(x, np.array(a)) <= dense_gcv(x, np.array(b)) else (hi, a)
    return 0.5 * (lo + hi)


def dense_second_derivative(x: np.ndarray, rate: float) -> np.ndarray:
    basis = dense_basis(len(x))
    lam = 10.0 ** dense_log_lambda(x) * basis.lam
    return basis.second_v @ ((basis.v.T @ x) / (1.0 + lam)[:, None]) * rate**2


def assert_matches_dense(x: np.ndarray) -> None:
    """Banded and dense: the same λ (to the search's 1e-3 in log10) and second
    derivatives within 1e-8 of the reference's largest, every frame."""
    reference = dense_second_derivative(x, RATE)
    assert abs(gcv_log_lambda(x) - dense_log_lambda(x)) < 1e-3
    assert np.abs(spline_second_derivative(x, RATE) - reference).max() <= 1e-8 * np.abs(reference).max()


@pytest.mark.parametrize("n", [20, 33, 100, 257, 800])
def test_banded_equals_the_dense_reference_on_random_trajectories(n: int) -> None:
    """Random walks of random walks (drifting positions) with white noise, three components."""
    rng = np.random.default_rng(n)
    x = np.cumsum(np.cumsum(rng.normal(0.0, 1e-4, (n, 3)), axis=0), axis=0) + rng.normal(0.0, 2e-4, (n, 3))
    assert_matches_dense(x)


def test_gcv_equals_the_dense_one_over_the_whole_search() -> None:
    """GCV(λ) (its trace n - tr H: sum λμ/(1 + λμ) over the dense penalty's eigenvalues μ)
    at every tenth λ of the grid, 1e8 down to 1e-10: within 1e-6 relative, 1e-10 where
    λ ≤ 10 (at large λ the dense eigenvalues near the null space limit the reference)."""
    rng = np.random.default_rng(3)
    x = np.cumsum(rng.normal(size=(60, 3)), axis=0)
    grid = GRID[::10]
    relative = np.abs(gcv_values(x, grid) / dense_gcv(x, grid) - 1.0)
    assert relative.max() < 1e-6 and relative[grid <= 1.0].max() < 1e-10


@pytest.mark.parametrize("n", [12, 40, 323, 729])
def test_the_grid_in_the_sine_basis_equals_the_banded_gcv(n: int) -> None:
    """The search's grid (up to 729 frames: GCV in the sine basis, the corners by
    Woodbury) against the banded solves of :func:`gcv_values` at all 361 λ: within 1e-12
    relative where λ ≤ 1, 1e-6 above (where the banded system's condition, up to 6e9,
    limits it), and the same first local minimum."""
    rng = np.random.default_rng(n + 1)
    x = np.cumsum(np.cumsum(rng.normal(0.0, 1e-4, (n, 3)), axis=0), axis=0) + rng.normal(0.0, 2e-4, (n, 3))
    banded = gcv_values(x, GRID)
    values, best = gcv_spline._grid_search([x])
    relative = np.abs(values[0] / banded - 1.0)
    assert relative[GRID <= 0.0].max() < 1e-12 and relative.max() < 1e-6
    minima = np.flatnonzero((banded[1:-1] <= banded[:-2]) & (banded[1:-1] <= banded[2:])) + 1
    assert best[0] == (minima[0] if len(minima) else -1) and (best[0] > 0 or n == 12)  # 12: no minimum


def long_segment_com(file: tuple[str, str], segment: str) -> np.ndarray:
    """The right thigh's or tibia's centre of mass (m) through a shared Nexus trial."""
    trial = read_c3d(shared_file(*file))
    subject = subject_from_processing(trial.parameters)
    result = compute_lower_body(trial, subject)
    proximal, distal = {"thigh": ("RHJC", "RKJC"), "tibia": ("RKJC", "RAJC")}[segment]
    table_name = {"thigh": "femur"}.get(segment, segment)
    return long_segment(table_name, result.joint_centres[proximal], result.joint_centres[distal],
                        result.segment_frames["right_" + segment], subject.body_mass).com  # fmt: skip


@pytest.mark.parametrize(("file", "segment", "start", "n"), [
    (("pig-options", "PiGKad_Motion.c3d"), "tibia", 0, 1000),  # unfiltered: GCV smooths
    (("pig-options", "PiGKad_Motion.c3d"), "thigh", 40, 20),
    (("vicon", "Movement_trial.c3d"), "thigh", 0, 1000),  # filtered: GCV all but interpolates
    (("vicon", "Movement_trial.c3d"), "tibia", 100, 137),
])  # fmt: skip
def test_banded_equals_the_dense_reference_on_real_trajectories(file: tuple[str, str], segment: str, start: int,
                                                               n: int) -> None:  # fmt: skip
    """Centres of mass of shared Nexus trials (their run without gaps, cut to 20 … 323 frames)."""
    com = long_segment_com(file, segment)
    finite = np.flatnonzero(np.all(np.isfinite(com), axis=1))
    x = com[finite[0] + start : finite[-1] + 1][:n]
    assert np.isfinite(x).all() and len(x) >= 20
    assert_matches_dense(x)


@pytest.mark.parametrize(("file", "segment"), [
    (("pig-options", "PiGKad_Motion.c3d"), "tibia"),  # unfiltered: a minimum mid-grid
    (("vicon", "Movement_trial.c3d"), "thigh"),  # filtered: no minimum, the whole grid
    (("vicon", "Static_trial.c3d"), "thigh"),  # standing: a minimum near the heavy end
])  # fmt: skip
def test_the_sine_search_picks_the_banded_searchs_lambda(file: tuple[str, str], segment: str) -> None:
    """On real centres of mass the search (its grid in the sine basis) picks exactly the λ
    that the banded solves' GCV over the whole grid and in the golden section (one
    trajectory at a time, :func:`gcv_values`) give, so the accelerations are the banded
    spline's bit for bit."""
    com = long_segment_com(file, segment)
    x = com[np.all(np.isfinite(com), axis=1)][:729]
    banded = gcv_values(x, GRID)
    minima = np.flatnonzero((banded[1:-1] <= banded[:-2]) & (banded[1:-1] <= banded[2:])) + 1
    expected = float(GRID[-1])
    if len(minima):  # the documented golden section, on the banded GCV
        lo, hi = float(GRID[minima[0] + 1]), float(GRID[minima[0] - 1])
        ratio = (np.sqrt(5.0) - 1.0) / 2.0
        while hi - lo > 1e-3:
            a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
            hi, lo = (b, lo) if gcv_values(x, np.array([a, b])) @ np.array([1.0, -1.0]) <= 0.0 else (hi, a)
        expected = 0.5 * (lo + hi)
    assert gcv_log_lambda(x) == expected


def test_banded_equals_the_dense_reference_on_a_long_marker_trajectory() -> None:
    """The 499 frames of a dancer's marker (``Dance.c3d``, mm): the longest shared real run."""
    trial = read_c3d(shared_file("c3d-formats", "Dance.c3d"))
    seen = np.all(np.isfinite(trial.markers), axis=(0, 2))
    x = trial.markers[:, int(np.flatnonzero(seen)[0])]
    assert len(x) == 499
    assert_matches_dense(x)


def test_ten_thousand_frames_in_bounded_memory() -> None:
    """A 10,000-frame trajectory (a 0.8 Hz swing with 0.1 mm noise, in m, at 100 Hz): the
    Python allocations peak below 64 MB (one n × n float matrix would be 800 MB; the work
    is chunked at CHUNK_UNKNOWNS unknowns), and the acceleration is the swing's within
    0.05 m/s² RMS away from the ends (the five-point differences: noise-dominated, > 0.3)."""
    rng = np.random.default_rng(11)
    t = np.arange(10_000) / RATE
    w = 2 * np.pi * 0.8
    x = 0.05 * np.sin(w * t)[:, None] + rng.normal(0.0, 1e-4, (t.size, 3))
    tracemalloc.start()
    try:
        a = spline_second_derivative(x, RATE)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert a.shape == x.shape and peak < 64e6 and gcv_spline.CHUNK_UNKNOWNS * 80 < 64e6
    truth = -(w**2) * 0.05 * np.sin(w * t)[:, None]
    inner = slice(50, -50)
    assert np.sqrt(np.mean((a[inner] - truth[inner]) ** 2)) < 0.05
    five = derivative(derivative(x, RATE), RATE)
    assert np.sqrt(np.nanmean((five[inner] - truth[inner]) ** 2)) > 0.3
