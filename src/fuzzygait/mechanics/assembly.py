"""Symbolic assembly of a constrained multibody system in director form (thesis §4.1).

Every body — a rigid segment or one node of a geometrically exact beam — has the
configuration ``q^k = [φ, d1, d2, d3] ∈ R¹²`` (Eq. 4.1): the position of its centre of mass
(m, inertial frame, z up) and an orthonormal director triad.  The builder collects, as CasADi
``SX`` expressions of the stacked configuration ``q``, the velocity ``v``, the physical
parameters ``p`` (what the uncertainty engine may vary: moduli, densities, masses, …) and the
constants ``c`` (geometry, reference strains, joint offsets — numbers that fix a case but not
its structure):

* the constant mass matrix ``M(p, c)`` with the Euler-tensor principal values (Eq. 4.5),
* the potential energy of gravity along −z and of constant loads, linear in ``q`` (Eq. 4.6),
* the constraints ``g(q, c) = 0`` (internal Eq. 4.2 and joints Eqs. 4.7–4.10),
* element groups (:class:`ElementGroup`): a kernel giving one element's stored-energy
  gradient and dissipative force and their derivatives, evaluated for all elements at once
  and assembled like a finite-element code (the beam's Eqs. 4.30–4.33).

The structure key (body count, joint kinds and connectivity, output names) identifies the
generated code: two systems with the same key differ only in ``p`` and ``c`` and share one
compiled library.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

GRAVITY = 9.81  # m/s², along −z


def dot3(u, w):
    """Scalar product of two 3-vectors (numpy arrays or CasADi SX alike)."""
    return u[0] * w[0] + u[1] * w[1] + u[2] * w[2]


@dataclass(frozen=True)
class Body:
    """One 12-coordinate block of ``q``: ``offset`` is the index of φ_x in ``q``."""

    name: str
    offset: int

    def position(self, q):
        return q[self.offset : self.offset + 3]

    def director(self, q, i: int):
        """Director ``d_i`` (i = 1, 2, 3)."""
        start = self.offset + 3 * i
        return q[start : start + 3]

    def point(self, q, local):
        """Body-fixed point ``φ + Σ local_i d_i`` (local in m, in the director frame)."""
        return self.position(q) + sum(local[i] * self.director(q, i + 1) for i in range(3))


def director_configuration(position: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """``q^k`` (12,) from a position (3,) and a frame whose rows are d1, d2, d3."""
    return np.concatenate([np.asarray(position, float), np.asarray(frame, float).reshape(9)])


def euler_tensor_principal(j1, j2, j3):
    """Principal values of the Euler tensor ``E_i = ∫ X_i² dm`` from the moments of inertia.

    ``J_1 = E_2 + E_3`` (and cyclic) gives ``E_1 = (J_2 + J_3 − J_1) / 2`` (kg m²).
    """
    return (0.5 * (j2 + j3 - j1), 0.5 * (j3 + j1 - j2), 0.5 * (j1 + j2 - j3))


@dataclass
class SystemBuilder:
    """Collects the symbolic pieces of one multibody system.

    Args:
        body_names: names of the 12-coordinate blocks, in the order of ``q``.
        parameter_names: names of the entries of ``p`` (the varying physical parameters).
    """

    body_names: Sequence[str]
    parameter_names: Sequence[str]
    gravity: float = GRAVITY
    key_parts: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.bodies = {name: Body(name, 12 * k) for k, name in enumerate(self.body_names)}
        self.ndof = 12 * len(self.body_names)
        self.q = ca.SX.sym("q", self.ndof)
        self.v = ca.SX.sym("v", self.ndof)
        self.p = ca.SX.sym("p", len(self.parameter_names))
        self._c_symbols: list[ca.SX] = []
        self._c_values: list[np.ndarray] = []
        self.constant_names: list[tuple[str, int]] = []
        self.mass = ca.SX(self.ndof, self.ndof)
        self.gravity_energy = ca.SX(0)
        self.load_potential = ca.SX(0)
        self.constraints: list[ca.SX] = []
        self.constraint_labels: list[str] = []
        self.element_groups: list[ElementGroup] = []
        self.key_parts.append("bodies=" + ",".join(self.body_names))
        self.key_parts.append("p=" + ",".join(self.parameter_names))

    # -- symbols --------------------------------------------------------------------------
    def parameter(self, name: str) -> ca.SX:
        """The symbol of parameter ``name``."""
        return self.p[list(self.parameter_names).index(name)]

    def constant(self, name: str, value) -> ca.SX:
        """A constant input (geometry, offsets, …) with its numeric value; returns its symbol."""
        value = np.atleast_1d(np.asarray(value, dtype=float)).ravel()
        symbol = ca.SX.sym(name, value.size)
        self._c_symbols.append(symbol)
        self._c_values.append(value)
        self.constant_names.append((name, value.size))
        return symbol if value.size > 1 else symbol[0]

    @property
    def c(self) -> ca.SX:
        return ca.vertcat(*self._c_symbols) if self._c_symbols else ca.SX(0, 1)

    @property
    def constant_values(self) -> np.ndarray:
        return np.concatenate(self._c_values) if self._c_values else np.zeros(0)

    def body(self, name: str) -> Body:
        return self.bodies[name]

    # -- mass and energies ----------------------------------------------------------------
    def add_rigid_body_inertia(self, body: Body, mass, euler) -> None:
        """Mass ``m`` on φ and Euler-tensor values ``E_i`` on ``d_i`` (kg, kg m²)."""
        o = body.offset
        for axis in range(3):
            self.mass[o + axis, o + axis] += mass
            for i in range(3):
                self.mass[o + 3 * (i + 1) + axis, o + 3 * (i + 1) + axis] += euler[i]
        self.gravity_energy += mass * self.gravity * body.position(self.q)[2]

    def add_coupled_inertia(self, a: Body, b: Body, block: int, diag, off) -> None:
        """Consistent-mass coupling of block ``block`` (0 = φ, i = d_i) of two bodies."""
        for axis in range(3):
            ia = a.offset + 3 * block + axis
            ib = b.offset + 3 * block + axis
            self.mass[ia, ia] += diag
            self.mass[ib, ib] += diag
            self.mass[ia, ib] += off
            self.mass[ib, ia] += off

    def add_gravity_energy(self, expression) -> None:
        """Gravitational potential energy (J) of distributed mass (e.g. a beam)."""
        self.gravity_energy += expression

    def add_load_potential(self, expression) -> None:
        """Potential of a constant external load (J), e.g. ``−F·φ_tip`` of a tip force."""
        self.load_potential += expression

    @property
    def linear_potential(self) -> ca.SX:
        """Gravity plus constant loads (J), linear in ``q``."""
        return self.gravity_energy + self.load_potential

    def add_element_group(self, group: ElementGroup) -> None:
        self.element_groups.append(group)
        self.key_parts.append(f"elements:{group.name}:{group.kernel_name}:{len(group.node_offsets)}")

    # -- constraints ----------------------------------------------------------------------
    def add_constraints(self, label: str, expressions: Sequence) -> None:
        for k, expression in enumerate(expressions):
            self.constraints.append(expression)
            self.constraint_labels.append(f"{label}[{k}]")
        self.key_parts.append(f"g:{label}:{len(expressions)}")

    def add_internal_constraints(self, body: Body) -> None:
        """Orthonormality of the directors (Eq. 4.2)."""
        q = self.q
        d1, d2, d3 = (body.director(q, i) for i in (1, 2, 3))
        self.add_constraints(
            f"internal:{body.name}",
            [
                0.5 * (dot3(d1, d1) - 1),
                0.5 * (dot3(d2, d2) - 1),
                0.5 * (dot3(d3, d3) - 1),
                dot3(d1, d2),
                dot3(d3, d1),
                dot3(d2, d3),
            ],
        )

    def add_spherical_to_ground(self, label: str, body: Body, local, point) -> None:
        """Spherical joint of a body point to a fixed point (Eq. 4.8 with body 1 = ground)."""
        anchor = self.constant(f"{label}_point", point)
        arm = self.constant(f"{label}_arm", local)
        x = body.point(self.q, arm)
        self.add_constraints(label, [x[i] - anchor[i] for i in range(3)])

    def add_spherical(self, label: str, first: Body, local1, second: Body, local2) -> list:
        """Coincident body points of two bodies (the translational part of Eqs. 4.7–4.9)."""
        arm1 = self.constant(f"{label}_arm1", local1)
        arm2 = self.constant(f"{label}_arm2", local2)
        x1 = first.point(self.q, arm1)
        x2 = second.point(self.q, arm2)
        return [x2[i] - x1[i] for i in range(3)]

    def add_revolute(self, label: str, first: Body, local1, second: Body, local2, axis: int) -> None:
        """Revolute joint (Eq. 4.9): coincident points and the hinge ``n = d_axis`` of body 1
        kept perpendicular to the two other directors of body 2 (both bodies share the axis
        index in their reference configuration)."""
        position = self.add_spherical(label, first, local1, second, local2)
        n = first.director(self.q, axis)
        others = [i for i in (1, 2, 3) if i != axis]
        self.add_constraints(label, position + [dot3(n, second.director(self.q, i)) for i in others])

    def add_rigid(self, label: str, first: Body, local1, second: Body, local2, relative) -> None:
        """Rigid connection (Eq. 4.7): coincident points and three orientation conditions.

        ``relative[i, k]`` expresses the second body's reference director ``d_{i+1}`` in the
        first body's directors; with ``e_i = Σ_k relative[i, k] d_k^1`` the orientation
        conditions are ``d_1^2·e_2 = d_2^2·e_3 = d_3^2·e_1 = 0`` (full rank at the reference).
        """
        position = self.add_spherical(label, first, local1, second, local2)
        r = self.constant(f"{label}_relative", np.asarray(relative, float).reshape(9))
        frame = [sum(r[3 * i + k] * first.director(self.q, k + 1) for k in range(3)) for i in range(3)]
        d = [second.director(self.q, i) for i in (1, 2, 3)]
        self.add_constraints(label, position + [dot3(d[0], frame[1]), dot3(d[1], frame[2]), dot3(d[2], frame[0])])

    def add_clamp(self, label: str, body: Body, position, frame) -> None:
        """Fix a body's position and orientation to the given values (Eq. 4.10, written as
        3 position + 3 orientation conditions so it stays independent of Eq. 4.2)."""
        x0 = self.constant(f"{label}_position", position)
        e = self.constant(f"{label}_frame", np.asarray(frame, float).reshape(9))
        frame_sym = [e[3 * i : 3 * i + 3] for i in range(3)]
        d = [body.director(self.q, i) for i in (1, 2, 3)]
        x = body.position(self.q)
        self.add_constraints(
            label,
            [x[i] - x0[i] for i in range(3)]
            + [dot3(d[0], frame_sym[1]), dot3(d[1], frame_sym[2]), dot3(d[2], frame_sym[0])],
        )

    def add_anchor(self, label: str, body: Body, position) -> None:
        """Fix a body's position, leaving its rotation free (stance: blade nodes on the ground)."""
        x0 = self.constant(f"{label}_position", position)
        x = body.position(self.q)
        self.add_constraints(label, [x[i] - x0[i] for i in range(3)])

    # -- result ---------------------------------------------------------------------------
    @property
    def g(self) -> ca.SX:
        return ca.vertcat(*self.constraints) if self.constraints else ca.SX(0, 1)

    @property
    def structure_key(self) -> str:
        constants = "c=" + ",".join(f"{n}:{s}" for n, s in self.constant_names)
        return "|".join(self.key_parts + [constants])


