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
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from fuzzygait.io.c3d_guard import Layout

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
        analog_per_frame: analog samples per point frame as the backend read the data
            block (ezc3d derives it from the ``ANALOG`` parameters; if that disagrees with
            the header, its frames are misaligned), None when unknown.
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
    analog_per_frame: int | None = None


def _first_sentence(message: str) -> str:
    """The reader's message without its advice to developers (first line, first sentence)."""
    line = message.split("\n")[0].strip()
    for cut in (". If you want", ", please open"):
        line = line.split(cut)[0]
    return line.rstrip(". ")


def _clean_strings(values: Any) -> list[str]:
    return [str(v).strip() for v in np.atleast_1d(np.asarray(values, dtype=object)).ravel()]


# --------------------------------------------------------------------------- ezc3d
def open_ezc3d(path: Path) -> tuple[Any, list[str], ParamGetter]:
    """``path`` opened by ezc3d (force-platform extraction off): the ezc3d object, the
    warnings it gave, and a getter of its parameters (string lists cleaned, numbers as
    arrays, None for a parameter the file lacks).

    Raises:
        BackendError: ezc3d refused the file (its first sentence).
    """
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

    return c, [str(w.message) for w in caught], get


def _decode_ezc3d(path: Path) -> RawC3D:
    c, caught, get = open_ezc3d(path)
    params = c["parameters"]
    header = c["header"]
    points = np.asarray(c["data"]["points"], dtype=float)[:3].transpose(2, 1, 0)
    analogs = np.shape(c["data"]["analogs"])  # (1, channels, samples)
    event_notes: list[str] = []
    events = header_event_slots(
        [str(lbl) for lbl in header["events"]["events_label"]],
        [float(t) for t in header["events"]["events_time"]],
        _header_event_count(path),
        event_notes,
    )
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
        warnings=caught + event_notes,
        analog_per_frame=analogs[1] * analogs[2] // points.shape[0] if points.shape[0] and len(analogs) == 3 else None,
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


def suffixed(get: ParamGetter, group: str, name: str) -> list[Any]:
    """The values of ``group:name``, ``name2``, ``name3``, ... while they exist: C3D's
    convention for a parameter of more than 255 entries (a dimension is one byte), as
    in ``POINT:LABELS2`` or ``EVENT:TIMES2``."""
    parts: list[Any] = []
    while (value := get(group, f"{name}{len(parts) + 1}" if parts else name)) is not None:
        parts.append(value)
    return parts


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


def _lenient_reader(handle: Any) -> Any:
    """A ``c3d.Reader`` whose header/parameter agreement checks (assertions in
    ``_check_metadata``: point count, scale, rate, analog rate) become notes: the data
    are read from the parameters, as the package does anyway, so such a file is never
    refused for a disagreement that ezc3d tolerates."""
    import c3d

    class LenientReader(c3d.Reader):  # the package is untyped
        disagreements: list[str] = []

        def _check_metadata(self) -> None:
            try:
                super()._check_metadata()
            except AssertionError as exc:
                self.disagreements = [f"header and parameters disagree ({exc}); the parameters are used"]

    return LenientReader(handle)


def _decode_c3d(path: Path, n_frames: int | None = None) -> RawC3D:
    """Decode with the ``c3d`` package; ``n_frames``: read that many frames (when the
    header's count is smaller than what the file holds)."""
    try:
        with open(path, "rb") as handle, warnings.catch_warnings(record=True) as records:
            warnings.simplefilter("always")
            reader = _lenient_reader(handle)
            if n_frames and reader.get("TRIAL:ACTUAL_END_FIELD") is None:
                reader.header.last_frame = max(reader.header.last_frame, reader.header.first_frame + n_frames - 1)
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
            event_notes: list[str] = []
            events = _c3d_header_events(header, event_notes)
            # materialise every parameter now: the file closes when we leave this block
            cache, unreadable = _materialise(get, names)
    except Exception as exc:  # the c3d package raises ValueError, struct.error, ...
        raise BackendError(_c3d_reason(exc)) from exc
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
        warnings=list(reader.disagreements) + unreadable + event_notes,
    )


