"""``--per-source/--no-per-source`` of ``uncertainty`` and ``report`` (issue 15 Deliver 4):
the flexion bands of each error source alone by default, saved and printed (uncertainty)
or drawn (report); none with ``--no-per-source``.

Speed: the first 40 frames of the sample trial, left knee, α = 0, no tolerance, one worker.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.markererror.per_source import source_components, widest_source_bands
from fuzzygait.markererror.result import read_marker_result
from support import SAMPLE_DATA, run

pytestmark = pytest.mark.slow  # each test runs the marker-error analysis in a subprocess

SAMPLE_ARGS = ("--static", SAMPLE_DATA / "static.c3d", "--subject", SAMPLE_DATA / "subject.toml")
CHEAP = ("--angles", "LKneeAngles", "--alphas", "0", "--tolerance", "0", "--workers", "1")


@pytest.fixture(scope="module")
def short(tmp_path_factory: pytest.TempPathFactory) -> Path:
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    n = 40
    path = tmp_path_factory.mktemp("short") / "short.c3d"
    write_c3d(dataclasses.replace(trial, markers=trial.markers[:n], outputs={}, output_kinds={},
                                  events=[e for e in trial.events if e.time < n / trial.rate]), path)  # fmt: skip
    return path


def test_uncertainty_per_source_by_default_and_off(short: Path, tmp_path: Path) -> None:
    out = tmp_path / "fuzzy.nc"
    result = run("uncertainty", short, *SAMPLE_ARGS, *CHEAP, "--out", out)
    assert result.returncode == 0, result.stderr
    dataset = read_marker_result(out)
    assert source_components(dataset) == ["LKneeAngles_X"]
    assert "note: per-source bands (Fig. 5.9): measurement, placement, sta each alone" in result.stdout
    text = result.stdout.split("Widest α = 0 band per error source alone and all together")[1]
    (line,) = [line for line in text.splitlines() if line.startswith("LKneeAngles_X")]
    table = widest_source_bands(dataset)
    for source in ("measurement", "placement", "sta", "all"):
        assert f"{table.width('LKneeAngles_X', source):.1f}" in line, (source, line)
    assert line.rstrip().endswith(table.dominant("LKneeAngles_X") or "–")

    off = tmp_path / "off.nc"
    result = run("uncertainty", short, *SAMPLE_ARGS, *CHEAP, "--no-per-source", "--out", off)
    assert result.returncode == 0, result.stderr
    assert read_marker_result(off).sources is None and "Widest α = 0 band" not in result.stdout


def test_report_per_source_flag(short: Path, tmp_path: Path) -> None:
    on, off = tmp_path / "on", tmp_path / "off"
    for folder, flag in ((on, "--per-source"), (off, "--no-per-source")):
        result = run("report", short, *SAMPLE_ARGS, *CHEAP, flag, "--out", folder)
        assert result.returncode == 0, result.stderr
    page = (on / "short.html").read_text(encoding="utf-8")
    assert 'id="sources"' in page and (on / "short_files" / "sources.png").is_file()
    page = (off / "short.html").read_text(encoding="utf-8")
    assert 'id="sources"' not in page and not (off / "short_files" / "sources.png").exists()


def test_help_shows_the_flag() -> None:
    for command in ("uncertainty", "report"):
        result = run(command, "--help")
        assert result.returncode == 0 and "--per-source" in result.stdout and "--no-per-source" in result.stdout
