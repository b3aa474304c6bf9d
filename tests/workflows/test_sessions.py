"""Session discovery and the batch report's running: which static rule fired, subject
mismatch warnings, skip-unchanged by content hash, --force, no partial files after a
killed trial, identical page data with 1 and 2 workers."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.io import read_c3d
from fuzzygait.workflows import trial_job
from fuzzygait.workflows.angles import Preprocessing
from fuzzygait.workflows.batch_report import BatchReportRequest, load_page_data, write_batch_report
from fuzzygait.workflows.session import find_sessions, static_rule
from support import SAMPLE_DATA, SHARED_DATA, VICON, needs_shared, synthetic_session, trial_window

MISMATCH = ("subject mismatch: the trial is of subject 'A22' but the subject file Test.vsk is of 'Test'; "
            "check that the right subject file is in the session folder")  # fmt: skip


@pytest.fixture
def session(tmp_path: Path) -> Path:
    """Two walking trials with a complete gait cycle per side (140 frames)."""
    return synthetic_session(tmp_path / "visit-1", 140)


def test_static_rules() -> None:
    static = read_c3d(SAMPLE_DATA / "static.c3d")
    walking = read_c3d(SAMPLE_DATA / "walking.c3d")
    rule = static_rule(Path("cal01.c3d"), static)
    assert rule is not None and rule[0] == "markers" and "LKNM" in rule[1]
    keep = [i for i, m in enumerate(static.marker_labels) if m not in ("LKNM", "RKNM", "LMED", "RMED")]
    plain = dataclasses.replace(static, markers=static.markers[:, keep],
                                marker_labels=[static.marker_labels[i] for i in keep])  # fmt: skip
    assert static_rule(Path("trial07.c3d"), plain) == ("motion", "near-zero motion: pelvis range 0 mm, no gait events")
    assert static_rule(Path("Patient Static 1.c3d"), plain) == ("file name", "its name contains 'Static'")
    assert static_rule(Path("walk.c3d"), walking) is None
    assert static_rule(Path("unreadable.c3d"), None) is None


def test_synthetic_session_found(session: Path) -> None:
    (found,) = find_sessions([session.parent])  # a folder of session folders
    assert found.name == "visit-1" and found.output == "visit-1"
    assert [(s.path.name, s.rule) for s in found.statics] == [("cal01.c3d", "markers")]
    assert [t.path.name for t in found.trials] == ["walk01.c3d", "walk02.c3d"]
    assert all(t.static == session / "cal01.c3d" and t.subject_file == session / "Synthetic.toml"
               for t in found.trials)  # fmt: skip
    assert all(t.warnings == () for t in found.trials)  # the TOML names no subject: no check


def test_a_static_of_another_marker_set_is_not_paired(tmp_path: Path) -> None:
    """A Plug-in Gait walking trial beside a Plug-in Gait and a CGM 2.4 static whose names
    say nothing (``walk.c3d``, ``cal-a.c3d``, ``cal-b.c3d``): the static with the walking
    trial's marker set is paired, whichever comes first by name."""
    import shutil

    folder = tmp_path / "visit"
    folder.mkdir()
    shutil.copy(SAMPLE_DATA / "walking.c3d", folder / "walk.c3d")
    for name, source in (("cal-a.c3d", "cgm24_static.c3d"), ("cal-b.c3d", "static.c3d")):
        shutil.copy(SAMPLE_DATA / source, folder / name)
    (found,) = find_sessions([folder])
    assert sorted(s.path.name for s in found.statics) == ["cal-a.c3d", "cal-b.c3d"]
    (trial,) = found.trials
    assert trial.static == folder / "cal-b.c3d"  # static.c3d's Plug-in Gait markers
    labels = set(read_c3d(folder / "walk.c3d").marker_labels)
    shared = {name: len(labels & set(read_c3d(folder / name).marker_labels)) / len(labels | set(
        read_c3d(folder / name).marker_labels)) for name in ("cal-a.c3d", "cal-b.c3d")}  # fmt: skip
    assert shared["cal-b.c3d"] > shared["cal-a.c3d"]


