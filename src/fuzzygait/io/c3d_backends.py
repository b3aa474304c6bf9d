"""Low-level C3D decoding through two maintained readers.

:func:`decode` turns a file into a :class:`RawC3D`: point data in the file's own length
unit, raw labels, rate, first frame and a parameter accessor. ezc3d is tried first; when
it refuses a file (e.g. SGI/MIPS processor format, non-standard parameter types) the
pure-Python ``c3d`` package is tried. Everything above this module (label handling, unit
conversion, model outputs, events) is backend-independent and lives in
:mod:`fuzzygait.io.c3d`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ParamGetter = Callable[[str, str], Any]
"""``get(group, name)``: the parameter value (list of str, or numpy array in the
parameter's declared dimension order), or ``None`` when absent."""


class BackendError(Exception):
    """A backend could not decode the file (message: the backend's own reason)."""


@dataclass
class RawC3D:
    """What a backend reads, before any interpretation.

    Attributes:
        points: ``(n_frames, n_points, 3)`` in the file's length unit; NaN where the file
            marks a sample invalid (negative residual).
        labels: ``POINT:LABELS`` (+ ``LABELS2``, ...) as stored, possibly more than points.
        header_rate: point rate from the file header, Hz.
        first_frame: 1-based number of the first frame from the header.
        header_events: ``(label, time_s)`` pairs from the header's event block.
        get: parameter accessor.
        parameter_names: parameter names of every group present.
        backend: ``"ezc3d"`` or ``"c3d"``.
        warnings: messages the backend emitted while reading.
    """

    points: np.ndarray
    labels: list[str]
    header_rate: float
    first_frame: int
    header_events: list[tuple[str, float]]
    get: ParamGetter
    parameter_names: dict[str, list[str]]
    backend: str
    warnings: list[str] = field(default_factory=list)


def _first_sentence(message: str) -> str:
    """The reader's message without its advice to developers (first line, first sentence)."""
    line = message.split("\n")[0].strip()
    for cut in (". If you want", ", please open"):
        line = line.split(cut)[0]
    return line.rstrip(". ")


def _clean_strings(values: Any) -> list[str]:
    return [str(v).strip() for v in np.atleast_1d(np.asarray(values, dtype=object)).ravel()]


# --------------------------------------------------------------------------- ezc3d
def _decode_ezc3d(path: Path) -> RawC3D:
    import ezc3d

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            c = ezc3d.c3d(str(path), extract_forceplat_data=False)
    except Exception as exc:  # ezc3d raises OSError, ValueError, RuntimeError, ...
        raise BackendError(_first_sentence(str(exc))) from exc
    params = c["parameters"]

    def get(group: str, name: str) -> Any:
        try:
            value = params[group][name]["value"]
        except (KeyError, TypeError):
            return None
        if isinstance(value, list):
            return _clean_strings(value) if value and isinstance(value[0], str) else value
        return np.asarray(value)

    header = c["header"]
    points = np.asarray(c["data"]["points"], dtype=float)[:3].transpose(2, 1, 0)
    events = [
        (str(lbl).strip(), float(t))
        for lbl, t in zip(header["events"]["events_label"], header["events"]["events_time"])
        if str(lbl).strip()
    ]
    return RawC3D(
        points=points,
        labels=list(get("POINT", "LABELS") or []) + _extra_labels(get),
        header_rate=float(header["points"]["frame_rate"]),
        first_frame=int(header["points"]["first_frame"]) + 1,
        header_events=events,
        get=get,
        parameter_names={
            g: [p for p in params[g].keys() if p != "__METADATA__"]
            for g in params.keys()
            if g != "__METADATA__"
        },
        backend="ezc3d",
        warnings=[str(w.message) for w in caught],
    )


def _extra_labels(get: ParamGetter) -> list[str]:
    """``POINT:LABELS2``, ``LABELS3``, ... which hold labels beyond the 255th."""
    extra: list[str] = []
    for i in range(2, 100):
        more = get("POINT", f"LABELS{i}")
        if more is None:
            break
        extra += list(more)
    return extra


# --------------------------------------------------------------------------- c3d
def _c3d_param_value(param: Any) -> Any:
    if param.bytes_per_element == -1:
        return _clean_strings(param.string_array) if param.dimensions else [param.string_value]
    kind = {4: "float", 2: "int16"}.get(param.bytes_per_element, "int8")
    if not param.dimensions:  # a scalar parameter
        return np.array([getattr(param, f"{kind}_value")])
    arr = getattr(param, f"{kind}_array")
    # The c3d package returns arrays in C order of reversed dimensions; ezc3d (and the
    # C3D manual) list them first-index-fastest. Transpose to ezc3d's order.
    arr = np.asarray(arr)
    return arr.T if arr.ndim >= 2 else arr


def _decode_c3d(path: Path) -> RawC3D:
    import c3d

    try:
        with open(path, "rb") as handle, warnings.catch_warnings(record=True) as records:
            warnings.simplefilter("always")
            reader = c3d.Reader(handle)
            frames = [pts for _, pts, _ in reader.read_frames()]
            # The package's own warnings (missing optional parameters, header/parameter
            # disagreements it resolves itself) are not data-quality news for a user;
            # a short data block is reported by the caller from the frame counts.
            del records
            header = reader.header
            names = {
                g: list(reader.get(g).param_keys()) for g in reader.group_keys() if isinstance(g, str)
            }

            def get(group: str, name: str) -> Any:
                param = reader.get(f"{group}:{name}")
                return None if param is None else _c3d_param_value(param)

            labels = list(get("POINT", "LABELS") or []) + _extra_labels(get)
            first_frame = int(reader.first_frame)
            rate = float(reader.point_rate)
            events = _c3d_header_events(header)
            # materialise every parameter now: the file closes when we leave this block
            cache = {(g, p): get(g, p) for g, params in names.items() for p in params}
    except Exception as exc:  # the c3d package raises ValueError, struct.error, ...
        raise BackendError(_first_sentence(str(exc)) or type(exc).__name__) from exc
    if frames:
        block = np.stack(frames)  # (n_frames, n_points, 5): x, y, z, residual, cameras
        points = block[:, :, :3].astype(float)
        points[block[:, :, 3] < 0] = np.nan
    else:
        points = np.zeros((0, len(labels), 3))
    return RawC3D(
        points=points,
        labels=labels,
        header_rate=rate,
        first_frame=first_frame,
        header_events=events,
        get=lambda g, p: cache.get((g, p)),
        parameter_names=names,
        backend="c3d",
    )


def _c3d_header_events(header: Any) -> list[tuple[str, float]]:
    try:
        count = int(header.event_count)
        labels = [
            (lbl.decode("latin-1") if isinstance(lbl, bytes) else str(lbl)).strip()
            for lbl in header.event_labels[:count]
        ]
        times = [float(t) for t in header.event_timings[:count]]
    except Exception:  # old headers without an event block
        return []
    return [(lbl, t) for lbl, t in zip(labels, times) if lbl]


# --------------------------------------------------------------------------- public
#: What the ``c3d`` package (0.6) says of a parameter name that occurs twice in a group.
#: Vicon Nexus writes such files and ezc3d reads them, so it is not taken as corruption.
DUPLICATE_PARAMETER = "Parameter already exists"


def check_parameter_section(path: Path) -> None:
    """Parse header and parameter section with the ``c3d`` package (milliseconds).

    ezc3d needs more than ten seconds to give up on some corrupt parameter sections;
    this quick structural check refuses them at once.

    Raises:
        BackendError: the header or parameter section is not valid C3D.
    """
    import c3d

    try:
        with open(path, "rb") as handle, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c3d.Reader(handle)
    except Exception as exc:
        if DUPLICATE_PARAMETER in str(exc):  # a repeated name (Nexus writes such files): not corruption
            return
        raise BackendError(
            f"header or parameter section is corrupt ({_first_sentence(str(exc)) or type(exc).__name__})"
        ) from exc


def decode(path: Path) -> RawC3D:
    """Decode ``path`` with ezc3d, falling back to the ``c3d`` package.

    The parameter section is first checked by :func:`check_parameter_section`.

    Raises:
        BackendError: when the parameter section is corrupt or neither reader can decode
            the file; the message carries the readers' reasons.
    """
    check_parameter_section(path)
    try:
        return _decode_ezc3d(path)
    except BackendError as first:
        try:
            raw = _decode_c3d(path)
        except BackendError as second:
            raise BackendError(f"ezc3d: {first}; c3d: {second}") from None
        raw.warnings.insert(0, f"ezc3d refused the file ({first}); read with the c3d package")
        return raw
