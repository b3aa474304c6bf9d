"""The batch report's cache of a trial (``<name>_files/entry.json``, issue 37): JSON data
with a schema version and the job's key, never a pickle.  The round trip of an entry, a
tampered or foreign ``entry.json`` refused, and on a re-run: unchanged trials reused,
a planted ``entry.pkl`` never opened, a tampered or old cache recomputed."""

from __future__ import annotations

import copy
import json
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.viz.report import TrialEntry
from fuzzygait.viz.report.allowable import AllowableRow, AllowableSummary
from fuzzygait.viz.report.bands import Headline
from fuzzygait.workflows.batch_report import BatchReportRequest, load_entry, write_batch_report
from fuzzygait.workflows.report_entries import (
    ENTRY_SCHEMA,
    EntryFormatError,
    entry_from_json,
    entry_to_json,
    read_entry,
    write_entry,
)
from support import synthetic_session


def full_entry() -> TrialEntry:
    """An entry with every field set (numpy scalars where a run gives them)."""
    row = AllowableRow("LKneeAngles_X", "Left knee, sagittal (+ flexion)", "within", "2.3", "46",
                       {"pelvis": "", "thigh": "2.1", "shank": "2.4"}, "", "known within ±2.5° if ...")  # fmt: skip
    return TrialEntry(
        source=Path("/data/visit-1/walk01.c3d"),
        page="walk01.html",
        n_frames=np.int64(140),  # type: ignore[arg-type]
        rate=np.float64(100.0),
        cycles={"L": 1, "R": 2},
        gaps_filled=3,
        gaps_left=1,
        headline=Headline(
            (12.5, "LKneeAngles_X", 0.0),
            (7.25, "RHipAngles_X", 0.25),
            0.0,
            ["LFootProgressAngles_Z"],
            24,
            ["RAnkleAngles_X"],
        ),  # fmt: skip
        allowable=AllowableSummary(2.5, "Table 3.1", [row]),
        gps=6.5,
        moved=("left shank",),
        run_warnings=("marker diameter 14 mm contradicts the file's 25 mm",),
    )


def test_entry_json_round_trip(tmp_path: Path) -> None:
    entry = full_entry()
    back = entry_from_json(json.loads(json.dumps(entry_to_json(entry))))
    assert back == entry
    assert type(back.n_frames) is int and type(back.rate) is float and isinstance(back.moved, tuple)
    empty = TrialEntry(Path("walk02.c3d"), "walk02.html")  # defaults: no headline numbers, no allowable table
    assert entry_from_json(json.loads(json.dumps(entry_to_json(empty)))) == empty
    write_entry(tmp_path / "entry.json", entry, "k1")
    assert read_entry(tmp_path / "entry.json", "k1") == entry == read_entry(tmp_path / "entry.json")
    stored = json.loads((tmp_path / "entry.json").read_text(encoding="utf-8"))
    assert stored["schema"] == ENTRY_SCHEMA and stored["key"] == "k1"
    with pytest.raises(EntryFormatError, match="another job"):
        read_entry(tmp_path / "entry.json", "k2")


def _set(content: dict[str, Any], path: str, value: Any) -> None:
    *parents, last = path.split(".")
    target: Any = content
    for name in parents:
        target = target[int(name)] if isinstance(target, list) else target[name]
    if value is KeyError:
        del target[last]
    else:
        target[int(last) if isinstance(target, list) else last] = value


TAMPERED = [
    ("schema", 2), ("schema", "1"), ("schema", True), ("schema", 1.0), ("format", "pickle"), ("key", 3),
    ("schema", KeyError), ("extra", "x"),
    ("entry.n_frames", "140"), ("entry.n_frames", True), ("entry.n_frames", 1.5), ("entry.rate", "100"),
    ("entry.page", 3), ("entry.source", None), ("entry.cycles", [1, 2]), ("entry.cycles.L", "1"),
    ("entry.cycles.L", False), ("entry.moved", "left shank"), ("entry.moved", [1]), ("entry.gps", [6.5]),
    ("entry.headline.largest", [12.5, 3, 0.0]), ("entry.headline.largest", [12.5, "LKneeAngles_X"]),
    ("entry.headline.undetermined", {"a": 1}), ("entry.headline.n_components", None),
    ("entry.headline.__class__", "TrialEntry"), ("entry.allowable.rows", "x"), ("entry.allowable.rows.0.mm", 2.3),
    ("entry.allowable.rows.0.segments", {"thigh": 2.1}), ("entry.allowable.tolerance", "2.5"),
    ("entry.allowable", ["TrialEntry"]), ("entry.run_warnings", KeyError), ("entry", None),
]  # fmt: skip


