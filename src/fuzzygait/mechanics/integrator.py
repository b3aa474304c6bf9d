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

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from fuzzygait.core.errors import ParameterError, SimulationError
from fuzzygait.mechanics.assembly import ElementGroup, SystemBuilder
from fuzzygait.mechanics.codegen import compile_functions, load_cached

# Newton keeps its LU factorisation across iterations and steps and refreshes it when an
# update shrinks by less than this factor (linear convergence too slow to be worth it).
REFRESH_CONTRACTION = 0.25
# Largest Newton update of any coordinate per iteration (m for positions, 1 for directors);
# a time step of a few ms never moves a coordinate this far, so larger updates are divergence.
MAX_UPDATE = 0.2

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


KERNEL_KINDS = ("force", "tangent", "parameters", "energy", "em_force", "em_tangent", "em_parameters")
SCHEMES = ("variational", "energy-momentum")


def _group_functions(group: ElementGroup) -> list[ca.Function]:
    n_el = len(group.node_offsets)
    # a map is generated as a loop over one element's code, not n_el inlined copies
    return [group.kernels[kind].map(f"{group.name}_{kind}", "serial", n_el, [], []) for kind in KERNEL_KINDS]


class BufferedFunction:
    """Zero-copy evaluation of a CasADi function into numpy buffers (nonzeros of each output)."""

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self.buffer, self._evaluate = function.buffer()
        self.results = []
        for i in range(function.n_out()):
            out = np.zeros(function.sparsity_out(i).nnz())
            self.buffer.set_res(i, out.data)  # type: ignore[call-arg]  # stub lists the byte size the binding derives
            self.results.append(out)
        self._args: list[np.ndarray] = [np.zeros(0)] * function.n_in()

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        for i, value in enumerate(args):
            array = np.ascontiguousarray(value, dtype=float).ravel(order="F")
            self._args[i] = array  # keep alive while the buffer points at it
            self.buffer.set_arg(i, array.data)  # type: ignore[call-arg]  # as set_res
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
    def from_builder(cls, builder: SystemBuilder, compile: bool = True) -> DiscreteModel:
        """Load the cached compiled library for this structure, or build (and compile) it."""
        key = builder.structure_key
        names = list(GLOBAL_FUNCTIONS) + [f"{g.name}_{kind}" for g in builder.element_groups for kind in KERNEL_KINDS]
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


@dataclass
class _GroupBuffers:
    """One element group's kernels, index arrays and per-element inputs in a step assembler."""

    group: ElementGroup
    dofs: np.ndarray
    flat: np.ndarray
    constants: np.ndarray
    pe: np.ndarray
    kernels: dict[str, BufferedFunction]
    rows: np.ndarray
    cols: np.ndarray
    h: np.ndarray


