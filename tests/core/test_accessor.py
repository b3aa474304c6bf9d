"""``dataset.fuzzy`` and ``check_result``: one way to read and check every fuzzy result —
the Graph Follower's, the marker-error analysis', the FRV-GFA's — against numbers worked
out by hand and against the functions each analysis had before."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent
from fuzzygait.markererror.analysis import relative_envelope_width
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset
from fuzzygait.testing import ModelCheckError, check_result
from fuzzygait.uncertainty import FunctionModel, FuzzyVector, graph_follower, load_result, save_result, triangular

ALPHAS = np.array([0.0, 0.5, 1.0])


def angles_dataset(undetermined: bool = False) -> xr.Dataset:
    """Two components on 4 frames with bands known by construction: the measured angle m,
    the band at α of half-width (1 − α)·w per frame."""
    frames = np.arange(10, 14)
    measured = {"LKneeAngles_X": np.array([10.0, 40.0, -20.0, 5.0]),
                "LKneeAngles_Y": np.array([-2.0, -4.0, -3.0, -1.0])}  # fmt: skip
    half = {"LKneeAngles_X": np.array([1.0, 3.0, 2.0, 0.5]), "LKneeAngles_Y": np.array([0.2, 0.1, 0.4, 0.3])}
    hulls = {c: np.stack([np.stack([m - (1 - a) * half[c], m + (1 - a) * half[c]]) for a in ALPHAS])
             for c, m in measured.items()}  # fmt: skip
    flags = {c: np.zeros((ALPHAS.size, frames.size), dtype=bool) for c in hulls}
    if undetermined:
        flags["LKneeAngles_X"][0, 1] = True  # α = 0 at frame 11: the widest band, undetermined
    axes = AngleAxes(alphas=ALPHAS, frames=frames, times=(frames - 1) / 100.0, markers=["LKNE"], ball_radius=[10.0])
    return fuzzy_angles_dataset(hulls, axes, undetermined=flags)


def test_the_marker_error_layout_read_through_the_accessor() -> None:
    ds = angles_dataset()
    assert ds.fuzzy.problems() == [] and ds.fuzzy.axis == "frame" and ds.fuzzy.units == "deg"
    assert ds.fuzzy.components == [AngleComponent.parse("LKneeAngles_X"), AngleComponent.parse("LKneeAngles_Y")]
    band = ds.fuzzy.band(0.5, component="LKneeAngles_X")
    np.testing.assert_allclose(band.sel(bound="upper") - band.sel(bound="lower"), [1.0, 3.0, 2.0, 0.5])
    np.testing.assert_allclose(ds.fuzzy.measured(AngleComponent.parse("LKneeAngles_Y")), [-2.0, -4.0, -3.0, -1.0])
    np.testing.assert_allclose(ds.fuzzy.width(0.0, "LKneeAngles_X"), [2.0, 6.0, 4.0, 1.0])
    # ΔΦ by hand: widest band / largest |measured|, in %: X: 6/40, 3/40; Y: 0.8/4, 0.4/4
    expected = {"LKneeAngles_X": {0.0: 15.0, 0.5: 7.5}, "LKneeAngles_Y": {0.0: 20.0, 0.5: 10.0}}
    delta = ds.fuzzy.delta_phi()
    for name, by_alpha in expected.items():
        for alpha, value in by_alpha.items():
            assert float(delta.sel(component=name, alpha=alpha)) == pytest.approx(value, rel=1e-12)
    assert delta.attrs["units"] == "%"


def test_delta_phi_agrees_with_the_analysis_table_undetermined_frames_left_out() -> None:
    ds = angles_dataset(undetermined=True)
    table = relative_envelope_width(ds)  # the marker-error analysis' own ΔΦ (Eq. 5.3)
    delta = ds.fuzzy.delta_phi()
    for name in table.index:
        for alpha in table.columns:
            assert float(delta.sel(component=name, alpha=alpha)) == pytest.approx(float(table.loc[name, alpha]),
                                                                                  rel=1e-12)  # fmt: skip
    assert float(delta.sel(component="LKneeAngles_X", alpha=0.0)) == pytest.approx(100.0 * 4.0 / 40.0)
    assert bool(ds.fuzzy.undetermined(0.0, "LKneeAngles_X").sel(frame=11))


def test_a_graph_follower_result_and_its_file() -> None:
    times = np.linspace(0.0, 1.0, 21)
    model = FunctionModel(lambda p: p[0] * times + p[1], times, lambda p: np.column_stack([times, np.ones_like(times)]))
    params = FuzzyVector([triangular(1.0, 2.0, 3.0), triangular(0.0, 0.5, 1.0)])
    result = graph_follower(model, params, (0.0, 0.5))
    assert result.fuzzy.axis == "time" and result.fuzzy.components == []
    # f is monotone in both parameters: the α = 0 band at t is [1 t + 0, 3 t + 1], width 2 t + 1
    np.testing.assert_allclose(result.fuzzy.width(0.0), 2.0 * times + 1.0, atol=1e-6)
    # ΔΦ by hand: widest band 3 at t = 1 over the largest |f(p_det)| = 2.5
    assert float(result.fuzzy.delta_phi().sel(alpha=0.0)) == pytest.approx(100.0 * 3.0 / 2.5, rel=1e-6)
    assert check_result(result)["values"] == result["hull"].size
    with pytest.raises(ParameterError, match="component= is only for results stacked by component"):
        result.fuzzy.band(0.0, component="LKneeAngles_X")


def test_a_stored_result_reads_the_same(tmp_path) -> None:
    ds = angles_dataset()
    save_result(ds, tmp_path / "fuzzy.nc")
    loaded = load_result(tmp_path / "fuzzy.nc")
    xr.testing.assert_allclose(loaded.fuzzy.delta_phi(), ds.fuzzy.delta_phi())
    check_result(loaded)


@pytest.mark.parametrize(
    ("damage", "needle"),
    [
        ("swap", "lower above upper"),
        ("widen", "not nested"),
        ("split_one", "α = 1 not a single value"),
        ("no_one", "alpha must ascend within"),
        ("dims", "hull has dims"),
    ],
)
def test_check_result_finds_each_defect(damage: str, needle: str) -> None:
    ds = angles_dataset()
    check_result(ds)
    hull = ds["hull"].copy()
    if damage == "swap":
        hull[0, 0, :, 2] = hull[0, 0, ::-1, 2].values
    elif damage == "widen":
        hull[1, 1, 1, 0] = hull[1, 0, 1, 0] + 1.0  # α = 0.5 above α = 0
    elif damage == "split_one":
        hull[0, 2, 1, 3] += 0.1
    ds = ds.assign(hull=hull)
    if damage == "no_one":
        ds = ds.isel(alpha=[0, 1])
    if damage == "dims":
        ds = ds.assign(hull=ds["hull"].transpose("component", "bound", "alpha", "frame"))
    with pytest.raises(ModelCheckError, match=needle):
        check_result(ds)


def test_undetermined_frames_are_not_held_to_nesting() -> None:
    """A band that is undetermined (the segment frame can flip) may be anything there."""
    ds = angles_dataset(undetermined=True)
    hull = ds["hull"].copy()
    hull[0, 0, 0, 1] = -500.0
    check_result(ds.assign(hull=hull))


def test_an_frv_study_keeps_the_schema(tmp_path) -> None:
    from fuzzygait.uncertainty.frv import FRVSpec, FRVStudy, StudyOptions

    times = np.linspace(0.0, 2.0, 15)
    model = FunctionModel(lambda p: np.sin(p[..., :1] * times), times,
                          lambda p: (times * np.cos(p[0] * times))[:, None])  # fmt: skip
    study = FRVStudy.create(model, FRVSpec("p", 1.0), 200, StudyOptions(n_disc=12, seed=3), store=tmp_path / "s.zarr")
    hulls = study.hulls()
    assert hulls.fuzzy.axis == "time" and hulls["hull"].dims[0] == "sample"
    assert check_result(hulls)["values"] > 0


def test_the_marker_error_analysis_of_the_sample_trial_keeps_the_schema(angles_run) -> None:
    """A real analysis (sample walking trial, knee angles, 4 frames): layout, bounds and
    nesting hold, and ΔΦ through the accessor is the analysis' own table."""
    from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles

    frames = np.array([100, 160, 220, 280])
    markers = np.full_like(angles_run.trial.markers, np.nan)
    markers[frames] = angles_run.trial.markers[frames]
    fuzzy = fuzzy_joint_angles(angles_run.trial.with_markers(markers), angles_run.subject, angles_run.result,
                               FuzzyAngleOptions(alphas=(0.0, 0.5), workers=1), ["LKneeAngles"])  # fmt: skip
    assert check_result(fuzzy)["values"] > 0
    table = relative_envelope_width(fuzzy)
    delta = fuzzy.fuzzy.delta_phi()
    for name in table.index:
        np.testing.assert_allclose(delta.sel(component=name, alpha=list(table.columns)).to_numpy(),
                                   table.loc[name].to_numpy(dtype=float), rtol=1e-12)  # fmt: skip
