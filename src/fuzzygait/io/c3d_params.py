"""A C3D parameter section as records: read from any file (Intel, DEC or SGI/MIPS
processor format, converted to Intel), merged, and written back byte for byte.

ezc3d's Python API cannot write every parameter back as the file held it (it turns
byte parameters into integers and integer lists into floats, flattens character arrays
of more than two dimensions, strips padding, and never writes ``ANALOG:OFFSET``), so
:mod:`fuzzygait.io.c3d_writeback` copies the records of an input file through this
module instead: a record's type, dimensions, data, description and lock flag are kept
exactly (numbers only converted to the Intel format the written file uses).

:func:`event_parameters` gives the writer's ``EVENT`` group for any number of events
(C3D's ``NAME2`` convention beyond 255), :func:`check_blocks` refuses a written file
whose parameter section does not fit its one-byte block count.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from fuzzygait.io.c3d_guard import BLOCK

if TYPE_CHECKING:
    from fuzzygait.core.trial import Event

_ELEMENT = {-1: 1, 1: 1, 2: 2, 4: 4}  # bytes per element of each parameter type
_MAX_BLOCKS = 255  # the section's block count is one byte
_MAX_BODY = 32765  # the offset to the next record is a signed 16-bit word (body + 2)
PER_PARAMETER = 255  # entries of one parameter (a dimension is one byte); more go to NAME2, NAME3, ...
_MAX_EVENTS = 32767  # EVENT:USED is a signed 16-bit integer


class SectionError(Exception):
    """The parameter section cannot be read or written (message: why)."""


@dataclass(frozen=True)
class Parameter:
    """One parameter record (Intel format).

    Attributes:
        name: name as stored (case kept).
        kind: -1 char, 1 byte, 2 16-bit integer, 4 float.
        dims: dimensions, first index fastest.
        data: the values, ``prod(dims)`` elements of ``kind``'s size.
        description: description bytes.
        locked: the record's lock flag (a negative name length).
    """

    name: str
    kind: int
    dims: tuple[int, ...]
    data: bytes
    description: bytes = b""
    locked: bool = False

    def numbers(self) -> np.ndarray:
        """The values of a numeric parameter, flat in storage order (float64)."""
        dtype = {1: "<i1", 2: "<i2", 4: "<f4"}[self.kind]
        return np.frombuffer(self.data, dtype=dtype).astype(float)

    def strings(self) -> list[str]:
        """A character parameter as strings, as ezc3d reads it: one per column of the
        first dimension (``prod(dims[1:])`` of them), trailing blanks and NULs stripped;
        a 1-dimensional one is one string, none when it is empty."""
        text = self.data.decode("latin-1")
        if len(self.dims) < 2:
            return [text.rstrip(" \x00")] if text else []
        width, count = self.dims[0], int(np.prod(self.dims[1:]))
        return [text[i * width : (i + 1) * width].rstrip(" \x00") for i in range(count)]

    def value(self) -> tuple[object, ...]:
        """The value for comparisons: strings or numbers, whatever the storage type (no
        strings and only empty ones alike: ezc3d's Python API stores ``[""]`` as nothing)."""
        if self.kind == -1:
            strings = tuple(self.strings())
            return strings if any(strings) else ()
        return tuple(float(v) for v in self.numbers())


@dataclass
class Group:
    """A group record and its parameters (keyed by upper-case name, in file order)."""

    name: str
    description: bytes = b""
    locked: bool = False
    parameters: dict[str, Parameter] = field(default_factory=dict)


#: A parameter section: groups keyed by upper-case name, in file order.
Section = dict[str, Group]


# --------------------------------------------------------------------------- reading
def read_section(data: bytes) -> Section:
    """The parameter section of a whole C3D file's bytes ``data``, numbers converted to
    the Intel format. Call it only on files :func:`fuzzygait.io.c3d_guard.inspect` finds
    not ``broken``.

    Raises:
        SectionError: a record lies outside the file or is malformed.
    """
    start = (data[0] - 1) * BLOCK
    processor = data[start + 3] if start + 4 <= len(data) else 0
    if processor not in (84, 85, 86):
        raise SectionError(f"unknown processor type {processor}")
    endian = ">" if processor == 86 else "<"
    if processor == 86:  # as the c3d package (the only reader of this format) reads it: the declared blocks
        data = data[: start + BLOCK * data[start + 2]]
    groups: dict[int, Group] = {}
    pending: list[tuple[int, Parameter]] = []
    pos = start + 4
    while pos + 2 <= len(data):
        n_chars, group_id = struct.unpack("bb", data[pos : pos + 2])
        if n_chars == 0 or group_id == 0:
            break
        name_end = pos + 2 + abs(n_chars)
        name = data[pos + 2 : name_end].decode("ascii", "replace").strip()
        (offset,) = struct.unpack(f"{endian}H", data[name_end : name_end + 2])
        body = name_end + 2
        end = name_end + offset if offset else len(data)
        if group_id < 0:
            groups[-group_id] = Group(name, _description(data, body, end), n_chars < 0)
        else:
            pending.append((group_id, _parameter(data, body, end, name, n_chars < 0, processor)))
        if not offset:
            break
        pos = name_end + offset
    section: Section = {}
    for group in groups.values():
        section.setdefault(group.name.upper(), group)
    by_id = {gid: section[g.name.upper()] for gid, g in groups.items()}
    for group_id, param in pending:
        if group_id in by_id:  # a parameter of an undefined group is lost (as in ezc3d)
            by_id[group_id].parameters[param.name.upper()] = param  # a repeated name keeps the last
    return section


def _description(data: bytes, at: int, end: int) -> bytes:
    if at >= min(end, len(data)):
        return b""
    return data[at + 1 : at + 1 + data[at]]


def _parameter(data: bytes, body: int, end: int, name: str, locked: bool, processor: int) -> Parameter:
    if body + 2 > len(data):
        raise SectionError(f"parameter {name} is cut short")
    kind, n_dims = struct.unpack("bB", data[body : body + 2])
    if kind not in _ELEMENT:
        raise SectionError(f"parameter {name} has an invalid type {kind}")
    dims = tuple(data[body + 2 : body + 2 + n_dims])
    count = int(np.prod(dims)) if dims else 1
    at = body + 2 + n_dims
    values = data[at : at + count * _ELEMENT[kind]]
    if len(values) != count * _ELEMENT[kind]:
        raise SectionError(f"parameter {name} is cut short")
    description = _description(data, at + len(values), end)
    if kind == -1 and not dims:  # a character "scalar" (ezc3d crashes on it): its one character as a string
        dims = (len(values),)
    return Parameter(name, kind, dims, _to_intel(values, kind, processor), description, locked)


def _to_intel(values: bytes, kind: int, processor: int) -> bytes:
    """Numbers of ``kind`` stored by ``processor`` (84 Intel, 85 DEC, 86 SGI/MIPS) as
    Intel (little-endian IEEE) bytes."""
    if kind in (-1, 1) or processor == 84 or (processor == 85 and kind == 2):
        return values
    if processor == 86:  # big-endian
        code = "i2" if kind == 2 else "f4"
        return np.frombuffer(values, dtype=f">{code}").astype(f"<{code}").tobytes()
    return dec_to_ieee(values).tobytes()


def dec_to_ieee(values: bytes) -> np.ndarray:
    """DEC (VAX F) floats as little-endian IEEE float32: the two 16-bit halves swapped,
    the value divided by 4 (DEC's exponent bias is 2 larger and its mantissa 0.1f)."""
    halves = np.frombuffer(values, dtype="<u2").reshape(-1, 2)[:, ::-1]
    ieee = np.ascontiguousarray(halves).view("<f4").ravel()
    return (ieee / np.float32(4.0)).astype("<f4")


# --------------------------------------------------------------------------- writing
def section_bytes(section: Section) -> bytes:
    """``section`` as a parameter section (Intel): the 4-byte start, the records, a
    terminating zero name length, padded to whole 512-byte blocks.

    Raises:
        SectionError: more than 127 groups, a record too long for its 16-bit offset, or
            more than 255 blocks.
    """
    if len(section) > 127:
        raise SectionError(f"{len(section)} parameter groups (at most 127 fit)")
    records = []
    for gid, group in enumerate(section.values(), start=1):
        records.append(_record(group.name, -gid, group.locked, bytes([len(group.description)]) + group.description))
        for p in group.parameters.values():
            head = struct.pack("bB", p.kind, len(p.dims)) + bytes(p.dims)
            records.append(_record(p.name, gid, p.locked, head + p.data + bytes([len(p.description)]) + p.description))
    body = b"".join(records) + b"\x00\x00"
    blocks = -(-(4 + len(body)) // BLOCK)
    if blocks > _MAX_BLOCKS:
        raise SectionError(f"the parameters need {blocks} blocks of 512 bytes (at most {_MAX_BLOCKS} fit)")
    head = bytes([1, 0x50, blocks, 84])
    return (head + body).ljust(blocks * BLOCK, b"\x00")


def _record(name: str, group_id: int, locked: bool, body: bytes) -> bytes:
    raw = name.encode("ascii", "replace")
    if len(body) > _MAX_BODY or not 0 < len(raw) < 128:
        raise SectionError(f"parameter record {name!r} cannot be stored ({len(body)} bytes)")
    head = struct.pack("<bb", -len(raw) if locked else len(raw), group_id)
    return head + raw + struct.pack("<H", len(body) + 2) + body


def int16s(values: list[int]) -> Parameter:
    """A nameless 16-bit integer vector parameter holding ``values`` (each taken modulo
    2**16, as C3D stores unsigned words); :func:`dataclasses.replace` names it."""
    words = [((v + 32768) % 65536) - 32768 for v in values]
    return Parameter("", 2, (len(words),), struct.pack(f"<{len(words)}h", *words))


def with_data(param: Parameter, data: bytes) -> Parameter:
    """``param`` with its values replaced by ``data`` (same type and dimensions)."""
    return replace(param, data=data)


# --------------------------------------------------------------------------- events
def event_parameters(events: Sequence[Event]) -> list[tuple[str, object]]:
    """``(name, value)`` of the ``EVENT`` parameters for ezc3d's ``add_parameter``, in
    the order, types and values ezc3d's ``add_event`` writes them (``USED``, ``TIMES``
    as minutes and seconds, ``CONTEXTS``, ``LABELS``, ``DESCRIPTIONS``, ``SUBJECTS``,
    ``ICON_IDS``, ``GENERIC_FLAGS``); beyond 255 events the next 255 go to ``TIMES2``,
    ``CONTEXTS2``, ..., then ``TIMES3``, ... (C3D's convention for ``POINT:LABELS2``;
    ``add_event`` would store the count modulo 256), ``USED`` counting them all.

    Raises:
        SectionError: more events than ``EVENT:USED`` can count.
    """
    if not events:
        return []
    if len(events) > _MAX_EVENTS:
        raise SectionError(f"{len(events)} events: EVENT:USED counts at most {_MAX_EVENTS}; split the trial")
    minutes, seconds = zip(*(divmod(float(e.time), 60.0) for e in events))
    columns: dict[str, np.ndarray] = {
        "TIMES": np.array([minutes, seconds], dtype=float),
        "CONTEXTS": np.array([e.context for e in events]),
        "LABELS": np.array([e.label for e in events]),
        "DESCRIPTIONS": np.array([e.description for e in events]),
        "SUBJECTS": np.array([e.subject for e in events]),
        "ICON_IDS": np.array([e.icon_id() for e in events], dtype=float),  # stored as integers: integer_records
        "GENERIC_FLAGS": np.array([e.flag for e in events], dtype=float),
    }
    params: list[tuple[str, object]] = [("USED", len(events))]
    for part, start in enumerate(range(0, len(events), PER_PARAMETER), start=1):
        suffix = str(part) if part > 1 else ""
        params += [(name + suffix, values[..., start : start + PER_PARAMETER]) for name, values in columns.items()]
    return params


#: ``EVENT`` parameters Vicon stores as integers (ezc3d's Python API writes floats): C3D type.
EVENT_INTEGER_KINDS = {"ICON_IDS": 2, "GENERIC_FLAGS": 1}


def integer_event_records(section: Section) -> bool:
    """Store the ``EVENT`` group's float ``ICON_IDS`` (as 16-bit integers) and
    ``GENERIC_FLAGS`` (as bytes), their continuations ``ICON_IDS2`` ... too, as Vicon
    Nexus does; True if a record changed."""
    group = section.get("EVENT")
    changed = False
    for name, param in list(group.parameters.items()) if group is not None else []:
        kind = EVENT_INTEGER_KINDS.get(name.upper().rstrip("0123456789"))
        if kind is None or param.kind != 4:
            continue
        values = [int(v) for v in np.rint(param.numbers())]
        data = struct.pack(f"<{len(values)}h", *values) if kind == 2 else bytes(v % 256 for v in values)
        # one event: a 1-vector, as Vicon and ezc3d's add_event store it (ezc3d's add_parameter: a scalar)
        group.parameters[name] = replace(param, kind=kind, dims=param.dims or (len(values),),  # type: ignore[union-attr]
                                         data=data)  # fmt: skip
        changed = True
    return changed


def check_blocks(path: Path) -> None:
    """Refuse the written C3D ``path`` if its parameter section spans more than 255
    blocks (from the header's first parameter block to its data start): ezc3d writes
    the section's one-byte block count modulo 256, and readers that trust the count
    (the ``c3d`` package) lose the parameters beyond it, e.g. events past the ~3000th.

    Raises:
        SectionError: it does (the message says how many blocks).
    """
    with open(path, "rb") as handle:
        head = handle.read(18)
    blocks = int.from_bytes(head[16:18], "little") - head[0] if len(head) == 18 else 0
    if blocks > _MAX_BLOCKS:
        raise SectionError(
            f"its parameters need {blocks} blocks of 512 bytes and a C3D file holds at most {_MAX_BLOCKS} "
            "(too many events or labels; split the trial)"
        )
