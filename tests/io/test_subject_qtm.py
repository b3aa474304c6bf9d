"""Qualisys Track Manager ``session.xml`` subject files (:mod:`fuzzygait.io.qtm_session`):
metres in, mm out; QTM's "not measured" zeros; one-line errors; session folders find it;
the shared CGM 2.4 session runs with it as with the same values typed into a TOML file."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import messages
from fuzzygait.io.qtm_session import qtm_session_values, qtm_subject_name
from fuzzygait.io.subject import is_subject_file, read_subject
from support import SAMPLE_DATA, SHARED_DATA, needs_shared, run_here, trial_window

QTM_SESSION = SHARED_DATA / "cgm2" / "qualisys-cgm24-input"


def session_xml(fields: dict[str, str], first: str = "Ada", last: str = "Lovelace",
                feet: tuple[str, str] | None = None) -> str:
    """A QTM session.xml shaped as QTM writes it: the patient, one visit with ``fields``,
    a subsession with ``feet`` = its (left, right) "foot normalised to static trial"
    fields (None: absent) and a measurement."""
    visit = "".join(f"<{k}>{v}</{k}>" for k, v in fields.items())
    flags = "" if feet is None else (f"<Left_foot_normalised_to_static_trial>{feet[0]}"
                                     "</Left_foot_normalised_to_static_trial><Right_foot_normalised_to_static_trial>"
                                     f"{feet[1]}</Right_foot_normalised_to_static_trial>")  # fmt: skip
    return ('<?xml version="1.0"?>\n<Subject Type="Patient" Filename="x">'
            f"<Fields><First_name>{first}</First_name><Last_name>{last}</Last_name></Fields>"
            f'<Session Type="Clinical Gait Session" Filename="2020-05-13"><Fields>{visit}</Fields>'
            '<Subsession Type="CGM2"><Fields><IkAccuracy>0.0001</IkAccuracy>'
            f"{flags}</Fields><Measurement Type=\"Gait\" Filename=\"g.qtm\">"
            "<Fields><Used>True</Used></Fields></Measurement></Subsession></Session></Subject>\n")  # fmt: skip


VISIT = {"Height": "1.799999952", "Weight": "70.000000000", "Leg_length_left": "0.905000000",
         "Leg_length_right": "0.910000000", "Knee_width_left": "0.101999998", "Knee_width_right": "0.103000000",
         "Ankle_width_left": "0.072000000", "Ankle_width_right": "0.071000000", "Marker_diameter": "0.016000000",
         "Sole_delta_left": "0.000000000", "Sole_delta_right": "0.005000000", "Elbow_width_left": "0.000000000"}  # fmt: skip


@pytest.mark.parametrize("encoding", ["utf-16", "utf-8"])
def test_reads_metres_as_mm(tmp_path: Path, encoding: str) -> None:
    """QTM writes UTF-16 with a byte-order mark; both encodings read the same."""
    path = tmp_path / "session.xml"
    path.write_text(session_xml(VISIT), encoding=encoding)
    subject = read_subject(path)
    assert (subject.body_mass, subject.height, subject.marker_diameter) == (70.0, 1800.0, 16.0)
    assert (subject.left.leg_length, subject.left.knee_width, subject.left.ankle_width) == (905.0, 102.0, 72.0)
    assert (subject.right.leg_length, subject.right.knee_width, subject.right.ankle_width) == (910.0, 103.0, 71.0)
    assert (subject.left.sole_delta, subject.right.sole_delta) == (0.0, 5.0)  # 0 is a sole delta, not "unmeasured"
    assert str(path) in subject.source
    assert qtm_subject_name(path) == "Ada Lovelace"


def test_unmeasured_required_value_is_named(tmp_path: Path) -> None:
    path = tmp_path / "session.xml"
    path.write_text(session_xml(VISIT | {"Knee_width_left": "0.000000000"}), encoding="utf-16")
    with pytest.raises(ParameterError, match=r"session\.xml: missing subject parameters LKneeWidth;"):
        read_subject(path)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"Leg_length_left": "905"}, r"Leg_length_left = 905 is not in metres .*0\.905 if that is mm"),
        ({"Ankle_width_right": "wide"}, r"field Ankle_width_right has non-numeric value 'wide'"),
    ],
)
def test_bad_values_get_one_line(tmp_path: Path, change: dict[str, str], message: str) -> None:
    path = tmp_path / "session.xml"
    path.write_text(session_xml(VISIT | change), encoding="utf-16")
    with pytest.raises(ParameterError, match=message) as caught:
        read_subject(path)
    assert "\n" not in str(caught.value) and str(path) in str(caught.value)


def test_other_xml_and_broken_xml_are_refused(tmp_path: Path) -> None:
    other = tmp_path / "settings.xml"
    other.write_text("<Settings><Rate>100</Rate></Settings>")
    with pytest.raises(ParameterError, match=r"settings\.xml: not a QTM session\.xml \(its root element is "
                                             r"<Settings>"):  # fmt: skip
        read_subject(other)
    broken = tmp_path / "session.xml"
    broken.write_text("<Subject><Session>")
    with pytest.raises(ParameterError, match=r"session\.xml: cannot read the QTM session\.xml"):
        read_subject(broken)
    empty = tmp_path / "empty" / "session.xml"
    empty.parent.mkdir()
    empty.write_text('<Subject><Session><Fields><Height>1.8</Height></Fields></Session></Subject>')
    with pytest.raises(ParameterError, match="no <Session> with Leg_length_left"):
        qtm_session_values(empty)
    with pytest.raises(ParameterError, match="no such subject file"):
        read_subject(tmp_path / "absent" / "session.xml")
    with pytest.raises(ParameterError, match="use .toml, .vsk, a Vicon Nexus or pyCGM2 .mp or a QTM session.xml"):
        read_subject(tmp_path / "s.json")


def test_only_session_xml_is_a_subject_file_of_a_folder() -> None:
    assert is_subject_file(Path("visit/session.xml")) and is_subject_file(Path("visit/Session.XML"))
    assert not is_subject_file(Path("visit/Gait 1.settings.xml"))
    assert all(is_subject_file(Path(f"visit/p{s}")) for s in (".toml", ".vsk", ".mp"))


def test_session_folder_uses_session_xml(tmp_path: Path) -> None:
    """A QTM-style folder: static and walking trial, session.xml and another XML file; the
    subject comes from session.xml, and its patient name is what a mismatch is checked
    against."""
    from fuzzygait.workflows.session import find_sessions

    folder = tmp_path / "visit"
    folder.mkdir()
    shutil.copy(SAMPLE_DATA / "static.c3d", folder / "Static 1.c3d")
    trial_window(SAMPLE_DATA / "walking.c3d", folder / "Gait 1.c3d", 0, 30)
    (folder / "session.xml").write_text(session_xml(VISIT, first="Synthetic", last=""), encoding="utf-16")
    (folder / "Gait 1.settings.xml").write_text("<Settings/>")
    (found,) = find_sessions([folder])
    assert found.subject_files == (folder / "session.xml",)
    (trial,) = found.trials
    assert trial.subject_file == folder / "session.xml" and trial.warnings == ()  # same patient: no warning
    (folder / "session.xml").write_text(session_xml(VISIT), encoding="utf-16")
    (trial,) = find_sessions([folder])[0].trials
    assert trial.warnings == ("subject mismatch: the trial is of subject 'Synthetic' but the subject file session.xml "
                              "is of 'Ada Lovelace'; check that the right subject file is in the session folder",)  # fmt: skip


@needs_shared
def test_shared_qtm_session_reads_its_stated_values() -> None:
    """The shared session's session.xml: the values it states in metres (0.094999999 m
    knee, 0.064999998 m ankle, 1.0 m legs, 0.014 m markers, 1.799999952 m, 70 kg)."""
    subject = read_subject(QTM_SESSION / "session.xml")
    assert (subject.left.leg_length, subject.right.leg_length) == (1000.0, 1000.0)
    assert (subject.left.knee_width, subject.right.knee_width) == (95.0, 95.0)
    assert (subject.left.ankle_width, subject.right.ankle_width) == (65.0, 65.0)
    assert (subject.marker_diameter, subject.body_mass, subject.height) == (14.0, 70.0, 1800.0)
    assert qtm_subject_name(QTM_SESSION / "session.xml") == "Test CGM2"


@needs_shared
def test_shared_qtm_session_angles_equal_the_toml_route(tmp_path: Path) -> None:
    """The CGM 2.4 session with ``--subject session.xml`` gives the angles of the same
    values typed into a TOML subject file with ``--flat-foot`` (the route the benchmarks
    took before; its session.xml sets foot flat)."""
    from fuzzygait.workflows.angles import run_angles

    toml = tmp_path / "subject.toml"
    toml.write_text("Bodymass = 70.0\nHeight = 1800.0\nLLegLength = 1000.0\nRLegLength = 1000.0\n"
                    "LKneeWidth = 95.0\nRKneeWidth = 95.0\nLAnkleWidth = 65.0\nRAnkleWidth = 65.0\n"
                    "MarkerDiameter = 14.0\n")  # fmt: skip
    runs = [run_angles(QTM_SESSION / "Gait - CGM2 1.c3d", static=QTM_SESSION / "Static - CGM2 1.c3d",
                       subject_file=subject, model="auto", flat_foot=flat)
            for subject, flat in ((QTM_SESSION / "session.xml", None), (toml, True))]  # fmt: skip
    # session.xml normalises both feet to the static trial: foot flat on by default, noted
    assert any("foot flat on as session.xml sets it" in note for note in messages(runs[0].notes))
    assert runs[0].result.model == "cgm2.4"
    names = sorted(runs[1].result.angles)
    assert sorted(runs[0].result.angles) == names and len(names) >= 10
    for name in names:
        np.testing.assert_array_equal(runs[0].result.angles[name], runs[1].result.angles[name], err_msg=name)


@pytest.mark.slow  # the angles command end to end on the real session
def test_cli_angles_with_session_xml(tmp_path: Path) -> None:
    """``angles --subject session.xml`` as a user runs it: the synthetic trial with its
    subject's values in metres gives the angles of its TOML subject file; the same file
    in mm is one line naming the field."""
    import pandas as pd

    from fuzzygait.io.subject import read_subject_toml
    from support import assert_one_line_error, run

    toml = read_subject_toml(SAMPLE_DATA / "subject.toml")
    metres = {"Height": toml.height, "Weight": toml.body_mass, "Marker_diameter": toml.marker_diameter}
    for side, values in (("left", toml.left), ("right", toml.right)):
        metres |= {f"Leg_length_{side}": values.leg_length, f"Knee_width_{side}": values.knee_width,
                   f"Ankle_width_{side}": values.ankle_width}  # fmt: skip
    xml = tmp_path / "session.xml"
    xml.write_text(session_xml({k: f"{v / 1000:.9f}" if k != "Weight" else f"{v:.9f}" for k, v in metres.items()}),
                   encoding="utf-16")  # fmt: skip
    outs = []
    for subject in (xml, SAMPLE_DATA / "subject.toml"):
        outs.append(tmp_path / f"{subject.suffix[1:]}.csv")
        result = run("angles", SAMPLE_DATA / "walking.c3d", "--static", SAMPLE_DATA / "static.c3d",
                     "--subject", subject, "--out", outs[-1])  # fmt: skip
        assert result.returncode == 0, result.stderr
    pd.testing.assert_frame_equal(pd.read_csv(outs[0]), pd.read_csv(outs[1]))
    xml.write_text(session_xml(VISIT | {"Knee_width_left": "102"}), encoding="utf-16")
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", "--subject", xml, "--out", tmp_path / "x.csv")
    assert_one_line_error(result, "session.xml", "Knee_width_left = 102 is not in metres")
    assert not (tmp_path / "x.csv").exists()


@pytest.mark.parametrize(
    ("feet", "expected"),
    [(("True", "True"), True), (("False", "False"), False), (("True", "False"), None), (None, None),
     (("yes", "yes"), None)],
)
def test_foot_flat_setting(tmp_path: Path, feet: tuple[str, str] | None, expected: bool | None) -> None:
    """Both feet agree: their setting; they differ, or it is absent or not True/False: none."""
    from fuzzygait.io.qtm_session import qtm_foot_flat

    path = tmp_path / "session.xml"
    path.write_text(session_xml(VISIT, feet=feet), encoding="utf-16")
    assert qtm_foot_flat(path) is expected
    assert read_subject(path).flat_foot is expected


def test_foot_flat_default_follows_session_xml(tmp_path: Path) -> None:
    """``flat_foot=None`` takes the file's setting (noted); an explicit value overrides it;
    a TOML subject has none (off). (The synthetic static foot stands with heel and toe at
    one height, so its offsets are the same either way; the angles differ on the shared
    session: test_shared_foot_flat_default_changes_the_angles.)"""
    from fuzzygait.io.subject import read_subject_toml
    from fuzzygait.workflows.angles import calibrate_static

    toml = read_subject_toml(SAMPLE_DATA / "subject.toml")
    xml = tmp_path / "session.xml"
    xml.write_text(session_xml(VISIT, feet=("True", "True")), encoding="utf-16")
    by_file = read_subject(xml)
    static = SAMPLE_DATA / "static.c3d"
    default = calibrate_static(static, by_file)
    assert default.flat_foot is True and "foot flat on" in default.describe()
    assert ("foot flat on as session.xml sets it (feet normalised to the static trial); flat_foot=False "
            "overrides it") in messages(default.notes)  # fmt: skip
    overridden = calibrate_static(static, by_file, flat_foot=False)
    assert overridden.flat_foot is False and not any("sets it" in n for n in messages(overridden.notes))
    plain = calibrate_static(static, toml)
    assert plain.flat_foot is False and not any("sets it" in n for n in messages(plain.notes))
    xml.write_text(session_xml(VISIT, feet=("False", "False")), encoding="utf-16")
    off = calibrate_static(static, read_subject(xml))
    assert off.flat_foot is False
    assert ("foot flat off as session.xml sets it (feet not normalised to the static trial); flat_foot=True "
            "overrides it") in messages(off.notes)  # fmt: skip


@needs_shared
def test_shared_foot_flat_default_changes_the_angles() -> None:
    """On the shared CGM 2.4 session (session.xml: both feet normalised) the default is
    the explicit ``--flat-foot`` run, and ``--no-flat-foot`` gives other ankle angles."""
    from fuzzygait.workflows.angles import run_angles

    def ankle(flat: bool | None) -> np.ndarray:
        run = run_angles(QTM_SESSION / "Gait - CGM2 1.c3d", static=QTM_SESSION / "Static - CGM2 1.c3d",
                         subject_file=QTM_SESSION / "session.xml", model="cgm2.4", flat_foot=flat)  # fmt: skip
        return run.result.angles["LAnkleAngles"]

    default, on, off = ankle(None), ankle(True), ankle(False)
    np.testing.assert_array_equal(default, on)
    assert np.nanmax(np.abs(on - off)) > 1.0
