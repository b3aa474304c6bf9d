"""``dataset.fuzzy``: one way to read every fuzzy result the package makes.

Every fuzzy result holds ``hull (..., alpha, bound, AXIS)``: the lower and upper bound of
an output at each α-level (ascending, α = 1 the deterministic or measured value), over
``AXIS`` — ``time`` (the Graph Follower's results, s) or ``frame`` (the marker-error
analysis' joint angles, with ``time`` as a coordinate on it) — with optional leading
dimensions that stack several results (``component`` for angle components, ``sample``
for the FRV-GFA's samples, ``source`` for the marker-error analysis' bands of each error
source alone). The accessor answers the questions a reader asks of any of
them in the result's own units::

    import fuzzygait.core.schema  # registers the accessor (every result-making module does)
    ds.fuzzy.band(0.5, component="LKneeAngles_X")    # (bound, frame), degrees
    ds.fuzzy.width()                                  # upper - lower, (..., alpha, frame)
    ds.fuzzy.undetermined(0.0)                        # bool (..., frame); all False if never
    ds.fuzzy.delta_phi()                              # ΔΦ of Eq. 5.3 in %, (..., alpha < 1)
    ds.fuzzy.problems()                               # what keeps ds from the schema ([] if none)

Selections by ``component`` take a label (``"LKneeAngles_X"``) or a
:class:`~fuzzygait.core.names.AngleComponent`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent

#: The dimensions a hull may run along.
AXES = ("time", "frame")
#: Leading dimensions that stack results.
STACKING = ("source", "component", "sample")
BOUND_NAMES = ("lower", "upper")


@xr.register_dataset_accessor("fuzzy")
class FuzzyAccessor:
    """The ``fuzzy`` accessor of a fuzzy-result :class:`xarray.Dataset` (module docstring)."""

    def __init__(self, dataset: xr.Dataset) -> None:
        self._ds = dataset

    # -- layout ---------------------------------------------------------------------------
    def problems(self) -> list[str]:
        """What keeps the dataset from the fuzzy-result schema (empty when it keeps it)."""
        ds = self._ds
        if "hull" not in ds.data_vars:
            return ["variable 'hull' missing"]
        dims = ds["hull"].dims
        problems = []
        if len(dims) < 3 or dims[-3:-1] != ("alpha", "bound") or dims[-1] not in AXES:
            problems.append(f"hull has dims {dims}, expected (..., alpha, bound, time|frame)")
        elif any(d not in STACKING for d in dims[:-3]):
            problems.append(f"hull's leading dims {dims[:-3]} are not among {STACKING}")
        if "bound" in ds.coords and [str(b) for b in ds["bound"].values] != list(BOUND_NAMES):
            problems.append(f"bound must be {list(BOUND_NAMES)}")
        if "alpha" in ds.coords:
            alphas = np.asarray(ds["alpha"].values, dtype=float)
            if alphas.size == 0 or np.any(np.diff(alphas) <= 0) or alphas[0] < 0 or alphas[-1] != 1.0:
                problems.append(f"alpha must ascend within [0, 1] and end at 1; got {alphas.tolist()}")
        else:
            problems.append("coordinate 'alpha' missing")
        if "undetermined" in ds.data_vars and ds["undetermined"].dtype != bool:
            problems.append("undetermined must be boolean")
        if "units" not in ds["hull"].attrs and "units" not in ds.attrs:
            problems.append("the hull's units are not stated (attribute 'units')")
        return problems

    def _require(self) -> None:
        problems = self.problems()
        if problems:
            name = self._ds.attrs.get("trial") or self._ds.attrs.get("output") or "the dataset"
            raise ParameterError(f"{name} is not a fuzzy result: {'; '.join(problems)}")

    @property
    def axis(self) -> str:
        """The dimension the hull runs along: ``"time"`` or ``"frame"``."""
        self._require()
        return str(self._ds["hull"].dims[-1])

    @property
    def units(self) -> str:
        """The hull's units (``"deg"``, ``"J"``, ...)."""
        return str(self._ds["hull"].attrs.get("units", self._ds.attrs.get("units", "")))

    @property
    def alphas(self) -> np.ndarray:
        """The α-levels, ascending (the last is 1)."""
        self._require()
        return np.asarray(self._ds["alpha"].values, dtype=float)

    @property
    def components(self) -> list[AngleComponent]:
        """The angle components of a stacked result, in order (empty when not stacked by
        component)."""
        if "component" not in self._ds.dims:
            return []
        return [AngleComponent.parse(str(c)) for c in self._ds["component"].values]

    def _select(self, data: xr.DataArray, component: str | AngleComponent | None) -> xr.DataArray:
        if component is None:
            return data
        if "component" not in data.dims:
            raise ParameterError("component= is only for results stacked by component (angle components)")
        label = component.label if isinstance(component, AngleComponent) else AngleComponent.parse(component).label
        if label not in {str(c) for c in self._ds["component"].values}:
            raise ParameterError(f"{label} is not among the result's components; it has "
                                 f"{', '.join(str(c) for c in self._ds['component'].values)}")  # fmt: skip
        return data.sel(component=label, drop=True)

    # -- reading --------------------------------------------------------------------------
    def hull(self, component: str | AngleComponent | None = None) -> xr.DataArray:
        """``hull (..., alpha, bound, axis)`` (of one component), in :attr:`units`."""
        self._require()
        return self._select(self._ds["hull"], component)

    def _require_alpha(self, alpha: float) -> None:
        """Refuse an ``alpha`` that is not one of the result's α-levels (names it and them)."""
        if not np.any(np.isclose(self.alphas, alpha, rtol=0.0, atol=1e-12)):
            raise ParameterError(f"α = {alpha:g} is not among the result's α-levels {self.alphas.tolist()}")

    def band(self, alpha: float, component: str | AngleComponent | None = None) -> xr.DataArray:
        """The band at ``alpha``: ``(..., bound, axis)``."""
        hull = self.hull(component)
        self._require_alpha(alpha)
        return hull.sel(alpha=alpha, method="nearest", tolerance=1e-12)

    def measured(self, component: str | AngleComponent | None = None) -> xr.DataArray:
        """The α = 1 value (the deterministic run, the measured angle): ``(..., axis)``."""
        return self.band(1.0, component).sel(bound="upper", drop=True)

    def width(self, alpha: float | None = None, component: str | AngleComponent | None = None) -> xr.DataArray:
        """Upper minus lower bound: ``(..., alpha, axis)``, or ``(..., axis)`` at ``alpha``."""
        hull = self.hull(component) if alpha is None else self.band(alpha, component)
        return hull.sel(bound="upper", drop=True) - hull.sel(bound="lower", drop=True)

    def undetermined(self, alpha: float | None = None,
                     component: str | AngleComponent | None = None) -> xr.DataArray:  # fmt: skip
        """Where a band is undetermined (a segment frame can flip; the marker-error
        analysis): bool ``(..., alpha, axis)`` or ``(..., axis)`` at ``alpha``; all False
        for results that have no such flag."""
        hull = self.hull(component)
        if "undetermined" in self._ds.data_vars:
            flags = self._select(self._ds["undetermined"], component)
        else:
            flags = xr.zeros_like(hull.isel(bound=0, drop=True), dtype=bool)
        if alpha is None:
            return flags
        self._require_alpha(alpha)
        return flags.sel(alpha=alpha, method="nearest", tolerance=1e-12)

    def delta_phi(self, component: str | AngleComponent | None = None) -> xr.DataArray:
        """ΔΦ of thesis Eq. 5.3 in %: the widest band over the axis where it is determined,
        relative to the largest magnitude of the α = 1 value, for each α < 1:
        ``(..., alpha)``. NaN where the α = 1 value is 0 throughout or no frame is
        determined."""
        width = self.width(component=component).where(~self.undetermined(component=component))
        widest = width.max(self.axis, skipna=True)
        reference = abs(self.measured(component)).max(self.axis, skipna=True)
        ratio = 100.0 * widest / reference.where(reference > 0)
        ratio = ratio.sel(alpha=self.alphas[self.alphas < 1.0])
        ratio.attrs = {"units": "%", "long_name": "relative envelope width ΔΦ (Eq. 5.3)"}
        return ratio


__all__ = ["AXES", "BOUND_NAMES", "STACKING", "FuzzyAccessor"]
