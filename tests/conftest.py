"""Shared helpers and fixtures: where the reference data lives (skipping when it does not),
the `fuzzygait` command in a subprocess, the sample trials and a Dask cluster."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

# Small linear-algebra calls (scipy's optimisers, 3x3 frames) only lose time to BLAS
# threads on the 2-core CI machine; set before numpy is first imported.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

if TYPE_CHECKING:
    from distributed import LocalCluster

    from fuzzygait.core.trial import Trial
    from fuzzygait.io.subject import SubjectParameters
    from fuzzygait.workflows.angles import AnglesRun

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_DATA = ROOT / "sample_data"
SHARED_DATA = ROOT.parent / "shared" / "data"
VICON = SHARED_DATA / "vicon"
C3D_FORMATS = SHARED_DATA / "c3d-formats"

needs_shared = pytest.mark.skipif(
    not SHARED_DATA.is_dir(),
    reason=f"reference data {SHARED_DATA} is absent (it sits beside the clone in CI)",
)


def shared_file(*parts: str) -> Path:
    """Path of a reference file; skips the calling test when it is absent."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"reference file {path} is absent")
    return path


def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    """Run the `fuzzygait` command in a subprocess, as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "fuzzygait", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=300,
    )


def assert_one_line_error(result: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert result.returncode != 0
    assert "Traceback" not in result.stderr + result.stdout
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("fuzzygait: error: ")
    for needle in needles:
        assert needle in lines[0]


def cut(markers: np.ndarray, cuts: list[tuple[int, int, int]]) -> np.ndarray:
    """Copy of ``(frames, markers, 3)`` marker data with NaN runs ``(marker, start, length)``."""
    out = markers.copy()
    for m, start, length in cuts:
        out[start : start + length, m] = np.nan
    return out


# --------------------------------------------------------------------------- fixtures
# Module scope: each test module gets its own copy (all are cheap to make), so a test
# that changed one could not reach into another module.
@pytest.fixture(scope="module")
def walking() -> Trial:
    """sample_data/walking.c3d as read (the synthetic walking trial)."""
    from fuzzygait.io import read_c3d

    return read_c3d(SAMPLE_DATA / "walking.c3d")


@pytest.fixture(scope="module")
def truth() -> pd.DataFrame:
    """The true joint angles of walking.c3d (sample_data/walking_truth_angles.csv, deg)."""
    return pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv")


@pytest.fixture(scope="module")
def subject() -> SubjectParameters:
    """sample_data/subject.toml."""
    from fuzzygait.io.subject import read_subject

    return read_subject(SAMPLE_DATA / "subject.toml")


@pytest.fixture(scope="module")
def movement() -> Trial:
    """The Vicon Movement_trial.c3d of the reference data (skips when absent)."""
    from fuzzygait.io import read_c3d

    return read_c3d(shared_file("vicon", "Movement_trial.c3d"))


@pytest.fixture(scope="module")
def angles_run() -> AnglesRun:
    """The angles pipeline on walking.c3d, calibrated on static.c3d with subject.toml."""
    from fuzzygait.workflows.angles import run_angles

    return run_angles(SAMPLE_DATA / "walking.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


@pytest.fixture(scope="module")
def cluster() -> Iterator[LocalCluster]:
    """A 2-process Dask LocalCluster shared by the tests of a module (≈1.5 s to start)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, silence_logs=logging.ERROR,
        dashboard_address=None, scheduler_kwargs={"dashboard": False, "dashboard_address": "127.0.0.1:0"},
    ) as c:  # fmt: skip
        yield c
