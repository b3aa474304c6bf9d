"""Marker error sources and the α = 0 ball radius of every marker (thesis §3.7, Table 3.1).

Each marker's true position lies in a ball around its measured position; the radius is a
triangular fuzzy number whose support is the marker's cumulative error Σ: the sum of the
selected sources' maximum deviations for the marker's segment (mm):

============  ===========  =========  ====================  =====
segment       measurement  placement  soft-tissue artefact  Σ
============  ===========  =========  ====================  =====
pelvis        2            15         15                    32
thigh         2            10         20                    32
shank         2            8          20                    30
ankle         2            8          10                    20
foot          2            5          0                     7
============  ===========  =========  ====================  =====

Markers on a joint take the values of the joint's proximal limb (thesis: KNE is a thigh
marker, ANK has its own "ankle" row). Values can be overridden per segment or per marker
in a TOML file::

    [segments.thigh]            # replaces the thigh row (any of the three sources)
    placement = 12.0
    [markers.LKNE]              # one marker: a fixed total radius, or per source
    radius = 25.0
    [markers.RKNE]
    sta = 15.0
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from numbers import Real
from pathlib import Path

from fuzzygait.core.errors import ParameterError
from fuzzygait.io.tomlfile import load_toml

SOURCES = ("measurement", "placement", "sta")
SOURCE_TITLES = {
    "measurement": "measurement system",
    "placement": "marker placement",
    "sta": "soft-tissue artefact",
}

#: Table 3.1, "used" columns (mm).
TABLE_3_1: dict[str, dict[str, float]] = {
    "pelvis": {"measurement": 2.0, "placement": 15.0, "sta": 15.0},
    "thigh": {"measurement": 2.0, "placement": 10.0, "sta": 20.0},
    "shank": {"measurement": 2.0, "placement": 8.0, "sta": 20.0},
    "ankle": {"measurement": 2.0, "placement": 8.0, "sta": 10.0},
    "foot": {"measurement": 2.0, "placement": 5.0, "sta": 0.0},
}

#: Plug-in Gait / CGM marker (without side letter) -> segment of Table 3.1.
MARKER_SEGMENTS: dict[str, str] = {
    "ASI": "pelvis", "PSI": "pelvis", "SACR": "pelvis",
    "THI": "thigh", "THAP": "thigh", "THAD": "thigh", "KNE": "thigh", "KNM": "thigh",
    "TIB": "shank", "TIAP": "shank", "TIAD": "shank",
    "ANK": "ankle", "MED": "ankle",
    "HEE": "foot", "TOE": "foot", "VMH": "foot", "FMH": "foot", "SMH": "foot",
}  # fmt: skip


def marker_segment(label: str) -> str:
    """Segment of Table 3.1 for a marker label such as ``LKNE`` or ``SACR``.

    Raises:
        ParameterError: unknown marker (give its radius in the errors file).
    """
    for name in (label, label[1:]):
        if name in MARKER_SEGMENTS:
            return MARKER_SEGMENTS[name]
    raise ParameterError(
        f"marker {label!r} has no segment in the error model; give it a radius under "
        f"[markers.{label}] in the errors file"
    )


def parse_sources(text: str | Iterable[str]) -> tuple[str, ...]:
    """``"measurement,placement,sta"`` (or a list) -> validated source names."""
    names = [s.strip().lower() for s in (text.split(",") if isinstance(text, str) else text) if s.strip()]
    unknown = [n for n in names if n not in SOURCES]
    if unknown or not names:
        raise ParameterError(f"unknown error sources {unknown or names}; choose from {', '.join(SOURCES)}")
    return tuple(dict.fromkeys(names))


@dataclass(frozen=True)
class ErrorModel:
    """Maximum marker deviations per source (mm), by segment, with per-marker overrides.

    Attributes:
        segments: segment -> source -> mm (Table 3.1 by default).
        marker_sources: marker -> source -> mm (overrides the segment's value).
        marker_radius: marker -> total radius in mm (overrides everything).
        source: where the values came from.
    """

    segments: Mapping[str, Mapping[str, float]] = field(default_factory=lambda: TABLE_3_1)
    marker_sources: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    marker_radius: Mapping[str, float] = field(default_factory=dict)
    source: str = "Table 3.1"

    def __post_init__(self) -> None:
        """Refuse what :meth:`radius` could not use: a segment of Table 3.1 missing or
        lacking a source, an unknown segment, a size that is not a distance in mm."""
        if not isinstance(self.segments, Mapping) or set(self.segments) != set(TABLE_3_1):
            given = list(self.segments) if isinstance(self.segments, Mapping) else self.segments
            raise ParameterError(f"ErrorModel: segments must give every segment {', '.join(TABLE_3_1)} (each "
                                 f"source -> mm, e.g. TABLE_3_1); got {given!r}")  # fmt: skip
        for name, table in self.segments.items():
            lacking = [s for s in SOURCES if s not in _check_values("ErrorModel", f"segments.{name}", table, SOURCES)]
            if lacking:
                raise ParameterError(f"ErrorModel: [segments.{name}] lacks {', '.join(lacking)}; give every source "
                                     f"({', '.join(SOURCES)}) in mm")  # fmt: skip
        for label, table in self.marker_sources.items():
            _check_values("ErrorModel", f"markers.{label}", table, SOURCES)
        for label, radius in self.marker_radius.items():
            _check_values("ErrorModel", f"markers.{label}", {"radius": radius}, ("radius",))

    def radius(self, label: str, sources: Sequence[str] = SOURCES) -> float:
        """Cumulative error Σ (mm) of ``label`` for the selected ``sources``."""
        if label in self.marker_radius:
            return float(self.marker_radius[label])
        values = dict(self.segments[marker_segment(label)])
        values.update(self.marker_sources.get(label, {}))
        return float(sum(values[s] for s in parse_sources(sources)))

    def radii(self, labels: Sequence[str], sources: Sequence[str] = SOURCES) -> dict[str, float]:
        return {label: self.radius(label, sources) for label in labels}


def _check_values(origin: str | Path, where: str, table: object, allowed: Sequence[str]) -> dict[str, float]:
    """``table`` (``[where]`` of the errors file or model ``origin``) as source -> mm,
    checked: keys among ``allowed``, values distances in mm (0..500)."""
    if not isinstance(table, Mapping):
        raise ParameterError(f"{origin}: [{where}] must be a table of numbers")
    out = {}
    for key, value in table.items():
        if key not in allowed:
            raise ParameterError(f"{origin}: [{where}] has unknown key {key!r}; use {', '.join(allowed)}")
        if isinstance(value, bool) or not isinstance(value, Real) or not 0 <= float(value) <= 500:
            raise ParameterError(f"{origin}: [{where}] {key} = {value!r} must be a distance in mm (0..500)")
        out[key] = float(value)
    return out


def read_error_model(path: str | os.PathLike[str]) -> ErrorModel:
    """Read segment and marker overrides from a TOML file (see the module docstring)."""
    path = Path(path)
    data = load_toml(path, "errors file")
    unknown = set(data) - {"segments", "markers"}
    if unknown:
        raise ParameterError(f"{path}: unknown tables {sorted(unknown)}; use [segments.*] and [markers.*]")
    segments = {name: dict(values) for name, values in TABLE_3_1.items()}
    for name, table in data.get("segments", {}).items():
        if name not in TABLE_3_1:
            raise ParameterError(f"{path}: unknown segment {name!r}; use {', '.join(TABLE_3_1)}")
        segments[name].update(_check_values(path, f"segments.{name}", table, SOURCES))
    marker_sources, marker_radius = {}, {}
    for label, table in data.get("markers", {}).items():
        values = _check_values(path, f"markers.{label}", table, (*SOURCES, "radius"))
        if "radius" in values:
            marker_radius[label] = values.pop("radius")
        if values:
            marker_sources[label] = values
    return ErrorModel(segments, marker_sources, marker_radius, source=str(path))
