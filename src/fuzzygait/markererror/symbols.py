"""Symbolic scalars to trace the kinematic model once and compile it (:mod:`.row_kernel`).

The kinematic chain is written with numpy operations on ``(rows, 3)`` arrays.  Called
with numpy ``object`` arrays whose elements are :class:`Symbol` (a CasADi ``SX``
expression), the same code builds the expression graph of one row instead of numbers:
numpy applies an operation on an object array element by element, calling the element's
operator (``a + b``) or its method of the ufunc's name (``np.arctan2(a, b)`` calls
``a.arctan2(b)``).  :func:`fuzzygait.core.arrays.floats` and ``plain`` pass such arrays
through.

A decision on the *values* — a comparison, ``bool``, ``float`` — has no answer for a
symbol: it raises :class:`NotTraceable`, so a model whose chain branches on its data (the
cluster fits' visibility masks, an iteration to convergence) is never compiled with a
branch taken for one row and wrong for another; it runs on numpy instead.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

import casadi as ca
import numpy as np


class NotTraceable(TypeError):
    """The traced code took a decision on a symbolic value."""


def _sx(value: Any) -> ca.SX:
    if isinstance(value, Symbol):
        return value.sx
    if isinstance(value, int | float | np.floating | np.integer):
        return ca.SX(float(value))
    raise NotTraceable(f"cannot combine a symbol with {type(value).__name__}")


def _binary(operation: Any, reflected: bool = False) -> Any:
    """A Symbol operator: with an array the array's own (element by element), else
    ``operation`` on the two expressions."""

    def apply(self: Symbol, other: Any) -> Any:
        if isinstance(other, np.ndarray):
            return NotImplemented
        a, b = (_sx(other), self.sx) if reflected else (self.sx, _sx(other))
        return Symbol(operation(a, b))

    return apply


def _unary(operation: Any) -> Any:
    """A Symbol method applying ``operation`` to its expression."""

    def apply(self: Symbol) -> Symbol:
        return Symbol(operation(self.sx))

    return apply


class Symbol:
    """One scalar of a traced computation: a CasADi ``SX`` expression with the operators
    and numpy ufunc methods the kinematic chain uses."""

    __slots__ = ("sx",)

    def __init__(self, sx: ca.SX) -> None:
        self.sx = sx

    # arithmetic (an array on the other side applies the operation element by element)
    __add__ = _binary(lambda a, b: a + b)
    __radd__ = _binary(lambda a, b: a + b, reflected=True)
    __sub__ = _binary(lambda a, b: a - b)
    __rsub__ = _binary(lambda a, b: a - b, reflected=True)
    __mul__ = _binary(lambda a, b: a * b)
    __rmul__ = _binary(lambda a, b: a * b, reflected=True)
    __truediv__ = _binary(lambda a, b: a / b)
    __rtruediv__ = _binary(lambda a, b: a / b, reflected=True)

    def __pow__(self, other: Any) -> Symbol:
        if isinstance(other, int | float) and other == 2:
            return Symbol(self.sx * self.sx)
        return Symbol(self.sx ** _sx(other))

    def __neg__(self) -> Symbol:
        return Symbol(-self.sx)

    def __pos__(self) -> Symbol:
        return self

    def __mod__(self, other: Any) -> Symbol:
        """Python's (and numpy's) modulo: the result has the divisor's sign."""
        divisor = _sx(other)
        return Symbol(self.sx - divisor * ca.floor(self.sx / divisor))

    # numpy ufunc methods (``np.sqrt(array)`` calls ``element.sqrt()``)
    sqrt = _unary(ca.sqrt)
    square = _unary(lambda x: x * x)
    sin, cos, tan = _unary(ca.sin), _unary(ca.cos), _unary(ca.tan)
    arcsin, arccos, arctan = _unary(ca.asin), _unary(ca.acos), _unary(ca.atan)
    arctan2 = _binary(ca.atan2)
    degrees = _unary(lambda x: x * (180.0 / math.pi))
    radians = _unary(lambda x: x * (math.pi / 180.0))
    sign = _unary(ca.sign)

    def capped_arcsin(self) -> Symbol:
        """``arcsin`` of the value clipped to [-1, 1]; NaN stays NaN."""
        x = self.sx
        return Symbol(ca.asin(ca.if_else(x > 1.0, 1.0, ca.if_else(x < -1.0, -1.0, x))))

    def undefined_above(self, limit: float) -> Symbol:
        """0 where the value is at most ``limit``, NaN above it (and for NaN)."""
        return Symbol(ca.if_else(self.sx <= limit, 0.0, math.nan))

    # decisions: no answer for a symbol
    def _refuse(self, *_: Any) -> Any:
        raise NotTraceable("the traced code decides on a symbolic value")

    __bool__ = __float__ = __int__ = __index__ = _refuse
    __lt__ = __le__ = __gt__ = __ge__ = __eq__ = __ne__ = _refuse
    __hash__ = None  # type: ignore[assignment]  # unhashable, as its equality refuses


def symbol_array(sx: ca.SX, shape: tuple[int, ...]) -> np.ndarray:
    """The elements of the column ``sx`` as an object array of :class:`Symbol` of ``shape``
    (C order)."""
    count = int(np.prod(shape))
    if sx.numel() != count:
        raise ValueError(f"{sx.numel()} symbols for shape {shape}")
    array = np.empty(count, dtype=object)
    for i in range(count):
        array[i] = Symbol(sx[i])
    return array.reshape(shape)


def expressions(values: Iterable[Any]) -> ca.SX:
    """The column of the expressions of ``values`` (symbols or numbers)."""
    return ca.vertcat(*[_sx(v) for v in values])
