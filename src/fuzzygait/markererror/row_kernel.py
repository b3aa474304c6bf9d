"""Compiled marker-error models: a model's own code traced once into C, row by row.

The α-level optimisation asks a model for millions of rows (one deviation at one frame
each).  In numpy with autograd a joint-angle row costs about 1 µs for the values and
2.3 µs with its gradient, plus 0.7 / 2.5 ms per call (``benchmarks/RESULTS.md``, issue 40);
a joint-moment row, which runs the chain on nine frames, ten times that.  Here the model's
row function — its own Python code, the kinematic chain and the dynamics — is called once
with symbols instead of numbers (:mod:`.symbols`), giving a CasADi expression of one row;
CasADi differentiates it (reverse mode) and generates C, compiled with the row loops of
``native/rows.c`` into a library cached on disk (:mod:`fuzzygait.core.codegen`:
``$FUZZYGAIT_CACHE_DIR``; once per model structure and subject, whichever process asks
first).  The values equal the numpy code's to rounding; the gradients are the exact ones of
the same expression.

A row function ``f(x, p, q)`` takes three flat inputs:

* ``x`` ``(n_x,)``: what the row's frame gives (marker positions, the ground's load), one
  row of a ``base`` table per model frame, picked by the row's node;
* ``p`` ``(n_p,)``: the row's deviations, the parameters the gradient is taken for;
* ``q`` ``(n_q,)``: shared by every row (the progression frame, the sampling rate …), an
  input rather than a constant so that one library serves every trial;

and returns ``(n_out + n_checks,)`` outputs; the gradient is that of the output a row
selects among the first ``n_out`` (the last ``n_checks`` are values only: what tells a row
beyond the model's limits).

No kernel (the model runs on numpy, same numbers, slower): without a C compiler or with
``FUZZYGAIT_NO_COMPILE=1``, and for code that decides on its data, where tracing stops with
:class:`~.symbols.NotTraceable` or numpy refuses an operation on symbols.  The kinematic
code's iterations (the rotated chord, the cluster fits' polar rotation) run fixed steps when
traced and make a row they have not settled NaN: status :data:`UNSETTLED`, which the model
computes on numpy.
"""

from __future__ import annotations

import ctypes
import hashlib
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from fuzzygait.core.codegen import build_library, cache_dir, compiler
from fuzzygait.markererror.symbols import NotTraceable, expressions, symbol_array

ROWS_SOURCE = Path(__file__).with_name("native") / "rows.c"
#: File-name prefix of the row kernels' libraries in the compiled-code cache.
ROW_LIBRARY_PREFIX = "fg_rows_"
#: Compiler optimisation of the kernels (part of the cache key).
OPTIMISATION = "-O2"
VALUES, GRADIENT = "fg_values", "fg_gradient"

#: Row status: outputs; an input missing (NaN outputs and gradients, as numpy gives);
#: outputs NaN from measured inputs — the caller computes those rows with the numpy code
#: (an iteration the fixed steps did not settle, or an output not defined there).
SETTLED, MISSING, UNSETTLED = 0, 1, 2

#: ``f(x, p, q)`` on object arrays of symbols -> the ``(n_out,)`` outputs (module docstring).
RowFunction = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]

_double_p = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_long_p = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")
_status_p = np.ctypeslib.ndpointer(dtype=np.int8, flags="C_CONTIGUOUS")


@dataclass(frozen=True)
class Shape:
    """The sizes of a row function's inputs and outputs: ``n_out`` outputs a gradient can
    select, then ``n_checks`` values only (module docstring)."""

    n_x: int
    n_p: int
    n_q: int
    n_out: int
    n_checks: int = 0

    @property
    def n_values(self) -> int:
        """Every output of a row: the selectable ones and the checks."""
        return self.n_out + self.n_checks


