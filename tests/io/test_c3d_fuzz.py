"""Seeded fuzzing of ``read_c3d`` over every shared C3D file (fuzzygait.testing.c3d_fuzz).

The variants are read in one worker process (``python -m fuzzygait.testing.c3d_fuzz``), so a
segmentation fault or a hang inside a C++ reader fails the test instead of killing the
test run. Every variant must be refused with one line naming the file, or read -- with a
note wherever its frames, points, rate, first frame, events or parameters differ from
the original's (a changed sample value or parameter text keeps every count and is not
detectable: C3D has no checksum).
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest
from support import SHARED_DATA, needs_shared

from fuzzygait.testing.c3d_fuzz import OUTCOMES, Variant, save_specs, variants

ACCEPTABLE = set(OUTCOMES[:6])


def _shared_c3d() -> list[Path]:
    return sorted(p for p in SHARED_DATA.rglob("*") if p.suffix.lower() == ".c3d")


def _campaign(specs: list[Variant], tmp_path: Path, timeout: float) -> list[dict]:
    """Read ``specs`` in one worker process; every variant must report an outcome."""
    spec_file = tmp_path / "specs.json"
    save_specs(specs, spec_file)
    done = subprocess.run(
        [sys.executable, "-m", "fuzzygait.testing.c3d_fuzz", str(spec_file)],
        capture_output=True,
        text=True,
        timeout=timeout,  # stops a hang only; not a timing assertion
    )
    records = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert done.returncode == 0, f"worker died (exit {done.returncode}) after {len(records)} of {len(specs)} variants"
    assert [r["index"] for r in records] == list(range(len(specs)))
    return [r for r in records if r["outcome"]]


def _check(specs: list[Variant], records: list[dict]) -> Counter[str]:
    bad = [(specs[r["index"]].name, r["what"], r["outcome"], r["message"]) for r in records if r["outcome"] not in ACCEPTABLE]
    assert not bad, bad[:5]
    return Counter(r["outcome"] for r in records)


def _cheap_variants(seed: int, small: int, large: int) -> list[Variant]:
    """``small`` corruptions of each file under 0.5 MB, ``large`` of the bigger ones."""
    files = _shared_c3d()
    out = []
    for path in files:
        per_file = small if path.stat().st_size < 500_000 else large
        out += [v for v in variants([path], per_file, seed=seed + len(out), written=False)]
    return out


@needs_shared
def test_fast_fuzz_of_every_shared_file_is_refused_in_one_line_or_read_with_notes(tmp_path: Path) -> None:
    specs = _cheap_variants(seed=11, small=16, large=4)
    assert len(specs) >= 200 and {Path(v.source) for v in specs} == set(_shared_c3d())
    counts = _check(specs, _campaign(specs, tmp_path, timeout=300))
    # the variants do exercise both sides: refusals and notes (the corruption is real)
    assert counts["refused in one line"] >= 10 and counts["read with a note"] >= 10, counts


@needs_shared
@pytest.mark.slow
def test_slow_fuzz_with_written_files(tmp_path: Path) -> None:
    """40 corruptions of every shared file plus the ezc3d- and c3d-package-written copies."""
    specs = variants(_shared_c3d(), 40, seed=23)
    records = _campaign(specs, tmp_path, timeout=1800)
    counts = _check(specs, records)
    assert counts["written file read back equal"] >= 13 + 19, counts  # the copies ezc3d and the c3d package write
