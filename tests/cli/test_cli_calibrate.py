"""``fuzzygait calibrate`` end to end (subprocess), and ``--marker-diameter`` on the
commands that compute angles."""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support import SAMPLE_DATA, assert_one_line_error, run, run_here, shared_file

from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.subject import read_subject, subject_from_processing, subject_values
from fuzzygait.workflows.angles import calibrate_static

STATIC = SAMPLE_DATA / "static.c3d"
SUBJECT = SAMPLE_DATA / "subject.toml"
#: The values a static calibration writes (Vicon names without the side letter).
OFFSETS = ("ThighRotation", "ShankRotation", "TibialTorsion", "AnkleAbAdd", "StaticPlantFlex", "StaticRotOff")


def _calibrate(tmp_path: Path, name: str, *args: str | Path) -> Path:
    out = tmp_path / name
    result = run("calibrate", *args, "--out", out)
    assert result.returncode == 0, result.stderr
    assert f"wrote {out}" in result.stdout
    return out


def test_calibrate_writes_what_static_calibration_computes(tmp_path: Path) -> None:
    out = _calibrate(tmp_path, "cal.toml", STATIC, "--subject", SUBJECT)
    written = read_subject(out)
    expected = calibrate_static(STATIC, read_subject(SUBJECT))
    assert expected.method == "plain"
    assert written == expected.subject  # every value, exactly (floats written in full)
    truth = subject_values(read_subject(SUBJECT))  # the sample generator's own offsets
    for side in "LR":
        for name in OFFSETS:
            assert subject_values(written)[side + name] == pytest.approx(truth[side + name], abs=1e-6), side + name
    document = tomllib.loads(out.read_text())
    assert document["calibration"]["method"] == "plain" and document["calibration"]["flat_foot"] is False
    assert "Method plain, foot flat off, 14 mm markers" in out.read_text()


def test_the_static_trial_is_not_low_passed() -> None:
    """Offsets are means over the standing frames; the walking trials' 6 Hz filter would
    only add its edge transients.  The sample static trial with a 2 Hz filter asked for
    gives the calibration of the unfiltered markers, exactly."""
    from fuzzygait.kinematics import static_calibration
    from fuzzygait.workflows.angles import Preprocessing

    trial, subject = read_c3d(STATIC), read_subject(SUBJECT)
    asked = calibrate_static(trial, subject, preprocessing=Preprocessing(cutoff=2.0, filter=True))
    assert asked.subject == static_calibration(trial, subject)
    filtered, _ = Preprocessing(cutoff=2.0, filter=True).apply(trial)
    assert static_calibration(filtered, subject) != asked.subject  # a filter would change it


@pytest.mark.slow  # end-to-end: several CLI runs
def test_vsk_and_toml_outputs_agree(tmp_path: Path) -> None:
    toml = _calibrate(tmp_path, "cal.toml", STATIC, "--subject", SUBJECT, "--flat-foot")
    vsk = _calibrate(tmp_path, "cal.vsk", STATIC, "--subject", SUBJECT, "--flat-foot")
    assert read_subject(vsk) == read_subject(toml)
    assert "foot flat on" in vsk.read_text()


def test_without_subject_file_the_static_trials_processing_group(tmp_path: Path) -> None:
    out = _calibrate(tmp_path, "cal.toml", STATIC)
    from_c3d = subject_from_processing(read_c3d(STATIC).parameters)  # float32 values
    assert read_subject(out) == calibrate_static(STATIC, from_c3d).subject
    assert "measurements from static.c3d PROCESSING group" in out.read_text()


@pytest.mark.slow  # end-to-end: several CLI runs
def test_angles_with_the_calibrated_file_equal_angles_with_the_static_trial(tmp_path: Path) -> None:
    walking = SAMPLE_DATA / "walking_noisy.c3d"
    tables = {}
    calibrated = _calibrate(tmp_path, "cal.toml", STATIC, "--subject", SUBJECT)
    for key, args in {"static": ("--static", STATIC, "--subject", SUBJECT), "file": ("--subject", calibrated)}.items():
        result = run("angles", walking, *args, "--out", tmp_path / f"{key}.csv")
        assert result.returncode == 0, result.stderr
        tables[key] = pd.read_csv(tmp_path / f"{key}.csv")
    pd.testing.assert_frame_equal(tables["static"], tables["file"], rtol=0, atol=1e-12)


