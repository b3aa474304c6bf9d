"""Carry an input C3D's analog channels, force platforms, events and parameters over
into a C3D the package writes from it (``fuzzygait preprocess``, ``angles --c3d-out``).

:func:`fuzzygait.io.c3d.write_c3d` first lets ezc3d write the trial (points, model
outputs, the parameters the writer sets) and, when the trial was read from a file, the
input's analog samples *as stored* (``ANALOG`` scale 1, offset 0). :func:`write_back`
then replaces that file's parameter section by a merge (:mod:`fuzzygait.io.c3d_params`):

* the input's records, byte for byte, for every group and parameter the writer does not
  own -- ``ANALOG`` (with its ``SCALE``, ``OFFSET``, ``GEN_SCALE``, so every reader
  computes the input's analog values from the stored samples), ``FORCE_PLATFORM``,
  ``ANALYSIS``, ``TRIAL``, ``MANUFACTURER``, custom groups, ...;
* the written records where the writer owns the parameter (:data:`OWNED_POINT`, the
  ``EVENT`` group unless the trial's events are the input's, ``ROTATION``) or changed its
  value (``PROCESSING`` values, ``SUBJECTS``, ``text_parameters``): a parameter the writer
  wrote with the input's value keeps the input's record;
* ``TRIAL:ACTUAL_START_FIELD``/``ACTUAL_END_FIELD`` and ``POINT:LONG_FRAMES`` rewritten
  when the trial covers other frames than the input, whose analog samples are cut to the
  trial's frames.

ezc3d reads the result back before it is kept: its analog values must equal the input's
bit for bit. Whatever cannot be carried over (ezc3d cannot read the input, an analog
block that does not fit the point frames, a damaged parameter section, ...) is left out
and named in one note; the file is written all the same.
"""

from __future__ import annotations

import math
import struct
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from fuzzygait.core.trial import Trial
from fuzzygait.io.c3d_backends import _first_sentence
from fuzzygait.io.c3d_groups import read_events  # the reader's own rules
from fuzzygait.io.c3d_guard import BLOCK, Layout, inspect
from fuzzygait.io.c3d_params import Group, Parameter, Section, SectionError, int16s, read_section, section_bytes
from fuzzygait.io.c3d_points import CarryError, InputPoints, input_points, trial_window

#: ``POINT`` parameters naming the unit of a model-output type: the input's is kept where
#: the writer writes none.
OUTPUT_UNIT_PARAMETERS = frozenset(
    {"ANGLE_UNITS", "FORCE_UNITS", "MOMENT_UNITS", "POWER_UNITS", "SCALAR_UNITS", "MODELED_MARKER_UNITS"}
)
#: ``POINT`` parameters the writer owns: they describe its point block (labels, units,
#: rate, storage, model-output type lists); the input's values are never copied (its
#: descriptions and lock flags are, :func:`_point_record`).
OWNED_POINT = frozenset(
    {"USED", "FRAMES", "SCALE", "DATA_START", "RATE", "UNITS", "LABELS", "DESCRIPTIONS", "TYPE_GROUPS"}
    | {"ANGLES", "FORCES", "MOMENTS", "POWERS", "SCALARS", "MODELED_MARKERS"}
    | OUTPUT_UNIT_PARAMETERS
)
#: Groups whose written version is kept whole (ezc3d's own bookkeeping of data the
#: writer does not carry over).
OWNED_GROUPS = frozenset({"ROTATION", "EZC3D"})
#: Groups describing the analog channels: carried over with the analog samples only.
CHANNEL_GROUPS = ("ANALOG", "FORCE_PLATFORM")
_CHANNEL_PARTS = ("analog channels", "force platforms")


def owned_point(name: str) -> bool:
    """Whether ``POINT:<name>`` is the writer's (``LABELS2``, ``UNITS3``... included)."""
    name = name.upper()
    return name in OWNED_POINT or name.rstrip("0123456789") in ("LABELS", "DESCRIPTIONS", "UNITS")


@dataclass
class Analogs:
    """The input's analog channels over the trial's frames.

    Attributes:
        stored: ``(channels, samples)`` the samples as the input stores them (integers of
            an integer file; float32-exact), for the ``ANALOG`` parameters copied with them.
        values: ``(channels, samples)`` as ezc3d reads them from the input (its units).
        per_frame: samples per channel per point frame.
    """

    stored: np.ndarray
    values: np.ndarray
    per_frame: int