@dataclass(frozen=True)
class RowKernel:
    """A compiled row function.  ``base`` ``(n_frames, n_x)``: one ``x`` per model frame;
    ``nodes`` ``(k,)``: each row's frame (an index into ``base``); ``P`` ``(k, n_p)``: the
    rows' deviations; ``q`` ``(n_q,)``.  Each call returns the rows' status too
    (:data:`SETTLED`, :data:`MISSING`, :data:`UNSETTLED`)."""

    library: ctypes.CDLL
    shape: Shape

    def _rows(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray,
              q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        base, P = np.ascontiguousarray(base, dtype=float), np.ascontiguousarray(P, dtype=float)
        nodes, q = np.ascontiguousarray(nodes, dtype=np.int64), np.ascontiguousarray(q, dtype=float).ravel()
        s = self.shape
        if base.shape[1:] != (s.n_x,) or P.shape != (len(nodes), s.n_p) or q.shape != (s.n_q,):
            raise ValueError(f"rows of {base.shape[1:]}, {P.shape[1:]}, {q.shape} for a kernel of {s}")
        if len(nodes) and (nodes.min() < 0 or nodes.max() >= len(base)):
            raise IndexError("a row's node lies outside the base table")
        return base, nodes, P, q

    def values(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray,
               q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """``(k, n_out + n_checks)`` outputs and the ``(k,)`` status.  A row that repeats
        another (the same node and deviations: the blocks of one model screening the same
        random points) is computed once (:func:`distinct_rows`)."""
        base, nodes, P, q = self._rows(base, nodes, P, q)
        repeats = distinct_rows(nodes, P)
        if repeats is not None:
            first, inverse = repeats
            out, status = self.values(base, nodes[first], P[first], q)
            return out[inverse], status[inverse]
        k, s = len(nodes), self.shape
        out, status = np.empty((k, s.n_values)), np.empty(k, dtype=np.int8)
        if self.library.fg_value_rows(k, s.n_x, s.n_p, s.n_values, base, nodes, P, q, out, status):
            raise MemoryError("a compiled model could not allocate its workspace")
        return out, status

    def gradients(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray, q: np.ndarray,
                  select: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """Per row ``i`` output ``select[i]`` (< ``n_out``) ``(k,)``, the checks ``(k,
        n_checks)``, the gradient of that output with respect to the row's deviations ``(k,
        n_p)`` and the ``(k,)`` status."""
        base, nodes, P, q = self._rows(base, nodes, P, q)
        k, s = len(nodes), self.shape
        select = np.ascontiguousarray(np.broadcast_to(select, (k,)), dtype=np.int64)
        if k and (select.min() < 0 or select.max() >= s.n_out):
            raise IndexError(f"a row selects an output outside 0..{s.n_out - 1}")
        values, checks, gradients = np.empty(k), np.empty((k, s.n_checks)), np.empty((k, s.n_p))
        status = np.empty(k, dtype=np.int8)
        if self.library.fg_gradient_rows(k, s.n_x, s.n_p, s.n_out, s.n_checks, base, nodes, P, q, select, values,
                                         checks, gradients, status):  # fmt: skip
            raise MemoryError("a compiled model could not allocate its workspace")
        return values, checks, gradients, status


#: :func:`distinct_rows` looks for repeated rows from this many rows on.
MIN_ROWS_TO_SHARE = 256


def distinct_rows(nodes: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(first, inverse)``: the first of each distinct row ``(nodes[i], P[i])`` and each
    row's index among them (row ``i`` equals row ``first[inverse[i]]`` exactly), or None
    where fewer than a quarter of the rows repeat, or there are fewer than
    :data:`MIN_ROWS_TO_SHARE` rows, or the first row does not repeat (the cheap test that
    spares a call without repeats the sort: where blocks share rows, each of the first
    block's rows has its twins).  Rows are told apart by a fixed random projection, and the
    match is checked element by element (a collision, or a NaN, gives None)."""
    k = len(nodes)
    if k < MIN_ROWS_TO_SHARE:
        return None
    weights = np.random.default_rng(0).uniform(0.5, 1.5, P.shape[1] + 1)
    key = P @ weights[1:] + weights[0] * nodes
    if np.count_nonzero(key == key[0]) < 2:
        return None
    _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    if first.size > 0.75 * k:
        return None
    inverse = inverse.ravel()
    each = first[inverse]
    if not (np.array_equal(P[each], P) and np.array_equal(nodes[each], nodes)):
        return None
    return first, inverse


class CompiledModel:
    """A model with a compiled row function: its kernel looked up once per instance
    (:meth:`held_kernel`) and left behind when the instance is pickled (a worker process
    loads its own)."""

    #: False: always numpy (the same numbers, slower).
    compiled: bool

    def held_kernel(self, make: Callable[[], RowKernel | None]) -> RowKernel | None:
        """``make()`` the first time (None when not :attr:`compiled`), then the same."""
        if not self.compiled:
            return None
        if "_kernel" not in self.__dict__:
            self._kernel = make()
        return self._kernel

    def __getstate__(self) -> dict[str, object]:
        """The instance's state without the loaded kernel."""
        return {k: v for k, v in self.__dict__.items() if k != "_kernel"}


def traced_functions(function: RowFunction, shape: Shape) -> tuple[ca.Function, ca.Function]:
    """The values and selected-gradient functions of ``function`` for one row (raises
    :class:`~.symbols.NotTraceable`, or numpy a ``TypeError``, where it decides on its data).
    The gradient function ``(x, p, q, w) -> (outputs, gradient of w · the selectable outputs)``
    is one reverse sweep for every output, the row's selection an input: one function
    per output would take up to a sixth less time a row, but its C code, one copy per
    output, took nine times as long to compile (a leg's kinetics 28 s against 6 s)."""
    x, p, q, w = (ca.SX.sym(name, size) for name, size in (("x", shape.n_x), ("p", shape.n_p), ("q", shape.n_q),
                                                           ("w", shape.n_out)))  # fmt: skip
    out = np.ravel(function(symbol_array(x, (shape.n_x,)), symbol_array(p, (shape.n_p,)),
                            symbol_array(q, (shape.n_q,))))  # fmt: skip
    if out.shape != (shape.n_values,):
        raise NotTraceable(f"the row function gave {out.shape} outputs, not ({shape.n_values},)")
    y = expressions(out)
    selectable = y[: shape.n_out]
    return ca.Function(VALUES, [x, p, q], [y]), ca.Function(GRADIENT, [x, p, q, w],
                                                             [y, ca.gradient(ca.dot(w, selectable), p)])  # fmt: skip


def _load(path: Path) -> ctypes.CDLL:
    library = ctypes.CDLL(str(path))
    n = [ctypes.c_long] * 4
    library.fg_value_rows.argtypes = [*n, _double_p, _long_p, _double_p, _double_p, _double_p, _status_p]
    library.fg_gradient_rows.argtypes = [*n, ctypes.c_long, _double_p, _long_p, _double_p, _double_p, _long_p,
                                         _double_p, _double_p, _double_p, _status_p]  # fmt: skip
    return library


_KERNELS: dict[str, RowKernel | None] = {}


def model_key(*parts: object) -> str:
    """A digest of what a model's row function is made of (version, outputs, markers,
    subject, calibration …): their ``repr`` with every array in full and every float exact
    (shortest round-trip digits), for :func:`compile_kernel`'s memo."""
    with np.printoptions(threshold=sys.maxsize, floatmode="unique"):
        text = repr(parts)
    return hashlib.sha256(text.encode()).hexdigest()


def compile_kernel(key: str, function: RowFunction, shape: Shape, purpose: str) -> RowKernel | None:
    """The compiled kernel of ``function`` (memoised per process under ``key``, a digest of
    what the function is made of: model version, outputs, markers, subject …), or None where
    it cannot be had (module docstring).  ``purpose`` names the model in a compiler warning."""
    if key in _KERNELS:
        return _KERNELS[key]
    kernel = None
    if compiler() is not None:
        try:
            functions = traced_functions(function, shape)
        except TypeError:  # NotTraceable, or numpy refusing an operation on symbols (np.isfinite)
            functions = None
        if functions is not None:
            version = ca.__version__  # type: ignore[attr-defined]  # set at import, absent from casadi's stub
            text = "|".join([version, OPTIMISATION, ROWS_SOURCE.read_text(), *(f.serialize() for f in functions)])
            target = cache_dir() / f"{ROW_LIBRARY_PREFIX}{hashlib.sha256(text.encode()).hexdigest()[:20]}.so"
            try:
                path = target if target.exists() else build_library(
                    target, functions, sources=[ROWS_SOURCE], optimisation=OPTIMISATION, purpose=purpose)  # fmt: skip
                kernel = None if path is None else RowKernel(_load(path), shape)
            except OSError as error:  # a cache folder that cannot be written, a library that cannot be loaded
                warnings.warn(f"cannot compile {purpose} in {cache_dir()} ({error}); running uncompiled (slower); "
                              "set FUZZYGAIT_CACHE_DIR to a writable folder", stacklevel=3)  # fmt: skip
    _KERNELS[key] = kernel
    return kernel
