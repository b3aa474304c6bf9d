"""Results of a time integration: the trajectory and its energies."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzygait.mechanics.discrete import BufferedFunction, DiscreteModel


@dataclass
class Trajectory:
    """Result of :func:`.integrator.integrate` (SI units, inertial frame).

    Attributes:
        times: (N+1,) s.
        q: (N+1, ndof) configurations at the time nodes.
        multipliers: (N, nconstraints) λ_j of each step.
        iterations: (N,) Newton iterations per step.
        sensitivities: (N+1, ndof, n_p) dq/dp, or None.
        velocities: (N+1, ndof) nodal velocities of the energy-momentum scheme (None for the
            variational integrator, whose energies use central differences).
        scheme: "variational" or "energy-momentum".
        substeps: uniform integration steps per interval of ``times`` (> 1 when
            :func:`.integrator.integrate` refined the step after a failed one).
        timings: seconds spent in residual/Jacobian evaluation, LU factorisation and solves.
    """

    times: np.ndarray
    q: np.ndarray
    multipliers: np.ndarray
    iterations: np.ndarray
    sensitivities: np.ndarray | None
    timings: dict[str, float]
    velocities: np.ndarray | None = None
    scheme: str = "variational"
    substeps: int = 1



@dataclass
class Energies:
    """Energies at the time nodes (J).  Kinetic energy uses the central difference velocity
    ``(q_{j+1} − q_{j−1}) / 2h`` (``v_0`` at the start, a second-order one-sided difference
    at the end); the dissipated energy sums ``h · 2 V_visc`` over the intervals up to each node.

    Attributes:
        kinetic, gravity, internal, load, dissipated: (N+1,).
        element: (N+1, n_el) stored energy per element of each element group, concatenated.
        total: kinetic + gravity + internal + load (without the dissipated energy).
    """

    kinetic: np.ndarray
    gravity: np.ndarray
    internal: np.ndarray
    load: np.ndarray
    dissipated: np.ndarray
    element: np.ndarray

    @property
    def total(self) -> np.ndarray:
        return self.kinetic + self.gravity + self.internal + self.load


def trajectory_energies(
    model: DiscreteModel, trajectory: Trajectory, p: np.ndarray, v0: np.ndarray | None = None
) -> Energies:
    """Kinetic, gravitational, internal, load and dissipated energy along a trajectory."""
    q = trajectory.q
    n_nodes = len(q)
    h = float(trajectory.times[1] - trajectory.times[0]) if n_nodes > 1 else 1.0
    p = np.asarray(p, float)
    c = model.constants
    v = np.empty_like(q)
    v[1:-1] = (q[2:] - q[:-2]) / (2 * h) if n_nodes > 2 else v[1:-1]
    v[0] = 0.0 if v0 is None else v0
    if n_nodes > 2:  # second-order one-sided difference at the last node
        v[-1] = (3 * q[-1] - 4 * q[-2] + q[-3]) / (2 * h)
    elif n_nodes == 2:
        v[-1] = (q[-1] - q[-2]) / h
    if trajectory.velocities is not None:  # energy-momentum: the scheme's own velocities
        v = trajectory.velocities
    mass = BufferedFunction(model.functions["mass"])
    m_matrix = mass.sparse(0, mass(p, c)[0])
    kinetic = 0.5 * np.einsum("ij,ij->i", v, (m_matrix @ v.T).T)
    potential = BufferedFunction(model.functions["potential"])
    gravity = np.empty(n_nodes)
    load = np.empty(n_nodes)
    for j in range(n_nodes):
        vg, vl = potential(q[j], p, c)
        gravity[j], load[j] = vg[0], vl[0]
    n_el = sum(len(g.node_offsets) for g in model.groups)
    element = np.zeros((n_nodes, n_el))
    rate = np.zeros(max(n_nodes - 1, 0))
    start = 0
    for group in model.groups:
        kernel = BufferedFunction(model.functions[f"{group.name}_energy"])
        size = len(group.node_offsets)
        for j in range(n_nodes):
            energy, _, _, _ = kernel(*model.group_inputs(group, q[j], q[j], h, p))
            element[j, start : start + size] = energy
        for j in range(n_nodes - 1):
            _, dissipation, _, _ = kernel(*model.group_inputs(group, q[j], q[j + 1], h, p))
            rate[j] += dissipation.sum()
        start += size
    dissipated = np.concatenate([[0.0], np.cumsum(rate * h)])
    return Energies(kinetic, gravity, element.sum(axis=1), load, dissipated, element)