def test_files_given_directly_keep_static_and_subject(session: Path) -> None:
    (found,) = find_sessions([session / "walk01.c3d", session / "walk01.c3d"], SAMPLE_DATA / "static.c3d",
                             SAMPLE_DATA / "subject.toml")  # fmt: skip
    assert found.folder is None and found.output == ""
    (trial,) = found.trials
    assert trial.static == SAMPLE_DATA / "static.c3d" and trial.subject_file == SAMPLE_DATA / "subject.toml"


@needs_shared
def test_real_sessions_and_subject_mismatch() -> None:
    vicon, pig = find_sessions([VICON, SHARED_DATA / "pig-options"])
    assert [(s.path.name, s.rule) for s in vicon.statics] == [("Static_trial.c3d", "file name")]
    trials = {t.path.name: t for t in vicon.trials}
    assert sorted(trials) == ["Movement_trial.c3d", "gait-pig.c3d", "gait-raw.c3d"]
    assert trials["Movement_trial.c3d"].warnings == ()
    assert trials["gait-pig.c3d"].subject_file is not None and trials["gait-pig.c3d"].subject_file.name == "Test.vsk"
    assert trials["gait-pig.c3d"].warnings[0] == MISMATCH
    rules = {s.path.name: s.rule for s in pig.statics}
    assert rules == {"PiGKadMed_Calibration.c3d": "markers", "PiGKad_Calibration.c3d": "markers",
                     "PiG_Calibration-FlatFoot-Full.c3d": "file name"}  # fmt: skip
    paired = {t.path.name: t.static.name for t in pig.trials if t.static is not None}
    assert paired == {"PiGKadMed_Motion.c3d": "PiGKadMed_Calibration.c3d",
                      "PiGKad_Motion.c3d": "PiGKad_Calibration.c3d",
                      "PiG_Motion-FlatFoot-Full.c3d": "PiG_Calibration-FlatFoot-Full.c3d"}  # fmt: skip


def _job_files(folder: Path, name: str) -> dict[str, float]:
    return {p.name: p.stat().st_mtime_ns for p in [folder / f"{name}.html", *(folder / f"{name}_files").iterdir()]}


@pytest.mark.slow
def test_skip_unchanged_force_and_changed_options(session: Path, tmp_path: Path) -> None:
    out = tmp_path / "report"
    first = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert first.n_ok == 2 and first.n_skipped == 0
    pages = out / "visit-1"
    assert (out / "index.html").is_file() and (pages / "index.html").is_file()
    assert (pages / "session_files" / "cycles.png").is_file()
    assert "visit-1" in (out / "index.html").read_text(encoding="utf-8")
    assert "cal01.c3d (found by markers" in (pages / "index.html").read_text(encoding="utf-8")
    before = _job_files(pages, "walk01")

    again = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert again.n_skipped == 2 and _job_files(pages, "walk01") == before

    trial_window(SAMPLE_DATA / "walking.c3d", session / "walk02.c3d", 101, 140)  # same name, other content
    changed = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert [o.skipped for o in changed.outcomes] == [True, False]

    other = write_batch_report(BatchReportRequest([session], out, uncertainty="none",
                                                  preprocessing=Preprocessing(cutoff=5.0)))  # fmt: skip
    assert other.n_skipped == 0
    forced = write_batch_report(BatchReportRequest([session], out, uncertainty="none",
                                                   preprocessing=Preprocessing(cutoff=5.0), force=True))  # fmt: skip
    assert forced.n_skipped == 0 and _job_files(pages, "walk01") != before


