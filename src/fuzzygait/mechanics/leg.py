"""The leg + prosthesis model (thesis §4.2): thigh, shank and a beam (or rigid) foot.

Frames and conventions (inertial frame: x forward, y lateral/left, z up, gravity along −z):

* Thigh and shank are rigid bodies in director form.  Their directors: d1 = lateral axis
  (the knee's hinge axis, J1), d3 = long axis pointing proximally (J3), d2 = d3 × d1.
* ``hip_angle`` is the hip flexion (rad, thigh forward of the vertical; the thesis' swing
  "hip extension π/6" is −π/6) and ``knee_angle`` the knee flexion (rad, shank behind the
  thigh's line).
* Hip: spherical joint to the inertial point ``hip_position`` (Eq. 4.8).  Knee: revolute
  about the thigh's d1 (Eq. 4.9).  Ankle: the foot's first node (or the rigid foot) rigidly
  connected to the distal end of the shank (Eq. 4.7).  Stance: chosen blade nodes anchored
  in position, free to rotate (Eq. 4.10 without the rotation part).
* The blade is given in its attachment frame (x forward, y lateral, z up at the shank's
  distal end, see :mod:`fuzzygait.mechanics.geometry`); it rotates with the shank.

The parameter vector (what the uncertainty engine may vary) is :data:`LEG_PARAMETERS`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Option
from fuzzygait.mechanics.assembly import SystemBuilder, director_configuration, euler_tensor_principal
from fuzzygait.mechanics.beam import BeamSection, GivenStiffness, add_beam
from fuzzygait.mechanics.geometry import BladeGeometry, BladeMesh, default_blade
from fuzzygait.mechanics.homogenisation import LayerMaterials, coupled_stiffness, standard_stiffness
from fuzzygait.mechanics.presets import SHANK, THIGH, Material, SegmentData
from fuzzygait.mechanics.sections import SHEAR_CORRECTION_RECTANGLE, RectangleSection

LEG_PARAMETERS: tuple[str, ...] = (
    "E",
    "nu",
    "rho",
    "eta",
    "thigh_mass",
    "thigh_J1",
    "thigh_J2",
    "thigh_J3",
    "shank_mass",
    "shank_J1",
    "shank_J2",
    "shank_J3",
)
PARAMETER_UNITS = {
    "E": "Pa", "nu": "1", "rho": "kg/m^3", "eta": "Pa s",
    "thigh_mass": "kg", "thigh_J1": "kg m^2", "thigh_J2": "kg m^2", "thigh_J3": "kg m^2",
    "shank_mass": "kg", "shank_J1": "kg m^2", "shank_J2": "kg m^2", "shank_J3": "kg m^2",
}
FootKind = Literal["beam", "rigid", "none"]
SectionKind = Literal["homogeneous", "standard", "coupled"]


def segment_frame(direction_distal: np.ndarray) -> np.ndarray:
    """Directors (rows d1, d2, d3) of a leg segment whose long axis points ``direction_distal``
    (proximal → distal) in the sagittal x–z plane."""
    d3 = -np.asarray(direction_distal, float) / np.linalg.norm(direction_distal)
    d1 = np.array([0.0, 1.0, 0.0])
    d2 = np.cross(d3, d1)
    return np.array([d1, d2, d3])


def attachment_rotation(shank_frame: np.ndarray) -> np.ndarray:
    """Rotation from the blade's attachment frame (x fwd, y lat, z up) to the inertial frame:
    columns −d2, d1, d3 of the shank."""
    d1, d2, d3 = shank_frame
    return np.column_stack([-d2, d1, d3])


@dataclass(frozen=True)
class RigidFoot:
    """A rigid stand-in for the blade: mass (kg), centre of mass in the attachment frame (m)
    and principal inertias about it along the attachment axes (kg m²)."""

    mass: float
    centre: tuple[float, float, float]
    inertia: tuple[float, float, float]

    @classmethod
    def from_mesh(cls, mesh: BladeMesh, density: float) -> RigidFoot:
        """Mass and centre of the blade; inertia = diagonal of its inertia tensor about that
        centre in the attachment frame, elements as point masses plus their own rod inertia
        (products of inertia are neglected — the rigid foot is a test stand-in)."""
        area = mesh.width * mesh.total_thickness()
        masses = density * area * mesh.element_length
        mids = 0.5 * (mesh.positions[1:] + mesh.positions[:-1])
        total = float(masses.sum())
        centre = (masses[:, None] * mids).sum(axis=0) / total
        r = mids - centre
        tensor = sum(m * (np.dot(x, x) * np.eye(3) - np.outer(x, x)) for m, x in zip(masses, r))
        return cls(total, tuple(centre), tuple(np.diag(tensor)))


@dataclass(frozen=True)
class LegConfiguration:
    """Structure and pose of the leg model.

    Attributes:
        hip_angle, knee_angle: initial hip and knee flexion (rad).
        nodes: beam nodes of the blade (≥ 2).
        foot: "beam" (the prosthesis), "rigid" (blade replaced by a rigid body) or "none".
        anchored_nodes: blade nodes held in position (stance), by index (negative from the toe).
        blade: the blade geometry (default: the packaged Vari-Flex-like file).
        thigh, shank: segment data (Table 4.1).
        hip_position: inertial position of the hip joint centre (m).
        section: "homogeneous" (one material on the whole section, the thesis' §4.2 model),
            or the three-layer blade homogenised by the "standard" (Eq. 4.37) or "coupled"
            (Eqs. 4.38–4.42) approach; these need ``layers`` and then the parameter E is the
            face modulus (the core modulus scales with it).
        layers: face/core materials for the layered sections.
    """

    hip_angle: float
    knee_angle: float
    nodes: int = 20
    foot: FootKind = "beam"
    anchored_nodes: tuple[int, ...] = ()
    blade: BladeGeometry = field(default_factory=default_blade)
    thigh: SegmentData = THIGH
    shank: SegmentData = SHANK
    hip_position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    section: SectionKind = "homogeneous"
    layers: LayerMaterials | None = None

    def __post_init__(self) -> None:
        if self.section not in ("homogeneous", "standard", "coupled"):
            raise ParameterError(f"section must be 'homogeneous', 'standard' or 'coupled'; got {self.section!r}")
        if self.section != "homogeneous" and self.layers is None:
            raise ParameterError(
                f"the {self.section} homogenisation needs the face/core materials (layers=LayerMaterials(...))"
            )
        if self.foot not in ("beam", "rigid", "none"):
            raise ParameterError(f"foot must be 'beam', 'rigid' or 'none'; got {self.foot!r}")
        if self.foot == "beam" and self.nodes < 2:
            raise ParameterError(f"the blade needs at least 2 nodes ({Option.NODES}); got {self.nodes}")
        if self.foot == "beam":
            for k in self.anchored_nodes:
                if not -self.nodes <= k < self.nodes:
                    raise ParameterError(f"anchored node {k} does not exist in a blade of {self.nodes} nodes")


def default_parameters(material: Material, thigh: SegmentData = THIGH, shank: SegmentData = SHANK,
                       shank_mass: float | None = None) -> np.ndarray:
    """The parameter vector (order :data:`LEG_PARAMETERS`) from a material and the segments."""
    return np.array(
        [material.youngs_modulus, material.poisson, material.density, material.damping,
         thigh.mass, *thigh.inertia, shank.mass if shank_mass is None else shank_mass, *shank.inertia],
        dtype=float,
    )


@dataclass
class LegModel:
    """The assembled leg: symbolic system, reference configuration, blade mesh and body names."""

    configuration: LegConfiguration
    builder: SystemBuilder
    q0: np.ndarray
    mesh: BladeMesh | None
    blade_bodies: list[str]
    rigid_foot: RigidFoot | None


def build_leg(configuration: LegConfiguration, rigid_foot_density: float = 8.55e3) -> LegModel:
    """Assemble the leg model (symbolic) and its consistent initial configuration."""
    cfg = configuration
    mesh = cfg.blade.discretise(max(cfg.nodes, 2))
    blade_bodies = [f"blade{k:03d}" for k in range(cfg.nodes)] if cfg.foot == "beam" else []
    names = ["thigh", "shank"] + blade_bodies + (["foot"] if cfg.foot == "rigid" else [])
    b = SystemBuilder(names, LEG_PARAMETERS)
    b.key_parts.append(f"leg:foot={cfg.foot}:anchors={len(cfg.anchored_nodes)}")

    hip = np.asarray(cfg.hip_position, float)
    u_thigh = np.array([np.sin(cfg.hip_angle), 0.0, -np.cos(cfg.hip_angle)])
    shank_angle = cfg.hip_angle - cfg.knee_angle
    u_shank = np.array([np.sin(shank_angle), 0.0, -np.cos(shank_angle)])
    thigh_frame, shank_frame = segment_frame(u_thigh), segment_frame(u_shank)
    knee = hip + cfg.thigh.length * u_thigh
    ankle = knee + cfg.shank.length * u_shank
    q_blocks = {
        "thigh": director_configuration(hip + cfg.thigh.com_from_proximal * u_thigh, thigh_frame),
        "shank": director_configuration(knee + cfg.shank.com_from_proximal * u_shank, shank_frame),
    }
    thigh, shank = b.body("thigh"), b.body("shank")
    for body, prefix in ((thigh, "thigh"), (shank, "shank")):
        j = [b.parameter(f"{prefix}_J{i}") for i in (1, 2, 3)]
        b.add_rigid_body_inertia(body, b.parameter(f"{prefix}_mass"), euler_tensor_principal(*j))
        b.add_internal_constraints(body)
    b.add_spherical_to_ground("hip", thigh, (0.0, 0.0, cfg.thigh.com_from_proximal), hip)
    b.add_revolute(
        "knee", thigh, (0.0, 0.0, -(cfg.thigh.length - cfg.thigh.com_from_proximal)),
        shank, (0.0, 0.0, cfg.shank.com_from_proximal), axis=1,
    )
    ankle_arm = (0.0, 0.0, -(cfg.shank.length - cfg.shank.com_from_proximal))
    rotation = attachment_rotation(shank_frame)
    rigid_foot = None
    if cfg.foot == "beam":
        positions = ankle + mesh.positions @ rotation.T
        frames = np.einsum("ab,kib->kia", rotation, mesh.directors)
        reference = np.array([director_configuration(x, f) for x, f in zip(positions, frames)])
        for name, qk in zip(blade_bodies, reference):
            q_blocks[name] = qk
        nodes = [b.body(name) for name in blade_bodies]
        for node in nodes:
            b.add_internal_constraints(node)
        section = RectangleSection(width=mesh.width, height=mesh.total_thickness())
        stiffness = None
        if cfg.section != "homogeneous":
            assert cfg.layers is not None  # LegConfiguration requires layers for these sections
            homogenise = standard_stiffness if cfg.section == "standard" else coupled_stiffness
            stiffness = homogenise(cfg.layers, mesh.width, mesh.core_thickness, mesh.face_thickness,
                                   shear_factor=SHEAR_CORRECTION_RECTANGLE)
        add_beam(
            b, "blade", nodes, reference, mesh.element_length,
            BeamSection(section.area, section.second_moment_1, section.second_moment_2,
                        section.torsion_constant, SHEAR_CORRECTION_RECTANGLE),
            given=GivenStiffness.optional(stiffness, cfg.layers.face_modulus if cfg.layers is not None else None),
        )
        relative = frames[0] @ shank_frame.T  # relative[i, k] = d_i(node 0) · d_k(shank)
        b.add_rigid("ankle", shank, ankle_arm, nodes[0], (0.0, 0.0, 0.0), relative)
        for k in cfg.anchored_nodes:
            b.add_anchor(f"anchor{k % cfg.nodes}", nodes[k], positions[k])
    elif cfg.foot == "rigid":
        rigid_foot = RigidFoot.from_mesh(mesh, rigid_foot_density)
        foot = b.body("foot")
        centre_world = ankle + rotation @ np.asarray(rigid_foot.centre)
        q_blocks["foot"] = director_configuration(centre_world, shank_frame)
        # inertias along the attachment axes (x fwd = −d2, y = d1, z = d3) → along d1, d2, d3
        jx, jy, jz = rigid_foot.inertia
        mass = b.constant("foot_mass", rigid_foot.mass)
        inertia = b.constant("foot_inertia", [jy, jx, jz])
        b.add_rigid_body_inertia(foot, mass, euler_tensor_principal(inertia[0], inertia[1], inertia[2]))
        b.add_internal_constraints(foot)
        # foot centre in the shank's director coordinates: x_att = −d2 → local (y, −x, z)
        local = (rigid_foot.centre[1], -rigid_foot.centre[0], rigid_foot.centre[2])
        b.add_rigid("ankle", shank, np.add(ankle_arm, local), foot, (0.0, 0.0, 0.0), np.eye(3))
    q0 = np.concatenate([q_blocks[name] for name in names])
    return LegModel(cfg, b, q0, mesh if cfg.foot == "beam" else None, blade_bodies, rigid_foot)
