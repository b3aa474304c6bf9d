"""Arrays that may be traced for reverse-mode derivatives.

The kinematic model (:mod:`fuzzygait.kinematics`) is written with the operations of
``autograd.numpy``, which act on plain numpy arrays exactly as numpy does and, on the
boxed arrays autograd passes through a function it differentiates, record the
operation for the reverse sweep.  The marker-error analysis differentiates joint angles
with respect to marker deviations that way (exact gradients, one reverse sweep for every
deviation at once).  Code on that path must not turn its inputs into plain arrays:
:func:`floats` is ``np.asarray(x, dtype=float)`` for anything but a traced array, which
it leaves as it is.

Indexing a traced array with basic indices (integers, slices, ``None``, ``...``; e.g. a
marker's column of the positions) has a reverse sweep that adds the gradient into a
zero array at the indexed place.  autograd does that with ``numpy.add.at`` whatever the
index, which is made for repeated fancy indices and is slow; a basic index cannot
repeat an element, so here it is an in-place ``+=`` of the view (the same numbers).
Measured on the joint-angle gradients of the marker-error analysis
(``benchmarks/RESULTS.md``, issue 40): ``add.at`` was about a quarter of the CPU of a
knee angle's gradients.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from autograd.extend import SparseObject, defvjp, primitive, vspace
from autograd.numpy.numpy_boxes import ArrayBox
from autograd.numpy.numpy_vjps import untake
from autograd.tracer import getval, isbox

__all__ = ["each", "floats", "plain", "signs", "symbolic", "undefined_above"]


def symbolic(x: Any) -> bool:
    """True for a symbolic array: numpy's ``object`` array of symbols, which the kinematic
    model is traced with to compile it (:mod:`fuzzygait.markererror.symbols`)."""
    return isinstance(x, np.ndarray) and x.dtype == object


def floats(x: Any) -> np.ndarray:
    """``x`` as a float array: ``np.asarray(x, dtype=float)``, or ``x`` itself when it is
    traced (its values are floats already) or symbolic (:func:`symbolic`)."""
    if isbox(x) or symbolic(x):
        return x
    return np.asarray(x, dtype=float)


def plain(x: Any) -> np.ndarray:
    """The values of ``x`` as a plain float array (a traced array's current values; for
    decisions such as convergence tests, which are not differentiated); a symbolic array
    stays itself (a decision on it then refuses, :mod:`fuzzygait.markererror.symbols`)."""
    if symbolic(x):
        return x
    return np.asarray(getval(x), dtype=float)


def each(x: np.ndarray, method: str, *args: Any) -> np.ndarray:
    """Of a symbolic array, each element's own ``method(*args)``, in an array of its shape
    (where numpy's object loop would compare symbols or has no such loop)."""
    return np.array([getattr(e, method)(*args) for e in x.ravel()], dtype=object).reshape(x.shape)


def signs(x: Any) -> np.ndarray:
    """``np.sign`` of plain values (:func:`plain`: not differentiated); of a symbolic
    array, each symbol's own ``sign()``."""
    values = plain(x)
    return each(values, "sign") if symbolic(values) else np.sign(values)


def undefined_above(x: np.ndarray, limit: float) -> np.ndarray:
    """0 where ``x <= limit``, NaN elsewhere (and where ``x`` is NaN): added to a result,
    it marks the rows a fixed-step computation has not settled.  Of a symbolic array, each
    symbol's own ``undefined_above(limit)``."""
    if symbolic(x):
        return each(x, "undefined_above", limit)
    with np.errstate(invalid="ignore"):
        return np.where(np.asarray(x) <= limit, 0.0, np.nan)


def _basic(index: Any) -> bool:
    """True for a basic index: no element can be selected twice."""
    parts = index if isinstance(index, tuple) else (index,)
    return all(isinstance(p, int | slice | type(None) | type(Ellipsis)) and not isinstance(p, bool) for p in parts)


@primitive
def _untake_basic(x: Any, index: Any, space: Any) -> SparseObject:
    """The reverse sweep of ``A[index]`` for a basic ``index``: ``x`` added at ``index``
    of a zero array of ``A``'s space."""

    def add(out: np.ndarray) -> np.ndarray:
        out[index] += x
        return out

    return SparseObject(space, add)


defvjp(_untake_basic, lambda ans, x, index, _space: lambda g: g[index])
defvjp(ArrayBox.__getitem__,
       lambda ans, A, index: lambda g: (_untake_basic if _basic(index) else untake)(g, index, vspace(A)))  # fmt: skip
