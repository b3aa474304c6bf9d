"""Swing and stance scenarios of the leg + prosthesis model (thesis §4.2.4, Tables 4.3/4.4).

:class:`LegSimulator` builds (or loads from the on-disk cache) the model of a scenario once
and runs it for any parameter vector; :meth:`LegSimulator.run` returns an
``xarray.Dataset`` with configurations, energies, joint angles and the target outputs of the
thesis — total deformation energy (Eq. 5.1), maximum element energy (Eq. 5.2) and the last
blade node's position — with their parameter sensitivities on request.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.mechanics.discrete import BufferedFunction, DiscreteModel
from fuzzygait.mechanics.geometry import BladeGeometry, default_blade
from fuzzygait.mechanics.homogenisation import LayerMaterials
from fuzzygait.mechanics.integrator import integrate
from fuzzygait.mechanics.leg import (
    LEG_PARAMETERS,
    PARAMETER_UNITS,
    FootKind,
    LegConfiguration,
    SectionKind,
    build_leg,
    default_parameters,
)
from fuzzygait.mechanics.presets import STANCE, SWING, ScenarioPreset
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.trajectory import trajectory_energies

SCENARIOS: dict[str, ScenarioPreset] = {"swing": SWING, "stance": STANCE}


def stance_anchors(blade: BladeGeometry, nodes: int) -> tuple[int, int]:
    """The two blade nodes held on the ground in the stance scenario: the lowest node of the
    heel bend (first 60 % of the blade) and the toe (last node)."""
    mesh = blade.discretise(nodes)
    heel_region = max(2, int(0.6 * nodes))
    heel = int(np.argmin(mesh.positions[:heel_region, 2]))
    return (heel, nodes - 1)


class LegSimulator:
    """A scenario's model, ready to run for many parameter vectors.

    Args:
        scenario: "swing" (Table 4.3) or "stance" (Table 4.4).
        nodes: blade nodes (default 20, as in the thesis).
        foot: "beam" (default), "rigid" (blade replaced by a rigid body) or "none".
        blade: blade geometry (default: the packaged Vari-Flex-like file).
        compile: compile the generated code (cached on disk) when a C compiler is available.
        section, layers: the blade's cross-section law (see :class:`LegConfiguration`).
    """

    def __init__(
        self,
        scenario: str = "swing",
        nodes: int = 20,
        foot: FootKind = "beam",
        blade: BladeGeometry | None = None,
        compile: bool = True,
        section: SectionKind = "homogeneous",
        layers: LayerMaterials | None = None,
    ) -> None:
        if scenario not in SCENARIOS:
            raise ParameterError(f"unknown scenario {scenario!r}; choose one of {', '.join(SCENARIOS)}")
        self.scenario = scenario
        self.preset = SCENARIOS[scenario]
        blade = blade or default_blade()
        anchors = stance_anchors(blade, nodes) if scenario == "stance" and foot == "beam" else ()
        self.configuration = LegConfiguration(
            hip_angle=self.preset.hip_angle, knee_angle=self.preset.knee_angle, nodes=nodes, foot=foot,
            anchored_nodes=anchors, blade=blade, section=section, layers=layers,
        )  # fmt: skip
        self.leg = build_leg(self.configuration, rigid_foot_density=self.preset.material.density)
        self.model = DiscreteModel.from_builder(self.leg.builder, compile=compile)
        self.default_parameters = default_parameters(self.preset.material, shank_mass=self.preset.shank_mass)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return LEG_PARAMETERS

    def parameters(self, **overrides: float) -> np.ndarray:
        """The scenario's default parameter vector with named overrides (SI units)."""
        p = self.default_parameters.copy()
        for name, value in overrides.items():
            if name not in LEG_PARAMETERS:
                raise ParameterError(f"unknown parameter {name!r}; known: {', '.join(LEG_PARAMETERS)}")
            p[LEG_PARAMETERS.index(name)] = float(value)
        validate_parameters(p)
        return p

    def run(
        self,
        p: np.ndarray | None = None,
        settings: SolverSettings | None = None,
        *,
        sensitivities: bool = False,
        progress: Callable[[int], None] | None = None,
    ) -> xr.Dataset:
        """Simulate and return the results (see the module docstring for the variables).

        ``settings``: time step, simulated time, scheme ("variational", Eq. 4.26, or
        "energy-momentum": exact energy balance, more robust for very flexible and stiff
        blades; both with sensitivities) and Newton settings — see
        :func:`fuzzygait.mechanics.integrator.integrate`; None: the scenario's
        (:attr:`.presets.ScenarioPreset.solver`).  A run whose energy balance is off by more
        than :data:`ENERGY_TOLERANCE` is repeated with twice the sub-steps while that helps,
        up to ``2^settings.max_halvings``.
        """
        p = self.default_parameters.copy() if p is None else np.asarray(p, dtype=float).ravel()
        validate_parameters(p)
        settings = self.preset.solver if settings is None else settings
        start = time.perf_counter()
        substeps, previous = settings.substeps, np.inf
        while True:
            trajectory = integrate(self.model, self.leg.q0, None, p, settings.derive(substeps=substeps),
                                   sensitivities=sensitivities, progress=progress)  # fmt: skip
            energies = trajectory_energies(self.model, trajectory, p)
            error = energy_balance_error(energies)
            # refine while the balance is off and refining helps: an error that halving the step
            # does not halve is the O(dt²) error of evaluating the energies on the dt grid itself
            if (error <= ENERGY_TOLERANCE or error > 0.5 * previous
                    or trajectory.substeps >= 2**settings.max_halvings):  # fmt: skip
                break
            substeps, previous = 2 * trajectory.substeps, error
        wall = time.perf_counter() - start
        return self._dataset(trajectory, energies, error, p, settings.dt, wall)

    # -- results --------------------------------------------------------------------------
    def _dataset(self, trajectory, energies, energy_error: float, p: np.ndarray, dt: float,
                 wall: float) -> xr.Dataset:  # fmt: skip
        names = list(self.leg.builder.body_names)
        q = trajectory.q.reshape(len(trajectory.times), len(names), 12)
        time_coord = ("time", trajectory.times, {"units": "s"})
        thigh_dir = -q[:, 0, 9:12]
        shank_dir = -q[:, 1, 9:12]
        hip = np.arctan2(thigh_dir[:, 0], -thigh_dir[:, 2])
        shank_angle = np.arctan2(shank_dir[:, 0], -shank_dir[:, 2])
        data = {
            "position": (
                ("time", "body", "xyz"), q[:, :, :3], {"units": "m", "long_name": "centre of mass / node position"}
            ),
            "directors": (
                ("time", "body", "director", "xyz"), q[:, :, 3:].reshape(len(q), len(names), 3, 3), {"units": "1"}
            ),
            "hip_flexion": ("time", hip, {"units": "rad"}),
            "knee_flexion": ("time", np.unwrap(hip - shank_angle), {"units": "rad"}),
            "kinetic_energy": ("time", energies.kinetic, {"units": "J"}),
            "gravitational_energy": ("time", energies.gravity, {"units": "J"}),
            "internal_energy": ("time", energies.internal, {"units": "J"}),
            "dissipated_energy": ("time", energies.dissipated, {"units": "J"}),
            "total_energy": ("time", energies.total, {"units": "J", "long_name": "kinetic + gravitational + internal"}),
            "newton_iterations": ("step", trajectory.iterations, {"units": "1", "long_name": "Newton iterations"}),
        }
        coords: dict[str, object] = {"time": time_coord, "body": names, "xyz": ["x", "y", "z"],
                                     "director": ["d1", "d2", "d3"], "parameter": list(LEG_PARAMETERS),
                  "parameter_unit": ("parameter", [PARAMETER_UNITS[k] for k in LEG_PARAMETERS]),
                  "step": ("step", np.arange(1, len(trajectory.iterations) + 1),
                           {"long_name": "time step (step 1 ends at dt)"})}  # fmt: skip
        if self.model.groups:
            element = energies.element
            data["element_energy"] = (("time", "element"), element, {"units": "J"})
            coords["element"] = np.arange(element.shape[1])
            data["total_deformation_energy"] = ("time", element.sum(axis=1), {"units": "J", "long_name": "Eq. 5.1"})
            data["max_element_energy"] = ("time", element.max(axis=1), {"units": "J", "long_name": "Eq. 5.2"})
            data["last_node_position"] = (("time", "xyz"), q[:, -1, :3], {"units": "m"})
        data["parameter_value"] = ("parameter", p, {"long_name": "leg parameter value, in its parameter_unit"})
        if trajectory.sensitivities is not None:
            s = trajectory.sensitivities
            data["configuration_sensitivity"] = (("time", "dof", "parameter"), s,
                                                 {"long_name": "dq/dp", "units": "per parameter unit"})  # fmt: skip
            coords["dof"] = np.arange(s.shape[1])
            if self.model.groups:
                d_total, d_max = self._target_sensitivities(trajectory, p, energies.element)
                per_unit = "per parameter unit"
                data["total_deformation_energy_sensitivity"] = (
                    ("time", "parameter"), d_total, {"units": f"J {per_unit}"}
                )
                data["max_element_energy_sensitivity"] = (("time", "parameter"), d_max, {"units": f"J {per_unit}"})
                data["last_node_position_sensitivity"] = (
                    ("time", "xyz", "parameter"), s[:, -12:-9, :], {"units": f"m {per_unit}"}
                )
        ds = xr.Dataset(data, coords=coords)
        ds.attrs.update(
            scenario=self.scenario,
            nodes=self.configuration.nodes if self.configuration.foot == "beam" else 0,
            foot=self.configuration.foot,
            scheme=trajectory.scheme,
            section=self.configuration.section,
            dt=dt,
            substeps=trajectory.substeps,
            energy_error=energy_error,
            energy_error_definition="max over t of |E(t) + D(t) - E(0)| / max over t of (kinetic + internal), "
                                    "E the total and D the dissipated energy",
            duration=float(trajectory.times[-1]),
            wall_time_s=wall,
            compiled=int(self.model.compiled),
            blade=self.configuration.blade.name,
            anchored_nodes=list(self.configuration.anchored_nodes),
            newton_loop="compiled" if "pivot_orders" in trajectory.timings else "python",
            factorisations=trajectory.timings.get("factorisations", 0.0),
            pivot_orders=trajectory.timings.get("pivot_orders", 0.0),
            **{f"time_{k}_s": v for k, v in trajectory.timings.items() if k not in ("factorisations", "pivot_orders")},
        )
        return ds

    def _target_sensitivities(self, trajectory, p, element):
        """d(Σ_e W_e)/dp and d(max_e W_e)/dp from ∇W_e · dq/dp + ∂W_e/∂p."""
        model = self.model

        n_t = len(trajectory.times)
        n_p = len(p)
        d_total = np.zeros((n_t, n_p))
        d_max = np.zeros((n_t, n_p))
        start = 0
        for group in model.groups:
            kernel = BufferedFunction(model.functions[f"{group.name}_energy"])
            dofs = group.dofs
            pe = np.repeat(p[list(group.parameter_indices)][:, None], len(dofs), axis=1)
            constants = group.constants.T
            for j in range(n_t):
                qj = trajectory.q[j]
                _, _, grad, dpe = kernel(qj[dofs].T, np.zeros((24, len(dofs))), constants, pe)
                grad = grad.reshape(len(dofs), 24)
                dpe = dpe.reshape(len(dofs), len(group.parameter_indices))
                per_element = np.einsum("ek,ekp->ep", grad, trajectory.sensitivities[j][dofs])
                for k, index in enumerate(group.parameter_indices):
                    per_element[:, index] += dpe[:, k]
                d_total[j] += per_element.sum(axis=0)
                e_max = int(np.argmax(element[j]))
                if start <= e_max < start + len(dofs):
                    d_max[j] = per_element[e_max - start]
            start += len(dofs)
        return d_total, d_max


