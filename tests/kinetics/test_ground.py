"""The ground's load at the marker frames and Nexus' plate assignment, on synthetic plates."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.io import read_c3d
from fuzzygait.kinetics.assignment import (
    ContactUse,
    Foot,
    PlateContact,
    assigned_ground,
    automatic_assignment,
    contact_ground,
    stored_assignment,
)
from fuzzygait.kinetics.ground import frame_means, plate_load, samples_per_frame
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N, read_force_plates
from support import shared_file


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


# ------------------------------------------------------------------ automatic assignment
@dataclass(frozen=True)
class Outlined(Plate):
    corners: np.ndarray = field(default_factory=lambda: np.zeros((4, 3)))


def square(x0: float) -> np.ndarray:
    """A 500 mm square plate from x0 to x0 + 500, y 0..500, corners round it."""
    return np.array([[x0 + 500, 500, 0], [x0 + 500, 0, 0], [x0, 0, 0], [x0, 500, 0.0]])


def foot_at(heel: tuple[float, float], n: int = 100) -> Foot:
    """A static foot pointing +x: heel, toe 200 mm ahead, ankle 50 mm ahead and up."""
    h = np.tile([heel[0], heel[1], 30.0], (n, 1))
    return Foot(h, h + [200.0, 0, 0], h + [50.0, 0, 50.0])


def loaded(x0: float, cop: tuple[float, float], on: slice = slice(200, 800), number: int = 1) -> Outlined:
    p = plate(number, 1000, np.array([0.0, 0.0, 700.0]), np.array([cop[0], cop[1], 0.0]), 0.0, on)
    return Outlined(p.number, p.rate, p.force, p.cop, p.free_moment, p.contact, square(x0))


def test_a_foot_wholly_on_the_plate_gets_the_contact() -> None:
    feet = {Side.LEFT: foot_at((100, 150)), Side.RIGHT: foot_at((700, 350))}
    contacts = automatic_assignment([loaded(0.0, (200, 160))], feet, 100.0, 10.0)
    assert contacts == [PlateContact(1, 20, 79, Side.LEFT)]
    ground = contact_ground([loaded(0.0, (200, 160))], contacts, Side.LEFT, 100, 100.0)
    assert np.all(ground.force[21:79, 2] == 700.0) and np.all(ground.force[:20] == 0.0)


@pytest.mark.parametrize(("feet", "reason", "foot", "text"), [
    ({Side.LEFT: foot_at((-100, 150))}, ContactUse.OFF_EDGE, Side.LEFT, "not used: left foot off the plate's edge"),
    ({Side.LEFT: foot_at((100, 150)), Side.RIGHT: foot_at((100, 200))}, ContactUse.BOTH_FEET, None,
     "not used: both feet over the centre of pressure"),
    ({Side.LEFT: foot_at((900, 150))}, ContactUse.NO_FOOT, None, "not used: no foot over the centre of pressure"),
])  # fmt: skip
def test_contacts_that_are_not_used(feet: dict[Side, Foot], reason: ContactUse, foot: Side | None, text: str) -> None:
    cop = (50.0, 160.0) if reason is ContactUse.OFF_EDGE else (200.0, 170.0)
    (contact,) = automatic_assignment([loaded(0.0, cop)], feet, 100.0, 10.0)
    assert (contact.side, contact.reason, contact.foot, contact.describe()) == (None, reason, foot, text)
    assert not contact.reason.used


def test_a_foot_on_two_plates_at_once_uses_neither() -> None:
    """A foot across two plates' joint (heel 20 mm before it, ankle 20 mm after), loading
    both: each contact alone would be its."""
    heel = np.tile([480.0, 150.0, 30.0], (100, 1))
    feet = {Side.RIGHT: Foot(heel, heel + [200.0, 0, 0], heel + [40.0, 0, 50.0])}
    plates = [loaded(0.0, (490, 150), number=1), loaded(500.0, (600, 150), number=2)]
    assert [c.side for c in automatic_assignment(plates[:1], feet, 100.0, 10.0)] == [Side.RIGHT]
    contacts = automatic_assignment(plates, feet, 100.0, 10.0)
    assert [(c.side, c.reason, c.foot) for c in contacts] == [(None, ContactUse.TWO_PLATES, Side.RIGHT)] * 2
    assert contacts[0].describe() == "not used: right foot on two plates at once"


def test_automatic_assignment_agrees_with_nexus_on_pigkad() -> None:
    """PiGKad: each foot's one contact on the plate Nexus used, the frames where both
    plates' loads exceed the threshold."""
    path = shared_file("pig-options", "PiGKad_Motion.c3d")
    trial = read_c3d(path)
    feet = {side: Foot(*(trial.marker(side.value + m) for m in ("HEE", "TOE", "ANK"))) for side in Side}
    contacts = automatic_assignment(read_force_plates(path), feet, trial.rate, DEFAULT_THRESHOLD_N)
    assert [(c.plate, c.side) for c in contacts] == [(1, Side.RIGHT), (2, Side.LEFT)]
    nexus = np.flatnonzero(np.isfinite(trial.outputs["RGroundReactionForce"][:, 2]))
    assert (contacts[0].first, contacts[0].last) == (nexus[0], nexus[-1])
