"""Pure-Python sanity pass over a C3D file's header and parameter section.

ezc3d (C++) trusts the file: a parameter whose dimension count is corrupt makes it loop
for minutes, an analog group that declares more channels than it has scales or offsets
makes it read outside its own arrays (a segmentation fault, which no ``try`` can catch).
:func:`inspect` walks the header and the parameter records the way ezc3d does, in
milliseconds and without trusting any count, and lists every *doubt*: a reason why ezc3d
should not be run in the reading process. It never refuses a file by itself -- a file
with doubts is still given to the pure-Python ``c3d`` package and, if that refuses it
too, to ezc3d in a child process with a time limit (:mod:`fuzzygait.io.c3d_backends`).

What is checked, and why:

* the header's parameter-block pointer and the processor byte of the parameter section
  (84 Intel, 85 DEC, 86 SGI/MIPS): ezc3d and the ``c3d`` package read every number of the
  file in that format; a wrong byte gives garbage or, in the ``c3d`` package, an internal
  error;
* every group and parameter record, walked through the records' "offset to next" chain
  as ezc3d does: the record must lie inside the file, its name must be printable, a
  group's description must fill its record exactly (a parameter record whose group
  number turned negative reads as a group, on which ezc3d crashes), a parameter's type
  one of -1, 1, 2, 4, and its data (the product of its dimensions times the element size,
  plus the description) must fit inside its record -- this bounds every dimension by the
  section's size, so a corrupt dimension count can no longer announce 10^80 elements;
* the ``ANALOG`` group: when analog channels are declared (header or ``ANALOG:USED``),
  ``ANALOG:SCALE`` and ``ANALOG:OFFSET`` must hold a value per channel (ezc3d indexes
  them per channel without bounds checks);
* the header's point and analog counts against ``POINT:USED`` and ``ANALOG:USED``.

It also gives the raw values of the parameters the reader reports on (``POINT:FRAMES``
as stored -- ezc3d rewrites it to what it read --, ``POINT:SCALE``, ``POINT:DATA_START``)
and the number of frames the data block can hold given the file's size, so that
truncation and header/parameter disagreements become notes (:func:`frame_notes`).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

BLOCK = 512  # bytes per C3D block
PROCESSORS = {84: "Intel", 85: "DEC", 86: "SGI/MIPS"}
_ELEMENT_SIZE = {-1: 1, 1: 1, 2: 2, 4: 4}
_NAME_BYTES = frozenset(range(0x20, 0x7F))  # printable ASCII
#: Bytes read for the pass: a parameter section starts within 255 blocks and spans at
#: most 255 blocks, so this covers it in any file (the data block is never read).
_HEAD_BYTES = 2 * 255 * BLOCK + BLOCK
_MAX_DIMS = 7  # the C3D manual's limit; ezc3d nests one loop per dimension


@dataclass(frozen=True)
class RawParameter:
    """One parameter record as stored: ``kind`` -1 (char), 1 (byte), 2 (int16), 4 (float)."""

    kind: int
    dims: tuple[int, ...]
    data: bytes
    position: int = 0  # byte offset of the record (its name-length byte) in the file


@dataclass
class Layout:
    """What the sanity pass found.

    Attributes:
        size: file size, bytes.
        processor: the processor byte (84, 85, 86), 0 when unreadable.
        point_count, analog_count: header words 2 and 3 (points; analog samples per frame).
        first_frame, last_frame: header frame numbers (1-based, unsigned 16-bit).
        header_scale: header point scale (negative: float data), NaN if unreadable.
        header_rate: header point rate, Hz.
        data_start: header data-start block (1-based).
        parameters: ``{(GROUP, NAME): RawParameter}`` (a repeated name keeps the last,
            as ezc3d does).
        doubts: reasons not to run ezc3d in this process (empty: the file is safe for it).
        repeated: ``GROUP:NAME`` of parameters stored more than once.
        broken: a doubt concerns the header or the parameter records themselves.
        notes: things a user should know that do not stop ezc3d (the record chain ending
            before the section does, header frame numbers that disagree with ``TRIAL``).
    """

    size: int
    processor: int = 0
    point_count: int = 0
    analog_count: int = 0
    first_frame: int = 0
    last_frame: int = 0
    header_scale: float = float("nan")
    header_rate: float = float("nan")
    data_start: int = 0
    parameters: dict[tuple[str, str], RawParameter] = field(default_factory=dict)
    doubts: list[str] = field(default_factory=list)
    repeated: list[str] = field(default_factory=list)
    broken: bool = False
    notes: list[str] = field(default_factory=list)

    def doubt(self, reason: str, *, broken: bool = False) -> None:
        """Record a reason not to run ezc3d here; ``broken``: the header or the record
        chain itself is damaged (ezc3d cannot read such a file either)."""
        self.doubts.append(reason)
        self.broken = self.broken or broken

    # ----------------------------------------------------------------- values
    def number(self, group: str, name: str) -> float | None:
        """First value of a numeric parameter (None if absent, empty or textual)."""
        values = self.numbers(group, name)
        return values[0] if values else None

    def numbers(self, group: str, name: str) -> list[float]:
        """All values of a numeric parameter, in storage order ([] if absent or textual)."""
        param = self.parameters.get((group, name))
        if param is None or param.kind == -1:
            return []
        count = len(param.data) // _ELEMENT_SIZE[param.kind]
        endian = ">" if self.processor == 86 else "<"
        if param.kind == 1:
            return [float(v) for v in struct.unpack(f"{count}b", param.data[:count])]
        if param.kind == 2:
            return [float(v) for v in struct.unpack(f"{endian}{count}h", param.data[: 2 * count])]
        return [self._float(param.data[4 * i : 4 * i + 4]) for i in range(count)]

    def _float(self, raw: bytes) -> float:
        if self.processor == 85:
            return _dec_float(raw)
        return float(struct.unpack(">f" if self.processor == 86 else "<f", raw)[0])

    # ----------------------------------------------------------------- frames
    def declared_frames(self) -> tuple[int | None, int | None]:
        """``(header count, POINT:FRAMES)``: frames announced by the header
        (last - first + 1) and by the parameter (as stored; None when absent)."""
        header = self.last_frame - self.first_frame + 1 if self.last_frame >= self.first_frame > 0 else None
        frames = self.number("POINT", "FRAMES")
        param = None
        if frames is not None and frames == frames:  # not NaN
            kind = self.parameters[("POINT", "FRAMES")].kind
            param = int(frames) + 65536 if kind == 2 and frames < 0 else int(frames)  # unsigned 16-bit
        return header, param

    def frame_size(self) -> int | None:
        """Bytes per frame of the data block (None when unknown or zero)."""
        scale = self.number("POINT", "SCALE")
        scale = self.header_scale if scale is None else scale
        if scale != scale or self.data_start <= 0:
            return None
        word = 4 if scale < 0 else 2
        frame_bytes = word * (4 * self.point_count + self.analog_count)
        return frame_bytes if frame_bytes > 0 else None

    def frames_in_file(self) -> int | None:
        """Whole frames the data block can hold between its start and the end of the
        file (None when the frame size is unknown or zero)."""
        frame_bytes = self.frame_size()
        if frame_bytes is None:
            return None
        return max(0, self.size - (self.data_start - 1) * BLOCK) // frame_bytes


def _dec_float(raw: bytes) -> float:
    """A DEC (VAX F) float, converted by the ``c3d`` package's own routine."""
    from c3d.c3d import DEC_to_IEEE

    return float(DEC_to_IEEE(struct.unpack("<I", raw)[0]))


