"""Properties of a homogeneous rectangular beam cross-section.

The cross-section lies in the plane of the directors d1 (width ``b``, lateral) and d2
(height ``a``, thickness direction); d3 is the beam tangent (thesis Section 4.2.1, the
stiffness matrices ``D^Γ = diag(GA, GA, EA)`` and ``D^K = diag(EI_1, EI_2, GJ)``).  The
layered (face–core–face) case is in :mod:`fuzzygait.mechanics.homogenisation`.
All lengths in m, areas in m², second moments in m⁴.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzygait.core.errors import ParameterError

#: Timoshenko shear correction factor of a rectangle, κ = 5/6 (the classical value from
#: the parabolic shear-stress distribution).  Cowper (1966) gives the Poisson-dependent
#: κ = 10(1 + ν)/(12 + 11ν) (0.85 for ν = 0.265); we use 5/6, independent of ν.
SHEAR_CORRECTION_RECTANGLE = 5.0 / 6.0

#: Number of terms of the Saint-Venant torsion series (odd n = 1, 3, ..., 99).
TORSION_SERIES_TERMS = 50


def rectangle_torsion_constant(long: np.ndarray, short: np.ndarray) -> np.ndarray:
    """Saint-Venant torsion constant ``J`` (m⁴) of a solid rectangle ``long ≥ short``.

    ``J = long · short³ · [1/3 − (64/π⁵)(short/long) Σ tanh(nπ·long/(2·short))/n⁵]``,
    summed over odd ``n`` with :data:`TORSION_SERIES_TERMS` terms (Timoshenko & Goodier,
    Theory of Elasticity).
    """
    long = np.asarray(long, dtype=float)
    short = np.asarray(short, dtype=float)
    n = 2.0 * np.arange(TORSION_SERIES_TERMS) + 1.0
    ratio = (long / short)[..., None]
    series = np.sum(np.tanh(n * math.pi * ratio / 2.0) / n**5, axis=-1)
    k1 = 1.0 / 3.0 - 64.0 / math.pi**5 * (short / long) * series
    return k1 * long * short**3


@dataclass(frozen=True, eq=False)
class RectangleSection:
    """Solid rectangle ``b × a``; scalars or arrays (one value per element).

    Attributes:
        width: ``b`` (m), the side along d1 (lateral).
        height: ``a`` (m), the side along d2 (thickness direction).
    """

    width: np.ndarray
    height: np.ndarray

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = np.array(getattr(self, name), dtype=float)
            if not np.all(np.isfinite(value)) or np.any(value <= 0):
                raise ParameterError(f"RectangleSection: {name} must be finite and > 0 m")
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        try:
            np.broadcast_shapes(self.width.shape, self.height.shape)
        except ValueError:
            raise ParameterError(
                f"RectangleSection: width {self.width.shape} and height {self.height.shape} "
                "must have the same shape (one value per element)"
            ) from None

    @property
    def area(self) -> np.ndarray:
        """``A = b a`` (m²)."""
        return self.width * self.height

    @property
    def second_moment_1(self) -> np.ndarray:
        """``I_1 = ∫ x2² dA = b a³ / 12`` (m⁴): bending about d1, i.e. in the d2–d3
        plane (the blade's sagittal, soft bending mode)."""
        return self.width * self.height**3 / 12.0

    @property
    def second_moment_2(self) -> np.ndarray:
        """``I_2 = ∫ x1² dA = a b³ / 12`` (m⁴): bending about d2."""
        return self.height * self.width**3 / 12.0

    @property
    def polar_moment(self) -> np.ndarray:
        """``I_1 + I_2`` (m⁴); not the torsion constant of a rectangle (see below)."""
        return self.second_moment_1 + self.second_moment_2

    @property
    def torsion_constant(self) -> np.ndarray:
        """Saint-Venant torsion constant ``J`` (m⁴), for either aspect ratio."""
        long = np.maximum(self.width, self.height)
        short = np.minimum(self.width, self.height)
        return rectangle_torsion_constant(long, short)
