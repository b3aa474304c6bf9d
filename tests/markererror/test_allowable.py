"""Allowable marker error — the inverse question (thesis §5.5.2, issue 15 Deliver 3):
the search on analytic excursions, the two-marker worst case arcsin(2r/d) inverted, and
the acceptance check on the sample trial: at the allowable error found for knee flexion a
dense Monte Carlo inside those balls never leaves the tolerance, at 1.2x that error the
Graph Follower band does.

Speed: the sample trial is cut to 6 frames (markers NaN elsewhere; fuzzy_joint_angles
skips frames with missing markers), as in test_markererror.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.markererror.allowable import (
    AllowableRequest,
    ScaleSearch,
    allowable_errors,
    allowable_sentence,
    band_excursion,
    refined_levels,
)
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles
from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject
from fuzzygait.markererror.comparison import monte_carlo_envelope
from fuzzygait.markererror.result import component_hull
from fuzzygait.markererror.sources import ErrorModel
from fuzzygait.testing import check_result
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower
from fuzzygait.workflows.angles import AnglesRun
from support import TwoMarkerLine

N_FRAMES = 6
TOLERANCE = 2.5
PLAIN_ALPHAS = (0.0, 0.5, 0.75)
KNEE = "LKneeAngles_X"


def run_search(search: ScaleSearch, excursion) -> int:  # noqa: ANN001
    """Drive ``search`` with ``excursion(scale)``; the number of evaluations."""
    n = 0
    while (scale := search.propose()) is not None:
        search.record(scale, excursion(scale))
        n += 1
        assert n < 30, search.points
    return n


# ---------------------------------------------------------------------------- the search
@pytest.mark.parametrize(
    "excursion",
    [lambda s: 33.0 * s, lambda s: 30 * s + 60 * s**2, lambda s: 20 * np.sqrt(s), lambda s: 10 * s + 500 * s**3,
     lambda s: 8 * s if s < 0.4 else math.inf],  # the last: the band becomes undetermined
    ids=["linear", "quadratic", "sqrt", "cubic", "flip"],
)  # fmt: skip
def test_search_brackets_the_allowable_scale(excursion) -> None:  # noqa: ANN001
    """Monotone excursions: the bracket ends within the step of the true allowable scale,
    the passing end within the tolerance, in a handful of evaluations."""
    step = 0.1 / 32  # 0.1 mm on a 32 mm ball
    points = {s: excursion(s) for s in (0.25, 0.5, 0.75, 1.0)}  # the plain run's levels
    search = ScaleSearch(TOLERANCE, step, points)
    n = run_search(search, excursion)
    lo, hi = search.bracket()
    assert hi is not None and 0 < hi - lo <= step
    assert excursion(lo) <= TOLERANCE < excursion(hi)
    assert n <= 8, (n, sorted(search.points))


def test_search_edge_cases() -> None:
    # everything passes (even the full Table 3.1): nothing to refine
    search = ScaleSearch(TOLERANCE, 0.01, {0.5: 1.0, 1.0: 2.0})
    assert search.propose() is None and search.bracket() == (1.0, None)
    # nothing but s = 0 passes, the first level fails by far: refined down to the step
    search = ScaleSearch(TOLERANCE, 0.01, {0.25: math.inf})
    run_search(search, lambda s: 1000.0 * s)
    lo, hi = search.bracket()
    assert lo == pytest.approx(0.0025, abs=0.01) and hi - lo <= 0.01
    # the excursion is made monotone: a smaller scale's failure makes larger ones fail
    search = ScaleSearch(TOLERANCE, 0.01, {0.1: 3.0, 0.2: 2.0})
    assert search.excursions() == {0.0: 0.0, 0.1: 3.0, 0.2: 3.0}
    assert search.bracket() == (0.0, 0.1)


# ---------------------------------------------------------------------------- analytic case
def test_two_markers_allowable_radius_is_d_sin_tau_over_2() -> None:
    """Balls of radius s·r around two markers at distance d turn the line by at most
    arcsin(2sr/d): within τ over the trial while s·r <= d_min·sin(τ)/2. The search on
    Graph Follower hulls brackets exactly that radius (the hulls are exact to 1e-6)."""
    model, r = TwoMarkerLine(n=41, degrees=True), 30.0
    deterministic = model.evaluate(np.zeros(6)).values
    balls = FuzzyBalls(np.zeros((2, 3)), [r, r], ("A", "B"))

    def excursion(scale: float) -> float:
        hull = graph_follower(model, balls, (1.0 - scale,), strategy=BatchedDirect())["hull"].sel(alpha=1.0 - scale)
        return float(np.max(np.maximum(hull.sel(bound="upper") - deterministic,
                                       deterministic - hull.sel(bound="lower"))))  # fmt: skip

    step = 0.01 / r  # 0.01 mm
    search = ScaleSearch(TOLERANCE, step, {s: excursion(s) for s in (0.25, 0.5)})
    run_search(search, excursion)
    lo, hi = search.bracket()
    exact = model.distance.min() * np.sin(np.radians(TOLERANCE)) / 2 / r  # fraction of r
    assert hi is not None and lo <= exact + 1e-6 <= hi + 2e-6 and hi - lo <= step
    print(f"\nallowable radius {lo * r:.4f}..{hi * r:.4f} mm, exact {exact * r:.4f} mm")


# ---------------------------------------------------------------------------- sample trial
@pytest.fixture(scope="module")
def frames(angles_run: AnglesRun) -> np.ndarray:
    return np.linspace(0, angles_run.trial.n_frames - 1, N_FRAMES).round().astype(int)


@pytest.fixture(scope="module")
def sparse_trial(angles_run: AnglesRun, frames: np.ndarray) -> Trial:
    markers = np.full_like(angles_run.trial.markers, np.nan)
    markers[frames] = angles_run.trial.markers[frames]
    return angles_run.trial.with_markers(markers)


@pytest.fixture(scope="module")
def plain(angles_run: AnglesRun, sparse_trial: Trial) -> xr.Dataset:
    options = FuzzyAngleOptions(alphas=PLAIN_ALPHAS)
    return fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result, options, ["LKneeAngles"])


@pytest.fixture(scope="module")
def knee(angles_run: AnglesRun, sparse_trial: Trial, plain: xr.Dataset):  # noqa: ANN201
    options = FuzzyAngleOptions(alphas=PLAIN_ALPHAS)
    return allowable_errors(sparse_trial, angles_run.subject, angles_run.result,
                            AllowableRequest(options, TOLERANCE, [KNEE]), fuzzy=plain)  # fmt: skip


def test_allowable_knee_flexion_checked_by_monte_carlo(angles_run: AnglesRun, sparse_trial: Trial,
                                                       frames: np.ndarray, knee) -> None:  # noqa: ANN001  # fmt: skip
    """Issue 15 acceptance: at the allowable error found for knee flexion, 20,000 uniform
    deviations per frame inside those balls (and 5,000 whole perturbed curves) never take
    the angle further than the tolerance from the measured one; at 1.2x that error the
    Graph Follower band (a fresh run at that α-level) does."""
    table, _ = knee
    scale = float(table.loc[KNEE, "allowable_scale"])
    assert 0.0 < scale < 1.0 and not table.loc[KNEE, "smallest_fails"]
    fixed = fixed_subject(sparse_trial, angles_run.subject)
    measured = angles_run.result.angles["LKneeAngles"][frames, 0]
    model = JointAngleModel(sparse_trial, fixed, angles_run.result.progression, "LKneeAngles", 0, frames,
                            reference=measured)  # fmt: skip
    radii = scale * np.array([ErrorModel().radius(m) for m in model.markers])
    largest = 0.0
    for per_frame, n in ((True, 20_000), (False, 5_000)):
        lower, upper = monte_carlo_envelope(model, radii, n, seed=15, per_frame=per_frame)
        largest = max(largest, float(np.max(np.maximum(upper - measured, measured - lower))))
    print(f"\n{KNEE}: allowable {scale:.4f} of Table 3.1 = {table.loc[KNEE, 'allowable_mm']:.2f} mm; "
          f"Monte Carlo excursion {largest:.3f} deg "
          f"(GFA {table.loc[KNEE, 'excursion_deg']:.3f}, tolerance {TOLERANCE})")  # fmt: skip
    assert largest <= TOLERANCE
    assert largest >= 0.5 * TOLERANCE  # the check is not vacuous: the sample reaches near the tolerance

    beyond = 1.0 - 1.2 * scale
    fuzzy = fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result,
                               FuzzyAngleOptions(alphas=(beyond,)), ["LKneeAngles"])  # fmt: skip
    excursion = band_excursion(fuzzy, KNEE).loc[beyond]
    print(f"at 1.2x ({1.2 * table.loc[KNEE, 'allowable_mm']:.2f} mm): GFA excursion {excursion:.3f} deg")
    assert excursion > TOLERANCE


def test_table_and_refined_dataset(knee, plain: xr.Dataset) -> None:  # noqa: ANN001
    table, fuzzy = knee
    row = table.loc[KNEE]
    assert list(table.index) == [KNEE]
    assert row["label"] == "Left knee, sagittal (+ flexion)" and row["tolerance_deg"] == TOLERANCE
    scale, failing = row["allowable_scale"], row["failing_scale"]
    assert 0 < scale < failing and (failing - scale) * 32.0 <= 0.1 + 1e-9  # resolution 0.1 mm on the 32 mm balls
    assert row["alpha"] == pytest.approx(1.0 - scale)
    assert row["allowable_mm"] == pytest.approx(32.0 * scale)
    assert row["thigh_mm"] == row["pelvis_mm"] == pytest.approx(32.0 * scale)
    assert row["shank_mm"] == pytest.approx(30.0 * scale) and row["ankle_mm"] == pytest.approx(20.0 * scale)
    assert math.isnan(row["foot_mm"])  # the knee uses no foot marker
    assert not row["full_table_passes"] and not row["smallest_fails"] and row["evaluations"] >= 1
    assert row["text"].startswith("Left knee, sagittal (+ flexion): known within ±2.5° if every marker stays within "
                                  f"{32 * scale:.1f} mm of where it was measured")  # fmt: skip

    # every refinement level is kept; the excursion read back from the dataset is the table's
    levels = refined_levels(fuzzy, KNEE)
    refinement = fuzzy.allowable
    assert int(levels["refined"].sum()) == row["evaluations"] == refinement.attrs["runs"]
    excursion = band_excursion(fuzzy, KNEE)
    assert excursion.loc[row["alpha"]] == pytest.approx(row["excursion_deg"]) and row["excursion_deg"] <= TOLERANCE
    assert excursion.loc[1.0 - failing] > TOLERANCE
    assert bool((np.diff(excursion.to_numpy()[::-1]) >= 0).all())  # monotone in the scale (nested hulls)
    hull = levels["hull"].dropna("frame")
    assert hull.sizes["frame"] == N_FRAMES  # nested over all levels:
    assert bool((hull.sel(bound="upper").diff("alpha") <= 0).all())
    assert bool((hull.sel(bound="lower").diff("alpha") >= 0).all())
    assert refinement["scale"].sel(component=KNEE) == scale
    assert refinement.attrs["tolerance_deg"] == TOLERANCE and refinement.attrs["node_evaluations"] > 0
    # the plain levels are unchanged in layout (other components untouched)
    assert fuzzy.bands["alpha"].to_numpy().tolist() == plain["alpha"].to_numpy().tolist()
    xr.testing.assert_identical(component_hull(fuzzy.bands, "LKneeAngles_Z"), component_hull(plain, "LKneeAngles_Z"))
    # no prefixed names, no comma-joined attributes; every part (the refined levels merged) keeps the schema
    assert not any(str(v).startswith(("refined_", "allowable_", "source_")) for v in fuzzy.bands.variables)
    assert not any(k.startswith(("allowable_", "source_")) for k in fuzzy.bands.attrs)
    assert list(fuzzy.parts()) == ["/", f"/allowable/{KNEE}"]
    assert check_result(fuzzy)["largest_violation"] <= 1e-9


def test_table_survives_saving(knee, tmp_path) -> None:  # noqa: ANN001
    """The table is rebuilt from the saved dataset (the report reads the .nc file)."""
    from fuzzygait.markererror.allowable import allowable_table
    from fuzzygait.markererror.result import MarkerErrorResult, read_marker_result, save_marker_result

    table, fuzzy = knee
    again = read_marker_result(save_marker_result(fuzzy, tmp_path / "fuzzy.nc"))
    import pandas as pd

    pd.testing.assert_frame_equal(allowable_table(again), table, check_dtype=False)
    xr.testing.assert_allclose(refined_levels(again, KNEE)["hull"], refined_levels(fuzzy, KNEE)["hull"])
    assert fuzzy.allowable["status"].to_numpy().tolist() == ["within", "", ""]  # only X was asked for
    with pytest.raises(ParameterError, match="no allowable-error refinement"):
        allowable_table(MarkerErrorResult(fuzzy.bands))


def test_full_table_passes_and_smallest_fails(angles_run: AnglesRun, sparse_trial: Trial, plain: xr.Dataset) -> None:
    # 2 mm balls (measurement only): knee flexion is within ±2.5° even at α = 0
    options = FuzzyAngleOptions(alphas=(0.0,), sources=("measurement",))
    table, fuzzy = allowable_errors(sparse_trial, angles_run.subject, angles_run.result,
                                    AllowableRequest(options, TOLERANCE, [KNEE]))  # fmt: skip
    row = table.loc[KNEE]
    assert row["full_table_passes"] and row["allowable_scale"] == 1.0 and row["evaluations"] == 0
    assert "even with the full errors of Table 3.1 (measurement)" in row["text"]
    assert fuzzy.allowable.attrs["runs"] == 0
    # a tolerance no tried scale meets, at a coarse resolution: nothing passes
    options = FuzzyAngleOptions(alphas=PLAIN_ALPHAS)
    table, _ = allowable_errors(sparse_trial, angles_run.subject, angles_run.result,
                                AllowableRequest(options, 0.01, [KNEE], resolution=40.0), fuzzy=plain)  # fmt: skip
    row = table.loc[KNEE]
    assert row["smallest_fails"] and row["allowable_scale"] == 0.0 and row["failing_scale"] == 0.25
    assert "not known within ±0.01° even if every marker stays within 8.00 mm" in row["text"]


def test_bad_arguments(angles_run: AnglesRun, sparse_trial: Trial, plain: xr.Dataset) -> None:
    args = (sparse_trial, angles_run.subject, angles_run.result)
    options = FuzzyAngleOptions(alphas=PLAIN_ALPHAS)
    with pytest.raises(ParameterError, match="tolerance"):
        allowable_errors(*args, AllowableRequest(options, 0.0), fuzzy=plain)
    with pytest.raises(ParameterError, match="LHipAngles_X"):
        allowable_errors(*args, AllowableRequest(options, angles=["LHipAngles_X"]), fuzzy=plain)
    with pytest.raises(ParameterError, match="sources"):
        allowable_errors(*args, AllowableRequest(FuzzyAngleOptions(sources=("measurement",))), fuzzy=plain)
    with pytest.raises(ParameterError, match="ball radius of LKNE"):
        wrong = FuzzyAngleOptions(error_model=ErrorModel(marker_radius={"LKNE": 5.0}))
        allowable_errors(*args, AllowableRequest(wrong), fuzzy=plain)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [("options", None, "options must be FuzzyAngleOptions"), ("tolerance", 0.0, "tolerance must be > 0"),
     ("tolerance", float("nan"), "tolerance must be > 0"), ("angles", "LKneeAngles", "angles must be a sequence"),
     ("resolution", -0.1, "resolution must be > 0"), ("max_evaluations", 0, "max_evaluations must be a whole"),
     ("max_evaluations", 2.5, "max_evaluations must be a whole")],
)  # fmt: skip
def test_request_rejects_each_bad_field(field: str, value: object, message: str) -> None:
    with pytest.raises(ParameterError, match=f"^{message}"):
        AllowableRequest(**{field: value})  # type: ignore[arg-type]


def test_sentence_without_frames() -> None:
    assert "no frame" in allowable_sentence("Left knee, sagittal", 2.5, math.nan, {}, "Table 3.1", False, False,
                                            math.nan)  # fmt: skip