def inspect(path: Path) -> Layout:
    """Walk ``path``'s header and parameter section without trusting any count.

    Never raises on a damaged file (only ``OSError`` when it cannot be opened): every
    problem becomes a doubt in :attr:`Layout.doubts`.
    """
    with open(path, "rb") as handle:
        head = handle.read(_HEAD_BYTES)
        size = handle.seek(0, 2)
    return inspect_bytes(head, size)


def inspect_bytes(data: bytes, size: int | None = None) -> Layout:
    """:func:`inspect` of a file's first bytes (all of it, or at least the first
    :data:`_HEAD_BYTES`); ``size``: the whole file's size (default ``len(data)``)."""
    layout = Layout(size=len(data) if size is None else size)
    if len(data) < BLOCK:
        layout.doubt("the file is shorter than one 512-byte block", broken=True)
        return layout
    start = (data[0] - 1) * BLOCK
    if data[0] == 0 or start + 4 > len(data):
        layout.doubt(f"the header's parameter-section pointer (block {data[0]}) lies outside the file", broken=True)
        return layout
    layout.processor = data[start + 3] if data[start + 3] in PROCESSORS else 0
    if not layout.processor:
        layout.doubt(
            f"unknown processor type byte {data[start + 3]} in the parameter section "
            "(expected 84 Intel, 85 DEC or 86 SGI/MIPS)",
            broken=True,
        )
        return layout
    if data[1] != 0x50:
        layout.doubt(f"the header's key byte is {data[1]}, not 80")
    _read_header(data, layout)
    if layout.processor == 86:  # ezc3d refuses this format at once; the c3d package reads it
        layout.doubt("SGI/MIPS processor format, which ezc3d does not read")
        end = start + BLOCK * data[start + 2]
        _walk_parameters(data[:end], start + 4, Layout(size=layout.size, processor=86), into=layout)
    else:
        _walk_parameters(data, start + 4, layout)
    _check_counts(layout)
    _check_trial_frames(layout)
    _check_header_agreement(layout)
    return layout


