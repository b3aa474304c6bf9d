"""Our angles against the ones a file already stores (:mod:`fuzzygait.workflows.crosscheck`,
``fuzzygait compare``).

Truth: the Nexus files of the reference data, whose stored Plug-in Gait angles our model
reproduces from their own markers and PROCESSING values (Vicon Nexus is the independent
truth), and synthetic files whose stored angles were made with known inputs (16 mm
markers, another knee width) so that the cross-check must name the input that differs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.subject import read_subject
from fuzzygait.synthetic.generate import make_walking_trial
from fuzzygait.synthetic.leg_model import SubjectGeometry
from fuzzygait.workflows.angles import Preprocessing, calibrate_static, model_output_trial, resolve_subject, run_angles
from fuzzygait.workflows.compare import compare_trial
from fuzzygait.workflows.crosscheck import AGREE_DEG, FLAG_DEG, compare_angles, recover_flat_foot, stored_angle_names
from fuzzygait.workflows.subject_resolution import for_static_calibration, settle_marker_diameter
from fuzzygait.workflows.trial_inputs import TrialInputs
from support import SAMPLE_DATA, assert_one_line_error, needs_shared, run_here, shared_file

RAW = Preprocessing(filter=False)


def _stored_file(tmp_path: Path, diameter: float = 14.0, **processing: float) -> Path:
    """A synthetic walking trial with the angles (and virtual markers) of a run with
    ``diameter`` mm markers stored in it, as Nexus stores Plug-in Gait's, and a PROCESSING
    group without MarkerDiameter (``processing`` overrides its values)."""
    walking, _ = make_walking_trial(n_cycles=1, geometry=SubjectGeometry(marker_diameter=diameter))
    out = model_output_trial(run_angles(walking, preprocessing=RAW))
    out.parameters.pop("MarkerDiameter")
    out.parameters.update(processing)
    path = tmp_path / "stored.c3d"
    write_c3d(out, path)
    return path


def test_a_file_made_with_our_inputs_agrees_and_the_notes_say_so(tmp_path: Path) -> None:
    run = run_angles(_stored_file(tmp_path), preprocessing=RAW)
    check = run.crosscheck
    assert check is not None and not check.flagged
    assert len(check.groups) == 10 and max(check.groups.values()) < 1e-3  # float32 storage
    assert any(f"agree within {AGREE_DEG:g}° in every group" in note for note in messages(run.notes))


def test_16_mm_outputs_run_at_14_mm_name_the_marker_diameter(tmp_path: Path) -> None:
    run = run_angles(_stored_file(tmp_path, diameter=16.0), preprocessing=RAW, marker_diameter=14.0)
    check = run.crosscheck
    assert check is not None and check.flagged
    assert check.causes[0].startswith("marker diameter (14 mm used; the file's outputs were made with 16.00 mm")
    note = next(n for n in messages(run.notes) if "stored angles" in n)
    assert f"DIFFER by more than {FLAG_DEG:g}°" in note and "likely cause: marker diameter" in note


def test_other_subject_values_are_named(tmp_path: Path) -> None:
    """The file's outputs were made with its PROCESSING knee width (105 mm); a subject file
    saying 115 mm moves our left knee centre, and the cross-check names the width."""
    path = _stored_file(tmp_path)
    text = (SAMPLE_DATA / "subject.toml").read_text(encoding="utf-8")
    wide = tmp_path / "wide.toml"
    wide.write_text(text.replace("LKneeWidth = 105.0", "LKneeWidth = 115.0"), encoding="utf-8")
    run = run_angles(path, preprocessing=RAW, subject_file=wide)
    check = run.crosscheck
    assert check is not None and "LKneeAngles" in check.flagged and "RKneeAngles" not in check.flagged
    assert check.causes == ["subject values other than the file's PROCESSING (LKneeWidth 115 vs 105 mm)"]
    # the same values as the file's: nothing flagged, nothing named
    same = run_angles(path, preprocessing=RAW, subject_file=SAMPLE_DATA / "subject.toml")
    assert same.crosscheck is not None and same.crosscheck.flagged == {} and same.crosscheck.causes == []


def test_the_vicon_prefixed_set_is_plug_in_gait_where_both_exist(tmp_path: Path) -> None:
    trial = read_c3d(_stored_file(tmp_path))
    names = [n for n in trial.outputs if n.endswith("Angles")]
    for name in names:  # the true ones under the Vicon names, another model's under the plain ones
        trial.outputs[f"{name[0]}Vicon{name[1:]}"] = trial.outputs[name]
        trial.output_kinds[f"{name[0]}Vicon{name[1:]}"] = "angle"
        trial.outputs[name] = trial.outputs[name] + 5.0
    assert stored_angle_names(trial, ["LKneeAngles"]) == {"LKneeAngles": "LViconKneeAngles"}
    run = run_angles(trial, preprocessing=RAW)
    assert run.crosscheck is not None and run.crosscheck.prefixed and not run.crosscheck.flagged
    rows = compare_angles(run.result.angles, trial)
    assert {row.stored for row in rows} == {f"{n[0]}Vicon{n[1:]}" for n in names}


def test_compare_prints_the_table_and_writes_it(tmp_path: Path) -> None:
    path = _stored_file(tmp_path, diameter=16.0)
    result = run_here("compare", path, "--no-filter", "--marker-diameter", "14", "--out", tmp_path / "t.csv")
    assert result.returncode == 0, result.stderr
    assert "LAnkleAngles" in result.stdout and "RMS" in result.stdout and " !" in result.stdout
    assert "likely cause: marker diameter" in result.stdout
    assert "contradicts" in result.stderr  # the warning on the given diameter
    import pandas as pd

    table = pd.read_csv(tmp_path / "t.csv")
    assert list(table.columns[:6]) == ["angle", "axis", "stored", "frames", "rms", "max"]
    assert len(table) == 30 and table["max"].max() > FLAG_DEG


def test_compare_without_stored_angles_is_one_line() -> None:
    result = run_here("compare", SAMPLE_DATA / "walking.c3d")
    assert_one_line_error(result, "walking.c3d", "holds no stored angles")


# --------------------------------------------------------------------- reference files
NEXUS = [("vicon", "Movement_trial.c3d", ()), ("vicon", "Static_trial.c3d", ()),
         ("pig-options", "PiGKad_Motion.c3d", ()), ("pig-options", "PiGKad_Calibration.c3d", ()),
         ("pig-options", "PiGKadMed_Motion.c3d", ()), ("pig-options", "PiGKadMed_Calibration.c3d", ()),
         ("pig-options", "PiG_Motion-FlatFoot-Full.c3d", ()),
         ("pig-options", "PiG_Calibration-FlatFoot-Full.c3d", ())]  # fmt: skip


@needs_shared
@pytest.mark.parametrize(("folder", "name", "options"), NEXUS)
def test_every_nexus_file_agrees_within_a_hundredth_of_a_degree(folder: str, name: str, options: tuple) -> None:
    """With the file's own PROCESSING values and nothing given by hand (the FlatFoot
    session's marker size and its static trial's foot flat are recovered)."""
    comparison = compare_trial(TrialInputs(shared_file(folder, name), flat_foot=True if options else None))
    groups = comparison.check.groups
    assert len(groups) == 10 and max(groups.values()) <= 0.01, groups
    assert all(row.frames > 0 for row in comparison.check.rows)
    assert any("agree within 0.01° in every group" in note for note in messages(comparison.run.notes))


@needs_shared
def test_the_flat_foot_static_names_foot_flat_when_given_the_other_way() -> None:
    static = shared_file("pig-options", "PiG_Calibration-FlatFoot-Full.c3d")
    comparison = compare_trial(TrialInputs(static, flat_foot=False))
    assert set(comparison.check.flagged) <= {"LAnkleAngles", "RAnkleAngles", "LFootProgressAngles",
                                             "RFootProgressAngles"}  # fmt: skip
    assert comparison.check.causes[0] == "foot flat (the file's static outputs were made with foot flat on)"


@needs_shared
def test_a_second_run_of_the_written_c3d_compares_with_our_own_outputs(tmp_path: Path) -> None:
    """``angles --c3d-out`` writes our angles under Nexus' names: read back, they are the
    stored set, and ours on the written (filtered) markers agree with them."""
    out = tmp_path / "ours.c3d"
    result = run_here("angles", shared_file("vicon", "Movement_trial.c3d"), "--c3d-out", out)
    assert result.returncode == 0, result.stderr
    run = run_angles(out, preprocessing=RAW)
    assert run.crosscheck is not None and max(run.crosscheck.groups.values()) < 1e-3
    assert np.isfinite(list(run.crosscheck.groups.values())).all()


def test_a_static_trial_without_stored_angles_leaves_foot_flat_off() -> None:
    static = read_c3d(SAMPLE_DATA / "static.c3d")
    assert recover_flat_foot(static, read_subject(SAMPLE_DATA / "subject.toml")) is None


@needs_shared
@pytest.mark.parametrize(("name", "flat"), [("PiG_Calibration-FlatFoot-Full.c3d", True),
                                            ("PiGKad_Calibration.c3d", False)])  # fmt: skip
def test_the_static_trials_foot_flat_is_recovered_from_its_outputs(name: str, flat: bool) -> None:
    """Nexus' foot-flat setting is not in the file; its static outputs tell it, and the
    calibration then gives Nexus' offsets with nothing given by hand."""
    static = read_c3d(shared_file("pig-options", name))
    subject = settle_marker_diameter(resolve_subject(static, None), None, (static,)).subject
    calibration = calibrate_static(static, for_static_calibration(subject, None))
    assert calibration.flat_foot is flat
    assert f"foot flat {'on' if flat else 'off'}, as the static trial's own stored Plug-in Gait angles were made " \
           "(reproduced with it, not without)" in messages(calibration.notes)
    motion = read_c3d(shared_file("pig-options", name.replace("Calibration", "Motion")))
    for side in "LR":
        ours, nexus = calibration.subject.side(side), motion.parameters
        assert abs(ours.static_plant_flex - nexus[f"{side}StaticPlantFlex"]) < 1e-6
        assert abs(ours.static_rot_off - nexus[f"{side}StaticRotOff"]) < 1e-6
