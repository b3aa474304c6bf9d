"""``fuzzygait angles`` and ``fuzzygait demo`` end to end (subprocess, as users run them)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support import SAMPLE_DATA, assert_one_line_error, needs_shared, run, run_here, shared_file

from fuzzygait.io import read_c3d, write_c3d

ANGLES = [f"{s}{a}" for a in ("PelvisAngles", "HipAngles", "KneeAngles", "AnkleAngles", "FootProgressAngles") for s in "LR"]
SAMPLE_ARGS = ("--static", SAMPLE_DATA / "static.c3d", "--subject", SAMPLE_DATA / "subject.toml")


def test_angles_csv_recovers_the_synthetic_truth(tmp_path: Path) -> None:
    out = tmp_path / "angles.csv"
    result = run("angles", SAMPLE_DATA / "walking.c3d", *SAMPLE_ARGS, "--no-filter", "--out", out)
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out)
    expected = ["frame", "time"] + [f"{a}_{x}" for a in ANGLES for x in "XYZ"]
    kinetic = list(table.columns[len(expected) : -1])  # the sample stands on force plates: Nexus' kinetic names
    assert sorted(table.columns[: len(expected)]) == sorted(expected)
    assert "LKneeMoment_X" in kinetic and "RAnklePower_Z" in kinetic and len(kinetic) == 2 * (3 * 3 * 2 + 3 + 3 * 2)
    assert table.columns[-1] == "model" and set(table["model"]) == {"cgm1.0"}  # the auto choice, named
    truth = pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv")
    merged = table.merge(truth, on="frame", suffixes=("", "_truth"))
    assert len(merged) == len(truth)
    compared = [c for c in truth.columns if c not in ("frame", "time_s")]
    assert len(compared) >= 24
    for column in compared:
        diff = np.abs(merged[column] - merged[f"{column}_truth"])
        assert diff.max() <= 0.01, (column, diff.max())


def test_angles_parquet_cycles_and_c3d_outputs(tmp_path: Path) -> None:
    result = run(
        "angles", SAMPLE_DATA / "walking_noisy.c3d", *SAMPLE_ARGS,
        "--out", tmp_path / "a.parquet", "--cycles", tmp_path / "c.csv", "--c3d-out", tmp_path / "m.c3d",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    table = pd.read_parquet(tmp_path / "a.parquet")
    assert table.shape[0] == read_c3d(SAMPLE_DATA / "walking_noisy.c3d").n_frames
    cycles = pd.read_csv(tmp_path / "c.csv")
    assert {"angle", "percent", "mean", "sd", "n_cycles"} <= set(cycles.columns)
    knee = cycles[cycles["angle"] == "LKneeAngles_X"]
    assert len(knee) == 101 and knee["n_cycles"].max() >= 3
    assert 50 < knee["mean"].max() < 70  # swing-phase knee flexion of the synthetic gait
    model = read_c3d(tmp_path / "m.c3d")
    assert model.output_kinds["LKneeAngles"] == "angle"
    np.testing.assert_allclose(model.outputs["LKneeAngles"][:, 0], table["LKneeAngles_X"], atol=1e-3)
    assert "LFEO" in model.outputs and "LStaticPlantFlex" in model.parameters
    assert len(model.events) >= 6


def test_missing_marker_names_it_and_keeps_the_other_angles(tmp_path: Path) -> None:
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    without = trial.select_markers([m for m in trial.marker_labels if m != "LKNE"])
    write_c3d(without, tmp_path / "no_lkne.c3d")
    out = tmp_path / "angles.csv"
    result = run("angles", tmp_path / "no_lkne.c3d", *SAMPLE_ARGS, "--out", out)
    assert result.returncode == 0, result.stderr
    assert "LKNE" in result.stdout and "LKneeAngles" in result.stdout
    table = pd.read_csv(out)
    assert table["LKneeAngles_X"].isna().all()
    for name in ("RKneeAngles", "RHipAngles", "LPelvisAngles", "RAnkleAngles"):
        assert table[f"{name}_X"].notna().all(), name


def test_implausible_subject_is_one_line(tmp_path: Path) -> None:
    text = (SAMPLE_DATA / "subject.toml").read_text().replace("LLegLength = 900.0", "LLegLength = 0.9")
    (tmp_path / "s.toml").write_text(text)
    out = tmp_path / "a.csv"
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", "--subject", tmp_path / "s.toml", "--out", out)
    assert_one_line_error(result, "LLegLength", "mm")
    assert not out.exists()


def test_bad_output_suffix_is_refused_before_work(tmp_path: Path) -> None:
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "a.xlsx")
    assert_one_line_error(result, "a.xlsx", ".csv or .parquet")


@needs_shared
def test_angles_match_vicon_on_movement_trial(tmp_path: Path) -> None:
    """Acceptance through the CLI: --no-filter, PROCESSING parameters."""
    source = shared_file("vicon", "Movement_trial.c3d")
    out = tmp_path / "angles.csv"
    result = run("angles", source, "--no-filter", "--out", out)
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out)
    vicon = read_c3d(source).outputs
    for name in ANGLES:
        for k, axis in enumerate("XYZ"):
            ours = table[f"{name}_{axis}"].to_numpy()
            theirs = vicon[name][:, k]
            both = np.isfinite(ours) & np.isfinite(theirs)
            assert both.sum() > 250, name
            diff = ours[both] - theirs[both]
            assert np.sqrt(np.mean(diff**2)) <= 0.001 and np.abs(diff).max() <= 0.01, (name, axis)


@pytest.mark.slow
def test_demo_writes_results(tmp_path: Path) -> None:
    out = tmp_path / "demo"
    result = run("demo", "--out", out)
    assert result.returncode == 0, result.stderr
    for name in ("angles.csv", "cycles.csv", "gait_cycles.png", "summary.md"):
        assert (out / name).is_file(), name
    assert (out / "gait_cycles.png").stat().st_size > 20_000
    summary = (out / "summary.md").read_text()
    assert "| LKneeAngles_X |" in summary
    assert "ΔΦ" in summary
    # how far to trust the knee angles leads; the accuracy against the truth follows
    assert summary.index("known within ±2.5°") < summary.index("ΔΦ") < summary.index("against the known truth")
    assert "| LKneeAngles | " in summary.split("against the known truth")[1]
    index = (out / "report" / "index.html").read_text()
    assert "walking_noisy" in index and "OK" in index
    # the session report of the synthetic session: both walking trials, their summary
    session = (out / "session" / "session.html").read_text(encoding="utf-8")
    assert "walking.c3d" in session and "walking_noisy.c3d" in session and 'src="session_files/cycles.png"' in session
    assert (out / "session" / "session_files" / "cycles.png").is_file()
    assert (out / "session" / "walking.html").is_file() and (out / "session" / "walking_noisy.html").is_file()
    assert "Session report (walking.c3d and walking_noisy.c3d; angles and the kinetics of the cycles" in summary
    assert "The forces are synthetic" in summary and "| left | 1 | " in summary  # the sample trial stands on plates


def test_demo_generates_missing_sample_data(tmp_path: Path) -> None:
    """The demo's first step on an empty ``--data`` folder (the rest of the demo is
    test_demo_writes_results: the generated files are the bundled ones byte for byte,
    tests/synthetic/test_synthetic.py)."""
    import io

    from rich.console import Console

    from fuzzygait.workflows.demo import SAMPLE_FILES, _ensure_sample_data

    said = io.StringIO()
    _ensure_sample_data(tmp_path / "data", Console(file=said, width=400))
    assert f"sample data not found in {tmp_path / 'data'}; generating it" in said.getvalue()
    assert all((tmp_path / "data" / name).is_file() for name in SAMPLE_FILES)


@pytest.mark.parametrize("flag", ["--cycles", "--out"])
def test_table_options_check_suffix(tmp_path: Path, flag: str) -> None:
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", flag, tmp_path / "x.txt")
    assert_one_line_error(result, flag)


@pytest.mark.slow
def test_c3d_suffix_is_checked_before_work_and_applied(tmp_path: Path) -> None:
    walking = SAMPLE_DATA / "walking.c3d"
    assert_one_line_error(run_here("angles", walking, "--c3d-out", tmp_path / "m.c3d", "--suffix", "a b"), "--suffix")
    assert not list(tmp_path.iterdir())
    result = run("angles", walking, *SAMPLE_ARGS, "--model", "cgm1.0", "--c3d-out", tmp_path / "m.c3d",
                 "--suffix", "model")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "note: model cgm1.0 (given by name)" in result.stdout
    model = read_c3d(tmp_path / "m.c3d")
    assert model.output_kinds["LKneeAngles_CGM_1.0"] == "angle" and "LKneeAngles" not in model.outputs


@pytest.mark.slow
def test_knee_ankle_centre_rule_reaches_the_cluster_calibration(tmp_path: Path) -> None:
    """On the synthetic CGM 2.4 session the KNM/MED rule (default) and the chord put the
    knee centre where it is (both recover the truth); pyCGM2's THAP chord does not."""
    session = [SAMPLE_DATA / "cgm24_walking.c3d", "--static", SAMPLE_DATA / "cgm24_static.c3d", "--no-filter"]
    truth = pd.read_csv(SAMPLE_DATA / "cgm24_walking_truth_angles.csv")
    knee = {}
    for rule in ("medial", "chord", "pycgm2"):
        out = tmp_path / f"{rule}.csv"
        result = run("angles", *session, "--knee-ankle-centres", rule, "--out", out)
        assert result.returncode == 0, result.stderr
        assert "model cgm2.4" in result.stdout
        knee[rule] = pd.read_csv(out)["LKneeAngles_X"].to_numpy() - truth["LKneeAngles_X"].to_numpy()
    assert "pyCGM2 THAP/TIAP chord knee/ankle centres" in result.stdout
    assert np.abs(knee["medial"]).max() < 0.01 and np.abs(knee["chord"]).max() < 0.01
    assert np.abs(knee["pycgm2"]).max() > 0.5
    bad = run("angles", *session, "--knee-ankle-centres", "lateral")
    assert_one_line_error(bad, "--knee-ankle-centres 'lateral'", "medial, chord, pycgm2")
