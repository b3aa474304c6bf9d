"""C3D reading and writing against the reference files and synthetic round trips."""

from __future__ import annotations

import numpy as np
import pytest
from support import C3D_FORMATS, SHARED_DATA, needs_shared, shared_file

from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import messages
from fuzzygait.io import Event, Trial, read_c3d, write_c3d
from fuzzygait.io.c3d_backends import _decode_c3d, _decode_ezc3d

# frame and marker counts each odd file must load with (from the files' headers and
# the data blocks actually present), or None when the file must raise C3DError.
EXPECTED_FORMATS = {
    "pc_real.c3d": (89, 36),
    "pc_int.c3d": (89, 36),
    "dec_int.c3d": (89, 36),
    "sgi_int.c3d": (89, 36),
    "Eb015pr.c3d": (450, 26),
    "dynamic.C3D": (296, 34),
    "Dance.c3d": (499, 40),  # header says 500 frames; the data block holds 499
    "bad_parameter_section.c3d": None,
}


@needs_shared
@pytest.mark.parametrize("name", sorted(EXPECTED_FORMATS))
def test_odd_formats_load_or_raise_one_clear_error(name: str) -> None:
    path = C3D_FORMATS / name
    expected = EXPECTED_FORMATS[name]
    if expected is None:
        with pytest.raises(C3DError) as info:
            read_c3d(path)
        message = str(info.value)
        assert name in message and "\n" not in message
        assert "corrupt" in message
        return
    trial = read_c3d(path)
    assert (trial.n_frames, trial.n_markers) == expected
    assert np.isfinite(trial.markers).any()


@needs_shared
def test_every_shared_file_is_covered_by_the_format_table() -> None:
    names = {p.name for p in C3D_FORMATS.iterdir() if p.suffix.lower() == ".c3d"}
    assert names == set(EXPECTED_FORMATS)


@needs_shared
def test_processor_formats_agree_with_the_float_file() -> None:
    """Intel float, Intel int, DEC and SGI/MIPS storage of one trial give one trial."""
    ref = read_c3d(C3D_FORMATS / "pc_real.c3d")
    scale = 0.2812  # POINT:SCALE of the integer files, mm per count
    for name in ("pc_int.c3d", "dec_int.c3d", "sgi_int.c3d"):
        trial = read_c3d(C3D_FORMATS / name)
        assert trial.marker_labels == ref.marker_labels
        np.testing.assert_array_equal(np.isnan(trial.markers), np.isnan(ref.markers))
        assert np.nanmax(np.abs(trial.markers - ref.markers)) <= scale
        # header events; the DEC file itself stores 8 of the 9 (no "EOF"), both readers agree
        n = len(trial.events)
        assert n >= 8
        assert [e.label for e in trial.events] == [e.label for e in ref.events[:n]]
        assert np.allclose([e.time for e in trial.events], [e.time for e in ref.events[:n]])


@needs_shared
def test_both_backends_decode_the_same_numbers() -> None:
    for path in (C3D_FORMATS / "pc_int.c3d", SHARED_DATA / "vicon" / "gait-pig.c3d"):
        a, b = _decode_ezc3d(path), _decode_c3d(path)
        np.testing.assert_array_equal(np.isnan(a.points), np.isnan(b.points))
        assert np.nanmax(np.abs(a.points - b.points)) < 1e-3
        assert a.labels[: a.points.shape[1]] == b.labels[: b.points.shape[1]]
        assert a.first_frame == b.first_frame and a.header_rate == b.header_rate


@needs_shared
def test_fallback_reader_is_noted() -> None:
    trial = read_c3d(C3D_FORMATS / "sgi_int.c3d")
    assert any("read with the c3d package" in note for note in messages(trial.notes))


@needs_shared
def test_duplicate_labels_and_missing_rate_are_repaired_and_noted() -> None:
    trial = read_c3d(C3D_FORMATS / "dynamic.C3D")
    assert len(set(trial.marker_labels)) == trial.n_markers
    assert "r should" in trial.marker_labels and "r should_2" in trial.marker_labels
    assert trial.rate == 100.0
    assert any("duplicate labels" in note for note in messages(trial.notes))


def test_truncated_and_missing_files_raise_c3d_error(tmp_path) -> None:
    with pytest.raises(C3DError, match="no such file"):
        read_c3d(tmp_path / "absent.c3d")
    short = tmp_path / "short.c3d"
    short.write_bytes(b"\x02\x50" + b"\x00" * 100)
    with pytest.raises(C3DError, match="short.c3d"):
        read_c3d(short)
    garbage = tmp_path / "garbage.c3d"
    garbage.write_bytes(bytes(range(256)) * 8)
    with pytest.raises(C3DError, match="garbage.c3d"):
        read_c3d(garbage)


@needs_shared
def test_vicon_prefix_events_and_outputs() -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    assert trial.label_prefix == "A22:"
    assert trial.subject == "A22"
    assert not any(":" in lbl for lbl in trial.marker_labels + list(trial.outputs))
    # 13 real markers; angles, forces, moments, powers and PiG segment frames apart
    assert trial.n_markers == 13 and "LKNE" in trial.marker_labels
    assert trial.output_kinds["LKneeAngles"] == "angle"
    assert trial.output_kinds["LHipPower"] == "power"
    assert trial.output_kinds["LFEO"] == "segment_frame"
    assert "LKneeAngles" not in trial.marker_labels
    # events as stored in EVENT:TIMES (minutes, seconds) with contexts
    strikes = [e.time for e in trial.events if e.label == "Foot Strike" and e.context == "Left"]
    np.testing.assert_allclose(strikes, [0.57, 1.52, 2.48], atol=1e-6)
    assert len(trial.events) == 9
    assert {e.context for e in trial.events} == {"Left", "Right"}


