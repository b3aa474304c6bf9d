"""Spatio-temporal parameters (issue 16) against hand-computed values of the synthetic
walker and against the values Vicon Nexus / Workstation stored in the reference files'
``ANALYSIS`` group (``benchmarks/RESULTS.md``, "Spatio-temporal parameters against Vicon
Nexus")."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from support import shared_file
from fuzzygait.core.errors import EventError, ParameterError
from fuzzygait.core.findings import messages
from fuzzygait.core.trial import AnalysisValue, Trial
from fuzzygait.gait.spatiotemporal import (
    NAMES,
    UNITS,
    agreement_tolerance,
    column_name,
    nexus_reference,
    parameters_table,
    reference_convention,
    side_parameters,
    spatiotemporal_parameters,
)
from fuzzygait.io import read_c3d
from fuzzygait.synthetic import make_walking_trial
from fuzzygait.synthetic.gait_curves import FOOT_OFF_PHASE, RIGHT_PHASE_SHIFT, STRIDE_TIME_S
from fuzzygait.synthetic.generate import WALKING_SPEED_MM_S


@pytest.fixture(scope="module")
def synthetic() -> Trial:
    trial, _ = make_walking_trial(n_cycles=3, rate=100.0)
    return trial


def _by_hand() -> dict[str, float]:
    """The walker's parameters from its definition: the pose is periodic in the gait
    phase on top of a constant forward speed v, so a foot advances v T per stride; the
    right limb repeats the left one mirrored half a cycle later, so a step is v T / 2.
    Opposite Foot Off is the other limb's Foot Off, (0.5 + 0.6) mod 1 = 0.1 of the cycle."""
    t = STRIDE_TIME_S
    opposite_off = (RIGHT_PHASE_SHIFT + FOOT_OFF_PHASE) % 1.0
    return {
        "Cadence": 2 * 60.0 / t,
        "Walking Speed": WALKING_SPEED_MM_S / 1000.0,
        "Stride Time": t,
        "Step Time": (1.0 - RIGHT_PHASE_SHIFT) * t,
        "Opposite Foot Off": 100.0 * opposite_off,
        "Opposite Foot Contact": 100.0 * RIGHT_PHASE_SHIFT,
        "Foot Off": 100.0 * FOOT_OFF_PHASE,
        "Single Support": (RIGHT_PHASE_SHIFT - opposite_off) * t,
        "Double Support": (opposite_off + FOOT_OFF_PHASE - RIGHT_PHASE_SHIFT) * t,
        "Stride Length": WALKING_SPEED_MM_S * t / 1000.0,
        "Step Length": WALKING_SPEED_MM_S * t / 2000.0,
    }


def _assert_close(name: str, ours: float, expected: float) -> None:
    if UNITS[name] == "m":
        assert abs(ours - expected) <= 1e-3, (name, ours, expected)  # <= 1 mm
    else:
        assert ours == pytest.approx(expected, rel=0.01), name


# ------------------------------------------------------------------ synthetic walker
def test_synthetic_walker_matches_the_hand_computed_values(synthetic: Trial) -> None:
    expected = _by_hand()
    result = spatiotemporal_parameters(synthetic)
    assert result.event_source == "file" and not result.notes
    for code in ("L", "R"):
        side = result.sides[code]
        assert len(side.cycles) == 3 and len(side.complete_cycles) == 3
        for cycle in side.cycles:
            for name in NAMES:
                _assert_close(name, cycle.values[name], expected[name])
        mean, sd = side.mean(), side.sd()
        for name in NAMES:
            _assert_close(name, mean[name], expected[name])
            assert sd[name] < 1e-6  # exactly periodic


def test_synthetic_walker_is_exact_to_rounding(synthetic: Trial) -> None:
    # events on frames and an exactly periodic walker: far inside the 1 % / 1 mm bound
    expected = _by_hand()
    for side in spatiotemporal_parameters(synthetic).sides.values():
        for name in NAMES:
            assert side.mean()[name] == pytest.approx(expected[name], rel=1e-9, abs=1e-9)


