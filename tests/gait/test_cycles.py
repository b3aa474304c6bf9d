"""Gait cycles and time normalisation against the synthetic walker's exact curves.

The synthetic gait is exactly periodic (stride 1.1 s, foot off at 60 %), so every
normalised cycle must equal the analytic Fourier curve of
:mod:`fuzzygait.synthetic.gait_curves` at the percent points.  Measured maximum errors of
the cubic-spline normalisation (all hip/knee/ankle components, both sides):
7.3e-5 deg at 100 Hz from ``walking.c3d`` (float32 event times) + the truth CSV,
2.7e-5 deg with float64 event times, 3.5e-4 deg at 50 Hz (linear interpolation: 0.043
and 0.18 deg).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from support import shared_file
from fuzzygait.core.errors import ParameterError
from fuzzygait.io import Trial, read_c3d
from fuzzygait.gait.cycles import (
    GaitCycle,
    cycle_statistics,
    gait_cycles,
    mean_sd_table,
    normalise_cycles,
    normalised_angle_table,
    percent_points,
)
from fuzzygait.synthetic import make_walking_trial
from fuzzygait.synthetic.gait_curves import FOOT_OFF_PHASE, STRIDE_TIME_S, joint_angle_curves

JOINTS = ("hip", "knee", "ankle")
TOL_100HZ = 2e-4  # deg, measured 7.3e-5
TOL_50HZ = 1e-3  # deg, measured 3.5e-4


def _angles(truth: pd.DataFrame, side: str, joint: str) -> np.ndarray:
    """``(n_frames, 3)`` deg: the truth CSV's ``{side}{Joint}Angles_X/Y/Z``."""
    return truth[[f"{side}{joint.capitalize()}Angles_{a}" for a in "XYZ"]].to_numpy()


def _exact(joint: str, n_points: int = 101) -> np.ndarray:
    """``(n_points, 3)`` analytic angles at the percent points (limb phase = percent)."""
    return joint_angle_curves(percent_points(n_points) / 100.0, joint)


# ----------------------------------------------------------------- cycles
@pytest.mark.parametrize("side, context", [("L", "Left"), ("R", "Right"), ("Left", "Left")])
def test_cycles_follow_the_foot_strikes(walking: Trial, side: str, context: str) -> None:
    cycles = gait_cycles(walking, walking.events, side)
    strikes = sorted(
        walking.event_index(e)
        for e in walking.events
        if e.label == "Foot Strike" and e.context == context
    )
    assert len(strikes) == 5 and len(cycles) == 4
    assert [c.index for c in cycles] == [0, 1, 2, 3]
    assert {c.side for c in cycles} == {context[0]}
    assert [c.start for c in cycles] == strikes[:-1]
    assert [c.end for c in cycles] == strikes[1:]
    for cycle in cycles:
        assert cycle.start < cycle.foot_off < cycle.end
        assert cycle.foot_off_percent == pytest.approx(100 * FOOT_OFF_PHASE, abs=1e-4)
        assert cycle.duration == pytest.approx(STRIDE_TIME_S, abs=1e-6)  # float32 times
        assert cycle.start_time == pytest.approx(
            (walking.first_frame + cycle.start - 1) / walking.rate, abs=1e-12
        )
        assert cycle.end_time - cycle.start_time == pytest.approx(cycle.duration)
        assert cycle.foot_off_time == pytest.approx(
            cycle.start_time + 0.6 * cycle.duration, abs=1e-6
        )


def test_cycle_without_foot_off_and_bad_input(walking: Trial) -> None:
    strikes_only = [e for e in walking.events if e.label == "Foot Strike"]
    cycles = gait_cycles(walking, strikes_only, "R")
    assert len(cycles) == 4
    assert all(c.foot_off is None and c.foot_off_percent is None for c in cycles)
    with pytest.raises(ParameterError, match="side"):
        gait_cycles(walking, walking.events, "X")
    with pytest.raises(ParameterError, match="end after"):
        GaitCycle("L", 0, start=10.0, end=10.0, rate=100.0)
    with pytest.raises(ParameterError, match="outside"):
        GaitCycle("L", 0, start=10.0, end=20.0, rate=100.0, foot_off=25.0)
    assert gait_cycles(walking, [], "L") == []