@needs_shared
def test_processing_group_and_first_frame() -> None:
    trial = read_c3d(shared_file("vicon", "Movement_trial.c3d"))
    assert trial.rate == 120.0 and trial.n_frames == 323
    assert trial.first_frame == 695  # TRIAL:ACTUAL_START_FIELD
    params = trial.parameters
    assert params["LLegLength"] == 877.0 and params["RKneeWidth"] == 139.0
    assert params["InterAsisDistance"] == 306.0
    np.testing.assert_allclose(params["LStaticPlantFlex"], 0.25269872, rtol=1e-6)
    assert trial.output_kinds["LKneeAngles"] == "angle"
    # negative residuals are NaN: Vicon had no joint power before the first force plate
    power = trial.outputs["LKneePower"]
    assert np.isnan(power).any() and np.isfinite(power).any()
    assert np.all(np.isnan(power).all(axis=1) == np.isnan(power).any(axis=1))


def _synthetic_trial(n_frames: int = 120) -> Trial:
    rng = np.random.default_rng(7)
    t = np.arange(n_frames) / 100.0
    markers = 1000.0 * rng.standard_normal((1, 4, 3)) + 50.0 * np.sin(
        2 * np.pi * t[:, None, None] * np.array([1.0, 1.3, 0.7, 2.1])[None, :, None]
    )
    markers[10:15, 1] = np.nan
    angles = np.stack([30 * np.sin(2 * np.pi * t), 5 * np.cos(t), t], axis=1)
    angles[:3] = np.nan
    return Trial(
        markers=markers,
        marker_labels=["LASI", "RASI", "LKNE", "RKNE"],
        rate=100.0,
        first_frame=31,
        outputs={"LKneeAngles": angles},
        output_kinds={"LKneeAngles": "angle"},
        events=[
            Event("Foot Strike", "Left", 0.35, subject="S1"),
            Event("Foot Off", "Right", 0.8125, subject="S1"),
            Event("Foot Strike", "Right", 61.25, subject="S1"),
        ],
        parameters={"LLegLength": 900.0, "LStaticPlantFlex": 0.125},
        subject="S1",
        label_prefix="S1:",
    )


def test_round_trip_reproduces_everything(tmp_path) -> None:
    trial = _synthetic_trial()
    path = tmp_path / "trial.c3d"
    write_c3d(trial, path)
    back = read_c3d(path)
    np.testing.assert_array_equal(np.isnan(back.markers), np.isnan(trial.markers))
    assert np.nanmax(np.abs(back.markers - trial.markers)) <= 1e-3
    assert back.marker_labels == trial.marker_labels
    assert back.rate == trial.rate and back.first_frame == trial.first_frame
    assert back.label_prefix == "S1:" and back.subject == "S1"
    assert [(e.label, e.context, e.subject) for e in back.events] == [
        (e.label, e.context, e.subject) for e in trial.events
    ]
    np.testing.assert_allclose([e.time for e in back.events], [e.time for e in trial.events], atol=1e-5)
    assert back.parameters == trial.parameters
    assert back.output_kinds == {"LKneeAngles": "angle"}
    np.testing.assert_allclose(back.outputs["LKneeAngles"], trial.outputs["LKneeAngles"], atol=1e-4)


def test_written_files_are_read_by_both_backends(tmp_path) -> None:
    trial = _synthetic_trial()
    path = tmp_path / "trial.c3d"
    write_c3d(trial, path)
    a, b = _decode_ezc3d(path), _decode_c3d(path)
    np.testing.assert_array_equal(a.points, b.points)
    assert a.first_frame == b.first_frame == trial.first_frame
    assert a.labels == b.labels


def test_round_trip_converts_metres_to_millimetres(tmp_path) -> None:
    """A file in metres reads back in mm (the writer always writes mm, so patch units)."""
    import ezc3d

    trial = _synthetic_trial()
    path = tmp_path / "metres.c3d"
    write_c3d(trial, path)
    c = ezc3d.c3d(str(path))
    c["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    c["data"]["points"][:3] /= 1000.0
    c.write(str(path))
    back = read_c3d(path)
    assert np.nanmax(np.abs(back.markers - trial.markers)) <= 1e-3
    assert any("converted from m to mm" in note for note in messages(back.notes))


@needs_shared
def test_round_trip_of_a_vicon_trial(tmp_path) -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    write_c3d(trial, tmp_path / "copy.c3d")
    back = read_c3d(tmp_path / "copy.c3d")
    np.testing.assert_array_equal(np.isnan(back.markers), np.isnan(trial.markers))
    assert np.nanmax(np.abs(back.markers - trial.markers)) <= 1e-3
    assert back.marker_labels == trial.marker_labels and back.events == trial.events
    assert list(back.outputs) == list(trial.outputs) and back.output_kinds == trial.output_kinds


def test_writer_leaves_nothing_behind_on_failure(tmp_path) -> None:
    trial = _synthetic_trial()
    trial.marker_labels[0] = "X" * 40  # longer than C3D labels may be
    target = tmp_path / "out.c3d"
    with pytest.raises(C3DError, match="longer than 32"):
        write_c3d(trial, target)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(C3DError, match="does not exist"):
        write_c3d(_synthetic_trial(), tmp_path / "no" / "such" / "dir.c3d")
