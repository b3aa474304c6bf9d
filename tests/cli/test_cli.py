"""The ``fuzzygait`` command, run as a user runs it (a subprocess; the one-line-error
checks in this process, ``support.run_here``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.io import read_c3d, write_c3d
from support import SAMPLE_DATA, SHARED_DATA, assert_one_line_error, needs_shared, run, run_here, shared_file


@needs_shared
def test_info_over_every_shared_file_summarises_or_gives_one_error_line() -> None:
    files = sorted(p for p in SHARED_DATA.rglob("*") if p.suffix.lower() == ".c3d")
    assert len(files) >= 12
    result = run("info", *files)
    assert "Traceback" not in result.stdout + result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("fuzzygait: error:")]
    summarised = [line for line in result.stdout.splitlines() if line and not line.startswith(" ")]
    # the corrupt parameter section is the one file that cannot be read
    assert len(errors) == 1 and "bad_parameter_section.c3d" in errors[0]
    assert sorted(summarised) == sorted(p.name for p in files if p.name != "bad_parameter_section.c3d")
    assert result.returncode == 1
    assert "rate 120 Hz, 323 frames (695-1017" in result.stdout


def test_info_on_sample_data() -> None:
    result = run("info", SAMPLE_DATA / "walking.c3d")
    assert result.returncode == 0, result.stderr
    assert "rate 100 Hz" in result.stdout
    assert "16 markers" in result.stdout
    assert "Left Foot Strike" in result.stdout and "Right Foot Off" in result.stdout
    assert "gaps: none" in result.stdout


def test_info_reports_gaps_of_the_noisy_sample() -> None:
    result = run("info", SAMPLE_DATA / "walking_noisy.c3d")
    assert result.returncode == 0, result.stderr
    assert "gaps: none" not in result.stdout


def test_missing_input_is_one_line_and_no_output(tmp_path: Path) -> None:
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", tmp_path / "nope.c3d", "--out", out)
    assert_one_line_error(result, "nope.c3d", "no such file")
    assert not out.exists()


def test_corrupt_input_is_one_line_and_no_output(tmp_path: Path) -> None:
    bad = tmp_path / "bad.c3d"
    bad.write_bytes(bytes(range(256)) * 8)
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", bad, "--out", out)
    assert_one_line_error(result, "bad.c3d")
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.c3d"]


def test_impossible_cutoff_is_one_line_and_no_output(tmp_path: Path) -> None:
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", SAMPLE_DATA / "walking.c3d", "--out", out, "--cutoff", "80")
    assert_one_line_error(result, "cutoff")
    assert not out.exists()


def test_output_must_be_c3d(tmp_path: Path) -> None:
    result = run_here("preprocess", SAMPLE_DATA / "walking.c3d", "--out", tmp_path / "out.csv")
    assert_one_line_error(result, "out.csv")


def test_preprocess_fills_and_filters_the_noisy_sample(tmp_path: Path) -> None:
    """Noise on slowly moving markers drops to well under half after the 6 Hz filter.

    White noise of sigma 0.5 mm at 100 Hz keeps ~12 % of its power below 6 Hz
    (sigma ~0.17 mm); foot markers move faster than 6 Hz allows and are not compared.
    """
    out = tmp_path / "clean.c3d"
    result = run("preprocess", SAMPLE_DATA / "walking_noisy.c3d", "--out", out)
    assert result.returncode == 0, result.stderr
    assert "filled" in result.stdout
    slow = ["LASI", "RASI", "LPSI", "RPSI", "LTHI", "RTHI", "LKNE", "RKNE"]
    truth = read_c3d(SAMPLE_DATA / "walking.c3d").select_markers(slow).markers
    noisy = read_c3d(SAMPLE_DATA / "walking_noisy.c3d").select_markers(slow).markers
    clean = read_c3d(out).select_markers(slow).markers
    both = np.isfinite(noisy).all(axis=2)
    err_in = np.sqrt(np.mean((noisy[both] - truth[both]) ** 2))
    err_out = np.sqrt(np.mean((clean[both] - truth[both]) ** 2))
    assert 0.45 < err_in < 0.55
    assert err_out < 0.5 * err_in
    # the short gaps are filled, the long and the edge gaps are not
    assert np.isnan(clean).sum() < np.isnan(noisy).sum()


def _cut_gaps(markers: np.ndarray, lengths: range, seed: int) -> np.ndarray:
    """Cut gaps of the given lengths (frames) into every marker, 25+ frames apart."""
    rng = np.random.default_rng(seed)
    cut = markers.copy()
    n = markers.shape[0]
    for column in range(markers.shape[1]):
        start = 15 + int(rng.integers(0, 10))
        for length in rng.permutation(list(lengths)).tolist() * 3:
            if start + length + 15 >= n:
                break
            cut[start : start + length, column] = np.nan
            start += length + 25 + int(rng.integers(0, 10))
    return cut


def _preprocess_cut_trial(tmp_path: Path, source: Path, lengths: range) -> tuple[float, int]:
    trial = read_c3d(source)
    complete = [m for m in trial.marker_labels if np.isfinite(trial.marker(m)).all()]
    whole = trial.select_markers(complete)
    cut = whole.with_markers(_cut_gaps(whole.markers, lengths, seed=3))
    write_c3d(cut, tmp_path / "cut.c3d")
    result = run("preprocess", tmp_path / "cut.c3d", "--out", tmp_path / "filled.c3d", "--no-filter")
    assert result.returncode == 0, result.stderr
    filled = read_c3d(tmp_path / "filled.c3d").markers
    holes = ~np.isfinite(cut.markers).all(axis=2)
    assert np.isfinite(filled[holes]).all()
    err = np.linalg.norm(filled[holes] - whole.markers[holes], axis=1)
    return float(np.sqrt(np.mean(err**2))), int(holes.sum())


@needs_shared
def test_preprocess_no_filter_refills_cut_gaps_at_120_hz(tmp_path: Path) -> None:
    """Acceptance: gaps of 1-10 frames cut into a complete 120 Hz Vicon walking trial."""
    rms, n = _preprocess_cut_trial(tmp_path, shared_file("vicon", "Movement_trial.c3d"), range(1, 11))
    print(f"Movement_trial (120 Hz), gaps 1-10 frames: RMS {rms:.3f} mm over {n} samples")
    assert n > 2000
    assert rms < 1.0


@needs_shared
def test_preprocess_no_filter_refills_short_gaps_at_50_hz(tmp_path: Path) -> None:
    """At 50 Hz a cubic spline keeps RMS < 1 mm for gaps up to 3 frames (60 ms).

    Longer gaps at 50 Hz exceed 1 mm (foot markers in swing move too fast for any
    interpolation); benchmarks/gap_fill_accuracy.py prints the full table.
    """
    rms, n = _preprocess_cut_trial(tmp_path, shared_file("vicon", "gait-pig.c3d"), range(1, 4))
    print(f"gait-pig (50 Hz), gaps 1-3 frames: RMS {rms:.3f} mm over {n} samples")
    assert n > 50
    assert rms < 1.0


def test_version_and_help() -> None:
    result = run("--version")
    assert result.returncode == 0 and result.stdout.startswith("fuzzygait ")
    result = run("--help")
    assert result.returncode == 0
    for command in ("info", "preprocess", "sample-data"):
        assert command in result.stdout


def test_the_command_list_gives_each_command_one_row() -> None:
    """``fuzzygait --help`` at 80 columns: every command's summary fits its row (a
    command's full description is its own ``--help``)."""
    from typer.main import get_command

    from fuzzygait.cli.app import app

    names = sorted(get_command(app).commands)  # type: ignore[attr-defined]
    assert len(names) >= 14
    result = subprocess.run([sys.executable, "-m", "fuzzygait", "--help"], capture_output=True, text=True,
                            env={**os.environ, "COLUMNS": "80", "TERM": "dumb"}, timeout=60)  # fmt: skip
    listing = result.stdout.split("Commands")[1].split("╰")[0]
    rows = listing.splitlines()[1:]  # after the box's top line
    assert sorted(row.split()[1] for row in rows) == names, result.stdout


