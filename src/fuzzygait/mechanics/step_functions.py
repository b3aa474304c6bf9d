"""The whole step of each time-stepping scheme as single CasADi functions, for the compiled
Newton loop (:mod:`.native`).

:mod:`.schemes` assembles a step's residual and Jacobian in Python from the element kernels
(one call per kernel, sums by ``bincount``).  Here the same equations (the module docstring
of :mod:`.schemes`) are written once as CasADi ``MX`` graphs over the whole system — the
element kernels mapped over each group's elements, gathers and scatters as constant sparse
matrices — so generated C code evaluates a residual, a Jacobian or a sensitivity right-hand
side in one call, with no Python in between.  Three variants:

* ``vi1`` — the first variational step (discrete Legendre transform, Eq. 4.29),
* ``vi`` — every later variational step (Eq. 4.26),
* ``em`` — the energy-momentum step (discrete gradient, ``G(q_{j+½})ᵀλ``).

Every function takes ``(x, q_cur, q_prev, v, p, c, gc, h)``: the unknowns ``x = (q_{j+1},
λ_j)``, the two known configurations, the velocity (``v_0`` for ``vi1``, ``v_j`` for
``em``; unused by ``vi``), the parameters, the global constants, the element constants of
every group stacked (:func:`group_constants`) and the step ``h`` (s):

* ``fgs_res_<variant>`` → the residual ``R`` (n + m),
* ``fgs_jac_<variant>`` → ``∂R/∂x`` (sparse; the element blocks from the ``tangent``
  kernels, as :meth:`.schemes.StepAssembler.jacobian`),
* ``fgs_sens_<variant>`` with three more inputs ``S_cur, S_prev, S_v`` (each ``n_p × n``,
  the transposed sensitivities ``dq_j/dp``, ``dq_{j−1}/dp``, ``dv_j/dp``) →
  ``(∂R/∂q_j S_j + ∂R/∂q_{j−1} S_{j−1} + ∂R/∂v_j S_v + ∂R/∂p)ᵀ`` (n_p × (n + m)), term by
  term from the ``tangent`` and ``parameters`` kernels as
  :meth:`.schemes.StepAssembler.sensitivity_rhs` (not by automatic differentiation of the
  residual, whose generated code is ten times larger).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from fuzzygait.mechanics.assembly import ElementGroup, SystemBuilder

VARIANTS = ("vi1", "vi", "em")
KINDS = ("res", "jac", "sens")


def function_names() -> list[str]:
    """Names of the generated functions, ``fgs_<kind>_<variant>``."""
    return [f"fgs_{kind}_{variant}" for variant in VARIANTS for kind in KINDS]


def group_constants(groups: Sequence[ElementGroup]) -> np.ndarray:
    """The ``gc`` input: every group's ``(n_el, k)`` element constants, element-major, stacked."""
    parts = [np.asarray(g.constants, dtype=float).ravel() for g in groups]
    return np.concatenate(parts) if parts else np.zeros(0)


