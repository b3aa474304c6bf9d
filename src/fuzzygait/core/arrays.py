"""Arrays that may be traced for reverse-mode derivatives.

The kinematic model (:mod:`fuzzygait.kinematics`) is written with the operations of
``autograd.numpy``, which act on plain numpy arrays exactly as numpy does and, on the
boxed arrays autograd passes through a function it differentiates, record the
operation for the reverse sweep.  The marker-error analysis differentiates joint angles
with respect to marker deviations that way (exact gradients, one reverse sweep for every
deviation at once).  Code on that path must not turn its inputs into plain arrays:
:func:`floats` is ``np.asarray(x, dtype=float)`` for anything but a traced array, which
it leaves as it is.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from autograd.tracer import getval, isbox

__all__ = ["floats", "plain"]


def floats(x: Any) -> np.ndarray:
    """``x`` as a float array: ``np.asarray(x, dtype=float)``, or ``x`` itself when it is
    traced (its values are floats already)."""
    if isbox(x):
        return x
    return np.asarray(x, dtype=float)


def plain(x: Any) -> np.ndarray:
    """The values of ``x`` as a plain float array (a traced array's current values; for
    decisions such as convergence tests, which are not differentiated)."""
    return np.asarray(getval(x), dtype=float)
