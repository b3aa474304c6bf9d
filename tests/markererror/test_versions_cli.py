"""``fuzzygait uncertainty`` / ``report --model`` (issue 15): the marker-error analysis by
the model version of the angles, named in the dataset (subprocess, a 1 s CGM 2.4 trial)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.uncertainty import load_result
from support import SAMPLE_DATA, assert_one_line_error, run, run_here

SESSION_ARGS = ("--static", SAMPLE_DATA / "cgm24_static.c3d", "--subject", SAMPLE_DATA / "cgm24_subject.toml")


@pytest.fixture(scope="module")
def short_walk(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The first second of the synthetic CGM 2.4 walking trial."""
    trial = read_c3d(SAMPLE_DATA / "cgm24_walking.c3d")
    n = int(trial.rate)
    short = dataclasses.replace(trial, markers=trial.markers[:n], outputs={}, output_kinds={},
                                events=[e for e in trial.events if e.time < n / trial.rate])  # fmt: skip
    path = tmp_path_factory.mktemp("cgm24") / "walk.c3d"
    write_c3d(short, path)
    return path


@pytest.mark.slow  # two marker-error analyses in subprocesses: about 12 s
@pytest.mark.parametrize(("model", "expected"), [("auto", "cgm2.4"), ("cgm2.3", "cgm2.3")])
def test_uncertainty_runs_the_model_version(tmp_path: Path, short_walk: Path, model: str, expected: str) -> None:
    out = tmp_path / "fuzzy.nc"
    result = run("uncertainty", short_walk, *SESSION_ARGS, "--model", model, "--angles", "LKneeAngles",
                 "--alphas", "0.5", "--workers", "1", "--out", out)  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert f"model {expected}" in result.stdout and f"{expected} marker model" in result.stdout
    fuzzy = load_result(out)
    assert fuzzy.attrs["model"] == expected
    assert "LTHAP" in fuzzy["marker"].to_numpy().tolist() and "LKNM" not in fuzzy["marker"].to_numpy().tolist()


@pytest.mark.slow
def test_unknown_model_is_one_line_before_work(tmp_path: Path) -> None:
    for command, out in (("uncertainty", tmp_path / "x.nc"), ("report", tmp_path / "rep")):
        result = run_here(command, tmp_path / "absent.c3d", "--model", "cgm3", "--out", out)
        assert_one_line_error(result, "--model", "cgm3", "cgm2.4")
        assert not out.exists()


def test_forefoot_angles_can_be_selected(tmp_path: Path) -> None:
    result = run_here("uncertainty", tmp_path / "absent.c3d", "--angles", "LForeFootAngles", "--out", tmp_path / "x.nc")
    assert_one_line_error(result, "absent.c3d")  # the angle name passed; the missing file stops it
