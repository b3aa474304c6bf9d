"""``fuzzygait report`` over a session folder holding C3D files on which ezc3d crashes
(SIGSEGV) or hangs: the batch finishes the good trials and lists each broken one with
one line (issue 17). Before the reader's sanity pass the segfault killed the whole batch
and the hang blocked it."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import needs_shared, run, shared_file, synthetic_session


def _corrupt_copy(source: Path, target: Path, patch: dict[int, int] | tuple[int, int]) -> None:
    data = bytearray(source.read_bytes())
    if isinstance(patch, tuple):
        data[patch[0] : patch[1]] = bytes(patch[1] - patch[0])
    else:
        for at, value in patch.items():
            data[at] = value
    target.write_bytes(bytes(data))


@needs_shared
@pytest.mark.slow
def test_report_batch_with_segfault_hang_and_unreadable_files(tmp_path: Path) -> None:
    session = synthetic_session(tmp_path / "visit", 150)
    formats = ("c3d-formats",)
    # ezc3d: SIGSEGV (analog channels without offsets), a loop of minutes (69 dimensions), a 20-s refusal
    _corrupt_copy(shared_file(*formats, "bad_parameter_section.c3d"), session / "walk03.c3d", (5632, 6144))
    _corrupt_copy(shared_file(*formats, "pc_real.c3d"), session / "walk04.c3d", {3817: 0x45})
    _corrupt_copy(shared_file(*formats, "bad_parameter_section.c3d"), session / "walk05.c3d", {})
    out = tmp_path / "report"
    result = run("report", session, "--out", out, "--uncertainty", "none", "--workers", "1")
    assert "Traceback" not in result.stdout + result.stderr
    assert "report: 1 session(s), 2 of 5 trials OK, 3 failed" in result.stdout, result.stdout + result.stderr
    failed = [line for line in result.stderr.splitlines() if line.startswith("fuzzygait: failed: ")]
    assert len(failed) == 3  # one line each, naming its file
    for name in ("walk03.c3d", "walk04.c3d", "walk05.c3d"):
        assert sum(name in line for line in failed) == 1, failed
    # the two files ezc3d cannot survive are read by the c3d package (they hold no foot
    # markers, hence no events); the third, which no reader reads, is refused as corrupt
    assert "do not fill its record" in next(line for line in failed if "walk05.c3d" in line)
    for name in ("walk01", "walk02"):
        assert (out / "visit" / f"{name}.html").read_text(encoding="utf-8").rstrip().endswith("</html>")
    index = (out / "visit" / "index.html").read_text(encoding="utf-8")
    assert all(name in index for name in ("walk03", "walk04", "walk05"))
