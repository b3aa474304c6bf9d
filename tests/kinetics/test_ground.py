"""The ground's load at the marker frames and Nexus' plate assignment, on synthetic plates."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.kinetics.assignment import assigned_ground, stored_assignment
from fuzzygait.kinetics.ground import frame_means, plate_load, samples_per_frame


@dataclass(frozen=True)
class Plate:
    number: int
    rate: float
    force: np.ndarray
    cop: np.ndarray
    free_moment: np.ndarray
    contact: np.ndarray


def plate(number: int, n: int, force: np.ndarray, cop: np.ndarray, tz: float, on: slice) -> Plate:
    contact = np.zeros(n, dtype=bool)
    contact[on] = True
    free = np.zeros((n, 3))
    free[:, 2] = tz
    cops = np.where(contact[:, None], np.tile(cop, (n, 1)), np.nan)
    return Plate(number, 1000.0, np.tile(force, (n, 1)) * contact[:, None], cops, free * contact[:, None], contact)


@pytest.mark.parametrize(("ratio", "width"), [(9, 9), (10, 11)])
def test_frame_means_are_centred_on_each_frames_first_sample(ratio: int, width: int) -> None:
    """A ramp's centred mean is its value at the centre; a spike counts in ``width``
    frames' windows (Nexus: 9 samples at 1080/120 Hz, 11 at 1000/100 Hz)."""
    n_frames = 20
    samples = np.arange(n_frames * ratio, dtype=float)
    means = frame_means(samples, ratio, n_frames)
    np.testing.assert_allclose(means[1:-1], (np.arange(n_frames) * ratio)[1:-1])
    spike = np.zeros(n_frames * ratio)
    spike[5 * ratio + ratio // 2] = 1.0  # the last sample of frame 5's window
    np.testing.assert_allclose(frame_means(spike, ratio, n_frames)[5], 1.0 / width)


def test_plate_load_is_force_and_moment_about_the_origin() -> None:
    force, cop = np.array([30.0, -12.0, 700.0]), np.array([400.0, 250.0, 20.0])
    p = plate(1, 1000, force, cop, tz=1500.0, on=slice(200, 700))
    load = plate_load(p, 100, 100.0)
    inside, outside = slice(21, 69), np.r_[:19, 71:100]
    np.testing.assert_allclose(load.force[inside], np.tile(force, (48, 1)))
    expected = np.cross(cop * 1e-3, force) + np.array([0.0, 0.0, 1.5])
    np.testing.assert_allclose(load.moment[inside], np.tile(expected, (48, 1)))
    assert np.all(load.force[outside] == 0.0) and np.all(load.moment[outside] == 0.0)


def test_a_plate_rate_not_a_multiple_of_the_marker_rate_is_refused() -> None:
    with pytest.raises(ParameterError, match="1000 Hz is not a whole multiple of the marker rate 120 Hz"):
        samples_per_frame(1000.0, 120.0)


def test_stored_assignment_finds_the_plate_and_the_frames() -> None:
    n, mass = 1000, 70.0
    first = plate(1, n, np.array([10.0, 5.0, 600.0]), np.array([100.0, 200.0, 0.0]), 0.0, slice(100, 400))
    second = plate(2, n, np.array([-20.0, 0.0, 800.0]), np.array([700.0, 200.0, 0.0]), 0.0, slice(500, 800))
    stored = np.full((100, 3), np.nan)
    stored[52:78] = np.array([-20.0, 0.0, 800.0]) / mass
    stored[60] += 1.0  # a frame no plate explains
    found = stored_assignment([first, second], {"LGroundReactionForce": stored}, Side.LEFT, mass, 100.0)
    np.testing.assert_array_equal(np.flatnonzero(found.plate), np.arange(52, 78))
    assert set(found.plate[52:78]) == {2}
    np.testing.assert_array_equal(np.flatnonzero(found.unmatched), [60])
    ground = assigned_ground([first, second], found.plate, 100.0)
    np.testing.assert_allclose(ground.force[55], [-20.0, 0.0, 800.0])
    assert np.all(ground.force[:52] == 0.0)
