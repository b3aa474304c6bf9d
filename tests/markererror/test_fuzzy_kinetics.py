"""Fuzzy joint moments: the leg's kinetics as a model of marker and centre-of-pressure
deviations (:mod:`fuzzygait.markererror.moment_model`) and the bands of
:func:`~fuzzygait.markererror.fuzzy_kinetics.fuzzy_joint_moments`.

Truth: a static foot on a plate with a known vertical force, whose ankle moment band for
a centre-of-pressure ball of radius r is ``M ± F r |y_h| / m`` in closed form (``y_h``:
the horizontal part of the foot's flexion axis, 1 for a level axis); the existing
Plug-in Gait kinetics (:func:`~fuzzygait.kinetics.plug_in_gait.plug_in_gait_kinetics`)
at zero deviation; central differences for the gradients; random deviations inside the
balls for the hulls.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import Side
from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d
from fuzzygait.io.subject import read_subject_toml
from fuzzygait.kinematics import compute_lower_body
from fuzzygait.kinetics.inverse_dynamics import ComDerivative, Load
from fuzzygait.kinetics.plug_in_gait import JOINTS, plug_in_gait_kinetics
from fuzzygait.markererror.fuzzy_kinetics import (
    FootGround,
    FuzzyKineticsOptions,
    allowable_kinetic_error,
    foot_ground,
    fuzzy_joint_moments,
)
from fuzzygait.markererror.moment_model import LegKineticsModel, PlateShare, plate_axes
from fuzzygait.markererror.sources import ErrorModel
from fuzzygait.testing import check_model, check_result
from fuzzygait.uncertainty import FuzzyBalls, graph_follower
from support import SAMPLE_DATA, shared_file

#: A level plate whose x, y run along the laboratory's and whose normal points down.
LEVEL_PLATE = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
FORCE_N = 700.0
#: The model's centre-of-mass derivative (five-point, nine-frame windows): what its zero
#: deviation is compared with (plug_in_gait_kinetics defaults to the GCV spline).
FIVE = ComDerivative.FIVE_POINT


def ground_under(trial: Trial, side: Side, force: np.ndarray) -> FootGround:
    """``force`` (N, constant) at the foot's heel-toe midpoint on the floor (z = 0), with
    a free moment of 2 N·m about the vertical, on every frame: one plate."""
    n = trial.n_frames
    cop = 0.5 * (trial.marker(side.value + "HEE") + trial.marker(side.value + "TOE")) * 1e-3
    cop[:, 2] = 0.0
    forces = np.tile(force, (n, 1))
    moment = np.cross(cop, forces) + np.array([0.0, 0.0, 2.0])
    return FootGround(forces, moment, (PlateShare(1, forces, LEVEL_PLATE),))


@pytest.fixture(scope="module")
def sample() -> tuple[Trial, object]:
    return read_c3d(SAMPLE_DATA / "walking.c3d"), read_subject_toml(SAMPLE_DATA / "subject.toml")


@pytest.fixture(scope="module")
def standing(sample: tuple[Trial, object]) -> tuple[Trial, object]:
    """Frame 100 of the sample trial held for 13 frames: every derivative is zero."""
    trial, subject = sample
    markers = np.repeat(trial.markers[100:101], 13, axis=0)
    return Trial(markers=markers, marker_labels=list(trial.marker_labels), rate=trial.rate), subject


def no_marker_error(trial: Trial) -> ErrorModel:
    return ErrorModel(marker_radius=dict.fromkeys(trial.marker_labels, 0.0))


def test_static_foot_band_is_the_cop_ball_times_the_force(standing: tuple[Trial, object]) -> None:
    """Markers exact, the COP within r = 15 mm: the right ankle's sagittal moment band at
    level α is M ± F (1 − α) r |y_h| / m exactly, M the statics of the resting foot."""
    trial, subject = standing
    force = np.array([0.0, 0.0, FORCE_N])
    ground = ground_under(trial, Side.RIGHT, force)
    result = compute_lower_body(trial, subject)
    options = FuzzyKineticsOptions(alphas=(0.0, 0.5), error_model=no_marker_error(trial), cop_error_mm=15.0)
    frames = np.array([5, 6, 7])
    ds = fuzzy_joint_moments(trial, subject, result, {Side.RIGHT: ground}, options, ["RAnkleMoment_X"], frames)
    hull = ds.fuzzy.hull("RAnkleMoment_X").isel(frame=frames)

    # the resting foot: the ground's load and the foot's weight balanced about the AJC
    mass, foot = subject.body_mass, result.segment_frames["right_foot"][6]
    ajc = result.joint_centres["RAJC"][6] * 1e-3
    length = np.mean(np.linalg.norm(trial.marker("RHEE") - trial.marker("RTOE"), axis=1)) - subject.marker_radius
    com = ajc - 0.5 * length * 1e-3 * foot[:, 2]
    weight = 0.0145 * mass * np.array([0.0, 0.0, -9.81])
    cop = np.r_[0.5 * (trial.marker("RHEE")[6] + trial.marker("RTOE")[6])[:2] * 1e-3, 0.0]
    moment = -(np.cross(cop - ajc, force) + np.array([0.0, 0.0, 2.0]) + np.cross(com - ajc, weight))
    measured = foot[:, 1] @ moment / mass
    half = FORCE_N * 0.015 * np.hypot(foot[0, 1], foot[1, 1]) / mass
    for alpha, scale in ((0.0, 1.0), (0.5, 0.5), (1.0, 0.0)):
        expected = np.array([measured - scale * half, measured + scale * half])
        np.testing.assert_allclose(hull.sel(alpha=alpha).to_numpy(), np.tile(expected[:, None], (1, 3)), rtol=1e-9)
    # the same M as the Plug-in Gait kinetics (N·mm/kg)
    load = Load(np.zeros((13, 3)), ground.force, ground.moment)
    nexus_like = plug_in_gait_kinetics(result, trial, subject, {Side.RIGHT: load}, FIVE).outputs["RAnkleMoment"]
    np.testing.assert_allclose(nexus_like[frames, 0] * 1e-3, measured, rtol=1e-9)
    # the allowable answer: half-width s x half <= 0.1 N·m/kg on the levels 0, 0.5, 1
    answer = allowable_kinetic_error(ds, "RAnkleMoment_X", tolerance=0.6 * half)
    assert (answer.scale, answer.failing, answer.cop_mm, answer.marker_mm) == (0.5, 1.0, 7.5, 0.0)
    assert "centre of pressure within 7.5 mm" in answer.sentence


def leg(sample: tuple[Trial, object], kind: str = "Moment") -> LegKineticsModel:
    trial, subject = sample
    ground = ground_under(trial, Side.RIGHT, np.array([40.0, -15.0, FORCE_N]))
    components = tuple((j, a) for j in JOINTS for a in ((0, 1, 2) if kind == "Moment" else (2,)))
    return LegKineticsModel(trial, subject, Side.RIGHT, components, np.arange(4, trial.n_frames - 4, 7),
                            ground.force, ground.moment, ground.plates, kind=kind)  # fmt: skip


@pytest.mark.parametrize("kind", ["Moment", "Power"])
def test_zero_deviation_is_the_plug_in_gait_kinetics(sample: tuple[Trial, object], kind: str) -> None:
    trial, subject = sample
    model = leg(sample, kind)
    values = model.evaluate(np.zeros(model.n_parameters)).values.reshape(model.blocks, -1)
    ground = ground_under(trial, Side.RIGHT, np.array([40.0, -15.0, FORCE_N]))
    load = Load(np.zeros((trial.n_frames, 3)), ground.force, ground.moment)
    result = compute_lower_body(trial, subject)
    outputs = plug_in_gait_kinetics(result, trial, subject, {Side.RIGHT: load}, FIVE).outputs
    scale = 1e-3 if kind == "Moment" else 1.0
    for b, (joint, axis) in enumerate(model.components):
        expected = outputs["R" + joint + kind][model.frames, axis] * scale
        np.testing.assert_allclose(values[b], expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_leg_model_keeps_the_protocol_with_exact_gradients(sample: tuple[Trial, object]) -> None:
    model = leg(sample)
    assert model.parameter_names[-3:] == ("COP1_x", "COP1_y", "COP1_z")
    p = np.random.default_rng(3).normal(0.0, 3.0, model.n_parameters)
    report = check_model(model, p)
    # the nodes compiled (row_kernel), the whole trajectory in numpy: equal to rounding
    assert report["node_gradients_error"] < 1e-4 and report["nodes_error"] < 1e-12
    # the COP's normal coordinate moves nothing; along the plate's x it moves the moment by d x F
    nodes = np.arange(model.times.size)
    _, gradients = model.evaluate_nodes_gradients(np.zeros((nodes.size, model.n_parameters)), nodes)
    assert np.all(gradients[:, -1] == 0.0)


def test_plate_axes_follow_the_c3d_corner_rule() -> None:
    corners = np.array([[600.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 400.0, 0.0], [600.0, 400.0, 0.0]])
    np.testing.assert_allclose(plate_axes(corners), LEVEL_PLATE, atol=1e-15)


def uniform_in_balls(rng: np.random.Generator, radii: np.ndarray, n: int) -> np.ndarray:
    """``(n, 3 × balls)`` deviations uniformly distributed in the balls."""
    direction = rng.standard_normal((n, radii.size, 3))
    direction /= np.linalg.norm(direction, axis=2, keepdims=True)
    return (direction * (radii * rng.random((n, radii.size)) ** (1.0 / 3.0))[..., None]).reshape(n, -1)


def test_bands_hold_every_monte_carlo_sample(sample: tuple[Trial, object]) -> None:
    """300 deviations inside the α = 0 and α = 0.5 balls, markers and COP, on four frames:
    none outside a determined hull; the dataset keeps the result schema.  An undetermined
    bound is no outer bound: its search stopped where a segment frame turned past 91°
    (capability ``"node_limits"``, as an angle's stops 91° from the measured one;
    :func:`test_a_stopped_bound_has_its_witness_in_the_ball`)."""
    trial, subject = sample
    ground = ground_under(trial, Side.RIGHT, np.array([40.0, -15.0, FORCE_N]))
    frames = np.array([60, 140, 220, 300])
    options = FuzzyKineticsOptions(alphas=(0.0, 0.5))
    ds = fuzzy_joint_moments(trial, subject, compute_lower_body(trial, subject), {Side.RIGHT: ground}, options,
                             ["RAnkleMoment_X", "RKneeMoment_X", "RHipMoment_Y"], frames)  # fmt: skip
    assert check_result(ds)["largest_violation"] == 0.0
    assert ds.fuzzy.units == "N·m/kg" and list(ds["marker"].to_numpy()[-1:]) == ["COP1"]
    assert list(ds["cop"].to_numpy()) == [False] * 9 + [True]
    assert float(ds["ball_radius"].sel(marker="COP1")) == 10.0 and float(ds["ball_radius"].sel(marker="RTHI")) == 32.0
    # Table 3.1's full balls turn the thigh, tibia or foot frame by more than 90° here (the
    # fuzzy ankle angles' bands are 120-350° wide at α = 0 on these frames): undetermined
    assert bool(ds.fuzzy.undetermined(0.0).isel(frame=frames).all())
    assert not bool(ds.fuzzy.undetermined(1.0).any())
    model = leg(sample)
    model = replace(model, components=(("Ankle", 0), ("Knee", 0), ("Hip", 1)), frames=frames)
    radii = ds["ball_radius"].to_numpy()
    rng = np.random.default_rng(0)
    checked = 0
    for alpha in (0.0, 0.5):
        P = uniform_in_balls(rng, (1.0 - alpha) * radii, 300)
        values = np.stack([model.evaluate(p).values for p in P]).reshape(300, 3, frames.size)
        hull = ds["hull"].sel(alpha=alpha).isel(frame=frames).to_numpy()  # (component, bound, frame)
        determined = ~ds["undetermined"].sel(alpha=alpha).isel(frame=frames).to_numpy()  # (component, frame)
        below, above = hull[None, :, 0] - values, values - hull[None, :, 1]
        assert np.max(np.where(determined[None], np.maximum(below, above), -np.inf)) <= 0.0, alpha
        checked += int(determined.sum())
    assert checked >= 4  # not vacuous: α = 0.5 leaves determined bands on these frames


def test_a_stopped_bound_has_its_witness_in_the_ball(sample: tuple[Trial, object]) -> None:
    """The Graph Follower on the leg (Table 3.1's 32 mm balls at α = 0 and 0.5, a 10 mm COP
    ball): every bound whose extremiser the model calls beyond its limits lies in its α-ball
    and turns a segment frame more than 90° over the nine frames (numpy's chain, not the
    compiled check), so the band it leaves undetermined has its witness; such bounds occur
    at α = 0 and the hull is finite everywhere."""
    model = replace(leg(sample), components=(("Ankle", 0), ("Knee", 0)), frames=np.array([60, 140, 220, 300]))
    radii = np.array([32.0] * len(model.markers) + [10.0])
    params = FuzzyBalls(np.zeros((radii.size, 3)), radii, tuple(model.ball_names))
    result = graph_follower(model, params, (0.0, 0.5, 1.0), strategy=FuzzyKineticsOptions().strategy())
    assert np.all(np.isfinite(result.hull.to_numpy()))
    extremiser = result["extremiser"].to_numpy()  # (alpha, bound, node, n_p)
    nodes = np.arange(model.times.size)
    stopped = 0
    for a, alpha in enumerate((0.0, 0.5, 1.0)):
        for b in range(2):
            points = extremiser[a, b]
            _, beyond = model.evaluate_nodes_limited(points, nodes)
            norms = np.linalg.norm(points.reshape(nodes.size, -1, 3), axis=2)
            assert np.all(norms <= (1.0 - alpha) * radii + 1e-9)
            turn = model.frame_turn(points, np.tile(model.frames, model.blocks))
            assert np.all(turn[beyond] > 90.0), (alpha, b)
            stopped += int(beyond.sum())
    assert stopped > 0


def test_bad_options_are_one_line(standing: tuple[Trial, object]) -> None:
    trial, subject = standing
    result = compute_lower_body(trial, subject)
    with pytest.raises(ParameterError, match=r"^kind must be one of Moment, Power; got 'Force'$"):
        fuzzy_joint_moments(trial, subject, result, {}, FuzzyKineticsOptions(kind="Force"))
    with pytest.raises(ParameterError, match=r"^the centre-of-pressure error must be a distance >= 0 mm; got -1"):
        fuzzy_joint_moments(trial, subject, result, {}, FuzzyKineticsOptions(cop_error_mm=-1.0))
    with pytest.raises(ParameterError, match=r"^'LKneeAngles_X' is not a moment output of a leg joint"):
        fuzzy_joint_moments(trial, subject, result, {}, outputs=["LKneeAngles_X"])
    with pytest.raises(ParameterError, match=r"^body mass must be positive \(kg\) for kinetics; got 0.0$"):
        fuzzy_joint_moments(trial, replace(subject, body_mass=0.0), result, {})


def test_a_subset_of_the_markers_keeps_the_others_where_measured(sample: tuple[Trial, object]) -> None:
    full = leg(sample)
    part = replace(full, markers=["RTOE", "RANK"])
    assert part.parameter_names[:6] == ("RTOE_x", "RTOE_y", "RTOE_z", "RANK_x", "RANK_y", "RANK_z")
    np.testing.assert_array_equal(part.evaluate(np.zeros(part.n_parameters)).values,
                                  full.evaluate(np.zeros(full.n_parameters)).values)  # fmt: skip
    with pytest.raises(ParameterError, match=r"^the right leg's kinetics are computed from LASI, RASI, .*; got LHEE$"):
        replace(full, markers=["LHEE"])


def test_a_static_leg_generates_no_power_whatever_the_cop(standing: tuple[Trial, object]) -> None:
    """Powers in W/kg: a leg at rest has none, at every level of the COP ball."""
    trial, subject = standing
    ground = ground_under(trial, Side.RIGHT, np.array([0.0, 0.0, FORCE_N]))
    options = FuzzyKineticsOptions(alphas=(0.0,), error_model=no_marker_error(trial), kind="Power")
    ds = fuzzy_joint_moments(trial, subject, compute_lower_body(trial, subject), {Side.RIGHT: ground}, options,
                             frames=np.array([6]))  # fmt: skip
    assert list(ds["component"].to_numpy()) == ["LAnklePower_Z", "LKneePower_Z", "LHipPower_Z", "RAnklePower_Z",
                                                "RKneePower_Z", "RHipPower_Z"]  # fmt: skip
    assert ds.fuzzy.units == "W/kg" and ds.attrs["output"] == "joint power"
    np.testing.assert_array_equal(ds["hull"].isel(frame=6).to_numpy(), 0.0)
    cop = ds["deviation"].sel(marker="COP1", component="RAnklePower_Z").isel(frame=6).to_numpy()
    assert np.all(cop <= 15.0 + 1e-9)


def test_movement_trial_plates_give_the_nexus_matched_kinetics() -> None:
    """Movement_trial (skips without ../shared): each foot's load from the plates Nexus
    used (:func:`foot_ground`) — its plate shares add up to it, the plates' normals point
    down — and at zero deviation every moment and power of both legs is the Plug-in Gait
    kinetics' (which agree with Nexus', tests/kinetics)."""
    from fuzzygait.io.subject import subject_from_processing
    from fuzzygait.kinetics.assignment import stored_assignment
    from fuzzygait.kinetics.plates import read_force_plates

    path = shared_file("vicon", "Movement_trial.c3d")
    trial = read_c3d(path)
    subject = subject_from_processing(trial.parameters)
    plates = read_force_plates(path, threshold_n=0.0)
    ground = {side: foot_ground(plates, stored_assignment(plates, trial.outputs, side, subject.body_mass,
                                                          trial.rate).plate, trial.rate) for side in Side}  # fmt: skip
    assert [p.number for p in ground[Side.LEFT].plates] == [1] and [p.number for p in ground[Side.RIGHT].plates] == [4]
    loads = {side: Load(np.zeros((trial.n_frames, 3)), g.force, g.moment) for side, g in ground.items()}
    outputs = plug_in_gait_kinetics(compute_lower_body(trial, subject), trial, subject, loads, FIVE).outputs
    frames = np.arange(4, trial.n_frames - 4)
    for side, g in ground.items():
        np.testing.assert_array_equal(sum(p.force for p in g.plates), g.force)
        assert all(p.axes[2, 2] < -0.999 for p in g.plates)
        for kind, scale in (("Moment", 1e-3), ("Power", 1.0)):
            components = tuple((j, a) for j in JOINTS for a in ((0, 1, 2) if kind == "Moment" else (2,)))
            model = LegKineticsModel(trial, subject, side, components, frames, g.force, g.moment, g.plates, kind=kind)
            values = model.evaluate(np.zeros(model.n_parameters)).values.reshape(model.blocks, -1)
            for b, (joint, axis) in enumerate(components):
                expected = outputs[side.value + joint + kind][frames, axis] * scale
                np.testing.assert_allclose(values[b], expected, rtol=0.0, atol=1e-12)


def test_contacts_ground_is_the_assignments_load_with_its_plate_shares() -> None:
    """Two synthetic plates (1000 Hz, markers at 100 Hz) and the automatic assignment's
    contacts: the foot's load equals :func:`~fuzzygait.kinetics.assignment.contact_ground`'s
    and each plate's share is its load on its contact's frames."""
    from types import SimpleNamespace

    from fuzzygait.kinetics.assignment import PlateContact, contact_ground
    from fuzzygait.markererror.fuzzy_kinetics import contacts_ground

    n, samples = 40, 400
    corners = np.array([[600.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 400.0, 0.0], [600.0, 400.0, 0.0]])
    plates = []
    for number, shift in ((1, 0.0), (2, 600.0)):
        force = np.tile([10.0 * number, 0.0, 600.0], (samples, 1))
        cop = np.tile([300.0 + shift, 200.0, 0.0], (samples, 1))
        plates.append(SimpleNamespace(number=number, rate=1000.0, force=force, cop=cop,
                                      free_moment=np.zeros((samples, 3)), contact=np.ones(samples, dtype=bool),
                                      corners=corners + [shift, 0.0, 0.0]))  # fmt: skip
    contacts = [PlateContact(1, 5, 14, Side.LEFT), PlateContact(2, 20, 29, Side.LEFT), PlateContact(2, 30, 35, None)]
    ground = contacts_ground(plates, contacts, Side.LEFT, n, 100.0)
    expected = contact_ground(plates, contacts, Side.LEFT, n, 100.0)
    np.testing.assert_array_equal(ground.force, expected.force)
    np.testing.assert_array_equal(ground.moment, expected.moment)
    assert [p.number for p in ground.plates] == [1, 2]
    np.testing.assert_allclose(ground.plates[0].force[5:15], np.tile([10.0, 0.0, 600.0], (10, 1)), rtol=1e-12)
    np.testing.assert_array_equal(ground.plates[0].force[15:], 0.0)
    np.testing.assert_array_equal(ground.plates[0].force + ground.plates[1].force, ground.force)
    np.testing.assert_allclose(ground.plates[1].axes, LEVEL_PLATE, atol=1e-15)


@pytest.mark.parametrize("kind", ["Moment", "Power"])
def test_the_compiled_leg_equals_numpy(sample: tuple[Trial, object], kind: str) -> None:
    """The kinetics compiled (:mod:`fuzzygait.markererror.row_kernel`: chain on the nine
    frames and Newton–Euler traced once) against the same code on numpy with autograd:
    values within 1e-11 and gradients within 1e-10 (N·m/kg or W/kg, per mm), at marker
    and COP deviations of 5 and 40 mm; a row with a marker missing in its window is NaN
    in both (its compiled gradient NaN too); the model pickles without its library."""
    import pickle

    model = leg(sample, kind)
    assert model.kernel() is not None
    markers = model.trial.markers.copy()
    markers[model.frames[3] + 2, model.trial.marker_labels.index("RKNE")] = np.nan  # inside frame 3's window
    gapped = replace(model, trial=replace(model.trial, markers=markers))
    rng = np.random.default_rng(7)
    P = np.vstack([rng.normal(0.0, 5.0, (40, model.n_parameters)), rng.normal(0.0, 40.0, (40, model.n_parameters))])
    nodes = rng.integers(0, model.times.size, P.shape[0])
    nodes[:3] = [3, model.frames.size + 3, 4]
    for compiled in (model, gapped, pickle.loads(pickle.dumps(model))):
        plain = replace(compiled, compiled=False)
        values, gradients = compiled.evaluate_nodes_gradients(P, nodes)
        expected, expected_gradients = plain.evaluate_nodes_gradients(P, nodes)
        np.testing.assert_allclose(values, expected, rtol=0, atol=1e-11)
        defined = np.isfinite(expected)  # numpy's gradient of an undefined row may be partly finite
        np.testing.assert_allclose(gradients[defined], expected_gradients[defined], rtol=1e-9, atol=1e-10)
        assert np.isnan(gradients[~defined]).all()
        np.testing.assert_allclose(compiled.evaluate_nodes(P, nodes), expected, rtol=0, atol=1e-11)
    assert np.isnan(gapped.evaluate_nodes(P[:3], nodes[:3])[:2]).all() and np.isfinite(values[2])


@pytest.mark.slow  # compiles the KAD subject's leg kinetics (12 s on a fresh clone)
def test_unsettled_compiled_rows_take_numpy(sample: tuple[Trial, object]) -> None:
    """With the KAD's rotation offsets the rotated chord runs fixed steps in C; rows far
    outside any ball (100 mm) that they do not settle are computed by numpy — the same
    values and gradients as the numpy model's."""
    from fuzzygait.markererror.row_kernel import UNSETTLED

    trial, subject = sample
    kad = subject.with_side("R", thigh_rotation=0.12, shank_rotation=-0.09)  # type: ignore[attr-defined]
    model = leg((trial, kad))
    kernel = model.kernel()
    assert kernel is not None
    rng = np.random.default_rng(11)
    P = rng.normal(0.0, 100.0, (60, model.n_parameters))
    nodes = rng.integers(0, model.times.size, P.shape[0])
    j, _ = model._selected(nodes)
    _, status = kernel.values(model._kernel_rows(), j, P, model._kernel_shared())
    assert np.any(status == UNSETTLED)
    plain = replace(model, compiled=False)
    expected, expected_gradients = plain.evaluate_nodes_gradients(P, nodes)
    np.testing.assert_allclose(model.evaluate_nodes(P, nodes), expected, rtol=0, atol=1e-9)
    values, gradients = model.evaluate_nodes_gradients(P, nodes)
    np.testing.assert_allclose(values, expected, rtol=0, atol=1e-9)
    defined = np.isfinite(expected)
    np.testing.assert_allclose(gradients[defined], expected_gradients[defined], rtol=1e-8, atol=1e-9)