def test_table_has_a_row_per_side_and_units_in_the_header(synthetic: Trial) -> None:
    result = spatiotemporal_parameters(synthetic)
    table = parameters_table([result, replace(result, trial="again.c3d")])
    assert list(table[["trial", "side"]].itertuples(index=False, name=None)) == [
        (synthetic.name, "Left"), (synthetic.name, "Right"), ("again.c3d", "Left"), ("again.c3d", "Right")]  # fmt: skip
    assert "Cadence (steps/min)" in table and "Step Length SD (m)" in table
    assert "Opposite Foot Off (%)" in table and "Double Support (s)" in table
    assert (table["cycles"] == 3).all()
    first = parameters_table([result], "nexus")
    assert (first["cycles"] == 1).all() and first["Cadence SD (steps/min)"].isna().all()
    assert column_name("Walking Speed", "SD") == "Walking Speed SD (m/s)"
    with pytest.raises(ParameterError, match="nexus"):
        parameters_table([result], "median")


def test_a_cycle_without_the_opposite_foot_off_is_not_complete(synthetic: Trial) -> None:
    # drop the right Foot Off inside the second left cycle
    left = side_parameters(synthetic, synthetic.events, "L")
    start, end = left.cycles[1].start_time, left.cycles[1].end_time
    events = [e for e in synthetic.events
              if not (e.label == "Foot Off" and e.context == "Right" and start < e.time < end)]  # fmt: skip
    cut = side_parameters(synthetic, events, "L")
    assert [c.complete for c in cut.cycles] == [True, False, True]
    values = cut.cycles[1].values
    assert math.isnan(values["Opposite Foot Off"]) and math.isnan(values["Single Support"])
    assert values["Stride Time"] == pytest.approx(STRIDE_TIME_S)
    assert cut.mean()["Stride Time"] == pytest.approx(STRIDE_TIME_S)  # from the complete ones
    assert cut.first_complete is cut.cycles[0]


def test_no_complete_cycle_is_one_clear_error(synthetic: Trial) -> None:
    strikes = [e for e in synthetic.events if e.label == "Foot Strike"]
    with pytest.raises(EventError, match=r"no complete gait cycle.*add the missing events"):
        spatiotemporal_parameters(replace(synthetic, source=None), strikes)


def test_missing_toe_marker_gives_nan_lengths_and_a_note(synthetic: Trial) -> None:
    markers = synthetic.markers.copy()
    markers[:, synthetic.marker_labels.index("LTOE")] = np.nan
    result = spatiotemporal_parameters(synthetic.with_markers(markers))
    left = result.sides["L"].mean()
    assert math.isnan(left["Stride Length"]) and math.isnan(left["Walking Speed"])
    assert left["Cadence"] == pytest.approx(120 / STRIDE_TIME_S)
    assert any("LTOE missing" in note for note in messages(result.notes))
    # the right step length needs the left toe too
    assert math.isnan(result.sides["R"].mean()["Step Length"])


def test_agreement_tolerance_is_one_frame_or_one_percent() -> None:
    assert agreement_tolerance("Stride Time", 1.0, 100.0, 1.0) == pytest.approx(0.01)
    assert agreement_tolerance("Foot Off", 60.0, 50.0, 1.0) == pytest.approx(2.0)
    assert agreement_tolerance("Stride Length", 1.2, 100.0, 1.0) == pytest.approx(0.012)


def test_reference_units_of_both_vicon_generations_are_converted() -> None:
    def value(name: str, unit: str, number: float) -> AnalysisValue:
        return AnalysisValue(name, "Left", unit, number)

    trial = Trial(markers=np.zeros((2, 1, 3)), marker_labels=["X"], rate=50.0, analysis=[
        value("Cadence", "1/s", 1.0), value("Stride Time", "s", 1.0), value("Step Time", "%", 50.0),
        value("Single Support", "%", 40.0), value("Stride Length", "mm", 1300.0),
        value("Walking Speed", "mm/s", 1300.0), value("Foot Off", "%", 60.0),
        value("Step Length", "furlong", 1.0), value("Step Width", "mm", 100.0),
        AnalysisValue("Cadence", "Right", "steps/min", 110.0)])  # fmt: skip
    reference = nexus_reference(trial)
    assert reference["L"] == pytest.approx({"Cadence": 120.0, "Stride Time": 1.0, "Step Time": 0.5,
                                            "Single Support": 0.4, "Stride Length": 1.3,
                                            "Walking Speed": 1.3, "Foot Off": 60.0})  # fmt: skip
    assert reference["R"] == {"Cadence": 110.0}


