"""The three-layer blade under a tip load with uncertain layers (thesis §5.4).

The blade alone is clamped at its attachment (node 0, position and orientation) and loaded
by a constant force on its toe; its section is the coupled homogenisation of face and core
(Eqs. 4.38–4.42).  :class:`LayeredBladeModel` exposes the total deformation energy or a toe
coordinate over time as a function of the face modulus, the core modulus and the face
thickness, for the uncertainty engine.  The homogenised stiffness is not a CasADi
expression of these parameters, so the engine differentiates by finite differences
(counted as forward simulations); the compiled library is shared by all evaluations (the
parameters change only the constant inputs).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.cantilever import build_clamped_beam
from fuzzygait.mechanics.geometry import BladeGeometry, default_blade
from fuzzygait.mechanics.homogenisation import LayerMaterials, coupled_stiffness, standard_stiffness
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.trajectory import trajectory_energies
from fuzzygait.uncertainty.protocol import Evaluation, Output

LAYER_PARAMETERS: tuple[str, ...] = ("face_modulus", "core_modulus", "face_thickness")
LAYER_UNITS = {"face_modulus": "Pa", "core_modulus": "Pa", "face_thickness": "m"}
LAYER_TARGETS = ("total_deformation_energy", "toe_x", "toe_z")


@dataclass
class LayeredBladeModel:
    """Target output of the clamped, tip-loaded layered blade for (E_f, E_c, t_f).

    Args:
        target: "total_deformation_energy" (J), "toe_x" or "toe_z" (m).
        face_modulus, core_modulus: base moduli (Pa); the face value is Table 4.2's, the core
            one an assumption (the thesis could not identify the core material; §4.3).
        face_thickness: base t_f (m, §4.3).
        poisson, density: common Poisson ratio and density (kg/m³) of both layers.
        damping: Kelvin–Voigt η (Pa s) so the blade settles under the load.
        tip_force: force on the toe (N, blade attachment frame: x forward, z up).
        nodes, dt, duration: discretisation (s).
        homogenisation: "coupled" (Eqs. 4.38–4.42) or "standard" (Eq. 4.37).
    """

    target: str = "total_deformation_energy"
    face_modulus: float = 59.958e9
    core_modulus: float = 59.958e9 / 10
    face_thickness: float = 0.0005
    poisson: float = 0.265
    density: float = 1.71e3
    damping: float = 1e8
    tip_force: tuple[float, float, float] = (0.0, 0.0, 500.0)
    nodes: int = 20
    dt: float = 1e-3
    duration: float = 0.3
    homogenisation: str = "coupled"
    blade: BladeGeometry = field(default_factory=default_blade)
    names: Sequence[str] = LAYER_PARAMETERS
    runs: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        if self.target not in LAYER_TARGETS:
            raise ParameterError(f"unknown target {self.target!r}; choose one of {', '.join(LAYER_TARGETS)}")
        if self.homogenisation not in ("coupled", "standard"):
            raise ParameterError(f"homogenisation must be 'coupled' or 'standard'; got {self.homogenisation!r}")
        unknown = [n for n in self.names if n not in LAYER_PARAMETERS]
        if unknown:
            raise ParameterError(
                f"unknown layer parameter(s) {', '.join(unknown)}; known: {', '.join(LAYER_PARAMETERS)}"
            )
        self.names = tuple(self.names)
        self.times = np.arange(int(round(self.duration / self.dt)) + 1) * self.dt

    @property
    def base(self) -> np.ndarray:
        return np.array([getattr(self, n) for n in self.names], dtype=float)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(self.names)

    @property
    def output(self) -> Output:
        units = "J" if self.target == "total_deformation_energy" else "m"
        return Output(self.target, units)

    capabilities = frozenset[str]()  # none: the engine uses finite differences

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """One forward simulation for the varying layer parameters ``p`` (order ``names``);
        no sensitivities (the engine uses finite differences)."""
        return Evaluation(self._simulate(p))

    def _simulate(self, p: np.ndarray) -> np.ndarray:
        values = {n: getattr(self, n) for n in LAYER_PARAMETERS}
        values.update(zip(self.names, np.asarray(p, float).ravel()))
        for name, value in values.items():
            if not (np.isfinite(value) and value > 0):
                raise ParameterError(f"{name} must be > 0 {LAYER_UNITS[name]}; got {value}")
        mesh = replace(self.blade, face_thickness=values["face_thickness"]).discretise(self.nodes)
        layers = LayerMaterials(values["face_modulus"], values["core_modulus"], self.poisson,
                                self.density, self.density)  # fmt: skip
        homogenise = coupled_stiffness if self.homogenisation == "coupled" else standard_stiffness
        stiffness = homogenise(layers, mesh.width, mesh.core_thickness, mesh.face_thickness)
        model, q0 = build_clamped_beam(mesh, self.tip_force, stiffness=stiffness,
                                       reference_modulus=values["face_modulus"])  # fmt: skip
        p_beam = np.array([values["face_modulus"], self.poisson, self.density, self.damping])
        settings = SolverSettings(dt=self.dt, n_steps=self.times.size - 1, scheme="energy-momentum")
        trajectory = integrate(model, q0, None, p_beam, settings)
        self.runs += 1
        if self.target == "total_deformation_energy":
            return trajectory_energies(model, trajectory, p_beam).internal
        axis = {"toe_x": 0, "toe_z": 2}[self.target]
        return trajectory.q[:, -12 + axis]
