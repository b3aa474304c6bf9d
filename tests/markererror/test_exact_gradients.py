"""Exact gradients of the joint angles with respect to the marker deviations (issue 15,
Deliver 5): reverse-mode automatic differentiation through the kinematic model
(:func:`fuzzygait.markererror.angle_model.row_gradients`), with closed-form reverse
sweeps for the vector primitives and the polar rotation of the cluster fit.

Truth: central differences of the model itself (step 1e-4 mm, error ≈ 1e-9 °/mm), for
every angle and component of every model version and for Plug-in Gait with non-zero
static offsets (thigh/shank rotation, tibial torsion, AnkleAbAdd); the engine's hulls
with exact gradients against those with forward differences.
"""

from __future__ import annotations

import dataclasses

import autograd.numpy as anp
import numpy as np
import pytest
from autograd import grad
from autograd.test_util import check_grads

from fuzzygait.core.errors import ParameterError
from fuzzygait.kinematics import vectors
from fuzzygait.kinematics.angles import capped_arcsin
from fuzzygait.kinematics.rigid import polar_rotation
from fuzzygait.kinematics.versions import MODEL_VERSIONS
from fuzzygait.markererror.angle_model import AngleComponentsModel, JointAngleModel, fixed_subject
from fuzzygait.markererror.spherical import SphericalDeviationModel
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower
from fuzzygait.uncertainty.counting import CountedModel
from fuzzygait.uncertainty.gfa.batched import BatchCounts, BatchedObjective
from fuzzygait.uncertainty.protocol import NODE_GRADIENTS, NODES, Evaluation, Output, model_problem
from fuzzygait.workflows.angles import AnglesRun, run_angles
from support import SAMPLE_DATA

CGM24 = {"static": SAMPLE_DATA / "cgm24_static.c3d", "subject_file": SAMPLE_DATA / "cgm24_subject.toml"}
PIG = {"static": SAMPLE_DATA / "static.c3d", "subject_file": SAMPLE_DATA / "subject.toml"}
FRAMES = np.array([40, 200, 360])
#: Central-difference step (mm) and the agreement asked for (°/mm): the differences' own
#: truncation and rounding error is ≈ 1e-9 °/mm at this step.
STEP, TOLERANCE = 1e-4, 1e-6


@pytest.fixture(scope="module")
def cgm24_runs() -> dict[str, AnglesRun]:
    """The synthetic CGM 2.4 walking trial by every model version (same markers)."""
    return {model: run_angles(SAMPLE_DATA / "cgm24_walking.c3d", model=model, **CGM24) for model in MODEL_VERSIONS}


@pytest.fixture(scope="module")
def pig_offsets_run() -> AnglesRun:
    """Plug-in Gait on the synthetic walking trial, with non-zero static offsets on the
    left side: the thigh and shank wands' rotations (the KAD's results), tibial torsion
    and AnkleAbAdd all enter the chain the gradients pass through."""
    run = run_angles(SAMPLE_DATA / "walking.c3d", model="cgm1.0", **PIG)
    subject = run.subject.with_side("L", thigh_rotation=0.12, shank_rotation=-0.09, tibial_torsion=0.3,
                                    ankle_abadd=0.06)  # fmt: skip
    return dataclasses.replace(run, subject=subject)


def model_of(run: AnglesRun, name: str, axis: int, frames: np.ndarray = FRAMES) -> JointAngleModel:
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis,
                           frames, model=run.model, clusters=run.clusters)  # fmt: skip


def central_differences(model: JointAngleModel | SphericalDeviationModel, P: np.ndarray,
                        nodes: np.ndarray) -> np.ndarray:  # fmt: skip
    """``(k, n_p)`` central differences of ``model.evaluate_nodes`` per row."""
    out = np.empty_like(P)
    for i in range(P.shape[1]):
        plus, minus = P.copy(), P.copy()
        plus[:, i] += STEP
        minus[:, i] -= STEP
        out[:, i] = (model.evaluate_nodes(plus, nodes) - model.evaluate_nodes(minus, nodes)) / (2 * STEP)
    return out


