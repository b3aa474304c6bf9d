"""The thesis' leg, material and scenario parameters (Tables 4.1–4.4).

Units: SI (m, kg, s, Pa, rad).  Joint angles follow one sign convention: flexion is
positive, so a hip *extension* of π/6 is stored as ``hip_angle = −π/6``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.solver import SolverSettings


@dataclass(frozen=True)
class SegmentData:
    """A rigid leg segment (thesis Table 4.1, from Chandler et al. 1975, [Cha75]).

    Attributes:
        name: segment name.
        length: proximal-to-distal joint centre distance (m).
        mass: kg.
        inertia: principal moments of inertia ``(J1, J2, J3)`` about the centre of mass
            in kg·m² (the thesis prints the unit as "kg/m²"; it is kg m²); J3 is the
            moment about the segment's long axis, J1 and J2 about the transverse axes.
        com_from_proximal: distance of the centre of mass from the proximal joint
            centre along the long axis (m).
    """

    name: str
    length: float
    mass: float
    inertia: tuple[float, float, float]
    com_from_proximal: float


#: Thigh, thesis Table 4.1.
THIGH = SegmentData("thigh", 0.4582, 6.5233, (0.1137, 0.1158, 0.0225), 0.1779)
#: Shank, thesis Table 4.1.
SHANK = SegmentData("shank", 0.3753, 2.6857, (0.0391, 0.0393, 0.0029), 0.1943)


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material with Kelvin–Voigt viscous damping.

    Attributes:
        youngs_modulus: E (Pa).
        poisson: Poisson's ratio ν (−), in (−1, 0.5).
        density: ρ (kg/m³).
        damping: viscous damping parameter η = η_E = η_G of the thesis (Eq. 4.33),
            multiplying the strain rates (the thesis uses 1.0 and gives no unit).

    Raises:
        ParameterError: impossible values, naming the parameter.
    """

    youngs_modulus: float
    poisson: float
    density: float
    damping: float

    def __post_init__(self) -> None:
        checks = {
            "youngs_modulus": (lambda v: v > 0, "must be > 0 Pa"),
            "poisson": (lambda v: -1.0 < v < 0.5, "must lie in (-1, 0.5)"),
            "density": (lambda v: v > 0, "must be > 0 kg/m^3"),
            "damping": (lambda v: v >= 0, "must be >= 0"),
        }
        for name, (ok, rule) in checks.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ParameterError(f"material parameter {name} must be a number; got {value!r}")
            value = float(value)
            if not math.isfinite(value) or not ok(value):
                raise ParameterError(f"material parameter {name} {rule}; got {value}")
            object.__setattr__(self, name, value)

    @property
    def shear_modulus(self) -> float:
        """``G = E / (2 (1 + ν))`` (Pa)."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson))


#: Reverse-engineered prosthesis material, thesis Table 4.2 ([Soe19]).  The table prints
#: E = 59958e6 Pa and G = E/(2(1+ν)) = 23.693e6 Pa; the two are inconsistent
#: (59958e6 / 2.53 = 23.699e9 Pa).  E is kept as printed; G is always derived from E, ν.
REVERSE_ENGINEERED = Material(youngs_modulus=59958e6, poisson=0.265, density=1.71e3, damping=1.0)

#: Softened, heavier material of the swing scenario, thesis Table 4.3 (G = 23.69e4 Pa).
SWING_SOFT = Material(youngs_modulus=59.95e4, poisson=0.265, density=8.55e3, damping=1.0)

#: Material of the stance (squat under load) scenario, thesis Table 4.4 (G = 23.69e7 Pa).
STANCE_MATERIAL = Material(youngs_modulus=59.958e7, poisson=0.265, density=8.55e3, damping=1.0)

#: Alias of :data:`SWING_SOFT`, named like :data:`STANCE_MATERIAL`.
SWING_MATERIAL = SWING_SOFT


def material_with(material: Material, **overrides: float) -> Material:
    """A copy of ``material`` with some parameters replaced.

    Args:
        material: the base material.
        **overrides: any of ``youngs_modulus`` (Pa), ``poisson``, ``density`` (kg/m³),
            ``damping``.

    Raises:
        ParameterError: an unknown parameter name or an impossible value, naming it.
    """
    names = [f.name for f in dataclasses.fields(Material)]
    unknown = sorted(set(overrides) - set(names))
    if unknown:
        raise ParameterError(
            f"unknown material parameter {unknown[0]!r}; use one of {', '.join(names)}"
        )
    return dataclasses.replace(material, **overrides)


@dataclass(frozen=True)
class ScenarioPreset:
    """Initial pose, prosthesis material and time stepping of a thesis scenario.

    Attributes:
        name: scenario name.
        material: prosthesis material.
        hip_angle: initial hip angle (rad), flexion positive (extension negative).
        knee_angle: initial knee flexion angle (rad), flexion positive.
        dt: time step Δt (s).
        duration: simulated time T (s).
        shank_mass: shank mass (kg); raised in the stance scenario to represent body weight.
    """

    name: str
    material: Material
    hip_angle: float
    knee_angle: float
    dt: float
    duration: float
    shank_mass: float

    def __post_init__(self) -> None:
        for name in ("dt", "duration", "shank_mass"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ParameterError(f"scenario {self.name!r}: {name} must be > 0; got {value!r}")

    @property
    def solver(self) -> SolverSettings:
        """The table's time stepping: Δt and T, the other settings the solver's defaults
        (the variational scheme)."""
        return SolverSettings(dt=self.dt, duration=self.duration)


#: Pendulum swing, thesis Table 4.3: hip extension π/6, knee flexion π/3, Δt = 1 ms, T = 2 s;
#: the shank keeps its Table 4.1 mass.
SWING = ScenarioPreset(
    name="swing",
    material=SWING_SOFT,
    hip_angle=-math.pi / 6,
    knee_angle=math.pi / 3,
    dt=0.001,
    duration=2.0,
    shank_mass=SHANK.mass,
)

#: Squat under load, thesis Table 4.4: hip flexion π/2 (thigh horizontal), knee flexion π/2
#: (shank vertical), shank mass 107 kg, Δt = 1 ms, T = 2 s.
STANCE = ScenarioPreset(
    name="stance",
    material=STANCE_MATERIAL,
    hip_angle=math.pi / 2,
    knee_angle=math.pi / 2,
    dt=0.001,
    duration=2.0,
    shank_mass=107.0,
)


@dataclass(frozen=True)
class CommandDefaults:
    """What the commands (``simulate``, ``fuzzy-sim``) change from a thesis scenario so
    that it runs to its end with the shipped blade geometry (which the thesis does not
    give; ours is an assumed Vari-Flex-like blade, see :mod:`fuzzygait.mechanics.geometry`).

    Attributes:
        values: parameter values (SI units) replacing the table's, by leg parameter name.
        scheme: the time integrator.
        nodes: blade nodes (the thesis: 20).
        reason: why, as measured (README "Simulator defaults").
    """

    values: dict[str, float]
    scheme: str
    nodes: int
    reason: str

    def solver(self, preset: ScenarioPreset) -> SolverSettings:
        """The solver settings of the command: the scenario ``preset``'s with :attr:`scheme`."""
        return preset.solver.derive(scheme=self.scheme)


