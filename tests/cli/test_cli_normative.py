"""``fuzzygait normative``: a lab's normative file from reference trials."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from support import SAMPLE_DATA, assert_one_line_error, run, run_here

from fuzzygait.gait.normative import build_normative, normalised_cycles, read_normative
from fuzzygait.workflows.angles import run_angles


def test_normative_from_a_trial(tmp_path: Path) -> None:
    out = tmp_path / "norm.csv"
    result = run("normative", SAMPLE_DATA / "walking.c3d", "--static", SAMPLE_DATA / "static.c3d",
                 "--subject", SAMPLE_DATA / "subject.toml", "--out", out, "--per-side")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "30 angle components from 1 trial" in result.stdout
    data = read_normative(out)
    angles = run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                        subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    expected = build_normative([normalised_cycles(angles.result.angles, angles.trial, angles.events)], per_side=True)
    assert list(data.curves) == list(expected.curves)
    for name, (mean, sd) in expected.curves.items():
        assert np.array_equal(data.curves[name][0], mean) and np.array_equal(data.curves[name][1], sd)


def test_normative_errors_are_one_line(tmp_path: Path) -> None:
    assert_one_line_error(run_here("normative", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "n.txt"), ".csv")
    missing = run("normative", tmp_path / "absent.c3d", "--out", tmp_path / "n.csv")
    assert_one_line_error(missing, "absent.c3d")
    assert not (tmp_path / "n.csv").exists()