def _read_header(data: bytes, layout: Layout) -> None:
    endian = ">" if layout.processor == 86 else "<"
    words = struct.unpack(f"{endian}4H", data[2:10])
    layout.point_count, layout.analog_count, layout.first_frame, layout.last_frame = words
    layout.header_scale = layout._float(data[12:16])
    layout.header_rate = layout._float(data[20:24])
    (layout.data_start,) = struct.unpack(f"{endian}H", data[16:18])


def _walk_parameters(data: bytes, pos: int, layout: Layout, into: Layout | None = None) -> None:
    """Follow the record chain as ezc3d does (for SGI files, which only the ``c3d``
    package reads, ``data`` ends with the section as that package reads it), checking
    each record's bounds."""
    endian = ">" if layout.processor == 86 else "<"
    groups: dict[int, str] = {}
    pending: list[tuple[int, str, RawParameter]] = []
    for _ in range(100_000):  # every record moves forward (checked below)
        if pos + 2 > len(data):
            layout.doubt(f"the parameter section runs past the end of the file (byte {pos})", broken=True)
            break
        n_chars, group_id = struct.unpack("bb", data[pos : pos + 2])
        if n_chars == 0 or group_id == 0:
            _check_tail(data, pos, layout)
            break
        name_end = pos + 2 + abs(n_chars)
        raw_name = data[pos + 2 : name_end]
        if name_end + 2 > len(data):
            layout.doubt(f"the parameter section runs past the end of the file (byte {pos})", broken=True)
            break
        if not raw_name or any(b not in _NAME_BYTES for b in raw_name):
            layout.doubt(f"garbled parameter record at byte {pos} (name {raw_name!r})", broken=True)
            break
        name = raw_name.decode("ascii").strip().upper()
        (offset,) = struct.unpack(f"{endian}H", data[name_end : name_end + 2])
        body = name_end + 2
        next_pos = body + offset - 2 if offset else 0
        record_end = next_pos if offset else len(data)
        if offset and (offset < 2 or next_pos > len(data)):
            layout.doubt(f"parameter record {name} at byte {pos} points outside the file", broken=True)
            break
        if group_id < 0:
            if offset and (body + 1 > len(data) or offset != 3 + data[body]):
                layout.doubt(
                    f"group record {name} at byte {pos} is malformed (its description does not fill its record)",
                    broken=True,
                )
                break
            groups[-group_id] = name
        else:
            param = _read_parameter(data, body, record_end, name, layout, pos, exact=bool(offset))
            if param is not None:  # a bad record is skipped, as the c3d package does
                pending.append((group_id, name, param))
        if not offset:
            break
        if next_pos <= pos:  # pragma: no cover - offset >= 2 always moves forward
            break
        pos = next_pos
    if into is not None:  # keep the values, drop the doubts (see inspect)
        layout = into
    for group_id, name, param in pending:
        group = groups.get(group_id)
        if group is None:
            layout.doubt(f"parameter {name} belongs to group number {group_id}, which is not defined")
            continue
        if (group, name) in layout.parameters:
            layout.repeated.append(f"{group}:{name}")
        layout.parameters[(group, name)] = param


def _check_tail(data: bytes, pos: int, layout: Layout) -> None:
    """A chain that ends (a zero name length) well before the section's declared end,
    with non-zero bytes after it, has lost the parameters stored there."""
    start = (data[0] - 1) * BLOCK
    end = min(len(data), start + BLOCK * data[start + 2])
    left = sum(1 for b in data[pos:end] if b)
    if left > 16:
        layout.notes.append(
            f"the parameter records stop at byte {pos} but {left} non-zero bytes follow in the parameter "
            "section: parameters stored after that point are lost (damaged file?)"
        )


