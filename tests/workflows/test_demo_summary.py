"""The demo summary's fuzzy part (:func:`fuzzygait.workflows.demo.uncertainty_lines`):
determined bands first, "undetermined" where the dataset says so (the whole demo runs
end to end in tests/cli/test_cli_angles.py)."""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.markererror.analysis import relative_envelope_width
from fuzzygait.markererror.result import AngleAxes, fuzzy_angles_dataset
from fuzzygait.workflows.angles import AnglesRun, run_angles
from fuzzygait.workflows.demo import uncertainty_lines
from support import SAMPLE_DATA, FakeAnalysis

ALPHAS = np.array([0.0, 0.5, 1.0])




def knee_analysis(run: AnglesRun, undetermined: dict[str, slice]) -> FakeAnalysis:
    """Knee angles ± 3 (1 − α) deg; ``undetermined[name]``: frames where α = 0 of that
    component is undetermined (bounds ±175° there)."""
    table = run.angle_table()
    hulls, flags = {}, {}
    for name in (f"{side}KneeAngles_{axis}" for side in "LR" for axis in "XYZ"):
        measured = table[name].to_numpy()
        flag = np.zeros((ALPHAS.size, measured.size), dtype=bool)
        if name in undetermined:
            flag[0, undetermined[name]] = True
        half = np.where(flag, 175.0, (1.0 - ALPHAS)[:, None] * 3.0)
        hulls[name], flags[name] = np.stack([measured - half, measured + half], axis=1), flag
    fuzzy = fuzzy_angles_dataset(hulls, AngleAxes(alphas=ALPHAS, frames=run.trial.frames, times=run.trial.times,
                                 markers=list(run.trial.marker_labels), ball_radius=np.full(run.trial.n_markers, 20.0)),
                                 attrs={"trial": run.trial.name}, undetermined=flags)  # fmt: skip
    return FakeAnalysis(run, fuzzy, relative_envelope_width(fuzzy))


@pytest.fixture(scope="module")
def noisy_run() -> AnglesRun:
    return run_angles(SAMPLE_DATA / "walking_noisy.c3d", static=SAMPLE_DATA / "static.c3d",
                      subject_file=SAMPLE_DATA / "subject.toml")  # fmt: skip


def _row(lines: list[str], name: str) -> list[str]:
    (line,) = [line for line in lines if line.startswith(f"| {name} |")]
    return [cell.strip() for cell in line.strip("|").split("|")]


def test_undetermined_cells_and_determined_bands_first(noisy_run: AnglesRun) -> None:
    flipping = {"LKneeAngles_X": slice(100, 140), "RKneeAngles_Z": slice(None)}
    lines = uncertainty_lines(knee_analysis(noisy_run, flipping))
    text = "\n".join(lines)
    assert "undetermined" in text and "thigh or shank frame flip" in text  # says what it means
    assert "360" not in text and "999" not in text
    assert _row(lines, "LKneeAngles_X")[2:] == ["undetermined", "40 of 512"]  # α = 0
    assert _row(lines, "LKneeAngles_X")[1].isdigit()  # α = 0.5 determined: a number
    assert _row(lines, "RKneeAngles_Z")[2:] == ["undetermined", "512 of 512"]
    assert _row(lines, "RKneeAngles_X")[2:] != ["undetermined", "none"] and _row(lines, "RKneeAngles_X")[3] == "none"
    bullets = [line for line in lines if line.startswith("- ")]
    assert bullets[0].startswith("- determined bands: largest flexion ΔΦ") and "RKneeAngles_X" in bullets[0]
    assert "at α = 0 " in bullets[0]  # the right knee flexion is determined at α = 0
    assert bullets[1] == ("- undetermined at α = 0: 2 of 6 components, flexion among them "
                          "(LKneeAngles_X on 40 of 512 frames)")  # fmt: skip


def test_every_band_determined(noisy_run: AnglesRun) -> None:
    lines = uncertainty_lines(knee_analysis(noisy_run, {}))
    assert "- every band is determined at α = 0" in lines
    rows = [line for line in lines if line.startswith("| ") and "KneeAngles" in line]
    assert len(rows) == 6 and all("undetermined" not in row for row in rows)


def test_accuracy_table_one_row_per_angle(noisy_run: AnglesRun) -> None:
    """The accuracy table groups the per-component comparison by angle: every value of
    :func:`truth_comparison` appears in its angle's row at its axis' position."""
    import pandas as pd

    from fuzzygait.workflows.demo import accuracy_lines, truth_comparison

    comparison = truth_comparison(noisy_run, pd.read_csv(SAMPLE_DATA / "walking_truth_angles.csv"))
    lines = accuracy_lines(comparison)
    rows = lines[2:]
    assert len(comparison) == 24 and len(rows) == 8  # 4 joints x 2 sides, X/Y/Z each
    for record in comparison.itertuples():
        name, axis = record.angle[:-2], "XYZ".index(record.angle[-1])
        rms, top = (cell.split(" / ") for cell in _row(lines, name)[1:])
        assert float(rms[axis]) == pytest.approx(record.rms_deg, abs=5e-4)
        assert float(top[axis]) == pytest.approx(record.max_deg, abs=5e-4)


def test_accuracy_table_marks_missing_components() -> None:
    import pandas as pd

    from fuzzygait.workflows.demo import accuracy_lines

    comparison = pd.DataFrame({"angle": ["LHipAngles_X", "LHipAngles_Z"], "rms_deg": [0.1, 0.3],
                               "max_deg": [0.2, 0.6], "frames": [10, 10]})  # fmt: skip
    assert accuracy_lines(comparison)[2] == "| LHipAngles | 0.100 / – / 0.300 | 0.200 / – / 0.600 |"