class _StepAssembler:
    """Residuals, Jacobians and sensitivity terms of the step equations, assembled from the
    element kernels and the global functions (see the module docstring).

    Per step, everything that depends only on the known ``q_j, q_{j−1}`` (the interval
    ``[q_{j−1}, q_j]``, ``G(q_j)``) is evaluated once in :meth:`begin_step`; a Newton
    iteration then evaluates only the new interval and the constraints at ``q_{j+1}``.
    """

    def __init__(self, model: DiscreteModel, p: np.ndarray, h: float, sensitivities: bool,
                 scheme: str = "variational") -> None:
        self.model, self.p, self.h = model, p, h
        self.energy_momentum = scheme == "energy-momentum"
        n, m = model.ndof, model.nconstraints
        self.n, self.m = n, m
        c = model.constants
        f = model.functions
        mass_fn = BufferedFunction(f["mass"])
        self.mass_values = mass_fn(p, c)[0].copy()
        self.mass = mass_fn.sparse(0, self.mass_values)
        linear = BufferedFunction(f["linear"])
        grad_linear, dgrad_dp = linear(np.zeros(n), p, c)
        self.grad_linear = grad_linear.copy()
        self.constraints = BufferedFunction(f["constraints"])
        self.g_rows, self.g_cols = self.constraints.coordinates(1)
        self.groups: list[_GroupBuffers] = []
        for group in model.groups:
            dofs = group.dofs
            pe = np.repeat(p[list(group.parameter_indices)][:, None], len(dofs), axis=1)
            self.groups.append(
                _GroupBuffers(
                    group=group,
                    dofs=dofs,
                    flat=dofs.ravel(),
                    constants=np.ascontiguousarray(group.constants.T),
                    pe=pe,
                    kernels={kind: BufferedFunction(f[f"{group.name}_{kind}"]) for kind in KERNEL_KINDS},
                    rows=np.broadcast_to(dofs[:, None, :], (len(dofs), 24, 24)),  # buffer layout [e, col, row]
                    cols=np.broadcast_to(dofs[:, :, None], (len(dofs), 24, 24)),
                    h=np.full(len(dofs), h),
                )
            )
        m_rows, m_cols = mass_fn.coordinates(0)
        element_coords = [(g.rows, g.cols) for g in self.groups]
        self.hessian = BufferedFunction(f["constraint_hessian"])
        h_rows, h_cols = self.hessian.coordinates(0)
        self.jacobian_pattern = _Pattern(
            (n + m, n + m),
            [(m_rows, m_cols)] + element_coords + [(self.g_cols, n + self.g_rows), (n + self.g_rows, self.g_cols)]
            + ([(h_rows, h_cols)] if self.energy_momentum else []),
        )
        if sensitivities:
            self.dgrad_dp = linear.sparse(1, dgrad_dp).toarray()
            self.mass_sens = BufferedFunction(f["mass_sens"])
            self.state_pattern = _Pattern((n, n), [(m_rows, m_cols)] + element_coords * 2 + [(h_rows, h_cols)])
            self.em_state_pattern = _Pattern((n, n), [(m_rows, m_cols)] + element_coords + [(h_rows, h_cols)])
            self.prev_pattern = _Pattern((n, n), [(m_rows, m_cols)] + element_coords)

    # -- kernels --------------------------------------------------------------------------
    def _inputs(self, g: _GroupBuffers, q_a: np.ndarray, q_b: np.ndarray):
        mid = 0.5 * (q_a[g.dofs] + q_b[g.dofs]).T
        vel = ((q_b[g.dofs] - q_a[g.dofs]) / self.h).T
        return mid, vel, g.constants, g.pe

    def _forces(self, q_a, q_b, weight, em: bool = False) -> np.ndarray:
        out = np.zeros(self.n)
        for g in self.groups:
            if em:
                (force,) = g.kernels["em_force"](*self._inputs(g, q_a, q_b), g.h)
            else:
                (force,) = g.kernels["force"](*self._inputs(g, q_a, q_b))
            out += np.bincount(g.flat, weights=weight * force, minlength=self.n)
        return out

    def _tangents(self, q_a, q_b, weight, em: bool = False):
        """Per group: (d force/d q_b, d force/d q_a) blocks, weighted, layout [e, col, row]."""
        out = []
        for g in self.groups:
            if em:
                _, dq, dv = g.kernels["em_tangent"](*self._inputs(g, q_a, q_b), g.h)
            else:
                _, dq, dv = g.kernels["tangent"](*self._inputs(g, q_a, q_b))
            dq = dq.reshape(-1, 24, 24)
            dv = dv.reshape(-1, 24, 24)
            out.append((weight * (0.5 * dq + dv / self.h), weight * (0.5 * dq - dv / self.h)))
        return out

    # -- step -----------------------------------------------------------------------------
    def begin_step(self, q_cur, q_prev, first: bool, v0) -> None:
        """Prepare step j → j+1; ``v0`` is the initial velocity (variational) or the current
        velocity ``v_j`` (energy-momentum)."""
        h, c = self.h, self.model.constants
        self.q_cur, self.q_prev, self.first, self.v0 = q_cur, q_prev, first, v0
        if self.energy_momentum:  # M (v_{j+1} − v_j)/h + ∇̄V + G(q_{j+½})ᵀλ = 0, v_{j+1} = 2Δq/h − v_j
            self.mass_scale, self.weight = 2.0 / h**2, 1.0
            self.base = self.grad_linear - self.mass @ (2.0 * (q_cur + h * v0) / h**2)
            return
        if first:
            self.mass_scale, self.weight = 2.0 / h**2, 1.0
            self.base = self.grad_linear - self.mass @ (2.0 * (q_cur + h * v0) / h**2)
        else:
            self.mass_scale, self.weight = 1.0 / h**2, 0.5
            self.base = (
                self.grad_linear
                + self.mass @ ((q_prev - 2.0 * q_cur) / h**2)
                + self._forces(q_prev, q_cur, 0.5)
            )
        self.jac_cur = self.constraints(q_cur, c)[1].copy()

    def residual(self, x: np.ndarray) -> np.ndarray:
        n = self.n
        q_next, lam = x[:n], x[n:]
        if self.energy_momentum:
            jac_mid = self.constraints(0.5 * (self.q_cur + q_next), self.model.constants)[1]
            constraint_force = np.bincount(self.g_cols, weights=jac_mid * lam[self.g_rows], minlength=n)
            g_next = self.constraints(q_next, self.model.constants)[0]
            residual_q = (
                self.base
                + self.mass_scale * (self.mass @ q_next)
                + constraint_force
                + self._forces(self.q_cur, q_next, 1.0, em=True)
            )
            return np.concatenate([residual_q, g_next])
        g_next = self.constraints(q_next, self.model.constants)[0]
        residual_q = (
            self.base
            + self.mass_scale * (self.mass @ q_next)
            + np.bincount(self.g_cols, weights=self.jac_cur * lam[self.g_rows], minlength=n)
            + self._forces(self.q_cur, q_next, self.weight)
        )
        return np.concatenate([residual_q, g_next])

    def jacobian(self, x: np.ndarray) -> sp.csc_matrix:
        q_next = x[: self.n]
        c = self.model.constants
        if self.energy_momentum:
            mid = 0.5 * (self.q_cur + q_next)
            jac_mid = self.constraints(mid, c)[1].copy()
            jac_next = self.constraints(q_next, c)[1].copy()
            hess = 0.5 * self.hessian(mid, x[self.n :], c)[0]
            blocks = [t[0] for t in self._tangents(self.q_cur, q_next, 1.0, em=True)]
            return self.jacobian_pattern.matrix(
                [self.mass_values * self.mass_scale] + blocks + [jac_mid, jac_next, hess]
            )
        jac_next = self.constraints(q_next, self.model.constants)[1].copy()
        blocks = [t[0] for t in self._tangents(self.q_cur, q_next, self.weight)]
        return self.jacobian_pattern.matrix([self.mass_values * self.mass_scale] + blocks + [self.jac_cur, jac_next])

    def sensitivity_rhs(self, x, s_cur, s_prev) -> np.ndarray:
        """``∂R/∂q_j S_j + ∂R/∂q_{j−1} S_{j−1} + ∂R/∂p`` (n × n_p), the rows of ``R_q``.

        Energy-momentum: ``s_prev`` is the velocity sensitivity ``dv_j/dp`` and the terms are
        ``∂R/∂q_j S_j + ∂R/∂v_j dv_j/dp + ∂R/∂p``.
        """
        n, h, p, c = self.n, self.h, self.p, self.model.constants
        q_next, lam = x[:n], x[n:]
        q_cur, q_prev = self.q_cur, self.q_prev
        if self.energy_momentum:
            acc = 2.0 * (q_next - q_cur - h * self.v0) / h**2
            rhs = self.mass_sens.sparse(0, self.mass_sens(acc, p, c)[0]).toarray() + self.dgrad_dp
            for g in self.groups:
                (dp,) = g.kernels["em_parameters"](*self._inputs(g, q_cur, q_next), g.h)
                dp = dp.reshape(-1, len(g.group.parameter_indices), 24)
                for k, index in enumerate(g.group.parameter_indices):
                    rhs[:, index] += np.bincount(g.flat, weights=dp[:, k, :].ravel(), minlength=n)
            blocks = self._tangents(q_cur, q_next, 1.0, em=True)
            hess = 0.5 * self.hessian(0.5 * (q_cur + q_next), lam, c)[0]
            d_cur = self.em_state_pattern.matrix([-2.0 * self.mass_values / h**2] + [t[1] for t in blocks] + [hess])
            return rhs + d_cur @ s_cur - (2.0 / h) * (self.mass @ s_prev)
        if self.first:
            acc = 2.0 * (q_next - q_cur - h * self.v0) / h**2
            intervals = [(q_cur, q_next, 1.0)]
        else:
            acc = (q_next - 2.0 * q_cur + q_prev) / h**2
            intervals = [(q_cur, q_next, 0.5), (q_prev, q_cur, 0.5)]
        rhs = self.mass_sens.sparse(0, self.mass_sens(acc, p, c)[0]).toarray() + self.dgrad_dp
        for q_a, q_b, weight in intervals:
            for g in self.groups:
                (dp,) = g.kernels["parameters"](*self._inputs(g, q_a, q_b))
                dp = dp.reshape(-1, len(g.group.parameter_indices), 24)
                for k, index in enumerate(g.group.parameter_indices):
                    rhs[:, index] += np.bincount(g.flat, weights=weight * dp[:, k, :].ravel(), minlength=n)
        if self.first:  # S_0 = 0: the initial state does not depend on the parameters
            return rhs
        plus = self._tangents(q_cur, q_next, 0.5)
        minus = self._tangents(q_prev, q_cur, 0.5)
        (hess,) = self.hessian(q_cur, lam, c)
        # q_j is the start of [q_j, q_{j+1}] and the end of [q_{j−1}, q_j]
        d_cur = self.state_pattern.matrix(
            [-2.0 * self.mass_values / h**2] + [t[1] for t in plus] + [t[0] for t in minus] + [hess]
        )
        d_prev = self.prev_pattern.matrix([self.mass_values / h**2] + [t[1] for t in minus])
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
        velocities: (N+1, ndof) nodal velocities of the energy-momentum scheme (None for the
            variational integrator, whose energies use central differences).
        scheme: "variational" or "energy-momentum".
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


