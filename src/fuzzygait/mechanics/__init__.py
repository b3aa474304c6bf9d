"""mechanics: the leg + prosthesis simulator (thesis §4) and the ideal pendulum example.

Modules, from the bottom up:

* :mod:`.assembly` — bodies in director form, mass matrix, gravity, joints (Eqs. 4.1–4.10),
* :mod:`.beam` — predeformed geometrically exact beam elements (Eqs. 4.30–4.33),
* :mod:`.sections`, :mod:`.homogenisation` — cross-section stiffness, homogeneous and
  three-layer (Eqs. 4.35–4.42),
* :mod:`.geometry` — the blade centreline file and its discretisation,
* :mod:`.presets` — Tables 4.1–4.4,
* :mod:`.discrete` — the CasADi functions of a built system and their buffered evaluation,
* :mod:`.schemes` — the step equations of the variational (Eqs. 4.16–4.29) and the
  energy-momentum scheme: residuals, Jacobians, sensitivity terms,
* :mod:`.step_functions` — each scheme's whole step (residual, Jacobian, sensitivity terms)
  as single CasADi functions for generated C code,
* :mod:`.native` — the compiled Newton loop (``native/stepper.c``: Newton, sparse LU with a
  reused pivot order, folding check, sensitivities; one call per chunk of steps),
* :mod:`.integrator` — time stepping: Newton with a kept sparse LU, forward parameter
  sensitivities (the compiled loop where there is one, else the same loop in Python),
* :mod:`.trajectory` — the results: trajectory and energies,
* :mod:`fuzzygait.core.codegen` (shared with the compiled joint-angle models) — compiled
  CasADi code cached on disk by model structure,
* :mod:`.leg`, :mod:`.scenarios` — the leg model and the swing/stance scenarios,
* :mod:`.cantilever` — the clamped straight beam used for verification,
* :mod:`.pendulum` — the ideal pendulum of the uncertainty-engine examples.
"""

from fuzzygait.mechanics.cantilever import Cantilever, build_cantilever
from fuzzygait.mechanics.discrete import DiscreteModel
from fuzzygait.mechanics.geometry import BladeGeometry, default_blade, read_blade_geometry
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.leg import LEG_PARAMETERS, LegConfiguration, build_leg
from fuzzygait.mechanics.scenarios import SCENARIOS, LegSimulator
from fuzzygait.mechanics.trajectory import Trajectory, trajectory_energies

__all__ = [
    "BladeGeometry",
    "Cantilever",
    "DiscreteModel",
    "LEG_PARAMETERS",
    "LegConfiguration",
    "LegSimulator",
    "SCENARIOS",
    "Trajectory",
    "build_cantilever",
    "build_leg",
    "default_blade",
    "integrate",
    "read_blade_geometry",
    "trajectory_energies",
]
