"""The ``FORCE_PLATFORM`` group: each plate's type, corners, frame, transducer origin,
channels and calibration (conventions: :mod:`fuzzygait.io.force_plates`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fuzzygait.io.analog import AnalogData

__all__ = ["PlateSetup", "plate_frame", "plate_setups"]

#: Channels per plate type; types 4 and 5 need ``CAL_MATRIX`` (6 x channels).
CHANNELS = {1: 6, 2: 6, 3: 8, 4: 6, 5: 8}
#: Factors to N and N·mm of the analog units force and moment channels carry.
FORCE_UNITS = {"n": 1.0, "nt": 1.0, "newton": 1.0, "kn": 1000.0}
MOMENT_UNITS = {"nmm": 1.0, "ntmm": 1.0, "n.mm": 1.0, "n*mm": 1.0, "n·mm": 1.0, "nm": 1000.0, "n.m": 1000.0,
                "n*m": 1000.0, "n·m": 1000.0, "ntm": 1000.0, "knmm": 1000.0}  # fmt: skip


def factor(unit: str, table: dict[str, float]) -> float | None:
    """The factor of ``unit`` in ``table`` (case, spaces ignored), None if unknown."""
    return table.get(unit.strip().lower().replace(" ", ""))


@dataclass(frozen=True)
class PlateSetup:
    """One plate as ``FORCE_PLATFORM`` describes it.

    Attributes:
        number: 1-based plate number.
        kind: ``TYPE`` (1..5 are read).
        corners: ``(4, 3)`` mm, laboratory frame, the file's order.
        centre: ``(3,)`` mm, the surface centre (mean of the corners), laboratory frame.
        rotation: ``(3, 3)``, columns the plate's x, y, z axes in the laboratory frame
            (z into the plate): ``lab = centre + rotation @ plate``.
        depth: ``(3,)`` mm, plate frame: from the surface centre to the transducer
            origin (z >= 0, into the plate); for type 3 ``(0, 0, |az0|)``.
        sensor_offsets: type 3: the sensors' offsets a, b (mm) from ``ORIGIN``.
        channels: 0-based analog channel indices, in the type's order.
        calibration: ``(6, len(channels))`` for types 4 and 5 (outputs N and N·mm), else None.
        zero: ``FORCE_PLATFORM:ZERO`` (first, last marker frame of the baseline).
    """

    number: int
    kind: int
    corners: NDArray[np.float64]
    centre: NDArray[np.float64]
    rotation: NDArray[np.float64]
    depth: NDArray[np.float64]
    sensor_offsets: tuple[float, float]
    channels: tuple[int, ...]
    calibration: NDArray[np.float64] | None
    zero: tuple[int, int]

    def half_size(self) -> NDArray[np.float64]:
        """Half the plate's extent along its x and y axes, mm."""
        local = (self.corners - self.centre) @ self.rotation
        return np.asarray(np.abs(local[:, :2]).max(axis=0), dtype=float)


