"""``fuzzygait report`` over session folders: --uncertainty, --pdf, warnings, re-runs."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support import SAMPLE_DATA, SHARED_DATA, VICON, assert_one_line_error, needs_shared, run, run_here, synthetic_session, trial_window


def test_bad_uncertainty_mode_is_one_line(tmp_path: Path) -> None:
    result = run_here("report", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "r", "--uncertainty", "quick")
    assert_one_line_error(result, "--uncertainty 'quick'", "none, fast, full")
    assert not (tmp_path / "r").exists()


def test_help_names_the_batch_options() -> None:
    result = run("report", "--help")
    assert result.returncode == 0
    for option in ("--uncertainty", "--pdf", "--scheduler", "--force", "--normative", "--workers"):
        assert option in result.stdout, option


@needs_shared
@pytest.mark.slow
def test_shared_sessions_angles_only(tmp_path: Path) -> None:
    """The acceptance run: vicon + pig-options, --uncertainty none, every trial a page or
    one line; the subject mismatch of gait-pig (A22 with Test.vsk) warned on stderr,
    its page and the index; a re-run reuses every trial."""
    out = tmp_path / "report"
    args = ("report", VICON, SHARED_DATA / "pig-options", "--out", out, "--uncertainty", "none", "--workers", "2")
    result = run(*args)
    assert result.returncode == 0, result.stderr
    # no traceback of ours (a loaded machine can make a Dask worker log a heartbeat timeout at shutdown)
    assert "Traceback" not in result.stdout and "fuzzygait: error" not in result.stderr
    assert not [line for line in result.stderr.splitlines() if line.strip().startswith("File") and "fuzzygait" in line]
    assert "report: 2 session(s), 6 of 6 trials OK" in result.stdout
    assert "fuzzygait: warning: vicon/gait-pig.c3d: subject mismatch: the trial is of subject 'A22'" in result.stderr
    index = (out / "index.html").read_text(encoding="utf-8")
    assert "subject mismatch" in index and "pig-options" in index
    assert "subject mismatch" in (out / "vicon" / "gait-pig.html").read_text(encoding="utf-8")
    assert "Static_trial.c3d (found by file name" in (out / "vicon" / "index.html").read_text(encoding="utf-8")
    again = run(*args)
    assert again.returncode == 0 and "6 unchanged (reused; --force recomputes)" in again.stdout


@pytest.mark.slow
def test_pdf_of_trial_and_session_pages(tmp_path: Path) -> None:
    session = tmp_path / "visit"
    session.mkdir()
    for name in ("static.c3d", "walking.c3d", "subject.toml"):
        shutil.copy(SAMPLE_DATA / name, session / name)
    out = tmp_path / "report"
    result = run("report", session, "--out", out, "--uncertainty", "none", "--pdf", "--workers", "1")
    assert result.returncode == 0, result.stderr
    for pdf in (out / "visit" / "walking.pdf", out / "visit" / "index.pdf"):
        assert pdf.read_bytes()[:5] == b"%PDF-" and pdf.stat().st_size > 10_000, pdf
    assert not [p for p in out.rglob("*") if p.name.startswith(".")], "temporary files left"


@pytest.mark.slow
def test_unreachable_scheduler_is_one_line_and_leaves_no_folder(tmp_path: Path) -> None:
    out = tmp_path / "r"
    result = run_here("report", SAMPLE_DATA / "walking.c3d", "--static", SAMPLE_DATA / "static.c3d", "--out", out,
                 "--uncertainty", "none", "--scheduler", "tcp://127.0.0.1:1")  # fmt: skip
    assert_one_line_error(result, "cannot reach the Dask scheduler at 'tcp://127.0.0.1:1'")
    assert not out.exists()


@pytest.mark.slow
def test_batch_killed_mid_run_resumes_without_recomputing(tmp_path: Path) -> None:
    """A real kill (SIGKILL of the whole process group, as a closed terminal or an OOM
    killer would) once the first trial is finished: no partial page is visible, and the
    re-run reuses the finished trial, computes the others and leaves no temporary file."""
    session = synthetic_session(tmp_path / "visit", 240)
    trial_window(SAMPLE_DATA / "walking.c3d", session / "walk03.c3d", 50, 240)
    out = tmp_path / "report"
    args = [sys.executable, "-m", "fuzzygait", "report", str(session), "--out", str(out), "--uncertainty", "none",
            "--workers", "1"]  # fmt: skip
    process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    finished = out / "visit" / "walk01_files" / "job.json"
    try:
        deadline = time.monotonic() + 300  # a generous bound for a loaded machine, not a timing assertion
        while not finished.exists() and process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert finished.exists(), "the first trial never finished"
        os.killpg(process.pid, signal.SIGKILL)
    finally:
        process.wait()
    pages = sorted(p.name for p in (out / "visit").glob("*.html"))
    assert "walk03.html" not in pages, "the batch finished before the kill: nothing was tested"
    for page in pages:  # whatever is visible is whole
        assert page == "index.html" or (out / "visit" / page.replace(".html", "_files") / "job.json").exists(), page
        assert (out / "visit" / page).read_text(encoding="utf-8").rstrip().endswith("</html>"), page
    again = run("report", session, "--out", out, "--uncertainty", "none", "--workers", "1")
    assert again.returncode == 0, again.stderr
    assert "3 of 3 trials OK" in again.stdout
    reused = int(again.stdout.split(" unchanged (reused")[0].split()[-1])
    assert reused >= 1  # walk01 at least was not recomputed
    assert not [p for p in out.rglob("*") if p.name.startswith(".")], "temporary files left"
