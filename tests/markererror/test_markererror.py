"""The spherical fuzzy marker-error model (thesis §3.7, §5.5): error sources (Table 3.1),
soundness of the Graph Follower hulls against Monte Carlo sampling, an analytic worst
case, Cartesian vs spherical formulation (§3.7.2), ΔΦ (Eq. 5.3), the result layout and
the comparison methods of Fig. 5.11.

Speed: the Plug-in Gait models are restricted to 8 frames spread over the sample trial
(``JointAngleModel(frames=...)``, or a copy of the trial whose markers are NaN outside
those frames for :func:`fuzzy_joint_angles`, which skips frames with missing markers).
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles, relative_envelope_width
from fuzzygait.markererror.angle_model import AXES, JointAngleModel, fixed_subject
from fuzzygait.markererror.comparison import (
    DIAGONAL,
    deviation_norms,
    fixed_deviation_curves,
    monte_carlo_envelope,
    random_deviation_curves,
)
from fuzzygait.markererror.result import (
    AngleAxes,
    angle_components,
    ball_radius,
    component_deviation,
    component_hull,
    error_sources,
    fuzzy_angles_dataset,
)
from fuzzygait.markererror.sources import TABLE_3_1, ErrorModel, parse_sources, read_error_model
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower
from fuzzygait.workflows.angles import AnglesRun
from support import TwoMarkerLine

JOINTS = ("Hip", "Knee", "Ankle")
N_FRAMES = 8


@pytest.fixture(scope="module")
def frames(angles_run: AnglesRun) -> np.ndarray:
    """8 sample indices spread over the trial (0-based)."""
    return np.linspace(0, angles_run.trial.n_frames - 1, N_FRAMES).round().astype(int)


@pytest.fixture(scope="module")
def sparse_trial(angles_run: AnglesRun, frames: np.ndarray) -> Trial:
    """The trial with every marker NaN outside ``frames``: fuzzy_joint_angles then only
    works on those 8 frames."""
    markers = np.full_like(angles_run.trial.markers, np.nan)
    markers[frames] = angles_run.trial.markers[frames]
    return angles_run.trial.with_markers(markers)


def angle_model(run: AnglesRun, name: str, axis: int, frames: np.ndarray) -> JointAngleModel:
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis, frames)


def balls(model: JointAngleModel, sources: tuple[str, ...] = ("measurement", "placement", "sta")) -> FuzzyBalls:
    radii = ErrorModel().radii(model.markers, sources)
    return FuzzyBalls(np.zeros((len(model.markers), 3)), np.array([radii[m] for m in model.markers]),
                      tuple(model.markers))  # fmt: skip


# ---------------------------------------------------------------------------- soundness
@pytest.mark.slow
@pytest.mark.parametrize("side", ["L", "R"])
def test_hulls_contain_monte_carlo(angles_run: AnglesRun, frames: np.ndarray, side: str) -> None:
    """At α = 0 and 0.5, for every hip/knee/ankle component, the Graph Follower hull
    contains the range of 10,000 uniform random deviations per frame (same balls).
    Both are inner bounds of the true range; the GFA's should reach further."""
    ratios = []
    for joint in JOINTS:
        for axis in range(3):
            model = angle_model(angles_run, f"{side}{joint}Angles", axis, frames)
            params = balls(model)
            result = graph_follower(model, params, (0.0, 0.5), strategy=BatchedDirect())
            for k, alpha in enumerate((0.0, 0.5)):
                radii = (1.0 - alpha) * params.support_radii
                lower, upper = monte_carlo_envelope(model, radii, 10_000, seed=100 + k)
                hull = result["hull"].sel(alpha=alpha)
                gfa_lower, gfa_upper = hull.sel(bound="lower").to_numpy(), hull.sel(bound="upper").to_numpy()
                label = f"{side}{joint}Angles_{AXES[axis]} alpha={alpha}"
                # transverse angles can reach ±180 deg here (the thigh plane flips with
                # 32 mm balls): then the containment is trivial, but still must hold
                assert np.all(gfa_upper >= upper - 1e-9), (label, gfa_upper - upper)
                assert np.all(gfa_lower <= lower + 1e-9), (label, lower - gfa_lower)
                ratios.append((label, (gfa_upper - gfa_lower) / (upper - lower)))
    every = np.concatenate([r for _, r in ratios])
    print(f"\n{side}: GFA hull width / Monte Carlo width: mean {every.mean():.3f}, min {every.min():.3f}")
    for label, r in ratios:
        print(f"  {label:28s} mean {r.mean():.3f} min {r.min():.3f}")
    assert every.min() >= 1.0 - 1e-12


