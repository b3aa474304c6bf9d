"""The demo's CGM 2.4 part (the whole demo runs end to end in tests/cli/test_cli_angles.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fuzzygait.workflows.angles import Preprocessing, run_angles
from fuzzygait.workflows.demo import cgm24_session, truth_comparison
from support import SAMPLE_DATA


@pytest.fixture(scope="module")
def demo_part(tmp_path_factory) -> tuple[Path, list[str]]:
    out = tmp_path_factory.mktemp("demo")
    return out, cgm24_session(SAMPLE_DATA, out)


def test_cgm24_files_and_summary(demo_part) -> None:
    out, lines = demo_part
    text = "\n".join(lines)
    assert "model (`--model auto`) cgm2.4:" in text  # the richest version the markers support
    angles = pd.read_csv(out / "cgm24_angles.csv")
    assert len(angles) == 512 and "LKneeAngles_X" in angles
    accuracy = pd.read_csv(out / "cgm24_accuracy.csv")
    assert set(accuracy["model"]) == {"cgm2.4"}
    truth = pd.read_csv(SAMPLE_DATA / "cgm24_walking_truth_angles.csv")
    assert sorted(accuracy["angle"]) == sorted(c for c in truth.columns if c[-2:] in ("_X", "_Y", "_Z"))
    assert (accuracy["frames"] == 512).all()
    assert accuracy["max_deg"].max() < 0.01  # clean session, float32 markers
    for name in ("LPelvisAngles", "RForeFootAngles"):
        assert any(line.startswith(f"| {name} | ") for line in lines), name
    assert "not compared" not in text


def test_truth_comparison_skips_a_pelvis_in_another_order() -> None:
    """cgm1.0 reports the pelvis tilt first: not compared with a CGM 2.x (ROT) truth."""
    run = run_angles(SAMPLE_DATA / "cgm24_walking.c3d", static=SAMPLE_DATA / "cgm24_static.c3d",
                     preprocessing=Preprocessing(filter=False), model="cgm1.0")  # fmt: skip
    truth = pd.read_csv(SAMPLE_DATA / "cgm24_walking_truth_angles.csv")
    rot = truth_comparison(run, truth, pelvis_sequence="ROT")
    assert not rot["angle"].str.contains("Pelvis").any()
    assert rot["angle"].str.startswith("LHipAngles").any()
    tor = truth_comparison(run, pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv"))
    pelvis = tor[tor["angle"].str.contains("Pelvis")]
    assert len(pelvis) == 6 and np.all(pelvis["max_deg"] < 1e-3)
