"""``fuzzygait normative``: a lab's normative file from reference trials."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzygait.core.names import Side
from fuzzygait.gait.cycles import gait_cycles, normalise_cycles
from fuzzygait.gait.normative import build_normative, normalised_cycles, read_normative
from fuzzygait.workflows.angles import run_angles
from support import SAMPLE_DATA, assert_one_line_error, needs_shared, run, run_here, shared_file


def test_normative_from_a_trial(tmp_path: Path) -> None:
    out = tmp_path / "norm.csv"
    result = run("normative", SAMPLE_DATA / "walking.c3d", "--static", SAMPLE_DATA / "static.c3d",
                 "--subject", SAMPLE_DATA / "subject.toml", "--out", out, "--per-side")  # fmt: skip
    assert result.returncode == 0, result.stderr
    # the sample walking trial stands on two force plates: its kinetics join the angles
    assert "30 angle components and 30 kinetic components from 1 trial" in result.stdout
    data = read_normative(out)
    angles = run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                        subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    expected = build_normative([normalised_cycles(angles.result.angles, angles.trial, angles.events)], per_side=True)
    assert list(data.curves)[: len(expected.curves)] == list(expected.curves)
    assert "LKneeMoment_X" in data.curves and "RAnklePower_Z" in data.curves and len(data.curves) == 60
    for name, (mean, sd) in expected.curves.items():
        assert np.array_equal(data.curves[name][0], mean) and np.array_equal(data.curves[name][1], sd)


def test_normative_errors_are_one_line(tmp_path: Path) -> None:
    assert_one_line_error(run_here("normative", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "n.txt"), ".csv")
    missing = run("normative", tmp_path / "absent.c3d", "--out", tmp_path / "n.csv")
    assert_one_line_error(missing, "absent.c3d")
    assert not (tmp_path / "n.csv").exists()


@needs_shared
def test_normative_kinetics_from_a_trial_with_force_plates(tmp_path: Path) -> None:
    path = shared_file("vicon", "Movement_trial.c3d")
    out = tmp_path / "norm.csv"
    result = run("normative", path, "--out", out)
    assert result.returncode == 0, result.stderr
    assert "15 angle components and 15 kinetic components from 1 trial" in result.stdout
    data = read_normative(out)
    angles = run_angles(path)
    assert angles.kinetics is not None
    moment = angles.kinetics.data["moment"].sel(joint="Knee", axis="X")  # N·m/kg
    # the cycles whose mid-stance (20, 30, 40 %) lies in a contact the side's foot was given
    stacks = []
    for side in Side:
        used = [c for c in angles.kinetics.contacts if c.side is side]
        cycles = [c for c in gait_cycles(angles.trial, angles.events, side.value)
                  if all(any(u.first <= round(c.start + p / 100 * (c.end - c.start)) <= u.last for u in used)
                         for p in (20, 30, 40))]  # fmt: skip
        stacks.append(normalise_cycles(moment.sel(side=side.value).values, cycles, 101))
    pooled = np.concatenate(stacks)
    assert pooled.shape == (3, 101)
    mean, sd = data.curve("LKneeMoment_X")
    np.testing.assert_allclose(mean, pooled.mean(axis=0), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sd, pooled.std(axis=0, ddof=1), rtol=1e-9, atol=1e-12)
    assert data.cycles["KneeMoment_X"] == 3 and data.curve("RAnklePower_Z") is not None
