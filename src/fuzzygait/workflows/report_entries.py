"""A trial's index entry (:class:`~fuzzygait.viz.report.bands.TrialEntry`) as JSON:
``<name>_files/entry.json`` of the batch report, so that a re-run can reuse a trial
without recomputing it.

The file is data, never code: every field is written and read explicitly, and read back
only when it has exactly the fields of :data:`ENTRY_SCHEMA`'s layout with the right
types (an ``int`` is not a ``bool``, a list of strings holds only strings).  Anything else
-- another schema version, a missing or extra field, a wrong type, a job key that is
not the expected one, a file that is not JSON -- raises :class:`EntryFormatError`, and
the batch recomputes the trial.  (Earlier versions pickled the entry into
``entry.pkl``; unpickling a file from a shared folder can run code, so such files are
never opened.)

Layout::

    {"format": "fuzzygait-report-entry", "schema": 1, "key": "<job key>",
     "entry": {"source": str, "page": str|null, "error": str|null, "n_frames": int|null,
               "rate": float|null, "cycles": {side: int}, "gaps_filled": int,
               "gaps_left": int, "gps": float|null, "moved": [str], "run_warnings": [str],
               "headline": {"largest": [float, str, float]|null, "widest": ...|null,
                            "alpha": float|null, "undetermined": [str],
                            "n_components": int, "flexion_undetermined": [str]},
               "allowable": null | {"tolerance": float, "source": str,
                                    "rows": [{"component": str, "label": str,
                                              "status": str, "mm": str, "percent": str,
                                              "segments": {str: str}, "note": str,
                                              "text": str}]}}}

Floats may be ``NaN``/``Infinity`` (Python's JSON dialect).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from fuzzygait.viz.report.allowable import AllowableRow, AllowableSummary
from fuzzygait.viz.report.bands import Headline, Summary, TrialEntry

__all__ = ["ENTRY_FORMAT", "ENTRY_SCHEMA", "EntryFormatError", "entry_from_json", "entry_to_json", "read_entry",
           "write_entry"]  # fmt: skip

#: The ``format`` tag of ``entry.json``.
ENTRY_FORMAT = "fuzzygait-report-entry"
#: The version of ``entry.json``'s layout: a file of another version is recomputed.
ENTRY_SCHEMA = 1
#: Larger files are not read (an entry is a few kB).
MAX_BYTES = 4 << 20


class EntryFormatError(ValueError):
    """``entry.json`` is not an entry of this version (recompute the trial)."""


# ============================================================================ writing
def _float(value: float | None) -> float | None:
    return None if value is None else float(value)


def _summary(value: Summary | None) -> list[object] | None:
    return None if value is None else [float(value[0]), str(value[1]), float(value[2])]


def _headline(head: Headline) -> dict[str, object]:
    return {"largest": _summary(head.largest), "widest": _summary(head.widest), "alpha": _float(head.alpha),
            "undetermined": [str(n) for n in head.undetermined], "n_components": int(head.n_components),
            "flexion_undetermined": [str(n) for n in head.flexion_undetermined]}  # fmt: skip


def _row(row: AllowableRow) -> dict[str, object]:
    return {"component": str(row.component), "label": str(row.label), "status": str(row.status), "mm": str(row.mm),
            "percent": str(row.percent), "segments": {str(k): str(v) for k, v in row.segments.items()},
            "note": str(row.note), "text": str(row.text)}  # fmt: skip


def _allowable(summary: AllowableSummary | None) -> dict[str, object] | None:
    if summary is None:
        return None
    return {"tolerance": float(summary.tolerance), "source": str(summary.source),
            "rows": [_row(row) for row in summary.rows]}  # fmt: skip


def entry_to_json(entry: TrialEntry) -> dict[str, object]:
    """The fields of ``entry`` as plain JSON values (numpy scalars converted)."""
    return {
        "source": str(entry.source),
        "page": None if entry.page is None else str(entry.page),
        "error": None if entry.error is None else str(entry.error),
        "n_frames": None if entry.n_frames is None else int(entry.n_frames),
        "rate": _float(entry.rate),
        "cycles": {str(side): int(n) for side, n in entry.cycles.items()},
        "gaps_filled": int(entry.gaps_filled),
        "gaps_left": int(entry.gaps_left),
        "headline": _headline(entry.headline),
        "allowable": _allowable(entry.allowable),
        "gps": _float(entry.gps),
        "moved": [str(s) for s in entry.moved],
        "run_warnings": [str(w) for w in entry.run_warnings],
    }


# ============================================================================ reading
class _Fields:
    """The fields of one JSON object, each read with its type checked; every field must
    be read (:meth:`done`), so an extra field is an error too."""

    def __init__(self, value: object, where: str, names: tuple[str, ...]) -> None:
        if not isinstance(value, dict):
            raise EntryFormatError(f"{where}: not an object")
        if set(value) != set(names):
            odd = sorted(set(value) ^ set(names))
            raise EntryFormatError(f"{where}: fields {', '.join(map(str, odd))} missing or unexpected")
        self.value, self.where = value, where

    def typed(self, name: str, kinds: tuple[type, ...], optional: bool) -> Any:
        value = self.value[name]
        if value is None and optional:
            return None
        if isinstance(value, bool) and bool not in kinds or not isinstance(value, kinds):
            raise EntryFormatError(f"{self.where}.{name}: {type(value).__name__} is not {kinds[0].__name__}")
        return value

    def text(self, name: str, optional: bool = False) -> Any:
        return self.typed(name, (str,), optional)

    def integer(self, name: str, optional: bool = False) -> Any:
        return self.typed(name, (int,), optional)

    def number(self, name: str, optional: bool = False) -> Any:
        value = self.typed(name, (float, int), optional)
        return None if value is None else float(value)

    def strings(self, name: str) -> list[str]:
        items = self.typed(name, (list,), False)
        if not all(isinstance(item, str) for item in items):
            raise EntryFormatError(f"{self.where}.{name}: not a list of strings")
        return list(items)

    def mapping(self, name: str, kind: type) -> dict[str, Any]:
        items: Mapping[str, object] = self.typed(name, (dict,), False)
        for key, item in items.items():
            if isinstance(item, bool) or not isinstance(item, kind):
                raise EntryFormatError(f"{self.where}.{name}[{key!r}]: {type(item).__name__} is not {kind.__name__}")
        return dict(items)

    def summary(self, name: str) -> Summary | None:
        value = self.typed(name, (list,), True)
        if value is None:
            return None
        if len(value) != 3 or not isinstance(value[1], str) or any(
                isinstance(v, bool) or not isinstance(v, (int, float)) for v in (value[0], value[2])):  # fmt: skip
            raise EntryFormatError(f"{self.where}.{name}: not [number, component, alpha]")
        return (float(value[0]), value[1], float(value[2]))


_HEADLINE = ("largest", "widest", "alpha", "undetermined", "n_components", "flexion_undetermined")
_ROW = ("component", "label", "status", "mm", "percent", "segments", "note", "text")
_ENTRY = ("source", "page", "error", "n_frames", "rate", "cycles", "gaps_filled", "gaps_left", "headline",
          "allowable", "gps", "moved", "run_warnings")  # fmt: skip


def _read_headline(value: object) -> Headline:
    f = _Fields(value, "entry.headline", _HEADLINE)
    return Headline(f.summary("largest"), f.summary("widest"), f.number("alpha", optional=True),
                    f.strings("undetermined"), f.integer("n_components"),
                    f.strings("flexion_undetermined"))  # fmt: skip


def _read_row(value: object, where: str) -> AllowableRow:
    f = _Fields(value, where, _ROW)
    return AllowableRow(f.text("component"), f.text("label"), f.text("status"), f.text("mm"), f.text("percent"),
                        f.mapping("segments", str), f.text("note"), f.text("text"))  # fmt: skip


def _read_allowable(value: object) -> AllowableSummary | None:
    if value is None:
        return None
    f = _Fields(value, "entry.allowable", ("tolerance", "source", "rows"))
    rows = f.typed("rows", (list,), False)
    return AllowableSummary(f.number("tolerance"), f.text("source"),
                            [_read_row(row, f"entry.allowable.rows[{i}]") for i, row in enumerate(rows)])  # fmt: skip


def entry_from_json(value: object) -> TrialEntry:
    """The :class:`TrialEntry` of :func:`entry_to_json`'s output, every field's type
    checked.

    Raises:
        EntryFormatError: a field is missing, unexpected or of the wrong type.
    """
    f = _Fields(value, "entry", _ENTRY)
    return TrialEntry(
        source=Path(f.text("source")),
        page=f.text("page", optional=True),
        error=f.text("error", optional=True),
        n_frames=f.integer("n_frames", optional=True),
        rate=f.number("rate", optional=True),
        cycles=f.mapping("cycles", int),
        gaps_filled=f.integer("gaps_filled"),
        gaps_left=f.integer("gaps_left"),
        headline=_read_headline(f.value["headline"]),
        allowable=_read_allowable(f.value["allowable"]),
        gps=f.number("gps", optional=True),
        moved=tuple(f.strings("moved")),
        run_warnings=tuple(f.strings("run_warnings")),
    )


# ============================================================================ files
def write_entry(path: Path, entry: TrialEntry, key: str) -> None:
    """Write ``entry`` as ``path`` (``entry.json``) with the schema version and the job
    ``key`` it belongs to (whole or not at all)."""
    content = {"format": ENTRY_FORMAT, "schema": ENTRY_SCHEMA, "key": key, "entry": entry_to_json(entry)}
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        tmp.write_text(json.dumps(content, indent=1, ensure_ascii=False), encoding="utf-8")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def read_entry(path: Path, key: str | None = None) -> TrialEntry:
    """The entry stored in ``path`` by :func:`write_entry`.

    Args:
        key: the job key the entry must have been written for (None: any).

    Raises:
        EntryFormatError: not an entry of :data:`ENTRY_SCHEMA` (or of another key).
        OSError: the file cannot be read.
    """
    with open(path, "rb") as handle:
        raw = handle.read(MAX_BYTES + 1)
    if len(raw) > MAX_BYTES:
        raise EntryFormatError(f"{path}: larger than {MAX_BYTES} bytes")
    try:
        content = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise EntryFormatError(f"{path}: not JSON ({exc})") from None
    if not isinstance(content, dict) or content.get("format") != ENTRY_FORMAT:
        raise EntryFormatError(f"{path}: not a report entry")
    schema = content.get("schema")
    if type(schema) is not int or schema != ENTRY_SCHEMA:
        raise EntryFormatError(f"{path}: schema {schema!r}, this version reads {ENTRY_SCHEMA}")
    if set(content) != {"format", "schema", "key", "entry"} or not isinstance(content["key"], str):
        raise EntryFormatError(f"{path}: unexpected layout")
    if key is not None and content["key"] != key:
        raise EntryFormatError(f"{path}: written for another job")
    return entry_from_json(content["entry"])