def _materialise(get: ParamGetter, names: dict[str, list[str]]) -> tuple[dict[tuple[str, str], Any], list[str]]:
    """Every parameter's value; one whose stored shape or type cannot be decoded (a
    damaged record the package skipped past) is left out with a note."""
    cache: dict[tuple[str, str], Any] = {}
    bad = []
    for group, params in names.items():
        for name in params:
            try:
                cache[(group, name)] = get(group, name)
            except Exception:  # numpy/struct errors on a damaged record
                bad.append(f"{group}:{name}")
    notes = [f"parameters {', '.join(bad)} could not be decoded and are ignored"] if bad else []
    return cache, notes


def _c3d_reason(exc: Exception) -> str:
    """The ``c3d`` package's reason, or a plain one where the package fails internally
    (e.g. ``UnboundLocalError`` on an unknown processor type)."""
    if isinstance(exc, (NameError, AttributeError, UnboundLocalError)):
        return f"the c3d package failed internally ({type(exc).__name__}) on a damaged header or parameter section"
    return _first_sentence(str(exc)) or type(exc).__name__


def _c3d_header_events(header: Any, notes: list[str]) -> list[tuple[str, float]]:
    try:
        count = int(header.event_count)
        labels = [lbl.decode("latin-1") if isinstance(lbl, bytes) else str(lbl) for lbl in header.event_labels]
        times = [float(t) for t in header.event_timings]
    except Exception:  # old headers without an event block
        return []
    return header_event_slots(labels, times, count, notes)


#: Byte offset of the header's event count (16-bit word 151; little-endian in the
#: formats ezc3d reads) and the number of event slots the header has.
_EVENT_COUNT_AT = 300
_EVENT_SLOTS = 18


def _header_event_count(path: Path) -> int:
    """The header's number of defined events (word 151), 18 when unreadable."""
    with open(path, "rb") as fh:
        fh.seek(_EVENT_COUNT_AT)
        word = fh.read(2)
    return int.from_bytes(word, "little") if len(word) == 2 else _EVENT_SLOTS


def header_event_slots(labels: list[str], times: list[float], count: int, notes: list[str]) -> list[tuple[str, float]]:
    """``(label, time_s)`` of the header's first ``count`` event slots that have a label;
    labelled slots beyond ``count`` (or a count beyond the 18 slots) are noted, not read."""
    labels = [lbl.strip() for lbl in labels]
    used = max(0, min(count, _EVENT_SLOTS, len(labels)))
    beyond = [i + 1 for i in range(used, len(labels)) if labels[i]]
    if count > _EVENT_SLOTS:
        notes.append(f"the header declares {count} events but has {_EVENT_SLOTS} event slots; reading {used}")
    elif beyond:
        notes.append(
            f"the header declares {count} events but event slot(s) {', '.join(map(str, beyond))} also hold labels; "
            "those are not read"
        )
    return [(lbl, t) for lbl, t in zip(labels[:used], times[:used]) if lbl]


# --------------------------------------------------------------------------- public
def decode(path: Path) -> RawC3D:
    """Decode ``path``: never stricter than ezc3d and the ``c3d`` package, never dying.

    1. :func:`~fuzzygait.io.c3d_guard.inspect` walks header and parameter section in
       pure Python (about 1 ms per file).
    2. No doubt: ezc3d reads the file in this process (the fast, normal path); if it
       refuses the file, returns no frames, or fewer frames than the file holds, the
       ``c3d`` package is tried and the better reading kept, with a note.
    3. Doubts (a parameter record that does not fit, too many dimensions, analog
       parameters ezc3d would index out of bounds, ...): ezc3d is not run here. The
       ``c3d`` package reads the file (its checks of header/parameter agreement turned
       into notes); if it refuses, ezc3d reads it in a child process with a time limit
       (:mod:`fuzzygait.io.c3d_child`) unless the doubt is a broken record chain,
       which ezc3d cannot read either.

    Notes for truncation and header/parameter disagreements are added to
    :attr:`RawC3D.warnings` (:func:`frame_notes`).

    Raises:
        BackendError: no reader can decode the file; the message gives the reasons.
    """
    from fuzzygait.io.c3d_guard import inspect

    layout = inspect(path)
    if layout.doubts:
        raw = _decode_doubtful(path, layout)
    else:
        raw = _decode_trusted(path, layout)
    raw.warnings.extend(layout.notes + frame_notes(layout, raw))
    return raw


