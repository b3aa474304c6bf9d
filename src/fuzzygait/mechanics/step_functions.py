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


def step_functions(builder: SystemBuilder, globals_: Callable[[str], ca.Function]) -> list[ca.Function]:
    """The nine functions of the module docstring for the system of ``builder``.

    ``globals_(name)`` gives the symbolic global function ``name`` (``mass``, ``linear``,
    ``constraints``, ``constraint_hessian``) of :mod:`.discrete`.
    """
    n, m, n_p = builder.ndof, builder.g.numel(), len(builder.parameter_names)
    groups = builder.element_groups
    x = ca.MX.sym("x", n + m)
    q_cur, q_prev, v = ca.MX.sym("q_cur", n), ca.MX.sym("q_prev", n), ca.MX.sym("v", n)
    p, c = ca.MX.sym("p", n_p), ca.MX.sym("c", builder.c.numel())
    gc = ca.MX.sym("gc", int(group_constants(groups).size))
    h = ca.MX.sym("h")
    s_cur, s_prev, s_v = ca.MX.sym("S_cur", n_p, n), ca.MX.sym("S_prev", n_p, n), ca.MX.sym("S_v", n_p, n)
    parts: list[_Group] = []
    offset = 0
    for group in groups:
        parts.append(_Group(group, gc, offset, n))
        offset += parts[-1].size
    q_next, lam = x[:n], x[n:]
    (mass,) = globals_("mass").call([p, c])
    grad_linear = globals_("linear").call([ca.MX.zeros(n), p, c])[0]
    g_next, jac_next = globals_("constraints").call([q_next, c])
    _, jac_cur = globals_("constraints").call([q_cur, c])
    mid = 0.5 * (q_cur + q_next)
    _, jac_mid = globals_("constraints").call([mid, c])

    def forces(q_a: ca.MX, q_b: ca.MX, em: bool = False) -> ca.MX:
        total = ca.MX.zeros(n)
        for part in parts:
            total = total + part.force(q_a, q_b, p, h, em)
        return total

    def tangents(q_a: ca.MX, q_b: ca.MX, weight: float, em: bool = False, end: str = "b") -> ca.MX:
        total = ca.MX(n, n)
        for part in parts:
            total = total + part.tangent(q_a, q_b, p, h, weight, em, end)
        return total

    def parameter_forces(q_a: ca.MX, q_b: ca.MX, weight: float, em: bool = False) -> ca.MX:
        total = ca.MX(n, n_p)
        for part in parts:
            total = total + part.parameter_force(q_a, q_b, p, h, weight, em, n_p)
        return total

    residual_q = {
        "vi1": 2.0 * ca.mtimes(mass, q_next - q_cur - h * v) / h**2 + grad_linear + forces(q_cur, q_next)
        + ca.mtimes(jac_cur.T, lam),
        "vi": ca.mtimes(mass, q_next - 2.0 * q_cur + q_prev) / h**2 + grad_linear
        + 0.5 * (forces(q_cur, q_next) + forces(q_prev, q_cur)) + ca.mtimes(jac_cur.T, lam),
        "em": 2.0 * ca.mtimes(mass, q_next - q_cur - h * v) / h**2 + grad_linear + forces(q_cur, q_next, em=True)
        + ca.mtimes(jac_mid.T, lam),
    }
    (hessian_mid,) = globals_("constraint_hessian").call([mid, lam, c])
    jacobian_qq = {
        "vi1": 2.0 * mass / h**2 + tangents(q_cur, q_next, 1.0),
        "vi": mass / h**2 + tangents(q_cur, q_next, 0.5),
        "em": 2.0 * mass / h**2 + tangents(q_cur, q_next, 1.0, em=True) + 0.5 * hessian_mid,
    }
    constraint_columns = {"vi1": jac_cur.T, "vi": jac_cur.T, "em": jac_mid.T}
    # sensitivity right-hand sides, term by term as StepAssembler.sensitivity_rhs
    (hessian_cur,) = globals_("constraint_hessian").call([q_cur, lam, c])
    d_grad_dp = globals_("linear").call([ca.MX.zeros(n), p, c])[1]

    def mass_sensitivity(acceleration: ca.MX) -> ca.MX:
        return globals_("mass_sens").call([acceleration, p, c])[0]

    start_acceleration = 2.0 * (q_next - q_cur - h * v) / h**2
    s_cur_t, s_prev_t, s_v_t = s_cur.T, s_prev.T, s_v.T
    rhs_q = {
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
    }
    inputs = [x, q_cur, q_prev, v, p, c, gc, h]
    names = ["x", "q_cur", "q_prev", "v", "p", "c", "gc", "h"]
    out: list[ca.Function] = []
    for variant in VARIANTS:
        residual = ca.vertcat(residual_q[variant], g_next)
        jacobian = ca.blockcat([[jacobian_qq[variant], constraint_columns[variant]], [jac_next, ca.MX(m, m)]])
        rhs = ca.densify(ca.vertcat(rhs_q[variant], ca.MX(m, n_p)))  # (n + m, n_p): the constraints do not depend on p
        out += [
            ca.Function(f"fgs_res_{variant}", inputs, [residual], names, ["residual"]),
            ca.Function(f"fgs_jac_{variant}", inputs, [jacobian], names, ["jacobian"]),
            ca.Function(f"fgs_sens_{variant}", [*inputs, s_cur, s_prev, s_v], [rhs.T],
                        [*names, "S_cur", "S_prev", "S_v"], ["rhs"]),  # fmt: skip
        ]
    return out
