"""Bad input to the mechanics simulators gives one clear error naming what is wrong.

Every case raises :class:`fuzzygait.core.errors.ParameterError` (a ``ValueError``) or
:class:`~fuzzygait.core.errors.SimulationError` with a one-line message that names the
parameter (and, for a failed step, the time, the residual and the parameter values).
"""

from __future__ import annotations

import pytest

from fuzzygait.core.errors import FuzzyGaitError, ParameterError, SimulationError
from fuzzygait.mechanics.cantilever import build_cantilever
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.leg import LEG_PARAMETERS
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings


@pytest.fixture(scope="module")
def sim():
    return LegSimulator("swing", nodes=6, compile=False)


def one_line(error: pytest.ExceptionInfo) -> str:
    message = str(error.value)
    assert message and "\n" not in message
    assert isinstance(error.value, FuzzyGaitError)
    return message


@pytest.mark.parametrize(
    "overrides, needles",
    [
        (dict(E=-1.0), ["E", "> 0", "-1.0"]),
        (dict(E=0.0), ["E", "> 0"]),
        (dict(E=float("nan")), ["E", "finite"]),
        (dict(nu=0.6), ["nu", "0.6", "0.5"]),
        (dict(nu=-1.0), ["nu"]),
        (dict(rho=0.0), ["rho"]),
        (dict(eta=-1.0), ["eta"]),
        (dict(thigh_mass=-6.5), ["thigh_mass"]),
        (dict(foo=1.0), ["foo", "unknown"]),
        (dict(thigh_J1=0.0), ["thigh_J1"]),
        (dict(shank_J3=-0.1), ["shank_J3"]),
    ],
)
def test_bad_parameter_is_named(sim, overrides, needles):
    with pytest.raises(ParameterError) as error:
        sim.parameters(**overrides)
    message = one_line(error)
    for needle in needles:
        assert needle in message, message


def test_bad_parameter_vector_passed_to_run(sim):
    p = sim.parameters()
    p[LEG_PARAMETERS.index("nu")] = 0.6
    with pytest.raises(ParameterError) as error:
        sim.run(p, SolverSettings(dt=1e-3, duration=0.01))
    assert "nu" in one_line(error)
    with pytest.raises(ParameterError) as error:
        sim.run(p[:5], SolverSettings(dt=1e-3, duration=0.01))
    assert "parameters" in one_line(error)


@pytest.mark.parametrize("dt", [0.0, -1e-3, float("nan")])
def test_bad_time_step(sim, dt):
    with pytest.raises(ParameterError) as error:
        sim.run(sim.parameters(), SolverSettings(dt=dt, duration=0.01))
    assert "dt" in one_line(error)
    with pytest.raises(ParameterError) as error:
        integrate(sim.model, sim.leg.q0, None, sim.parameters(), SolverSettings(dt=dt, n_steps=3))
    assert "dt" in one_line(error)


def test_bad_duration(sim):
    with pytest.raises(ParameterError) as error:
        sim.run(sim.parameters(), SolverSettings(dt=1e-3, duration=0.0))
    assert "duration" in one_line(error)


@pytest.mark.parametrize("nodes", [1, 0])
def test_too_few_nodes(nodes):
    with pytest.raises(ParameterError) as error:
        LegSimulator("swing", nodes=nodes, compile=False)
    assert "nodes" in one_line(error)
    with pytest.raises(ParameterError) as error:
        build_cantilever(1.0, 0.05, 0.01, nodes, (0.0, 0.0, -1.0), compile=False)
    assert "nodes" in one_line(error)


def test_bad_scenario_and_foot():
    with pytest.raises(ParameterError) as error:
        LegSimulator("sprint", compile=False)
    assert "sprint" in one_line(error)
    with pytest.raises(ParameterError) as error:
        LegSimulator("swing", foot="wooden", compile=False)
    assert "foot" in one_line(error)


def test_bad_cantilever_geometry():
    with pytest.raises(ParameterError) as error:
        build_cantilever(-1.0, 0.05, 0.01, 5, (0.0, 0.0, -1.0), compile=False)
    assert "length" in one_line(error)


def test_inconsistent_initial_configuration(sim):
    q0 = sim.leg.q0.copy()
    q0[0] += 0.01  # move the thigh off the hip
    with pytest.raises(ParameterError) as error:
        integrate(sim.model, q0, None, sim.parameters(), SolverSettings(dt=1e-3, n_steps=3))
    assert "constraint" in one_line(error)


def test_non_converging_run_names_time_residual_and_parameters(sim):
    # a floppy blade (E = 1 kPa) with 50 ms steps: Newton cannot follow the motion
    # (measured: fails at t = 0.2 s, step 4, residual norm 2.75; without step refinement —
    # with it, the run at 25 ms sub-steps folds the blade at t = 0.175 s instead)
    with pytest.raises(SimulationError) as error:
        integrate(sim.model, sim.leg.q0, None, sim.parameters(E=1e3, eta=0.0),
                  SolverSettings(dt=0.05, n_steps=10, max_halvings=0))  # fmt: skip
    message = one_line(error)
    for needle in ("t = ", "residual", "E=1000", "eta=0", "dt"):
        assert needle in message, message
    with pytest.raises(SimulationError) as error:
        sim.run(sim.parameters(E=1e3, eta=0.0), SolverSettings(dt=0.05, duration=0.5))
    assert "folded" in one_line(error) and "(with 2 sub-steps per dt = 0.05 s)" in one_line(error)
