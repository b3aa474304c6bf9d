"""Normative data and the Gait Profile Score (:mod:`fuzzygait.gait.normative`): GVS/GPS
against hand-computed RMS on made-up curves, the file format, and a trial scored against
normative data built from itself."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support import SAMPLE_DATA

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.gait.normative import (
    GPS_VARIABLES,
    NormativeData,
    build_normative,
    gait_profile,
    gait_variable_score,
    mean_curves,
    normalised_cycles,
    read_normative,
    write_normative,
)
from fuzzygait.workflows.angles import run_angles

PERCENT = np.linspace(0.0, 100.0, 101)


def _hand_rms(a: np.ndarray, b: np.ndarray) -> float:
    """RMS of a - b at 0, 2, ..., 100 %, written out as a loop."""
    total, n = 0.0, 0
    for p in range(0, 101, 2):
        total += (a[p] - b[p]) ** 2
        n += 1
    return math.sqrt(total / n)


def _curves(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    out = {}
    for side in "LR":
        for base in ("PelvisAngles", "HipAngles", "KneeAngles", "AnkleAngles", "FootProgressAngles"):
            for axis in "XYZ":
                amp, phase, off = rng.uniform(1, 20), rng.uniform(0, 6), rng.uniform(-10, 10)
                out[f"{side}{base}_{axis}"] = off + amp * np.sin(2 * np.pi * PERCENT / 100 + phase)
    return out


def test_gvs_is_the_rms_difference_every_two_percent() -> None:
    a, b = _curves(1)["LKneeAngles_X"], _curves(2)["LKneeAngles_X"]
    assert gait_variable_score(a, b) == pytest.approx(_hand_rms(a, b), rel=1e-12)
    assert gait_variable_score(a + 3.0, a) == pytest.approx(3.0, rel=1e-12)  # a constant offset
    b_odd = b.copy()
    b_odd[1::2] += 100.0  # the odd percentages are not sampled
    assert gait_variable_score(a, b_odd) == pytest.approx(_hand_rms(a, b), rel=1e-12)
    a_gap = a.copy()
    a_gap[50] = np.nan
    assert math.isnan(gait_variable_score(a_gap, b))


def test_gps_map_and_overall_gps_by_hand() -> None:
    trial, reference = _curves(3), _curves(4)
    normative = NormativeData({k: (v, np.ones(101)) for k, v in reference.items()}, source="made up")
    profile = gait_profile(trial, normative)
    names = [name for _, _, name in GPS_VARIABLES]
    gvs = {side: [_hand_rms(trial[f"{side}{b}_{a}"], reference[f"{side}{b}_{a}"]) for b, a, _ in GPS_VARIABLES]
           for side in "LR"}  # fmt: skip
    for side in "LR":
        assert [profile.gvs[side][n] for n in names] == pytest.approx(gvs[side], rel=1e-12)  # MAP = GVS
        assert profile.gps[side] == pytest.approx(math.sqrt(sum(g * g for g in gvs[side]) / 9), rel=1e-12)
    fifteen = gvs["L"] + gvs["R"][3:]  # the pelvis counted once, from the left
    assert profile.overall == pytest.approx(math.sqrt(sum(g * g for g in fifteen) / 15), rel=1e-12)
    table = profile.table()
    assert list(table.index) == [*names, "GPS"]
    assert table.loc["Knee flexion", "R"] == pytest.approx(gvs["R"][6], rel=1e-12)


def test_pooled_curves_serve_both_sides_and_sided_ones_win() -> None:
    pooled, left = np.zeros(101), np.ones(101)
    data = NormativeData({"KneeAngles_X": (pooled, left), "LKneeAngles_X": (left, left)})
    assert data.curve("RKneeAngles_X")[0] is pooled  # type: ignore[index]
    assert data.curve("LKneeAngles_X")[0] is left  # type: ignore[index]
    assert data.curve("LHipAngles_X") is None


def test_build_pools_every_cycle_of_every_trial() -> None:
    rng = np.random.default_rng(5)
    a = {"LKneeAngles_X": rng.normal(size=(3, 101)), "RKneeAngles_X": rng.normal(size=(2, 101))}
    b = {"LKneeAngles_X": rng.normal(size=(4, 101))}
    pooled = build_normative([a, b])
    stack = np.concatenate([a["LKneeAngles_X"], a["RKneeAngles_X"], b["LKneeAngles_X"]])
    mean, sd = pooled.curves["KneeAngles_X"]
    np.testing.assert_allclose(mean, stack.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(sd, stack.std(axis=0, ddof=1), rtol=1e-12)
    assert pooled.cycles["KneeAngles_X"] == 9
    sided = build_normative([a, b], per_side=True)
    assert sorted(sided.curves) == ["LKneeAngles_X", "RKneeAngles_X"] and sided.cycles["LKneeAngles_X"] == 7


def test_file_round_trip_is_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(6)
    data = build_normative([{"LKneeAngles_X": rng.normal(size=(3, 101)) * 20,
                             "LHipAngles_Y": rng.normal(size=(3, 101))}])  # fmt: skip
    back = read_normative(write_normative(data, tmp_path / "norm.csv"))
    assert list(back.curves) == list(data.curves)
    for name, (mean, sd) in data.curves.items():
        assert np.array_equal(back.curves[name][0], mean) and np.array_equal(back.curves[name][1], sd)
        assert back.cycles[name] == 3
    assert not list(tmp_path.glob(".*tmp"))


def test_coarse_grid_is_interpolated(tmp_path: Path) -> None:
    path = tmp_path / "coarse.csv"
    path.write_text("variable,percent,mean,sd\nKneeAngles_X,100,20,2\nKneeAngles_X,0,0,0\nKneeAngles_X,50,60,4\n")
    mean, sd = read_normative(path).curves["KneeAngles_X"]
    assert mean[25] == pytest.approx(30.0) and mean[75] == pytest.approx(40.0) and sd[50] == pytest.approx(4.0)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("variable,percent,mean\nKneeAngles_X,0,1\n", "missing column(s) sd"),
        ("variable,percent,mean,sd\nKneeAngles_X,0,1,1\nKneeAngles_X,90,1,1\n", "from 0 to 100"),
        ("variable,percent,mean,sd\nKneeAngles_X,0,1,-1\nKneeAngles_X,100,1,1\n", "sd must be >= 0"),
        ("variable,percent,mean,sd\nKneeAngles_X,0,one,1\nKneeAngles_X,100,1,1\n", "line 2: mean is not a number"),
        ("variable,percent,mean,sd\nKneeAngles_X,0,1,1\nKneeAngles_X,0,1,1\nKneeAngles_X,100,1,1\n", "twice"),
    ],
)
def test_bad_files_give_one_line(tmp_path: Path, text: str, needle: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(FuzzyGaitError) as info:
        read_normative(path)
    message = str(info.value)
    assert "\n" not in message and str(path) in message and needle in message
    with pytest.raises(FuzzyGaitError, match="no such normative file"):
        read_normative(tmp_path / "absent.csv")


@pytest.fixture(scope="module")
def walking_run():
    return run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


def test_gps_of_a_trial_against_itself_is_zero(walking_run, tmp_path: Path) -> None:
    cycles = normalised_cycles(walking_run.result.angles, walking_run.trial, walking_run.events)
    assert all(stack.shape == (4, 101) for stack in cycles.values())
    path = write_normative(build_normative([cycles], per_side=True, source="self"), tmp_path / "self.csv")
    profile = gait_profile(mean_curves(cycles), read_normative(path))
    assert profile.overall == 0.0 and profile.gps == {"L": 0.0, "R": 0.0}
    assert all(v == 0.0 for side in "LR" for v in profile.gvs[side].values())
    # against another trial's data it is not 0, and it equals the hand RMS
    noisy = run_angles(SAMPLE_DATA / "walking_noisy.c3d", static=SAMPLE_DATA / "static.c3d",
                       subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip
    other = mean_curves(normalised_cycles(noisy.result.angles, noisy.trial, noisy.events))
    profile = gait_profile(other, read_normative(path))
    own = mean_curves(cycles)
    assert profile.gvs["L"]["Knee flexion"] == pytest.approx(_hand_rms(other["LKneeAngles_X"], own["LKneeAngles_X"]))
    assert profile.overall > 0