@pytest.mark.slow  # end-to-end: several CLI runs
def test_marker_diameter_overrides_the_subjects(tmp_path: Path) -> None:
    out = _calibrate(tmp_path, "cal16.toml", STATIC, "--subject", SUBJECT, "--marker-diameter", "16")
    written = read_subject(out)
    assert written.marker_diameter == 16.0
    assert written == calibrate_static(STATIC, replace(read_subject(SUBJECT), marker_diameter=16.0)).subject
    assert written.left.static_plant_flex != read_subject(SUBJECT).left.static_plant_flex
    walking = SAMPLE_DATA / "walking.c3d"
    runs = {"static": ("--static", STATIC, "--subject", SUBJECT, "--marker-diameter", "16"),
            "file": ("--subject", out), "file14": ("--subject", out, "--marker-diameter", "14")}  # fmt: skip
    for key, args in runs.items():
        result = run("angles", walking, *args, "--out", tmp_path / f"{key}.csv")
        assert result.returncode == 0, result.stderr
    static, file, file14 = (pd.read_csv(tmp_path / f"{k}.csv") for k in ("static", "file", "file14"))
    pd.testing.assert_frame_equal(static, file, rtol=0, atol=1e-12)
    assert not np.allclose(file["LKneeAngles_Z"], file14["LKneeAngles_Z"], atol=1e-3)


@pytest.mark.parametrize("command", ["calibrate", "angles", "uncertainty", "report"])
def test_marker_diameter_in_help(command: str) -> None:
    result = run(command, "--help")
    assert result.returncode == 0
    text = " ".join(result.stdout.replace("│", " ").split())  # rich draws the option table's borders
    assert "--marker-diameter" in text and "not in the C3D" in text and "else 14" in text


# ----------------------------------------------------------------------- bad input
def test_bad_output_suffix_is_refused_before_work(tmp_path: Path) -> None:
    result = run_here("calibrate", tmp_path / "absent.c3d", "--out", tmp_path / "cal.json")
    assert_one_line_error(result, "cal.json", ".toml or .vsk")


def test_missing_static_file_is_one_line(tmp_path: Path) -> None:
    result = run_here("calibrate", tmp_path / "absent.c3d", "--out", tmp_path / "cal.toml")
    assert_one_line_error(result, "absent.c3d")
    assert not (tmp_path / "cal.toml").exists()


def test_static_without_a_heel_marker_is_one_line_and_writes_nothing(tmp_path: Path) -> None:
    trial = read_c3d(STATIC)
    write_c3d(trial.select_markers([m for m in trial.marker_labels if m != "LHEE"]), tmp_path / "s.c3d")
    result = run_here("calibrate", tmp_path / "s.c3d", "--subject", SUBJECT, "--out", tmp_path / "cal.toml")
    assert_one_line_error(result, "s.c3d", "LHEE", "label")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.c3d"]


@pytest.mark.parametrize("diameter", ["0", "160", "nan"])
def test_implausible_marker_diameter_is_one_line(tmp_path: Path, diameter: str) -> None:
    result = run_here("calibrate", STATIC, "--marker-diameter", diameter, "--out", tmp_path / "cal.toml")
    assert_one_line_error(result, "marker diameter", "mm")
    assert not (tmp_path / "cal.toml").exists()


def test_bad_subject_file_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "s.toml").write_text(SUBJECT.read_text().replace("LKneeWidth = 105.0", "LKneeWidth = 0.105"))
    result = run_here("calibrate", STATIC, "--subject", tmp_path / "s.toml", "--out", tmp_path / "cal.vsk")
    assert_one_line_error(result, "s.toml", "LKneeWidth")
    assert not (tmp_path / "cal.vsk").exists()


# ----------------------------------------------------------------------- Nexus sessions
#: session: (static trial, file whose PROCESSING holds Nexus' calibration, calibrate options).
#: The foot-flat session's static trial stores the parameters before calibration, its walking
#: trial those after; 16 mm markers; static trials are never low-passed.
NEXUS_SESSIONS = {
    "PiGKad": ("PiGKad_Calibration.c3d", "PiGKad_Calibration.c3d", ()),
    "PiGKadMed": ("PiGKadMed_Calibration.c3d", "PiGKadMed_Calibration.c3d", ()),
    "FlatFoot": ("PiG_Calibration-FlatFoot-Full.c3d", "PiG_Motion-FlatFoot-Full.c3d",
                 ("--flat-foot", "--marker-diameter", "16")),
}  # fmt: skip


@pytest.mark.parametrize("session", NEXUS_SESSIONS)
def test_calibrate_reproduces_nexus_processing_values(tmp_path: Path, session: str) -> None:
    static_name, reference_name, options = NEXUS_SESSIONS[session]
    static = shared_file("pig-options", static_name)
    nexus = read_c3d(shared_file("pig-options", reference_name)).parameters
    out = _calibrate(tmp_path, "cal.vsk", static, *options)
    written = subject_values(read_subject(out))
    for side in "LR":
        for name in OFFSETS:
            assert written[side + name] == pytest.approx(nexus[side + name], abs=1e-6), side + name
    assert written["InterAsisDistance"] == pytest.approx(nexus["InterAsisDistance"], abs=1e-3)
    method = {"PiGKad": "KAD", "PiGKadMed": "KAD+MED", "FlatFoot": "plain"}[session]
    assert f"Method {method}, foot flat {'on' if options else 'off'}" in out.read_text()