# ---------------------------------------------------------------------------- analytic case
def test_two_marker_angle_worst_case_is_arcsin() -> None:
    """Balls of radius r around two markers at distance d: the line turns by at most
    arcsin(2r/d) either way (the inner common tangent of the two circles); at level α
    the radius is (1 − α) r. The batched direct mode reproduces it to 1e-6 rad."""
    model, r = TwoMarkerLine(), 30.0
    result = graph_follower(model, FuzzyBalls(np.zeros((2, 3)), [r, r], ("A", "B")), (0.0, 0.25, 0.5, 0.75),
                            strategy=BatchedDirect())  # fmt: skip
    assert result.attrs["strategy"] == "batched-direct"  # the all-nodes batched solver ran
    deterministic = model.evaluate(np.zeros(6)).values
    for alpha in (0.0, 0.25, 0.5, 0.75):
        exact = np.arcsin(2 * (1 - alpha) * r / model.distance)
        hull = result["hull"].sel(alpha=alpha)
        np.testing.assert_allclose(hull.sel(bound="upper") - deterministic, exact, rtol=0, atol=1e-6)
        np.testing.assert_allclose(deterministic - hull.sel(bound="lower"), exact, rtol=0, atol=1e-6)
        # the extremising deviations lie on the ball surfaces
        norms = np.linalg.norm(result["extremiser"].sel(alpha=alpha).to_numpy().reshape(2, -1, 2, 3), axis=-1)
        np.testing.assert_allclose(norms, (1 - alpha) * r, rtol=1e-6)


# ---------------------------------------------------------------------------- formulations
@pytest.mark.slow
def test_cartesian_and_spherical_give_the_same_envelopes(angles_run: AnglesRun, sparse_trial: Trial,
                                                         frames: np.ndarray) -> None:  # fmt: skip
    """Thesis §3.7.2: the norm-constrained Cartesian deviations and the box-constrained
    spherical ones (r, θ, φ) give the same joint-angle envelopes.

    Both runs are local multistart optimisations of the same hull, so they agree only up
    to their convergence. Measured on these 8 frames (hip and knee flexion, Table 3.1,
    6 starts, 50 iterations, seeds 0-4): |Cartesian − spherical| is at most 8.7 % and on
    average <= 4 % of the hull width at that frame and α; the spherical run differs from
    *itself* across seeds by up to 9.2 % (its box has artificial seams at φ = ±π and
    poles at θ = 0, π on which the local search stalls), the Cartesian by <= 1.5 %. So
    the difference is the spherical optimiser's own scatter, not a different envelope;
    the bounds asserted (12 % max, 5 % mean) leave margin above the measured scatter.
    """
    options = dict(alphas=(0.0, 0.5), starts=6, iterations=50, seed=0)
    angles = ["LHipAngles", "LKneeAngles"]
    fuzzy = {method: fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result,
                                        FuzzyAngleOptions(method=method, **options), angles)
             for method in ("cartesian", "spherical")}  # fmt: skip
    print()
    for name in ("LHipAngles_X", "LKneeAngles_X"):
        cartesian = component_hull(fuzzy["cartesian"], name).sel(alpha=[0.0, 0.5]).isel(frame=frames).to_numpy()
        spherical = component_hull(fuzzy["spherical"], name).sel(alpha=[0.0, 0.5]).isel(frame=frames).to_numpy()
        width = cartesian[:, 1] - cartesian[:, 0]  # (alpha, frame)
        difference = np.abs(cartesian - spherical).max(axis=1)
        relative = difference / width
        print(f"{name}: max |cartesian - spherical| = {difference.max():.2f} deg "
              f"({100 * relative.max():.1f} % of the hull width, mean {100 * relative.mean():.1f} %)")  # fmt: skip
        assert relative.max() <= 0.12
        assert relative.mean() <= 0.05
    for method in ("cartesian", "spherical"):
        norms = component_deviation(fuzzy[method], "LKneeAngles_X").sel(alpha=0.0).isel(frame=frames)
        radius = fuzzy[method]["ball_radius"].sel(marker=norms["marker"])
        assert bool(((norms <= radius + 1e-9) | norms.isnull()).all())