@dataclass
class Source:
    """What an input file lets the writer carry over, and what it does not.

    Attributes:
        path: the input file.
        section: its parameter section (None: it cannot be read).
        analogs: its analog channels over the trial's frames (None: none, or not carried).
        points: its point block over the trial's frames (None: ezc3d cannot read it).
        same_frames: the trial covers exactly the input's frames.
        same_events: the trial's events are the input's (its ``EVENT`` group is copied).
        lost: what is left out (``"parameters"``, ``"analog channels"``, ...), in order.
        reasons: why, one phrase each.
    """

    path: Path
    section: Section | None = None
    analogs: Analogs | None = None
    points: InputPoints | None = None
    same_frames: bool = True
    same_events: bool = False
    lost: list[str] = field(default_factory=list)
    reasons: list[str] = field(default_factory=list)

    def lose(self, what: list[str], reason: str) -> None:
        """Record that ``what`` is left out because of ``reason``."""
        self.lost += [w for w in what if w not in self.lost]
        if reason and reason not in self.reasons:
            self.reasons.append(reason)

    def channel_parts(self) -> list[str]:
        """``"analog channels"`` and ``"force platforms"`` when the input has them."""
        if self.section is None:
            return []
        section = self.section
        return [
            part for group, part in zip(CHANNEL_GROUPS, _CHANNEL_PARTS) if _first_number(section, group, "USED") > 0
        ]

    def notes(self, out: Path) -> list[str]:
        """One line naming what was left out of ``out`` and why ([] when nothing)."""
        if not self.lost:
            return []
        what = ", ".join(self.lost[:-2] + [" and ".join(self.lost[-2:])])
        return [f"{out}: the {what} of {self.path.name} could not be carried over ({'; '.join(self.reasons)})"]


def _first_number(section: Section, group: str, name: str) -> float:
    param = section.get(group, Group(group)).parameters.get(name)
    if param is None or param.kind == -1 or not param.data:
        return 0.0
    return float(param.numbers()[0])


# --------------------------------------------------------------------------- the input
def open_source(path: Path, trial: Trial) -> Source:
    """What of ``path`` (the file ``trial`` was read from) can be carried over; never
    raises: what cannot is recorded in :attr:`Source.lost`."""
    try:
        return _open_source(Path(path), trial)
    except Exception as exc:  # a file no check foresaw: the trial is still written
        source = Source(Path(path))
        source.lose(["parameters", "analog channels"], f"{type(exc).__name__}: {exc}")
        return source


def _open_source(path: Path, trial: Trial) -> Source:
    source = Source(path)
    layout = None
    try:
        layout = inspect(source.path)
        if layout.broken:
            raise SectionError(layout.doubts[0])
        source.section = read_section(source.path.read_bytes())
    except (OSError, SectionError, ValueError, IndexError, struct.error) as exc:
        analog = ["analog channels"] if layout is not None and layout.analog_count else []
        source.lose(["parameters", *analog], f"its parameter section cannot be read: {exc}")
        return source
    section = source.section
    first, count = layout.first_frame, layout.declared_frames()[0]
    source.same_frames = trial.first_frame == first and trial.n_frames == count
    source.same_events = _same_events(source, trial)
    if _first_number(section, "ROTATION", "USED") > 0:
        source.lose(["rotations"], "fuzzygait does not carry rotation data over")
    parts = source.channel_parts()
    try:
        c = _read_ezc3d(source, layout)
    except CarryError as exc:
        source.lose([*parts, "point residuals"], str(exc))
        return source
    if "analog channels" in parts:
        try:
            source.analogs = _analogs(source, c, layout, trial)
        except CarryError as exc:
            source.lose(parts, str(exc))
    try:
        source.points = input_points(c, trial)
    except CarryError as exc:
        source.lose(["point residuals"], str(exc))
    return source


def _read_ezc3d(source: Source, layout: Layout) -> Any:
    """The input read by ezc3d; :class:`CarryError` where ezc3d must not (``c3d_guard``'s
    doubts) or cannot read it."""
    import ezc3d

    if layout.doubts:  # ezc3d must not run on this file in this process (c3d_guard)
        raise CarryError(f"ezc3d cannot read the file: {layout.doubts[0]}")
    try:
        return ezc3d.c3d(str(source.path))
    except Exception as exc:  # ezc3d raises ValueError, RuntimeError, ...
        raise CarryError(f"ezc3d cannot read the file: {_first_sentence(str(exc))}") from None


