"""A CGM 2.x static calibration in a subject file (issue 14, Deliver 3): ``calibrate``
writes the cluster calibration with the subject parameters (TOML table, or a .vsk's
sidecar), and walking trials processed from that file alone get the angles of the static
trial itself; missing or foreign calibrations say what to do."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import read_subject, write_subject
from fuzzygait.kinematics.calibration_file import cluster_table, clusters_from_table, read_stored_calibration
from fuzzygait.kinematics.versions import model_version
from fuzzygait.workflows.angles import Preprocessing, calibrate_static, resolve_subject, run_angles
from fuzzygait.workflows.calibrate import calibrate_to_file, calibration_model
from support import SAMPLE_DATA

NO_FILTER = Preprocessing(filter=False)


def _same_angles(a, b, tolerance: float = 1e-9) -> None:
    assert a.result.angles.keys() == b.result.angles.keys() and a.result.unavailable == b.result.unavailable
    for name, values in a.result.angles.items():
        assert np.nanmax(np.abs(values - b.result.angles[name])) <= tolerance, name
    for name, values in a.result.joint_centres.items():
        assert np.nanmax(np.abs(values - b.result.joint_centres[name])) <= 1e-9, name


@pytest.mark.parametrize("suffix", [".toml", ".vsk"])
def test_angles_from_the_calibration_file_equal_angles_from_the_static_trial(
    tmp_path: Path, cgm24_session: tuple[Path, Path], suffix: str
) -> None:
    static, walking = cgm24_session
    written = calibrate_to_file(static, tmp_path / f"cal{suffix}", model="cgm2.3")
    assert written.model == "cgm2.3" and written.calibration.clusters is not None
    files = [tmp_path / f"cal{suffix}"] + ([tmp_path / "cal.clusters.toml"] if suffix == ".vsk" else [])
    assert written.files == files
    with_static = run_angles(walking, static=static, model="cgm2.3", preprocessing=NO_FILTER)
    from_file = run_angles(walking, subject_file=files[0], model="cgm2.3", preprocessing=NO_FILTER)
    assert from_file.result.unavailable == {} and len(from_file.result.angles) >= 10
    _same_angles(with_static, from_file)
    assert from_file.subject == with_static.subject
    assert any(note.startswith(f"cluster calibration from {files[-1].name} (static trial static.c3d") for note in
               messages(from_file.notes))  # fmt: skip
    # auto without --static takes the file's model
    auto = run_angles(walking, subject_file=files[0], model="auto", preprocessing=NO_FILTER)
    assert auto.model == "cgm2.3" and f"model cgm2.3 (the model of the cluster calibration in {files[-1].name})" \
        in messages(auto.notes)  # fmt: skip
    _same_angles(with_static, auto)


def test_the_file_says_which_model_and_static_trial(tmp_path: Path, cgm24_session: tuple[Path, Path]) -> None:
    static, _ = cgm24_session
    written = calibrate_to_file(static, tmp_path / "cal.toml", model="cgm2.3")
    text = (tmp_path / "cal.toml").read_text()
    assert text.startswith("# CGM 2.3 subject calibrated by fuzzygait")
    table = tomllib.loads(text)["calibration"]
    assert table["model"] == "cgm2.3" and table["static"] == "static.c3d"
    assert table["method"] == "cgm2.3 clusters, KNM/MED knee/ankle centres"
    assert set(table["clusters"]) == {"LThigh", "LTibia", "RThigh", "RTibia"}
    assert table["clusters"]["LThigh"]["markers"] == ["LTHI", "LTHAP", "LTHAD", "LKNE"]
    assert np.shape(table["clusters"]["RTibia"]["local"]) == (4, 3)
    stored = read_stored_calibration(tmp_path / "cal.toml")
    assert stored.model == "cgm2.3" and stored.static == "static.c3d" and stored.clusters is not None
    assert written.calibration.clusters is not None
    for key, cluster in written.calibration.clusters.segments.items():  # exactly, every bit
        assert stored.clusters.segments[key].markers == cluster.markers
        np.testing.assert_array_equal(stored.clusters.segments[key].local, cluster.local)
    assert read_subject(tmp_path / "cal.toml") == written.calibration.subject


def test_auto_calibrates_a_cluster_model_only_for_a_cluster_static_trial(tmp_path: Path, cgm24_session) -> None:
    static, _ = cgm24_session
    name, why = calibration_model(read_c3d(static))
    assert name in ("cgm2.3", "cgm2.4") and "KNM/MED" in why
    assert calibration_model(read_c3d(SAMPLE_DATA / "static.c3d")) == (
        "cgm1.0", "static trial without thigh/shank clusters and KNM/MED")
    written = calibrate_to_file(SAMPLE_DATA / "static.c3d", tmp_path / "pig.toml",
                                subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    assert written.model == "cgm1.0" and written.calibration.clusters is None
    table = tomllib.loads((tmp_path / "pig.toml").read_text())["calibration"]
    assert table["model"] == "cgm1.0" and "clusters" not in table


def test_cgm24_calibration_carries_the_forefoot(tmp_path: Path, cgm24_session: tuple[Path, Path]) -> None:
    try:
        model_version("cgm2.4")
    except ParameterError:
        pytest.skip("cgm2.4 not implemented in this tree")
    static, walking = cgm24_session
    calibrate_to_file(static, tmp_path / "cal24.toml", model="cgm2.4")
    table = tomllib.loads((tmp_path / "cal24.toml").read_text())["calibration"]
    assert {"LForefoot", "RForefoot"} <= set(table["clusters"]) and set(table["forefoot_joint_centres"]) == {"L", "R"}
    with_static = run_angles(walking, static=static, model="cgm2.4", preprocessing=NO_FILTER)
    from_file = run_angles(walking, subject_file=tmp_path / "cal24.toml", model="auto", preprocessing=NO_FILTER)
    assert from_file.model == "cgm2.4" and "LForeFootAngles" in from_file.result.angles
    _same_angles(with_static, from_file)
    # a 2.3 calibration has no forefoot for 2.4: one line saying what to do
    calibrate_to_file(static, tmp_path / "cal23.toml", model="cgm2.3")
    with pytest.raises(ParameterError, match="has no forefoot for cgm2.4; give the static trial"):
        run_angles(walking, subject_file=tmp_path / "cal23.toml", model="cgm2.4")


def test_a_subject_file_without_clusters_says_what_to_do(tmp_path: Path, cgm24_session: tuple[Path, Path]) -> None:
    _, walking = cgm24_session
    subject = resolve_subject(read_c3d(walking), None)
    plain = write_subject(subject, tmp_path / "plain.toml")
    with pytest.raises(ParameterError, match=r"plain.toml: no cluster calibration for cgm2.3; give the static "
                       r"trial \(static= STATIC.c3d\), or calibrate once with `fuzzygait calibrate"):  # fmt: skip
        run_angles(walking, subject_file=plain, model="cgm2.3")
    vsk = write_subject(subject, tmp_path / "plain.vsk")
    with pytest.raises(ParameterError, match=r"plain.vsk \(no plain.clusters.toml beside it\): no cluster"):
        run_angles(walking, subject_file=vsk, model="cgm2.3")
    with pytest.raises(ParameterError, match="cgm2.3 tracks the thigh and shank clusters"):
        run_angles(walking, model="cgm2.3")
    assert run_angles(walking, subject_file=plain, model="auto").model == "cgm1.0"  # no clusters, no static


def test_a_calibration_from_another_marker_set_names_the_missing_markers(tmp_path: Path, cgm24_session) -> None:
    """Markers of the calibration absent from the walking trial: those angles are not
    computed and name them, the others are (the missing-marker path of --static)."""
    static, walking = cgm24_session
    calibrate_to_file(static, tmp_path / "cal.toml", model="cgm2.3")
    trial = read_c3d(walking)
    other = trial.select_markers([m for m in trial.marker_labels if m not in ("LTHAP", "LTHAD")])
    run = run_angles(other, subject_file=tmp_path / "cal.toml", model="cgm2.3")
    for name in ("LHipAngles", "LKneeAngles", "LAnkleAngles"):
        assert "LTHAP" in run.result.unavailable[name] and "LTHAD" in run.result.unavailable[name], name
    assert {"RHipAngles", "RKneeAngles", "LPelvisAngles"} <= set(run.result.angles)
    assert run.result.unavailable == run_angles(other, static=static, model="cgm2.3").result.unavailable


def test_older_and_plug_in_gait_files_read_as_before(tmp_path: Path) -> None:
    """A subject file of the earlier ``calibrate`` (flat [calibration], no model) and
    the sample subject file: subject parameters as before, no cluster calibration."""
    subject = read_subject(SAMPLE_DATA / "subject.toml")
    old = write_subject(subject, tmp_path / "old.toml", comments=["Plug-in Gait subject calibrated by fuzzygait"],
                        metadata={"static": "static.c3d", "method": "plain", "flat_foot": False})  # fmt: skip
    assert read_subject(old) == subject
    stored = read_stored_calibration(old)
    assert stored.clusters is None and stored.model is None and stored.static == "static.c3d"
    run = run_angles(SAMPLE_DATA / "walking.c3d", subject_file=old, model="auto")
    assert run.model == "cgm1.0" and not any("calibrated for" in note for note in messages(run.notes))
    assert read_stored_calibration(SAMPLE_DATA / "subject.toml").clusters is None


def test_model_mismatch_between_file_and_run_is_noted(tmp_path: Path) -> None:
    calibrate_to_file(SAMPLE_DATA / "static.c3d", tmp_path / "pig.toml", subject_file=SAMPLE_DATA / "subject.toml")
    run = run_angles(SAMPLE_DATA / "walking.c3d", subject_file=tmp_path / "pig.toml", model="cgm2.1")
    assert "pig.toml was calibrated for cgm1.0; its offsets are used by cgm2.1 as they are" in messages(run.notes)


def test_a_plug_in_gait_vsk_removes_the_sidecar_of_an_earlier_cluster_calibration(
    tmp_path: Path, cgm24_session: tuple[Path, Path]
) -> None:
    static, walking = cgm24_session
    calibrate_to_file(static, tmp_path / "cal.vsk", model="cgm2.3")
    assert (tmp_path / "cal.clusters.toml").is_file()
    written = calibrate_to_file(static, tmp_path / "cal.vsk", model="cgm1.0")
    assert written.removed == [tmp_path / "cal.clusters.toml"] and not written.removed[0].exists()
    with pytest.raises(ParameterError, match="no cluster calibration"):
        run_angles(walking, subject_file=tmp_path / "cal.vsk", model="cgm2.3")


def _table(static: Path) -> dict:
    calibration = calibrate_static(static, resolve_subject(read_c3d(static), None), model="cgm2.3")
    assert calibration.clusters is not None
    return cluster_table(calibration.clusters)


@pytest.mark.parametrize("change, message", [
    (lambda t: t["clusters"].pop("RTibia"), "lacks RTibia"),
    (lambda t: t["clusters"].update(LHead=t["clusters"]["LThigh"]), "LHead]: unknown segment"),
    (lambda t: t["clusters"]["LThigh"]["local"].pop(), "LThigh] local must be 4 rows"),
    (lambda t: t["clusters"]["LThigh"]["local"][0].__setitem__(1, "x"), "finite numbers"),
    (lambda t: t["clusters"]["LThigh"].__setitem__("markers", ["LTHI", "LKNE"]), "at least 3 different"),
    (lambda t: t["clusters"]["LThigh"].__setitem__("markers", "LTHI"), "list of marker labels"),
    (lambda t: t.__setitem__("forefoot_joint_centres", {"L": [0.0, 0.0, 0.0]}), "or neither"),
])  # fmt: skip
def test_malformed_cluster_tables_are_one_clear_error(cgm24_session, change, message: str) -> None:
    static, _ = cgm24_session
    table = _table(static)
    assert clusters_from_table(table, "cal.toml") is not None and clusters_from_table({}, "x") is None
    change(table)
    with pytest.raises(ParameterError, match=message) as error:
        clusters_from_table(table, "cal.toml")
    assert str(error.value).startswith("cal.toml: ") and "recalibrate with fuzzygait calibrate" in str(error.value)