def plate_frame(corners: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rotation whose columns are the plate axes in the laboratory frame (the C3D rule:
    x from corner 2 to 1, z = x cross (corner 4 -> 1), y = z cross x)."""
    x = corners[0] - corners[1]
    z = np.cross(x, corners[0] - corners[3])
    y = np.cross(z, x)
    norms = np.linalg.norm([x, y, z], axis=1)
    if not np.all(norms > 1e-9 * max(1.0, float(np.abs(corners).max()))):
        raise ValueError("the corners do not span a surface")
    return np.asarray(np.stack([x, y, z], axis=1) / norms, dtype=float)


def _array(get: Any, name: str) -> NDArray[np.float64] | None:
    value = get("FORCE_PLATFORM", name)
    if value is None or isinstance(value, list):
        return None
    return np.asarray(value, dtype=float)


def _column(values: NDArray[np.float64] | None, rows: int, index: int) -> NDArray[np.float64] | None:
    """Plate ``index``'s column of a ``(rows, plates)`` parameter (None when short)."""
    if values is None or values.size < rows * (index + 1):
        return None
    return np.asarray(values.reshape(-1, order="F")[rows * index : rows * (index + 1)], dtype=float)


def _calibration(get: Any, kind: int, index: int, units: list[str]) -> tuple[NDArray[np.float64] | None, str | None]:
    """The plate's 6 x ``n`` matrix for types 4 and 5 (None otherwise) or the problem.
    A type 4 plate without a matrix whose channels are labelled N and N·mm (Motion
    Analysis writes such files) is read with the identity, as ezc3d does."""
    if kind not in (4, 5):
        return None, None
    n = CHANNELS[kind]
    cal = _array(get, "CAL_MATRIX")
    loads = len(units) == 6 and all(factor(u, FORCE_UNITS) == 1.0 for u in units[:3]) and all(
        factor(u, MOMENT_UNITS) == 1.0 for u in units[3:])  # fmt: skip
    if kind == 4 and loads and (cal is None or cal.size == 0):
        return np.eye(6), None
    if cal is None or cal.ndim < 2 or cal.shape[0] != 6 or cal.shape[1] < n:
        return None, f"type {kind} needs a 6 x {n} FORCE_PLATFORM:CAL_MATRIX, the file has none (uncalibrated)"
    plates = cal.reshape(6, cal.shape[1], -1, order="F")
    if plates.shape[2] <= index or not np.any(plates[:, :n, index]):
        return None, "its FORCE_PLATFORM:CAL_MATRIX is missing or all zeros (uncalibrated)"
    return np.asarray(plates[:, :n, index], dtype=float), None


def _depth(kind: int, origin: NDArray[np.float64]) -> tuple[NDArray[np.float64], tuple[float, float]]:
    if kind == 1:
        return np.zeros(3), (0.0, 0.0)
    if kind == 3:
        return np.array([0.0, 0.0, abs(origin[2])]), (float(origin[0]), float(origin[1]))
    return (origin if origin[2] >= 0 else -origin).astype(float), (0.0, 0.0)


def _one(analog: AnalogData, index: int, unit: float) -> tuple[PlateSetup, str | None]:
    """Plate ``index`` (0-based) and the reason it cannot be used, if any."""
    get = analog.get
    types = _array(get, "TYPE")
    kind = int(types.ravel()[index]) if types is not None and types.size > index else 0
    corners = _column(_array(get, "CORNERS"), 12, index)
    corners = np.zeros((4, 3)) if corners is None else corners.reshape(4, 3) * unit
    origin = _column(_array(get, "ORIGIN"), 3, index)
    n = CHANNELS.get(kind, 6)
    channel_values = _array(get, "CHANNEL")
    rows = channel_values.shape[0] if channel_values is not None and channel_values.ndim else n
    column = _column(channel_values, rows, index)
    channels = tuple(int(c) - 1 for c in column[:n]) if column is not None and rows >= n else ()
    zero_values = _array(get, "ZERO")
    zero = (0, 0)
    if zero_values is not None and zero_values.size >= 2:
        zero = (int(zero_values.ravel()[0]), int(zero_values.ravel()[1]))
    units = [analog.units[c] for c in channels if 0 <= c < len(analog.units)]
    calibration, problem = _calibration(get, kind, index, units)
    depth, offsets = _depth(kind, np.zeros(3) if origin is None else origin * unit)
    try:
        rotation = plate_frame(corners)
    except ValueError:
        rotation, problem = np.eye(3), problem or "FORCE_PLATFORM:CORNERS are missing or do not span a surface"
    setup = PlateSetup(index + 1, kind, corners, corners.mean(axis=0), rotation, depth, offsets, channels,
                       calibration, zero)  # fmt: skip
    return setup, problem or _channel_problem(analog, setup, origin, n)


def _channel_problem(analog: AnalogData, setup: PlateSetup, origin: NDArray[np.float64] | None, n: int) -> str | None:
    if setup.kind not in CHANNELS:
        return f"type {setup.kind} is not read (types 1 to 5 are)"
    if origin is None and setup.kind != 1:
        return "FORCE_PLATFORM:ORIGIN is missing"
    if len(setup.channels) != n:
        return f"FORCE_PLATFORM:CHANNEL does not list its {n} channels"
    width = analog.values.shape[1] if analog.values.ndim == 2 else 0
    outside = [c + 1 for c in setup.channels if not 0 <= c < width]
    if outside or not analog.values.shape[0]:
        return f"its channels {outside or list(setup.channels)} are not in the file's {width} analog channels"
    zero_scale = [analog.labels[c] or str(c + 1) for c in setup.channels if analog.scale[c] == 0]
    if zero_scale:
        return f"ANALOG:SCALE is 0 for its channels {', '.join(zero_scale)} (uncalibrated)"
    return None


def plate_setups(analog: AnalogData, length_units: Mapping[str, float]) -> tuple[list[PlateSetup], dict[int, str]]:
    """Every plate of ``FORCE_PLATFORM:USED`` and, by plate number, why one cannot be used.

    Args:
        analog: the file's analog block (its parameter accessor is used).
        length_units: factors to mm by ``POINT:UNITS`` (for ``CORNERS`` and ``ORIGIN``).
    """
    used = _array(analog.get, "USED")
    count = int(used.ravel()[0]) if used is not None and used.size else 0
    units = analog.get("POINT", "UNITS")
    unit = length_units.get(str(units[0]).strip().lower(), 1.0) if isinstance(units, list) and units else 1.0
    setups, problems = [], {}
    for index in range(max(count, 0)):
        setup, problem = _one(analog, index, unit)
        setups.append(setup)
        if problem:
            problems[setup.number] = problem
    return setups, problems