# ----------------------------------------------------------------- normalisation
def test_normalisation_equals_the_analytic_curves(walking: Trial, truth: pd.DataFrame) -> None:
    worst = 0.0
    for side in "LR":
        cycles = gait_cycles(walking, walking.events, side)
        for joint in JOINTS:
            normalised = normalise_cycles(_angles(truth, side, joint), cycles)
            assert normalised.shape == (4, 101, 3)
            error = np.abs(normalised - _exact(joint)).max()
            worst = max(worst, error)
            mean, sd = cycle_statistics(normalised)
            np.testing.assert_allclose(mean, _exact(joint), atol=TOL_100HZ, rtol=0)
            assert np.all(sd <= TOL_100HZ)
    assert worst <= TOL_100HZ
    assert worst > 1e-6  # the bound is measured, not trivially loose by orders


def test_normalisation_at_50_hz_and_linear_would_be_worse() -> None:
    trial, truth = make_walking_trial(rate=50.0)
    cycles = gait_cycles(trial, trial.events, "L")
    knee = _angles(truth, "L", "knee")
    spline_error = np.abs(normalise_cycles(knee, cycles) - _exact("knee")).max()
    assert spline_error <= TOL_50HZ
    positions = [c.start + percent_points() / 100 * (c.end - c.start) for c in cycles]
    linear = np.stack([np.interp(x, np.arange(len(knee)), knee[:, 0]) for x in positions])
    assert np.abs(linear - _exact("knee")[:, 0]).max() > 100 * spline_error


def test_n_points_and_trailing_shapes(walking: Trial, truth: pd.DataFrame) -> None:
    cycles = gait_cycles(walking, walking.events, "L")
    knee = _angles(truth, "L", "knee")
    normalised = normalise_cycles(knee, cycles, n_points=51)
    assert normalised.shape == (4, 51, 3)
    np.testing.assert_allclose(normalised[2], _exact("knee", 51), atol=TOL_100HZ, rtol=0)
    flexion = normalise_cycles(knee[:, 0], cycles, n_points=11)
    assert flexion.shape == (4, 11)
    np.testing.assert_array_equal(percent_points(11), np.arange(0, 101, 10))
    stacked = normalise_cycles(np.stack([knee, 2 * knee], axis=1), cycles)
    assert stacked.shape == (4, 101, 2, 3)
    np.testing.assert_allclose(stacked[:, :, 1], 2 * stacked[:, :, 0])
    for bad in (1, 0, 2.5, True):
        with pytest.raises(ParameterError, match="n_points"):
            normalise_cycles(knee, cycles, n_points=bad)
    with pytest.raises(ParameterError, match="frame axis"):
        normalise_cycles(np.float64(1.0), cycles)
    assert normalise_cycles(knee, [], n_points=101).shape == (0, 101, 3)


def test_nan_inside_a_cycle_excludes_only_that_cycle(
    walking: Trial, truth: pd.DataFrame
) -> None:
    cycles = gait_cycles(walking, walking.events, "R")
    knee = _angles(truth, "R", "knee").copy()
    knee[int(cycles[1].start) + 40, 0] = np.nan  # flexion only, inside cycle 1
    # a NaN just outside a cycle's span (in the spline margin) must not exclude it
    knee[int(np.floor(cycles[0].start)) - 1, 1] = np.nan
    normalised = normalise_cycles(knee, cycles)
    assert np.isnan(normalised[1, :, 0]).all()
    assert np.isfinite(normalised[1, :, 1:]).all()
    assert np.isfinite(np.delete(normalised, 1, axis=0)).all()
    np.testing.assert_allclose(normalised[0], _exact("knee"), atol=TOL_100HZ, rtol=0)
    mean, sd = cycle_statistics(normalised)
    np.testing.assert_allclose(mean, _exact("knee"), atol=TOL_100HZ, rtol=0)
    assert np.all(sd <= TOL_100HZ)
    # with fewer than 2 valid cycles the SD is NaN, with none the mean too
    one = normalised[:2].copy()
    one[0] = np.nan
    mean, sd = cycle_statistics(one)
    np.testing.assert_array_equal(mean[:, 1:], one[1, :, 1:])
    assert np.isnan(mean[:, 0]).all() and np.isnan(sd).all()


def test_sd_is_the_sample_sd() -> None:
    values = np.array([[1.0, 4.0], [3.0, np.nan], [5.0, 6.0]])[:, None, :]  # (3, 1, 2)
    mean, sd = cycle_statistics(values)
    np.testing.assert_allclose(mean, [[3.0, 5.0]])
    np.testing.assert_allclose(sd, [[2.0, np.sqrt(2.0)]])  # ddof=1