# ---------------------------------------------------------------------------- sources
def test_table_3_1_sums() -> None:
    model = ErrorModel()
    expected = {"pelvis": 32, "thigh": 32, "shank": 30, "ankle": 20, "foot": 7}
    assert {s: sum(v.values()) for s, v in TABLE_3_1.items()} == expected
    for label, radius in {"LASI": 32, "RPSI": 32, "SACR": 32, "LTHI": 32, "LKNE": 32, "RTIB": 30,
                          "LANK": 20, "RHEE": 7, "LTOE": 7}.items():  # fmt: skip
        assert model.radius(label) == radius, label


def test_single_sources() -> None:
    model = ErrorModel()
    labels = ["LASI", "LTHI", "LKNE", "LTIB", "LANK", "LTOE"]
    assert set(model.radii(labels, ["measurement"]).values()) == {2.0}
    assert model.radii(labels, ["placement"]) == {"LASI": 15, "LTHI": 10, "LKNE": 10, "LTIB": 8, "LANK": 8, "LTOE": 5}
    assert model.radii(labels, ["sta"]) == {"LASI": 15, "LTHI": 20, "LKNE": 20, "LTIB": 20, "LANK": 10, "LTOE": 0}
    assert model.radius("LKNE", parse_sources("measurement, placement")) == 12.0
    assert parse_sources("sta,measurement,sta") == ("sta", "measurement")
    with pytest.raises(ParameterError, match="noise"):
        parse_sources("measurement,noise")
    with pytest.raises(ParameterError, match="'LFOO'"):
        model.radius("LFOO")


def test_toml_overrides(tmp_path) -> None:  # noqa: ANN001
    path = tmp_path / "errors.toml"
    path.write_text(
        "[segments.thigh]\nplacement = 12.0\n\n"
        "[markers.LKNE]\nradius = 25.0\n\n"
        "[markers.RKNE]\nsta = 15\n\n"
        "[markers.CUSTOM]\nradius = 4.5\n",
        encoding="utf-8",
    )
    model = read_error_model(path)
    assert model.radius("LTHI") == 2 + 12 + 20  # segment override
    assert model.radius("LKNE") == 25.0  # fixed total radius, whatever the sources
    assert model.radius("LKNE", ["measurement"]) == 25.0
    assert model.radius("RKNE") == 2 + 12 + 15  # per-source marker override on the segment's row
    assert model.radius("RKNE", ["placement"]) == 12.0
    assert model.radius("CUSTOM") == 4.5  # a marker unknown to Table 3.1, given a radius
    assert model.radius("LTIB") == 30.0  # untouched
    assert str(path) in model.source


@pytest.mark.parametrize(
    ("text", "needles"),
    [
        ("[segments.thigh\nplacement = 1", ["not a valid TOML"]),
        ("[markers.LKNE]\nradius = -3.0\n", ["markers.LKNE", "radius", "-3.0"]),
        ("[segments.thigh]\nsta = -1\n", ["segments.thigh", "sta"]),
        ("[markers.LKNE]\nradious = 3.0\n", ["markers.LKNE", "'radious'"]),
        ("[segments.arm]\nsta = 1.0\n", ["'arm'"]),
        ("[markers.LKNE]\nradius = \"big\"\n", ["markers.LKNE", "radius"]),
        ("[marker.LKNE]\nradius = 3.0\n", ["'marker'"]),
        ("[segments]\nthigh = 3.0\n", ["segments.thigh"]),
    ],
)
def test_bad_error_files(tmp_path, text: str, needles: list[str]) -> None:  # noqa: ANN001
    path = tmp_path / "errors.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ParameterError) as info:
        read_error_model(path)
    message = str(info.value)
    assert str(path) in message
    for needle in needles:
        assert needle in message, message


