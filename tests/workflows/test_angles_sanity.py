"""The angle pipeline runs the content checks (issue 17 Deliver 2): a spike is blanked and
the angles equal the clean trial's, a marker missing throughout is named with the angles
it leaves empty and not counted, a walking trial as the static one, metres and absurd
rates are refused in one line."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from support import SAMPLE_DATA, VICON, assert_one_line_error, needs_shared, run, run_here

from fuzzygait.core.errors import C3DError
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.workflows.angles import run_angles
from fuzzygait.workflows.calibrate import calibrate_to_file

SUBJECT = SAMPLE_DATA / "subject.toml"


@pytest.fixture(scope="module")
def trials():
    return read_c3d(SAMPLE_DATA / "walking.c3d"), read_c3d(SAMPLE_DATA / "static.c3d")


@pytest.fixture(scope="module")
def clean(trials):
    walking, static = trials
    return run_angles(walking, static=static, subject_file=SUBJECT, model="cgm1.0")


def _with(trial, label, change):
    markers = trial.markers.copy()
    change(markers[:, trial.marker_labels.index(label), :])
    return trial.with_markers(markers)


def test_a_spike_is_blanked_and_the_angles_equal_the_clean_trial_s(trials, clean):
    walking, static = trials
    spiked = _with(walking, "LKNE", lambda m: m.__setitem__((200, 0), 1e30))
    run = run_angles(spiked, static=static, subject_file=SUBJECT, model="cgm1.0")
    assert any(n.startswith("LKNE: 1 implausible sample blanked (frame 201:") for n in messages(run.notes))
    assert any(n.startswith("gap filling: 1 of 1 gaps filled") for n in messages(run.notes))
    assert set(run.result.angles) == set(clean.result.angles) and not run.result.unavailable
    far = np.r_[0:180, 221:walking.n_frames]
    for name, values in clean.result.angles.items():
        np.testing.assert_allclose(run.result.angles[name], values, atol=1e-3, err_msg=name)  # at the spike too
        np.testing.assert_allclose(run.result.angles[name][far], values[far], atol=1e-6, err_msg=name)


def test_a_spike_in_the_static_trial_is_blanked_and_noted(trials, clean):
    walking, static = trials
    spiked = _with(static, "RANK", lambda m: m.__setitem__((50, 2), -1e30))
    run = run_angles(walking, static=spiked, subject_file=SUBJECT, model="cgm1.0")
    assert "static trial static.c3d: RANK: 1 implausible sample blanked (frame 51:" in " ".join(messages(run.notes))
    for name, values in clean.result.angles.items():
        np.testing.assert_allclose(run.result.angles[name], values, atol=1e-9, err_msg=name)


def test_a_marker_missing_throughout_is_named_and_its_angles_not_counted(trials, clean):
    walking, static = trials
    run = run_angles(_with(walking, "LKNE", lambda m: m.fill(np.nan)), static=static, subject_file=SUBJECT,
                     model="cgm1.0")  # fmt: skip
    empty = {"LHipAngles", "LKneeAngles", "LAnkleAngles", "LFootProgressAngles"}
    assert set(run.result.unavailable) == empty
    for name in empty:
        assert np.isnan(run.result.angles[name]).all()
        expected = f"{name} not computed: no frame could be computed (marker LKNE missing in every frame)"
        assert expected in messages(run.notes)
    computed = [n for n in run.result.angles if n not in run.result.unavailable]
    assert computed and all(np.isfinite(run.result.angles[n]).any() for n in computed)
    for name in computed:  # the other side and the pelvis are as before
        np.testing.assert_allclose(run.result.angles[name], clean.result.angles[name], atol=1e-9)


def test_a_walking_trial_as_the_static_one_is_refused(trials, tmp_path):
    walking, _ = trials
    with pytest.raises(C3DError, match=r"^walking\.c3d: given as the static trial but it moves"):
        run_angles(walking, static=walking, subject_file=SUBJECT)
    with pytest.raises(C3DError, match=r"^walking\.c3d: given as the static trial but it moves"):
        calibrate_to_file(walking, tmp_path / "cal.toml", subject_file=SUBJECT)
    assert not (tmp_path / "cal.toml").exists()


def test_a_motionless_walking_trial_has_no_gait_events(trials):
    _, static = trials
    run = run_angles(static, static=static, subject_file=SUBJECT, model="cgm1.0")
    assert run.events == [] and run.event_source.startswith("none detected: the trial is motionless")
    assert any(n.startswith("gait events none detected: the trial is motionless") for n in messages(run.notes))


def test_the_cli_refuses_metres_in_one_line(trials, tmp_path):
    walking, _ = trials
    write_c3d(walking.with_markers(walking.markers / 1000), tmp_path / "metres.c3d")
    out = tmp_path / "a.csv"
    result = run_here("angles", tmp_path / "metres.c3d", "--subject", SUBJECT, "--out", out)
    assert_one_line_error(result, "metres.c3d: marker distances are about 1000 times too small", "metres")
    assert not out.exists()


@pytest.mark.slow
def test_the_cli_refuses_absurd_rates_in_one_line(trials, tmp_path):
    walking, _ = trials
    out = tmp_path / "a.csv"
    for rate in (1e6, 4e-23):
        write_c3d(replace(walking, rate=rate), tmp_path / "rate.c3d")
        result = run_here("angles", tmp_path / "rate.c3d", "--subject", SUBJECT, "--out", out)
        assert_one_line_error(result, f"rate.c3d: point rate {rate:g} Hz is implausible")
    assert not out.exists()


@needs_shared
@pytest.mark.slow
def test_the_cli_on_the_real_trial_with_a_spike_and_as_static(tmp_path):
    """The fault campaign's cases on Movement_trial.c3d, from the command line."""
    walking = read_c3d(VICON / "Movement_trial.c3d")
    spiked = _with(walking, "LKNE", lambda m: m.__setitem__((150, 0), 1e30))
    write_c3d(spiked, tmp_path / "spike.c3d")
    clean_csv, spike_csv = tmp_path / "clean.csv", tmp_path / "spike.csv"
    static = VICON / "Static_trial.c3d"
    assert run("angles", VICON / "Movement_trial.c3d", "--static", static, "--out", clean_csv).returncode == 0
    result = run("angles", tmp_path / "spike.c3d", "--static", static, "--out", spike_csv)
    assert result.returncode == 0
    assert "note: LKNE: 1 implausible sample blanked (frame 845:" in result.stdout
    import pandas as pd

    a, b = pd.read_csv(clean_csv), pd.read_csv(spike_csv)
    angles = [c for c in a.columns if c[-2:] in ("_X", "_Y", "_Z") and "Angle" in c]  # spike.c3d has no plates
    assert np.nanmax(np.abs(a[angles].to_numpy() - b[angles].to_numpy())) < 1e-3
    result = run_here("angles", VICON / "Movement_trial.c3d", "--static", VICON / "Movement_trial.c3d", "--out", clean_csv)
    assert_one_line_error(result, "Movement_trial.c3d: given as the static trial but it moves (pelvis 1638 mm")


