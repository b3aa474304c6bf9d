"""Constrained forced variational integrator (thesis §4.1.2, Eqs. 4.16–4.29).

With the midpoint discrete Lagrangian ``L_d = h L((q_j + q_{j+1})/2, (q_{j+1} − q_j)/h)``,
the trapezoidal constraint term and the Lagrange–d'Alembert forces of Eq. 4.25, the
discrete Euler–Lagrange equations (4.26), divided by −h, read for the unknowns
``x = (q_{j+1}, λ_j)``::

    M (q_{j+1} − 2 q_j + q_{j−1}) / h² + ½ [∇V(q_{j+½}) + ∇V(q_{j−½})] + G(q_j)ᵀ λ_j
        − ½ [f(q_{j+½}, v_{j+½}) + f(q_{j−½}, v_{j−½})] = 0,      g(q_{j+1}) = 0,

with ``q_{j±½}`` the interval midpoints, ``v_{j±½}`` the difference quotients and
``f = −∂V_visc/∂v`` the viscous force.  The first step follows from the discrete Legendre
transform (Eq. 4.29) with the initial momentum ``p_0 = M v_0``::

    2 M (q_1 − q_0 − h v_0) / h² + ∇V(q_½) + G(q_0)ᵀ λ_0 − f(q_½, v_½) = 0,   g(q_1) = 0.

Each step is solved by Newton–Raphson with a sparse LU of the Jacobian.  Parameter
sensitivities ``S_j = dq_j/dp`` follow by differentiating the converged step equations:
``J_x [S_{j+1}; dλ_j/dp] = −(∂R/∂q_j S_j + ∂R/∂q_{j−1} S_{j−1} + ∂R/∂p)`` — the same
Jacobian, so one extra back-substitution per step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from fuzzygait.errors import ParameterError, SimulationError
from fuzzygait.mechanics.assembly import ElementGroup, SystemBuilder
from fuzzygait.mechanics.codegen import compile_functions, load_cached

GLOBAL_FUNCTIONS = ("mass", "mass_sens", "linear", "constraints", "constraint_hessian", "potential")


def _global_functions(builder: SystemBuilder) -> list[ca.Function]:
    """The small global functions: mass matrix, linear potential, constraints."""
    q, p, c = builder.q, builder.p, builder.c
    acc = ca.SX.sym("a", builder.ndof)
    lam = ca.SX.sym("lam", builder.g.numel())
    g = builder.g
    jac_g = ca.jacobian(g, q)
    grad_linear = ca.gradient(builder.linear_potential, q)
    return [
        ca.Function("mass", [p, c], [builder.mass]),
        ca.Function("mass_sens", [acc, p, c], [ca.jacobian(ca.mtimes(builder.mass, acc), p)]),
        ca.Function("linear", [q, p, c], [ca.densify(grad_linear), ca.jacobian(grad_linear, p)]),
        ca.Function("constraints", [q, c], [g, jac_g]),
        ca.Function("constraint_hessian", [q, lam, c], [ca.jacobian(ca.mtimes(jac_g.T, lam), q)]),
        ca.Function("potential", [q, p, c], [builder.gravity_energy, builder.load_potential]),
    ]


def _group_functions(group: ElementGroup) -> list[ca.Function]:
    n_el = len(group.node_offsets)
    # a map is generated as a loop over one element's code, not n_el inlined copies
    return [
        group.kernel.map(f"{group.name}_kernel", "serial", n_el, [], []),
        group.energy_kernel.map(f"{group.name}_energy", "serial", n_el, [], []),
    ]


class _Buffered:
    """Zero-copy evaluation of a CasADi function into numpy buffers (nonzeros of each output)."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.buffer, self._evaluate = function.buffer()
        self.results = []
        for i in range(function.n_out()):
            out = np.zeros(function.sparsity_out(i).nnz())
            self.buffer.set_res(i, memoryview(out))
            self.results.append(out)
        self._args: list[np.ndarray] = [np.zeros(0)] * function.n_in()

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        for i, value in enumerate(args):
            array = np.ascontiguousarray(value, dtype=float).ravel(order="F")
            self._args[i] = array  # keep alive while the buffer points at it
            self.buffer.set_arg(i, memoryview(array))
        self._evaluate()
        return self.results

    def coordinates(self, index: int) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of the nonzeros of output ``index``, in buffer order."""
        sparsity = self.function.sparsity_out(index)
        rows = np.asarray(sparsity.row(), dtype=np.int64)
        colind = np.asarray(sparsity.colind(), dtype=np.int64)
        cols = np.repeat(np.arange(sparsity.size2()), np.diff(colind))
        return rows, cols

    def sparse(self, index: int, values: np.ndarray) -> sp.csc_matrix:
        sparsity = self.function.sparsity_out(index)
        return sp.csc_matrix(
            (values.copy(), np.asarray(sparsity.row()), np.asarray(sparsity.colind())),
            shape=(sparsity.size1(), sparsity.size2()),
        )


class _Pattern:
    """The fixed sparsity of a sum of sparse parts; values are summed with one bincount."""

    def __init__(self, shape: tuple[int, int], parts: Sequence[tuple[np.ndarray, np.ndarray]]) -> None:
        rows = np.concatenate([np.ravel(r) for r, _ in parts]).astype(np.int64)
        cols = np.concatenate([np.ravel(c) for _, c in parts]).astype(np.int64)
        unique, self.inverse = np.unique(cols * shape[0] + rows, return_inverse=True)
        self.indices = (unique % shape[0]).astype(np.int32)
        self.indptr = np.searchsorted(unique // shape[0], np.arange(shape[1] + 1)).astype(np.int32)
        self.shape = shape
        self.nnz = unique.size

    def matrix(self, values: Sequence[np.ndarray]) -> sp.csc_matrix:
        data = np.bincount(self.inverse, weights=np.concatenate([np.ravel(v) for v in values]), minlength=self.nnz)
        return sp.csc_matrix((data, self.indices, self.indptr), shape=self.shape)


@dataclass
class DiscreteModel:
    """A built system ready for time stepping: functions, sizes and the fixed inputs.

    Attributes:
        functions: CasADi functions (compiled library or virtual machine), by name.
        ndof, nconstraints: sizes of q and λ.
        parameter_names: names of the entries of ``p``.
        constants: the numeric constant vector ``c``.
        groups: element groups (beam elements) with their dofs and constants.
        constraint_labels: one label per constraint row.
        compiled: whether the functions come from a compiled library.
        structure_key: what identifies the generated code.
    """

    functions: dict[str, ca.Function]
    ndof: int
    nconstraints: int
    parameter_names: tuple[str, ...]
    constants: np.ndarray
    groups: tuple[ElementGroup, ...]
    constraint_labels: tuple[str, ...]
    compiled: bool
    structure_key: str

    @classmethod
    def from_builder(cls, builder: SystemBuilder, compile: bool = True) -> "DiscreteModel":
        """Load the cached compiled library for this structure, or build (and compile) it."""
        key = builder.structure_key
        names = list(GLOBAL_FUNCTIONS) + [f"{g.name}_{kind}" for g in builder.element_groups for kind in ("kernel", "energy")]
        functions = load_cached(key, names) if compile else None
        compiled = functions is not None
        if functions is None:
            symbolic = _global_functions(builder) + [f for g in builder.element_groups for f in _group_functions(g)]
            functions = compile_functions(key, symbolic) if compile else {f.name(): f for f in symbolic}
            compiled = functions["mass"].is_a("External")
        return cls(
            functions=functions,
            ndof=builder.ndof,
            nconstraints=builder.g.numel(),
            parameter_names=tuple(builder.parameter_names),
            constants=builder.constant_values,
            groups=tuple(builder.element_groups),
            constraint_labels=tuple(builder.constraint_labels),
            compiled=compiled,
            structure_key=key,
        )

    def group_inputs(self, group: ElementGroup, q_a: np.ndarray, q_b: np.ndarray, h: float, p: np.ndarray):
        """Kernel inputs at the midpoint of the interval ``[q_a, q_b]`` (all elements)."""
        dofs = group.dofs
        mid = 0.5 * (q_a + q_b)[dofs].T
        vel = ((q_b - q_a) / h)[dofs].T
        pe = np.repeat(p[list(group.parameter_indices)][:, None], len(dofs), axis=1)
        return mid, vel, group.constants.T, pe


class _StepAssembler:
    """Residuals, Jacobians and sensitivity terms of the step equations, assembled from the
    element kernels and the global functions (see the module docstring)."""

    def __init__(self, model: DiscreteModel, p: np.ndarray, h: float, sensitivities: bool) -> None:
        self.model, self.p, self.h = model, p, h
        n, m = model.ndof, model.nconstraints
        c = model.constants
        f = model.functions
        self.mass_fn = _Buffered(f["mass"])
        (mass_values,) = self.mass_fn(p, c)
        self.mass_values = mass_values.copy()
        self.mass = self.mass_fn.sparse(0, self.mass_values)
        self.linear = _Buffered(f["linear"])
        grad_linear, dgrad_dp = self.linear(np.zeros(n), p, c)
        self.grad_linear = grad_linear.copy()
        self.constraints = _Buffered(f["constraints"])
        self.kernels = [_Buffered(f[f"{g.name}_kernel"]) for g in model.groups]
        self.energy_kernels = [_Buffered(f[f"{g.name}_energy"]) for g in model.groups]
        m_rows, m_cols = self.mass_fn.coordinates(0)
        g_rows, g_cols = self.constraints.coordinates(1)
        self.element_coords = []
        for group in model.groups:
            dofs = group.dofs  # (n_el, 24): buffer layout [e, col, row]
            rows = np.broadcast_to(dofs[:, None, :], (len(dofs), 24, 24))
            cols = np.broadcast_to(dofs[:, :, None], (len(dofs), 24, 24))
            self.element_coords.append((rows, cols))
        self.jacobian_pattern = _Pattern(
            (n + m, n + m),
            [(m_rows, m_cols)] + self.element_coords + [(g_cols, n + g_rows), (n + g_rows, g_cols)],
        )
        self.sensitivities = sensitivities
        if sensitivities:
            self.dgrad_dp = self.linear.sparse(1, dgrad_dp)
            self.mass_sens = _Buffered(f["mass_sens"])
            self.hessian = _Buffered(f["constraint_hessian"])
            h_rows, h_cols = self.hessian.coordinates(0)
            self.state_pattern = _Pattern((n, n), [(m_rows, m_cols)] + self.element_coords * 2 + [(h_rows, h_cols)])
            self.prev_pattern = _Pattern((n, n), [(m_rows, m_cols)] + self.element_coords)

    def _element_terms(self, q_a, q_b, weight):
        """Element forces and the blocks d/dq_b, d/dq_a for the interval [q_a, q_b]."""
        out = []
        for group, kernel in zip(self.model.groups, self.kernels):
            force, dq, dv, dp = kernel(*self.model.group_inputs(group, q_a, q_b, self.h, self.p))
            dq = dq.reshape(len(group.dofs), 24, 24)
            dv = dv.reshape(len(group.dofs), 24, 24)
            out.append((group, force.reshape(len(group.dofs), 24), weight * (0.5 * dq + dv / self.h),
                        weight * (0.5 * dq - dv / self.h), weight * dp.reshape(len(group.dofs), 3, 24)))
        return out

    def residual_jacobian(self, x, q_cur, q_prev, first: bool, v0=None):
        """Residual and Jacobian (CSC) of a step at the unknowns ``x = (q_next, λ)``."""
        n, h = self.model.ndof, self.h
        q_next, lam = x[:n], x[n:]
        c = self.model.constants
        if first:
            acc = 2.0 * (q_next - q_cur - h * v0) / h**2
            intervals = [(q_cur, q_next, 1.0)]
            mass_scale = 2.0 / h**2
        else:
            acc = (q_next - 2.0 * q_cur + q_prev) / h**2
            intervals = [(q_cur, q_next, 0.5), (q_prev, q_cur, 0.5)]
            mass_scale = 1.0 / h**2
        residual_q = self.mass @ acc + self.grad_linear
        g_next, jac_next = (a.copy() for a in self.constraints(q_next, c))
        _, jac_cur = self.constraints(q_cur, c)
        rows, cols = self.constraints.coordinates(1)
        residual_q += np.bincount(cols, weights=jac_cur * lam[rows], minlength=n)
        jac_cur = jac_cur.copy()
        element_values = []
        for k, (q_a, q_b, weight) in enumerate(intervals):
            for group, force, d_next, _, _ in self._element_terms(q_a, q_b, weight):
                residual_q += np.bincount(group.dofs.ravel(), weights=weight * force.ravel(), minlength=n)
                if k == 0:
                    element_values.append(d_next)
        jacobian = self.jacobian_pattern.matrix(
            [self.mass_values * mass_scale] + element_values + [jac_cur, jac_next]
        )
        return np.concatenate([residual_q, g_next]), jacobian

    def sensitivity_rhs(self, x, q_cur, q_prev, s_cur, s_prev, first: bool, v0=None) -> np.ndarray:
        """``∂R/∂q_j S_j + ∂R/∂q_{j−1} S_{j−1} + ∂R/∂p`` (n × n_p), top block only."""
        n, h, p = self.model.ndof, self.h, self.p
        q_next, lam = x[:n], x[n:]
        c = self.model.constants
        if first:
            acc = 2.0 * (q_next - q_cur - h * v0) / h**2
            intervals = [(q_cur, q_next, 1.0)]
        else:
            acc = (q_next - 2.0 * q_cur + q_prev) / h**2
            intervals = [(q_cur, q_next, 0.5), (q_prev, q_cur, 0.5)]
        (mass_sens,) = self.mass_sens(acc, p, c)
        rhs = self.mass_sens.sparse(0, mass_sens).toarray() + self.dgrad_dp.toarray()
        terms = [self._element_terms(q_a, q_b, w) for q_a, q_b, w in intervals]
        for group_terms in terms:
            for group, _, _, _, dp in group_terms:
                for k, index in enumerate(group.parameter_indices):
                    rhs[:, index] += np.bincount(group.dofs.ravel(), weights=dp[:, k, :].ravel(), minlength=n)
        if first:
            return rhs
        (hess,) = self.hessian(q_cur, lam, c)
        # q_cur enters as the end of the interval (q_prev, q_cur) and the start of (q_cur, q_next)
        plus, minus = terms
        d_cur = self.state_pattern.matrix(
            [-2.0 * self.mass_values / h**2]
            + [t[3] for t in plus]
            + [t[2] for t in minus]
            + [hess]
        )
        d_prev = self.prev_pattern.matrix([self.mass_values / h**2] + [t[3] for t in minus])
        return rhs + d_cur @ s_cur + d_prev @ s_prev


@dataclass
class Trajectory:
    """Result of :func:`integrate` (SI units, inertial frame).

    Attributes:
        times: (N+1,) s.
        q: (N+1, ndof) configurations at the time nodes.
        multipliers: (N, nconstraints) λ_j of each step.
        iterations: (N,) Newton iterations per step.
        sensitivities: (N+1, ndof, n_p) dq/dp, or None.
        timings: seconds spent in residual/Jacobian evaluation, LU factorisation and solves.
    """

    times: np.ndarray
    q: np.ndarray
    multipliers: np.ndarray
    iterations: np.ndarray
    sensitivities: np.ndarray | None
    timings: dict[str, float]


def _describe(parameter_names: Sequence[str], p: np.ndarray) -> str:
    return ", ".join(f"{name}={value:.6g}" for name, value in zip(parameter_names, p))


def integrate(
    model: DiscreteModel,
    q0: np.ndarray,
    p: np.ndarray,
    dt: float,
    n_steps: int,
    *,
    v0: np.ndarray | None = None,
    sensitivities: bool = False,
    tolerance: float = 1e-10,
    constraint_tolerance: float = 1e-11,
    max_iterations: int = 25,
    progress: Callable[[int], None] | None = None,
) -> Trajectory:
    """Integrate ``n_steps`` steps of size ``dt`` (s) from ``q0`` with velocity ``v0``.

    Newton stops when the last update is ≤ ``tolerance`` (m, unit directors) and the
    constraints hold to ``constraint_tolerance``.  Raises :class:`SimulationError` naming the
    time, the residual norm and the parameter values when a step does not converge.
    """
    import time as _time

    n, m = model.ndof, model.nconstraints
    p = np.asarray(p, dtype=float).ravel()
    if p.size != len(model.parameter_names):
        raise ParameterError(f"expected {len(model.parameter_names)} parameters ({', '.join(model.parameter_names)}), got {p.size}")
    if not (np.isfinite(dt) and dt > 0):
        raise ParameterError(f"time step dt must be > 0 s; got {dt}")
    q0 = np.asarray(q0, dtype=float).ravel()
    v0 = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).ravel()
    c = model.constants
    g0 = model.functions["constraints"](q0, c)[0]
    g0 = np.asarray(g0).ravel()
    if g0.size and np.max(np.abs(g0)) > 1e-9:
        worst = int(np.argmax(np.abs(g0)))
        raise ParameterError(
            f"initial configuration violates constraint {model.constraint_labels[worst]} by {g0[worst]:.3g}"
        )
    assembler = _StepAssembler(model, p, dt, sensitivities)
    n_p = p.size
    q = np.empty((n_steps + 1, n))
    lam = np.empty((n_steps, m))
    iterations = np.zeros(n_steps, dtype=int)
    sens = np.zeros((n_steps + 1, n, n_p)) if sensitivities else None
    q[0] = q0
    timings = {"evaluation": 0.0, "factorisation": 0.0, "solve": 0.0, "sensitivity": 0.0}
    x = np.concatenate([q0 + dt * v0, np.zeros(m)])
    clock = _time.perf_counter
    for j in range(n_steps):
        first = j == 0
        q_cur = q[j]
        q_prev = q[j - 1] if j > 0 else q0
        if not first:
            x[:n] = 2 * q[j] - q[j - 1]
            x[n:] = lam[j - 1]
        lu = None
        converged = False
        small_update = False
        residual = np.full(n + m, np.nan)
        for k in range(max_iterations + 1):
            t0 = clock()
            residual, jacobian = assembler.residual_jacobian(x, q_cur, q_prev, first, v0)
            timings["evaluation"] += clock() - t0
            if not np.all(np.isfinite(residual)):
                break
            if small_update and np.max(np.abs(residual[n:]), initial=0.0) <= constraint_tolerance:
                converged = True
                break
            if k == max_iterations:
                break
            t0 = clock()
            try:
                lu = splu(jacobian, permc_spec="COLAMD")
            except RuntimeError:
                break
            t1 = clock()
            dx = lu.solve(residual)
            timings["factorisation"] += t1 - t0
            timings["solve"] += clock() - t1
            x -= dx
            small_update = bool(np.max(np.abs(dx[:n])) <= tolerance * (1.0 + np.max(np.abs(x[:n]))))
        if not converged:
            norm = float(np.linalg.norm(residual)) if np.all(np.isfinite(residual)) else float("nan")
            raise SimulationError(
                f"Newton did not converge at t = {(j + 1) * dt:.4f} s (step {j + 1}, dt = {dt:g} s): "
                f"residual norm {norm:.3g} after {k} iterations; parameters {_describe(model.parameter_names, p)}; "
                "try a smaller dt or more damping (eta)"
            )
        q[j + 1] = x[:n]
        lam[j] = x[n:]
        iterations[j] = k
        if sensitivities and lu is not None:
            t0 = clock()
            s_prev = sens[j - 1] if j > 0 else sens[0]
            rhs = assembler.sensitivity_rhs(x, q_cur, q_prev, sens[j], s_prev, first, v0)
            sens[j + 1] = -lu.solve(np.vstack([rhs, np.zeros((m, n_p))]))[:n]
            timings["sensitivity"] += clock() - t0
        if progress is not None:
            progress(j + 1)
    return Trajectory(
        times=np.arange(n_steps + 1) * dt,
        q=q,
        multipliers=lam,
        iterations=iterations,
        sensitivities=sens,
        timings=timings,
    )


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


def trajectory_energies(model: DiscreteModel, trajectory: Trajectory, p: np.ndarray, v0: np.ndarray | None = None) -> Energies:
    """Kinetic, gravitational, internal, load and dissipated energy along a trajectory."""
    q = trajectory.q
    n_nodes = len(q)
    h = float(trajectory.times[1] - trajectory.times[0]) if n_nodes > 1 else 1.0
    p = np.asarray(p, float)
    c = model.constants
    v = np.empty_like(q)
    v[1:-1] = (q[2:] - q[:-2]) / (2 * h)
    v[0] = 0.0 if v0 is None else v0
    if n_nodes > 2:  # second-order one-sided difference at the last node
        v[-1] = (3 * q[-1] - 4 * q[-2] + q[-3]) / (2 * h)
    elif n_nodes == 2:
        v[-1] = (q[-1] - q[-2]) / h
    mass = _Buffered(model.functions["mass"])
    m_matrix = mass.sparse(0, mass(p, c)[0])
    kinetic = 0.5 * np.einsum("ij,ij->i", v, (m_matrix @ v.T).T)
    potential = _Buffered(model.functions["potential"])
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
        kernel = _Buffered(model.functions[f"{group.name}_energy"])
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