def test_missing_error_file(tmp_path) -> None:  # noqa: ANN001
    with pytest.raises(ParameterError, match="no such errors file"):
        read_error_model(tmp_path / "absent.toml")


def test_larger_source_sets_give_wider_envelopes(
    angles_run: AnglesRun, sparse_trial: Trial, frames: np.ndarray
) -> None:
    """Fig. 5.9: the balls of measurement ⊂ placement and measurement ⊂ measurement +
    placement ⊂ all three are nested, and so are the α = 0 knee envelopes."""
    hulls = {}
    all_three = ("measurement", "placement", "sta")
    for sources in (("measurement",), ("placement",), ("measurement", "placement"), all_three):
        options = FuzzyAngleOptions(alphas=(0.0,), sources=sources)
        fuzzy = fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result, options, ["LKneeAngles"])
        assert error_sources(fuzzy) == sources and fuzzy["error_source"].dims == ("error_source",)
        assert fuzzy["ball_radius"].sel(marker="LKNE") == ErrorModel().radius("LKNE", sources)
        hulls[sources] = {name: component_hull(fuzzy, name).sel(alpha=0.0).isel(frame=frames)
                          for name in ("LKneeAngles_X", "LKneeAngles_Y")}  # fmt: skip
    chains = [(("measurement",), ("placement",)), (("measurement",), ("measurement", "placement")),
              (("measurement", "placement"), all_three)]  # fmt: skip
    for small, large in chains:
        for name in ("LKneeAngles_X", "LKneeAngles_Y"):
            inner, outer = hulls[small][name], hulls[large][name]
            assert bool((outer.sel(bound="upper") >= inner.sel(bound="upper")).all()), (small, large, name)
            assert bool((outer.sel(bound="lower") <= inner.sel(bound="lower")).all()), (small, large, name)
            width = lambda h: float((h.sel(bound="upper") - h.sel(bound="lower")).mean())  # noqa: E731
            assert width(outer) > width(inner)


# ---------------------------------------------------------------------------- ΔΦ (Eq. 5.3)
def test_relative_envelope_width_by_hand() -> None:
    """ΔΦ_α = max_t (upper − lower) / max_t |Φ| in %, NaN frames skipped."""
    phi = np.array([10.0, 40.0, 20.0, np.nan])
    hull = np.array([
        [[0.0, 20.0, 10.0, np.nan], [30.0, 60.0, 25.0, np.nan]],  # α = 0: widths 30, 40, 15
        [[5.0, 30.0, 18.0, np.nan], [15.0, 48.0, 22.0, np.nan]],  # α = 0.5: widths 10, 18, 4
        [phi, phi],
    ])  # fmt: skip
    negative = -hull[:, ::-1]  # mirrored angle: Φ = −10, −40, −20; reference |−40|
    fuzzy = fuzzy_angles_dataset({"LKneeAngles_X": hull, "LHipAngles_Y": negative}, AngleAxes(alphas=[0.0, 0.5, 1.0],
                                 frames=[1, 2, 3, 4], times=[0.0, 0.01, 0.02, 0.03], markers=["LKNE"],
                                 ball_radius=[32.0]))  # fmt: skip
    table = relative_envelope_width(fuzzy)
    assert list(table.columns) == [0.5, 0.0]
    assert sorted(table.index) == ["LHipAngles_Y", "LKneeAngles_X"]
    assert table.loc["LKneeAngles_X", 0.0] == pytest.approx(100.0 * 40 / 40)
    assert table.loc["LKneeAngles_X", 0.5] == pytest.approx(100.0 * 18 / 40)
    assert table.loc["LHipAngles_Y", 0.0] == pytest.approx(100.0)
    assert table.loc["LHipAngles_Y", 0.5] == pytest.approx(45.0)