# ------------------------------------------------------------------ Vicon reference files
def _within(trial: Trial, code: str, cycle_values: dict[str, float], names: tuple[str, ...]) -> None:
    reference = nexus_reference(trial)[code]
    for name in names:
        tol = agreement_tolerance(name, reference[name], trial.rate, cycle_values["Stride Time"])
        assert abs(cycle_values[name] - reference[name]) <= tol, (code, name, cycle_values[name], reference[name])


@pytest.mark.parametrize("code", ["L", "R"])
def test_nexus_flat_foot_session_every_parameter(code: str) -> None:
    trial = read_c3d(shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d"))
    side = spatiotemporal_parameters(trial).sides[code]
    first = side.first_complete
    assert first is not None and first.index == {"L": 0, "R": 1}[code]  # right cycle 0 lacks the left Foot Off
    reference = nexus_reference(trial)[code]
    assert set(reference) == set(NAMES)
    _within(trial, code, first.values, NAMES)
    for name in NAMES:  # in fact to float32 precision
        assert first.values[name] == pytest.approx(reference[name], rel=2e-6, abs=1e-7), name


def test_nexus_flat_foot_session_reports_the_first_complete_cycle_not_the_mean() -> None:
    trial = read_c3d(shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d"))
    left = spatiotemporal_parameters(trial).sides["L"]
    assert left.mean()["Stride Time"] == pytest.approx(1.015, abs=1e-6)  # (1.03 + 1.00) / 2
    assert nexus_reference(trial)["L"]["Stride Time"] == pytest.approx(1.03, abs=1e-6)


@pytest.mark.parametrize("code", ["L", "R"])
def test_workstation_gait_pig_every_parameter_with_workstation_definitions(code: str) -> None:
    """Vicon Workstation's values of gait-pig: its first cycle (the left one not complete),
    the opposite Foot Off even after the cycle, the opposite foot's step (module docstring)."""
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    assert reference_convention(trial) == "workstation"
    first = spatiotemporal_parameters(trial).sides[code].first
    assert first is not None
    reference = nexus_reference(trial)[code]
    _within(trial, code, first.workstation, tuple(reference))
    for name in reference:  # in fact within 0.005 % (the step to 0.02 mm)
        assert first.workstation[name] == pytest.approx(reference[name], rel=5e-5), name


def test_workstation_step_is_the_opposite_feet_step_nexus_the_one_ending_at_this_strike() -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    right = spatiotemporal_parameters(trial).sides["R"].first_complete
    assert right is not None and right.index == 0
    # Nexus' definition gives 637.7 mm, 2 % short of Workstation's 650.7 mm
    assert right.values["Step Length"] == pytest.approx(0.6377, abs=5e-4)
    assert right.workstation["Step Length"] == pytest.approx(0.65075, abs=5e-5)
    assert reference_convention(read_c3d(shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d"))) == "nexus"


def test_workstation_gait_pig_left_side_used_its_incomplete_first_cycle() -> None:
    trial = read_c3d(shared_file("vicon", "gait-pig.c3d"))
    left = spatiotemporal_parameters(trial).sides["L"]
    first, second = left.cycles
    assert not first.complete and second.complete and left.first is first
    # Nexus' definition: no opposite Foot Off inside the cycle; Workstation took the right
    # Foot Off after the cycle's end (109.6 %) and defined no Single Support
    assert math.isnan(first.values["Opposite Foot Off"])
    assert first.workstation["Opposite Foot Off"] == pytest.approx(109.605, abs=1e-3)
    assert math.isnan(first.workstation["Single Support"])
    assert "Single Support" not in nexus_reference(trial)["L"]
