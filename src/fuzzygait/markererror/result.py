"""The fuzzy joint-angle dataset (the result of
:func:`fuzzygait.markererror.analysis.fuzzy_joint_angles`, layout described there): one
builder and the read access every consumer (reports, Rerun recordings, comparisons)
uses, so the layout is defined in this module only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numpy.typing import NDArray

import fuzzygait.core.accessor  # noqa: F401 - registers ``dataset.fuzzy``
from fuzzygait.core.errors import ParameterError
from fuzzygait.core.names import AngleComponent
from fuzzygait.kinematics.labels import component_label


@dataclass(frozen=True)
class AngleAxes:
    """The axes of a fuzzy joint-angle dataset besides its components.

    Attributes:
        alphas: ascending α-levels in [0, 1] (1 included).
        frames: 1-based C3D frame numbers; ``times`` their times in s (one per frame).
        markers: marker labels of the ``marker`` dimension.
        ball_radius: α = 0 ball radius Σ (mm) per marker (finite, ≥ 0).
    """

    alphas: Sequence[float] | NDArray[np.float64]
    frames: Sequence[int] | NDArray[np.int_]
    times: Sequence[float] | NDArray[np.float64]
    markers: Sequence[str]
    ball_radius: Sequence[float] | NDArray[np.float64]

    def __post_init__(self) -> None:
        alphas = np.asarray(self.alphas, dtype=float)
        if alphas.ndim != 1 or alphas.size == 0 or not np.all((alphas >= 0) & (alphas <= 1)) \
                or np.any(np.diff(alphas) <= 0):
            raise ParameterError(f"alphas must be ascending α-levels in [0, 1], at least one; got {list(alphas)}")
        if len(self.times) != len(self.frames):
            raise ParameterError(f"times must have one value per frame ({len(self.frames)}); got {len(self.times)}")
        if len(self.ball_radius) != len(self.markers):
            raise ParameterError(f"ball_radius must have one value per marker ({len(self.markers)}); "
                                 f"got {len(self.ball_radius)}")  # fmt: skip
        radius = np.asarray(self.ball_radius, dtype=float)
        if not np.all(np.isfinite(radius) & (radius >= 0)):
            raise ParameterError(f"ball_radius must be finite and >= 0 mm; got {list(radius)}")


def fuzzy_angles_dataset(
    hulls: Mapping[str, NDArray[np.float64]],
    axes: AngleAxes,
    *,
    deviations: Mapping[str, NDArray[np.float64]] | None = None,
    attrs: Mapping[str, object] | None = None,
    undetermined: Mapping[str, NDArray[np.bool_]] | None = None,
) -> xr.Dataset:
    """Build the dataset.

    Args:
        hulls: component name (``"LKneeAngles_X"``) → hull ``(alpha, bound, frame)`` in
            degrees, bounds ordered lower, upper.
        axes: the α-levels, frames and their times, markers and their ball radii.
        deviations: component → deviation norms ``(alpha, bound, frame, marker)`` in mm
            (NaN for markers the component does not use); None: no ``deviation`` variable.
        attrs: dataset attributes (``units`` is set to ``"deg"``).
        undetermined: component -> ``(alpha, frame)`` True where the band is undetermined;
            None: all False.
    """
    alphas, frames, times, markers, ball_radius = axes.alphas, axes.frames, axes.times, axes.markers, axes.ball_radius
    components = list(hulls)
    parsed = [AngleComponent.parse(c) for c in components]
    shape = (len(components), len(alphas), len(frames))
    flags = np.zeros(shape, dtype=bool) if undetermined is None else np.stack([undetermined[c] for c in components])
    data: dict[str, tuple] = {
        "hull": (("component", "alpha", "bound", "frame"), np.stack([hulls[c] for c in components]),
                 {"units": "deg", "long_name": "joint angle bounds of the α-level (continuous branch)"}),
        "undetermined": (("component", "alpha", "frame"), flags,
                         {"long_name": "band undetermined: a bound more than 90 deg from the measured angle"}),
        "ball_radius": (("marker",), np.asarray(ball_radius, dtype=float),
                        {"units": "mm", "long_name": "marker error ball radius at α = 0"}),
    }  # fmt: skip
    if deviations is not None:
        stacked = np.stack([deviations[c] for c in components])
        data["deviation"] = (("component", "alpha", "bound", "frame", "marker"), stacked,
                             {"units": "mm", "long_name": "marker deviation norm at the bound"})  # fmt: skip
    return xr.Dataset(
        data,
        coords={
            "component": ("component", components, {"long_name": "angle component"}),
            "label": ("component", [component_label(c) for c in components]),
            "angle": ("component", [c.angle for c in parsed]),
            "axis": ("component", [c.axis.value for c in parsed]),
            "alpha": np.asarray(alphas, dtype=float),
            "bound": ["lower", "upper"],
            "frame": np.asarray(frames),
            "time": ("frame", np.asarray(times, dtype=float), {"units": "s"}),
            "marker": list(markers),
        },
        attrs={**dict(attrs or {}), "units": "deg"},
    )


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


def component_undetermined(fuzzy: xr.Dataset, component: str) -> xr.DataArray:
    """Where the band of one component is undetermined, dims ``(alpha, frame)`` (all
    False for datasets written before the flag existed)."""
    _require_layout(fuzzy)
    if "undetermined" not in fuzzy.data_vars:
        hull = component_hull(fuzzy, component)
        return xr.zeros_like(hull.isel(bound=0, drop=True), dtype=bool)
    return fuzzy["undetermined"].sel(component=component, drop=True)


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