def test_relative_envelope_width_of_an_angle_zero_throughout_is_infinite_without_a_warning() -> None:
    """A band around an angle that is 0° at every frame has no relative width: inf (NaN
    where the band has no width either), quietly, beside a normal component."""
    zero = np.zeros(3)
    hull = np.array([[zero - 2.0, zero + 2.0], [zero, zero], [zero, zero]])  # α = 0: width 4; α = 0.5: none
    knee = np.array([[[8.0, 18.0, 28.0], [12.0, 22.0, 32.0]], [[9.0, 19.0, 29.0], [11.0, 21.0, 31.0]],
                     [[10.0, 20.0, 30.0], [10.0, 20.0, 30.0]]])  # fmt: skip
    fuzzy = fuzzy_angles_dataset({"LKneeAngles_X": knee, "LFootProgressAngles_Y": hull},
                                 AngleAxes(alphas=[0.0, 0.5, 1.0], frames=[1, 2, 3], times=[0.0, 0.01, 0.02],
                                           markers=["LKNE"], ball_radius=[32.0]))  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = relative_envelope_width(fuzzy)
    assert table.loc["LFootProgressAngles_Y", 0.0] == np.inf and np.isnan(table.loc["LFootProgressAngles_Y", 0.5])
    assert table.loc["LKneeAngles_X", 0.0] == pytest.approx(100.0 * 4 / 30)
    assert table.loc["LKneeAngles_X", 0.5] == pytest.approx(100.0 * 2 / 30)