class _Group:
    """One element group in the graph: gathers, scatter matrix and mapped kernels."""

    def __init__(self, group: ElementGroup, gc: ca.MX, offset: int, n: int) -> None:
        dofs = group.dofs
        self.n_el = len(dofs)
        self.index = dofs.ravel().tolist()  # element-major: column e of a (24, n_el) gather
        k = group.constants.shape[1]
        self.constants = ca.reshape(gc[offset : offset + k * self.n_el], k, self.n_el)
        self.size = k * self.n_el
        self.scatter = ca.DM(ca.Sparsity.triplet(n, 24 * self.n_el, self.index, list(range(24 * self.n_el))),
                             1.0)  # fmt: skip
        self.parameter_indices = list(group.parameter_indices)
        kinds = ("force", "tangent", "parameters", "em_force", "em_tangent", "em_parameters")
        self.kernels = {kind: group.kernels[kind].map(f"{group.name}_{kind}_step", "serial", self.n_el, [], [])
                        for kind in kinds}  # fmt: skip

    def inputs(self, q_a: ca.MX, q_b: ca.MX, p: ca.MX, h: ca.MX) -> list[ca.MX]:
        a = ca.reshape(q_a[self.index], 24, self.n_el)
        b = ca.reshape(q_b[self.index], 24, self.n_el)
        pe = ca.repmat(p[self.parameter_indices], 1, self.n_el) if self.parameter_indices else ca.MX(0, self.n_el)
        return [0.5 * (a + b), (b - a) / h, self.constants, pe]

    def force(self, q_a: ca.MX, q_b: ca.MX, p: ca.MX, h: ca.MX, em: bool) -> ca.MX:
        """The assembled element forces (n,) of the interval ``[q_a, q_b]``."""
        args = self.inputs(q_a, q_b, p, h) + ([ca.repmat(h, 1, self.n_el)] if em else [])
        (force,) = self.kernels["em_force" if em else "force"].call(args)
        return ca.mtimes(self.scatter, ca.vec(force))

    def tangent(self, q_a: ca.MX, q_b: ca.MX, p: ca.MX, h: ca.MX, weight: float, em: bool,
                end: str = "b") -> ca.MX:  # fmt: skip
        """``weight ·`` the derivative of the interval's forces with respect to ``q_b``
        (``end`` "b") or ``q_a`` ("a"), assembled (n × n sparse)."""
        args = self.inputs(q_a, q_b, p, h) + ([ca.repmat(h, 1, self.n_el)] if em else [])
        _, dq, dv = self.kernels["em_tangent" if em else "tangent"].call(args)
        block = weight * (0.5 * dq + dv / h if end == "b" else 0.5 * dq - dv / h)  # (24, 24 n_el)
        blocks = ca.diagcat(*ca.horzsplit(block, 24)) if self.n_el > 1 else block
        # kernel layout: block[row, col] = d force_row / d q_col (as StepAssembler: [e, col, row] in memory)
        assembled = ca.mtimes(ca.mtimes(self.scatter, blocks), self.scatter.T)
        return assembled  # type: ignore[return-value]  # MX: casadi's stub types mtimes as DM

    def parameter_force(self, q_a: ca.MX, q_b: ca.MX, p: ca.MX, h: ca.MX, weight: float, em: bool,
                        n_p: int) -> ca.MX:  # fmt: skip
        """``weight ·`` the derivative of the interval's forces with respect to ``p`` (n × n_p)."""
        n_pe = len(self.parameter_indices)
        columns = [ca.MX(self.scatter.size1(), 1)] * n_p
        if n_pe:
            args = self.inputs(q_a, q_b, p, h) + ([ca.repmat(h, 1, self.n_el)] if em else [])
            (dp,) = self.kernels["em_parameters" if em else "parameters"].call(args)  # (24, n_pe n_el)
            for k, index in enumerate(self.parameter_indices):
                columns[index] = weight * ca.mtimes(self.scatter, ca.vec(dp[:, list(range(k, n_pe * self.n_el, n_pe))]))
        return ca.horzcat(*columns)


INPUT_NAMES = ("x", "q_cur", "q_prev", "v", "p", "c", "gc", "h")
SENSITIVITY_NAMES = ("S_cur", "S_prev", "S_v")


@dataclass(frozen=True)
class _Symbols:
    """The inputs of the generated functions (module docstring), as CasADi ``MX`` symbols.

    Attributes:
        x: the unknowns ``(q_{j+1}, λ_j)`` (n + m).
        q_cur, q_prev: the known configurations ``q_j``, ``q_{j−1}`` (n, inertial frame).
        v: the velocity ``v_0`` (``vi1``) or ``v_j`` (``em``) (n, per second).
        p: the parameters (n_p); c: the global constants; gc: the stacked element constants.
        h: the time step (s).
        s_cur, s_prev, s_v: the transposed sensitivities ``dq_j/dp``, ``dq_{j−1}/dp``,
            ``dv_j/dp`` (each n_p × n).
    """

    x: ca.MX
    q_cur: ca.MX
    q_prev: ca.MX
    v: ca.MX
    p: ca.MX
    c: ca.MX
    gc: ca.MX
    h: ca.MX
    s_cur: ca.MX
    s_prev: ca.MX
    s_v: ca.MX

    @classmethod
    def of(cls, builder: SystemBuilder) -> _Symbols:
        """The symbols sized for the system of ``builder``."""
        n, m, n_p = builder.ndof, builder.g.numel(), len(builder.parameter_names)
        return cls(
            x=ca.MX.sym("x", n + m), q_cur=ca.MX.sym("q_cur", n), q_prev=ca.MX.sym("q_prev", n), v=ca.MX.sym("v", n),
            p=ca.MX.sym("p", n_p), c=ca.MX.sym("c", builder.c.numel()),
            gc=ca.MX.sym("gc", int(group_constants(builder.element_groups).size)), h=ca.MX.sym("h"),
            s_cur=ca.MX.sym("S_cur", n_p, n), s_prev=ca.MX.sym("S_prev", n_p, n), s_v=ca.MX.sym("S_v", n_p, n),
        )  # fmt: skip

    @property
    def inputs(self) -> list[ca.MX]:
        """The inputs of the residual and Jacobian functions, in the order of :data:`INPUT_NAMES`."""
        return [self.x, self.q_cur, self.q_prev, self.v, self.p, self.c, self.gc, self.h]


