"""A joint-angle model compiled: its angles and exact gradients in C, row by row.

The α-level optimisation asks the kinematic model for millions of rows (one set of
marker positions each).  In numpy a row costs about 1 µs for the values and 2.3 µs with
its autograd gradient, plus 0.7 / 2.5 ms per call (``benchmarks/RESULTS.md``, issue 40).
Here the model's own chain — the same Python code — is traced once with symbolic
positions (:mod:`.symbols`) into a CasADi expression of one row: the three angle
components (degrees) from the markers' positions (mm) and the progression frame; CasADi
differentiates it (reverse mode: the gradient of a weighted sum of the components with
respect to the perturbed markers' coordinates) and generates C, compiled with the row
loops of ``native/angle_rows.c`` into a library cached on disk (:mod:`fuzzygait.core.codegen`:
``$FUZZYGAIT_CACHE_DIR``, once per model structure and subject, whichever process asks
first).  The values equal the numpy chain's to rounding (1e-12°); the gradients are the
exact ones of the same expression.

No kernel (the model runs on numpy, same numbers, slower): without a C compiler or with
``FUZZYGAIT_NO_COMPILE=1``, and for a chain that decides on its data — the cluster fits
of CGM 2.3/2.4 (visibility masks, an iteration), Plug-in Gait's rotated chord (thigh or
shank rotation offsets, an iteration to convergence) — where tracing stops with
:class:`~.symbols.NotTraceable`.
"""

from __future__ import annotations

import ctypes
import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from fuzzygait.core.codegen import build_library, cache_dir, compiler
from fuzzygait.markererror.symbols import NotTraceable, expressions, symbol_array

ROWS_SOURCE = Path(__file__).with_name("native") / "angle_rows.c"
#: Compiler optimisation of the kernels (part of the cache key).
OPTIMISATION = "-O2"
VALUES, GRADIENTS = "fg_angles", "fg_angles_gradient"

_double_p = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_long_p = np.ctypeslib.ndpointer(dtype=np.int64, flags="C_CONTIGUOUS")
_status_p = np.ctypeslib.ndpointer(dtype=np.int8, flags="C_CONTIGUOUS")

#: ``angles(perturbed, fixed, progression)``: the model's chain on ``(rows, n, 3)`` and
#: ``(rows, n_fixed, 3)`` positions (mm) and a ``(3, 3)`` progression frame -> ``(rows, 3)``
#: degrees.
Chain = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


#: Row status of the kernel: its angles; a position missing (NaN angles and gradients,
#: as the chain gives); angles NaN from measured positions — the chain decides those rows
#: (an iteration the fixed steps did not settle, or an angle not defined there).
SETTLED, MISSING, UNSETTLED = 0, 1, 2


