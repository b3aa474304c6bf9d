"""Force plates in the laboratory frame at the marker frames: threshold, low-pass,
resampling (synthetic files of tests/plate_files.py and the shared Vicon trial)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import plate_files as pf
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind, of_kind
from fuzzygait.kinetics.plates import read_force_plates, resample
from fuzzygait.mocap.filtering import combined_gain_db
from support import shared_file

DEPTH = np.array([0.0, 0.0, 40.0])


def _smooth_truth(hum_n: float = 0.0) -> pf.Truth:
    """A stance-like load: Fz = -(600 + 100 sin) N, shear, a COP walking along x, and a
    ``hum_n`` N 200 Hz component on every force (to be filtered out)."""
    t = np.arange(pf.N) / pf.ANALOG_RATE
    hum = hum_n * np.sin(2 * np.pi * 200.0 * t)
    fz = -(600 + 100 * np.sin(2 * np.pi * 2 * t))
    force = np.column_stack([50 * np.sin(2 * np.pi * t), 20 + 0 * t, fz]) + hum[:, None]
    cop = np.column_stack([-150 + 1500 * t, 10 * np.ones_like(t)])
    return pf.Truth(force, cop, 300 * np.cos(2 * np.pi * t))


def _file(tmp_path: Path, truth: pf.Truth, name: str) -> tuple[Path, pf.Plate]:
    plate = pf.Plate(2, pf.yaw(0.6, 0.8), np.array([500.0, 250.0, 0.0]), (500, 400), DEPTH,
                     pf.type2_channels(truth, DEPTH))  # fmt: skip
    return pf.write(tmp_path / name, [plate]), plate


def test_resampled_to_marker_frames_first_frame_aligned(tmp_path: Path) -> None:
    """Without a low-pass, marker frame i is analog sample 10 i (10 samples a frame)."""
    truth = pf.truth(31)
    path, plate = _file(tmp_path, truth, "steps.c3d")
    (frames,) = read_force_plates(path, marker_rate=pf.POINT_RATE, cutoff_hz=None)
    (samples,) = read_force_plates(path)
    assert frames.rate == pf.POINT_RATE and frames.force.shape == (pf.N_FRAMES, 3)
    picked = np.arange(pf.N_FRAMES) * pf.PER_FRAME
    np.testing.assert_allclose(frames.force, samples.force[picked], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(frames.contact, samples.contact[picked])
    np.testing.assert_allclose(frames.cop[frames.contact], samples.cop[picked][frames.contact], rtol=0, atol=1e-9)


def test_low_pass_keeps_the_load_and_removes_the_hum(tmp_path: Path) -> None:
    """A 200 Hz hum of 40 N is reduced by the filter's own gain at 200 Hz (about -120 dB
    for 20 Hz, order 4: nothing left); the slow load passes (its 0.5-2 Hz components lose
    < 0.01 %), so frames 60 ms or more from the ends (past the filter's start-up on the
    hum) equal the hum-free truth within 0.05 N and the COP within 0.1 mm."""
    assert combined_gain_db(200.0, pf.ANALOG_RATE, 20.0) < -60
    clean = _smooth_truth()
    path, plate = _file(tmp_path, _smooth_truth(hum_n=40.0), "hum.c3d")
    (frames,) = read_force_plates(path, marker_rate=pf.POINT_RATE, cutoff_hz=20.0)
    expected = pf.expected_lab(plate, clean)
    picked = np.arange(pf.N_FRAMES) * pf.PER_FRAME
    middle = slice(6, -6)
    np.testing.assert_allclose(frames.force[middle], expected["force"][picked][middle], rtol=0, atol=0.05)
    np.testing.assert_allclose(frames.cop[middle], expected["cop"][picked][middle], rtol=0, atol=0.1)
    assert of_kind(frames.findings, FindingKind.LOW_PASS)[0].cutoff_hz == 20.0


def test_threshold_decides_contact(tmp_path: Path) -> None:
    truth = _smooth_truth()
    path, _ = _file(tmp_path, truth, "threshold.c3d")
    (low,) = read_force_plates(path, threshold_n=10.0)
    (high,) = read_force_plates(path, threshold_n=650.0)
    assert low.contact.all()
    np.testing.assert_array_equal(high.contact, -truth.force[:, 2] > 650.0)
    assert np.isnan(high.cop[~high.contact]).all() and not high.free_moment[~high.contact].any()


def test_bad_arguments_are_one_line(tmp_path: Path) -> None:
    path, _ = _file(tmp_path, _smooth_truth(), "args.c3d")
    with pytest.raises(ParameterError, match="threshold"):
        read_force_plates(path, threshold_n=-1.0)
    with pytest.raises(ParameterError, match="marker rate"):
        read_force_plates(path, marker_rate=0.0)
    with pytest.raises(ParameterError, match="Nyquist"):
        read_force_plates(path, marker_rate=100.0, cutoff_hz=600.0)


def test_resample_interpolates_between_samples() -> None:
    data = np.arange(10.0)[:, None] * np.array([1.0, -2.0])
    np.testing.assert_allclose(resample(data, 10.0, 4.0, 4), np.array([0.0, 2.5, 5.0, 7.5])[:, None] * [1.0, -2.0])


@pytest.mark.shared
def test_movement_trial_at_the_marker_frames() -> None:
    """Movement_trial.c3d: 4 plates, 1080 Hz analog, 120 Hz markers, 323 frames. Each
    plate is stepped on; while the normal force exceeds 100 N the COP lies on the plate
    (within 5 mm of its edges) and on its surface plane; the force points up."""
    plates = read_force_plates(shared_file("vicon", "Movement_trial.c3d"), marker_rate=120.0)
    assert len(plates) == 4
    for plate in plates:
        assert plate.force.shape == (323, 3) and plate.rate == 120.0
        loaded = plate.force[:, 2] > 100.0
        assert loaded.sum() > 20
        low, high = plate.corners.min(axis=0) - 5.0, plate.corners.max(axis=0) + 5.0
        cop = plate.cop[loaded]
        assert np.all((cop[:, :2] >= low[:2]) & (cop[:, :2] <= high[:2]))
        np.testing.assert_allclose(cop[:, 2], plate.centre[2], atol=1e-9)
        np.testing.assert_allclose(plate.free_moment[:, :2], 0.0, atol=1e-9)  # horizontal plates: Tz only
