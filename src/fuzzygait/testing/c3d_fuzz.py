"""Seeded corruptions of C3D files, and how :func:`~fuzzygait.io.c3d.read_c3d` takes them.

Shared by the fuzz tests (``tests/io/test_c3d_fuzz.py``) and the full campaign
(``benchmarks/fuzz_c3d.py``). A :class:`Variant` is a (source file, kind, seed) triple;
:func:`build` makes its bytes deterministically, so a worker process can rebuild any
variant from the triple alone. :func:`run_worker` (``python -m fuzzygait.testing.c3d_fuzz
SPECS.json START``) reads variants one after the other *in its own process* -- a
segmentation fault or a hang then kills or stalls that worker, which the driver notices,
records and restarts after -- and prints one JSON line per variant with its
:data:`OUTCOMES` class.

Kinds of corruption: random byte changes in the header, the parameter section and the
data block; zeroed ranges and zeroed 512-byte blocks; truncations; header fields (point
and analog counts, first/last frame, scale, data start, rate, parameter-block pointer)
and parameter values (``POINT:FRAMES``, ``USED``, ``SCALE``, ``RATE``, ``DATA_START``,
``ANALOG:USED`` ...) set to extreme values; parameter records with a corrupt name
length, group id, offset, data type, dimension count or dimension; control characters
in labels; plus the source written back by ezc3d and by the ``c3d`` package.
"""

from __future__ import annotations

import hashlib
import json
import math
import struct
import sys
import tempfile
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fuzzygait.io.c3d_guard import BLOCK, inspect_bytes

#: Corruption kinds, in the order variants cycle through them.
KINDS = (
    "flip_header",
    "flip_parameters",
    "flip_data",
    "zero_range",
    "zero_block",
    "truncate",
    "header_field",
    "parameter_field",
    "parameter_record",
    "label_control",
)
#: Files written from the source by the two public writers.
WRITTEN = ("written_ezc3d", "written_c3d")

#: Outcome classes (the campaign's table rows); the first six are acceptable: a byte
#: changed inside a sample value or a parameter's text/number/name that keeps every count
#: (frames, points, events; no parameter lost), rate and first frame is not detectable by
#: a reader -- C3D has no checksum.
OUTCOMES = (
    "read identical",
    "read with a note",
    "refused in one line",
    "written file read back equal",
    "read, only sample values differ (C3D has no checksum)",
    "read, only parameter contents differ (C3D has no checksum)",
    "read, differs, NO NOTE",
    "written file read back DIFFERENT",
    "refused, not one line",
    "traceback",
    "crash",
    "over 10 s",
)
SLOW_S = 10.0


@dataclass(frozen=True)
class Variant:
    """One corrupted (or re-written) copy of ``source``."""

    source: str
    kind: str
    seed: int

    @property
    def name(self) -> str:
        """File name of the variant (names the source, kind and seed)."""
        return f"{Path(self.source).stem}.{self.kind}.{self.seed}{Path(self.source).suffix}"


def variants(sources: list[Path], per_file: int, seed: int = 0, written: bool = True) -> list[Variant]:
    """``per_file`` corruptions of each source (kinds in turn) and, if ``written``,
    the two re-written copies of each."""
    out = []
    for i, source in enumerate(sources):
        for j in range(per_file):
            out.append(Variant(str(source), KINDS[j % len(KINDS)], seed * 1_000_003 + i * 10_007 + j))
        if written:
            out += [Variant(str(source), kind, 0) for kind in WRITTEN]
    return out


# =========================================================================== building
def build(variant: Variant, workdir: Path) -> tuple[Path, str]:
    """Write ``variant`` into ``workdir``; returns its path and what was done."""
    target = workdir / variant.name
    if variant.kind in WRITTEN:
        (_write_ezc3d if variant.kind == "written_ezc3d" else _write_c3d_package)(Path(variant.source), target)
        return target, variant.kind
    data = Path(variant.source).read_bytes()
    rng = np.random.default_rng(variant.seed)
    mutated, what = _MUTATORS[variant.kind](bytearray(data), rng)
    target.write_bytes(bytes(mutated))
    return target, what


def _regions(data: bytearray) -> tuple[int, int, int]:
    """(parameter section start, data block start, file size), clipped to the file."""
    start = min(max((data[0] - 1) * BLOCK, BLOCK), len(data))
    layout = inspect_bytes(bytes(data))
    data_start = (layout.data_start - 1) * BLOCK if layout.data_start > 0 else start + BLOCK
    return start, min(max(data_start, start + 4), len(data)), len(data)


def _flip(data: bytearray, lo: int, hi: int, rng: np.random.Generator, what: str) -> tuple[bytearray, str]:
    if hi <= lo:
        lo, hi = 0, len(data)
    pos = int(rng.integers(lo, hi))
    data[pos] ^= int(rng.integers(1, 256))
    return data, f"{what} byte {pos} changed"


