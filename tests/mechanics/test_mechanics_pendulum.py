"""The leg without a blade is a planar double pendulum: check the director-form variational
integrator against an independent minimal-coordinate model.

Truth: the Lagrange equations of two compound pendulums in the sagittal plane (absolute
angles, COM distances, moments of inertia about the COM about the lateral axis), written
here from scratch and integrated with scipy's DOP853 at rtol = atol = 1e-12.  With
``foot="rigid"`` the shank and the rigid foot form one body (total mass, combined centre of
mass, parallel-axis inertia).

Measured (swing from rest, hip −π/6, knee π/3, 1 s, compile=False):

=========  =========================  =========================  =====
foot       max error dt = 1 ms (rad)  max error dt = 0.5 ms       ratio
=========  =========================  =========================  =====
none       4.08e-5 (knee; hip 1.33e-5) 1.02e-5                   3.99
rigid      4.14e-5 (knee; hip 1.68e-5) 1.04e-5                   4.00
=========  =========================  =========================  =====

(dt = 0.25 ms gives 2.73e-6 / 2.65e-6: second order down to the Newton tolerance.)
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from fuzzygait.mechanics.leg import RigidFoot
from fuzzygait.mechanics.presets import SHANK, SWING, THIGH
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings

GRAVITY = 9.81
DURATION = 1.0


def distal_body(foot: RigidFoot | None):
    """Mass (kg), COM offset from the knee (a along the shank's distal axis u, b along the
    forward normal n = du/dφ) in m, and inertia about that COM about the lateral axis (kg m²)."""
    ms, cs, js, ls = SHANK.mass, SHANK.com_from_proximal, SHANK.inertia[0], SHANK.length
    if foot is None:
        return ms, cs, 0.0, js
    # attachment frame: origin at the ankle (distal end of the shank), z up along the shank
    # (= −u), x forward (= n): the foot centre sits at (ls − cz) u + cx n from the knee
    mf = foot.mass
    cx, cy, cz = foot.centre
    assert cy == 0.0
    r_shank = np.array([cs, 0.0])
    r_foot = np.array([ls - cz, cx])
    mass = ms + mf
    com = (ms * r_shank + mf * r_foot) / mass
    inertia = (
        js + ms * np.sum((r_shank - com) ** 2)
        + foot.inertia[1] + mf * np.sum((r_foot - com) ** 2)  # y entry: moment about the lateral axis
    )
    return mass, com[0], com[1], inertia


def double_pendulum(foot: RigidFoot | None, times: np.ndarray, hip0: float, knee0: float):
    """Hip and knee flexion (rad) of the planar double pendulum released from rest.

    Generalised coordinates: θ (thigh angle from the downward vertical, forward positive,
    = hip flexion) and ψ, the angle of the line knee → distal COM.  With u(φ) = (sin φ, −cos φ)
    in the (x, z) plane the distal COM sits at ``l1 u(θ) + ρ u(ψ)``; the shank's own angle is
    φ = ψ − δ with δ = atan2(b, a), and the knee flexion is θ − φ.
    """
    m1, c1, j1, l1 = THIGH.mass, THIGH.com_from_proximal, THIGH.inertia[0], THIGH.length
    m2, a, b, j2 = distal_body(foot)
    rho, delta = np.hypot(a, b), np.arctan2(b, a)
    m11 = m1 * c1**2 + j1 + m2 * l1**2
    m22 = m2 * rho**2 + j2
    k = m2 * l1 * rho

    def rhs(_t, y):
        th, ps, w1, w2 = y
        s, c = np.sin(th - ps), np.cos(th - ps)
        mass = np.array([[m11, k * c], [k * c, m22]])
        force = -np.array(
            [k * s * w2**2 + (m1 * c1 + m2 * l1) * GRAVITY * np.sin(th),
             -k * s * w1**2 + m2 * GRAVITY * rho * np.sin(ps)]
        )
        acc = np.linalg.solve(mass, force)
        return [w1, w2, acc[0], acc[1]]

    phi0 = hip0 - knee0
    solution = solve_ivp(rhs, (0.0, times[-1]), [hip0, phi0 + delta, 0.0, 0.0], t_eval=times,
                         method="DOP853", rtol=1e-12, atol=1e-12)  # fmt: skip
    assert solution.success
    hip = solution.y[0]
    shank = solution.y[1] - delta
    return hip, hip - shank


@functools.lru_cache(maxsize=None)
def swing_run(foot: str):
    """Simulator, the dt = 1 ms run and the max (hip, knee) errors by dt."""
    sim = LegSimulator("swing", foot=foot, compile=False)  # 2–3 bodies: no compile needed
    assert np.isclose(sim.configuration.hip_angle, -np.pi / 6)
    assert np.isclose(sim.configuration.knee_angle, np.pi / 3)
    p = sim.parameters()
    errors = {}
    for dt in (1e-3, 5e-4):
        ds = sim.run(p, SolverSettings(dt=dt, duration=DURATION))
        hip, knee = double_pendulum(sim.leg.rigid_foot, ds.time.values, SWING.hip_angle, SWING.knee_angle)
        errors[dt] = (
            float(np.max(np.abs(ds.hip_flexion.values - hip))),
            float(np.max(np.abs(ds.knee_flexion.values - knee))),
        )
        if dt == 1e-3:
            coarse = ds
    return sim, coarse, errors


@pytest.mark.parametrize("foot", ["none", "rigid"])
def test_swing_matches_minimal_coordinate_double_pendulum(foot):
    _, ds, errors = swing_run(foot)
    hip_error, knee_error = errors[1e-3]
    # measured: none 1.33e-5 / 4.08e-5, rigid 1.68e-5 / 4.14e-5 rad
    assert max(hip_error, knee_error) <= 1e-3, (foot, errors)
    # the motion is not trivial: the leg swings through a large arc within the second
    assert np.ptp(ds.hip_flexion.values) > 0.5
    assert np.ptp(ds.knee_flexion.values) > 1.0


@pytest.mark.parametrize("foot", ["none", "rigid"])
def test_swing_error_is_second_order_in_dt(foot):
    _, _, errors = swing_run(foot)
    ratio = max(errors[1e-3]) / max(errors[5e-4])
    # measured: none 3.99, rigid 4.00
    assert 3.2 <= ratio <= 4.8, (foot, errors, ratio)


def test_rigid_foot_is_felt():
    """The foot-less pendulum is a wrong model of the leg with a rigid foot (so the
    comparison above does test how the foot's mass, centre and inertia enter)."""
    sim, ds, errors = swing_run("rigid")
    hip, knee = double_pendulum(None, ds.time.values, SWING.hip_angle, SWING.knee_angle)
    wrong = max(np.max(np.abs(ds.hip_flexion.values - hip)), np.max(np.abs(ds.knee_flexion.values - knee)))
    assert wrong > 100 * max(errors[1e-3])  # measured 0.27 rad vs 4e-5 rad
    assert sim.leg.rigid_foot.mass > 1.0  # measured 1.785 kg