# ---------------------------------------------------------------------------- result layout
def test_dataset_layout_and_missing_markers(angles_run: AnglesRun, frames: np.ndarray) -> None:
    """Variables, dims and coordinates of the result; NaN exactly on the frames where a
    marker the angle needs is missing; deviation norms inside the α-level balls."""
    keep = np.zeros(angles_run.trial.n_frames, dtype=bool)
    keep[frames] = True
    keep[100:106] = True
    cut = np.array([frames[2], 101, 103])  # LKNE missing here
    markers = np.where(keep[:, None, None], angles_run.trial.markers, np.nan)
    markers[cut, angles_run.trial.marker_labels.index("LKNE")] = np.nan
    trial = angles_run.trial.with_markers(markers)
    alphas = (0.0, 0.5)
    fuzzy = fuzzy_joint_angles(trial, angles_run.subject, angles_run.result, FuzzyAngleOptions(alphas=alphas),
                               ["LPelvisAngles", "LKneeAngles"])  # fmt: skip

    components = [f"{n}_{a}" for n in ("LPelvisAngles", "LKneeAngles") for a in AXES]
    assert set(fuzzy.data_vars) == {"hull", "undetermined", "deviation", "ball_radius"}
    assert fuzzy["undetermined"].dims == ("component", "alpha", "frame") and fuzzy["undetermined"].dtype == bool
    assert fuzzy["label"].sel(component="LKneeAngles_X") == "Left knee, sagittal (+ flexion)"
    assert fuzzy.attrs["model"] == "cgm1.0" and fuzzy["hull"].attrs["long_name"]
    assert angle_components(fuzzy) == components
    assert fuzzy["angle"].to_numpy().tolist() == [c[:-2] for c in components]
    assert fuzzy["axis"].to_numpy().tolist() == [c[-1] for c in components]
    assert fuzzy["hull"].dims == ("component", "alpha", "bound", "frame") and fuzzy["hull"].attrs["units"] == "deg"
    assert fuzzy["deviation"].dims == ("component", "alpha", "bound", "frame", "marker")
    assert fuzzy["deviation"].attrs["units"] == fuzzy["ball_radius"].attrs["units"] == "mm"
    assert fuzzy["alpha"].to_numpy().tolist() == [0.0, 0.5, 1.0]
    assert fuzzy["bound"].to_numpy().tolist() == ["lower", "upper"]
    np.testing.assert_array_equal(fuzzy["frame"], angles_run.trial.frames)
    np.testing.assert_allclose(fuzzy["time"], angles_run.trial.times)
    knee_markers = ["LASI", "RASI", "LPSI", "RPSI", "LTHI", "LKNE", "LTIB", "LANK"]
    assert fuzzy["marker"].to_numpy().tolist() == knee_markers
    for c in components:
        assert component_hull(fuzzy, c).dims == ("alpha", "bound", "frame")
        assert component_deviation(fuzzy, c).dims == ("alpha", "bound", "frame", "marker")
    assert fuzzy["ball_radius"].to_numpy().tolist() == [32, 32, 32, 32, 32, 32, 30, 20]
    assert "sources" not in fuzzy.attrs
    assert fuzzy["error_source"].to_numpy().tolist() == ["measurement", "placement", "sta"]
    assert {"trial", "method", "units", "strategy", "forward_simulations", "node_evaluations",
            "seconds"} <= set(fuzzy.attrs)  # fmt: skip
    assert fuzzy.attrs["method"] == "cartesian" and fuzzy.attrs["node_evaluations"] > 0
    settings = {key: fuzzy.attrs[key] for key in ("solver", "starts", "iterations", "stride", "follow")}
    assert settings == {"solver": "spectral", "starts": 5, "iterations": 40, "stride": 8, "follow": 8}  # provenance

    knee_ok = keep.copy()
    knee_ok[cut] = False
    for name, ok in (("LPelvisAngles_X", keep), ("LKneeAngles_X", knee_ok), ("LKneeAngles_Z", knee_ok)):
        finite = np.isfinite(component_hull(fuzzy, name).to_numpy())
        assert np.all(finite[..., ok]) and not np.any(finite[..., ~ok]), name
        # α = 1 is the measured angle
        measured = angles_run.result.angles[name[:-2]][ok, AXES.index(name[-1])]
        np.testing.assert_allclose(component_hull(fuzzy, name).sel(alpha=1.0, bound="upper")[ok], measured, atol=1e-9)

    # deviations: NaN for markers the angle does not use, inside the α-level balls
    pelvis = component_deviation(fuzzy, "LPelvisAngles_X")
    assert bool(pelvis.sel(marker=["LTHI", "LKNE", "LTIB", "LANK"]).isnull().all())
    for name in ("LPelvisAngles_Y", "LKneeAngles_X", "LKneeAngles_Y"):
        norms = component_deviation(fuzzy, name)
        limit = ball_radius(fuzzy) * (1.0 - fuzzy["alpha"]) + 1e-9
        assert bool(((norms <= limit) | norms.isnull()).all()), name
        assert bool((norms.sel(alpha=1.0).fillna(0.0) == 0.0).all())
    # the convenience view for Fig. 5.12
    view = deviation_norms(fuzzy, "LKneeAngles_X", ["LPSI", "LKNE"])
    assert view.dims == ("alpha", "bound", "frame", "marker")
    assert view["alpha"].to_numpy().tolist() == [0.0, 0.5]
    assert deviation_norms(fuzzy, "LPelvisAngles_X")["marker"].to_numpy().tolist() == ["LASI", "RASI", "LPSI", "RPSI"]
    with pytest.raises(ParameterError, match="LKNE"):
        deviation_norms(fuzzy, "LPelvisAngles_X", ["LKNE"])
    with pytest.raises(ParameterError, match="LAnkleAngles_X"):
        deviation_norms(fuzzy, "LAnkleAngles_X")


# ---------------------------------------------------------------------------- Fig. 5.11 helpers
def test_fixed_deviation_curves(angles_run: AnglesRun, frames: np.ndarray) -> None:
    model = angle_model(angles_run, "LKneeAngles", 0, frames)
    radii = balls(model).support_radii
    curves = fixed_deviation_curves(model, radii)
    assert set(curves) == {"none", "positive", "negative"}
    np.testing.assert_allclose(curves["none"], angles_run.result.angles["LKneeAngles"][frames, 0], atol=1e-9)
    shift = (radii[:, None] * DIAGONAL).ravel()
    np.testing.assert_allclose(curves["positive"], model.evaluate(shift).values)
    np.testing.assert_allclose(curves["negative"], model.evaluate(-shift).values)
    np.testing.assert_allclose(np.linalg.norm(shift.reshape(-1, 3), axis=1), radii)  # on the spheres
    assert np.all(np.abs(curves["positive"] - curves["none"]) > 1e-3)
    with pytest.raises(ParameterError, match="one radius per marker"):
        fixed_deviation_curves(model, radii[:-1])


