"""A straight clamped beam with a constant tip force: the verification case of the beam.

The beam starts at the origin along +x (d3 = x, d1 = y, d2 = z), node 0 is clamped (position
and orientation, Eq. 4.10) and a constant force ``tip_force`` (N, inertial frame) acts on the
last node.  Gravity is off by default (``gravity=0``) so the static answer is the textbook
one: Timoshenko tip deflection ``P L³/(3 E I) + P L/(κ G A)`` for small loads, the elastica
for large ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.assembly import SystemBuilder, director_configuration
from fuzzygait.mechanics.beam import BeamSection, GivenStiffness, add_beam
from fuzzygait.mechanics.discrete import DiscreteModel
from fuzzygait.mechanics.geometry import BladeMesh, straight_beam
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.sections import SHEAR_CORRECTION_RECTANGLE, RectangleSection
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.trajectory import Trajectory

BEAM_PARAMETERS: tuple[str, ...] = ("E", "nu", "rho", "eta")


@dataclass
class Cantilever:
    """A built cantilever: the model, its reference configuration and section data.

    Attributes:
        model: the discrete model (parameters :data:`BEAM_PARAMETERS`).
        q0: (12 n,) reference configuration.
        length, width, thickness: m (width along y, thickness along z).
        section: the rectangle section.
        nodes: node count.
    """

    model: DiscreteModel
    q0: np.ndarray
    length: float
    width: float
    thickness: float
    section: RectangleSection
    nodes: int

    def tip_position(self, trajectory: Trajectory) -> np.ndarray:
        """(N+1, 3) position of the loaded end (m)."""
        return trajectory.q[:, -12:-9]

    def timoshenko_tip_deflection(self, force: float, modulus: float, poisson: float) -> float:
        """Linear Timoshenko tip deflection (m) under a transverse tip force (N) along z."""
        shear = modulus / (2 * (1 + poisson))
        i1 = float(self.section.second_moment_1)
        area = float(self.section.area)
        return force * self.length**3 / (3 * modulus * i1) + force * self.length / (
            SHEAR_CORRECTION_RECTANGLE * shear * area
        )

    def run(self, p, dt: float, n_steps: int, *, sensitivities: bool = False, **settings: Any) -> Trajectory:
        """Integrate ``n_steps`` steps of ``dt`` (s) from rest in the reference configuration;
        ``settings``: the other fields of :class:`.solver.SolverSettings` (scheme, tolerance, ...)."""
        solver = SolverSettings(dt=dt, n_steps=n_steps, **settings)
        return integrate(self.model, self.q0, None, p, solver, sensitivities=sensitivities)


def build_clamped_beam(
    mesh: BladeMesh,
    tip_force: tuple[float, float, float],
    gravity: float = 0.0,
    compile: bool = True,
    stiffness=None,
    reference_modulus: float | None = None,
) -> tuple[DiscreteModel, np.ndarray]:
    """A beam on ``mesh`` (attachment frame = inertial frame) clamped at node 0 (position and
    orientation, Eq. 4.10) with a constant force (N) on its last node.  Optional effective
    section ``stiffness`` (e.g. the homogenised three-layer blade) as in
    :func:`~fuzzygait.mechanics.beam.add_beam`.  Returns the model (parameters
    :data:`BEAM_PARAMETERS`) and the reference configuration."""
    nodes = mesh.n_nodes
    names = [f"node{k:03d}" for k in range(nodes)]
    builder = SystemBuilder(names, BEAM_PARAMETERS, gravity=gravity)
    builder.key_parts.append(f"clamped-beam:gravity={gravity != 0}")
    reference = np.array([director_configuration(x, d) for x, d in zip(mesh.positions, mesh.directors)])
    bodies = [builder.body(name) for name in names]
    for body in bodies:
        builder.add_internal_constraints(body)
    section = RectangleSection(width=mesh.width, height=mesh.total_thickness())
    add_beam(
        builder, "beam", bodies, reference, mesh.element_length,
        BeamSection(section.area, section.second_moment_1, section.second_moment_2,
                    section.torsion_constant, SHEAR_CORRECTION_RECTANGLE),
        given=GivenStiffness.optional(stiffness, reference_modulus),
    )
    builder.add_clamp("clamp", bodies[0], mesh.positions[0], mesh.directors[0])
    force = builder.constant("tip_force", tip_force)
    tip = bodies[-1].position(builder.q)
    builder.add_load_potential(-(force[0] * tip[0] + force[1] * tip[1] + force[2] * tip[2]))
    return DiscreteModel.from_builder(builder, compile=compile), reference.ravel()


def build_cantilever(
    length: float,
    width: float,
    thickness: float,
    nodes: int,
    tip_force: tuple[float, float, float],
    gravity: float = 0.0,
    compile: bool = True,
) -> Cantilever:
    """Assemble a clamped straight beam along +x with a constant tip force (N)."""
    for name, value in (("length", length), ("width", width), ("thickness", thickness)):
        if not (np.isfinite(value) and value > 0):
            raise ParameterError(f"cantilever {name} must be > 0 m; got {value}")
    if nodes < 2:
        raise ParameterError(f"a cantilever needs at least 2 nodes; got {nodes}")
    mesh = straight_beam(length, width, thickness, nodes)
    model, q0 = build_clamped_beam(mesh, tip_force, gravity=gravity, compile=compile)
    single = RectangleSection(width=np.asarray(width, dtype=float), height=np.asarray(thickness, dtype=float))
    return Cantilever(model, q0, length, width, thickness, single, nodes)