def test_preprocess_blanks_a_spike_before_the_filter(trials, tmp_path):
    from fuzzygait.workflows.angles import Preprocessing, preprocess_file

    walking, _ = trials
    write_c3d(_with(walking, "LKNE", lambda m: m.__setitem__((200, 0), 1e30)), tmp_path / "spike.c3d")
    checked, gaps = preprocess_file(tmp_path / "spike.c3d", tmp_path / "clean.c3d", Preprocessing(labelled_only=False))
    assert checked.notes[-1].message.startswith("LKNE: 1 implausible sample blanked (frame 201:")
    assert [(g.marker, g.start, g.filled) for g in gaps] == [("LKNE", 200, True)]
    reference, _ = Preprocessing(labelled_only=False).apply(walking)
    np.testing.assert_allclose(read_c3d(tmp_path / "clean.c3d").marker("LKNE"), reference.marker("LKNE"), atol=0.01)


@needs_shared
def test_the_campaign_spike_on_the_real_trial(monkeypatch):
    """One LKNE coordinate of 1e30 in Movement_trial.c3d: the angles equal the clean
    trial's within 1e-4 deg (1e-6 deg 20 frames away); without the check they were off
    by more than 90 deg."""
    import fuzzygait.workflows.angles as workflow

    walking, static = read_c3d(VICON / "Movement_trial.c3d"), read_c3d(VICON / "Static_trial.c3d")
    clean = run_angles(walking, static=static)
    spiked = _with(walking, "LKNE", lambda m: m.__setitem__((150, 0), 1e30))
    run = run_angles(spiked, static=static)
    far = np.r_[0:130, 171:walking.n_frames]
    for name, values in clean.result.angles.items():
        np.testing.assert_allclose(run.result.angles[name], values, atol=1e-4, err_msg=name)
        np.testing.assert_allclose(run.result.angles[name][far], values[far], atol=1e-6, err_msg=name)
    monkeypatch.setattr(workflow, "check_trial", lambda trial, static=False: trial)
    unchecked = run_angles(spiked, static=static)
    assert np.nanmax(np.abs(unchecked.result.angles["LKneeAngles"] - clean.result.angles["LKneeAngles"])) > 90
