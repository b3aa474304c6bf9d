"""Marker-error results of layout version 1 (before issue 38): one flat dataset with the
allowable-error refinement and the per-source bands as prefixed variables beside the
bands (``refined_*``, ``allowable_*``, ``segment_radius``; ``source_*`` over the dims
``source``, ``source_component`` and ``source_alpha``; a comma-joined ``source_alphas``
attribute). :func:`from_flat` turns one into a :class:`MarkerErrorResult` (layout
version 2), the numbers unchanged; :data:`ALLOWABLE_NAMES` and :data:`SOURCE_NAMES` are
the mapping (also what ``benchmarks/compare_outputs.py`` maps an older revision's file
with). The bands and kinetics of files written before issue 38 item 2 (version 1 and
early version 2) name their error sources in a comma-joined attribute ``sources``:
:func:`upgrade_sources` turns it into the coordinate
:data:`~fuzzygait.markererror.result.SOURCES_COORD`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from fuzzygait.core.errors import ParameterError
from fuzzygait.markererror.result import SOURCES_COORD, MarkerErrorResult, with_error_sources
from fuzzygait.markererror.sources import parse_sources

__all__ = ["ALLOWABLE_ATTRS", "ALLOWABLE_NAMES", "SOURCES_ATTR", "SOURCE_ATTRS", "SOURCE_DIMS", "SOURCE_NAMES",
           "from_flat", "upgrade_sources"]  # fmt: skip

#: Version-1 variable -> its name in the group ``allowable`` (``allowable_alpha``, which
#: is ``1 − allowable_scale``, is dropped: the table computes it).
ALLOWABLE_NAMES = {
    "refined_alpha": "alpha", "refined_hull": "hull", "refined_undetermined": "undetermined",
    "refined_deviation": "deviation", "allowable_scale": "scale", "allowable_mm": "mm",
    "allowable_failing_scale": "failing_scale", "allowable_excursion": "excursion",
    "allowable_evaluations": "evaluations", "allowable_status": "status", "segment_radius": "segment_radius",
}  # fmt: skip
#: Version-1 bands attribute -> its name on the group ``allowable``.
ALLOWABLE_ATTRS = {
    "tolerance_deg": "tolerance_deg", "allowable_resolution_mm": "resolution_mm", "allowable_source": "source",
    "allowable_seconds": "seconds", "allowable_runs": "runs", "allowable_node_evaluations": "node_evaluations",
}  # fmt: skip
#: Version-1 variable -> its name in the group ``sources``.
SOURCE_NAMES = {"source_hull": "hull", "source_undetermined": "undetermined", "source_ball_radius": "ball_radius"}
#: Version-1 dimension -> its name in the group ``sources``.
SOURCE_DIMS = {"source_component": "component", "source_alpha": "alpha"}
#: Version-1 bands attribute -> its name on the group ``sources`` (``source_alphas`` is
#: dropped: the α-levels are the coordinate ``alpha``).
SOURCE_ATTRS = {
    "source_seconds": "seconds", "source_runs": "runs", "source_forward_simulations": "forward_simulations",
    "source_node_evaluations": "node_evaluations", "source_nesting_excess_deg": "nesting_excess_deg",
}  # fmt: skip
#: The attribute that named the error sources, comma-joined, before the coordinate
#: :data:`~fuzzygait.markererror.result.SOURCES_COORD` (on the bands and the kinetics).
SOURCES_ATTR = "sources"
_DROPPED = ("allowable_alpha", "source_alphas")
_SHARED = ("bound", "frame", "time", "marker")


def _group(flat: xr.Dataset, names: dict[str, str], attrs: dict[str, str], dims: dict[str, str],
           shared: tuple[str, ...]) -> xr.Dataset | None:  # fmt: skip
    """The variables ``names`` of ``flat`` renamed, with the coordinates of their dims
    (and ``shared`` ones such as ``time`` along them), the dims ``dims`` renamed."""
    present = [n for n in names if n in flat.data_vars]
    if not present:
        return None
    used = {d for n in present for d in flat[n].dims}
    group = flat[present].rename({n: names[n] for n in present})
    group = group.drop_vars([c for c in group.coords if not set(group[c].dims) <= used or c not in {*used, *shared}])
    group = group.rename({d: new for d, new in dims.items() if d in group.dims})
    group.attrs = {new: flat.attrs[old] for old, new in attrs.items() if old in flat.attrs}
    return group


def from_flat(flat: xr.Dataset) -> MarkerErrorResult:
    """A version-1 dataset as a :class:`MarkerErrorResult`: the bands without the prefixed
    variables and their attributes, the refinement and the per-source bands as datasets
    with plain names (module docstring); every number as stored."""
    allowable = _group(flat, ALLOWABLE_NAMES, ALLOWABLE_ATTRS, {}, _SHARED)
    sources = _group(flat, SOURCE_NAMES, SOURCE_ATTRS, SOURCE_DIMS, _SHARED)
    if sources is not None:
        sources.attrs = {**sources.attrs, "units": "deg"}
    moved = [n for n in (*ALLOWABLE_NAMES, *SOURCE_NAMES, "allowable_alpha") if n in flat.data_vars]
    bands = flat.drop_vars(moved)
    bands = bands.drop_dims([d for d in ("refinement", "segment", "source", *SOURCE_DIMS) if d in bands.dims])
    bands.attrs = {k: v for k, v in flat.attrs.items() if k not in {*ALLOWABLE_ATTRS, *SOURCE_ATTRS, *_DROPPED}}
    return MarkerErrorResult(upgrade_sources(bands), allowable, sources)


def upgrade_sources(dataset: xr.Dataset) -> xr.Dataset:
    """``dataset`` (bands or kinetics) with its old :data:`SOURCES_ATTR` attribute
    (``"measurement,placement,sta"``) as the coordinate
    :data:`~fuzzygait.markererror.result.SOURCES_COORD` and the attribute dropped;
    ``dataset`` itself when it has the coordinate or no such attribute.

    Raises:
        ParameterError: the attribute names no known error source.
    """
    old = dataset.attrs.get(SOURCES_ATTR)
    if SOURCES_COORD in dataset.coords or old is None:
        return dataset
    try:
        names = parse_sources(str(old) if isinstance(old, str) else [str(n) for n in np.atleast_1d(old)])
    except ParameterError as error:
        trial = dataset.attrs.get("trial", "the dataset")
        raise ParameterError(f"{trial}: its attribute {SOURCES_ATTR!r} = {old!r}: {error}") from None
    upgraded = with_error_sources(dataset, names)
    upgraded.attrs = {k: v for k, v in dataset.attrs.items() if k != SOURCES_ATTR}
    return upgraded