def _same_events(source: Source, trial: Trial) -> bool:
    """Whether the input's ``EVENT`` group, read as :func:`fuzzygait.io.c3d.read_c3d`
    reads it, gives the trial's events (then it is copied whole, icons and flags kept)."""
    from fuzzygait.io.c3d_backends import RawC3D

    assert source.section is not None
    group = source.section.get("EVENT")
    if group is None:
        return not trial.events

    def get(g: str, name: str) -> object:
        param = group.parameters.get(name.upper()) if g == "EVENT" else None
        if param is None:
            return None
        return list(param.strings()) if param.kind == -1 else param.numbers()

    raw = RawC3D(np.zeros((0, 0, 3)), [], 0.0, 1, [], get, {}, "section")
    try:
        return Counter(read_events(source.path, raw, [])) == Counter(trial.events)
    except Exception:  # a group the reader would note as unreadable: the writer's own is written
        return False


def _analogs(source: Source, c: Any, layout: Layout, trial: Trial) -> Analogs:
    """The input's analog channels over the trial's frames, from ezc3d's reading ``c``.

    Raises:
        CarryError: its analog block does not fit the point frames, the trial's frames
            or rate are not the file's, or the samples cannot be stored exactly.
    """
    assert source.section is not None
    channels = int(_first_number(source.section, "ANALOG", "USED"))
    values = np.asarray(c["data"]["analogs"], dtype=float)[0]
    n_frames = int(np.shape(c["data"]["points"])[2])
    per_frame = layout.analog_count // channels if channels else 0
    if values.shape != (channels, n_frames * per_frame) or per_frame * channels != layout.analog_count:
        raise CarryError(
            f"ezc3d reads {values.shape[0]} analog channels of {values.shape[1]} samples; the file declares "
            f"{channels} channels, {layout.analog_count} samples a frame and {n_frames} frames"
        )
    rate = _file_rate(c)
    if not math.isclose(trial.rate, rate, rel_tol=1e-6):
        raise CarryError(f"the trial's rate {trial.rate:g} Hz is not the file's {rate:g} Hz")
    window = trial_window(c, trial)
    values = values[:, window.start * per_frame : window.stop * per_frame]
    return Analogs(_stored(values, source.section["ANALOG"], channels), values, per_frame)


def _file_rate(c: object) -> float:
    """The input's point rate as the reader takes it: ``POINT:RATE``, else the header's."""
    params = c["parameters"]  # type: ignore[index]
    try:
        rate = float(np.ravel(params["POINT"]["RATE"]["value"])[0])
    except (KeyError, IndexError, TypeError):
        rate = 0.0
    return rate if rate > 0 else float(c["header"]["points"]["frame_rate"])  # type: ignore[index]