def assert_gradients(model: JointAngleModel | SphericalDeviationModel, P: np.ndarray) -> None:
    nodes = np.arange(P.shape[0])
    values, gradients = model.evaluate_nodes_gradients(P, nodes)
    np.testing.assert_array_equal(values, model.evaluate_nodes(P, nodes))  # the same numbers as without
    reference = central_differences(model, P, nodes)
    assert np.all(np.isfinite(reference)) and np.all(np.isfinite(gradients))
    np.testing.assert_allclose(gradients, reference, rtol=TOLERANCE, atol=TOLERANCE)
    assert np.abs(reference).max() > 0.01  # the angle does depend on the deviations


def deviations(model: JointAngleModel, scale: float = 5.0, seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).normal(scale=scale, size=(model.frames.size, model.n_parameters))


# ---------------------------------------------------------------------------- the models
@pytest.mark.parametrize("model", MODEL_VERSIONS)
def test_gradients_of_every_angle_match_central_differences(cgm24_runs: dict[str, AnglesRun], model: str) -> None:
    """Every left angle and component of every version (cgm2.3/2.4: the cluster fits and
    their polar rotation; cgm2.4: the forefoot), at random deviations of 5 mm."""
    run = cgm24_runs[model]
    names = [name for name in run.result.angles if name.startswith("L") and name != "LFootProgressAngles"]
    assert "LKneeAngles" in names and ("LForeFootAngles" in names) == (model == "cgm2.4")
    for name in names:
        for axis in range(3):
            angle = model_of(run, name, axis)
            assert_gradients(angle, deviations(angle))


@pytest.mark.parametrize("name", ["LHipAngles", "LKneeAngles", "LAnkleAngles"])
def test_gradients_with_static_offsets_match_central_differences(pig_offsets_run: AnglesRun, name: str) -> None:
    for axis in range(3):
        angle = model_of(pig_offsets_run, name, axis)
        assert_gradients(angle, deviations(angle, seed=axis))


def test_spherical_gradients_match_central_differences(cgm24_runs: dict[str, AnglesRun]) -> None:
    """With respect to (r mm, θ, φ rad) per marker (the box parametrisation)."""
    cartesian = model_of(cgm24_runs["cgm2.4"], "LKneeAngles", 0)
    rng = np.random.default_rng(3)
    n = len(cartesian.markers)
    P = np.stack([rng.uniform(1.0, 10.0, (3, n)), rng.uniform(0.2, 2.9, (3, n)), rng.uniform(-3.0, 3.0, (3, n))],
                 axis=-1).reshape(3, -1)  # fmt: skip
    assert_gradients(SphericalDeviationModel(cartesian), P)


def test_a_missing_marker_gives_nan_in_its_row_only(cgm24_runs: dict[str, AnglesRun]) -> None:
    """Plug-in Gait knee with the thigh marker missing at one frame: that row's value and
    gradient are NaN, the other rows are those of the complete trial."""
    run = cgm24_runs["cgm1.0"]
    markers = run.trial.markers.copy()
    markers[FRAMES[1], run.trial.marker_labels.index("LTHI")] = np.nan
    gapped = dataclasses.replace(run, trial=run.trial.with_markers(markers))
    complete, missing = model_of(run, "LKneeAngles", 0), model_of(gapped, "LKneeAngles", 0)
    P = deviations(complete)
    nodes = np.arange(3)
    values, gradients = missing.evaluate_nodes_gradients(P, nodes)
    full_values, full_gradients = complete.evaluate_nodes_gradients(P, nodes)
    assert np.isnan(values[1]) and np.all(np.isnan(gradients[1]))
    np.testing.assert_allclose(values[[0, 2]], full_values[[0, 2]], rtol=0, atol=1e-12)
    np.testing.assert_allclose(gradients[[0, 2]], full_gradients[[0, 2]], rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------- primitives
def test_vector_primitives_reverse_sweeps_with_broadcasting() -> None:
    """norm, unit, dot, cross against autograd's own numerical check, with one operand
    broadcast over the frames (its gradient is summed back to its shape)."""
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=(5, 3)), rng.normal(size=3)
    check_grads(lambda v: anp.sum(vectors.norm(v) ** 2 * anp.arange(5.0)), modes=["rev"], order=1)(a)
    check_grads(lambda v: anp.sum(vectors.unit(v) * a), modes=["rev"], order=1)(a + 0.5)
    for function in (vectors.dot, vectors.cross):
        shape = function(a, b).shape
        weights = np.sin(np.arange(np.prod(shape))).reshape(shape)
        check_grads(lambda x, y, f=function, w=weights: anp.sum(f(x, y) * w), modes=["rev"], order=1)(a, b)
        assert grad(lambda y, f=function: anp.sum(f(a, y)))(b).shape == (3,)


