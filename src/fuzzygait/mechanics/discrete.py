"""The discrete model: the CasADi functions of a built system, ready for time stepping.

:class:`DiscreteModel` holds the global functions (mass matrix, linear potential,
constraints) and the per-element kernels of each element group (forces, tangents, parameter
derivatives and energies for both schemes), compiled and cached on disk by model structure
(:mod:`fuzzygait.core.codegen`).  :class:`BufferedFunction` evaluates one of them into numpy buffers
without copies.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import scipy.sparse as sp

from fuzzygait.core.codegen import compile_functions, load_cached
from fuzzygait.mechanics.assembly import ElementGroup, SystemBuilder
from fuzzygait.mechanics.native import ensure_stepper

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
        stepper: the compiled Newton loop of this structure (:mod:`.native`), or None
            (no compiler: :func:`.integrator.integrate` steps in Python).
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
    stepper: Path | None = None

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
        stepper = None
        if compile:
            symbolic_globals: dict[str, ca.Function] = {}

            def global_function(name: str) -> ca.Function:  # built only when the stepper is compiled
                if not symbolic_globals:
                    symbolic_globals.update({f.name(): f for f in _global_functions(builder)})
                return symbolic_globals[name]

            stepper = ensure_stepper(builder, global_function)
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
            stepper=stepper,
        )

    def group_inputs(self, group: ElementGroup, q_a: np.ndarray, q_b: np.ndarray, h: float, p: np.ndarray):
        """Kernel inputs at the midpoint of the interval ``[q_a, q_b]`` (all elements)."""
        dofs = group.dofs
        mid = 0.5 * (q_a + q_b)[dofs].T
        vel = ((q_b - q_a) / h)[dofs].T
        pe = np.repeat(p[list(group.parameter_indices)][:, None], len(dofs), axis=1)
        return mid, vel, group.constants.T, pe