@dataclass(frozen=True)
class ElementGroup:
    """Two-node elements sharing one kernel (e.g. the elements of one beam).

    Each kernel is a CasADi SX function of one element's ``(q_e, v_e, c_e, p_e)`` — q_e, v_e
    (24,) the stacked blocks of its two nodes, c_e its constants, p_e the parameters it uses:

    * ``force``: the element force ``∇W_e(q_e) − f_e(q_e, v_e)`` (24,),
    * ``tangent``: that force and its Jacobians with respect to q_e and v_e (24 × 24 each),
    * ``parameters``: its Jacobian with respect to p_e (24 × n_pe),
    * ``energy``: ``W_e``, the dissipation rate ``2 V_visc,e``, ``∇W_e`` and ``∂W_e/∂p_e``.

    Attributes:
        name: group name (e.g. "blade").
        kernel_name: identifies the element formulation in the structure key.
        kernels: the CasADi functions by kind.
        node_offsets: (n_el, 2) offsets in ``q`` of the element's two node blocks.
        constants: (n_el, k) per-element constants.
        parameter_indices: indices in ``p`` of the kernel's parameters.
    """

    name: str
    kernel_name: str
    kernels: dict
    node_offsets: np.ndarray
    constants: np.ndarray
    parameter_indices: tuple[int, ...]

    @property
    def dofs(self) -> np.ndarray:
        """(n_el, 24) global indices of each element's coordinates."""
        a = self.node_offsets[:, :1] + np.arange(12)
        b = self.node_offsets[:, 1:] + np.arange(12)
        return np.hstack([a, b])