def _stored(values: np.ndarray, analog: Group, channels: int) -> np.ndarray:
    """The samples as stored, from ezc3d's values ``(stored - |OFFSET|) * SCALE *
    GEN_SCALE`` (float32 difference, float64 products); checked to give ``values`` back
    bit for bit.

    Raises:
        CarryError: a scale or offset is missing, or a value has no exact stored sample.
    """
    params = analog.parameters
    if not all(name in params for name in ("SCALE", "OFFSET", "GEN_SCALE")):
        raise CarryError("ANALOG:SCALE, OFFSET or GEN_SCALE is missing")
    scale = params["SCALE"].numbers()[:channels, None]
    offset = np.abs(params["OFFSET"].numbers()[:channels, None]).astype(np.float32)
    gen = params["GEN_SCALE"].numbers()[0] if params["GEN_SCALE"].data else 1.0
    if scale.shape[0] != channels or offset.shape[0] != channels:
        raise CarryError(f"ANALOG:SCALE or OFFSET holds fewer than {channels} values")
    with np.errstate(all="ignore"):
        difference = (values / gen / scale).astype(np.float32)
        stored = np.where(offset == 0, difference, difference + offset).astype(np.float32)  # -0.0 + 0 is 0.0
        # a channel of scale 0 reads 0 whatever is stored: the sample's sign gives the zero's
        negative = np.signbit(values) != (np.signbit(scale) ^ np.signbit(gen))
        zero = np.broadcast_to(scale * gen == 0, values.shape)
        stored[zero] = (offset - negative.astype(np.float32))[zero]
        back = (stored - offset).astype(float) * scale * gen
    if not same_bits(back, values):
        raise CarryError("some analog samples cannot be stored exactly with the file's ANALOG:SCALE and OFFSET")
    return stored.astype(float)


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two float arrays hold the same numbers bit for bit: 0.0 and -0.0 told
    apart, any NaN equal to any NaN (a NaN's sign and payload are not kept by arithmetic)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or not np.array_equal(a, b, equal_nan=True):
        return False
    numbers = ~np.isnan(a)
    return bool(np.array_equal(np.signbit(a[numbers]), np.signbit(b[numbers])))


# --------------------------------------------------------------------------- the output
def write_back(tmp: Path, out: Path, source: Source, trial: Trial,
               write_stage: Callable[[Path, Analogs | None], None]) -> list[str]:  # fmt: skip
    """Write ``tmp`` (to become ``out``): ``write_stage(tmp, analogs)`` writes the trial
    with ezc3d, then the input's parameters are carried over (:func:`carry_over`) and the
    result read back. On any failure the file is written again with less carried over:
    without the analog channels, then without any parameter of the input.

    Returns:
        The note naming what was left out ([] when nothing).
    """
    if source.section is None:
        write_stage(tmp, None)
        return source.notes(out)
    for analogs in ([source.analogs] if source.analogs is not None else []) + [None]:
        if analogs is None:
            write_stage(tmp, None)  # the plain file: its errors are the writer's
        try:
            if analogs is not None:
                write_stage(tmp, analogs)
            carry_over(tmp, source, trial, analogs)
            return source.notes(out)
        except Exception as exc:  # ezc3d's own errors are of many types; nothing may stop the write
            reason = str(exc) if isinstance(exc, (CarryError, SectionError)) else _first_sentence(str(exc))
            source.lose(source.channel_parts() if analogs is not None else ["parameters"], reason)
    write_stage(tmp, None)
    return source.notes(out)


def carry_over(tmp: Path, source: Source, trial: Trial, analogs: Analogs | None) -> None:
    """Replace ``tmp``'s parameter section by the merge of its own and the input's, then
    read it back with ezc3d (analog values compared with the input's).

    Raises:
        CarryError, SectionError: the merged section cannot be written, or the file does
            not read back as it should.
    """
    assert source.section is not None
    data = tmp.read_bytes()
    carry_channels = analogs is not None or "analog channels" not in source.channel_parts()
    merged = merge(read_section(data), source, trial, carry_channels=carry_channels)
    result = bytearray(splice(data, merged))
    if analogs is not None:
        put_samples(result, analogs)
    tmp.write_bytes(result)
    check(tmp, analogs)


def put_samples(data: bytearray, analogs: Analogs) -> None:
    """Write the stored analog samples into the data block of the float C3D ``data``
    (ezc3d laid it out: per frame the points, 4 floats each, then the analog subframes),
    as float32 bit for bit (ezc3d's own writer turns -0.0 into 0.0).

    Raises:
        CarryError: the data block is not laid out for these samples.
    """
    points, per_frame = struct.unpack("<2H", data[2:6])
    (start,) = struct.unpack("<H", data[16:18])
    channels, samples = analogs.stored.shape
    frames = samples // analogs.per_frame
    words = 4 * points + per_frame
    at = (start - 1) * BLOCK
    if per_frame != channels * analogs.per_frame or len(data) < at + 4 * words * frames:
        raise CarryError("the written data block has no room for the analog samples")
    block = np.frombuffer(data, dtype="<f4", count=words * frames, offset=at).reshape(frames, words).copy()
    block[:, 4 * points :] = (
        analogs.stored.reshape(channels, frames, analogs.per_frame).transpose(1, 2, 0).reshape(frames, -1)
    )
    data[at : at + block.nbytes] = block.astype("<f4").tobytes()


def merge(written: Section, source: Source, trial: Trial, *, carry_channels: bool) -> Section:
    """The written file's section with the input's carried over (module docstring);
    ``carry_channels``: the input's analog samples (if any) are in the written file, else
    its channel groups are left out (nothing may refer to absent channels)."""
    assert source.section is not None
    parts = source.channel_parts()
    dropped = set() if carry_channels else {g for g, part in zip(CHANNEL_GROUPS, _CHANNEL_PARTS) if part in parts}
    merged: Section = {}
    for key, group in source.section.items():
        if key in OWNED_GROUPS or key in dropped or (key == "EVENT" and not source.same_events):
            continue
        if not group.name:  # a nameless group cannot be written
            if group.parameters:
                source.lose(["parameters of a nameless group"], "a group without a name cannot be written")
            continue
        if key in CHANNEL_GROUPS or key == "EVENT":
            params = dict(group.parameters)
        else:
            params = _merge_group(key, group, written.get(key, Group(group.name)), source, trial)
        merged[key] = replace(group, parameters=params)
    for key, group in written.items():
        merged.setdefault(key, group)
    return merged


def _merge_group(key: str, group: Group, mine: Group, source: Source, trial: Trial) -> dict[str, Parameter]:
    """One group: the input's parameters in its order (the writer's where it owns or
    changed them), then the writer's others."""
    params: dict[str, Parameter] = {}
    for name, theirs in group.parameters.items():
        ours = mine.parameters.get(name)
        if key == "POINT" and owned_point(name):
            chosen = _point_record(name, ours, theirs)
        elif (key, name) in _FRAME_PARAMETERS and not source.same_frames:
            chosen = _FRAME_PARAMETERS[(key, name)](theirs, trial)
        elif ours is not None and ours.value() != theirs.value():
            chosen = ours
        else:
            chosen = theirs
        if chosen is not None:
            params[name] = chosen
    for name, ours in mine.parameters.items():
        params.setdefault(name, ours)
    return params


def _point_record(name: str, ours: Parameter | None, theirs: Parameter) -> Parameter | None:
    """An owned ``POINT`` parameter: the writer's value with the input's description and
    lock flag; an output-unit parameter the writer did not write (``SCALAR_UNITS`` of a
    file with no scalars) is the input's."""
    if ours is None:
        return theirs if name.upper() in OUTPUT_UNIT_PARAMETERS else None
    return replace(ours, description=theirs.description or ours.description, locked=theirs.locked)


def _frame_field(which: str) -> Callable[[Parameter, Trial], Parameter | None]:
    """Vicon's ``TRIAL:ACTUAL_START_FIELD``/``END_FIELD`` (a frame number in two 16-bit
    words) for the trial's first or last frame; dropped if not stored that way."""

    def rewrite(param: Parameter, trial: Trial) -> Parameter | None:
        frame = trial.first_frame + (trial.n_frames - 1 if which == "end" else 0)
        if param.kind != 2 or param.dims != (2,):
            return None
        return replace(int16s([frame % 65536, frame // 65536]), name=param.name, description=param.description,
                       locked=param.locked)  # fmt: skip

    return rewrite


def _long_frames(param: Parameter, trial: Trial) -> Parameter | None:
    """``POINT:LONG_FRAMES`` (a float frame count) for the trial's frames."""
    if param.kind != 4 or len(param.numbers()) != 1:
        return None
    return replace(param, data=struct.pack("<f", float(trial.n_frames)))


#: Parameters holding the input's frame range: rewritten when the trial covers others.
_FRAME_PARAMETERS: dict[tuple[str, str], Callable[[Parameter, Trial], Parameter | None]] = {
    ("TRIAL", "ACTUAL_START_FIELD"): _frame_field("start"),
    ("TRIAL", "ACTUAL_END_FIELD"): _frame_field("end"),
    ("POINT", "LONG_FRAMES"): _long_frames,
}


def splice(data: bytes, section: Section) -> bytes:
    """The ezc3d-written file ``data`` with its parameter section replaced by
    ``section``: the header's and ``POINT:DATA_START``'s data-start block (and
    ``ROTATION:DATA_START``) moved by the change in the section's size.

    Raises:
        SectionError: the section does not fit (:func:`section_bytes`).
    """
    params_at = data[0]  # the parameter section's first block (1-based)
    (old_start,) = struct.unpack("<H", data[16:18])
    blocks = section_bytes(section)[2]
    new_start = params_at + blocks
    for group, name in (("POINT", "DATA_START"), ("ROTATION", "DATA_START")):
        param = section.get(group, Group(group)).parameters.get(name)
        if param is not None and param.kind == 2 and param.data:
            value = int(param.numbers()[0])
            moved = new_start if group == "POINT" else (value % 65536) + new_start - old_start if value else 0
            word = struct.pack("<H", moved % 65536)  # an unsigned block number in a 16-bit integer
            section[group].parameters[name] = replace(param, data=word + param.data[2:])
    header = bytearray(data[: (params_at - 1) * BLOCK])
    header[16:18] = struct.pack("<H", new_start)
    return bytes(header) + section_bytes(section) + data[(old_start - 1) * BLOCK :]


def check(path: Path, analogs: Analogs | None) -> None:
    """Read ``path`` back with ezc3d: it must read (without doubts) and, when analog
    channels were carried over, give the input's analog values bit for bit.

    Raises:
        CarryError: it does not.
    """
    import ezc3d

    layout = inspect(path)
    if layout.doubts:
        raise CarryError(f"the written file would not read back: {layout.doubts[0]}")
    try:
        c = ezc3d.c3d(str(path))
    except Exception as exc:  # ezc3d raises ValueError, RuntimeError, ...
        raise CarryError(f"ezc3d cannot read the written file back: {_first_sentence(str(exc))}") from None
    if analogs is not None:
        got = np.asarray(c["data"]["analogs"], dtype=float)[0]
        if not same_bits(got, analogs.values):
            raise CarryError("ezc3d reads other analog values back from the written file")
