"""Every model of the package keeps the engine's model protocol
(:func:`fuzzygait.testing.check_model`): declared attributes, shapes, finiteness,
determinism, sensitivities against central finite differences, single-node evaluations
against whole trajectories. And check_model itself finds each kind of defect."""

from __future__ import annotations

import numpy as np
import pytest

from support import SAMPLE_DATA
from fuzzygait.testing import AnalyticRecipe, ModelCheckError, check_model
from fuzzygait.uncertainty import Evaluation, FunctionModel, FuzzyModel, Output
from fuzzygait.uncertainty.execution import Evaluator


@pytest.fixture(scope="module")
def angles_run():
    from fuzzygait.workflows.angles import run_angles

    return run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


def joint_angle_model(run, name: str = "LKneeAngles", axis: int = 0):
    from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject

    frames = np.linspace(0, run.trial.n_frames - 1, 6).round().astype(int)
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis, frames)


def test_function_and_analytic_models() -> None:
    t = np.linspace(0.0, 1.0, 11)
    report = check_model(FunctionModel(lambda p: p[0] * t**2 + p[1], t, lambda p: np.column_stack([t**2, 1 + 0 * t])),
                         np.array([2.0, 0.5]))  # fmt: skip
    assert report["sensitivity_error"] < 1e-8
    check_model(FunctionModel(lambda p: np.sin(p[0] * t), t), np.array([1.0]))
    for kind in ("sin", "poly"):
        assert check_model(AnalyticRecipe(kind).build(), np.array([0.7, 1.3]))["sensitivity_error"] < 1e-6


def test_pendulum() -> None:
    from fuzzygait.mechanics.pendulum import Pendulum

    model = Pendulum(times=np.linspace(0.0, 1.0, 51))
    assert isinstance(model, FuzzyModel)
    assert check_model(model, np.array([1.0]))["sensitivity_error"] < 1e-5


def test_joint_angle_models(angles_run) -> None:
    from fuzzygait.markererror.spherical import SphericalDeviationModel

    cartesian = joint_angle_model(angles_run)
    p = np.random.default_rng(1).uniform(-5.0, 5.0, cartesian.n_parameters)
    report = check_model(cartesian, p, scale=np.full(p.size, 10.0))
    assert report["nodes_error"] <= 1e-9 and 0.0 < report["node_gradients_error"] <= 1e-4
    spherical = SphericalDeviationModel(cartesian)
    q = np.tile([4.0, 1.0, 0.5], len(cartesian.markers))
    assert 0.0 < check_model(spherical, q)["node_gradients_error"] <= 1e-4
    assert spherical.parameter_names[:3] == (f"{cartesian.markers[0]}_r", f"{cartesian.markers[0]}_theta",
                                             f"{cartesian.markers[0]}_phi")  # fmt: skip
    assert cartesian.output == Output("LKneeAngles_X", "deg")


def test_angle_components_model(angles_run) -> None:
    """The three components of one angle as one model: ``blocks`` and ``time_step``
    declared and kept (the frames are 6 of the trial's, whole numbers of its period)."""
    from fuzzygait.markererror.angle_model import AngleComponentsModel
    from fuzzygait.markererror.spherical import SphericalDeviationModel

    angle = joint_angle_model(angles_run)
    references = np.array([angles_run.result.angles["LKneeAngles"][angle.frames, axis] for axis in range(3)])
    model = AngleComponentsModel(angle, (0, 1, 2), references)
    p = np.random.default_rng(2).uniform(-5.0, 5.0, angle.n_parameters)
    assert check_model(model, p, scale=np.full(p.size, 10.0))["nodes_error"] <= 1e-9
    assert model.blocks == 3 and model.time_step == 1.0 / angles_run.trial.rate
    spherical = SphericalDeviationModel(model)
    assert spherical.blocks == 3 and check_model(spherical, np.tile([4.0, 1.0, 0.5], len(angle.markers)))


@pytest.mark.slow
def test_leg_target_model() -> None:
    from fuzzygait.mechanics.scenarios import LegSimulator
    from fuzzygait.mechanics.solver import SolverSettings
    from fuzzygait.mechanics.targets import LegTargetModel

    # uncompiled (CasADi's virtual machine, the same functions): the contract is what is checked here, and
    # 30 steps do not repay a 15 s compilation; tests/mechanics/test_mechanics_native.py checks that the
    # compiled stepper agrees with these functions
    swing = LegSimulator("swing", nodes=6, compile=False)
    base = swing.parameters(eta=1e5)
    for scheme in ("variational", "energy-momentum"):
        model = LegTargetModel(swing, "total_deformation_energy", ("E", "rho"), base=base,
                               settings=SolverSettings(duration=0.03, scheme=scheme))
        p = np.array([base[0], base[2]])
        report = check_model(model, p, fd_step=1e-5, sensitivity_rtol=1e-3)
        assert report["sensitivity_error"] < 1e-3, scheme