def test_capped_arcsin_has_a_finite_slope_at_the_cap() -> None:
    """The Cardan middle angle's asin: the exact derivative inside (-1, 1), a finite
    steep one at ±1 (gimbal lock: the plain chain rule through a clip gives NaN)."""
    slope = np.vectorize(grad(capped_arcsin))
    x = np.array([-0.9, 0.0, 0.5])
    np.testing.assert_allclose(slope(x), 1.0 / np.sqrt(1.0 - x**2), rtol=1e-12)
    at_cap = slope(np.array([-1.0, 1.0, 1.0 + 1e-15]))
    assert np.all(np.isfinite(at_cap)) and np.all(at_cap >= 1e5)
    np.testing.assert_array_equal(capped_arcsin(np.array([1.0 + 1e-15, -1.0 - 1e-15])), [np.pi / 2, -np.pi / 2])


def test_polar_rotation_reverse_sweep_matches_differences() -> None:
    """The closed-form reverse sweep of the polar rotation, by central differences, for
    covariances with positive (Newton) and negative (SVD) determinant."""
    rng = np.random.default_rng(5)
    covariance = rng.normal(size=(6, 3, 3)) + 2.0 * np.eye(3)
    covariance[3:] *= np.array([1.0, 1.0, -1.0])  # det < 0: the SVD branch with the reflection fix
    determinants = np.linalg.det(covariance)
    assert np.any(determinants > 0) and np.any(determinants < 0)
    weights = rng.normal(size=(6, 3, 3))

    def objective(c: np.ndarray) -> np.ndarray:
        return anp.sum(polar_rotation(c) * weights)

    exact = grad(objective)(covariance)
    step, reference = 1e-6, np.empty_like(covariance)
    for index in np.ndindex(covariance.shape):
        plus, minus = covariance.copy(), covariance.copy()
        plus[index] += step
        minus[index] -= step
        reference[index] = (objective(plus) - objective(minus)) / (2 * step)
    np.testing.assert_allclose(exact, reference, rtol=1e-6, atol=1e-7)
    rotations = polar_rotation(covariance)
    np.testing.assert_allclose(np.linalg.det(rotations), 1.0, atol=1e-12)


# ---------------------------------------------------------------------------- the engine
def test_exact_and_differenced_gradients_give_the_same_hulls(cgm24_runs: dict[str, AnglesRun]) -> None:
    """The batched optimiser with the model's gradients reaches the hull of the one with
    forward differences (0.01° agreement) while evaluating fewer node rows."""
    angle = model_of(cgm24_runs["cgm2.4"], "LKneeAngles", 0)
    radii = np.full(len(angle.markers), 10.0)
    balls = FuzzyBalls(np.zeros((len(angle.markers), 3)), radii, tuple(angle.markers))
    results = {source: graph_follower(angle, balls, (0.0, 0.5, 1.0), strategy=BatchedDirect(gradients=source))
               for source in ("auto", "differences")}  # fmt: skip
    exact, differences = (results[s]["hull"].to_numpy() for s in ("auto", "differences"))
    np.testing.assert_allclose(exact, differences, atol=0.01)
    assert np.all(exact[0, 1] - exact[0, 0] > 1.0)  # a real band, not the measured angle
    assert results["auto"].attrs["gradient_source"] == "exact" and results["auto"].attrs["node_gradients"] > 0
    assert results["differences"].attrs["gradient_source"] == "forward differences"
    assert results["differences"].attrs["node_gradients"] == 0
    assert results["auto"].attrs["node_evaluations"] < results["differences"].attrs["node_evaluations"] / 2


