"""The compiled Newton loop (mechanics/native.py, native/stepper.c) against the Python loop.

Truth: the Python loop of ``integrate(engine="python")`` — the same equations assembled
term by term from the element kernels and solved with SuperLU — which the finite-difference
and energy tests have checked independently.  Both loops take the same Newton iterations, so
they must agree to the Newton tolerance (update ≤ 1e-10·(1 + |q|)), over hundreds of steps
in which the compiled loop's fixed pivot order has to be renewed more than once; their
sensitivities agree to the same relative order; a run that stops stops at the same step
with the same message.
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError, SimulationError
from fuzzygait.mechanics.cantilever import build_cantilever
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings

DT = 1e-3
STIFF = {"E": 59958e6, "rho": 1710.0}  # Table 4.2 blade: runs for seconds with eta = 1


@pytest.fixture(scope="module")
def swing():
    return LegSimulator("swing")


def run_both(model, q0, p, n_steps, sensitivities=False, **settings):
    return [integrate(model, q0, None, p, SolverSettings(dt=DT, n_steps=n_steps, engine=engine, **settings),
                      sensitivities=sensitivities) for engine in ("python", "compiled")]  # fmt: skip


def test_the_swing_model_has_a_compiled_stepper(swing):
    assert swing.model.stepper is not None and swing.model.stepper.exists()


@pytest.mark.parametrize("scheme", ["variational", "energy-momentum"])
def test_compiled_loop_agrees_with_python_loop(swing, scheme):
    p = swing.parameters(**STIFF)
    python, compiled = run_both(swing.model, swing.leg.q0, p, 400, scheme=scheme)
    scale = 1.0 + np.max(np.abs(python.q))
    assert np.max(np.abs(compiled.q - python.q)) < 1e-8 * scale
    assert np.max(np.abs(compiled.multipliers - python.multipliers)) < 1e-6 * np.max(np.abs(python.multipliers))
    assert abs(int(compiled.iterations.sum()) - int(python.iterations.sum())) <= 0.01 * python.iterations.sum()
    assert compiled.timings["pivot_orders"] >= 2  # the fixed pivot order was renewed during the run
    if scheme == "energy-momentum":
        assert np.max(np.abs(compiled.velocities - python.velocities)) < 1e-5 * np.max(np.abs(python.velocities))


@pytest.mark.parametrize("scheme", ["variational", "energy-momentum"])
def test_compiled_sensitivities_agree_with_python_loop(swing, scheme):
    p = swing.parameters(**STIFF)
    python, compiled = run_both(swing.model, swing.leg.q0, p, 80, scheme=scheme, sensitivities=True)
    assert np.max(np.abs(compiled.q - python.q)) < 1e-9
    error = np.max(np.abs(compiled.sensitivities - python.sensitivities), axis=(0, 1))  # per parameter
    assert np.all(error <= 1e-6 * np.max(np.abs(python.sensitivities), axis=(0, 1)) + 1e-12)


def test_rigid_pendulum_without_beam_elements():
    sim = LegSimulator("swing", foot="none")
    python, compiled = run_both(sim.model, sim.leg.q0, sim.default_parameters, 500)
    assert not sim.model.groups
    assert np.max(np.abs(compiled.q - python.q)) < 1e-8


def test_cantilever_tip_history_agrees():
    """The clamped 19-element beam under a sudden tip load (benchmarks/simulator_exudyn.py,
    case a): past t = 0.507 s, where a renewed pivot order once had to be used at the very
    iterate whose factorisation failed (restarting the step from its predictor repeated
    the failure), with the same Newton iterations as the Python loop."""
    beam = build_cantilever(length=0.35, width=0.055, thickness=0.010, nodes=20, tip_force=(0.0, 0.0, -50.0))
    p = np.array([59958e6, 0.265, 1710.0, 1e5])  # E, nu, rho, eta (Table 4.2 material)
    python, compiled = run_both(beam.model, beam.q0, p, 600)
    assert compiled.timings["pivot_orders"] >= 10
    assert np.array_equal(compiled.iterations, python.iterations)
    assert np.max(np.abs(beam.tip_position(compiled) - beam.tip_position(python))) < 1e-9


def test_fold_stops_both_loops_with_the_same_message(swing):
    messages = []
    for engine in ("python", "compiled"):
        with pytest.raises(SimulationError) as error:
            integrate(swing.model, swing.leg.q0, None, swing.default_parameters,
                      SolverSettings(dt=DT, n_steps=400, engine=engine))  # fmt: skip
        messages.append(str(error.value))
    assert messages[0] == messages[1]
    assert "folded at t = " in messages[1]


def test_newton_failure_names_the_same_step(swing):
    messages = []
    for engine in ("python", "compiled"):
        with pytest.raises(SimulationError) as error:
            integrate(swing.model, swing.leg.q0, None, swing.parameters(**STIFF),
                      SolverSettings(dt=DT, n_steps=5, engine=engine, max_iterations=1, max_halvings=0))  # fmt: skip
        messages.append(str(error.value).split(": residual")[0])
    assert messages[0] == messages[1] == "Newton did not converge at t = 0.0010 s (step 1, dt = 0.001 s)"


def test_engine_choice_is_checked(swing):
    with pytest.raises(ParameterError, match="engine must be one of"):
        SolverSettings(dt=DT, n_steps=1, engine="fortran")
    assert swing.model.stepper is not None


def test_uncompiled_model_steps_in_python():
    sim = LegSimulator("swing", foot="none", compile=False)
    assert sim.model.stepper is None
    with pytest.raises(ParameterError, match="no compiled stepper"):
        integrate(sim.model, sim.leg.q0, None, sim.default_parameters,
                  SolverSettings(dt=DT, n_steps=1, engine="compiled"))  # fmt: skip
    settings = SolverSettings(dt=DT, n_steps=20)  # engine "auto": the Python loop
    trajectory = integrate(sim.model, sim.leg.q0, None, sim.default_parameters, settings)
    assert "pivot_orders" not in trajectory.timings


def test_progress_is_reported_between_chunks(swing):
    seen: list[int] = []
    integrate(swing.model, swing.leg.q0, None, swing.parameters(**STIFF),
              SolverSettings(dt=DT, n_steps=120, engine="compiled"), progress=seen.append)  # fmt: skip
    assert seen[-1] == 120 and seen == sorted(seen) and len(seen) >= 3


def test_newton_path_does_not_depend_on_sensitivities():
    """The sensitivities' LU has its own pivot order: renewing it never touches Newton's,
    so trajectories are bit-identical with and without sensitivities (the FRV and Graph
    Follower studies rely on it: α = 1 is the deterministic run).  The default 20 nodes
    (the library the scheme and README tests compile too): 7 pivot orders in 200 steps."""
    sim = LegSimulator("stance")
    p = sim.parameters(E=59.39e9)
    settings = SolverSettings(dt=DT, n_steps=200, scheme="energy-momentum", engine="compiled")
    runs = [integrate(sim.model, sim.leg.q0, None, p, settings, sensitivities=s) for s in (False, True)]
    assert runs[0].timings["pivot_orders"] >= 2
    assert np.array_equal(runs[0].q, runs[1].q) and np.array_equal(runs[0].iterations, runs[1].iterations)
