"""The compiled Newton loop: every step of a run solved in C (``native/stepper.c``).

The library holds the generated step functions of one model structure
(:mod:`.step_functions`: residual, Jacobian and sensitivity right-hand side of the first
variational, the later variational and the energy-momentum step) and the hand-written loop
that solves them — the modified Newton iteration, folding check and sensitivity recursion
of :func:`.integrator.integrate`, with a sparse LU whose pivot order comes from one SuperLU
factorisation and is reused (refreshed when a pivot becomes too small).  It is compiled
once per structure and cached beside the kernel library (:mod:`fuzzygait.core.codegen`); Python calls it
once per chunk of steps (progress and Ctrl-C between chunks), never per iteration.
"""

from __future__ import annotations

import ctypes
import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from fuzzygait.core.codegen import build_library, cache_dir, compiler, library_key
from fuzzygait.mechanics.assembly import SystemBuilder
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.mechanics.step_functions import function_names, step_functions

SOURCE = Path(__file__).with_name("native") / "stepper.c"
HEADER = "fgs_gen"
#: Compiler optimisation of the step library (part of its cache key): -O2 steps 15 % faster
#: than -O1 for about 3 s more compilation per model structure.
OPTIMISATION = "-O2"
#: Steps per call into C: progress callbacks and interrupts are handled in between.
CHUNK_STEPS = 50

OK, NEWTON, FOLD, PIVOT = 0, 1, 2, 3
#: Pivot orders computed at one step before its Jacobian counts as singular.
MAX_RENEWALS = 50

_double_p = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_int_p = np.ctypeslib.ndpointer(dtype=np.int32, flags="C_CONTIGUOUS")


def _nullable(pointer_type: type) -> type:
    """A pointer argument that also accepts None (a NULL pointer)."""

    class Nullable(pointer_type):
        @classmethod
        def from_param(cls, value: object) -> object:
            return None if value is None else pointer_type.from_param(value)  # type: ignore[attr-defined]

    return Nullable


def stepper_library_path(structure_key: str) -> Path:
    """Where the compiled stepper of this structure is cached."""
    digest = hashlib.sha256(SOURCE.read_bytes() + OPTIMISATION.encode()).hexdigest()[:12]
    return cache_dir() / f"fgs_{library_key(structure_key + '|stepper|' + digest, function_names())}.so"


def ensure_stepper(builder: SystemBuilder, globals_: Callable[[str], ca.Function]) -> Path | None:
    """The cached stepper library of ``builder``'s structure, compiled if missing; None
    without a C compiler (or ``FUZZYGAIT_NO_COMPILE=1``) or when compilation fails."""
    if compiler() is None:
        return None
    target = stepper_library_path(builder.structure_key)
    if target.exists():
        return target
    return build_library(target, step_functions(builder, globals_), [SOURCE], optimisation=OPTIMISATION, header=HEADER)


_LIBRARIES: dict[Path, ctypes.CDLL] = {}


def load(path: Path) -> ctypes.CDLL:
    """The stepper library at ``path`` with its C signatures (loaded once per process)."""
    if path in _LIBRARIES:
        return _LIBRARIES[path]
    lib = ctypes.CDLL(str(path))
    c_int, c_double, c_void = ctypes.c_int, ctypes.c_double, ctypes.c_void_p
    nd, ni = _nullable(_double_p), _nullable(_int_p)
    lib.fg_new.restype = c_void
    lib.fg_new.argtypes = [c_int, c_int, c_int, c_int, c_int, c_int, c_double, c_double, c_double, c_int,
                           _double_p, _double_p, _double_p, _double_p, _double_p,
                           _double_p, nd, nd, nd, _int_p,
                           c_int, ni, ni, c_int, ni]  # fmt: skip
    lib.fg_free.argtypes = [c_void]
    lib.fg_free.restype = None
    lib.fg_jacobian_nnz.argtypes = [c_void]
    lib.fg_jacobian_pattern.argtypes = [c_void, _int_p, _int_p]
    lib.fg_jacobian_pattern.restype = None
    lib.fg_jacobian.argtypes = [c_void, _double_p]
    lib.fg_jacobian.restype = None
    lib.fg_set_pivots.argtypes = [c_void, c_int, _int_p, _int_p]
    lib.fg_pivot_which.argtypes = [c_void]
    lib.fg_factor_size.argtypes = [c_void]
    lib.fg_run.argtypes = [c_void, c_int]
    lib.fg_step.argtypes = [c_void]
    lib.fg_status.argtypes = [c_void] + [ctypes.POINTER(c_int)] * 3 + [ctypes.POINTER(c_double)]
    lib.fg_status.restype = None
    lib.fg_statistics.argtypes = [c_void, _double_p]
    lib.fg_statistics.restype = None
    _LIBRARIES[path] = lib
    return lib


@dataclass
class Stopped:
    """Why a compiled run stopped early: ``kind`` "newton" (``step``, ``iterations``,
    residual norm ``value``) or "fold" (``step``, element ``index`` over all groups, the
    cosine ``value`` of its cross-sections' turn)."""

    kind: str
    step: int
    iterations: int
    index: int
    value: float


@dataclass
class NativeRun:
    """Outputs of :func:`run` (arrays as :class:`.trajectory.Trajectory`)."""

    q: np.ndarray
    multipliers: np.ndarray
    iterations: np.ndarray
    velocities: np.ndarray | None
    sensitivities: np.ndarray | None
    timings: dict[str, float]
    stopped: Stopped | None
    pivot_orders: int


