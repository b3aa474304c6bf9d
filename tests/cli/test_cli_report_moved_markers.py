"""``fuzzygait report`` on the shared Qualisys CGM 2.4 session, whose static trial does
not fit its walking trials (markers moved or relabelled between them): the terminal, the
session page and the index warn about it in the trial's row."""

from __future__ import annotations

from pathlib import Path

from support import SHARED_DATA, needs_shared, run

WARNING = ("markers moved since the static trial (left thigh, left shank, left foot, right thigh, right shank, right "
           "foot): the hip, knee, ankle and foot angles are unreliable")  # fmt: skip


@needs_shared
def test_the_session_with_moved_markers_is_flagged_everywhere(tmp_path: Path) -> None:
    out = tmp_path / "report"
    result = run("report", SHARED_DATA / "cgm2" / "qualisys-cgm24-input", "--out", out, "--uncertainty", "none")
    assert result.returncode == 0, result.stderr
    terminal = " ".join((result.stdout + result.stderr).split())
    assert f"Gait - CGM2 1.c3d: {WARNING}" in terminal
    session = (out / "qualisys-cgm24-input" / "index.html").read_text(encoding="utf-8")
    assert f"Gait - CGM2 1.c3d: {WARNING}" in " ".join(session.split())
    index = " ".join((out / "index.html").read_text(encoding="utf-8").split())
    assert f"warning: {WARNING}" in index
    page = " ".join((out / "qualisys-cgm24-input" / "Gait_-_CGM2_1.html").read_text(encoding="utf-8").split())
    assert "LMED labelled LTOE?" in page and "RMED labelled RTOE?" in page  # the data quality notes
