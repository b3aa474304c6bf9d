"""SolverSettings (issue 38.4): one validated object for the simulator's solver settings,
typed solver failures, and runs unchanged (to the rounding of the CPU).

Truth: ``data/solver_settings_reference.npz``, written by the code before SolverSettings
existed (commit ce6009d, ``FUZZYGAIT_NO_COMPILE=1``: CasADi's virtual machine and the Python
Newton loop) — the swing at 6 nodes, eta = 1e5, 0.03 s at the scenario's dt with
sensitivities for both schemes (``LegSimulator.run(p, duration=0.03, sensitivities=True,
scheme=...)``), a run refined to 4 sub-steps (``integrate(model, q0, p, 4e-3, 10,
max_iterations=6)``) and the messages of a Newton failure and of a fold.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError, SimulationError
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.presets import COMMAND_DEFAULTS, STANCE, SWING
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import BladeFolded, NewtonNotConverged, SolverError, SolverSettings
from fuzzygait.mechanics.targets import LegModelRecipe

REFERENCE = Path(__file__).with_name("data") / "solver_settings_reference.npz"
#: The reference was written on another CPU: numpy's SIMD kernels and the maths library
#: round differently on each (measured on two machines: at most 2.5e-11 of a variable's
#: largest value), so a run agrees with it to rounding; counts and times exactly.
ROUNDING = 1e-10


def assert_same_run(values: np.ndarray, reference: np.ndarray, name: str) -> None:
    """``values`` are ``reference`` up to the rounding of another CPU (:data:`ROUNDING`
    of the largest value; NaN where it is NaN)."""
    assert values.shape == reference.shape and np.array_equal(np.isnan(values), np.isnan(reference)), name
    scale = float(np.nanmax(np.abs(reference))) if reference.size else 0.0
    assert np.nanmax(np.abs(values - reference), initial=0.0) <= ROUNDING * scale, name
VARIABLES = ("position", "total_energy", "dissipated_energy", "total_deformation_energy",
             "total_deformation_energy_sensitivity", "newton_iterations", "time")  # fmt: skip


@pytest.fixture(scope="module")
def swing() -> LegSimulator:
    return LegSimulator("swing", nodes=6, compile=False)  # uncompiled, as the reference was made


def test_defaults_are_the_old_defaults() -> None:
    settings = SolverSettings()
    assert (settings.dt, settings.duration, settings.n_steps, settings.steps) == (1e-3, 2.0, None, 2000)
    assert (settings.scheme, settings.engine, settings.substeps, settings.max_halvings) == ("variational", "auto", 1, 3)
    assert (settings.tolerance, settings.constraint_tolerance, settings.max_iterations) == (1e-10, 1e-11, 25)
    assert SWING.solver == STANCE.solver == settings
    assert COMMAND_DEFAULTS["stance"].solver(STANCE) == settings.derive(scheme="energy-momentum")
    assert COMMAND_DEFAULTS["swing"].solver(SWING) == settings


def test_derive_switches_between_duration_and_steps() -> None:
    settings = SolverSettings(dt=2e-3, duration=0.1)
    assert settings.steps == 50
    by_steps = settings.derive(n_steps=7)
    assert (by_steps.duration, by_steps.n_steps, by_steps.steps, by_steps.dt) == (None, 7, 7, 2e-3)
    assert by_steps.derive(duration=0.02).steps == 10
    assert settings.derive(scheme="energy-momentum").steps == 50
    assert hash(settings) == hash(SolverSettings(dt=2e-3, duration=0.1))
    assert pickle.loads(pickle.dumps(settings)) == settings


@pytest.mark.parametrize(
    ("changes", "needles"),
    [
        ({"dt": 0.0}, ("dt", "> 0 s")),
        ({"dt": float("nan")}, ("dt", "> 0 s")),
        ({"dt": "1ms"}, ("dt", "number")),
        ({"duration": 0.0}, ("duration", "≥ dt")),
        ({"duration": float("inf")}, ("duration", "≥ dt")),
        ({"duration": 0.1, "n_steps": 100}, ("duration", "n_steps", "not both")),
        ({"n_steps": 0}, ("n_steps", "≥ 1")),
        ({"n_steps": 2.5}, ("n_steps", "integer")),
        ({"scheme": "euler"}, ("scheme must be one of", "variational", "energy-momentum", "'euler'")),
        ({"engine": "fortran"}, ("engine must be one of", "auto", "compiled", "python")),
        ({"tolerance": 0.0}, ("tolerance", "> 0")),
        ({"constraint_tolerance": -1e-11}, ("constraint_tolerance", "> 0")),
        ({"max_iterations": 0}, ("max_iterations", "≥ 1")),
        ({"max_halvings": -1}, ("max_halvings", "≥ 0")),
        ({"substeps": 3}, ("substeps", "power of two")),
        ({"substeps": 16}, ("substeps", "2^max_halvings")),
        ({"substeps": 2, "max_halvings": 0}, ("substeps", "2^max_halvings")),
    ],
)
def test_each_bad_field_is_one_clear_error(changes, needles) -> None:
    with pytest.raises(ParameterError) as error:
        SolverSettings(**changes)
    message = str(error.value)
    assert "\n" not in message
    for needle in needles:
        assert needle in message, message


def test_recipe_is_picklable_hashable_and_keyed_as_before() -> None:
    settings = SolverSettings(dt=1e-3, duration=0.05, scheme="energy-momentum")
    recipe = LegModelRecipe("stance", "max_element_energy", ("E",), (1.0, 2.0), nodes=6, settings=settings)
    assert pickle.loads(pickle.dumps(recipe)) == recipe and hash(recipe) == hash(pickle.loads(pickle.dumps(recipe)))
    # the key of the recipe with dt, duration and scheme fields, as it was
    assert recipe.key == ("LegModelRecipe", "stance", "max_element_energy", ("E",), (1.0, 2.0), 6, 1e-3, 0.05,
                          "energy-momentum", "beam")  # fmt: skip
    assert LegModelRecipe().key == ("LegModelRecipe", "swing", "total_deformation_energy", ("E",), None, 20, None, None,
                                    "variational", "beam")  # fmt: skip
    tighter = LegModelRecipe("stance", settings=settings.derive(tolerance=1e-12)).key
    assert tighter[-1] == ("tolerance", 1e-12) and tighter != LegModelRecipe("stance", settings=settings).key
    with pytest.raises(ParameterError, match="SolverSettings"):
        LegModelRecipe(settings={"dt": 1e-3})  # type: ignore[arg-type]


@pytest.mark.parametrize("scheme", ["variational", "energy-momentum"])
def test_a_run_with_settings_is_the_old_run(swing: LegSimulator, scheme: str) -> None:
    reference = np.load(REFERENCE)
    ds = swing.run(swing.parameters(eta=1e5), SolverSettings(duration=0.03, scheme=scheme), sensitivities=True)
    key = scheme.replace("-", "_")
    for name in VARIABLES:
        assert_same_run(ds[name].values, reference[f"{key}__{name}"], name)
    for name in ("newton_iterations", "time"):
        assert np.array_equal(ds[name].values, reference[f"{key}__{name}"]), name


def test_refinement_and_failures_are_the_old_ones(swing: LegSimulator) -> None:
    reference = np.load(REFERENCE)
    p = swing.parameters(eta=1e5)
    refined = integrate(swing.model, swing.leg.q0, None, p, SolverSettings(dt=4e-3, n_steps=10, max_iterations=6))
    assert refined.substeps == int(reference["refined__substeps"]) == 4
    assert_same_run(refined.q, reference["refined__q"], "q")
    assert np.array_equal(refined.iterations, reference["refined__iterations"])
    floppy = swing.parameters(E=1e3, eta=0.0)
    with pytest.raises(NewtonNotConverged) as newton:
        integrate(swing.model, swing.leg.q0, None, floppy, SolverSettings(dt=0.05, n_steps=10, max_halvings=0))
    with pytest.raises(BladeFolded) as folded:
        swing.run(floppy, SolverSettings(dt=0.05, duration=0.5))
    assert [str(newton.value), str(folded.value)] == list(reference["messages"])
    error = newton.value
    assert isinstance(error, SimulationError) and isinstance(error, SolverError)
    assert (error.step, error.time, error.iterations) == (4, pytest.approx(0.2), 25)
    assert error.residual == pytest.approx(0.126, abs=5e-4)
    fold = folded.value
    assert (fold.group, fold.element, fold.step) == ("blade", 0, 7) and fold.angle > 90
    assert fold.time == pytest.approx(0.175)
    for raised in (error, fold):  # they cross process boundaries (Dask workers) whole
        again = pickle.loads(pickle.dumps(raised))
        assert type(again) is type(raised) and str(again) == str(raised) and vars(again) == vars(raised)