def test_monte_carlo_envelope_chunks_and_modes(angles_run: AnglesRun, frames: np.ndarray) -> None:
    model = angle_model(angles_run, "LKneeAngles", 0, frames)
    radii = balls(model).support_radii
    lower, upper = monte_carlo_envelope(model, radii, 500, seed=3)
    assert lower.shape == upper.shape == (frames.size,)
    deterministic = model.evaluate(np.zeros(model.n_parameters)).values
    assert np.all(lower < deterministic) and np.all(deterministic < upper)
    # the chunk size (rows per model call) does not change the result
    again = monte_carlo_envelope(model, radii, 500, seed=3, chunk_rows=7 * frames.size + 3)
    np.testing.assert_array_equal(again[0], lower)
    np.testing.assert_array_equal(again[1], upper)
    # whole curves (one deviation per sample kept over all frames) on a subset of frames:
    # the envelope of the same seed's random curves at those frames
    sub = monte_carlo_envelope(model, radii, 200, seed=1, frames=[0, 5], per_frame=False)
    curves = random_deviation_curves(model, radii, 200, seed=1, per_frame=False)
    assert curves.shape == (200, frames.size)
    np.testing.assert_allclose(sub[0], curves[:, [0, 5]].min(axis=0))
    np.testing.assert_allclose(sub[1], curves[:, [0, 5]].max(axis=0))
    noisy = random_deviation_curves(model, radii, 3, seed=1)  # fresh deviations per frame
    assert noisy.shape == (3, frames.size) and np.all(np.isfinite(noisy))
    # zero radii: no spread
    flat = monte_carlo_envelope(model, np.zeros_like(radii), 20, seed=0)
    np.testing.assert_allclose(flat[0], deterministic, atol=1e-9)
    np.testing.assert_allclose(flat[1], deterministic, atol=1e-9)
    for bad in ({"n_samples": 0}, {"frames": [frames.size]}):
        with pytest.raises(ParameterError):
            monte_carlo_envelope(model, radii, **{"n_samples": 10, **bad})
    with pytest.raises(ParameterError, match=">= 0"):
        monte_carlo_envelope(model, -radii, 10)


def test_uniform_ball_samples_fill_the_ball() -> None:
    from fuzzygait.markererror.comparison import uniform_ball_deviations

    radii = np.array([2.0, 32.0, 0.0])
    P = uniform_ball_deviations(np.random.default_rng(0), 20_000, radii).reshape(-1, 3, 3)
    norms = np.linalg.norm(P, axis=-1)
    assert np.all(norms <= radii + 1e-12)
    # uniform in volume: P(|p| <= r/2) = 1/8, mean direction ~ 0
    assert abs(np.mean(norms[:, 1] <= 16.0) - 0.125) < 0.01
    assert np.all(np.abs(P[:, 1].mean(axis=0)) < 0.5)
    assert pd.Series(norms[:, 2]).eq(0).all()



def test_two_frames_are_enough(angles_run: AnglesRun) -> None:
    """A component with fewer optimisation nodes than the neighbour window still runs:
    finite hulls around the measured angle at the two frames, NaN elsewhere."""
    keep = np.zeros(angles_run.trial.n_frames, dtype=bool)
    keep[[10, 60]] = True
    trial = angles_run.trial.with_markers(np.where(keep[:, None, None], angles_run.trial.markers, np.nan))
    options = FuzzyAngleOptions(alphas=(0.0,), starts=2, iterations=5)
    fuzzy = fuzzy_joint_angles(trial, angles_run.subject, angles_run.result, options, ["LKneeAngles"])
    hull = component_hull(fuzzy, "LKneeAngles_X").sel(alpha=0.0).to_numpy()
    assert np.isfinite(hull[:, keep]).all() and np.isnan(hull[:, ~keep]).all()
    measured = angles_run.result.angles["LKneeAngles"][keep, 0]
    assert np.all(hull[0, keep] < measured) and np.all(measured < hull[1, keep])


