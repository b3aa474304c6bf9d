"""Predeformed geometrically exact beam in director form (thesis §4.2.1, Eqs. 4.30–4.33).

Each beam node is a 12-coordinate block ``[φ, d1, d2, d3]`` like a rigid body; d3 is the
tangent of the unstressed centreline, d1 and d2 span the cross-section (d1 along the width
b, d2 along the thickness a).  One two-node element with one-point (midpoint) quadrature
gives, with ``φ' = (φ_b − φ_a)/L``, ``d_i = (d_ia + d_ib)/2``, ``d_i' = (d_ib − d_ia)/L``:

* ``Γ_i = d_i·φ' − [d_i·φ']_ref`` (shear Γ1, Γ2 and elongation Γ3, Eq. 4.31),
* ``K_i = ½ ε_ijk (d_k·d_j' − [d_k·d_j']_ref)`` (bending K1, K2 and torsion K3, Eq. 4.32),

relative to the curved reference, so the reference configuration is stress free.  Stored
energy (Eq. 4.30) ``W_e = L/2 (Γᵀ D^Γ Γ + Kᵀ D^K K)`` with ``D^Γ = diag(κGA, κGA, EA)``
and ``D^K = diag(EI_1, EI_2, GJ)``; Kelvin–Voigt dissipation (Eq. 4.33)
``V_visc,e = L/2 (Γ̇ᵀ D^η1 Γ̇ + K̇ᵀ D^η2 K̇)`` with ``D^η1 = η diag(κA, κA, A)`` and
``D^η2 = η diag(I_1, I_2, J)`` (η in Pa·s, the thesis' η_E = η_G = η).  Inertia: consistent
linear-element mass for φ (ρA) and for the directors (Euler tensor: ρI_2 on d1 — the
spread of mass along d1 — and ρI_1 on d2; d3 carries none).  Gravity acts on ρA.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.assembly import Body, ElementGroup, SystemBuilder, dot3
from fuzzygait.mechanics.homogenisation import SectionStiffness


def element_strains(qa, qb, length):
    """Strain measures ``(γ1, γ2, γ3, κ1, κ2, κ3)`` of one element, not yet referenced.

    ``qa``, ``qb`` are the 12-coordinate blocks of the element's nodes (numpy arrays or CasADi
    SX), ``length`` the reference element length (m).  Returns a list of six scalars
    (γ dimensionless, κ in 1/m).
    """
    phi_a, phi_b = qa[0:3], qb[0:3]
    da = [qa[3 + 3 * i : 6 + 3 * i] for i in range(3)]
    db = [qb[3 + 3 * i : 6 + 3 * i] for i in range(3)]
    dphi = (phi_b - phi_a) / length
    d = [(da[i] + db[i]) / 2 for i in range(3)]
    dd = [(db[i] - da[i]) / length for i in range(3)]
    gamma = [dot3(d[i], dphi) for i in range(3)]
    kappa = [
        0.5 * (dot3(d[2], dd[1]) - dot3(d[1], dd[2])),
        0.5 * (dot3(d[0], dd[2]) - dot3(d[2], dd[0])),
        0.5 * (dot3(d[1], dd[0]) - dot3(d[0], dd[1])),
    ]
    return gamma + kappa


@dataclass(frozen=True)
class BeamSection:
    """Cross-section data per element (arrays of length n_elements, SI units).

    Attributes:
        area: A (m²).
        second_moment_1: I_1 = ∫ x2² dA (m⁴), bending about d1.
        second_moment_2: I_2 = ∫ x1² dA (m⁴), bending about d2.
        torsion_constant: Saint-Venant J (m⁴).
        shear_factor: shear correction factor κ (5/6 for a rectangle).
    """

    area: np.ndarray
    second_moment_1: np.ndarray
    second_moment_2: np.ndarray
    torsion_constant: np.ndarray
    shear_factor: float = 5.0 / 6.0


BEAM_KERNEL = "gebeam2-midpoint-v1"
# per element: L, A, I1, I2, J, κ, six reference strains, then (given stiffness only) the six
# stiffnesses κGA-like A_1, A_2, A_3 (N) and C_1, C_2, C_3 (N m²) at the modulus E_ref, and E_ref
N_ELEMENT_CONSTANTS = {"homogeneous": 12, "given": 19}


def _beam_kernels(law: str = "homogeneous") -> dict[str, ca.Function]:
    """Element kernels of the two-node beam element (see the module docstring and
    :class:`~fuzzygait.mechanics.assembly.ElementGroup`).

    ``law`` "homogeneous": ``D^Γ = diag(κGA, κGA, EA)``, ``D^K = diag(EI_1, EI_2, GJ)`` from
    the parameters E, ν; "given": the element's effective stiffnesses (e.g. the homogenised
    three-layer values of Eqs. 4.37–4.42) scaled by ``E / E_ref`` — the parameter E then
    scales face and core moduli together (ν is not used).
    """
    qe = ca.SX.sym("qe", 24)
    ve = ca.SX.sym("ve", 24)
    ce = ca.SX.sym("ce", N_ELEMENT_CONSTANTS[law])
    pe = ca.SX.sym("pe", 3)  # E (Pa), ν, η (Pa s)
    length, area, i1, i2, torsion, shear_factor = (ce[k] for k in range(6))
    modulus, poisson, damping = pe[0], pe[1], pe[2]
    shear_modulus = modulus / (2 * (1 + poisson))
    raw = ca.vertcat(*element_strains(qe[:12], qe[12:], length))
    strain = raw - ce[6:12]
    if law == "given":
        stiffness = ce[12:18] * (modulus / ce[18])
    else:
        stiffness = ca.vertcat(
            shear_factor * shear_modulus * area,
            shear_factor * shear_modulus * area,
            modulus * area,
            modulus * i1,
            modulus * i2,
            shear_modulus * torsion,
        )
    energy = 0.5 * length * ca.sum1(stiffness * strain**2)
    rate = ca.jtimes(raw, qe, ve)
    viscosity = damping * ca.vertcat(shear_factor * area, shear_factor * area, area, i1, i2, torsion)
    dissipation = 0.5 * length * ca.sum1(viscosity * rate**2)
    # element force of the step equations: ∇W − f with the viscous force f = −∂V_visc/∂v
    viscous = ca.gradient(dissipation, ve)
    force = ca.gradient(energy, qe) + viscous
    args = [qe, ve, ce, pe]
    # energy-momentum variant: the strains are quadratic in q, so with the interval midpoint
    # q_m and velocity v, (Γ(q_a) + Γ(q_b))/2 = Γ(q_m) + h²/8 ∇²Γ[v, v] exactly and
    # B(q_m)(q_b − q_a) = Γ(q_b) − Γ(q_a): the force B(q_m)ᵀ D (Γ_a + Γ_b)/2 does exactly the
    # work W(q_b) − W(q_a) (discrete gradient, Betsch & Steinmann), and the viscous force
    # B(q_m)ᵀ D^η B(q_m) v dissipates exactly h · 2 V_visc(q_m, v).
    h = ca.SX.sym("h")
    curvature = ca.jtimes(ca.jtimes(raw, qe, ve), qe, ve)  # ∇²Γ[v, v]
    averaged = strain + h**2 / 8 * curvature
    em_force = length * ca.mtimes(ca.jacobian(raw, qe).T, stiffness * averaged) + viscous
    em_args = [qe, ve, ce, pe, h]
    return {
        "em_force": ca.Function("beam_em_force", em_args, [em_force]),
        "em_tangent": ca.Function(
            "beam_em_tangent",
            em_args,
            [em_force, ca.densify(ca.jacobian(em_force, qe)), ca.densify(ca.jacobian(em_force, ve))],
        ),
        "em_parameters": ca.Function("beam_em_parameters", em_args, [ca.densify(ca.jacobian(em_force, pe))]),
        "force": ca.Function("beam_force", args, [force]),
        "tangent": ca.Function(
            "beam_tangent", args, [force, ca.densify(ca.jacobian(force, qe)), ca.densify(ca.jacobian(force, ve))]
        ),
        "parameters": ca.Function("beam_parameters", args, [ca.densify(ca.jacobian(force, pe))]),
        "energy": ca.Function(
            "beam_energy",
            args,
            [energy, 2 * dissipation, ca.densify(ca.gradient(energy, qe)), ca.densify(ca.jacobian(energy, pe))],
        ),
    }


@dataclass(frozen=True)
class BeamParameterNames:
    """Names of the beam's material parameters in the builder's parameter vector.

    Attributes:
        modulus: Young's modulus E (Pa).
        poisson: Poisson ratio ν (dimensionless).
        density: density ρ (kg/m³).
        damping: Kelvin–Voigt viscosity η (Pa·s).
    """

    modulus: str = "E"
    poisson: str = "nu"
    density: str = "rho"
    damping: str = "eta"

    def element_indices(self, parameter_names: Sequence[str]) -> tuple[int, int, int]:
        """Positions of E, ν and η in ``parameter_names`` (the element kernels' ``pe``);
        :class:`ParameterError` when one of the four names is not among them."""
        names = list(parameter_names)
        for field_name in ("modulus", "poisson", "density", "damping"):
            name = getattr(self, field_name)
            if name not in names:
                raise ParameterError(f"beam {field_name} parameter {name!r} is not a parameter of the model; "
                                     f"choose one of {', '.join(names)}")  # fmt: skip
        return names.index(self.modulus), names.index(self.poisson), names.index(self.damping)


@dataclass(frozen=True)
class GivenStiffness:
    """Effective section stiffnesses used as ``D^Γ``/``D^K`` instead of the homogeneous
    formulas (the "given" law of the element kernels).

    Attributes:
        stiffness: the stiffnesses per element or for all elements, e.g. the standard or coupled
            homogenisation of the three-layer blade: shear ``A₁``, ``A₂`` and axial ``A₃`` (N),
            bending ``C₁``, ``C₂`` and torsion ``C₃`` (N m²), in the section frame (d1, d2, d3).
        reference_modulus: the modulus E_ref (Pa) they were computed for; in the model they are
            scaled by ``E / E_ref`` with the beam's parameter E.
    """

    stiffness: SectionStiffness
    reference_modulus: float

    def __post_init__(self) -> None:
        _check_reference_modulus(self.reference_modulus)

    @classmethod
    def optional(cls, stiffness: SectionStiffness | None, reference_modulus: float | None) -> GivenStiffness | None:
        """None without ``stiffness`` (the homogeneous law), else the given stiffness;
        :class:`ParameterError` when ``reference_modulus`` is missing or not > 0."""
        return None if stiffness is None else cls(stiffness, _check_reference_modulus(reference_modulus))

    def values(self, n_el: int) -> np.ndarray:
        """The element constants of the given law: ``(n_el, 7)``, the six stiffnesses then E_ref."""
        values = np.column_stack(
            [np.broadcast_to(np.asarray(getattr(self.stiffness, name), float), n_el) for name in
             ("shear_1", "shear_2", "axial", "bending_1", "bending_2", "torsion")]
        )  # fmt: skip
        return np.column_stack([values, np.full(n_el, float(self.reference_modulus))])


def _check_reference_modulus(value: float | None) -> float:
    """``value`` when it is a finite modulus > 0 (Pa), else :class:`ParameterError`."""
    if value is None or not (np.isfinite(value) and value > 0):
        raise ParameterError(f"given section stiffnesses need reference_modulus > 0 Pa (the E they were computed "
                             f"for); got {value}")  # fmt: skip
    return value


def _element_constants(reference: np.ndarray, element_length: np.ndarray, section: BeamSection,
                       given: GivenStiffness | None) -> np.ndarray:  # fmt: skip
    """The ``(n_el, k)`` element constants of the kernels (``N_ELEMENT_CONSTANTS``): L, A,
    I_1, I_2, J, κ, the six reference strains and, with ``given``, its stiffnesses and E_ref."""
    n_el = len(element_length)
    reference_strains = np.array(
        [element_strains(reference[e], reference[e + 1], element_length[e]) for e in range(n_el)]
    )
    constants = np.column_stack(
        [
            element_length,
            np.broadcast_to(section.area, n_el),
            np.broadcast_to(section.second_moment_1, n_el),
            np.broadcast_to(section.second_moment_2, n_el),
            np.broadcast_to(section.torsion_constant, n_el),
            np.full(n_el, section.shear_factor),
            reference_strains,
        ]
    )
    return constants if given is None else np.column_stack([constants, given.values(n_el)])


def _add_inertia_and_gravity(builder: SystemBuilder, label: str, nodes: Sequence[Body], constants: np.ndarray,
                             density: str) -> None:  # fmt: skip
    """The consistent mass of every element (φ and directors) and the gravity energy of ρA."""
    n_el = len(nodes) - 1
    rho = builder.parameter(density)
    q = builder.q
    lengths = builder.constant(f"{label}_length", constants[:, 0])
    area = builder.constant(f"{label}_area", constants[:, 1])
    i1 = builder.constant(f"{label}_I1", constants[:, 2])
    i2 = builder.constant(f"{label}_I2", constants[:, 3])
    pick = (lambda x, e: x[e]) if n_el > 1 else (lambda x, e: x)
    for e in range(n_el):
        a, b = nodes[e], nodes[e + 1]
        length, A = pick(lengths, e), pick(area, e)
        # consistent mass of a linear element: L/6 [[2, 1], [1, 2]] per unit line density;
        # Euler tensor of the section: ρ∫x1² dA = ρI_2 on d1, ρ∫x2² dA = ρI_1 on d2, none on d3
        for block, line_density in ((0, rho * A), (1, rho * pick(i2, e)), (2, rho * pick(i1, e))):
            builder.add_coupled_inertia(a, b, block, line_density * length / 3, line_density * length / 6)
        builder.add_gravity_energy(rho * A * length * builder.gravity * 0.5 * (a.position(q)[2] + b.position(q)[2]))


def add_beam(
    builder: SystemBuilder,
    label: str,
    nodes: Sequence[Body],
    reference: np.ndarray,
    element_length: np.ndarray,
    section: BeamSection,
    names: BeamParameterNames = BeamParameterNames(),
    given: GivenStiffness | None = None,
) -> None:
    """Add a beam's elements, inertia and gravity to ``builder``.

    Args:
        label: the beam's name (its element group and constants).
        nodes: the node bodies in order along the beam (at least 2).
        reference: (n_nodes, 12) reference (unstressed) configuration, inertial frame.
        element_length: (n_nodes − 1,) reference element lengths (m), each > 0.
        section: per-element cross-section data.
        names: the names of E, ν, ρ and η in the builder's parameter vector.
        given: optional effective section stiffnesses used instead of the homogeneous
            formulas (scaled by ``E / E_ref``).
    """
    n_el = len(nodes) - 1
    element_length = np.asarray(element_length, float)
    reference = np.asarray(reference, float)
    if n_el < 1 or element_length.shape != (n_el,) or reference.shape != (n_el + 1, 12):
        raise ParameterError(f"beam {label!r} needs ≥ 2 nodes, (n_nodes, 12) reference coordinates and n_nodes − 1 "
                             f"element lengths; got {n_el + 1} nodes, reference {reference.shape}, lengths "
                             f"{element_length.shape}")  # fmt: skip
    if not np.all(np.isfinite(element_length) & (element_length > 0)):
        raise ParameterError(f"beam {label!r} element lengths must be finite and > 0 m; got {element_length}")
    indices = names.element_indices(builder.parameter_names)
    constants = _element_constants(reference, element_length, section, given)
    law = "homogeneous" if given is None else "given"
    builder.add_element_group(
        ElementGroup(
            name=label,
            kernel_name=f"{BEAM_KERNEL}:{law}",
            kernels=_beam_kernels(law),
            node_offsets=np.array([[nodes[e].offset, nodes[e + 1].offset] for e in range(n_el)]),
            constants=constants,
            parameter_indices=indices,
        )
    )
    _add_inertia_and_gravity(builder, label, nodes, constants, names.density)