@pytest.mark.parametrize(("path", "value"), TAMPERED, ids=[f"{p}={v!r}" for p, v in TAMPERED])
def test_tampered_entry_json_is_refused(tmp_path: Path, path: str, value: Any) -> None:
    write_entry(tmp_path / "entry.json", full_entry(), "k1")
    content = json.loads((tmp_path / "entry.json").read_text(encoding="utf-8"))
    tampered = copy.deepcopy(content)
    _set(tampered, path, value)
    (tmp_path / "entry.json").write_text(json.dumps(tampered), encoding="utf-8")
    with pytest.raises(EntryFormatError):
        read_entry(tmp_path / "entry.json", "k1")


@pytest.mark.parametrize("text", [b"", b"{", b"\x80\x04K\x01.", b"[1, 2]", b"null", b"[" * 100_000, b"{}"])
def test_entry_json_that_is_not_an_entry_is_refused(tmp_path: Path, text: bytes) -> None:
    (tmp_path / "entry.json").write_bytes(text)
    with pytest.raises(EntryFormatError):
        read_entry(tmp_path / "entry.json")


class _Planted:
    """A pickle that creates ``marker`` when it is loaded (what an attacker would plant)."""

    def __init__(self, marker: Path) -> None:
        self.marker = marker

    def __reduce__(self) -> tuple[Any, tuple[str, str]]:
        return (open, (str(self.marker), "w"))


def _tamper(path: Path, **entry: Any) -> None:
    content = json.loads(path.read_text(encoding="utf-8"))
    content["entry"].update(entry)
    path.write_text(json.dumps(content), encoding="utf-8")


@pytest.mark.slow
def test_rerun_reuses_entry_json_and_never_opens_entry_pkl(tmp_path: Path) -> None:
    session = synthetic_session(tmp_path / "visit-1", 140)
    out, marker = tmp_path / "report", tmp_path / "pwned"
    first = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    pages = out / "visit-1"
    assert first.n_ok == 2 and first.n_skipped == 0
    assert not list(out.rglob("*.pkl")) and (pages / "walk01_files" / "entry.json").is_file()
    assert load_entry(pages, "walk01") == first.outcomes[0].entry

    for name in ("walk01", "walk02"):  # planted beside a valid cache: ignored
        (pages / f"{name}_files" / "entry.pkl").write_bytes(pickle.dumps(_Planted(marker)))
    again = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert [o.skipped for o in again.outcomes] == [True, True] and not marker.exists()
    assert [o.entry for o in again.outcomes] == [o.entry for o in first.outcomes]

    _tamper(pages / "walk01_files" / "entry.json", n_frames="140")  # wrong type
    content = json.loads((pages / "walk02_files" / "entry.json").read_text(encoding="utf-8"))
    content["schema"] = ENTRY_SCHEMA + 1  # a future (or unknown) version
    (pages / "walk02_files" / "entry.json").write_text(json.dumps(content), encoding="utf-8")
    with pytest.raises(FuzzyGaitError, match="not a report entry"):
        load_entry(pages, "walk02")
    recomputed = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert [o.skipped for o in recomputed.outcomes] == [False, False] and recomputed.n_ok == 2
    assert [o.entry for o in recomputed.outcomes] == [o.entry for o in first.outcomes]
    assert not list(out.rglob("*.pkl")) and not marker.exists()  # the recomputed page folders replaced

    # a cache of the version before: entry.pkl and a job.json of the right key, no entry.json
    (pages / "walk01_files" / "entry.json").unlink()
    (pages / "walk01_files" / "entry.pkl").write_bytes(pickle.dumps(_Planted(marker)))
    old = write_batch_report(BatchReportRequest([session], out, uncertainty="none"))
    assert [o.skipped for o in old.outcomes] == [False, True] and not marker.exists()
    assert (pages / "walk01_files" / "entry.json").is_file() and not (pages / "walk01_files" / "entry.pkl").exists()