def _decode_trusted(path: Path, layout: Layout) -> RawC3D:
    try:
        raw = _decode_ezc3d(path)
    except BackendError as first:
        try:
            raw = _decode_c3d(path)
        except BackendError as second:
            raise BackendError(f"ezc3d: {first}; c3d: {second}") from None
        raw.warnings.insert(0, f"ezc3d refused the file ({first}); read with the c3d package")
        return raw
    if raw.analog_per_frame is not None and raw.analog_per_frame != layout.analog_count:
        try:  # ezc3d sized the frames from the ANALOG parameters, not the header: misaligned
            other = _decode_c3d(path)
        except BackendError:
            raw.warnings.insert(0, _misaligned(raw, layout) + "; the data may be wrong")
            return raw
        other.warnings.insert(0, _misaligned(raw, layout) + "; read with the c3d package, which follows the header")
        return other
    _hide_invented(raw, layout)
    target = _frames_present(layout)
    n = raw.points.shape[0]
    if n == 0 or (target is not None and n < target):
        try:  # the c3d package, told how many frames the file really holds
            other = _decode_c3d(path, n_frames=target)
        except BackendError:
            return raw
        if other.points.shape[0] > n:
            other.warnings.insert(
                0, f"ezc3d read {n} of the {other.points.shape[0]} frames the file holds; read with the c3d package"
            )
            return other
    return raw


#: Parameters ezc3d invents when a file lacks them (from the header, or "mm"); the
#: reader's notes for a missing rate or unit must still be given.
_INVENTED = (("POINT", "RATE"), ("POINT", "UNITS"))


def _hide_invented(raw: RawC3D, layout: Layout) -> None:
    """Make ``raw.get`` return None for the :data:`_INVENTED` parameters the file lacks."""
    missing = {key for key in _INVENTED if key not in layout.parameters}
    if missing:
        get = raw.get
        raw.get = lambda group, name: None if (group, name) in missing else get(group, name)


def _misaligned(raw: RawC3D, layout: Layout) -> str:
    return (
        f"ezc3d read frames with {raw.analog_per_frame} analog samples each, the header declares "
        f"{layout.analog_count} (its ANALOG parameters are incomplete)"
    )


def _frames_present(layout: Layout) -> int | None:
    """Frames to read when the declared counts disagree: the larger declared count the
    file's size supports (None: no better count than the readers' own)."""
    holds = layout.frames_in_file()
    declared = [d for d in layout.declared_frames() if d]
    if holds is None or not declared:
        return None
    best = max(min(d, holds) for d in declared)
    return best if best > min(declared) or best == 0 else None


def _decode_doubtful(path: Path, layout: Layout) -> RawC3D:
    doubt = layout.doubts[0] + (f" (and {len(layout.doubts) - 1} more doubts)" if len(layout.doubts) > 1 else "")
    try:
        raw = _decode_c3d(path, n_frames=_frames_present(layout))
    except BackendError as second:
        if layout.broken:
            raise BackendError(f"{doubt}; c3d: {second}") from None
        from fuzzygait.io.c3d_child import decode_isolated

        try:
            raw = decode_isolated(path)
        except BackendError as first:
            raise BackendError(f"{doubt}; c3d: {second}; ezc3d: {first}") from None
        raw.warnings.insert(0, f"{doubt}; read with ezc3d in a separate process")
        return raw
    raw.warnings.insert(0, f"{doubt}; read with the c3d package")
    return raw


def frame_notes(layout: Layout, raw: RawC3D) -> list[str]:
    """Notes when the frame counts of header, ``POINT:FRAMES``, file size and the data
    actually read disagree (a truncated file, a corrupt count)."""
    header, param = layout.declared_frames()
    holds = layout.frames_in_file()
    n = raw.points.shape[0]
    notes = []
    if header is not None and param is not None and header != param:
        notes.append(f"the header announces {header} frames but POINT:FRAMES says {param}")
    declared = [d for d in (header, param) if d is not None]
    if declared and n < max(declared):
        why = f"the file ends after {holds} frames (truncated)" if holds is not None and holds < max(declared) else ""
        notes.append(f"{max(declared)} frames announced, {n} read" + (f": {why}" if why else "") + f"; using the {n}")
    elif holds is not None and n < holds and not any(d >= holds for d in declared) and (
            layout.size - (layout.data_start - 1) * 512 - n * (layout.frame_size() or 0) > 512):  # fmt: skip
        # more than one 512-byte block after the last frame read: writers pad the data
        # block to whole blocks, and ezc3d ends its files with one more block (a file of
        # exactly 512 frames of 256 bytes has 512 bytes after them)
        notes.append(f"the data block holds {holds} frames but only {n} were read")
    return notes
