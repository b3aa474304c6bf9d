"""``fuzzygait gait-parameters`` as a user runs it: one row per trial and side, units in
the header, Nexus' values reproduced, a failing trial reported by one line while the
others are written."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from support import SAMPLE_DATA, assert_one_line_error, needs_shared, run, run_here, shared_file

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.options import use_command_line_names
from fuzzygait.gait.spatiotemporal import NAMES, agreement_tolerance, column_name, nexus_reference
from fuzzygait.io import read_c3d
from fuzzygait.workflows.gait_parameters import gait_parameters_files


@needs_shared
def test_nexus_values_reproduced_and_a_bad_trial_reported(tmp_path: Path) -> None:
    nexus = shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d")
    static = shared_file("vicon", "Static_trial.c3d")  # no gait cycles
    out = tmp_path / "params.csv"
    result = run("gait-parameters", nexus, static, SAMPLE_DATA / "walking.c3d", "--out", out, "--cycles", "nexus")
    assert result.returncode == 1
    errors = [line for line in result.stderr.splitlines() if line.startswith("fuzzygait: error:")]
    assert len(errors) == 1 and "Static_trial.c3d" in errors[0] and "no complete gait cycle" in errors[0]
    assert "Traceback" not in result.stderr
    assert "Cadence (steps/min)" in result.stdout and str(out) in result.stdout

    table = pd.read_csv(out)
    assert list(table.columns[:3]) == ["trial", "side", "cycles"]
    assert len(table) == 4 and set(table["side"]) == {"Left", "Right"}
    trial = read_c3d(nexus)
    reference = nexus_reference(trial)
    for code, side in (("L", "Left"), ("R", "Right")):
        row = table[(table["trial"] == str(nexus)) & (table["side"] == side)].iloc[0]
        for name in NAMES:
            ours = row[column_name(name)]
            tol = agreement_tolerance(name, reference[code][name], trial.rate, row["Stride Time (s)"])
            assert abs(ours - reference[code][name]) <= tol, (side, name)
    synthetic = table[table["trial"].str.endswith("walking.c3d")]
    assert synthetic["Stride Length (m)"].to_numpy() == pytest.approx([1.375, 1.375], abs=1e-3)


@needs_shared
def test_workstation_values_reproduced_with_its_definitions(tmp_path: Path) -> None:
    gait_pig = shared_file("vicon", "gait-pig.c3d")
    out = tmp_path / "params.csv"
    result = run("gait-parameters", gait_pig, "--out", out, "--cycles", "workstation")
    assert result.returncode == 0, result.stderr
    assert "Vicon Workstation's definitions" in result.stdout
    table = pd.read_csv(out)
    trial = read_c3d(gait_pig)
    reference = nexus_reference(trial)
    for code, side in (("L", "Left"), ("R", "Right")):
        row = table[table["side"] == side].iloc[0]
        for name, value in reference[code].items():
            tol = agreement_tolerance(name, value, trial.rate, row["Stride Time (s)"])
            assert abs(row[column_name(name)] - value) <= tol, (side, name)


def test_mean_over_cycles(tmp_path: Path) -> None:
    out = tmp_path / "params.csv"
    result = run("gait-parameters", SAMPLE_DATA / "walking.c3d", "--out", out)
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out)
    assert table["cycles"].tolist() == [4, 4]
    assert table["Cadence (steps/min)"].to_numpy() == pytest.approx([120 / 1.1] * 2, rel=1e-6)
    assert "Cadence SD (steps/min)" in table


def test_every_trial_failing_is_one_line_and_no_output(tmp_path: Path) -> None:
    missing = tmp_path / "missing.csv"
    result = run_here("gait-parameters", tmp_path / "nope.c3d", "--out", missing)
    assert_one_line_error(result, "nope.c3d", "no such file")
    assert not missing.exists()


def test_bad_output_suffix_or_cycle_selection_before_any_trial_is_read(tmp_path: Path) -> None:
    # the library names the keywords; the command its options (fuzzygait.core.options)
    with pytest.raises(FuzzyGaitError, match=r"out= must end in \.csv or \.parquet"):
        gait_parameters_files([tmp_path / "nope.c3d"], tmp_path / "p.txt")
    with pytest.raises(FuzzyGaitError, match="cycles= must be one of all, nexus, workstation"):
        gait_parameters_files([tmp_path / "nope.c3d"], tmp_path / "p.csv", "median")
    use_command_line_names()
    with pytest.raises(FuzzyGaitError, match="--cycles must be one of all, nexus, workstation"):
        gait_parameters_files([tmp_path / "nope.c3d"], tmp_path / "p.csv", "median")