def _read_parameter(
    data: bytes, body: int, record_end: int, name: str, layout: Layout, position: int, exact: bool
) -> RawParameter | None:
    """The parameter record whose body (type byte) is at ``body``; ``exact``: the record
    has a successor, so data and description must end exactly at ``record_end``."""
    if body + 2 > record_end:
        layout.doubt(f"parameter {name} (byte {body}) is cut short", broken=True)
        return None
    kind, n_dims = struct.unpack("bB", data[body : body + 2])
    if kind not in _ELEMENT_SIZE:
        layout.doubt(f"parameter {name} has an invalid data type {kind}", broken=True)
        return None
    dims = tuple(data[body + 2 : body + 2 + n_dims])
    count, loops = 1, 0
    for d in dims:
        count *= d
        loops = max(loops, count)  # ezc3d iterates the leading dimensions even if a later one is 0
    if n_dims > _MAX_DIMS or loops > max(65536, record_end - body):
        layout.doubt(
            f"parameter {name} declares {n_dims} dimensions {list(dims[:8])}{'...' if n_dims > 8 else ''} "
            f"(at most {_MAX_DIMS} bounded by its record's {record_end - body} bytes are valid)",
            broken=True,
        )
        return None
    size = count * _ELEMENT_SIZE[kind]
    data_start = body + 2 + n_dims
    if data_start + size + 1 > record_end:
        layout.doubt(
            f"parameter {name} declares {n_dims} dimensions {list(dims[:8])}{'...' if n_dims > 8 else ''} "
            f"({size} bytes), more than its record holds ({max(0, record_end - data_start)} bytes)",
            broken=True,
        )
        return None
    end = data_start + size + 1 + data[data_start + size]  # after the description
    if exact and end != record_end:  # ezc3d refuses such a record ("not standard"), after up to 20 s
        layout.doubt(
            f"parameter {name}'s data and description ({end - body} bytes) do not fill its record "
            f"({record_end - body} bytes)",
            broken=True,
        )
    elif not exact:  # the last record: nothing but padding may follow it in the section
        _check_tail(data, end, layout)
    if kind == -1 and not n_dims:
        layout.doubt(f"character parameter {name} has no dimensions (ezc3d crashes on it)")
    return RawParameter(kind, dims, data[data_start : data_start + size], position)


def _check_trial_frames(layout: Layout) -> None:
    """The header's first and last frame numbers: in order, and equal to Vicon's
    ``TRIAL:ACTUAL_START_FIELD``/``ACTUAL_END_FIELD`` (two 16-bit words each) when
    present (ezc3d uses the header's, the ``c3d`` package the ``TRIAL`` ones)."""
    if layout.first_frame > layout.last_frame or layout.first_frame == 0:
        layout.notes.append(
            f"the header's first frame number {layout.first_frame} is not between 1 and its last, {layout.last_frame}"
        )
    for name, header in (("ACTUAL_START_FIELD", layout.first_frame), ("ACTUAL_END_FIELD", layout.last_frame)):
        words = [int(w) % 65536 for w in layout.numbers("TRIAL", name)[:2]]
        if len(words) == 2 and layout.parameters[("TRIAL", name)].kind == 2:
            value = words[0] + 65536 * words[1]
            if value != header:
                which = "first" if name == "ACTUAL_START_FIELD" else "last"
                layout.notes.append(f"the header's {which} frame number {header} differs from TRIAL:{name} = {value}")


def _check_header_agreement(layout: Layout) -> None:
    """Rate and scale stored twice (header and ``POINT``) that disagree: the readers
    use different copies (ezc3d the header's sign of the scale, the ``c3d`` package the
    parameters), so the result depends on the reader -- worth a note."""
    rate = layout.number("POINT", "RATE")
    if rate is not None and layout.header_rate == layout.header_rate and not _close(rate, layout.header_rate):
        layout.notes.append(f"the header's rate {layout.header_rate:g} Hz differs from POINT:RATE = {rate:g} Hz")
    scale = layout.number("POINT", "SCALE")
    head = layout.header_scale
    if scale is None or head != head or scale != scale:
        return
    if (scale < 0) != (head < 0):
        layout.notes.append(
            f"the header's scale {head:g} and POINT:SCALE = {scale:g} disagree on whether the data are "
            "floating point (negative) or scaled integers"
        )
    elif scale > 0 and not _close(scale, head):
        layout.notes.append(f"the header's scale {head:g} differs from POINT:SCALE = {scale:g}")


def _close(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-6 * max(abs(a), abs(b))


def _check_counts(layout: Layout) -> None:
    """Doubts about the point and analog counts ezc3d sizes its arrays from."""
    used = layout.number("POINT", "USED")
    if used is not None and int(used) % 65536 != layout.point_count:
        layout.doubt(f"the header declares {layout.point_count} points but POINT:USED says {int(used)}")
    analog_used = layout.number("ANALOG", "USED")
    channels = int(analog_used) if analog_used is not None else 0
    if layout.analog_count and not channels:
        layout.doubt(
            f"the header declares {layout.analog_count} analog samples per frame but ANALOG:USED is 0 or absent"
        )
    if channels < 0:
        layout.doubt(f"ANALOG:USED is negative ({channels})")
    elif channels:
        if layout.analog_count % channels:
            layout.doubt(
                f"the header's {layout.analog_count} analog samples per frame are not a multiple "
                f"of ANALOG:USED = {channels}"
            )
        for name in ("SCALE", "OFFSET"):
            have = len(layout.numbers("ANALOG", name))
            if have < channels:
                layout.doubt(f"ANALOG:{name} holds {have} values for {channels} analog channels")
