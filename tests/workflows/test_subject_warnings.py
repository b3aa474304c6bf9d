"""What a run warns of about its subject (:func:`fuzzygait.workflows.subject_resolution.subject_warnings`):
files of another subject, measurements the static trial contradicts, and a session folder
whose subject files name none of its trials' subjects.

Truth: the synthetic static trial, whose markers sit exactly where the generator's
measurements put them (ASIS-malleolus, KNE-KNM and ANK-MED distances of the known leg
length and widths plus the 14 mm markers), and the same with one measurement changed."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import pytest

from fuzzygait.io import read_c3d
from fuzzygait.io.subject import read_subject
from fuzzygait.workflows.angles import run_angles
from fuzzygait.workflows.session import find_session
from fuzzygait.workflows.subject_resolution import measurement_warnings, subject_warnings
from support import SAMPLE_DATA, needs_shared, run_here, shared_file

SUBJECT = SAMPLE_DATA / "subject.toml"


def _subject_file(tmp_path: Path, name: str, **changes: str) -> Path:
    text = (SAMPLE_DATA / "subject.toml").read_text(encoding="utf-8")
    for old, new in changes.items():
        text = text.replace(old, new)
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_the_sample_subject_fits_its_static_trial() -> None:
    static = read_c3d(SAMPLE_DATA / "static.c3d")
    assert measurement_warnings(read_subject(SUBJECT), static) == []
    run = run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d", subject_file=SUBJECT)
    assert run.warnings == []


@pytest.mark.parametrize(("old", "new", "needle"), [
    ("LLegLength = 900.0", "LLegLength = 1010.0", "gives LLegLength 1010 mm but the static trial static.c3d's "
                                                  "LASI-LMED distance is 907 mm"),
    ("RKneeWidth = 105.0", "RKneeWidth = 80.0", "gives RKneeWidth 80 mm but the static trial's RKNE-RKNM distance "
                                                "less the 14 mm marker diameter is 105 mm"),
    ("LAnkleWidth = 70.0", "LAnkleWidth = 90.0", "LAnkleWidth 90 mm but the static trial's LANK-LMED distance"),
])  # fmt: skip
def test_a_measurement_the_static_trial_contradicts_is_named(tmp_path: Path, old: str, new: str, needle: str) -> None:
    subject = _subject_file(tmp_path, "s.toml", **{old: new})
    run = run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d", subject_file=subject)
    assert len(run.warnings) == 1 and needle in run.warnings[0], run.warnings


def test_within_the_margins_nothing_is_said(tmp_path: Path) -> None:
    """8 % on the leg length, 14 mm on a knee width: a tape and calipers, not another subject."""
    subject = read_subject(_subject_file(tmp_path, "s.toml", **{"LLegLength = 900.0": "LLegLength = 972.0",
                                                                "RKneeWidth = 105.0": "RKneeWidth = 91.0"}))  # fmt: skip
    assert measurement_warnings(subject, read_c3d(SAMPLE_DATA / "static.c3d")) == []


def test_files_of_another_subject_are_warned_of(tmp_path: Path) -> None:
    other = _subject_file(tmp_path, "other.toml", **{"Bodymass": 'Name = "Someone Else"\nBodymass'})
    walking = read_c3d(SAMPLE_DATA / "walking.c3d")
    static = replace(read_c3d(SAMPLE_DATA / "static.c3d"), subject="Another")
    found = subject_warnings(walking, other, static, read_subject(other))
    assert found == [
        "subject mismatch: the trial is of subject 'Synthetic' but the subject file other.toml is of 'Someone Else'; "
        "check that the right subject file is in the session folder",
        "subject mismatch: the trial is of subject 'Synthetic' but the static trial static.c3d is of 'Another'; "
        "check that the right static trial is in the session folder",
    ]
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", "--subject", other, "--out", tmp_path / "a.csv")
    assert result.returncode == 0
    assert "fuzzygait: warning: subject mismatch: the trial is of subject 'Synthetic'" in result.stderr


def test_calibrate_warns_too(tmp_path: Path) -> None:
    subject = _subject_file(tmp_path, "s.toml", **{"LLegLength = 900.0": "LLegLength = 1010.0"})
    result = run_here("calibrate", SAMPLE_DATA / "static.c3d", "--subject", subject, "--out", tmp_path / "c.toml")
    assert result.returncode == 0, result.stderr
    assert "fuzzygait: warning: s.toml gives LLegLength 1010 mm" in result.stderr


def test_several_subject_files_naming_nobody_are_listed(tmp_path: Path) -> None:
    folder = tmp_path / "visit"
    folder.mkdir()
    for name in ("walking.c3d", "static.c3d"):
        shutil.copy(SAMPLE_DATA / name, folder / name)
    _subject_file(folder, "a.toml", **{"Bodymass": 'Name = "X"\nBodymass'})
    _subject_file(folder, "b.toml")
    session = find_session(folder, "visit")
    (trial,) = session.trials
    assert trial.subject_file is None
    assert trial.warnings == (
        "none of the subject files a.toml (of 'X'), b.toml (names no subject) is named after its subject "
        "'Synthetic': none is used, the trial's PROCESSING group gives the subject; keep one subject file per "
        "session folder, name it after the subject, or give subject_file=",
    )
    # one of them named after the subject: that one, no warning
    _subject_file(folder, "b.toml", **{"Bodymass": 'Name = "Synthetic"\nBodymass'})
    (trial,) = find_session(folder, "visit").trials
    assert trial.subject_file == folder / "b.toml" and trial.warnings == ()


@needs_shared
def test_the_qualisys_session_xml_values_are_questioned() -> None:
    """QTM's session.xml of the shared CGM 2.4 session gives 1000 / 95 / 65 mm; its static
    trial's markers say a shorter left leg and wider knees."""
    folder = shared_file("cgm2", "qualisys-cgm24-input", "session.xml").parent
    static = read_c3d(folder / "Static - CGM2 1.c3d")
    found = measurement_warnings(read_subject(folder / "session.xml"), static)
    assert [w.split(" but ")[0] for w in found] == ["session.xml gives LLegLength 1000 mm",
                                                    "session.xml gives LKneeWidth 95 mm",
                                                    "session.xml gives RKneeWidth 95 mm"]  # fmt: skip
