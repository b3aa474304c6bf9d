"""The leg simulator as a model of the uncertainty engine (``f(p) -> target(t)``).

:class:`LegTargetModel` exposes one target output of a scenario — total deformation energy
(Eq. 5.1), maximum element energy (Eq. 5.2) or a coordinate of the last blade node — as a
function of a chosen subset of the leg parameters, with sensitivities from the
integrator's forward sensitivity analysis, so the Graph Follower algorithm can linearise
it (thesis OP-III).  Every ``evaluate`` is one forward simulation.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, fields

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.leg import LEG_PARAMETERS
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.uncertainty.protocol import SENSITIVITIES, Evaluation, Output

TARGETS = (
    "total_deformation_energy",
    "max_element_energy",
    "last_node_x",
    "last_node_y",
    "last_node_z",
)
#: The values a target can take at all (:attr:`~fuzzygait.uncertainty.protocol.Output.bounds`):
#: deformation energies are never negative; the node coordinates are unbounded.
TARGET_BOUNDS: dict[str, tuple[float, float]] = {
    "total_deformation_energy": (0.0, math.inf),
    "max_element_energy": (0.0, math.inf),
}


class LegTargetModel:
    """One target output of a scenario as a function of some leg parameters.

    Args:
        simulator: the scenario (built once; its compiled library is reused).
        target: one of :data:`TARGETS` (J for the energies, m for the node coordinates).
        names: the varying parameters (names of :data:`~fuzzygait.mechanics.leg.LEG_PARAMETERS`),
            in the order of the engine's parameter vector.
        base: the full parameter vector the others are fixed at (default: the scenario's).
        settings: time step, simulated time, scheme ("variational" or "energy-momentum", both
            give sensitivities) and Newton settings (default: the scenario's,
            :attr:`~fuzzygait.mechanics.presets.ScenarioPreset.solver`).

    Attributes ``runs`` counts the simulations run.
    """

    def __init__(self, simulator: LegSimulator, target: str = "total_deformation_energy",
                 names: Sequence[str] = ("E",), base: np.ndarray | None = None,
                 settings: SolverSettings | None = None) -> None:  # fmt: skip
        if target not in TARGETS:
            raise ParameterError(f"unknown target {target!r}; choose one of {', '.join(TARGETS)}")
        unknown = [n for n in names if n not in LEG_PARAMETERS]
        if unknown:
            raise ParameterError(f"unknown parameter(s) {', '.join(unknown)}; known: {', '.join(LEG_PARAMETERS)}")
        self.simulator, self.target = simulator, target
        self.names: tuple[str, ...] = tuple(names)
        self.base: np.ndarray = simulator.default_parameters.copy() if base is None else np.asarray(base, float)
        self.settings: SolverSettings = simulator.preset.solver if settings is None else settings
        self.times = np.arange(self.settings.steps + 1) * self.settings.dt
        self._index = [LEG_PARAMETERS.index(n) for n in self.names]
        self.runs = 0

    @property
    def dt(self) -> float:
        """Time step (s)."""
        return self.settings.dt

    @property
    def duration(self) -> float:
        """Simulated time (s): the settings' ``duration``, else ``n_steps · dt``."""
        duration = self.settings.duration
        return self.settings.steps * self.settings.dt if duration is None else duration

    @property
    def scheme(self) -> str:
        """Time stepping scheme."""
        return self.settings.scheme

    def __repr__(self) -> str:
        return (f"LegTargetModel({self.simulator.scenario!r}, {self.target!r}, names={self.names}, "
                f"dt={self.dt:g}, duration={self.duration:g}, scheme={self.scheme!r})")  # fmt: skip

    def full_parameters(self, p: np.ndarray) -> np.ndarray:
        """The full leg parameter vector with the varying entries set to ``p``."""
        full = self.base.copy()
        full[self._index] = np.asarray(p, float).ravel()
        return full

    def _run(self, p: np.ndarray, sensitivities: bool):
        self.runs += 1
        return self.simulator.run(self.full_parameters(p), self.settings, sensitivities=sensitivities)

    def _select(self, ds, sensitivities: bool):
        if self.target.startswith("last_node_"):
            axis = self.target[-1]
            value = ds["last_node_position"].sel(xyz=axis).values
            sens = ds["last_node_position_sensitivity"].sel(xyz=axis).values if sensitivities else None
        else:
            value = ds[self.target].values
            sens = ds[f"{self.target}_sensitivity"].values if sensitivities else None
        return value, (sens[:, self._index] if sens is not None else None)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(self.names)

    @property
    def output(self) -> Output:
        """The target's name, units and bounds (energies ≥ 0, :data:`TARGET_BOUNDS`)."""
        units = "m" if self.target.startswith("last_node_") else "J"
        return Output(self.target, units, bounds=TARGET_BOUNDS.get(self.target, (-math.inf, math.inf)))

    @property
    def capabilities(self) -> frozenset[str]:
        """Sensitivities from the integrator's forward sensitivity analysis (both schemes)."""
        return frozenset({SENSITIVITIES})

    def evaluate(self, p: np.ndarray, *, sensitivities: bool = False) -> Evaluation:
        """Target output at :attr:`times` for the varying parameters ``p`` and, with
        ``sensitivities``, its derivatives ``(n_time, n_p)``: one simulation either way."""
        value, sens = self._select(self._run(p, sensitivities), sensitivities)
        return Evaluation(value, sens)


@dataclass(frozen=True)
class LegModelRecipe:
    """Recipe of :class:`LegTargetModel` for the engine's
    :class:`~fuzzygait.uncertainty.execution.Evaluator`: one target output of
    a leg scenario as a function of the named parameters.

    Args:
        scenario: "swing" or "stance".
        target: see :data:`fuzzygait.mechanics.targets.TARGETS`.
        names: the varying parameters, in the order of the columns of ``P``.
        base: the full leg parameter vector the others are fixed at (None: the scenario's).
        nodes: blade nodes.
        settings: the solver settings (None: the scenario's,
            :attr:`~fuzzygait.mechanics.presets.ScenarioPreset.solver`).
        foot: "beam", "rigid" or "none".

    The :attr:`key` is ``("LegModelRecipe", scenario, target, names, base, nodes, dt,
    duration, scheme, foot)`` as before the settings were one object (``None, None,
    "variational"`` without settings), followed by the ``(field, value)`` of every other
    solver setting that differs from its default.
    """

    scenario: str = "swing"
    target: str = "total_deformation_energy"
    names: tuple[str, ...] = ("E",)
    base: tuple[float, ...] | None = None
    nodes: int = 20
    settings: SolverSettings | None = None
    foot: str = "beam"

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(str(n) for n in self.names))
        if self.base is not None:
            object.__setattr__(self, "base", tuple(float(v) for v in np.asarray(self.base, float).ravel()))
        object.__setattr__(self, "nodes", int(self.nodes))
        if self.settings is not None and not isinstance(self.settings, SolverSettings):
            raise ParameterError(f"settings must be a SolverSettings or None; got {self.settings!r}")

    @property
    def key(self) -> Hashable:
        settings = self.settings
        if settings is None:
            return ("LegModelRecipe", self.scenario, self.target, self.names, self.base, self.nodes, None, None,
                    "variational", self.foot)  # fmt: skip
        default = SolverSettings()
        others = tuple((f.name, getattr(settings, f.name)) for f in fields(SolverSettings)
                       if f.name not in ("dt", "duration", "scheme")
                       and getattr(settings, f.name) != getattr(default, f.name))  # fmt: skip
        return ("LegModelRecipe", self.scenario, self.target, self.names, self.base, self.nodes, settings.dt,
                settings.duration, settings.scheme, self.foot, *others)  # fmt: skip

    def build(self) -> LegTargetModel:
        simulator = LegSimulator(self.scenario, nodes=self.nodes, foot=self.foot)  # type: ignore[arg-type]
        base = None if self.base is None else np.asarray(self.base, dtype=float)
        return LegTargetModel(simulator, self.target, self.names, base, self.settings)
