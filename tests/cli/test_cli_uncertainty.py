"""``fuzzygait uncertainty`` end to end (subprocess)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support import SAMPLE_DATA, VICON, assert_one_line_error, needs_shared, run, run_here

from fuzzygait.io import read_c3d
from fuzzygait.markererror.result import angle_components, component_hull
from fuzzygait.uncertainty import load_result

pytestmark = pytest.mark.slow  # each test runs the marker-error analysis in a subprocess

SAMPLE_ARGS = ("--static", SAMPLE_DATA / "static.c3d", "--subject", SAMPLE_DATA / "subject.toml")


def test_uncertainty_writes_dataset_and_recording(tmp_path: Path) -> None:
    out, rrd = tmp_path / "fuzzy.nc", tmp_path / "trial.rrd"
    result = run("uncertainty", SAMPLE_DATA / "walking.c3d", *SAMPLE_ARGS, "--angles", "LHipAngles",
                 "--alphas", "0,0.5", "--out", out, "--rrd", rrd, "--workers", "1")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "ΔΦ" in result.stdout and "LHipAngles_X" in result.stdout
    ds = load_result(out)
    assert set(ds["alpha"].to_numpy()) == {0.0, 0.5, 1.0}
    assert {"hull", "deviation", "ball_radius"} <= set(ds)
    assert angle_components(ds) == ["LHipAngles_X", "LHipAngles_Y", "LHipAngles_Z"]
    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    np.testing.assert_array_equal(ds["frame"].to_numpy(), trial.frames)
    hull = component_hull(ds, "LHipAngles_X")
    lower, upper = hull.sel(bound="lower"), hull.sel(bound="upper")
    # nested hulls around the measured angle; α = 1 is the measured curve itself
    assert bool((lower.sel(alpha=0.0) <= lower.sel(alpha=0.5) + 1e-9).all())
    assert bool((upper.sel(alpha=0.0) >= upper.sel(alpha=0.5) - 1e-9).all())
    np.testing.assert_array_equal(lower.sel(alpha=1.0), upper.sel(alpha=1.0))
    assert bool((upper.sel(alpha=0.5) > lower.sel(alpha=0.5)).all())
    assert rrd.stat().st_size > 100_000


def test_uncertainty_bad_arguments_are_one_line(tmp_path: Path) -> None:
    walking = SAMPLE_DATA / "walking.c3d"
    assert_one_line_error(run_here("uncertainty", walking, "--out", tmp_path / "x.csv"), ".nc or .zarr")
    assert_one_line_error(run_here("uncertainty", walking, "--out", tmp_path / "x.nc", "--alphas", "2"), "--alphas")
    assert_one_line_error(run_here("uncertainty", walking, "--out", tmp_path / "x.nc", "--sources", "magic"), "magic")
    assert_one_line_error(run_here("uncertainty", walking, "--out", tmp_path / "x.nc", "--angles", "LElbow"), "LElbow")
    assert not list(tmp_path.iterdir())


@needs_shared
def test_report_over_the_vicon_folder(tmp_path: Path) -> None:
    """Every walking trial of ../shared/data/vicon given as files (no session folder: no
    subject file found): a page or one clear error line, no traceback (reduced to one
    angle and one α-level for speed; the full run is in RESULTS.md)."""
    out = tmp_path / "report"
    trials = [VICON / name for name in ("Movement_trial.c3d", "gait-pig.c3d", "gait-raw.c3d")]
    result = run("report", *trials, "--out", out, "--angles", "LKneeAngles", "--alphas", "0.5", "--workers", "1")
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stdout + result.stderr
    index = (out / "index.html").read_text()
    assert (out / "Movement_trial.html").is_file()
    for name in ("Movement_trial.c3d", "gait-pig.c3d", "gait-raw.c3d"):
        assert name in index
    assert "Static_trial.c3d" not in index.split("Trials")[1].split("</table>")[0]  # a calibration trial
    failures = [line for line in result.stderr.splitlines() if line.startswith("fuzzygait: failed:")]
    assert len(failures) == 2 and all("--subject" in line for line in failures)