def test_cycle_outside_the_data_is_nan(walking: Trial, truth: pd.DataFrame) -> None:
    n = walking.n_frames
    cycles = [
        GaitCycle("L", 0, start=n - 50.0, end=n + 10.0, rate=walking.rate),
        GaitCycle("L", 1, start=-0.5, end=60.0, rate=walking.rate),
        GaitCycle("L", 2, start=0.0, end=n - 1.0, rate=walking.rate),
    ]
    normalised = normalise_cycles(_angles(truth, "L", "knee"), cycles)
    assert np.isnan(normalised[:2]).all() and np.isfinite(normalised[2]).all()


# ----------------------------------------------------------------- tables
def test_angle_tables(walking: Trial, truth: pd.DataFrame) -> None:
    names = {"LKneeAngles": ("L", "knee"), "RKneeAngles": ("R", "knee"),
             "LHipAngles": ("L", "hip")}
    angles = {name: _angles(truth, side, joint) for name, (side, joint) in names.items()}
    angles["RKneeAngles"][200, :] = np.nan  # inside right cycle 1 (frames 176-286)
    table = normalised_angle_table(angles, walking, walking.events)
    assert list(table.columns) == ["angle", "side", "cycle", "percent", "value"]
    assert len(table) == 3 * 3 * 4 * 101
    assert list(table["angle"].unique()) == [
        f"{name}_{axis}" for name in names for axis in "XYZ"
    ]
    assert set(table.loc[table.angle.str.startswith("R"), "side"]) == {"R"}
    assert set(table["cycle"]) == {0, 1, 2, 3}
    np.testing.assert_array_equal(np.sort(table["percent"].unique()), np.arange(101.0))
    rows = table[(table.angle == "LKneeAngles_X") & (table.cycle == 2)]
    np.testing.assert_allclose(rows["value"], _exact("knee")[:, 0], atol=TOL_100HZ)
    excluded = (table.angle == "RKneeAngles_Y") & (table.cycle == 1)
    assert table.loc[excluded, "value"].isna().all()

    summary = mean_sd_table(table)
    assert list(summary.columns) == ["angle", "percent", "mean", "sd", "n_cycles"]
    assert len(summary) == 9 * 101
    counts = summary.groupby("angle", sort=False)["n_cycles"].unique()
    assert counts["LKneeAngles_X"].tolist() == [4] and counts["RKneeAngles_Z"].tolist() == [3]
    for name, (_, joint) in names.items():
        for j, axis in enumerate("XYZ"):
            rows = summary[summary.angle == f"{name}_{axis}"]
            np.testing.assert_allclose(rows["percent"], np.arange(101.0))
            np.testing.assert_allclose(rows["mean"], _exact(joint)[:, j], atol=TOL_100HZ)
            assert rows["sd"].max() <= TOL_100HZ

    small = normalised_angle_table({"LKneeAngles": angles["LKneeAngles"][:, 0]}, walking,
                                   walking.events, n_points=21)
    assert set(small["angle"]) == {"LKneeAngles"} and len(small) == 4 * 21
    empty = normalised_angle_table({}, walking, walking.events)
    assert list(empty.columns) == list(table.columns) and empty.empty
    assert list(mean_sd_table(empty).columns) == list(summary.columns)


def test_angle_table_errors(walking: Trial, truth: pd.DataFrame) -> None:
    knee = _angles(truth, "L", "knee")
    with pytest.raises(ParameterError, match="start with L or R"):
        normalised_angle_table({"KneeAngles": knee}, walking, walking.events)
    with pytest.raises(ParameterError, match="512 frames"):
        normalised_angle_table({"LKneeAngles": knee[:-1]}, walking, walking.events)


def test_gait_pig_outputs_with_an_excluded_cycle() -> None:
    """Real Plug-in Gait outputs: the ASIS vanish from frame 115, so the angles are NaN
    there and the second left cycle (frames 77-125) is excluded."""
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    angles = {k: v for k, v in trial.outputs.items() if k in ("LKneeAngles", "RKneeAngles")}
    summary = mean_sd_table(normalised_angle_table(angles, trial, trial.events))
    for angle, cycles in (("LKneeAngles_X", 1), ("RKneeAngles_X", 1)):
        rows = summary[summary.angle == angle]
        assert rows["n_cycles"].unique().tolist() == [cycles]
        assert rows["sd"].isna().all()
        peak = rows.loc[rows["mean"].idxmax()]
        assert 50.0 <= peak["mean"] <= 70.0 and 65.0 <= peak["percent"] <= 80.0  # swing
        assert abs(rows["mean"].iloc[0]) < 10.0  # knee nearly straight at foot strike