@dataclass(frozen=True)
class AngleKernel:
    """The compiled angle of one model.  A row is a frame's marker positions plus its
    deviations: ``base`` ``(n_frames, 3 n_markers)`` mm (the perturbed markers' x, y, z
    first, then the fixed markers'), ``nodes`` ``(k,)`` its frame per row, ``P``
    ``(k, 3 n_perturbed)`` mm the deviations; one ``(3, 3)`` progression frame for all.
    Each call also returns the rows' status (:data:`SETTLED`, :data:`MISSING`,
    :data:`UNSETTLED`)."""

    library: ctypes.CDLL
    n_markers: int
    n_perturbed: int

    def _rows(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (np.ascontiguousarray(base, dtype=float), np.ascontiguousarray(nodes, dtype=np.int64),
                np.ascontiguousarray(P, dtype=float))  # fmt: skip

    def angles(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray,
               progression: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """``(k, 3)`` degrees on the chain's own branch (wrapped into (-180°, 180°]) and the
        ``(k,)`` status."""
        base, nodes, P = self._rows(base, nodes, P)
        k = len(nodes)
        out, status = np.empty((k, 3)), np.empty(k, dtype=np.int8)
        q = np.ascontiguousarray(progression, dtype=float).ravel()
        if self.library.fg_angle_rows(k, base.shape[1], P.shape[1], base, nodes, P, q, out, status):
            raise MemoryError("the angle kernel could not allocate its workspace")
        return out, status

    def gradients(self, base: np.ndarray, nodes: np.ndarray, P: np.ndarray, progression: np.ndarray,
                  axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
        """``(k, 3)`` angles (degrees), ``(k, 3 n_perturbed)`` gradients (degrees/mm) of
        component ``axes[i]`` of row ``i`` with respect to its deviations, and the status."""
        base, nodes, P = self._rows(base, nodes, P)
        k = len(nodes)
        axes = np.ascontiguousarray(np.broadcast_to(axes, (k,)), dtype=np.int64)
        out, gradients, status = np.empty((k, 3)), np.empty((k, P.shape[1])), np.empty(k, dtype=np.int8)
        q = np.ascontiguousarray(progression, dtype=float).ravel()
        if self.library.fg_angle_gradient_rows(k, base.shape[1], P.shape[1], base, nodes, P, q, axes, out,
                                               gradients, status):  # fmt: skip
            raise MemoryError("the angle kernel could not allocate its workspace")
        return out, gradients, status


def traced_functions(chain: Chain, n_perturbed: int, n_fixed: int) -> tuple[ca.Function, ca.Function]:
    """The values and weighted-gradient functions of ``chain`` for one row (raises
    :class:`~.symbols.NotTraceable` when the chain decides on its data)."""
    n_markers = n_perturbed + n_fixed
    x, q, w = ca.SX.sym("x", 3 * n_markers), ca.SX.sym("q", 9), ca.SX.sym("w", 3)
    positions = symbol_array(x, (1, n_markers, 3))
    angles = chain(positions[:, :n_perturbed], positions[:, n_perturbed:], symbol_array(q, (3, 3)))
    if np.shape(angles) != (1, 3):
        raise NotTraceable(f"the chain gave {np.shape(angles)} angles for one row")
    y = expressions(np.ravel(angles))
    gradient = ca.gradient(ca.dot(w, y), x[: 3 * n_perturbed])
    return ca.Function(VALUES, [x, q], [y]), ca.Function(GRADIENTS, [x, q, w], [y, gradient])


def _load(path: Path) -> ctypes.CDLL:
    library = ctypes.CDLL(str(path))
    long_ = ctypes.c_long
    library.fg_angle_rows.argtypes = [long_, long_, long_, _double_p, _long_p, _double_p, _double_p, _double_p,
                                      _status_p]  # fmt: skip
    library.fg_angle_gradient_rows.argtypes = [long_, long_, long_, _double_p, _long_p, _double_p, _double_p, _long_p,
                                               _double_p, _double_p, _status_p]  # fmt: skip
    return library


_KERNELS: dict[str, AngleKernel | None] = {}


def compile_kernel(key: str, chain: Chain, n_perturbed: int, n_fixed: int) -> AngleKernel | None:
    """The compiled kernel of ``chain`` (memoised per process under ``key``, a digest of
    what the chain is made of: version, angle, markers, subject, calibration), or None
    where it cannot be had (module docstring)."""
    if key in _KERNELS:
        return _KERNELS[key]
    kernel = None
    if compiler() is not None:
        try:
            functions = traced_functions(chain, n_perturbed, n_fixed)
        except TypeError:  # NotTraceable, or numpy refusing an operation on symbols (np.isfinite)
            functions = None
        if functions is not None:
            version = ca.__version__  # type: ignore[attr-defined]  # set at import, absent from casadi's stub
            text = "|".join([version, OPTIMISATION, ROWS_SOURCE.read_text(), *(f.serialize() for f in functions)])
            digest = hashlib.sha256(text.encode()).hexdigest()[:20]
            target = cache_dir() / f"fg_angle_{digest}.so"
            path = target if target.exists() else build_library(
                target, functions, sources=[ROWS_SOURCE], optimisation=OPTIMISATION,
                purpose="a joint-angle model")  # fmt: skip
            if path is not None:
                kernel = AngleKernel(_load(path), n_perturbed + n_fixed, n_perturbed)
    _KERNELS[key] = kernel
    return kernel
