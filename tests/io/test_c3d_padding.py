"""The data block's padding is not data: files written by ezc3d (our own writer) end with
one more 512-byte block after the last frame, other writers pad to a whole block; neither
is reported as frames the reader did not read."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from support import SAMPLE_DATA
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d, write_c3d


@pytest.mark.parametrize("name", sorted(p.name for p in SAMPLE_DATA.glob("*.c3d")))
def test_bundled_files_read_without_notes(name: str) -> None:
    assert read_c3d(SAMPLE_DATA / name).notes == []


@pytest.mark.parametrize("frames", [1, 2, 3, 255, 256, 257, 511, 512])
def test_written_files_of_any_length_read_without_notes(frames: int, tmp_path: Path) -> None:
    source = read_c3d(SAMPLE_DATA / "walking.c3d")
    cut = source.markers[:frames]
    import dataclasses

    written = write_c3d(dataclasses.replace(source, markers=cut, events=[], outputs={}, output_kinds={}),
                        tmp_path / "cut.c3d")  # fmt: skip
    back = read_c3d(written if isinstance(written, Path) else tmp_path / "cut.c3d")
    assert back.n_frames == frames and back.notes == []
    np.testing.assert_allclose(back.markers, cut, atol=1e-3, equal_nan=True)


def test_extra_frames_after_the_declared_ones_are_noted(tmp_path: Path) -> None:
    """Two whole frames' worth of bytes (more than a block) appended after the declared
    data: noted, not silently dropped."""
    data = (SAMPLE_DATA / "walking.c3d").read_bytes()
    grown = tmp_path / "grown.c3d"
    grown.write_bytes(data + data[-1024:] + bytes(1024))
    notes = messages(read_c3d(grown).notes)
    assert any("the data block holds" in n for n in notes), notes
