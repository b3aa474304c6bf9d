"""The kinetics in the angles pipeline and its outputs (workflows.kinetics, issue 39):
the dataset against plug_in_gait_kinetics and Nexus, the table and the C3D written back,
and every bad input one line or a note."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import FindingKind, Severity, of_kind
from fuzzygait.core.names import Side
from fuzzygait.io import read_c3d
from fuzzygait.io.force_plates import ForcePlateError
from fuzzygait.kinetics.assignment import Foot, automatic_assignment, contact_ground
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N, read_force_plates
from fuzzygait.kinetics.plug_in_gait import JOINTS, plug_in_gait_kinetics
from fuzzygait.workflows.angles import AngleOutputs, AnglesRun, Preprocessing, run_angles
from fuzzygait.workflows.kinetics import run_kinetics, trial_kinetics
from support import SAMPLE_DATA, run_here, shared_file

RAW = Preprocessing(filter=False)  # Nexus' outputs come from the unfiltered markers


@pytest.fixture(scope="module")
def movement() -> AnglesRun:
    return run_angles(shared_file("vicon", "Movement_trial.c3d"), preprocessing=RAW)


def _independent(run: AnglesRun) -> dict[str, np.ndarray]:
    """plug_in_gait_kinetics on the same run, plates read and feet assigned here."""
    trial, path = run.trial, run.raw.source
    assert path is not None
    plates = read_force_plates(path)
    feet = {side: Foot(*(trial.marker(side.value + m) for m in ("HEE", "TOE", "ANK"))) for side in Side}
    contacts = automatic_assignment(plates, feet, trial.rate, DEFAULT_THRESHOLD_N)
    ground = {side: contact_ground(plates, contacts, side, trial.n_frames, trial.rate) for side in Side}
    return plug_in_gait_kinetics(run.result, trial, run.subject, ground).outputs


def test_the_dataset_is_plug_in_gait_kinetics_in_page_units(movement: AnglesRun) -> None:
    kinetics = movement.kinetics
    assert kinetics is not None and kinetics.body_mass == 85.0 and kinetics.plates == (1, 2, 3, 4)
    assert kinetics.plates_used(Side.LEFT) == (1, 3) and kinetics.plates_used(Side.RIGHT) == (2, 4)
    data, expected = kinetics.data, _independent(movement)
    assert data["moment"].dims == ("side", "joint", "axis", "frame")
    assert data["power"].dims == ("side", "joint", "frame")
    assert data["moment"].attrs["units"] == "N·m/kg" and data["grf"].attrs["units"] == "% BW"
    for side in "LR":
        for joint in JOINTS:
            moment = data["moment"].sel(side=side, joint=joint).values.T
            np.testing.assert_allclose(moment * 1e3, expected[side + joint + "Moment"], rtol=1e-12, atol=1e-12)
            power = data["power"].sel(side=side, joint=joint).values
            np.testing.assert_allclose(power, expected[side + joint + "Power"][:, 2], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(data["grf"].sel(side=side).values.T, expected[side + "NormalisedGRF"], rtol=1e-12)
    # the plate arrays: on a contact's frames the plate's force is the foot's ground reaction
    for c in kinetics.contacts:
        assert c.side is not None
        plate = data["plate_force"].sel(plate=c.plate).values[:, c.first : c.last + 1]
        foot = data["ground_force"].sel(side=c.side.value).values[:, c.first : c.last + 1] * 85.0
        np.testing.assert_allclose(plate, foot, rtol=1e-9, atol=1e-9)
        assert plate[2].max() > 500  # N, the body on the plate
    loaded = data["plate_force"].sel(axis="Z").values > 50
    assert np.all(np.isfinite(data["plate_cop"].values.transpose(1, 0, 2)[:, loaded]))
    # one note per contact, the kinetics' line
    assert len(of_kind(movement.notes, FindingKind.FORCE_PLATE_ASSIGNMENT)) == 4
    assert kinetics.summary() == "kinetics (4 force plates, 85 kg): left plate 1, 3; right plate 2, 4"


def test_moments_agree_with_nexus_where_the_ground_loads_agree(movement: AnglesRun) -> None:
    """RESULTS.md's agreement (moments <= 0.02 N·m/kg, powers <= 0.05 W/kg RMS) on the
    frames where our ground load equals Nexus' (Nexus left the two stair contacts unused),
    four frames (the derivatives' reach) away from any other."""
    assert movement.kinetics is not None
    ours, nexus = movement.kinetics.nexus_outputs(), read_c3d(movement.raw.source).outputs  # type: ignore[arg-type]
    for side in "LR":
        grf = np.nan_to_num(ours[side + "GroundReactionForce"][0])  # missing where no plate carries the foot: 0
        same = np.all(np.abs(grf - np.nan_to_num(nexus[side + "GroundReactionForce"])) < 0.05, axis=1)
        same = np.convolve(same.astype(int), np.ones(9, dtype=int), "same") == 9
        assert same.sum() > 150
        for joint in JOINTS:
            moment = (ours[side + joint + "Moment"][0] - nexus[side + joint + "Moment"])[same] * 1e-3
            assert np.all(np.sqrt(np.nanmean(moment**2, axis=0)) <= 0.02), (side, joint)
            power = (ours[side + joint + "Power"][0] - nexus[side + joint + "Power"])[same, 2]
            assert np.sqrt(np.nanmean(power**2)) <= 0.05, (side, joint)


def _labels(c3d: ezc3d.c3d) -> list[str]:
    point = c3d["parameters"]["POINT"]
    return [label for key in ("LABELS", "LABELS2", "LABELS3") if key in point for label in point[key]["value"]]


def test_table_and_c3d_carry_the_kinetics_as_nexus(tmp_path: Path, movement: AnglesRun) -> None:
    assert movement.kinetics is not None
    outputs = AngleOutputs(table=tmp_path / "a.parquet", cycles=tmp_path / "c.csv", c3d=tmp_path / "m.c3d",
                           suffix="_fg")  # fmt: skip
    outputs.write(movement)
    expected = movement.kinetics.nexus_outputs()
    table = pd.read_parquet(tmp_path / "a.parquet")
    units = json.loads(table.attrs["units"])
    assert units["LAnkleMoment_X"] == "N·mm/kg" and units["RHipPower_Z"] == "W/kg" and units["LKneeAngles_X"] == "deg"
    assert "LAnklePower_X" not in table.columns
    np.testing.assert_array_equal(table["LAnkleMoment_X"], expected["LAnkleMoment"][0][:, 0])
    np.testing.assert_array_equal(table["RNormalisedGRF_Z"], expected["RNormalisedGRF"][0][:, 2])
    cycles = pd.read_csv(tmp_path / "c.csv")
    assert {"LKneeMoment_X", "RAnklePower_Z"} <= set(cycles["angle"]) and "RAnklePower_X" not in set(cycles["angle"])
    # ezc3d reads ours in POINT:MOMENTS/POWERS/FORCES, Nexus' own beside, unchanged
    c3d = ezc3d.c3d(str(tmp_path / "m.c3d"))
    point, labels = c3d["parameters"]["POINT"], _labels(c3d)
    assert {"LAnkleMoment_fg", "RHipMoment_fg"} <= set(point["MOMENTS"]["value"])
    assert "LAnklePower_fg" in point["POWERS"]["value"] and "RNormalisedGRF_fg" in point["FORCES"]["value"]
    assert point["MOMENT_UNITS"]["value"] == ["Nmm"] and point["POWER_UNITS"]["value"] == ["W"]
    data = c3d["data"]["points"]
    for name in ("LAnkleMoment", "RKneePower", "LGroundReactionForce"):
        values = data[:3, labels.index(name + "_fg"), :].T
        np.testing.assert_allclose(values, expected[name][0], rtol=1e-6, atol=1e-3)  # float32
    back, raw = read_c3d(tmp_path / "m.c3d"), movement.raw
    assert back.output_kinds["LAnkleMoment_fg"] == "moment" and back.output_kinds["LAnklePower_fg"] == "power"
    for name in ("LAnkleMoment", "RHipPower", "LGroundReactionForce", "LGroundReactionMoment"):  # the input's, kept
        np.testing.assert_array_equal(back.outputs[name], raw.outputs[name])
    np.testing.assert_allclose(back.outputs["RHipMoment_fg"], expected["RHipMoment"][0], rtol=1e-6, atol=1e-3)


def test_a_trial_without_plates_runs_as_before_with_one_note() -> None:
    run = run_angles(SAMPLE_DATA / "cgm24_walking.c3d", static=SAMPLE_DATA / "cgm24_static.c3d",
                     subject_file=SAMPLE_DATA / "cgm24_subject.toml", model="cgm2.4")  # fmt: skip
    assert run.kinetics is None
    notes = of_kind(run.notes, FindingKind.KINETICS)
    assert [n.message for n in notes] == ["no force plates in cgm24_walking.c3d: no kinetics"]
    assert not of_kind(run.notes, FindingKind.FORCE_PLATE_ASSIGNMENT)
    pd.testing.assert_frame_equal(run.frame_table(), run.angle_table())
    assert set(run.units().values()) == {"deg"}


def test_the_sample_walking_trial_has_kinetics_from_its_synthetic_plates(angles_run: AnglesRun) -> None:
    """The generated sample stands on two plates, one step each (the demo's main job)."""
    assert angles_run.kinetics is not None
    assert angles_run.kinetics.plates_used(Side.LEFT) == (1,) and angles_run.kinetics.plates_used(Side.RIGHT) == (2,)
    table = angles_run.frame_table()
    assert list(table.columns[: len(angles_run.angle_table().columns)]) == list(angles_run.angle_table().columns)
    knee = table["LKneeMoment_X"].to_numpy() * 1e-3  # N·m/kg
    assert 0.1 < np.nanmax(np.abs(knee)) < 3.0  # a walking knee moment


def test_no_body_mass_is_one_line_naming_the_parameter(movement: AnglesRun) -> None:
    for mass in (0.0, -3.0, float("nan")):
        run = dataclasses.replace(movement, subject=dataclasses.replace(movement.subject, body_mass=mass))
        with pytest.raises(ParameterError, match="Bodymass") as caught:
            trial_kinetics(run)
        assert "\n" not in str(caught.value) and "Movement_trial.c3d" in str(caught.value)
        kinetics, notes = run_kinetics(run)  # in the pipeline: the angles stand, a warning says why
        assert kinetics is None and len(notes) == 1 and notes[0].severity is Severity.WARNING
        assert notes[0].message == f"kinetics not computed: {caught.value}"


def _copy(tmp_path: Path, name: str, *, metres: bool = False, corners_m: bool = False,
          zero_scale_plate: int | None = None) -> Path:  # fmt: skip
    """Movement_trial rewritten: markers in m (POINT:UNITS 'm', the plates' corners and
    origins with them), or only the corners and origins in m, or one plate's channels
    with ANALOG:SCALE 0 (an uncalibrated plate)."""
    c3d = ezc3d.c3d(str(shared_file("vicon", "Movement_trial.c3d")))
    params = c3d["parameters"]
    if metres:
        outputs = {n for g in ("ANGLES", "FORCES", "MOMENTS", "POWERS") for n in params["POINT"][g]["value"]}
        rows = [i for i, label in enumerate(_labels(c3d)) if label not in outputs]
        c3d["data"]["points"][:3, rows, :] /= 1000.0
        params["POINT"]["UNITS"]["value"] = ["m"]
    if metres or corners_m:
        for key in ("CORNERS", "ORIGIN"):
            params["FORCE_PLATFORM"][key]["value"] = params["FORCE_PLATFORM"][key]["value"] / 1000.0
    if zero_scale_plate is not None:
        channels = params["FORCE_PLATFORM"]["CHANNEL"]["value"][:, zero_scale_plate - 1].astype(int) - 1
        scale = np.array(params["ANALOG"]["SCALE"]["value"], dtype=float)
        scale[channels] = 0.0
        params["ANALOG"]["SCALE"]["value"] = scale
    path = tmp_path / f"{name}.c3d"
    c3d.write(str(path))
    return path


def test_markers_in_metres_are_converted_with_the_plates(tmp_path: Path, movement: AnglesRun) -> None:
    run = run_angles(_copy(tmp_path, "metres", metres=True), preprocessing=RAW)
    assert run.kinetics is not None and movement.kinetics is not None
    note = of_kind(run.kinetics.findings, FindingKind.KINETICS)
    assert [n.message for n in note] == ["kinetics in mm: the marker positions and the plates' corners were both "
                                         "converted to mm (POINT:UNITS), the forces are in N"]  # fmt: skip
    ours, mm = run.kinetics.data["moment"].values, movement.kinetics.data["moment"].values
    np.testing.assert_allclose(ours, mm, atol=2e-4, equal_nan=True)  # N·m/kg; float32 positions in m
    assert np.nanmax(np.abs(mm)) > 1.0


def test_plate_corners_in_other_units_than_its_moments_are_refused(tmp_path: Path) -> None:
    run = run_angles(_copy(tmp_path, "corners", corners_m=True), preprocessing=RAW)
    with pytest.raises(ForcePlateError, match=r"force plate 1: the centre of pressure lies off the plate") as caught:
        trial_kinetics(run)
    assert "\n" not in str(caught.value) and "POINT:UNITS" in str(caught.value)
    assert run.kinetics is None
    assert [n.message for n in of_kind(run.notes, FindingKind.KINETICS)] == [f"kinetics not computed: {caught.value}"]


def test_an_uncalibrated_plate_is_its_finding_and_carries_no_contact(tmp_path: Path, movement: AnglesRun) -> None:
    run = run_angles(_copy(tmp_path, "scale0", zero_scale_plate=4), preprocessing=RAW)
    assert run.kinetics is not None
    calibration = of_kind(run.notes, FindingKind.FORCE_PLATE_CALIBRATION)
    assert len(calibration) == 1 and calibration[0].severity is Severity.WARNING and "4" in calibration[0].message
    assert run.kinetics.plates_used(Side.RIGHT) == (2,) and run.kinetics.plates_used(Side.LEFT) == (1, 3)
    assert np.all(run.kinetics.data["plate_force"].sel(plate=4).values == 0)
    # the left side's kinetics are those with every plate
    assert movement.kinetics is not None
    np.testing.assert_array_equal(run.kinetics.data["moment"].sel(side="L").values,
                                  movement.kinetics.data["moment"].sel(side="L").values)  # fmt: skip


def test_a_contact_not_used_is_a_warning_note_per_contact() -> None:
    """PiGKadMed: the right heel marker beyond the plate's edge in mid-stance
    (docs/kinetics.md) - that contact is not used, the note says why."""
    run = run_angles(shared_file("pig-options", "PiGKadMed_Motion.c3d"), preprocessing=RAW)
    assert run.kinetics is not None
    unused = run.kinetics.unused()
    warned = [f for f in of_kind(run.notes, FindingKind.FORCE_PLATE_ASSIGNMENT) if f.severity is Severity.WARNING]
    assert len(unused) >= 1 and len(warned) == len(unused)
    assert all("not used" in f.message for f in warned)
    assert run.kinetics.summary().endswith(f"{len(unused)} contact{'s' if len(unused) != 1 else ''} not used")


def test_the_angles_command_prints_the_kinetics_line(tmp_path: Path) -> None:
    result = run_here("angles", shared_file("vicon", "Movement_trial.c3d"), "--out", tmp_path / "a.csv")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[1] == "  kinetics (4 force plates, 85 kg): left plate 1, 3; right plate 2, 4"
    assert "  note: force plate 2, frames 856-951: used by the right foot" in lines


def test_a_side_not_computed_leaves_the_inputs_outputs_in_the_c3d(tmp_path: Path, movement: AnglesRun) -> None:
    assert movement.kinetics is not None
    data = movement.kinetics.data.copy(deep=True)
    for var in ("moment", "joint_force", "power", "ground_force", "grf"):
        data[var].loc[{"side": "R"}] = np.nan
    run = dataclasses.replace(movement, kinetics=dataclasses.replace(movement.kinetics, data=data))
    AngleOutputs(c3d=tmp_path / "m.c3d").write(run)  # no suffix: ours take Nexus' names
    back = read_c3d(tmp_path / "m.c3d")
    for name in ("RAnkleMoment", "RHipPower", "RNormalisedGRF"):  # the input's (Nexus') own
        np.testing.assert_array_equal(back.outputs[name], movement.raw.outputs[name])
    np.testing.assert_allclose(back.outputs["LAnkleMoment"], movement.kinetics.nexus_outputs()["LAnkleMoment"][0],
                               rtol=1e-6, atol=1e-3)  # fmt: skip
    ours, nexus = np.nan_to_num(back.outputs["LAnkleMoment"]), np.nan_to_num(movement.raw.outputs["LAnkleMoment"])
    assert np.abs(ours - nexus).max() > 10  # N·mm/kg: ours replaced Nexus' (the stair contacts differ)


def test_a_leg_without_its_heel_marker_is_a_warning_and_nan(movement: AnglesRun) -> None:
    trial = read_c3d(shared_file("vicon", "Movement_trial.c3d"))
    markers = trial.markers.copy()
    markers[:, trial.marker_labels.index("RHEE")] = np.nan
    run = run_angles(trial.with_markers(markers), preprocessing=RAW)
    assert run.kinetics is not None and Side.RIGHT in run.kinetics.unavailable
    warned = [f for f in of_kind(run.notes, FindingKind.KINETICS) if f.side == "right"]
    assert len(warned) == 1 and warned[0].severity is Severity.WARNING and "RHEE" in warned[0].message
    assert np.isnan(run.kinetics.data["moment"].sel(side="R").values).all()
    assert movement.kinetics is not None  # the left side as with every marker
    np.testing.assert_array_equal(run.kinetics.data["moment"].sel(side="L").values,
                                  movement.kinetics.data["moment"].sel(side="L").values)  # fmt: skip
    assert run.kinetics.summary().startswith("kinetics (4 force plates, 85 kg): left plate 1, 3; right no plate "
                                             "(not computed)")  # fmt: skip


def test_a_trial_given_without_its_file_says_why_it_has_no_kinetics() -> None:
    """The plates are read from the C3D file: a Trial made in memory (no ``source``) gets
    a note saying so, not silence (the sample trial has two plates)."""
    trial = dataclasses.replace(read_c3d(SAMPLE_DATA / "walking.c3d"), source=None)
    run = run_angles(trial, subject_file=SAMPLE_DATA / "subject.toml")
    assert run.kinetics is None
    assert [f.message for f in of_kind(run.notes, FindingKind.KINETICS)] == [
        "the trial was given without its C3D file (Trial.source), where the force plates are read from: no kinetics"
    ]


def test_the_cycles_table_takes_the_kinetics_of_the_cycles_on_a_plate() -> None:
    """``--cycles``: the kinetics are averaged over the cycles whose stance was on a plate,
    as the pages show them: in the sample trial one per side (plate 1 under the left foot,
    plate 2 under the right); before, the cycles off the plates entered with a zero ground
    reaction and moments without one (LKneeMoment_X SD 370 N·mm/kg at 20 %)."""
    run = run_angles(SAMPLE_DATA / "walking.c3d", subject_file=SAMPLE_DATA / "subject.toml")
    assert run.kinetics is not None
    table = run.cycle_statistics()
    columns = run.kinetics.columns()
    for side, first_plate_frame in (("L", 122), ("R", 177)):  # 0-based frames of the plate contacts' first frame
        kinetic = table[table["angle"].str.startswith(side) & table["angle"].isin(list(columns))]
        assert set(kinetic["n_cycles"]) == {1} and kinetic["sd"].isna().all()
        # the moment at 0 % is the frame of the foot strike onto the plate: the frame table's value there
        moment = kinetic[kinetic["angle"] == f"{side}KneeMoment_X"].set_index("percent")["mean"]
        strike = [e.frame(run.trial.rate) - run.trial.first_frame for e in run.events
                  if e.context[0] == side and e.label == "Foot Strike"]  # fmt: skip
        start = min(strike, key=lambda f: abs(f - first_plate_frame))
        values = columns[f"{side}KneeMoment_X"][0]
        assert moment[0.0] == pytest.approx(np.interp(start, np.arange(values.size), values), abs=1.0)
        # the ground reaction over the stance the plate measured: loaded from 0 to 100 %, peak as the frames'
        vertical = kinetic[kinetic["angle"] == f"{side}NormalisedGRF_Z"]["mean"].to_numpy()
        frames = columns[f"{side}NormalisedGRF_Z"][0]
        assert vertical.min() > 0 and vertical.max() == pytest.approx(np.nanmax(frames), rel=0.02)


def test_a_foot_without_its_heel_marker_is_named_where_its_contacts_are_missing() -> None:
    """A trial without LHEE (the shared gait-pig has no heel markers): the kinetics notes
    say which marker keeps the left foot's plate contacts from being found."""
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    keep = [k for k, label in enumerate(trial.marker_labels) if label != "LHEE"]
    trial = dataclasses.replace(trial, markers=trial.markers[:, keep],
                                marker_labels=[trial.marker_labels[k] for k in keep])  # fmt: skip
    run = run_angles(trial, subject_file=SAMPLE_DATA / "subject.toml")
    notes = [f.message for f in of_kind(run.notes, FindingKind.KINETICS)]
    assert "the left foot's contacts with the force plates cannot be found: LHEE is not in the trial (a contact is " \
           "told by the heel, toe and ankle markers)" in notes, notes
    assert not any("right foot's contacts" in n for n in notes)


def test_a_contact_the_recording_cuts_says_so() -> None:
    """The sample trial cut at frame 150, during the left foot's contact on plate 1
    (frames 123-187): the contact's note and the page's row say the recording ends during
    it (its duration is not a stance's); the contacts inside the recording say nothing."""
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    run = run_angles(dataclasses.replace(trial, markers=trial.markers[:150]), subject_file=SAMPLE_DATA / "subject.toml")
    assert [f.message for f in of_kind(run.notes, FindingKind.FORCE_PLATE_ASSIGNMENT)] == [
        "force plate 1, frames 123-150 (the recording ends during it): used by the left foot"
    ]
    whole = run_angles(trial, subject_file=SAMPLE_DATA / "subject.toml")
    assert whole.kinetics is not None and not any(c.cut for c in whole.kinetics.contacts)