@pytest.mark.parametrize("exact", [True, False])
def test_one_objective_call_serves_both_bounds(cgm24_runs: dict[str, AnglesRun], exact: bool) -> None:
    """Bound node ``b · n_time + t``: the lower bound's rows are the negated angle and
    gradient at frame ``t``, the upper bound's the angle itself (exact and differenced)."""
    angle = model_of(cgm24_runs["cgm2.4"], "LKneeAngles", 0)
    n_time = angle.frames.size
    scale = np.ones(angle.n_parameters)
    objective = BatchedObjective(CountedModel(angle, scale), np.array([-1.0, 1.0]), n_time, scale, 1e-6,
                                 BatchCounts(), exact)  # fmt: skip
    P = np.concatenate([deviations(angle)] * 2)
    frames = np.arange(n_time)
    values, gradients = objective.values_and_gradients(P, np.concatenate([frames, frames + n_time]))
    truth, truth_gradients = angle.evaluate_nodes_gradients(P[:n_time], frames)
    np.testing.assert_allclose(values, np.concatenate([-truth, truth]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(gradients, np.concatenate([-truth_gradients, truth_gradients]), rtol=0,
                               atol=1e-12 if exact else 1e-4)  # fmt: skip


@pytest.mark.parametrize("name, model", [("LKneeAngles", "cgm2.4"), ("LAnkleAngles", "cgm1.0")])
def test_the_components_together_are_each_component_alone(cgm24_runs: dict[str, AnglesRun], name: str,
                                                          model: str) -> None:  # fmt: skip
    """:class:`AngleComponentsModel`: node ``b · n_frames + j`` gives the value and exact
    gradient of component ``axes[b]`` alone at frame ``j`` (on the branch through its
    reference; to rounding, measured bit for bit), rows of every component mixed in one
    call; and each block's gradient still matches central differences."""
    run = cgm24_runs[model]
    alone = [model_of(run, name, axis) for axis in (2, 0, 1)]
    references = np.stack([run.result.angles[name][FRAMES, axis] + 170.0 for axis in (2, 0, 1)])
    for single, reference in zip(alone, references, strict=True):
        single.reference = reference  # a reference far from the angle: the branch matters
    together = AngleComponentsModel(alone[0], (2, 0, 1), references)
    assert together.blocks == 3 and together.times.size == 3 * FRAMES.size
    n = FRAMES.size
    P = np.concatenate([deviations(alone[0], seed=s) for s in range(3)])
    nodes = np.random.default_rng(0).permutation(3 * n)
    values, gradients = together.evaluate_nodes_gradients(P, nodes)
    for b, single in enumerate(alone):
        rows = np.flatnonzero(nodes // n == b)
        value, gradient = single.evaluate_nodes_gradients(P[rows], nodes[rows] % n)
        np.testing.assert_allclose(values[rows], value, rtol=0, atol=1e-12)
        np.testing.assert_allclose(gradients[rows], gradient, rtol=0, atol=1e-12)
    assert_gradients(together, P)
    with pytest.raises(ParameterError, match=r"references must be \(components, frames\) = \(2, 3\)"):
        AngleComponentsModel(alone[0], (0, 1), references)


def test_an_unknown_gradient_source_is_refused() -> None:
    with pytest.raises(ParameterError, match="gradients must be one of auto, differences; got 'exact'"):
        BatchedDirect(gradients="exact")


class _NodesOnly:
    """A model declaring node gradients without providing them."""

    times = np.arange(3.0)
    parameter_names = ("a",)
    output = Output("y", "1")
    capabilities = frozenset({NODES, NODE_GRADIENTS})

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        return Evaluation(np.full(3, float(p[0])))

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        return P[:, 0]


def test_declaring_node_gradients_without_the_method_is_named() -> None:
    assert model_problem(_NodesOnly()) == (
        "_NodesOnly declares 'node_gradients' but not 'nodes' with evaluate_nodes_gradients(P, nodes)")
