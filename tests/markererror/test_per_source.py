"""Per-source bands of the flexion angles (issue 15 Deliver 4, thesis Fig. 5.9): each error
source of Table 3.1 alone beside all sources together.

Independent truths: the analytic two-marker case (balls r around two markers at distance d
turn the line by arcsin(2r/d) either way) for each source's Table 3.1 radius; on the sample
trial the nesting of the balls (a source's ball lies inside the sum's, so its band lies
inside the all-sources band), the 2 mm measurement balls giving the narrowest band, and the
same numbers as ``fuzzy_joint_angles(sources=(s,))``. Also the save/load round trip, the
progress callbacks (per-source runs and the allowable refinement) and bad input.

Speed: the sample trial cut to 6 frames (markers NaN elsewhere), left leg, α = 0 and 0.5.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.markererror.allowable import AllowableRequest, allowable_errors
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles
from fuzzygait.markererror.per_source import (
    ALL,
    PerSourceRequest,
    per_source_bands,
    source_bands_dataset,
    source_components,
    source_hull,
    source_names,
    source_undetermined,
    widest_source_bands,
)
from fuzzygait.markererror.result import (
    AngleAxes,
    MarkerErrorResult,
    component_hull,
    fuzzy_angles_dataset,
    read_marker_result,
    save_marker_result,
)
from fuzzygait.markererror.sources import SOURCES, TABLE_3_1, ErrorModel
from fuzzygait.testing import check_result
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower
from fuzzygait.uncertainty.storage import load_result
from fuzzygait.workflows.angles import AnglesRun
from support import TwoMarkerLine, sparse_angles_run

N_FRAMES = 6
ALPHAS = (0.0, 0.5)
LEFT_FLEXION = ["LHipAngles_X", "LKneeAngles_X", "LAnkleAngles_X"]


@pytest.fixture(scope="module")
def sparse_run(angles_run: AnglesRun) -> AnglesRun:
    """The sample run with every marker NaN outside 6 frames spread over the trial."""
    return sparse_angles_run(angles_run, N_FRAMES)


@pytest.fixture(scope="module")
def options() -> FuzzyAngleOptions:
    return FuzzyAngleOptions(alphas=ALPHAS, workers=1)


@pytest.fixture(scope="module")
def plain(sparse_run: AnglesRun, options: FuzzyAngleOptions) -> xr.Dataset:
    return fuzzy_joint_angles(sparse_run.trial, sparse_run.subject, sparse_run.result, options,
                              ["LHipAngles", "LKneeAngles", "LAnkleAngles"])  # fmt: skip


@pytest.fixture(scope="module")
def banded(sparse_run: AnglesRun, options: FuzzyAngleOptions, plain: xr.Dataset) -> MarkerErrorResult:
    sources = per_source_bands(sparse_run.trial, sparse_run.subject, sparse_run.result, plain,
                               PerSourceRequest(options))  # fmt: skip
    return MarkerErrorResult(plain, sources=sources)


def _valid(result: MarkerErrorResult) -> np.ndarray:
    """The frames (dataset index) with a band."""
    hull = component_hull(result.bands, "LKneeAngles_X").sel(alpha=0.0, bound="upper")
    return np.flatnonzero(np.isfinite(hull.to_numpy()))


# ---------------------------------------------------------------------------- analytic
def test_two_markers_per_source_give_arcsin_2r_over_d() -> None:
    """Two thigh markers (Table 3.1 thigh: measurement 2, placement 10, STA 20, all 32 mm)
    at distance d: the band of each source alone is 2·arcsin(2r/d) wide, widest where d is
    smallest; the table reads it to 1e-6 rad, nested, and names the soft-tissue artefact."""
    model, markers = TwoMarkerLine(n=24, distance=(250.0, 100.0), turn=(0.5, 2.3), offsets=(40.0, 10.0, 3.0), degrees=True, names=("LTHI", "LKNE")), ("LTHI", "LKNE")
    levels = np.array([0.0, 1.0])

    def hull(radius: float) -> np.ndarray:
        balls = FuzzyBalls(np.zeros((2, 3)), [radius, radius], markers)
        result = graph_follower(model, balls, levels, strategy=BatchedDirect())
        return result["hull"].transpose("alpha", "bound", "time").to_numpy()

    total = ErrorModel().radius("LTHI")
    assert total == 32.0
    frames = np.arange(1, model.times.size + 1)
    axes = AngleAxes(alphas=levels, frames=frames, times=model.times, markers=list(markers), ball_radius=[total, total])
    main = fuzzy_angles_dataset({"LKneeAngles_X": hull(total)}, axes)
    radii = {s: TABLE_3_1["thigh"][s] for s in SOURCES}
    sources = source_bands_dataset(main, {s: {"LKneeAngles_X": hull(r)} for s, r in radii.items()}, levels,
                                   radii={s: [r, r] for s, r in radii.items()})  # fmt: skip
    fuzzy = MarkerErrorResult(main, sources=sources)
    table = widest_source_bands(fuzzy)
    assert table.alpha == 0.0 and table.sources == list(SOURCES)
    for source, radius in [*radii.items(), (ALL, total)]:
        exact = np.max(2 * np.arcsin(2 * radius / model.distance))
        assert math.radians(table.width("LKneeAngles_X", source)) == pytest.approx(exact, abs=1e-6), source
        measured = model.evaluate(np.zeros(6)).values
        band = source_hull(fuzzy, source, "LKneeAngles_X").sel(alpha=0.0)
        np.testing.assert_allclose(np.radians(band.sel(bound="upper") - measured),
                                   np.arcsin(2 * radius / model.distance), atol=1e-6)  # fmt: skip
    assert table.dominant("LKneeAngles_X") == "sta"
    assert sources.attrs["nesting_excess_deg"] <= 1e-6
    np.testing.assert_array_equal(sources["ball_radius"].sel(source="placement"), [10.0, 10.0])
    assert check_result(fuzzy)["largest_violation"] <= 1e-9


# ---------------------------------------------------------------------------- the sample trial
def test_layout_and_main_result_unaffected(plain: xr.Dataset, banded: MarkerErrorResult) -> None:
    sources = banded.sources
    assert sources is not None and source_names(banded) == list(SOURCES)
    assert source_components(banded) == LEFT_FLEXION  # flexion only, no frontal/transverse runs
    assert sources["hull"].dims == ("source", "component", "alpha", "bound", "frame")
    assert sources["hull"].attrs["units"] == "deg" and sources["ball_radius"].attrs["units"] == "mm"
    assert all("long_name" in sources[v].attrs for v in ("hull", "undetermined", "ball_radius"))
    np.testing.assert_array_equal(sources["alpha"], [0.0, 1.0])  # the smallest level (and 1) only: a coordinate
    assert sources.attrs["runs"] == 9 and not any(isinstance(v, str) and "," in v for v in sources.attrs.values())
    assert not any(str(v).startswith(("source_", "refined_")) for v in [*sources.variables, *sources.attrs])
    assert banded.bands is plain  # the bands untouched
    check_result(banded)  # the bands and the per-source bands keep the schema
    # the measured curve at α = 1 of every source is the main one's
    for source in SOURCES:
        np.testing.assert_array_equal(source_hull(banded, source, "LKneeAngles_X").sel(alpha=1.0),
                                      component_hull(plain, "LKneeAngles_X").sel(alpha=1.0))  # fmt: skip


def test_each_source_band_nests_inside_all_sources(sparse_run: AnglesRun, options: FuzzyAngleOptions,
                                                   plain: xr.Dataset) -> None:  # fmt: skip
    """A source's ball lies inside the sum's, so its band lies inside the all-sources band
    at the same α (where both are determined; at α = 0 the all-sources ankle band is
    undetermined on every frame, so α = 0.5 too), and the 2 mm measurement band is the
    narrowest."""
    sources = per_source_bands(sparse_run.trial, sparse_run.subject, sparse_run.result, plain,
                               PerSourceRequest(options, alphas=(0.0, 0.5)))  # fmt: skip
    banded = MarkerErrorResult(plain, sources=sources)
    np.testing.assert_array_equal(sources["alpha"], [0.0, 0.5, 1.0])
    valid = _valid(banded)
    assert valid.size == N_FRAMES
    for component in LEFT_FLEXION:
        for alpha in (0.0, 0.5):
            outer = source_hull(banded, ALL, component).sel(alpha=alpha).isel(frame=valid)
            outer_flags = source_undetermined(banded, ALL, component).sel(alpha=alpha).isel(frame=valid)
            widths = {}
            for source in SOURCES:
                inner = source_hull(banded, source, component).sel(alpha=alpha).isel(frame=valid)
                flags = source_undetermined(banded, source, component).sel(alpha=alpha).isel(frame=valid)
                keep = ~(flags | outer_flags).to_numpy()
                assert keep.any() or alpha == 0.0, (component, source, alpha)  # the check is not vacuous
                upper, lower = inner.sel(bound="upper").to_numpy(), inner.sel(bound="lower").to_numpy()
                assert np.all(upper[keep] <= outer.sel(bound="upper").to_numpy()[keep] + 1e-6), (component, source)
                assert np.all(lower[keep] >= outer.sel(bound="lower").to_numpy()[keep] - 1e-6), (component, source)
                widths[source] = upper - lower
            for source in ("placement", "sta"):  # 2 mm on every marker against 5-20 mm
                assert np.all(widths["measurement"] < widths[source]), (component, source, alpha)
    assert sources.attrs["nesting_excess_deg"] <= 1e-6
    table = widest_source_bands(banded)
    for component in LEFT_FLEXION:
        assert table.width(component, "measurement") < table.width(component, "placement")
        assert table.dominant(component) in ("placement", "sta")


def test_the_same_bands_as_fuzzy_joint_angles_with_one_source(sparse_run: AnglesRun,
                                                              banded: MarkerErrorResult) -> None:  # fmt: skip
    for source in ("measurement", "sta"):
        one = FuzzyAngleOptions(alphas=(0.0,), sources=(source,), workers=1)
        alone = fuzzy_joint_angles(sparse_run.trial, sparse_run.subject, sparse_run.result, one, ["LKneeAngles"])
        expected = component_hull(alone, "LKneeAngles_X")
        np.testing.assert_allclose(source_hull(banded, source, "LKneeAngles_X"), expected, rtol=0, atol=1e-9)
        assert banded.sources is not None
        np.testing.assert_array_equal(banded.sources["ball_radius"].sel(source=source, marker=alone["marker"]),
                                      alone["ball_radius"])  # fmt: skip


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_round_trip(banded: MarkerErrorResult, tmp_path, suffix: str) -> None:  # noqa: ANN001
    path = save_marker_result(banded, tmp_path / f"fuzzy{suffix}")
    loaded = read_marker_result(path)
    assert loaded.sources is not None and loaded.allowable is None
    xr.testing.assert_identical(loaded.sources, banded.sources)
    xr.testing.assert_identical(loaded.bands, banded.bands)
    assert loaded.sources["undetermined"].dtype == bool
    assert source_names(loaded) == list(SOURCES) and source_components(loaded) == LEFT_FLEXION
    before, after = widest_source_bands(banded), widest_source_bands(loaded)
    assert after.widths.equals(before.widths) and after.undetermined.equals(before.undetermined)
    xr.testing.assert_identical(load_result(path).drop_attrs(), banded.bands.drop_attrs())  # the root: the bands


def test_progress_of_the_per_source_runs(sparse_run: AnglesRun, options: FuzzyAngleOptions, plain: xr.Dataset) -> None:
    calls: list[tuple[int, int]] = []
    per_source_bands(sparse_run.trial, sparse_run.subject, sparse_run.result, plain,
                     PerSourceRequest(options, components=["LKneeAngles_X"]),
                     progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    assert calls == [(3, 3)]  # serial: the three sources of the one component in one run (side by side)


def test_progress_of_the_allowable_refinement(sparse_run: AnglesRun, options: FuzzyAngleOptions,
                                              plain: xr.Dataset) -> None:  # fmt: skip
    calls: list[tuple[int, int]] = []
    _, refined = allowable_errors(sparse_run.trial, sparse_run.subject, sparse_run.result,
                                  AllowableRequest(options, angles=["LKneeAngles_X"]), fuzzy=plain,
                                  progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    assert refined.allowable is not None
    runs = refined.allowable.attrs["runs"]
    assert runs > 0 and calls[-1] == (runs, runs)
    done = [d for d, _ in calls]
    assert done == sorted(done) and all(0 <= d <= t for d, t in calls)


def test_bad_input(sparse_run: AnglesRun, options: FuzzyAngleOptions, plain: xr.Dataset) -> None:
    run = (sparse_run.trial, sparse_run.subject, sparse_run.result)
    with pytest.raises(ParameterError, match="components"):
        per_source_bands(*run, plain, PerSourceRequest(options, components=["RKneeAngles_X"]))
    with pytest.raises(ParameterError, match="alphas"):
        per_source_bands(*run, plain, PerSourceRequest(options, alphas=(0.25,)))
    with pytest.raises(ParameterError, match="no flexion"):
        per_source_bands(*run, plain.sel(component=["LKneeAngles_Y"]), PerSourceRequest(options))
    with pytest.raises(ParameterError, match="sources"):
        per_source_bands(*run, plain, PerSourceRequest(options, sources=("magic",)))
    with pytest.raises(ParameterError, match="no per-source bands"):
        widest_source_bands(MarkerErrorResult(plain))