def test_a_missing_kad_marker_is_one_line(tmp_path: Path) -> None:
    trial = read_c3d(shared_file("pig-options", "PiGKad_Calibration.c3d"))
    write_c3d(trial.select_markers([m for m in trial.marker_labels if m != "RKD2"]), tmp_path / "s.c3d")
    result = run_here("calibrate", tmp_path / "s.c3d", "--out", tmp_path / "cal.toml")
    assert_one_line_error(result, "RKD2 missing")
    assert not (tmp_path / "cal.toml").exists()


def test_calibrating_a_nexus_vsk_keeps_its_skeleton(tmp_path: Path) -> None:
    """``--subject Test.vsk --out cal.vsk``: Nexus' file with the calibrated values, its
    skeleton and marker set kept (what Nexus needs to load it as a subject)."""
    import xml.etree.ElementTree as ET

    vsk = shared_file("vicon", "Test.vsk")
    out = _calibrate(tmp_path, "cal.vsk", shared_file("vicon", "Static_trial.c3d"), "--subject", vsk)
    root = ET.parse(out).getroot()
    assert root.attrib["MODEL"] == "PlugInGait FullBody Ai"
    assert len(root.findall(".//Segment")) == len(ET.parse(vsk).getroot().findall(".//Segment")) > 0
    nexus = read_c3d(shared_file("vicon", "Movement_trial.c3d")).parameters
    written = subject_values(read_subject(out))
    for side in "LR":
        for name in ("StaticPlantFlex", "StaticRotOff"):
            assert written[side + name] == pytest.approx(nexus[side + name], abs=1e-6), side + name


@pytest.fixture(scope="module")
def cgm24_session(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The synthetic CGM 2.4 session (static with KNM/MED, 2-cycle walking) as C3D files."""
    from fuzzygait.synthetic.cgm24 import make_cgm24_static, make_cgm24_walking

    folder = tmp_path_factory.mktemp("cgm24")
    write_c3d(make_cgm24_static(), folder / "static.c3d")
    write_c3d(make_cgm24_walking(n_cycles=2)[0], folder / "walking.c3d")
    return folder / "static.c3d", folder / "walking.c3d"


@pytest.mark.slow  # end-to-end: several CLI runs
@pytest.mark.parametrize("suffix", [".toml", ".vsk"])
def test_cgm23_angles_from_the_calibration_file_equal_angles_with_the_static_trial(
    tmp_path: Path, cgm24_session: tuple[Path, Path], suffix: str
) -> None:
    static, walking = cgm24_session
    calibrated = tmp_path / f"cal{suffix}"
    result = run("calibrate", static, "--model", "cgm2.3", "--out", calibrated)
    assert result.returncode == 0, result.stderr
    assert f"wrote {calibrated}" in result.stdout
    assert "model cgm2.3 (given by name)" in result.stdout and "L thigh (4 markers)" in result.stdout
    if suffix == ".vsk":
        assert f"wrote {tmp_path / 'cal.clusters.toml'}" in result.stdout
    tables = {}
    for key, args in {"static": ("--static", static), "file": ("--subject", calibrated)}.items():
        result = run("angles", walking, *args, "--model", "cgm2.3", "--out", tmp_path / f"{key}.csv")
        assert result.returncode == 0, result.stderr
        assert "note: model cgm2.3 (given by name)" in result.stdout  # an explicit --model is said too
        tables[key] = pd.read_csv(tmp_path / f"{key}.csv")
    assert set(tables["file"]["model"]) == {"cgm2.3"}
    pd.testing.assert_frame_equal(tables["static"], tables["file"], rtol=0, atol=1e-9)


def test_cluster_model_without_a_cluster_calibration_is_one_line(tmp_path: Path, cgm24_session) -> None:
    _, walking = cgm24_session
    result = run_here("angles", walking, "--subject", SUBJECT, "--model", "cgm2.3", "--out", tmp_path / "a.csv")
    assert_one_line_error(result, "subject.toml: no cluster calibration for cgm2.3", "--static STATIC.c3d",
                          "fuzzygait calibrate STATIC.c3d --model cgm2.3 --out CAL.toml")  # fmt: skip
    assert not (tmp_path / "a.csv").exists()


def test_cluster_calibration_of_a_plug_in_gait_static_is_one_line(tmp_path: Path) -> None:
    result = run_here("calibrate", STATIC, "--subject", SUBJECT, "--model", "cgm2.3", "--out", tmp_path / "cal.toml")
    assert_one_line_error(result, "LTHAP", "missing")
    assert not (tmp_path / "cal.toml").exists()
