"""A static calibration's cluster part (CGM 2.3+) as plain tables for a subject file, so
that walking trials can be processed without the static trial.

Layout, under the subject file's ``[calibration]`` table (TOML; a ``.vsk``'s sidecar,
:mod:`fuzzygait.io.calibration_table`)::

    model = "cgm2.3"                      # the version calibrated
    [calibration.clusters.LThigh]         # also LTibia, RThigh, RTibia; L/RForefoot (2.4)
    markers = ["LTHI", "LTHAP", "LTHAD", "LKNE"]
    local = [[x, y, z], ...]              # mm, one row per marker
    [calibration.forefoot_joint_centres]  # CGM 2.4
    L = [x, y, z]                         # mm
    [calibration.shank_torsion.L]         # calibrated with KNM/MED; also R
    tibial_torsion = t                    # rad
    foot_correction = d                   # rad, CGM 2.3's foot

``local`` holds each tracking marker's mean position in its segment's **anatomical**
frame of the static trial (:class:`~fuzzygait.kinematics.clusters.ClusterCalibration`):
thigh origin KJC, tibia the torsioned tibia with origin AJC, forefoot origin vSMH.  The
technical frame *is* the anatomical one, so the technical-to-anatomical transform is the
identity and the knee and ankle joint centres are the frames' origins (0, 0, 0) -- the
file stores no separate transform or joint centre.  The forefoot joint centre is in the
hindfoot (Plug-in Gait foot) frame, origin AJC.  ``shank_torsion`` is the
:class:`~fuzzygait.kinematics.clusters.ShankTorsion` of each side (absent: calibrated
without MED, no torsion).  Numbers are written exactly (shortest round-trip decimals), so
the file gives the static trial's angles to the last bit.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.options import Advice, Option
from fuzzygait.io.calibration_table import read_calibration_table
from fuzzygait.io.tomlfile import TomlData
from fuzzygait.kinematics.clusters import ClusterCalibration, SegmentCluster, ShankTorsion
from fuzzygait.kinematics.rigid import MIN_MARKERS

#: Segment names of a cluster calibration and their spelling in the file.
SEGMENT_NAMES = {"thigh": "Thigh", "tibia": "Tibia", "forefoot": "Forefoot"}
#: What a malformed calibration table's error says to do.
AGAIN = Advice("; recalibrate with fuzzygait calibrate STATIC.c3d {out} FILE", out=Option.OUT)
#: Segments every cluster calibration has, per side.
REQUIRED_SEGMENTS = ("thigh", "tibia")


def segment_key(side: str, name: str) -> str:
    """``("L", "thigh")`` -> ``"LThigh"``, the segment's table name."""
    return side + SEGMENT_NAMES[name]


#: The fields of a side's ``shank_torsion`` table (rad).
SHANK_TORSION_FIELDS = ("tibial_torsion", "foot_correction")


def cluster_table(calibration: ClusterCalibration) -> dict[str, TomlData]:
    """``{"clusters": {"LThigh": {"markers": [...], "local": [[x, y, z], ...]}, ...},
    "forefoot_joint_centres": {"L": [x, y, z], ...}, "shank_torsion": {"L": {...}, ...}}``
    (the latter two only when calibrated)."""
    clusters: dict[str, TomlData] = {}
    for (side, name), cluster in sorted(calibration.segments.items(), key=lambda item: _order(*item[0])):
        clusters[segment_key(side, name)] = {
            "markers": list(cluster.markers),
            "local": [[float(v) for v in row] for row in np.asarray(cluster.local, dtype=float)],
        }
    table: dict[str, TomlData] = {"clusters": clusters}
    centres = calibration.forefoot_joint_centres
    if centres:
        table["forefoot_joint_centres"] = {side: [float(v) for v in np.asarray(centres[side], dtype=float)]
                                           for side in sorted(centres)}  # fmt: skip
    torsions = calibration.shank_torsions
    if torsions:
        table["shank_torsion"] = {side: {name: float(getattr(torsions[side], name)) for name in SHANK_TORSION_FIELDS}
                                  for side in sorted(torsions)}  # fmt: skip
    return table


def _order(side: str, name: str) -> tuple[int, int]:
    return "LR".index(side), list(SEGMENT_NAMES).index(name)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)


def _point(value: Any) -> bool:
    return isinstance(value, list) and len(value) == 3 and all(_is_number(v) for v in value)


def _points(value: Any, rows: int | None, where: str) -> np.ndarray:
    """``value`` as an ``(rows, 3)`` array of finite numbers (``rows`` None: ``(3,)``)."""
    if rows is None:
        ok = _point(value)
    else:
        ok = isinstance(value, list) and len(value) == rows and all(_point(row) for row in value)
    if not ok:
        raise ParameterError(f"{where} must be {'[x, y, z]' if rows is None else f'{rows} rows [x, y, z]'} "
                             f"of finite numbers (mm){AGAIN}")  # fmt: skip
    return np.array(value, dtype=float)