@pytest.mark.slow
def test_layered_blade_model(monkeypatch: pytest.MonkeyPatch) -> None:
    from fuzzygait.mechanics.layered_blade import LayeredBladeModel

    monkeypatch.setenv("FUZZYGAIT_NO_COMPILE", "1")  # 20 steps: uncompiled, as test_leg_target_model

    model = LayeredBladeModel(target="toe_z", nodes=8, duration=0.02, dt=1e-3, tip_force=(0.0, 0.0, 100.0))
    check_model(model, model.base)


def test_evaluated_model_on_the_serial_evaluator() -> None:
    recipe = AnalyticRecipe("sin", n_time=21)
    with Evaluator() as evaluator:
        model = evaluator.model(recipe, sensitivities=True)
        report = check_model(model, np.array([1.0, 2.0]))
    assert report["nodes_error"] == 0.0 and report["sensitivity_error"] < 1e-6


class Broken:
    """A model whose defects are switched on one at a time."""

    def __init__(self, defect: str) -> None:
        self.defect = defect
        self.times = np.linspace(0.0, 1.0, 5)
        self.parameter_names = ("a", "b") if defect == "names" else ("a",)
        self.output = Output()
        self.capabilities = frozenset({"sensitivities", "nodes", "node_gradients", "many", "blocks", "time_step"})
        if defect == "undeclared":
            self.capabilities = frozenset({"magic"})
        if defect == "unused_nodes":  # has evaluate_nodes(_gradients), declares neither
            self.capabilities -= {"nodes", "node_gradients"}
        if defect == "unused_blocks":  # has blocks, does not declare it
            self.capabilities -= {"blocks"}
        self.blocks = 2 if defect == "blocks" else 1
        self.time_step = 0.3 if defect == "time_step" else 0.25  # the times are 0.25 apart
        self.calls = 0

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation | np.ndarray:
        self.calls += 1
        values = p[0] * self.times
        if self.defect == "array":
            return values
        if self.defect == "shape":
            values = values[:-1]
        if self.defect == "nan":
            values = values.copy()
            values[2] = np.nan
        if self.defect == "random":
            values = values + 1e-3 * self.calls
        jacobian = self.times[:, None] * (2.0 if self.defect == "jacobian" else 1.0)
        return Evaluation(values, jacobian if sensitivities else None)

    def evaluate_nodes(self, P: np.ndarray, nodes: np.ndarray) -> np.ndarray:
        offset = 1.0 if self.defect == "nodes" else 0.0
        return P[:, 0] * self.times[nodes] + offset

    def evaluate_nodes_gradients(self, P: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        slope = self.times[nodes] * (1.1 if self.defect == "node_gradients" else 1.0)
        return self.evaluate_nodes(P, nodes), slope[:, None]

    def evaluate_many(self, P: np.ndarray) -> np.ndarray:
        return P[:, :1] * self.times[None, :] * (1.01 if self.defect == "many" else 1.0)

    def evaluate_many_with_sensitivities(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        jacobians = np.broadcast_to(self.times[None, :, None], (P.shape[0], self.times.size, 1))
        return self.evaluate_many(P), jacobians * (2.0 if self.defect == "many_sensitivities" else 1.0)


@pytest.mark.parametrize(
    ("defect", "needle"),
    [
        ("array", "expected an Evaluation"),
        ("shape", "shape"),
        ("nan", "non-finite"),
        ("random", "deterministic"),
        ("jacobian", "finite differences"),
        ("nodes", "evaluate_nodes differs"),
        ("node_gradients", "node gradients differ from central differences"),
        ("names", "2 parameter names"),
        ("undeclared", "unknown capabilities"),
        ("unused_nodes", "has evaluate_nodes_gradients, evaluate_nodes but does not declare 'node_gradients', 'nodes'"),
        ("unused_blocks", "has blocks but does not declare 'blocks'"),
        ("blocks", r"blocks \(2\) do not divide its 5 time nodes"),
        ("time_step", "time_step 0.3 does not divide the steps"),
        ("many", "evaluate_many gives other trajectories"),
        ("many_sensitivities", "evaluate_many_with_sensitivities gives other"),
    ],
)
def test_check_model_finds_each_defect(defect: str, needle: str) -> None:
    check_model(Broken("none"), np.array([2.0]))
    with pytest.raises(ModelCheckError, match=needle):
        check_model(Broken(defect), np.array([2.0]))


def test_the_engine_uses_only_declared_capabilities() -> None:
    """A model's ``blocks`` and ``time_step`` count only when declared."""
    from fuzzygait.uncertainty.protocol import declared_blocks, declared_time_step

    declared, unused = Broken("none"), Broken("unused_blocks")
    declared.blocks = unused.blocks = 5
    assert declared_blocks(declared) == 5 and declared_blocks(unused) == 1
    assert declared_time_step(declared) == 0.25 and declared_time_step(Broken("unused_nodes")) == 0.25
    unused.capabilities -= {"time_step"}
    assert declared_time_step(unused) is None


def test_check_model_names_what_is_missing() -> None:
    with pytest.raises(ModelCheckError, match="plain function"):
        check_model(lambda p: p, np.array([1.0]))
    with pytest.raises(ModelCheckError, match="lacks .*parameter_names"):
        check_model(type("Old", (), {"times": np.arange(3.0), "evaluate": lambda self, p: p})(), np.array([1.0]))