class _StepEquations:
    """The step equations of one system over :class:`_Symbols`: the global terms (mass
    matrix, linear potential, constraints at ``q_{j+1}``, ``q_j`` and the midpoint), the
    element sums, and per variant the residual, Jacobian and sensitivity right-hand side
    (the ``n`` configuration rows; the ``m`` constraint rows are added by :meth:`functions`)."""

    def __init__(self, builder: SystemBuilder, globals_: Callable[[str], ca.Function]) -> None:
        self.n, self.m, self.n_p = builder.ndof, builder.g.numel(), len(builder.parameter_names)
        self.globals_ = globals_
        self.s = s = _Symbols.of(builder)
        self.parts: list[_Group] = []
        offset = 0
        for group in builder.element_groups:
            self.parts.append(_Group(group, s.gc, offset, self.n))
            offset += self.parts[-1].size
        n, p, c = self.n, s.p, s.c
        self.q_next, self.lam = s.x[:n], s.x[n:]
        (self.mass,) = globals_("mass").call([p, c])
        self.grad_linear = globals_("linear").call([ca.MX.zeros(n), p, c])[0]
        self.g_next, self.jac_next = globals_("constraints").call([self.q_next, c])
        _, self.jac_cur = globals_("constraints").call([s.q_cur, c])
        self.mid = 0.5 * (s.q_cur + self.q_next)
        _, self.jac_mid = globals_("constraints").call([self.mid, c])

    def forces(self, q_a: ca.MX, q_b: ca.MX, em: bool = False) -> ca.MX:
        """The element forces of the interval ``[q_a, q_b]``, summed over the groups (n)."""
        total = ca.MX.zeros(self.n)
        for part in self.parts:
            total = total + part.force(q_a, q_b, self.s.p, self.s.h, em)
        return total

    def tangents(self, q_a: ca.MX, q_b: ca.MX, weight: float, em: bool = False, end: str = "b") -> ca.MX:
        """:meth:`_Group.tangent` summed over the groups (n × n sparse)."""
        total = ca.MX(self.n, self.n)
        for part in self.parts:
            total = total + part.tangent(q_a, q_b, self.s.p, self.s.h, weight, em, end)
        return total

    def parameter_forces(self, q_a: ca.MX, q_b: ca.MX, weight: float, em: bool = False) -> ca.MX:
        """:meth:`_Group.parameter_force` summed over the groups (n × n_p)."""
        total = ca.MX(self.n, self.n_p)
        for part in self.parts:
            total = total + part.parameter_force(q_a, q_b, self.s.p, self.s.h, weight, em, self.n_p)
        return total

    def residuals(self) -> dict[str, ca.MX]:
        """Per variant the configuration rows of the residual (n): Eq. 4.29, Eq. 4.26 and
        the energy-momentum step."""
        s, mass, q_next, lam = self.s, self.mass, self.q_next, self.lam
        q_cur, q_prev, h = s.q_cur, s.q_prev, s.h
        return {
            "vi1": 2.0 * ca.mtimes(mass, q_next - q_cur - h * s.v) / h**2 + self.grad_linear
            + self.forces(q_cur, q_next) + ca.mtimes(self.jac_cur.T, lam),
            "vi": ca.mtimes(mass, q_next - 2.0 * q_cur + q_prev) / h**2 + self.grad_linear
            + 0.5 * (self.forces(q_cur, q_next) + self.forces(q_prev, q_cur)) + ca.mtimes(self.jac_cur.T, lam),
            "em": 2.0 * ca.mtimes(mass, q_next - q_cur - h * s.v) / h**2 + self.grad_linear
            + self.forces(q_cur, q_next, em=True) + ca.mtimes(self.jac_mid.T, lam),
        }  # fmt: skip

    def jacobians(self, hessian_mid: ca.MX) -> dict[str, ca.MX]:
        """Per variant ``∂R_q/∂q_{j+1}`` (n × n sparse); ``hessian_mid`` is ``∂(Gᵀλ)/∂q`` at
        the midpoint."""
        mass, q_cur, q_next, h = self.mass, self.s.q_cur, self.q_next, self.s.h
        return {
            "vi1": 2.0 * mass / h**2 + self.tangents(q_cur, q_next, 1.0),
            "vi": mass / h**2 + self.tangents(q_cur, q_next, 0.5),
            "em": 2.0 * mass / h**2 + self.tangents(q_cur, q_next, 1.0, em=True) + 0.5 * hessian_mid,
        }

    def sensitivity_rhs(self, hessian_mid: ca.MX) -> dict[str, ca.MX]:
        """Per variant the configuration rows of the sensitivity right-hand side (n × n_p),
        term by term as :meth:`.schemes.StepAssembler.sensitivity_rhs`."""
        s, mass, q_next, globals_ = self.s, self.mass, self.q_next, self.globals_
        q_cur, q_prev, h, p, c = s.q_cur, s.q_prev, s.h, s.p, s.c
        (hessian_cur,) = globals_("constraint_hessian").call([q_cur, self.lam, c])
        d_grad_dp = globals_("linear").call([ca.MX.zeros(self.n), p, c])[1]

        def mass_sensitivity(acceleration: ca.MX) -> ca.MX:
            return globals_("mass_sens").call([acceleration, p, c])[0]

        start_acceleration = 2.0 * (q_next - q_cur - h * s.v) / h**2
        s_cur_t, s_prev_t, s_v_t = s.s_cur.T, s.s_prev.T, s.s_v.T
        tangents, parameter_forces = self.tangents, self.parameter_forces
        return {
            "vi1": mass_sensitivity(start_acceleration) + d_grad_dp + parameter_forces(q_cur, q_next, 1.0),
            "vi": mass_sensitivity((q_next - 2.0 * q_cur + q_prev) / h**2) + d_grad_dp
            + parameter_forces(q_cur, q_next, 0.5) + parameter_forces(q_prev, q_cur, 0.5)
            + ca.mtimes(-2.0 * mass / h**2 + tangents(q_cur, q_next, 0.5, end="a") + tangents(q_prev, q_cur, 0.5)
                        + hessian_cur, s_cur_t)
            + ca.mtimes(mass / h**2 + tangents(q_prev, q_cur, 0.5, end="a"), s_prev_t),
            "em": mass_sensitivity(start_acceleration) + d_grad_dp + parameter_forces(q_cur, q_next, 1.0, em=True)
            + ca.mtimes(-2.0 * mass / h**2 + tangents(q_cur, q_next, 1.0, em=True, end="a") + 0.5 * hessian_mid,
                        s_cur_t)
            - (2.0 / h) * ca.mtimes(mass, s_v_t),
        }  # fmt: skip

    def functions(self) -> list[ca.Function]:
        """The nine functions of the module docstring, ``(res, jac, sens)`` per variant."""
        s, m, n_p = self.s, self.m, self.n_p
        residual_q = self.residuals()
        (hessian_mid,) = self.globals_("constraint_hessian").call([self.mid, self.lam, s.c])
        jacobian_qq = self.jacobians(hessian_mid)
        constraint_columns = {"vi1": self.jac_cur.T, "vi": self.jac_cur.T, "em": self.jac_mid.T}
        rhs_q = self.sensitivity_rhs(hessian_mid)
        inputs, names = s.inputs, list(INPUT_NAMES)
        out: list[ca.Function] = []
        for variant in VARIANTS:
            residual = ca.vertcat(residual_q[variant], self.g_next)
            jacobian = ca.blockcat([[jacobian_qq[variant], constraint_columns[variant]], [self.jac_next, ca.MX(m, m)]])
            # (n + m, n_p): the constraints do not depend on p
            rhs = ca.densify(ca.vertcat(rhs_q[variant], ca.MX(m, n_p)))
            out += [
                ca.Function(f"fgs_res_{variant}", inputs, [residual], names, ["residual"]),
                ca.Function(f"fgs_jac_{variant}", inputs, [jacobian], names, ["jacobian"]),
                ca.Function(f"fgs_sens_{variant}", [*inputs, s.s_cur, s.s_prev, s.s_v], [rhs.T],
                            [*names, *SENSITIVITY_NAMES], ["rhs"]),  # fmt: skip
            ]
        return out


def step_functions(builder: SystemBuilder, globals_: Callable[[str], ca.Function]) -> list[ca.Function]:
    """The nine functions of the module docstring for the system of ``builder``.

    ``globals_(name)`` gives the symbolic global function ``name`` (``mass``, ``linear``,
    ``constraints``, ``constraint_hessian``, ``mass_sens``) of :mod:`.discrete`.
    """
    return _StepEquations(builder, globals_).functions()