FOLD_COSINE = 0.0  # adjacent beam cross-sections turned by more than 90° = a folded element


def _check_folding(model: DiscreteModel, q: np.ndarray, t: float, p: np.ndarray) -> None:
    """Raise when a beam element has folded: its two nodes' tangent directors d3 turned by
    more than 90° against each other.  The midpoint element then averages the directors to
    nearly zero and can stretch at almost no energy cost — a discretisation artefact, so the
    run stops instead of returning a physically meaningless motion."""
    for group in model.groups:
        dofs = group.dofs
        cosine = np.einsum("ek,ek->e", q[dofs[:, 9:12]], q[dofs[:, 21:24]])
        worst = int(np.argmin(cosine))
        if cosine[worst] < FOLD_COSINE:
            angle = float(np.degrees(np.arccos(np.clip(cosine[worst], -1.0, 1.0))))
            raise SimulationError(
                f"{group.name} element {worst} folded at t = {t:.4f} s: its cross-sections turned by "
                f"{angle:.0f}° (> 90°) within one element; parameters {_describe(model.parameter_names, p)}; "
                "use more nodes, a stiffer blade or more damping (eta)"
            )


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
    scheme: str = "variational",
) -> Trajectory:
    """Integrate ``n_steps`` steps of size ``dt`` (s) from ``q0`` with velocity ``v0``.

    ``scheme`` "variational" (default): the variational integrator of Eq. 4.26.
    "energy-momentum": the one-step midpoint scheme with the discrete-gradient beam force and
    ``G(q_{j+½})ᵀλ`` (Betsch & Steinmann): energy is conserved exactly without damping and
    the damped balance ``E_0 = E_j + D_j`` holds to the Newton tolerance.  Both give
    sensitivities.

    Newton stops when the last update is ≤ ``tolerance`` (m, unit directors) and the
    constraints hold to ``constraint_tolerance``.  Raises :class:`SimulationError` naming the
    time, the residual norm and the parameter values when a step does not converge.
    """
    import time as _time

    n, m = model.ndof, model.nconstraints
    p = np.asarray(p, dtype=float).ravel()
    if p.size != len(model.parameter_names):
        raise ParameterError(
            f"expected {len(model.parameter_names)} parameters ({', '.join(model.parameter_names)}), got {p.size}"
        )
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
    if scheme not in SCHEMES:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEMES)}; got {scheme!r}")
    energy_momentum = scheme == "energy-momentum"
    assembler = _StepAssembler(model, p, dt, sensitivities, scheme)
    velocities = np.empty((n_steps + 1, n)) if energy_momentum else None
    if velocities is not None:
        velocities[0] = v0
    n_p = p.size
    q = np.empty((n_steps + 1, n))
    lam = np.empty((n_steps, m))
    iterations = np.zeros(n_steps, dtype=int)
    factorisations = 0
    sens = np.zeros((n_steps + 1, n, n_p)) if sensitivities else None
    sens_v = np.zeros((n, n_p))  # dv_j/dp of the energy-momentum scheme (v_0 is given)
    q[0] = q0
    timings = {"evaluation": 0.0, "factorisation": 0.0, "solve": 0.0, "sensitivity": 0.0}
    x = np.concatenate([q0 + dt * v0, np.zeros(m)])
    clock = _time.perf_counter
    lu = None

    def factorise(at: np.ndarray):
        nonlocal factorisations
        t0 = clock()
        jacobian = assembler.jacobian(at)
        t1 = clock()
        timings["evaluation"] += t1 - t0
        try:
            factor = splu(jacobian, permc_spec="COLAMD")
        except RuntimeError:  # singular Jacobian
            factor = None
        timings["factorisation"] += clock() - t1
        factorisations += 1
        return factor

    for j in range(n_steps):
        first = j == 0
        q_cur = q[j]
        q_prev = q[j - 1] if j > 0 else q0
        if not first:
            x[:n] = 2 * q[j] - q[j - 1]
            x[n:] = lam[j - 1]
        t0 = clock()
        assembler.begin_step(q_cur, q_prev, first, velocities[j] if velocities is not None else v0)
        timings["evaluation"] += clock() - t0
        if lu is None or first:
            lu = factorise(x)
        # Newton with a kept factorisation (a chord step while it contracts well).  When an
        # update shrinks by less than REFRESH_CONTRACTION: if the previous update came from a
        # stale factorisation, undo it and refactorise there; otherwise refactorise here
        # (full Newton from then on, as long as needed).
        converged = False
        previous = np.inf
        residual = np.full(n + m, np.nan)
        fresh_here = first  # the factorisation was computed at the current x
        last_dx: np.ndarray | None = None
        last_stale = False
        k = 0
        while k < max_iterations and lu is not None:
            t0 = clock()
            residual = assembler.residual(x)
            timings["evaluation"] += clock() - t0
            finite = bool(np.all(np.isfinite(residual)))
            if finite:
                t0 = clock()
                dx = lu.solve(residual)
                timings["solve"] += clock() - t0
                size = float(np.max(np.abs(dx[:n])))
                finite = np.isfinite(size)
            if not finite or size > REFRESH_CONTRACTION * previous:
                if last_stale and last_dx is not None:
                    x += last_dx  # undo the chord step that went astray
                elif fresh_here or not finite:
                    break  # a fresh Newton step diverged or left the domain
                lu = factorise(x)
                fresh_here, last_dx, last_stale, previous = True, None, False, np.inf
                continue
            if size > MAX_UPDATE:  # damped Newton: never jump further than MAX_UPDATE per iteration
                dx *= MAX_UPDATE / size
            x -= dx
            k += 1
            last_dx, last_stale, fresh_here = dx, not fresh_here, False
            if size <= tolerance * (1.0 + float(np.max(np.abs(x[:n])))) and (
                np.max(np.abs(residual[n:]), initial=0.0) <= constraint_tolerance or size == 0.0
            ):
                converged = True
                break
            previous = size
        if converged:
            g_check = assembler.residual(x)[n:]
            converged = np.max(np.abs(g_check), initial=0.0) <= max(constraint_tolerance, 1e3 * tolerance)
        if not converged:
            with np.errstate(all="ignore"):
                norm = float(np.linalg.norm(residual)) if np.all(np.isfinite(residual)) else float("nan")
            raise SimulationError(
                f"Newton did not converge at t = {(j + 1) * dt:.4f} s (step {j + 1}, dt = {dt:g} s): "
                f"residual norm {norm:.3g} after {k} iterations; parameters {_describe(model.parameter_names, p)}; "
                "try a smaller dt, more damping (eta) or the energy-momentum scheme"
            )
        q[j + 1] = x[:n]
        lam[j] = x[n:]
        iterations[j] = k
        _check_folding(model, q[j + 1], (j + 1) * dt, p)
        if velocities is not None:
            velocities[j + 1] = 2.0 * (q[j + 1] - q[j]) / dt - velocities[j]
        if sens is not None:
            t0 = clock()
            exact = factorise(x)  # the Jacobian at the converged step
            if energy_momentum:  # velocity sensitivities dv_j/dp ride along
                s_prev = sens_v
            else:
                s_prev = sens[j - 1] if j > 0 else sens[0]
            rhs = assembler.sensitivity_rhs(x, sens[j], s_prev)
            sens[j + 1] = -exact.solve(np.vstack([rhs, np.zeros((m, n_p))]))[:n]
            if energy_momentum:
                sens_v = 2.0 * (sens[j + 1] - sens[j]) / dt - sens_v
            # the Newton path keeps its own factorisation: trajectories are bit-identical with and without sensitivities
            timings["sensitivity"] += clock() - t0
        if progress is not None:
            progress(j + 1)
    timings["factorisations"] = float(factorisations)
    return Trajectory(
        times=np.arange(n_steps + 1) * dt,
        q=q,
        multipliers=lam,
        iterations=iterations,
        sensitivities=sens,
        timings=timings,
        velocities=velocities,
        scheme=scheme,
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
