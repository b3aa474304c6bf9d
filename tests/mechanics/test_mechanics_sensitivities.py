"""Parameter sensitivities of the variational integrator against finite differences.

Truth: the five-point central difference
``f'(p) ≈ [−f(p+2h) + 8 f(p+h) − 8 f(p−h) + f(p−2h)] / 12h`` of the outputs of runs at
perturbed parameters, each integrated with a tight Newton tolerance (1e-13) so that
round-off in q does not swamp the difference.  Plain central differences with the default
tolerance bottom out at ~1e-6…1e-4 (noise), which is why both measures are used.  Steps are
chosen per parameter where the FD error is smallest (E, ρ: the blade's high-frequency
oscillation phase ∝ sqrt(E/ρ) makes larger steps nonlinear).

Measured (swing, stiff blade E = 59958e6, ρ = 1710, η = 1e7, 6 nodes, dt = 1 ms, 60 steps;
error = max over all times of |FD − S| / max |S|):

==========  ======  ==========  ===========  ============
parameter   rel h   dq/dp       d(ΣW_e)/dp   d(tip)/dp
==========  ======  ==========  ===========  ============
E           2e-3    1.1e-7      4.6e-7       5.3e-8
rho         2e-3    3.1e-8      9.8e-8       3.5e-9
eta         5e-3    8.1e-7      1.9e-7       2.6e-7
thigh_mass  1e-2    6.3e-9      6.5e-7       1.1e-9
shank_J1    1e-2    2.6e-8      2.2e-7       8.2e-10
==========  ======  ==========  ===========  ============

Cantilever (20 nodes, critical damping of mode 1, dt = 0.01 s, 400 steps): d(tip z)/dE vs
FD 3.5e-8 (rel. step 1e-3); at the settled state E·d(tip z)/dE / tip z = −0.9999977 (static: δ ∝ 1/E).
No wrong term found: mass, gravity, element, constraint-Hessian and first-step terms agree.
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.mechanics.cantilever import build_cantilever
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.leg import LEG_PARAMETERS
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.trajectory import trajectory_energies

DT = 1e-3
N_STEPS = 60
TIGHT = 1e-13  # Newton update tolerance of the finite-difference runs


def five_point(evaluate, p: np.ndarray, index: int, relative_step: float):
    """Five-point central difference of each output of ``evaluate(p)`` (a list of arrays)."""
    h = relative_step * p[index]
    runs = {}
    for k in (-2, -1, 1, 2):
        shifted = p.copy()
        shifted[index] += k * h
        runs[k] = evaluate(shifted)
    return [(-runs[2][j] + 8 * runs[1][j] - 8 * runs[-1][j] + runs[-2][j]) / (12 * h) for j in range(len(runs[1]))]


def relative_error(fd: np.ndarray, analytic: np.ndarray) -> float:
    return float(np.max(np.abs(fd - analytic)) / np.max(np.abs(analytic)))


@pytest.fixture(scope="module")
def swing():
    sim = LegSimulator("swing", nodes=6, compile=False)
    p = sim.parameters(E=59958e6, rho=1.71e3, eta=1e7)
    ds = sim.run(p, SolverSettings(dt=DT, duration=N_STEPS * DT), sensitivities=True)
    return sim, p, ds


STEPS = {"E": 2e-3, "rho": 2e-3, "eta": 5e-3, "thigh_mass": 1e-2, "shank_J1": 1e-2}


@pytest.mark.parametrize("name", list(STEPS))
def test_swing_sensitivities_match_finite_differences(swing, name):
    sim, p, ds = swing
    index = LEG_PARAMETERS.index(name)

    def outputs(q_p):
        settings = SolverSettings(dt=DT, n_steps=N_STEPS, tolerance=TIGHT)
        trajectory = integrate(sim.model, sim.leg.q0, None, q_p, settings)
        energies = trajectory_energies(sim.model, trajectory, q_p)
        return [trajectory.q, energies.element.sum(axis=1), trajectory.q[:, -12:-9]]

    fd_q, fd_energy, fd_tip = five_point(outputs, p, index, STEPS[name])
    analytic = {
        "configuration": ds.configuration_sensitivity.values[:, :, index],
        "total_deformation_energy": ds.total_deformation_energy_sensitivity.values[:, index],
        "last_node_position": ds.last_node_position_sensitivity.values[:, :, index],
    }
    assert np.all(analytic["configuration"][0] == 0.0)  # q0 does not depend on p
    errors = {
        key: relative_error(fd, analytic[key])
        for key, fd in zip(analytic, (fd_q, fd_energy, fd_tip))
    }
    for key, error in errors.items():
        assert error <= 1e-5, (name, errors)
    # the sensitivities are not trivially small: the parameter moves the outputs
    assert np.max(np.abs(analytic["configuration"])) * p[index] > 1e-6


def test_swing_sensitivity_dataset_is_consistent(swing):
    """``last_node_position_sensitivity`` is the tip block of ``configuration_sensitivity``."""
    _, _, ds = swing
    np.testing.assert_array_equal(
        ds.last_node_position_sensitivity.values, ds.configuration_sensitivity.values[:, -12:-9, :]
    )


@pytest.mark.slow
def test_cantilever_tip_sensitivity_to_E():
    length, width, thickness = 1.0, 0.05, 0.01
    E, nu, rho = 1e9, 0.3, 1000.0
    inertia = width * thickness**3 / 12
    omega = 1.875**2 * np.sqrt(E * inertia / (rho * width * thickness * length**4))
    force = 1e-3 * 3 * E * inertia / length**2
    beam = build_cantilever(length, width, thickness, 20, (0.0, 0.0, -force), compile=False)
    p = np.array([E, nu, rho, 2 * E / omega])
    dt, n_steps = 0.01, 400
    trajectory = beam.run(p, dt, n_steps, sensitivities=True)
    analytic = trajectory.sensitivities[:, -12:-9, 0][:, 2]

    def tip_z(q_p):
        return [beam.tip_position(beam.run(q_p, dt, n_steps, tolerance=TIGHT))[:, 2]]

    (fd,) = five_point(tip_z, p, 0, 1e-3)
    assert relative_error(fd, analytic) <= 1e-5  # measured 3.5e-8
    # settled static state: δ ∝ 1/E, so E dδ/dE = −δ
    tip = beam.tip_position(trajectory)[-1, 2]
    assert abs(E * analytic[-1] / tip + 1) <= 1e-3  # measured 2.3e-6
