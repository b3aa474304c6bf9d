"""Typed findings (``fuzzygait.core.findings``): the message is made once and shown as it
is; code outside the terminal edge (``cli/``) selects findings by kind and reads their
typed fields, and never reads a note's text back."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import pytest

from fuzzygait.core.findings import Finding, FindingKind, Severity, messages, of_kind

SRC = Path(__file__).resolve().parents[2] / "src" / "fuzzygait"


def test_a_finding_is_its_message_with_typed_fields() -> None:
    gap = Finding(FindingKind.GAP_FILLING, "gap filling: 1 of 2 gaps filled (max_gap=10 frames, method=auto)",
                  max_gap=10, method="auto")  # fmt: skip
    assert str(gap) == gap.message and f"{gap}" == gap.message
    assert gap.severity is Severity.INFO and (gap.side, gap.segment, gap.marker, gap.cutoff_hz) == (None,) * 4
    with pytest.raises(dataclasses.FrozenInstanceError):
        gap.message = "other"  # type: ignore[misc]
    moved = Finding(FindingKind.MOVED_MARKERS, "left foot markers sit elsewhere", Severity.WARNING,
                    side="left", segment="left foot")  # fmt: skip
    assert of_kind([gap, moved], FindingKind.MOVED_MARKERS) == [moved]
    assert messages([gap, moved]) == [gap.message, moved.message]
    assert len({gap, moved, dataclasses.replace(gap)}) == 2  # hashable, equal by value (the pages dedupe them)


#: A loop variable over notes/findings/warnings: ``for n in run.notes``.
_LOOP = re.compile(r"\bfor\s+(\w+)\s+in\s+[\w.\[\]()*, ]*\b(?:notes|findings|warnings)\b")
#: Reading a note's text back: its text tested by prefix/suffix, split on a marker, or matched.
_TEXT_READ = r"\.(?:startswith|endswith|partition|rpartition|split|index|find)\("
_DIRECT = [
    re.compile(r"\b(?:note|notes|finding|findings)(?:\[[^\]]*\])?(?:\.message)?" + _TEXT_READ),
    re.compile(r"\.message" + _TEXT_READ),
    re.compile(r"\bre\.\w+\([^\n]*\b(?:note|notes|finding)\b(?:\[[^\]]*\])?(?:\.message)?\s*[,)]"),
]


def _reads_back(line: str) -> bool:
    """Whether ``line`` reads a note's or finding's text back."""
    if any(pattern.search(line) for pattern in _DIRECT):
        return True
    for var in _LOOP.findall(line):
        if re.search(rf"\b{var}(?:\.message)?" + _TEXT_READ, line) or re.search(rf"\bre\.\w+\([^\n]*\b{var}\b", line):
            return True
    return False


def test_the_checker_sees_the_old_ways_of_reading_notes_back() -> None:
    """What the code did before findings were typed, each caught; unrelated string
    handling is not."""
    old = [
        '    gap = [n for n in notes if n.startswith("gap filling")]',
        '    static = [n for n in run.notes if n.startswith("static offsets")]',
        '        head, sep, _ = note.partition(" " + MOVED_NOTE)',
        '    found = re.search(r"max_gap=(\\d+) frames, method=(\\w+)", note)',
        '    lines += [f"- {note}" for note in run.notes if not note.startswith(("model ", "gap filling"))]',
        '    keep = [f for f in trial.notes if f.message.startswith("Butterworth")]',
    ]
    assert [_reads_back(line) for line in old] == [True] * len(old)
    fine = [
        '    parsed = [n for n in names if n.startswith("L")]',
        '    label.startswith(prefix)',
        '    gap = of_kind(run.trial.notes, FindingKind.GAP_FILLING)',
        '    lines += [f"  note: {note.message}" for note in trial.notes]',
        '    text = static[0].message',
    ]
    assert [_reads_back(line) for line in fine] == [False] * len(fine)


def test_no_code_outside_the_cli_reads_notes_back_by_their_text() -> None:
    """Consumers select findings by kind and read typed fields (issue 38): no prefix
    test, split or regular expression on a note's text in src/fuzzygait (the terminal
    edge, cli/, only prints messages)."""
    files = [p for p in SRC.rglob("*.py") if "cli" not in p.relative_to(SRC).parts]
    assert len(files) > 50
    found = [f"{path.relative_to(SRC)}:{number}: {line.strip()}"
             for path in files for number, line in enumerate(path.read_text().splitlines(), 1)
             if not line.lstrip().startswith("#") and _reads_back(line)]  # fmt: skip
    assert found == []