def _flip_header(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    hi = 24 if rng.random() < 0.6 else BLOCK  # the header's fields, mostly
    return _flip(data, 0, hi, rng, "header")


def _flip_parameters(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    start, data_start, _ = _regions(data)
    return _flip(data, start, data_start, rng, "parameter")


def _flip_data(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    _, data_start, size = _regions(data)
    return _flip(data, data_start, size, rng, "data")


def _zero_range(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    start, data_start, size = _regions(data)
    lo = int(rng.integers(start, max(data_start, start + 1))) if rng.random() < 0.7 else int(rng.integers(0, size))
    hi = min(size, lo + int(rng.integers(1, 2049)))
    data[lo:hi] = bytes(hi - lo)
    return data, f"bytes {lo}-{hi - 1} zeroed"


def _zero_block(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    block = int(rng.integers(0, max(1, len(data) // BLOCK)))
    data[block * BLOCK : (block + 1) * BLOCK] = bytes(len(data[block * BLOCK : (block + 1) * BLOCK]))
    return data, f"block {block + 1} zeroed"


def _truncate(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    start, data_start, size = _regions(data)
    choice = rng.integers(0, 4)
    bounds = [(1, BLOCK), (start, data_start), (data_start, size), (max(1, size - 64), size)][int(choice)]
    cut = int(rng.integers(bounds[0], max(bounds[1], bounds[0] + 1)))
    return data[:cut], f"truncated to {cut} bytes"


_U16_FIELDS = {"points": 2, "analog": 4, "first frame": 6, "last frame": 8, "data start": 16, "analog/frame": 18}
_FLOAT_FIELDS = {"scale": 12, "rate": 20}
_EXTREME_FLOATS = (0.0, -0.0, math.nan, math.inf, -math.inf, 1e30, -1e30, 4e-23, 1e6, -1.0, 1.0)


def _u16_values(old: int, rng: np.random.Generator) -> int:
    options = [0, 1, 2, 255, 32768, 65535, old + 1, old - 1, old * 2, old // 2, int(rng.integers(0, 65536))]
    return int(options[int(rng.integers(0, len(options)))]) % 65536


def _header_field(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    names = [*_U16_FIELDS, *_FLOAT_FIELDS, "parameter block"]
    name = names[int(rng.integers(0, len(names)))]
    if name == "parameter block":
        data[0] = int(rng.choice([0, 1, 3, 255, data[0] + 1, max(0, data[0] - 1)])) % 256
        return data, f"header parameter-block pointer set to {data[0]}"
    if name in _U16_FIELDS:
        pos = _U16_FIELDS[name]
        value = _u16_values(struct.unpack("<H", data[pos : pos + 2])[0], rng)
        data[pos : pos + 2] = struct.pack("<H", value)
        return data, f"header {name} set to {value}"
    pos = _FLOAT_FIELDS[name]
    old = struct.unpack("<f", data[pos : pos + 4])[0]
    number = float(rng.choice([*_EXTREME_FLOATS, -old, old * 10]))
    data[pos : pos + 4] = struct.pack("<f", number)
    return data, f"header {name} set to {number:g}"


_TARGETS = (
    ("POINT", "FRAMES"),
    ("POINT", "USED"),
    ("POINT", "SCALE"),
    ("POINT", "RATE"),
    ("POINT", "DATA_START"),
    ("ANALOG", "USED"),
    ("ANALOG", "RATE"),
    ("ANALOG", "SCALE"),
    ("EVENT", "USED"),
    ("TRIAL", "ACTUAL_END_FIELD"),
)


def _data_offset(data: bytearray, position: int) -> int:
    """Byte offset of a parameter record's data (after name, offset, type, dims)."""
    n_chars = abs(struct.unpack("b", data[position : position + 1])[0])
    body = position + 2 + n_chars + 2
    return body + 2 + data[body + 1]


def _parameter_field(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    layout = inspect_bytes(bytes(data))
    present = [t for t in _TARGETS if t in layout.parameters]
    if not present:
        return _flip_parameters(data, rng)
    group, name = present[int(rng.integers(0, len(present)))]
    param = layout.parameters[(group, name)]
    at = _data_offset(data, param.position)
    if param.kind == 4:
        value: float = float(rng.choice(_EXTREME_FLOATS))
        data[at : at + 4] = struct.pack("<f", value)
    elif param.kind == 2:
        old = struct.unpack("<h", data[at : at + 2])[0]
        value = int(rng.choice([0, 1, -1, 2, 32767, -32768, old + 1, old - 1, old * 2 % 32768]))
        data[at : at + 2] = struct.pack("<h", int(value))
    else:
        value = int(rng.integers(0, 256))
        data[at] = int(value)
    return data, f"{group}:{name} set to {value:g}"


def _parameter_record(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    layout = inspect_bytes(bytes(data))
    params = sorted(layout.parameters.items(), key=lambda item: item[1].position)
    if not params:
        return _flip_parameters(data, rng)
    (group, name), param = params[int(rng.integers(0, len(params)))]
    pos = param.position
    n_chars = abs(struct.unpack("b", data[pos : pos + 1])[0])
    body = pos + 2 + n_chars + 2
    field = ["name length", "group id", "offset", "type", "dimension count", "dimension"][int(rng.integers(0, 6))]
    if field == "name length":
        data[pos] = int(rng.integers(0, 256))
    elif field == "group id":
        data[pos + 1] = int(rng.integers(0, 256))
    elif field == "offset":
        value = int(rng.choice([0, 1, 2, 65535, 32768, int(rng.integers(0, 65536))]))
        data[body - 2 : body] = struct.pack("<H", value)
    elif field == "type":
        data[body] = int(rng.choice([0, 3, 5, 0x7F, 0x80, 0xFE, int(rng.integers(0, 256))])) % 256
    elif field == "dimension count":
        data[body + 1] = int(rng.choice([0, 8, 0x45, 0xFF, data[body + 1] + 1, int(rng.integers(0, 256))])) % 256
    elif data[body + 1]:
        k = body + 2 + int(rng.integers(0, data[body + 1]))
        data[k] = int(rng.choice([0, 0xFF, data[k] + 1, int(rng.integers(0, 256))])) % 256
    else:
        data[body + 1] = 1
    return data, f"{group}:{name} record {field} corrupted"


def _label_control(data: bytearray, rng: np.random.Generator) -> tuple[bytearray, str]:
    layout = inspect_bytes(bytes(data))
    labels = layout.parameters.get(("POINT", "LABELS"))
    if labels is None or not labels.data:
        return _flip_parameters(data, rng)
    at = _data_offset(data, labels.position) + int(rng.integers(0, len(labels.data)))
    code = int(rng.choice([0x1B, 0x07, 0x00, 0x08, 0x7F, 0x0D, 0x0A, 0x9B]))
    data[at] = code
    return data, f"POINT:LABELS byte {at} set to control character {code:#04x}"


_MUTATORS = {
    "flip_header": _flip_header,
    "flip_parameters": _flip_parameters,
    "flip_data": _flip_data,
    "zero_range": _zero_range,
    "zero_block": _zero_block,
    "truncate": _truncate,
    "header_field": _header_field,
    "parameter_field": _parameter_field,
    "parameter_record": _parameter_record,
    "label_control": _label_control,
}


def _write_ezc3d(source: Path, target: Path) -> None:
    """A plain ``ezc3d.c3d(F).write(G)`` round trip."""
    import ezc3d

    ezc3d.c3d(str(source)).write(str(target))


def _write_c3d_package(source: Path, target: Path) -> None:
    """The source's points (labels, rate, units) written by the ``c3d`` package's Writer."""
    import c3d

    with open(source, "rb") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reader = c3d.Reader(handle)
        frames = [points.copy() for _, points, _ in reader.read_frames()]
        labels = [str(lbl).strip()[:32] for lbl in reader.point_labels][: frames[0].shape[0]]
        units = reader.get("POINT:UNITS")
        unit = units.string_value.strip() if units is not None else "mm"
        rate = float(reader.point_rate)
    writer = c3d.Writer(point_rate=rate, analog_rate=0.0, point_scale=-1.0, point_units=(unit + "    ")[:4])
    writer.set_point_labels(labels)
    writer.add_frames([(points, np.zeros((0, 0))) for points in frames])
    with open(target, "wb") as handle, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        writer.write(handle)


# =========================================================================== outcomes
@dataclass
class Reading:
    """What reading one file gave: ``status`` "ok", "refused" or "exception"."""

    status: str
    message: str = ""
    notes: tuple[str, ...] = ()
    structure: str = ""
    counts: str = ""
    n_parameters: int = 0
    values: str = ""
    n_frames: int = 0
    points: dict[str, Any] | None = None


def read(path: Path, keep_points: bool = False) -> Reading:
    """Read ``path`` with :func:`read_c3d` and summarise the trial (hashes of its
    structure -- frames, labels, rate, events, parameters -- and of its sample values)."""
    from fuzzygait.core.errors import C3DError
    from fuzzygait.io.c3d import read_c3d

    try:
        trial = read_c3d(path)
    except C3DError as exc:
        return Reading("refused", str(exc))
    except Exception as exc:  # the campaign's point: there must be none
        return Reading("exception", f"{type(exc).__name__}: {exc}")
    structure = repr(
        (
            trial.n_frames,
            trial.marker_labels,
            sorted(trial.output_kinds.items()),
            trial.rate,
            trial.first_frame,
            [(e.label, e.context, round(e.time, 9)) for e in trial.events],
            sorted(trial.parameters.items()),
            trial.subject,
            trial.label_prefix,
            [(a.name, a.context, a.value) for a in trial.analysis],
        )
    )
    counts = repr(
        (
            trial.n_frames,
            trial.n_markers + len(trial.outputs),
            trial.rate,
            trial.first_frame,
            len(trial.events),
            len(trial.analysis),
        )
    )
    digest = hashlib.sha256(np.nan_to_num(trial.markers, nan=1e300).tobytes())
    for name in sorted(trial.outputs):
        digest.update(np.nan_to_num(trial.outputs[name], nan=1e300).tobytes())
    points = None
    if keep_points:
        points = {lbl: trial.markers[:, i] for i, lbl in enumerate(trial.marker_labels)} | dict(trial.outputs)
    return Reading(
        "ok",
        notes=tuple(note.message for note in trial.notes),
        structure=hashlib.sha256(structure.encode()).hexdigest(),
        counts=counts,
        n_parameters=len(trial.parameters),
        values=digest.hexdigest(),
        n_frames=trial.n_frames,
        points=points,
    )


def classify(variant: Variant, path: Path, got: Reading, original: Reading) -> str:
    """The :data:`OUTCOMES` class of ``got`` (reading ``path``) given the source's reading."""
    if got.status == "exception":
        return "traceback"
    if got.status == "refused":
        one_line = "\n" not in got.message and str(path) in got.message
        return "refused in one line" if one_line else "refused, not one line"
    if variant.kind in WRITTEN:
        return "written file read back equal" if _same_points(got, original) else "written file read back DIFFERENT"
    if original.status == "ok" and (got.structure, got.values) == (original.structure, original.values):
        return "read identical"
    if set(got.notes) - set(original.notes):
        return "read with a note"
    if original.status == "ok" and got.structure == original.structure:
        return "read, only sample values differ (C3D has no checksum)"
    # a changed byte in a parameter's name renames it (one of a repeated pair becomes a new
    # parameter); only parameters lost without a note count as a silent difference
    if original.status == "ok" and got.counts == original.counts and got.n_parameters >= original.n_parameters:
        return "read, only parameter contents differ (C3D has no checksum)"
    return "read, differs, NO NOTE"


def _same_points(got: Reading, original: Reading) -> bool:
    """Frame count equal and every point of the source equal within float32 storage
    precision (NaN where the source has NaN)."""
    if original.status != "ok" or got.n_frames != original.n_frames or not got.points or not original.points:
        return False
    for label, values in original.points.items():
        back = got.points.get(label)
        if back is None or back.shape != values.shape:
            return False
        if not np.array_equal(np.isnan(back), np.isnan(values)):
            return False
        if not np.allclose(back, values, rtol=1e-6, atol=1e-3, equal_nan=True):
            return False
    return True


# =========================================================================== worker
def run_worker(specs: list[Variant], start: int = 0, out: Any = None) -> None:
    """Read ``specs[start:]`` in this process, one JSON line per variant on ``out``."""
    out = out or sys.stdout
    originals: dict[str, Reading] = {}
    with tempfile.TemporaryDirectory(prefix="fuzz-c3d-") as tmp:
        for index in range(start, len(specs)):
            variant = specs[index]
            if variant.source not in originals:
                originals[variant.source] = read(Path(variant.source), keep_points=True)
            try:
                if variant.kind in WRITTEN and originals[variant.source].status != "ok":
                    raise ValueError("the source is unreadable")
                path, what = build(variant, Path(tmp))
            except Exception as exc:  # e.g. a writer that cannot write this source
                print(json.dumps({"index": index, "outcome": None, "what": f"not built: {exc}"}), file=out, flush=True)
                continue
            began = time.perf_counter()
            got = read(path, keep_points=variant.kind in WRITTEN)
            seconds = time.perf_counter() - began
            outcome = classify(variant, path, got, originals[variant.source])
            if seconds > SLOW_S:
                outcome = "over 10 s"
            new = [note for note in got.notes if note not in originals[variant.source].notes]
            message = got.message or (new[0] if new else "")
            record = {"index": index, "outcome": outcome, "what": what, "seconds": seconds, "message": message}
            print(json.dumps(record), file=out, flush=True)
            path.unlink(missing_ok=True)


def save_specs(specs: list[Variant], path: Path) -> None:
    """Write ``specs`` as JSON for :func:`run_worker`'s command line."""
    path.write_text(json.dumps([asdict(v) for v in specs]))


if __name__ == "__main__":  # python -m fuzzygait.testing.c3d_fuzz SPECS.json [START]
    loaded = [Variant(**v) for v in json.loads(Path(sys.argv[1]).read_text())]
    run_worker(loaded, int(sys.argv[2]) if len(sys.argv) > 2 else 0)