#: Largest accepted energy-balance error of a run, relative (see :func:`energy_balance_error`):
#: the variational integrator keeps it at 1e-5–3e-3 where it is stable (its O(dt²) error;
#: benchmarks/simulator_thesis_settings.py; stance with a rigid foot 3.1e-3 at 1 ms); where the
#: step is too large for a stiff blade's unresolved modes the energy jumps by a few per cent
#: (stance, Table 4.4, dt = 0.5 ms: +4.8 J of 210 J at t ≈ 1.7 s, Newton still converging), and
#: :meth:`LegSimulator.run` repeats the run with half the step while that halves the error.
ENERGY_TOLERANCE = 5e-3


def energy_balance_error(energies) -> float:
    """``max_t |E(t) + D(t) − E(0)|`` (kinetic + gravitational + internal + load energy plus the
    dissipated energy; the scenarios do no external work) over ``max_t (kinetic + internal)``,
    the largest energy in motion (0 when nothing moves)."""
    balance = energies.total + energies.dissipated
    scale = float(np.max(energies.kinetic + energies.internal))
    if not np.all(np.isfinite(balance)):
        return float("inf")
    return float(np.max(np.abs(balance - balance[0]))) / scale if scale > 0 else 0.0


def validate_parameters(p: np.ndarray) -> None:
    """One clear error for an impossible leg parameter vector (order :data:`LEG_PARAMETERS`).

    Moments of inertia need only be positive: the director formulation's rotational inertia
    is diag(J1, J2, J3) whatever the Euler-tensor split, so sets that break the triangle
    inequality (no real mass distribution has them; independent fuzzy inertias of §5.3 do)
    still give well-posed dynamics.
    """
    if p.size != len(LEG_PARAMETERS):
        raise ParameterError(f"expected {len(LEG_PARAMETERS)} parameters ({', '.join(LEG_PARAMETERS)}), got {p.size}")
    for name, value in zip(LEG_PARAMETERS, p):
        if not np.isfinite(value):
            raise ParameterError(f"parameter {name} must be finite; got {value}")
        if name == "nu":
            if not -1.0 < value < 0.5:
                raise ParameterError(f"Poisson ratio nu must lie in (-1, 0.5); got {value}")
        elif name == "eta":
            if value < 0:
                raise ParameterError(f"damping eta must be ≥ 0 Pa s; got {value}")
        elif value <= 0:
            raise ParameterError(f"parameter {name} must be > 0 {PARAMETER_UNITS[name]}; got {value}")
