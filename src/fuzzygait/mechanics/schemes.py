"""The step equations of the two time-stepping schemes (thesis §4.1.2, Eqs. 4.16–4.29).

Variational (default): with the midpoint discrete Lagrangian
``L_d = h L((q_j + q_{j+1})/2, (q_{j+1} − q_j)/h)``, the trapezoidal constraint term and the
Lagrange–d'Alembert forces of Eq. 4.25, the discrete Euler–Lagrange equations (4.26), divided
by −h, read for the unknowns ``x = (q_{j+1}, λ_j)``::

    M (q_{j+1} − 2 q_j + q_{j−1}) / h² + ½ [∇V(q_{j+½}) + ∇V(q_{j−½})] + G(q_j)ᵀ λ_j
        − ½ [f(q_{j+½}, v_{j+½}) + f(q_{j−½}, v_{j−½})] = 0,      g(q_{j+1}) = 0,

with ``q_{j±½}`` the interval midpoints, ``v_{j±½}`` the difference quotients and
``f = −∂V_visc/∂v`` the viscous force.  The first step follows from the discrete Legendre
transform (Eq. 4.29) with the initial momentum ``p_0 = M v_0``::

    2 M (q_1 − q_0 − h v_0) / h² + ∇V(q_½) + G(q_0)ᵀ λ_0 − f(q_½, v_½) = 0,   g(q_1) = 0.

Energy-momentum: the one-step midpoint scheme with the discrete-gradient beam force and
``G(q_{j+½})ᵀλ`` (Betsch & Steinmann)::

    M (v_{j+1} − v_j) / h + ∇̄V + G(q_{j+½})ᵀ λ_j = 0,   v_{j+1} = 2 (q_{j+1} − q_j) / h − v_j,   g(q_{j+1}) = 0.

:class:`StepAssembler` assembles the residuals, Jacobians and parameter-sensitivity terms of
either scheme from the element kernels and the global functions of a :class:`DiscreteModel`;
:mod:`.integrator` solves them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fuzzygait.mechanics.assembly import ElementGroup
from fuzzygait.mechanics.discrete import KERNEL_KINDS, BufferedFunction, DiscreteModel
from fuzzygait.mechanics.solver import SCHEMES as SCHEMES  # the schemes, listed with the solver settings


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


class StepAssembler:
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