@pytest.mark.parametrize("args", [("preprocess",), ("info",)])
def test_usage_errors_exit_non_zero(args: tuple[str, ...]) -> None:
    result = run(*args)
    assert result.returncode != 0
    assert "Traceback" not in result.stderr


SLOW = pytest.mark.slow  # three of the six in the fast selection


@pytest.mark.parametrize("args", [
    ("angles", "absent.c3d", "--out", "a.csv"),
    pytest.param(("uncertainty", SAMPLE_DATA / "walking.c3d", "--out", "u.nc", "--tolerance=-1"), marks=SLOW),
    pytest.param(("calibrate", SAMPLE_DATA / "static.c3d", "--marker-diameter", "500", "--out", "c.toml"), marks=SLOW),
    ("simulate", "swing", "--nodes", "0", "--out", "s.nc"),
    ("angles", "--no-such-option"),
    pytest.param(("info", SAMPLE_DATA / "walking.c3d"), marks=SLOW),
])  # fmt: skip
def test_run_here_gives_what_a_subprocess_gives(args, tmp_path, monkeypatch) -> None:
    """The in-process runner the one-line-error tests use: the same exit code, stdout and
    stderr as the command in its own process (errors of every kind, and a success)."""
    monkeypatch.chdir(tmp_path)
    here, there = run_here(*args), run(*args)
    assert (here.returncode, here.stdout, here.stderr) == (there.returncode, there.stdout, there.stderr)
    assert not list(tmp_path.iterdir())
