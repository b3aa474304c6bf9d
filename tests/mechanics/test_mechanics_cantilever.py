"""Static tip deflection of the clamped beam: linear Timoshenko theory and the elastica.

The static answer is reached by running the (implicit) dynamics with heavy Kelvin–Voigt
damping until it has settled; damping does not change the equilibrium.

Truths:
* small load: δ = P L³/(3EI) + P L/(κ G A) (Timoshenko; ``timoshenko_tip_deflection``);
* large load, inextensible and shear-rigid limit: the elastica θ'' = −(P L²/EI) cos θ,
  θ(0) = 0, θ'(L) = 0, solved here by shooting (solve_ivp + brentq), cross-checked with
  Bisshopp & Drucker (1945): PL²/EI = 1 → vertical δ/L = 0.30172, horizontal 0.94357.

Measured (20 nodes, compile=False):

* slender L = 1, b × a = 0.05 × 0.01, E = 1e9, δ/L = 1e-3: δ/δ_Timoshenko − 1 = −6.9e-4
  (−3.1e-3 with 10 nodes, −1.7e-4 with 40: O(1/n²));
* thick L/a = 5 (0.1 m, 0.02 × 0.02): −6.7e-4; the shear term is 3.05 % of δ;
* elastica (own shooting): PL²/EI = 1: x/L = 0.943567, y/L = 0.301721;
  PL²/EI = 2: x/L = 0.839358, y/L = 0.493457;
  simulated tip errors: PL²/EI = 1: x +7.6e-5, y +4.9e-4; PL²/EI = 2: x −3.3e-4, y +2.0e-3.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fuzzygait.mechanics.cantilever import build_cantilever
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.solver import SolverSettings

E, NU, RHO = 1e9, 0.3, 1000.0


def first_bending_frequency(length, width, thickness):
    """ω1 = 1.875² sqrt(EI / (ρ A L⁴)) (rad/s) of the clamped–free Euler–Bernoulli beam."""
    inertia = width * thickness**3 / 12
    return 1.875**2 * np.sqrt(E * inertia / (RHO * width * thickness * length**4))


def settled_tip_deflection(length, width, thickness, nodes, relative_deflection):
    """Tip deflection (m, downward positive) after ~20 creep times, and the Cantilever."""
    inertia = width * thickness**3 / 12
    omega = first_bending_frequency(length, width, thickness)
    force = relative_deflection * 3 * E * inertia / length**2  # P L²/(3EI) = δ/L
    beam = build_cantilever(length, width, thickness, nodes, (0.0, 0.0, -force), compile=False)
    eta = 2 * E / omega  # ζ1 = η ω1 / (2E) = 1: critical damping of mode 1
    dt = 0.1 / omega  # ≫ the axial/shear periods: the implicit scheme damps them away
    n_steps = 400  # 40/ω1 = 20 creep times η/E
    trajectory = beam.run(np.array([E, NU, RHO, eta]), dt, n_steps)
    tip = beam.tip_position(trajectory)
    assert np.max(np.abs(tip[-1] - tip[-11])) < 1e-6 * length  # settled (measured ~1e-11 m)
    return -tip[-1, 2], force, beam


def test_small_load_slender_beam_matches_timoshenko():
    deflection, force, beam = settled_tip_deflection(1.0, 0.05, 0.01, nodes=20, relative_deflection=1e-3)
    expected = beam.timoshenko_tip_deflection(force, E, NU)
    assert abs(deflection / expected - 1) <= 0.01  # measured −6.9e-4


def test_small_load_thick_beam_includes_shear():
    length, side = 0.1, 0.02  # L/a = 5
    deflection, force, beam = settled_tip_deflection(length, side, side, nodes=20, relative_deflection=1e-3)
    expected = beam.timoshenko_tip_deflection(force, E, NU)
    bending_only = force * length**3 / (3 * E * side**4 / 12)
    assert abs(deflection / expected - 1) <= 0.01  # measured −6.7e-4
    assert deflection / bending_only - 1 > 0.02  # the shear term matters: measured +3.05 %


# -- large deflection ------------------------------------------------------------------------
def elastica(load: float) -> tuple[float, float]:
    """Tip (x/L, y/L) of the inextensible cantilever under a transverse tip load, y downward,
    for ``load`` = P L²/EI: shooting on θ'(0) so that θ'(1) = 0 (no moment at the tip)."""

    def rhs(_s, y):
        theta, curvature = y[0], y[1]
        return [curvature, -load * np.cos(theta), np.cos(theta), np.sin(theta)]

    def end(curvature0):
        return solve_ivp(rhs, (0.0, 1.0), [0.0, curvature0, 0.0, 0.0], method="DOP853",
                         rtol=1e-12, atol=1e-12).y[:, -1]  # fmt: skip

    # θ'(0) = P x_tip/EI lies in (0, load]
    curvature0 = brentq(lambda k: end(k)[1], 0.0, load, xtol=1e-14)
    _, _, x, y = end(curvature0)
    return float(x), float(y)


def test_elastica_reference_matches_bisshopp_drucker():
    x, y = elastica(1.0)
    assert abs(y - 0.30172) < 1e-5  # Bisshopp & Drucker 1945; own: 0.3017208
    assert abs(x - 0.94357) < 1e-5  # horizontal projection; own: 0.9435668
    x2, y2 = elastica(2.0)  # own: 0.839358, 0.493457
    assert 0.49 < y2 < 0.50 and 0.83 < x2 < 0.85


THIN = dict(length=1.0, width=0.01, thickness=0.005)  # EA L²/EI = 12 L²/a² = 4.8e5: inextensible


def test_large_deflection_matches_elastica():
    """Load stepping PL²/EI = 1 → 2, each settled by heavily damped dynamics.

    dt = 0.025/ω1 (4.9 ms); with larger steps the Newton iteration fails (see
    ``test_large_load_from_rest_with_large_dt_converges``)."""
    length, width, thickness = THIN["length"], THIN["width"], THIN["thickness"]
    ei = E * width * thickness**3 / 12
    omega = first_bending_frequency(length, width, thickness)
    p = np.array([E, NU, RHO, 2 * 0.7 * E / omega])  # ζ1 = 0.7
    dt = 0.025 / omega
    q = None
    for load in (1.0, 2.0):
        beam = build_cantilever(length, width, thickness, 20, (0.0, 0.0, -load * ei / length**2), compile=False)
        start = beam.q0 if q is None else q  # the previous load's equilibrium
        trajectory = integrate(beam.model, start, None, p, SolverSettings(dt=dt, n_steps=600))  # 15/ω1
        tip = beam.tip_position(trajectory)
        assert np.max(np.abs(tip[-1] - tip[-20])) < 1e-4 * length  # settled (measured 3e-6 m)
        q = trajectory.q[-1]
        x, y = elastica(load)
        assert abs(tip[-1, 0] / (x * length) - 1) <= 0.01, (load, tip[-1], x, y)  # +7.6e-5, −3.3e-4
        assert abs(-tip[-1, 2] / (y * length) - 1) <= 0.01, (load, tip[-1], x, y)  # +4.9e-4, +2.0e-3


def test_large_load_from_rest_with_large_dt_converges():
    """Regression: Newton used to apply a diverging chord step from a stale factorisation
    before refreshing it, and failed here although full Newton converges in 4 iterations."""
    length, width, thickness = THIN["length"], THIN["width"], THIN["thickness"]
    ei = E * width * thickness**3 / 12
    omega = first_bending_frequency(length, width, thickness)
    beam = build_cantilever(length, width, thickness, 20, (0.0, 0.0, -2.0 * ei / length**2), compile=False)
    p = np.array([E, NU, RHO, 2 * E / omega])
    trajectory = beam.run(p, 0.05 / omega, 40)
    assert -beam.tip_position(trajectory)[-1, 2] > 0.1