@dataclass(frozen=True)
class NativeProblem:
    """The system a compiled run integrates: ``n`` coordinates, ``m`` constraints, the
    parameter vector ``p``, the model's ``constants`` and ``group_constants`` and
    ``fold_pairs``: offsets in ``q`` of the tangent directors d3 at the two nodes of every
    element and the start of each group's elements."""

    n: int
    m: int
    p: np.ndarray
    constants: np.ndarray
    group_constants: np.ndarray
    fold_pairs: tuple[np.ndarray, np.ndarray, np.ndarray]


def run(
    path: Path,
    problem: NativeProblem,
    q0: np.ndarray,
    v0: np.ndarray,
    settings: SolverSettings,
    *,
    sensitivities: bool = False,
    progress: Callable[[int], None] | None = None,
) -> NativeRun:
    """Integrate ``settings.steps`` uniform steps ``settings.dt`` with the compiled loop of
    the library at ``path`` (``settings.substeps`` and ``max_halvings`` are the caller's:
    :func:`.integrator.integrate`)."""
    lib = load(path)
    n, m, p, n_steps = problem.n, problem.m, problem.p, settings.steps
    n_p = int(p.size)
    energy_momentum = settings.scheme == "energy-momentum"
    q = np.empty((n_steps + 1, n))
    lam = np.empty((n_steps, m))
    iterations = np.zeros(n_steps, dtype=np.int32)
    velocities = np.empty((n_steps + 1, n)) if energy_momentum else None
    sens = np.empty((n_steps + 1, n, n_p)) if sensitivities else None
    arrays = [np.ascontiguousarray(a, dtype=float) for a in (p, problem.constants, problem.group_constants, q0, v0)]
    pair_a, pair_b, starts = (np.ascontiguousarray(a, dtype=np.int32) for a in problem.fold_pairs)
    ctx = lib.fg_new(n, m, n_p, n_steps, int(energy_momentum), int(sensitivities), float(settings.dt),
                     float(settings.tolerance), float(settings.constraint_tolerance), int(settings.max_iterations),
                     *arrays, q, lam, velocities, sens, iterations,
                     int(pair_a.size), pair_a, pair_b, int(starts.size - 1), starts)  # fmt: skip
    if not ctx:
        raise MemoryError("the compiled simulator could not allocate its work arrays")
    try:
        loop = _Loop(lib, ctx, n + m)
        stopped = loop.run(n_steps, sensitivities, progress)
        statistics = np.empty(5)
        lib.fg_statistics(ctx, statistics)
    finally:
        lib.fg_free(ctx)
    timings = dict(zip(("evaluation", "factorisation", "solve", "sensitivity", "factorisations"), statistics.tolist()))
    return NativeRun(q, lam, iterations.astype(int), velocities, sens, timings, stopped, loop.pivot_orders)


class _Loop:
    """Drives a compiled run ``ctx`` chunk by chunk; gives it SuperLU pivot orders when it asks."""

    def __init__(self, lib: ctypes.CDLL, ctx: int, size: int) -> None:
        self.lib, self.ctx, self.size = lib, ctx, size
        self.pivot_orders = 0
        nnz = lib.fg_jacobian_nnz(ctx)
        self.indptr, self.indices = np.empty(size + 1, dtype=np.int32), np.empty(nnz, dtype=np.int32)
        lib.fg_jacobian_pattern(ctx, self.indptr, self.indices)
        self.values = np.empty(nnz)

    def new_pivot_order(self, which: tuple[int, ...]) -> bool:
        """SuperLU's order for the Jacobian where the stepper stands, for the Newton LU
        (0) and/or the sensitivities' LU (1); False if that Jacobian is singular."""
        lib, ctx, N = self.lib, self.ctx, self.size
        lib.fg_jacobian(ctx, self.values)
        try:
            factor = splu(sp.csc_matrix((self.values, self.indices, self.indptr), shape=(N, N)), permc_spec="COLAMD")
        except RuntimeError:  # singular Jacobian: Newton cannot continue
            return False
        self.pivot_orders += 1
        perm_r = np.ascontiguousarray(factor.perm_r, dtype=np.int32)
        perm_c = np.ascontiguousarray(factor.perm_c, dtype=np.int32)
        return all(lib.fg_set_pivots(ctx, w, perm_r, perm_c) for w in which)

    def run(self, n_steps: int, sensitivities: bool, progress: Callable[[int], None] | None) -> Stopped | None:
        """Run to ``n_steps``; why it stopped early (None: it did not)."""
        lib, ctx = self.lib, self.ctx
        stopped: Stopped | None = None
        if not self.new_pivot_order((0, 1) if sensitivities else (0,)):
            stopped = Stopped("newton", 0, 0, 0, float("nan"))
        renewals: dict[tuple[int, int], int] = {}  # (step, which LU) -> orders computed there
        while stopped is None and lib.fg_step(ctx) < n_steps:
            before = lib.fg_step(ctx)
            status = lib.fg_run(ctx, min(before + CHUNK_STEPS, n_steps))
            if status == PIVOT:
                where = (lib.fg_step(ctx), lib.fg_pivot_which(ctx))
                renewals[where] = renewals.get(where, 0) + 1
                # fresh orders failing again and again at one step: the Jacobian is (nearly) singular there
                if renewals[where] > MAX_RENEWALS or not self.new_pivot_order((where[1],)):
                    stopped = Stopped("newton", where[0], 0, 0, float("nan"))
                continue
            if status in (NEWTON, FOLD):
                step, its, index, value = ctypes.c_int(), ctypes.c_int(), ctypes.c_int(), ctypes.c_double()
                lib.fg_status(ctx, ctypes.byref(step), ctypes.byref(its), ctypes.byref(index), ctypes.byref(value))
                stopped = Stopped("newton" if status == NEWTON else "fold", step.value, its.value, index.value,
                                  value.value)  # fmt: skip
            if progress is not None:
                progress(lib.fg_step(ctx))
        return stopped