@pytest.mark.slow
def test_killed_run_leaves_no_partial_file_and_resumes(session: Path, tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    out = tmp_path / "report"
    real = trial_job.page_data

    def killed_on_second(analysis: trial_job.MarkerErrorAnalysis) -> dict[str, np.ndarray]:
        if "walk02" in analysis.run.trial.name:
            raise KeyboardInterrupt  # the batch is killed mid-trial
        return real(analysis)

    monkeypatch.setattr(trial_job, "page_data", killed_on_second)
    with pytest.raises(KeyboardInterrupt):
        write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    pages = out / "visit-1"
    assert (pages / "walk01.html").is_file() and (pages / "walk01_files" / "job.json").is_file()
    assert not (pages / "walk02.html").exists() and not (pages / "walk02_files").exists()
    assert not [p for p in out.rglob("*") if ".tmp" in p.name], "partial files left"
    assert not (out / "index.html").exists()

    stale = pages / ".walk02.abc123.tmp"  # what a worker killed mid-trial leaves (no finally runs there)
    (stale / "w").mkdir(parents=True)
    monkeypatch.setattr(trial_job, "page_data", real)
    resumed = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert not stale.exists()
    assert [o.skipped for o in resumed.outcomes] == [True, False] and resumed.n_ok == 2
    assert json.loads((pages / "walk02_files" / "job.json").read_text())["key"]


@pytest.mark.slow
def test_failing_trial_is_listed_with_one_line(session: Path, tmp_path: Path) -> None:
    (session / "walk03.c3d").write_bytes(b"not a c3d file")
    failures: list[str] = []
    result = write_batch_report(BatchReportRequest([session], tmp_path / "r", uncertainty="none"),
                                on_failure=lambda path, error: failures.append(error))  # fmt: skip
    assert result.n_ok == 2 and result.n_failed == 1
    assert len(failures) == 1 and "\n" not in failures[0] and "walk03.c3d" in failures[0]
    assert "walk03.c3d" in (tmp_path / "r" / "visit-1" / "index.html").read_text(encoding="utf-8")


@pytest.mark.slow
def test_page_data_identical_with_one_and_two_workers(tmp_path: Path) -> None:
    """--uncertainty fast on a LocalCluster of 2 workers and in-process: the same numbers
    (30-frame trials: the analysis is ~1 s per 10 frames)."""
    session = synthetic_session(tmp_path / "visit-1", 30)
    one = write_batch_report(BatchReportRequest([session], tmp_path / "one", uncertainty="fast", workers=1))
    two = write_batch_report(BatchReportRequest([session], tmp_path / "two", uncertainty="fast", workers=2))
    assert one.n_ok == two.n_ok == 2
    for name in ("walk01", "walk02"):
        a, b = load_page_data(tmp_path / "one" / "visit-1", name), load_page_data(tmp_path / "two" / "visit-1", name)
        assert sorted(a) == sorted(b) and "hull" in a
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


@pytest.mark.slow
def test_pycgm2_subject_file_of_another_subject_warns(tmp_path: Path) -> None:
    """A session whose only subject file is a pyCGM2 .mp of "Patient02": used, with the
    mismatch warning; one named after the trial's subject is preferred."""
    folder = synthetic_session(tmp_path / "visit", 30)
    (folder / "Synthetic.toml").unlink()
    mp = ("MandatoryParameters:\n  Bodymass: 72\n  LeftLegLength: 900\n  RightLegLength: 900\n  LeftKneeWidth: 105\n"
          "  RightKneeWidth: 105\n  LeftAnkleWidth: 70\n  RightAnkleWidth: 70\n")  # fmt: skip
    (folder / "Patient02.mp").write_text(mp, encoding="utf-8")
    (found,) = find_sessions([folder])
    trial = found.trials[0]
    assert trial.subject == "Synthetic" and trial.subject_file == folder / "Patient02.mp"
    assert trial.warnings == ("subject mismatch: the trial is of subject 'Synthetic' but the subject file Patient02.mp "
                              "is of 'Patient02'; check that the right subject file is in the session folder",)  # fmt: skip
    assert found.warnings[0].startswith("walk01.c3d: subject mismatch")
    (folder / "Synthetic.mp").write_text(mp, encoding="utf-8")
    (found,) = find_sessions([folder])
    assert all(t.subject_file == folder / "Synthetic.mp" and t.warnings == () for t in found.trials)
    result = write_batch_report(BatchReportRequest([folder], tmp_path / "r", uncertainty="none"))  # the .mp is read
    assert result.n_ok == 2
