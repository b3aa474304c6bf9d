"""A trial of one frame (issue 17: "a 1-frame trial in `uncertainty` → internal
ValueError"): `uncertainty` and `report` finish with their outputs, and no plotting
library warning reaches the user."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pytest
from support import SAMPLE_DATA, run

from fuzzygait.io import read_c3d
from fuzzygait.viz.report.figures import time_limits


def one_frame(tmp_path: Path) -> Path:
    """Frame 100 of the sample walking trial, with its subject parameters."""
    source = ezc3d.c3d(str(SAMPLE_DATA / "walking.c3d"))
    c3d = ezc3d.c3d()
    for name in ("RATE", "LABELS"):
        c3d["parameters"]["POINT"][name]["value"] = source["parameters"]["POINT"][name]["value"]
    c3d["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c3d["data"]["points"] = source["data"]["points"][:, :, 100:101]
    for name in source["parameters"]["PROCESSING"].keys():
        if name != "__METADATA__":
            c3d.add_parameter("PROCESSING", name, source["parameters"]["PROCESSING"][name]["value"])
    path = tmp_path / "one_frame.c3d"
    c3d.write(str(path))
    assert read_c3d(path).n_frames == 1
    return path


def test_time_limits_widen_a_single_instant() -> None:
    assert time_limits(np.array([1.25])) == (1.245, 1.255)
    assert time_limits(np.array([0.0, 0.01, 3.0])) == (0.0, 3.0)


@pytest.mark.slow  # the whole command end to end (~10 s)
def test_uncertainty_of_one_frame(tmp_path: Path) -> None:
    result = run("uncertainty", one_frame(tmp_path), "--alphas", "0", "--angles", "LKneeAngles",
                 "--out", tmp_path / "u.nc")  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "Error" not in result.stderr and "Traceback" not in result.stderr
    assert (tmp_path / "u.nc").is_file()


@pytest.mark.slow
def test_report_of_one_frame(tmp_path: Path) -> None:
    result = run("report", one_frame(tmp_path), "--out", tmp_path / "r", "--uncertainty", "fast")
    assert result.returncode == 0, result.stderr
    assert "1 of 1 trials OK" in result.stdout + result.stderr
    assert "xlim" not in result.stderr and "Traceback" not in result.stderr
    assert (tmp_path / "r" / "index.html").is_file()