#: The command-line defaults of each scenario; the library (:class:`ScenarioPreset`) keeps
#: the tables' values.
COMMAND_DEFAULTS = {
    "swing": CommandDefaults(
        {"eta": 1e5}, "variational", 20,
        "Table 4.3's eta = 1 folds blade element 16 at t = 0.27 s on the shipped blade whatever the time step "
        "(dt/2, dt/4 and the energy-momentum scheme fold at the same time; 40 nodes at 0.42 s, 80 at 1.15 s): "
        "the soft, heavy blade cannot carry its own weight; it runs with eta >= 3e4 Pa s or E >= 2e7 Pa",
    ),
    "stance": CommandDefaults(
        {}, "energy-momentum", 40,
        "Table 4.4 with the variational scheme at dt = 1 ms turns unstable at t = 0.7 s (the stiff blade's "
        "unresolved modes; energy +95 J in 10 steps) and runs with 4 sub-steps per dt, 3-4 times the cost; the "
        "energy-momentum scheme runs the 2 s at dt; with 20 nodes element 11 folds at t = 0.40 s once E is 10 % "
        "lower, 40 nodes run it",
    ),
}  # fmt: skip

#: Measured on the shipped blade, swing of Table 4.3 at 20 nodes, dt = 1 ms, 2 s
#: (benchmarks/simulator_thesis_settings.py, issue 37.4): below both of these the blade folds.
SWING_RUNS_FROM = {"eta": 3e4, "E": 2e7}


def thesis_setting_note(scenario: str, values: Mapping[str, float]) -> str | None:
    """Why a swing with the user's damping and stiffness (``--set``) below
    :data:`SWING_RUNS_FROM` will fold on the shipped blade (None: it is not expected to)."""
    if scenario != "swing" or "eta" not in values:
        return None
    eta = values["eta"]
    stiffness = values.get("E", SWING.material.youngs_modulus)
    if eta >= SWING_RUNS_FROM["eta"] or stiffness >= SWING_RUNS_FROM["E"]:
        return None
    return (f"swing with eta = {eta:g} Pa s and E = {stiffness:g} Pa: on the shipped (assumed) blade the Table 4.3 "
            "material folds the toe region at 20 nodes at t = 0.27 s whatever the time step (dt/2, dt/4 and the "
            "energy-momentum scheme fold at the same time; 40 nodes at 0.42 s, 80 at 1.15 s) — its forward run sags "
            "under its own weight about 15 times its length (linear estimate), so the blade whips; the 2 s run "
            f"needs eta >= {SWING_RUNS_FROM['eta']:g} Pa s or E >= {SWING_RUNS_FROM['E']:g} Pa (20 nodes)")  # fmt: skip
