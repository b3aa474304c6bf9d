"""Gap filling against analytic truth.

Error model used for the bounds: inside a gap the spline acts like a cubic interpolant over
one knot interval of length ``L = (gap + 1) / rate`` seconds.  Cubic Hermite interpolation
has error ``f''''(xi) (t - a)^2 (t - b)^2 / 4!``, at most ``|f''''| L^4 / 384`` at mid-gap.
The spline's end slopes are themselves estimated, which multiplies this by a constant
``K(gap)`` that we measure exactly on a quartic (``f'''' = 24`` everywhere, so the leading
error term is the whole error): ``K`` is between 1.18 and 1.68 for gaps of 1..10 frames.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.interpolate import CubicSpline

from support import cut
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.findings import Finding, FindingKind, messages
from fuzzygait.core.trial import Trial
from fuzzygait.mocap import Gap, GapRun, fill_gaps, fill_trial_gaps, find_gaps, gap_report_table
from fuzzygait.mocap.gaps import WINDOW_VALID_SAMPLES

# Gait-like trajectory: fundamental 0.9 Hz plus two harmonics, amplitudes in mm.
HARMONICS = ((100.0, 0.9, 0.0), (30.0, 1.8, 0.5), (10.0, 2.7, 1.1))
#: Upper bound of |f''''| in mm/s^4 (triangle inequality over the harmonics).
MAX_D4 = sum(a * (2 * np.pi * f) ** 4 for a, f, _ in HARMONICS)
GAP_LENGTHS = range(1, 11)


def trajectory(t: np.ndarray, shift: float = 0.0) -> np.ndarray:
    return sum(a * np.sin(2 * np.pi * f * t + p + shift) for a, f, p in HARMONICS)


def markers_at(rate: float, seconds: float = 24.0, n_markers: int = 2) -> np.ndarray:
    """(frames, n_markers, 3) analytic markers in mm, each coordinate phase-shifted."""
    t = np.arange(int(round(seconds * rate))) / rate
    columns = [
        [trajectory(t, 0.7 * m + 2.1 * c) for c in range(3)] for m in range(n_markers)
    ]
    return np.transpose(np.array(columns), (2, 0, 1))


def interior_cuts(n_frames: int, n_markers: int) -> list[tuple[int, int, int]]:
    """Gaps of 1..10 frames, 97 frames apart (isolated windows), on every marker."""
    cuts, start = [], 60
    for m in range(n_markers):
        for length in GAP_LENGTHS:
            cuts.append((m, start + 13 * m, length))
            start += 97
    assert start + 13 * n_markers < n_frames - 60
    return cuts


@pytest.fixture(scope="module")
def spline_constant() -> dict[int, float]:
    """K(gap): max error of the fill on t^4 (unit spacing) over 24 L^4 / 384."""
    t = np.arange(400.0) - 200.0
    quartic = np.repeat((t**4)[:, None, None], 3, axis=2)
    constants = {}
    for length in GAP_LENGTHS:
        filled, _ = fill_gaps(cut(quartic, [(0, 200, length)]), ["Q"])
        constants[length] = np.max(np.abs(filled - quartic)) / (24 * (length + 1) ** 4 / 384)
    return constants


def max_error_by_length(rate: float) -> dict[int, float]:
    truth = markers_at(rate, seconds=2200 / rate)  # 2200 frames hold all cuts
    cuts = interior_cuts(len(truth), truth.shape[1])
    filled, gaps = fill_gaps(cut(truth, cuts), ["A", "B"], max_gap=10)
    assert all(g.filled for g in gaps) and len(gaps) == len(cuts)
    errors = dict.fromkeys(GAP_LENGTHS, 0.0)
    for m, start, length in cuts:
        err = np.max(np.abs(filled[start : start + length, m] - truth[start : start + length, m]))
        errors[length] = max(errors[length], err)
    return errors


def test_spline_constant_is_moderate(spline_constant):
    print("K(gap):", {k: round(v, 3) for k, v in spline_constant.items()})
    assert all(1.0 < k < 1.75 for k in spline_constant.values())


@pytest.mark.parametrize("rate", [50, 100, 120])
def test_fill_error_against_analytic_truth(rate, spline_constant):
    errors = max_error_by_length(rate)
    for length, err in errors.items():
        theory = spline_constant[length] * MAX_D4 * ((length + 1) / rate) ** 4 / 384
        print(f"{rate} Hz, gap {length:2d}: max error {err:.2e} mm, theory <= {theory:.2e} mm")
        # 30 % headroom for the higher-order (h^5 f^(5)) terms the L^4 model leaves out.
        assert err <= 1.3 * theory
    # Measured maxima for 10-frame gaps (mm): 50 Hz 7.8, 100 Hz 0.22, 120 Hz 0.26; the
    # worst case over gap positions is the theory value (100 Hz: 0.64 mm).
    assert errors[10] < {50: 9.0, 100: 0.7, 120: 0.32}[rate]
    assert errors[1] < {50: 0.02, 100: 1.2e-3, 120: 6e-4}[rate]


def test_fill_error_converges_as_fourth_power_of_sample_spacing():
    coarse, fine = max_error_by_length(60), max_error_by_length(120)
    for length in (1, 4, 10):
        ratio = coarse[length] / fine[length]
        print(f"gap {length}: 60 Hz {coarse[length]:.2e} mm, 120 Hz {fine[length]:.2e} mm, "
              f"ratio {ratio:.1f} (h^4 predicts 16)")
        assert ratio >= 8


def test_cubic_polynomial_is_filled_exactly():
    t = np.arange(300.0)
    cubic = 1e-4 * (t - 120) ** 3 - 0.02 * (t - 50) ** 2 + 3 * t - 400
    markers = np.stack([cubic, -cubic, 2 * cubic], axis=1)[:, None, :]
    filled, _ = fill_gaps(cut(markers, [(0, 100, 10), (0, 130, 1), (0, 200, 7)]), ["C"])
    np.testing.assert_allclose(filled, markers, rtol=0, atol=1e-8)


def test_only_gap_samples_change_and_input_not_mutated():
    truth = markers_at(100)
    holes = cut(truth, [(0, 100, 5), (1, 400, 30), (1, 0, 4), (0, len(truth) - 3, 3)])
    before = holes.copy()
    filled, _ = fill_gaps(holes, ["A", "B"], max_gap=10)
    assert np.array_equal(holes, before, equal_nan=True)
    valid = np.all(np.isfinite(holes), axis=2)
    assert np.array_equal(filled[valid], holes[valid])  # bit-identical outside gaps
    assert filled is not holes


def test_edge_and_long_gaps_are_reported_not_filled():
    truth = markers_at(100, seconds=6)
    n = len(truth)
    cuts = [(0, 0, 5), (0, 200, 11), (0, 300, 10), (0, n - 7, 7), (1, 250, 3)]
    filled, gaps = fill_gaps(cut(truth, cuts), ["LASI", "RASI"], max_gap=10)
    assert gaps == [
        Gap("LASI", 0, 5, False, "at start of trial"),
        Gap("LASI", 200, 11, False, "longer than max_gap=10"),
        Gap("LASI", 300, 10, True, "", "spline"),
        Gap("LASI", n - 7, 7, False, "at end of trial"),
        Gap("RASI", 250, 3, True, "", "spline"),
    ]
    assert np.all(np.isnan(filled[:5, 0]))
    assert np.all(np.isnan(filled[200:211, 0]))
    assert np.all(np.isnan(filled[n - 7 :, 0]))
    assert np.all(np.isfinite(filled[5 : n - 7][np.r_[0:195, 206 : n - 12], 0]))
    assert np.all(np.isfinite(filled[:, 1]))


def test_report_matches_random_cuts_exactly():
    rng = np.random.default_rng(7)
    truth = markers_at(120, seconds=30, n_markers=3)
    cuts = []
    for m in range(3):
        starts = np.sort(rng.choice(np.arange(20, len(truth) - 60, 40), size=25, replace=False))
        cuts += [(m, int(s), int(rng.integers(1, 30))) for s in starts]
    labels = ["X", "Y", "Z"]
    _, gaps = fill_gaps(cut(truth, cuts), labels, max_gap=12)
    assert [(g.marker, g.start, g.length) for g in gaps] == [
        (labels[m], s, length) for m, s, length in cuts
    ]
    assert [g.filled for g in gaps] == [length <= 12 for _, _, length in cuts]
    table = gap_report_table(gaps)
    assert list(table.columns) == [
        "marker", "start", "length", "filled", "reason", "method", "note"
    ]
    assert table["length"].tolist() == [length for _, _, length in cuts]
    assert table.loc[~table["filled"], "reason"].eq("longer than max_gap=12").all()


def test_empty_report_table_has_columns():
    table = gap_report_table([])
    assert isinstance(table, pd.DataFrame) and table.empty
    assert list(table.columns) == [
        "marker", "start", "length", "filled", "reason", "method", "note"
    ]


def test_max_gap_zero_fills_nothing():
    holes = cut(markers_at(100, seconds=4), [(0, 100, 1), (1, 200, 3)])
    filled, gaps = fill_gaps(holes, ["A", "B"], max_gap=0)
    assert np.array_equal(filled, holes, equal_nan=True)
    assert [g.reason for g in gaps] == ["longer than max_gap=0"] * 2


@pytest.mark.parametrize("bad", [-1, 2.5, 10.0, "10", None, True])
def test_bad_max_gap_raises(bad):
    with pytest.raises(ParameterError, match="max_gap"):
        fill_gaps(markers_at(50, seconds=2), ["A", "B"], max_gap=bad)


@pytest.mark.parametrize("shape", [(100, 3), (100, 2, 2), (100, 2, 3, 1)])
def test_bad_shape_raises(shape):
    with pytest.raises(ParameterError, match=r"\(frames, markers, 3\)"):
        fill_gaps(np.zeros(shape), ["A", "B"])


def test_label_count_mismatch_raises():
    with pytest.raises(ParameterError, match="labels"):
        fill_gaps(np.zeros((10, 2, 3)), ["A"])


def test_invisible_and_single_sample_markers_are_reported():
    markers = markers_at(100, seconds=2, n_markers=3)
    markers[:, 0] = np.nan
    markers[:50, 1] = np.nan
    markers[51:, 1] = np.nan
    filled, gaps = fill_gaps(markers, ["NEVER", "ONCE", "OK"])
    assert gaps == [
        Gap("NEVER", 0, 200, False, "marker never visible"),
        Gap("ONCE", 0, 50, False, "at start of trial"),
        Gap("ONCE", 51, 149, False, "at end of trial"),
    ]
    assert np.all(np.isnan(filled[:, 0]))
    assert np.array_equal(filled[:, 1], markers[:, 1], equal_nan=True)


def test_too_few_valid_samples_on_one_side():
    markers = markers_at(100, seconds=2, n_markers=1)
    # 20 missing at start, 1 valid (frame 20), 3 missing, then valid.
    holes = cut(markers, [(0, 0, 20), (0, 21, 3)])
    filled, gaps = fill_gaps(holes, ["M"])
    assert gaps[1] == Gap("M", 21, 3, False, "too few valid samples (need 2 on each side)")
    assert np.all(np.isnan(filled[21:24, 0]))
    # With two valid samples before it the gap is filled.
    filled, gaps = fill_gaps(cut(markers, [(0, 0, 20), (0, 22, 3)]), ["M"])
    assert gaps[1].filled and np.all(np.isfinite(filled[22:25, 0]))


def test_partially_missing_sample_counts_as_missing():
    truth = markers_at(100, seconds=3, n_markers=1)
    holes = truth.copy()
    holes[150, 0, 1] = np.nan  # only y missing
    holes[151, 0, 2] = np.inf  # a non-finite z counts as missing too
    filled, gaps = fill_gaps(holes, ["M"])
    assert gaps == [Gap("M", 150, 2, True, "", "spline")]
    assert np.array_equal(filled, fill_gaps(cut(truth, [(0, 150, 2)]), ["M"])[0])
    # unfilled partial samples come back NaN in all three coordinates
    filled, _ = fill_gaps(holes, ["M"], max_gap=1)
    assert np.all(np.isnan(filled[150:152, 0]))


def test_fill_uses_only_the_documented_window():
    truth = markers_at(100, seconds=4, n_markers=1)
    holes = cut(truth, [(0, 200, 8)])
    reference, _ = fill_gaps(holes, ["M"])
    far = holes.copy()
    far[: 200 - WINDOW_VALID_SAMPLES] += 50.0
    far[208 + WINDOW_VALID_SAMPLES :] -= 50.0
    changed, _ = fill_gaps(far, ["M"])
    assert np.array_equal(changed[200:208], reference[200:208])
    near = holes.copy()
    near[195] += 50.0  # next to the gap: must matter (the test can fail)
    assert not np.allclose(fill_gaps(near, ["M"])[0][200:208], reference[200:208])


def test_windowed_fill_equals_whole_trajectory_spline():
    """The documented locality claim: 30 samples per side are as good as all of them."""
    truth = markers_at(100, seconds=20)
    cuts = [(0, 100, 10), (0, 150, 3), (0, 170, 9), (0, 900, 6), (1, 500, 10), (1, 1500, 2)]
    holes = cut(truth, cuts)
    filled, _ = fill_gaps(holes, ["A", "B"])
    for m in range(2):
        valid = np.flatnonzero(np.isfinite(holes[:, m, 0]))
        whole = CubicSpline(valid, holes[valid, m], bc_type="not-a-knot")(np.arange(len(holes)))
        np.testing.assert_allclose(filled[:, m], whole, rtol=0, atol=1e-9)


def test_find_gaps_positions():
    mask = np.array([1, 1, 0, 0, 1, 0, 1, 1, 1, 0, 1], dtype=bool)
    assert find_gaps(mask) == [
        GapRun(0, 2, "start"),
        GapRun(4, 1, "interior"),
        GapRun(6, 3, "interior"),
        GapRun(10, 1, "end"),
    ]
    assert find_gaps(np.ones(4, bool)) == [GapRun(0, 4, "all")]
    assert find_gaps(np.zeros(4, bool)) == []
    assert find_gaps(mask)[2].stop == 9


def test_fill_trial_gaps_returns_new_trial_with_note():
    truth = markers_at(100, seconds=5)
    holes = cut(truth, [(0, 100, 4), (0, 0, 3), (1, 300, 20)])
    read = Finding(FindingKind.FILE_FORMAT, "read")
    trial = Trial(markers=holes, marker_labels=["LHEE", "RHEE"], rate=100.0, notes=[read])
    new, gaps = fill_trial_gaps(trial, max_gap=10)
    assert new is not trial and messages(new.notes) == [
        "read",
        "gap filling: 1 of 3 gaps filled (max_gap=10 frames, method=auto: 1 spline)",
    ]
    filling = new.notes[-1]
    assert filling.kind is FindingKind.GAP_FILLING and (filling.max_gap, filling.method) == (10, "auto")
    assert trial.notes == [read] and np.array_equal(trial.markers, holes, equal_nan=True)
    assert np.array_equal(new.markers, fill_gaps(holes, ["LHEE", "RHEE"])[0], equal_nan=True)
    assert [g.marker for g in gaps] == ["LHEE", "LHEE", "RHEE"]


def test_many_random_gaps_are_reported_once_and_filled_where_allowed():
    """A minute of 20 random-walk markers with 40 random gaps each (some overlapping):
    every NaN run is reported once, the short ones are filled, the rest left alone.
    (Its speed, on the 10-minute version, is ``benchmarks/gap_fill_speed.py``.)"""
    rng = np.random.default_rng(1)
    n, n_markers = 120 * 60, 20
    markers = np.cumsum(rng.normal(size=(n, n_markers, 3)), axis=0)
    for m in range(n_markers):
        for start in rng.integers(1, n - 40, size=40):
            markers[start : start + rng.integers(1, 30), m] = np.nan
    filled, gaps = fill_gaps(markers, [f"M{i}" for i in range(n_markers)])
    missing = np.isnan(markers[..., 0])
    runs = [(f"M{m}", r.start, r.length) for m in range(n_markers) for r in find_gaps(missing[:, m])]
    assert [(g.marker, g.start, g.length) for g in gaps] == runs
    assert np.array_equal(filled[~missing], markers[~missing])
    reasons = {g.reason for g in gaps}
    assert "" in reasons and "longer than max_gap=10" in reasons
    for g in gaps:
        column = filled[g.start : g.start + g.length, int(g.marker[1:])]
        assert g.filled == (g.reason == "") == np.isfinite(column).all(), g
        assert g.filled or np.isnan(column).all(), g
        assert (g.length <= 10) or not g.filled, g
        assert g.method in (("spline", "pattern") if g.filled else ("",)), g
