"""Bad input to the marker-error API gets one clear fuzzygait error naming the offending
argument (audit items 1, 2, 10, 11, 12); good input keeps working."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject
from fuzzygait.markererror.comparison import random_deviation_curves
from fuzzygait.markererror.result import (
    AngleAxes,
    component_deviation,
    component_hull,
    component_undetermined,
    fuzzy_angles_dataset,
)
from fuzzygait.markererror.sources import TABLE_3_1, ErrorModel
from support import TwoMarkerLine

ALPHAS = np.array([0.0, 0.5, 1.0])


def knee_dataset() -> xr.Dataset:
    """One component (LKneeAngles_X) on 3 frames, with deviations, of trial walk.c3d."""
    hull = np.stack([np.stack([np.full(3, -1.0 + a), np.full(3, 1.0 - a)]) for a in ALPHAS])
    axes = AngleAxes(alphas=ALPHAS, frames=[1, 2, 3], times=[0.0, 0.01, 0.02], markers=["LKNE"], ball_radius=[10.0])
    deviation = np.zeros((ALPHAS.size, 2, 3, 1))
    return fuzzy_angles_dataset({"LKneeAngles_X": hull}, axes, deviations={"LKneeAngles_X": deviation},
                                attrs={"trial": "walk.c3d"})  # fmt: skip


# ------------------------------------------------------------------ 1: unknown component
@pytest.mark.parametrize("read", [component_hull, component_undetermined, component_deviation])
def test_an_unknown_component_names_it_and_the_held_ones(read) -> None:
    fuzzy = knee_dataset()
    with pytest.raises(ParameterError, match=r"'RKneeAngles_X' is not in the dataset of walk\.c3d.*LKneeAngles_X"):
        read(fuzzy, "RKneeAngles_X")
    assert read(fuzzy, "LKneeAngles_X").sizes["alpha"] == ALPHAS.size


# ------------------------------------------------------------------ 2: the accessor's α
def test_the_accessor_refuses_an_alpha_it_does_not_hold_as_band_does() -> None:
    fuzzy = knee_dataset()
    with pytest.raises(ParameterError, match=r"α = 0\.3 is not among the result's α-levels \[0\.0, 0\.5, 1\.0\]"):
        fuzzy.fuzzy.undetermined(0.3)
    with pytest.raises(ParameterError, match=r"α = 0\.3 is not among"):
        fuzzy.fuzzy.band(0.3)
    assert not fuzzy.fuzzy.undetermined(0.5, component="LKneeAngles_X").any()


# ------------------------------------------------------------------ 10: JointAngleModel
def _angle_model(run, name: str = "LKneeAngles", axis: int = 0, frames=None) -> JointAngleModel:
    frames = np.arange(3) if frames is None else frames
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis,
                           frames)  # fmt: skip


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        ({"name": "LKneeAngle"}, r"unknown angle 'LKneeAngle'; give one of .*LKneeAngles"),
        ({"axis": 3}, r"axis must be 0, 1 or 2 .*got 3"),
        ({"axis": True}, r"axis must be 0, 1 or 2"),
        ({"frames": "past the end"}, r"frames must be whole 0-based sample indices of .*walking.*\((\d+) frames\)"),
        ({"frames": np.array([-1, 0])}, r"frames must be .*got \[-1\]"),
        ({"frames": np.array([0.5])}, r"frames must be .*got \[0\.5\]"),
    ],
)
def test_the_angle_model_refuses_bad_arguments(angles_run, change, needle) -> None:
    if isinstance(change.get("frames"), str):
        change = {"frames": np.array([0, angles_run.trial.n_frames])}
    with pytest.raises(ParameterError, match=needle):
        _angle_model(angles_run, **change)


def test_the_angle_model_takes_good_arguments(angles_run) -> None:
    model = _angle_model(angles_run, "LKneeAngles", 2, np.array([0, angles_run.trial.n_frames - 1]))
    assert model.measured_angles().shape == (2, 3)


# ------------------------------------------------------------------ 11: n_curves
@pytest.mark.parametrize("n_curves", [0, -1, 1.5])
def test_random_curves_refuse_a_count_below_one(n_curves) -> None:
    model = TwoMarkerLine(n=5)
    model.markers = ["A", "B"]
    with pytest.raises(ParameterError, match=rf"n_curves must be a whole number >= 1; got {n_curves}"):
        random_deviation_curves(model, [1.0, 1.0], n_curves)
    assert random_deviation_curves(model, [1.0, 1.0], 2).shape == (2, 5)


# ------------------------------------------------------------------ 12: ErrorModel
@pytest.mark.parametrize(
    ("segments", "needle"),
    [
        ({**TABLE_3_1, "thigh": {"measurement": -2.0, "placement": 10.0, "sta": 20.0}},
         r"\[segments\.thigh\] measurement = -2\.0 must be a distance in mm"),
        ({**TABLE_3_1, "thigh": {"measurement": float("nan"), "placement": 10.0, "sta": 20.0}},
         r"\[segments\.thigh\] measurement = nan must be a distance in mm"),
        ({**TABLE_3_1, "thigh": {"measurement": 2.0}}, r"\[segments\.thigh\] lacks placement, sta"),
        ({"thigh": {"measurement": 2.0, "placement": 10.0, "sta": 20.0}}, r"segments must give every segment pelvis"),
    ],
)  # fmt: skip
def test_an_error_model_checks_its_segments_when_made(segments, needle) -> None:
    with pytest.raises(ParameterError, match=needle):
        ErrorModel(segments=segments)


def test_an_error_model_checks_its_marker_sizes_when_made() -> None:
    with pytest.raises(ParameterError, match=r"\[markers\.LKNE\] radius = -1\.0 must be a distance"):
        ErrorModel(marker_radius={"LKNE": -1.0})
    with pytest.raises(ParameterError, match=r"\[markers\.LKNE\] sta = inf must be a distance"):
        ErrorModel(marker_sources={"LKNE": {"sta": float("inf")}})
    good = ErrorModel(segments={**TABLE_3_1, "thigh": {"measurement": 1.0, "placement": 2.0, "sta": 3.0}},
                      marker_radius={"LKNE": 5.0})  # fmt: skip
    assert good.radius("LTHI") == 6.0 and good.radius("LKNE") == 5.0