# ---------------------------------------------------------------------------- continuous bands
def test_a_band_across_180_degrees_is_one_band(angles_run: AnglesRun, sparse_trial: Trial) -> None:
    """Turning the progression frame by 180° about the vertical moves the pelvis rotation
    (Z) to about ±180°: wrapped, its band would be 360° wide; on the continuous branch it
    is the band of the unturned trial moved by 180° (same width), and determined."""
    import dataclasses

    from fuzzygait.kinematics.angles import joint_angles
    from fuzzygait.kinematics.vectors import axis_rotation

    result = angles_run.result
    turned_progression = result.progression @ axis_rotation(2, np.pi)
    pelvis = result.segment_frames["pelvis"]
    turned = dataclasses.replace(result, progression=turned_progression,
                                 angles={"LPelvisAngles": joint_angles(turned_progression, pelvis, "Pelvis", "L")})  # fmt: skip
    options = FuzzyAngleOptions(alphas=(0.0,), sources=("measurement",))
    plain = fuzzy_joint_angles(sparse_trial, angles_run.subject, result, options, ["LPelvisAngles"])
    across = fuzzy_joint_angles(sparse_trial, angles_run.subject, turned, options, ["LPelvisAngles"])
    hull, hull_turned = component_hull(plain, "LPelvisAngles_Z"), component_hull(across, "LPelvisAngles_Z")
    measured = hull_turned.sel(alpha=1.0, bound="upper")
    assert np.nanmin(np.abs(np.abs(measured) - 180.0)) < 10.0  # the measured angle is near ±180
    width = (hull.sel(bound="upper") - hull.sel(bound="lower")).sel(alpha=0.0)
    width_turned = (hull_turned.sel(bound="upper") - hull_turned.sel(bound="lower")).sel(alpha=0.0)
    assert float(width.max()) > 0.5  # a real band
    np.testing.assert_allclose(width_turned.dropna("frame"), width.dropna("frame"), atol=1e-6)
    assert not bool(across["undetermined"].any())


def test_undetermined_marks_bounds_more_than_a_quarter_turn_away() -> None:
    from fuzzygait.markererror.undetermined import UNDETERMINED_DEG, undetermined

    measured = np.array([10.0, 10.0, 10.0, 170.0])
    lower = np.array([-79.0, -81.0, 5.0, 100.0])
    upper = np.array([99.0, 20.0, 101.0, 260.5])
    assert UNDETERMINED_DEG == 90.0
    assert undetermined(lower, upper, measured).tolist() == [False, True, True, True]


def test_single_components_are_analysed_alone_with_the_same_hull(angles_run: AnglesRun, sparse_trial: Trial) -> None:
    """``angles=["LKneeAngles_X", "RHipAngles_X"]`` analyses those two components only
    (the report's ``--uncertainty fast``), each with the hull the whole angle's run gives
    it: the same optimisation with the same seed, the whole angle's components sharing
    the model calls (:func:`~fuzzygait.markererror.analysis.run_angle_task`), so equal up
    to the rounding of batched array operations (measured: bit-identical)."""
    options = FuzzyAngleOptions(alphas=(0.0, 0.5))
    alone = fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result, options,
                               ["LKneeAngles_X", "RHipAngles_X"])  # fmt: skip
    assert list(alone["component"].values) == ["LKneeAngles_X", "RHipAngles_X"]
    whole = fuzzy_joint_angles(sparse_trial, angles_run.subject, angles_run.result, options, ["LKneeAngles"])
    np.testing.assert_allclose(component_hull(alone, "LKneeAngles_X").to_numpy(),
                               component_hull(whole, "LKneeAngles_X").to_numpy(), rtol=0, atol=1e-9)  # fmt: skip
