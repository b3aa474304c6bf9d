"""Variational vs energy-momentum time stepping of the leg + prosthesis model.

Truths: the energy-momentum scheme's discrete energy balance is exact by construction
(discrete gradient of the quadratic strains), both schemes converge to the same solution as
dt → 0, and the variational integrator's balance error falls at second order.
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.core.errors import SimulationError
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.trajectory import trajectory_energies

STIFF = dict(E=59958e6, rho=1.71e3)  # Table 4.2 blade


@pytest.fixture(scope="module")
def swing() -> LegSimulator:
    return LegSimulator("swing", nodes=20)


def _balance(sim: LegSimulator, p: np.ndarray, dt: float, duration: float, scheme: str):
    trajectory = integrate(sim.model, sim.leg.q0, None, p, SolverSettings(dt=dt, duration=duration, scheme=scheme))
    energies = trajectory_energies(sim.model, trajectory, p)
    balance = energies.total + energies.dissipated
    return np.max(np.abs(balance - balance[0])) / abs(balance[0]), energies


def test_energy_momentum_balance_is_exact_with_damping(swing):
    p = swing.parameters(**STIFF, eta=1e6)
    mismatch, energies = _balance(swing, p, 1e-3, 0.3, "energy-momentum")
    assert energies.dissipated[-1] > 1e-6  # damping does visible work
    assert mismatch <= 1e-8  # measured 1.3e-10 (Newton tolerance)


def test_variational_balance_error_is_second_order(swing):
    p = swing.parameters(**STIFF, eta=1.0)
    errors = [_balance(swing, p, dt, 0.1, "variational")[0] for dt in (1e-3, 5e-4, 2.5e-4)]
    # measured 1.1e-6, 2.0e-7, 3.8e-8
    assert errors[0] < 1e-5
    assert errors[0] / errors[1] > 3.0 and errors[1] / errors[2] > 3.0


def test_schemes_converge_to_the_same_motion(swing):
    p = swing.parameters(**STIFF)
    n = 400
    a = integrate(swing.model, swing.leg.q0, None, p, SolverSettings(dt=2.5e-4, n_steps=n))
    b = integrate(swing.model, swing.leg.q0, None, p, SolverSettings(dt=2.5e-4, n_steps=n, scheme="energy-momentum"))
    ea = trajectory_energies(swing.model, a, p).internal.max()
    eb = trajectory_energies(swing.model, b, p).internal.max()
    assert np.max(np.abs(a.q[:, -12:-9] - b.q[:, -12:-9])) < 1e-5  # toe position, m
    assert ea == pytest.approx(eb, rel=0.01)  # measured 3.1265e-5 vs 3.1236e-5 J


@pytest.mark.slow
@pytest.mark.parametrize(("scenario", "overrides"), [("swing", {"eta": 1e5}), ("stance", {})])
def test_presets_run_their_full_two_seconds_with_energy_momentum(scenario, overrides):
    """Table 4.3 / 4.4 values (dt = 1 ms, T = 2 s); the soft swing blade needs η = 10⁵ Pa s
    with the shipped geometry (see the next test and the README)."""
    sim = LegSimulator(scenario, nodes=20)
    ds = sim.run(sim.parameters(**overrides), SolverSettings(scheme="energy-momentum"))
    assert float(ds.time[-1]) == pytest.approx(2.0)
    balance = ds.total_energy + ds.dissipated_energy
    assert float(np.abs(balance - balance[0]).max() / abs(balance[0])) < 1e-8
    constraints = sim.model.functions["constraints"]
    g_max = max(
        float(np.max(np.abs(np.asarray(constraints(np.concatenate(
            [np.concatenate([ds.position.values[j, k], ds.directors.values[j, k].ravel()])
             for k in range(ds.sizes["body"])]), sim.model.constants)[0]))))
        for j in range(0, ds.sizes["time"], 50)
    )
    assert g_max <= 1e-9


def test_soft_swing_blade_without_damping_stops_with_the_fold_error():
    """With η = 1 Pa s the Table 4.3 blade (EI ≈ 10⁻³ N m² on the shipped geometry) folds
    within one element at t ≈ 0.27 s; the run stops with one clear error instead of
    returning the near-free stretching of a folded two-node element."""
    sim = LegSimulator("swing", nodes=20)
    with pytest.raises(SimulationError, match=r"blade element \d+ folded at t = 0\.2\d+ s.*more damping"):
        sim.run(settings=SolverSettings(scheme="energy-momentum"))


@pytest.mark.parametrize(("name", "tolerance"), [("E", 1e-6), ("eta", 1e-5), ("thigh_mass", 1e-6)])
def test_energy_momentum_sensitivities_match_finite_differences(name, tolerance):
    """dq/dp of the energy-momentum scheme (velocity sensitivities carried along) against a
    five-point difference with a 1e-3 relative step (the finite-difference error dominates
    below that step; measured 6.8e-8 for E, 3.3e-6 for eta)."""
    sim = LegSimulator("swing", nodes=6, compile=False)
    p = sim.parameters(**STIFF, eta=1e7)
    k = sim.parameter_names.index(name)
    settings = SolverSettings(dt=1e-3, n_steps=60, scheme="energy-momentum", tolerance=1e-13)
    run = lambda params, **kw: integrate(sim.model, sim.leg.q0, None, params, settings, **kw)  # noqa: E731
    analytic = run(p, sensitivities=True).sensitivities[:, :, k]
    step = 1e-3 * p[k]
    q = [run(p + np.eye(len(p))[k] * s * step).q for s in (-2, -1, 1, 2)]
    fd = (q[0] - 8 * q[1] + 8 * q[2] - q[3]) / (12 * step)
    assert np.max(np.abs(fd - analytic)) / np.max(np.abs(analytic)) <= tolerance
