"""The analog channels of a C3D file and the parameters needed to interpret them.

:func:`read_analog` reads the ``ANALOG`` block of a file with the same two readers as
:mod:`fuzzygait.io.c3d_backends`: the pure-Python sanity pass
(:func:`fuzzygait.io.c3d_guard.inspect`) decides whether ezc3d may run in this process;
ezc3d is tried first, the ``c3d`` package when ezc3d refuses the file or the pass has
doubts about it. A file neither reader can decode gives one :class:`~fuzzygait.core.errors.C3DError`
line naming the file and both readers' reasons.

Both readers return the channels in physical units, ``(stored - OFFSET) * SCALE *
GEN_SCALE`` per channel (the C3D rule); the stored ADC counts are recovered from them for
the saturation check (:attr:`AnalogData.counts`).
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from fuzzygait.core.errors import C3DError
from fuzzygait.io.c3d_backends import (
    BackendError,
    ParamGetter,
    _c3d_param_value,
    _first_sentence,
    _lenient_reader,
    open_ezc3d,
)

__all__ = ["AnalogData", "read_analog"]


@dataclass(frozen=True)
class AnalogData:
    """The analog block of a file, in physical units.

    Attributes:
        path: the file.
        values: ``(n_samples, n_channels)``, each channel in its ``ANALOG:UNITS`` unit
            (scale, offset and general scale applied).
        rate: analog samples per second, Hz.
        point_rate: marker frames per second, Hz.
        n_frames: marker frames in the file.
        labels, units: ``ANALOG:LABELS`` and ``ANALOG:UNITS`` per channel ('' when absent).
        scale: ``SCALE * GEN_SCALE`` per channel (physical unit per ADC count).
        offset: ``ANALOG:OFFSET`` per channel (ADC counts).
        count_range: ``(lowest, highest)`` ADC count the converter can give
            (``ANALOG:BITS`` and ``FORMAT``; 16 bits for integer files without ``BITS``),
            None when the file does not say (floating-point data without ``BITS``).
        get: parameter accessor (``get(group, name)``, None when absent), values in the
            C3D manual's first-index-fastest order.
        backend: ``"ezc3d"`` or ``"c3d"``.
        notes: what the readers had to say (the fallback used).
    """

    path: Path
    values: NDArray[np.float64]
    rate: float
    point_rate: float
    n_frames: int
    labels: tuple[str, ...]
    units: tuple[str, ...]
    scale: NDArray[np.float64]
    offset: NDArray[np.float64]
    count_range: tuple[float, float] | None
    get: ParamGetter
    backend: str
    notes: tuple[str, ...] = ()

    @property
    def counts(self) -> NDArray[np.float64]:
        """``(n_samples, n_channels)`` stored ADC counts, NaN where ``scale`` is 0."""
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = np.where(self.scale != 0, self.scale, np.nan)
            return np.asarray(self.values / scale + self.offset, dtype=float)


@dataclass(frozen=True)
class _Block:
    values: NDArray[np.float64]
    rate: float
    point_rate: float
    n_frames: int
    get: ParamGetter


def _ezc3d_block(path: Path) -> _Block:
    c, _, get = open_ezc3d(path)  # ezc3d's warnings: the marker reader reports them

    analogs = np.asarray(c["data"]["analogs"], dtype=float)  # (1, channels, samples)
    header = c["header"]
    return _Block(
        values=analogs[0].T.copy() if analogs.ndim == 3 else np.zeros((0, 0)),
        rate=float(header["analogs"]["frame_rate"]),
        point_rate=float(header["points"]["frame_rate"]),
        n_frames=int(np.shape(c["data"]["points"])[2]),
        get=get,
    )


def _c3d_block(path: Path) -> _Block:
    try:
        with open(path, "rb") as handle, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            reader = _lenient_reader(handle)
            frames = [analog for _, _, analog in reader.read_frames(analog_transform=True)]
            rate, point_rate = float(reader.analog_rate), float(reader.point_rate)
            names = {g: list(reader.get(g).param_keys()) for g in reader.group_keys() if isinstance(g, str)}
            cache: dict[tuple[str, str], Any] = {}
            for group, keys in names.items():
                for name in keys:
                    try:
                        cache[(group, name)] = _c3d_param_value(reader.get(f"{group}:{name}"))
                    except Exception:  # a damaged record: absent for us
                        continue
    except Exception as exc:  # the c3d package raises ValueError, struct.error, ...
        raise BackendError(_first_sentence(str(exc)) or type(exc).__name__) from exc
    if frames and np.size(frames[0]):
        values = np.concatenate([np.asarray(a, dtype=float).T for a in frames], axis=0)
    else:
        values = np.zeros((0, 0))
    return _Block(values, rate, point_rate, len(frames), lambda g, n: cache.get((g, n)))


def _decode(path: Path) -> tuple[_Block, str, list[str]]:
    from fuzzygait.io.c3d_guard import inspect

    layout = inspect(path)
    if not layout.doubts:
        try:
            return _ezc3d_block(path), "ezc3d", []
        except BackendError as first:
            try:
                return _c3d_block(path), "c3d", [f"ezc3d refused the file ({first}); read with the c3d package"]
            except BackendError as second:
                raise C3DError(f"{path}: cannot read the analog data (ezc3d: {first}; c3d: {second})") from None
    doubt = layout.doubts[0]
    try:
        return _c3d_block(path), "c3d", [f"{doubt}; read with the c3d package"]
    except BackendError as second:
        raise C3DError(f"{path}: cannot read the analog data ({doubt}; c3d: {second})") from None


def _numbers(get: ParamGetter, group: str, name: str, n: int, default: float) -> NDArray[np.float64]:
    """The first ``n`` values of a numeric parameter, ``default`` for missing ones."""
    value = get(group, name)
    out = np.full(n, default, dtype=float)
    if value is None or isinstance(value, list):  # absent, or text
        return out
    flat = np.asarray(value, dtype=float).ravel(order="F")[:n]
    out[: flat.size] = flat
    return out


def _strings(get: ParamGetter, group: str, name: str, n: int) -> tuple[str, ...]:
    value = get(group, name)
    found = [str(v).strip() for v in value] if isinstance(value, list) else []
    return tuple((found + [""] * n)[:n])


def _count_range(get: ParamGetter) -> tuple[float, float] | None:
    """The ADC's lowest and highest count: ``ANALOG:BITS`` (integer files without it:
    the 16-bit words they store) and ``ANALOG:FORMAT`` (``SIGNED`` unless ``UNSIGNED``)."""
    bits = _numbers(get, "ANALOG", "BITS", 1, 0.0)
    integer_file = _numbers(get, "POINT", "SCALE", 1, -1.0)[0] > 0
    if 1 < bits[0] <= 32:
        n = int(bits[0])
    elif integer_file:
        n = 16
    else:
        return None
    unsigned = _strings(get, "ANALOG", "FORMAT", 1)[0].upper() == "UNSIGNED"
    return (0.0, 2.0**n - 1) if unsigned else (-(2.0 ** (n - 1)), 2.0 ** (n - 1) - 1)


def read_analog(path: str | os.PathLike[str]) -> AnalogData:
    """The analog channels of ``path`` in physical units (see :class:`AnalogData`).

    Raises:
        C3DError: neither reader can decode the file (one line naming the file).
    """
    path = Path(path)
    if not path.is_file():
        raise C3DError(f"{path}: no such file")
    block, backend, notes = _decode(path)
    n = block.values.shape[1]
    get = block.get
    return AnalogData(
        path=path,
        values=block.values,
        rate=block.rate,
        point_rate=block.point_rate,
        n_frames=block.n_frames,
        labels=_strings(get, "ANALOG", "LABELS", n),
        units=_strings(get, "ANALOG", "UNITS", n),
        scale=_numbers(get, "ANALOG", "SCALE", n, 1.0) * _numbers(get, "ANALOG", "GEN_SCALE", 1, 1.0)[0],
        offset=_numbers(get, "ANALOG", "OFFSET", n, 0.0),
        count_range=_count_range(get),
        get=get,
        backend=backend,
        notes=tuple(notes),
    )