def clusters_from_table(table: Mapping[str, Any], source: str) -> ClusterCalibration | None:
    """The cluster calibration of a ``[calibration]`` table (:func:`cluster_table`), or
    None when it has none (a Plug-in Gait calibration, an older file).

    Raises:
        ParameterError: a malformed table (names the file and the entry; says to
            recalibrate).
    """
    raw = table.get("clusters")
    if raw is None:
        return None
    again = AGAIN
    if not isinstance(raw, Mapping):
        raise ParameterError(f"{source}: [calibration.clusters] must be a table of segments{again}")
    by_key = {segment_key(side, name): (side, name) for side in "LR" for name in SEGMENT_NAMES}
    segments: dict[tuple[str, str], SegmentCluster] = {}
    for key, entry in raw.items():
        where = f"{source}: [calibration.clusters.{key}]"
        if key not in by_key:
            raise ParameterError(f"{where}: unknown segment; expected {', '.join(by_key)}{again}")
        if not isinstance(entry, Mapping):
            raise ParameterError(f"{where} must be a table with markers and local{again}")
        markers = entry.get("markers")
        if not (isinstance(markers, list) and all(isinstance(m, str) and m for m in markers)):
            raise ParameterError(f"{where}: markers must be a list of marker labels{again}")
        if len(markers) < MIN_MARKERS or len(set(markers)) != len(markers):
            raise ParameterError(f"{where}: needs at least {MIN_MARKERS} different markers, "
                                 f"has {', '.join(markers) or 'none'}{again}")  # fmt: skip
        local = _points(entry.get("local"), len(markers), f"{where} local")
        segments[by_key[key]] = SegmentCluster(tuple(markers), local)
    lacking = [segment_key(s, n) for s in "LR" for n in REQUIRED_SEGMENTS if (s, n) not in segments]
    if lacking:
        raise ParameterError(f"{source}: [calibration.clusters] lacks {', '.join(lacking)}{again}")
    centres: dict[str, np.ndarray] = {}
    raw_centres = table.get("forefoot_joint_centres", {})
    if not isinstance(raw_centres, Mapping) or set(raw_centres) - {"L", "R"}:
        raise ParameterError(f"{source}: [calibration.forefoot_joint_centres] must hold L and R{again}")
    for side, value in raw_centres.items():
        centres[side] = _points(value, None, f"{source}: [calibration.forefoot_joint_centres] {side}")
    forefoot = [side for side in "LR" if (side, "forefoot") in segments]
    if forefoot and sorted(centres) != ["L", "R"] or not forefoot and centres:
        raise ParameterError(f"{source}: the forefoot clusters and forefoot_joint_centres must both be there "
                             f"for both sides, or neither{again}")  # fmt: skip
    return ClusterCalibration(segments, centres, _shank_torsions(table.get("shank_torsion", {}), source))


def _shank_torsions(raw: Any, source: str) -> dict[str, ShankTorsion]:
    """The ``[calibration.shank_torsion]`` table's :class:`ShankTorsion` per side."""
    where = f"{source}: [calibration.shank_torsion]"
    if not isinstance(raw, Mapping) or set(raw) - {"L", "R"}:
        raise ParameterError(f"{where} must hold L and/or R{AGAIN}")
    torsions: dict[str, ShankTorsion] = {}
    for side, entry in raw.items():
        ok = isinstance(entry, Mapping) and set(entry) == set(SHANK_TORSION_FIELDS)
        if not (ok and all(_is_number(entry[name]) and abs(entry[name]) <= np.pi for name in SHANK_TORSION_FIELDS)):
            raise ParameterError(f"{where} {side} must be {{{', '.join(SHANK_TORSION_FIELDS)}}}, "
                                 f"finite angles in rad{AGAIN}")  # fmt: skip
        torsions[side] = ShankTorsion(*(float(entry[name]) for name in SHANK_TORSION_FIELDS))
    return torsions


@dataclass(frozen=True)
class StoredCalibration:
    """What a subject file says about the static calibration it holds.

    Attributes:
        source: the file the ``[calibration]`` table is in (a ``.vsk``'s sidecar), or None.
        table: that table as read (``{}``: none).
        clusters: its cluster calibration (None: none).
    """

    source: Path | None = None
    table: dict[str, Any] = field(default_factory=dict)
    clusters: ClusterCalibration | None = None

    @property
    def model(self) -> str | None:
        """The model version calibrated (None: not said; files before the model versions
        were Plug-in Gait, ``cgm1.0``)."""
        model = self.table.get("model")
        return model if isinstance(model, str) else None

    @property
    def static(self) -> str | None:
        """The static trial it was calibrated on, when the file says."""
        static = self.table.get("static")
        return static if isinstance(static, str) else None

    def has_forefoot(self) -> bool:
        """Both CGM 2.4 forefoots are in the cluster calibration."""
        return self.clusters is not None and all((s, "forefoot") in self.clusters.segments for s in "LR")


def read_stored_calibration(subject_file: str | os.PathLike[str]) -> StoredCalibration:
    """The calibration a subject file holds (:func:`~fuzzygait.io.calibration_table.read_calibration_table`
    and :func:`clusters_from_table`)."""
    table, source = read_calibration_table(subject_file)
    if source is None:
        return StoredCalibration()
    return StoredCalibration(source, table, clusters_from_table(table, str(source)))


__all__ = [
    "REQUIRED_SEGMENTS",
    "SEGMENT_NAMES",
    "StoredCalibration",
    "cluster_table",
    "clusters_from_table",
    "read_stored_calibration",
    "segment_key",
]
