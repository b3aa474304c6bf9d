"""Read access to a fuzzy joint-angle dataset (the result of
:func:`fuzzygait.markererror.analysis.fuzzy_joint_angles`; layout in that module).

Every consumer (reports, Rerun recordings, comparisons) reads the dataset through these
functions, so its layout is defined in one place.
"""

from __future__ import annotations

import xarray as xr

from fuzzygait.core.errors import ParameterError


def _require_layout(fuzzy: xr.Dataset) -> None:
    if "component" not in fuzzy.dims or "hull" not in fuzzy.data_vars:
        name = fuzzy.attrs.get("trial", "the dataset")
        raise ParameterError(
            f"{name} is not a fuzzy joint-angle result (no 'hull' over a 'component' dimension); "
            "compute it with fuzzygait uncertainty or fuzzy_joint_angles"
        )


def angle_components(fuzzy: xr.Dataset) -> list[str]:
    """Names of the angle components, e.g. ``["LKneeAngles_X", …]``, in dataset order."""
    _require_layout(fuzzy)
    return [str(c) for c in fuzzy["component"].values]


def component_hull(fuzzy: xr.Dataset, component: str) -> xr.DataArray:
    """Hull of one component in degrees, dims ``(alpha, bound, frame)``."""
    _require_layout(fuzzy)
    return fuzzy["hull"].sel(component=component, drop=True)


def component_deviation(fuzzy: xr.Dataset, component: str) -> xr.DataArray | None:
    """Norms (mm) of the marker deviations that give each hull value, dims ``(alpha,
    bound, frame, marker)`` (Fig. 5.12); None when the dataset has none."""
    _require_layout(fuzzy)
    if "deviation" not in fuzzy.data_vars:
        return None
    return fuzzy["deviation"].sel(component=component, drop=True)


def ball_radius(fuzzy: xr.Dataset) -> xr.DataArray | None:
    """α = 0 ball radius Σ (mm) per marker, dim ``marker``; None when absent."""
    if "ball_radius" in fuzzy.data_vars and "marker" in fuzzy["ball_radius"].dims:
        return fuzzy["ball_radius"]
    return None
