"""The fuzzy joint-angle dataset (the result of
:func:`fuzzygait.markererror.analysis.fuzzy_joint_angles`, layout described there): one
builder and the read access every consumer (reports, Rerun recordings, comparisons)
uses, so the layout is defined in this module only; and the whole marker-error result
(:class:`MarkerErrorResult`: the bands, the allowable-error refinement, the per-source
bands and the fuzzy joint moments and powers as up to four datasets, saved as the root and
groups of one file).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr
from numpy.typing import NDArray

import fuzzygait.core.accessor  # noqa: F401 - registers ``dataset.fuzzy``
from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.core.names import AngleComponent
from fuzzygait.kinematics.labels import component_label
from fuzzygait.uncertainty.storage import load_groups, save_groups


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


#: The coordinate, and its dimension, naming the error sources (Table 3.1:
#: ``measurement``, ``placement``, ``sta``) summed into every marker's ball, in order, on
#: the bands and the kinetics (before issue 38 item 2 a comma-joined attribute ``sources``,
#: converted on read: :func:`error_sources`, :func:`fuzzygait.markererror.legacy.upgrade_sources`).
SOURCES_COORD = "error_source"


def with_error_sources(dataset: xr.Dataset, sources: Sequence[str]) -> xr.Dataset:
    """``dataset`` with the coordinate :data:`SOURCES_COORD` (dimension of the same name)
    naming ``sources`` in order (the error sources its marker balls sum).

    Raises:
        ParameterError: no source, or a name that is not a non-empty string.
    """
    names = list(sources)
    if not names or not all(isinstance(n, str) and n for n in names):
        raise ParameterError(f"the error sources must be one or more names; got {names}")
    coordinate = (SOURCES_COORD, names, {"long_name": "error sources summed into each marker's ball (Table 3.1)"})
    return dataset.assign_coords({SOURCES_COORD: coordinate})


def error_sources(dataset: xr.Dataset) -> tuple[str, ...]:
    """The error sources summed into the marker balls of ``dataset`` (the bands, the
    kinetics), in order, e.g. ``("measurement", "placement", "sta")``: the coordinate
    :data:`SOURCES_COORD`, or, for a dataset written before it, its ``sources``
    attribute converted (:func:`fuzzygait.markererror.legacy.upgrade_sources`); empty
    when it names none."""
    if SOURCES_COORD not in dataset.coords:
        from fuzzygait.markererror.legacy import upgrade_sources

        dataset = upgrade_sources(dataset)
    if SOURCES_COORD not in dataset.coords:
        return ()
    return tuple(str(s) for s in dataset[SOURCES_COORD].to_numpy())


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


def _require_component(fuzzy: xr.Dataset, component: str) -> None:
    """Refuse a ``component`` the dataset does not hold (names it and the ones it holds)."""
    held = angle_components(fuzzy)
    if not isinstance(component, str) or component not in held:
        where = f"the dataset of {fuzzy.attrs['trial']}" if "trial" in fuzzy.attrs else "the dataset"
        raise ParameterError(f"component {component!r} is not in {where}; it holds {', '.join(held) or 'none'}")


def component_hull(fuzzy: xr.Dataset, component: str) -> xr.DataArray:
    """Hull of one component in degrees, dims ``(alpha, bound, frame)``.

    Raises:
        ParameterError: ``component`` is not in the dataset.
    """
    _require_component(fuzzy, component)
    return fuzzy["hull"].sel(component=component, drop=True)


def undetermined_flags(fuzzy: xr.Dataset) -> xr.DataArray:
    """Where the band of each component is undetermined, dims ``(component, alpha,
    frame)`` (all False for datasets written before the flag existed)."""
    _require_layout(fuzzy)
    if "undetermined" not in fuzzy.data_vars:
        return xr.zeros_like(fuzzy["hull"].isel(bound=0, drop=True), dtype=bool)
    return fuzzy["undetermined"].astype(bool)


def component_undetermined(fuzzy: xr.Dataset, component: str) -> xr.DataArray:
    """Where the band of one component is undetermined, dims ``(alpha, frame)``
    (:func:`undetermined_flags`).

    Raises:
        ParameterError: ``component`` is not in the dataset.
    """
    _require_component(fuzzy, component)
    return undetermined_flags(fuzzy).sel(component=component, drop=True)


def component_deviation(fuzzy: xr.Dataset, component: str) -> xr.DataArray | None:
    """Norms (mm) of the marker deviations that give each hull value, dims ``(alpha,
    bound, frame, marker)`` (Fig. 5.12); None when the dataset has none.

    Raises:
        ParameterError: ``component`` is not in the dataset.
    """
    _require_component(fuzzy, component)
    if "deviation" not in fuzzy.data_vars:
        return None
    return fuzzy["deviation"].sel(component=component, drop=True)


def ball_radius(fuzzy: xr.Dataset) -> xr.DataArray | None:
    """α = 0 ball radius Σ (mm) per marker, dim ``marker``; None when absent."""
    if "ball_radius" in fuzzy.data_vars and "marker" in fuzzy["ball_radius"].dims:
        return fuzzy["ball_radius"]
    return None


# ---------------------------------------------------------------------------- the result
#: Layout version of a saved marker-error result: 1 = one flat dataset, the refinement and
#: the per-source bands as ``refined_*``/``allowable_*``/``source_*`` variables beside the
#: bands (before issue 38); 2 = the bands at the root, the refinement in the group
#: ``allowable`` and the per-source bands in the group ``sources``, each with its own plain
#: names and dimensions; 3 = version 2 with the error sources as the coordinate
#: :data:`SOURCES_COORD` of the bands (and the kinetics) instead of a comma-joined
#: ``sources`` attribute (so a reader of version 2 refuses it in one line instead of
#: misreading it). :func:`read_marker_result` reads all three.
LAYOUT_VERSION = 3
#: The root attribute naming the layout version (absent in version 1).
LAYOUT_ATTR = "layout_version"
#: The coordinate of the kinetics group giving each component's units (N·m/kg, W/kg).
UNITS_COORD = "units"


@dataclass(frozen=True)
class MarkerErrorResult:
    """The marker-error analysis' result: three datasets, each with plain names.

    Attributes:
        bands: the fuzzy joint angles (:func:`fuzzy_angles_dataset` layout, with the
            coordinate :data:`SOURCES_COORD`, read by :func:`error_sources`; the
            ``dataset.fuzzy`` schema; saved at the root).
        allowable: the allowable-error refinement (group ``allowable``; layout in
            :mod:`fuzzygait.markererror.allowable`), None without one.
        sources: the bands of each error source alone (group ``sources``; layout in
            :mod:`fuzzygait.markererror.per_source`), None without them.
        kinetics: the fuzzy joint moments and powers (group ``kinetics``, optional in
            layout version 2: a file without it reads as before, a reader before it
            ignores it): :func:`~fuzzygait.markererror.fuzzy_kinetics.fuzzy_joint_moments`'
            layout, the moments and powers stacked along ``component`` with coordinate
            ``units (component)`` (``"N·m/kg"``, ``"W/kg"``) and :data:`SOURCES_COORD`
            (:func:`kinetic_part` selects one kind with its units), and the
            allowable-error answer per component
            (``allowable_scale``, ``allowable_failing``, ``allowable_marker_mm``,
            ``allowable_cop_mm``; NaN where not asked; attribute ``kinetic_tolerance``,
            N·m/kg); None without them.
    """

    bands: xr.Dataset
    allowable: xr.Dataset | None = None
    sources: xr.Dataset | None = None
    kinetics: xr.Dataset | None = None

    def __post_init__(self) -> None:
        _require_layout(self.bands)
        if self.kinetics is not None:
            _require_layout(self.kinetics)
            if UNITS_COORD not in self.kinetics.coords:
                raise ParameterError(f"the kinetics group needs the coordinate {UNITS_COORD!r} (per component)")
        known = set(angle_components(self.bands))
        for name, group in (("allowable", self.allowable), ("sources", self.sources)):
            if group is not None and not {str(c) for c in group["component"].to_numpy()} <= known:
                raise ParameterError(f"the {name} group has components the bands do not have")

    def groups(self) -> dict[str, xr.Dataset]:
        """The datasets as saved: ``"/"`` (the bands, with the layout version), then
        ``"/allowable"`` and ``"/sources"`` where present."""
        root = self.bands.copy()
        root.attrs[LAYOUT_ATTR] = LAYOUT_VERSION
        out = {"/": root}
        out.update({f"/{k}": v for k, v in (("allowable", self.allowable), ("sources", self.sources),
                                            ("kinetics", self.kinetics)) if v is not None})  # fmt: skip
        return out

    def parts(self) -> dict[str, xr.Dataset]:
        """Every part in the fuzzy-result schema (for
        :func:`fuzzygait.testing.check_result`): the bands, the per-source bands and, per
        refined component, its plain and refined levels merged along ``alpha``, and the
        fuzzy moments and powers each in its units (``/kinetics/N·m/kg`` ...)."""
        from fuzzygait.markererror.allowable import refined_components, refined_levels

        out = {"/": self.bands}
        if self.sources is not None:
            out["/sources"] = self.sources
        if self.kinetics is not None:
            for units in dict.fromkeys(str(u) for u in self.kinetics[UNITS_COORD].to_numpy()):
                out[f"/kinetics/{units}"] = kinetic_part(self.kinetics, units)
        for component in refined_components(self):
            out[f"/allowable/{component}"] = refined_levels(self, component).assign_attrs(units="deg")
        return out


def save_marker_result(result: MarkerErrorResult, path: str | os.PathLike[str]) -> Path:
    """Write ``result`` to ``path`` (.nc or .zarr) as groups (:data:`LAYOUT_VERSION`),
    atomically (:func:`fuzzygait.uncertainty.storage.save_groups`)."""
    return save_groups(result.groups(), path)


def read_marker_result(path: str | os.PathLike[str]) -> MarkerErrorResult:
    """Read a result written by :func:`save_marker_result`, or a version-1 file (one flat
    dataset, converted: :func:`fuzzygait.markererror.legacy.from_flat`); the bands and
    kinetics of a file written before the coordinate :data:`SOURCES_COORD` get it from
    their ``sources`` attribute (:func:`~fuzzygait.markererror.legacy.upgrade_sources`).

    Raises:
        FuzzyGaitError: a file of a newer layout version, or not a marker-error result.
    """
    groups = load_groups(path)
    root = groups["/"]
    version = int(root.attrs.get(LAYOUT_ATTR, 1))
    if version > LAYOUT_VERSION:
        raise FuzzyGaitError(f"{path}: marker-error result layout version {version}; this fuzzygait reads "
                             f"versions 1 to {LAYOUT_VERSION}: update fuzzygait to read it")  # fmt: skip
    if version == 1:
        from fuzzygait.markererror.legacy import from_flat

        return from_flat(root)
    from fuzzygait.markererror.legacy import upgrade_sources

    root.attrs.pop(LAYOUT_ATTR)
    kinetics = groups.get("/kinetics")
    return MarkerErrorResult(upgrade_sources(root), groups.get("/allowable"), groups.get("/sources"),
                             None if kinetics is None else upgrade_sources(kinetics))  # fmt: skip


def kinetic_part(kinetics: xr.Dataset, units: str) -> xr.Dataset:
    """The components of a kinetics group (:attr:`MarkerErrorResult.kinetics`) in
    ``units`` (``"N·m/kg"``: the moments, ``"W/kg"``: the powers) as one fuzzy result
    whose hull states those units (``part.fuzzy.units``).

    Raises:
        ParameterError: no component is in ``units``.
    """
    _require_layout(kinetics)
    chosen = kinetics[UNITS_COORD].to_numpy().astype(str) == units
    if not chosen.any():
        raise ParameterError(f"the kinetics hold no component in {units!r}; they hold "
                             f"{', '.join(dict.fromkeys(kinetics[UNITS_COORD].to_numpy().astype(str)))}")  # fmt: skip
    part = kinetics.isel(component=np.flatnonzero(chosen))
    part["hull"] = part["hull"].assign_attrs(units=units)
    return part.assign_attrs(units=units)
