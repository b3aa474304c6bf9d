"""Every output of the angles pipeline names its model (issue 14): the angle tables (CSV,
Parquet), the model-output C3D (optionally suffixed labels), the uncertainty dataset and
the report page; the numbers are those of the run, whatever the names."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from fuzzygait import __version__
from fuzzygait.core.errors import FuzzyGaitError
from fuzzygait.core.findings import messages
from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.kinematics import ANGLE_NAMES, FOREFOOT_ANGLE_NAMES
from fuzzygait.uncertainty import load_result
from fuzzygait.workflows.angles import AngleOutputs, angles_to_files, output_suffix, run_angles
from fuzzygait.workflows.marker_uncertainty import MarkerErrorRequest, MarkerErrorSettings, analyse_to_files
from fuzzygait.workflows.report_folder import ReportItem, write_report
from fuzzygait.workflows.trial_inputs import TrialInputs
from support import SAMPLE_DATA

SAMPLE = {"static": SAMPLE_DATA / "static.c3d", "subject_file": SAMPLE_DATA / "subject.toml"}


def _outputs(folder: Path, kind: str, suffix: str = "") -> AngleOutputs:
    folder.mkdir(parents=True, exist_ok=True)
    return AngleOutputs(table=folder / f"angles.{kind}", cycles=folder / f"cycles.{kind}", c3d=folder / "model.c3d",
                        suffix=suffix)  # fmt: skip


def _fuzzygait_group(path: Path) -> dict[str, str]:
    group = ezc3d.c3d(str(path))["parameters"]["FUZZYGAIT"]
    return {name: group[name]["value"][0] for name in group if name != "__METADATA__"}


def test_plug_in_gait_outputs_name_cgm10_and_keep_vicon_names(tmp_path: Path) -> None:
    trial = TrialInputs(SAMPLE_DATA / "walking.c3d", model="cgm1.0", **SAMPLE)  # type: ignore[arg-type]
    run, written = angles_to_files(trial, _outputs(tmp_path, "csv"))
    assert run.model == "cgm1.0" and len(written) == 3
    assert "model cgm1.0 (given by name)" in messages(run.notes)
    table = pd.read_csv(tmp_path / "angles.csv")  # plain read_csv
    assert table.columns[-1] == "model" and set(table["model"]) == {"cgm1.0"}
    expected = run.frame_table()  # the sample trial has force plates: the kinetics columns too
    assert list(table.columns[:-1]) == list(expected.columns)
    np.testing.assert_allclose(table.drop(columns="model"), expected, atol=5e-7)  # %.6f
    cycles = pd.read_csv(tmp_path / "cycles.csv")
    assert cycles.columns[-1] == "model" and set(cycles["model"]) == {"cgm1.0"}
    c3d = read_c3d(tmp_path / "model.c3d")
    assert {name for name, kind in c3d.output_kinds.items() if kind == "angle"} == set(ANGLE_NAMES)
    assert _fuzzygait_group(tmp_path / "model.c3d") == {"MODEL": "cgm1.0", "VERSION": __version__}


def test_parquet_tables_carry_the_model_in_their_metadata(tmp_path: Path, angles_run) -> None:
    _outputs(tmp_path, "parquet").write(angles_run)
    table = pd.read_parquet(tmp_path / "angles.parquet")
    assert table.attrs["model"] == "cgm1.0" and table.attrs["fuzzygait"] == __version__
    pd.testing.assert_frame_equal(table.drop(columns="model"), angles_run.frame_table(), check_exact=True)
    cycles = pd.read_parquet(tmp_path / "cycles.parquet")
    assert cycles.attrs["model"] == "cgm1.0"
    pd.testing.assert_frame_equal(cycles.drop(columns="model"), angles_run.cycle_statistics(), check_exact=True)


@pytest.mark.parametrize("suffix, expected", [("model", "_CGM_1.0"), ("_mine", "_mine")])
def test_c3d_suffix_renames_the_angles_only_and_changes_no_number(tmp_path: Path, angles_run, suffix: str,
                                                                  expected: str) -> None:  # fmt: skip
    _outputs(tmp_path / "plain", "csv").write(angles_run)
    _outputs(tmp_path / "suffixed", "csv", suffix).write(angles_run)
    plain, suffixed = read_c3d(tmp_path / "plain" / "model.c3d"), read_c3d(tmp_path / "suffixed" / "model.c3d")
    assert _fuzzygait_group(tmp_path / "suffixed" / "model.c3d")["SUFFIX"] == expected
    for name in ANGLE_NAMES:
        assert name not in suffixed.outputs and suffixed.output_kinds[name + expected] == "angle"
        np.testing.assert_array_equal(suffixed.outputs[name + expected], plain.outputs[name])
    for name in ("LFEO", "LKJC", "RAJC"):  # virtual markers and joint centres keep Vicon's names
        np.testing.assert_array_equal(suffixed.outputs[name], plain.outputs[name])
    np.testing.assert_array_equal(suffixed.markers, plain.markers)
    assert suffixed.parameters == plain.parameters
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "plain" / "angles.csv"),
                                  pd.read_csv(tmp_path / "suffixed" / "angles.csv"))  # fmt: skip


def test_bad_suffixes_are_refused() -> None:
    assert output_suffix("", "cgm2.3") == "" and output_suffix("model", "cgm2.3") == "_CGM_2.3"
    for bad in ("with space", "_x/y", "_" + "x" * 13):
        with pytest.raises(FuzzyGaitError, match="suffix= "):
            output_suffix(bad, "cgm1.0")


def test_cgm23_outputs_name_cgm23(tmp_path: Path, cgm24_session: tuple[Path, Path]) -> None:
    static, walking = cgm24_session
    outputs = _outputs(tmp_path, "parquet", "model")
    run, _ = angles_to_files(TrialInputs(walking, static=static, model="cgm2.3"), outputs)
    assert run.model == "cgm2.3" and "model cgm2.3 (given by name)" in messages(run.notes)
    assert pd.read_parquet(tmp_path / "angles.parquet").attrs["model"] == "cgm2.3"
    assert set(pd.read_parquet(tmp_path / "cycles.parquet")["model"]) == {"cgm2.3"}
    c3d = read_c3d(tmp_path / "model.c3d")
    assert _fuzzygait_group(tmp_path / "model.c3d") == {"MODEL": "cgm2.3", "VERSION": __version__,
                                                        "SUFFIX": "_CGM_2.3"}  # fmt: skip
    for name in ANGLE_NAMES:
        np.testing.assert_allclose(c3d.outputs[name + "_CGM_2.3"], run.result.angles[name], atol=1e-4)  # float32


def test_forefoot_angles_join_the_table_when_the_result_has_them(angles_run) -> None:
    table = angles_run.angle_table()
    assert not any(name in column for name in FOREFOOT_ANGLE_NAMES for column in table.columns)
    ones = np.ones((angles_run.trial.n_frames, 3))
    angles = {**angles_run.result.angles, "LForeFootAngles": ones}
    result = dataclasses.replace(angles_run.result, model="cgm2.4", angles=angles,
                                 unavailable={"RForeFootAngles": "marker RFMH missing"})  # fmt: skip
    table = dataclasses.replace(angles_run, result=result).angle_table()
    assert table.attrs["model"] == "cgm2.4"
    assert list(table.columns[-6:]) == [f"{s}ForeFootAngles_{a}" for s in "LR" for a in "XYZ"]
    assert (table["LForeFootAngles_Y"] == 1.0).all() and table["RForeFootAngles_Z"].isna().all()


def test_cgm24_tables_have_the_forefoot_angles(cgm24_session: tuple[Path, Path]) -> None:
    static, walking = cgm24_session
    run = run_angles(walking, static=static, model="auto")
    if run.model != "cgm2.4":
        pytest.skip(f"auto chose {run.model}: CGM 2.4 not implemented in this tree")
    table = run.angle_table()
    for name in FOREFOOT_ANGLE_NAMES:
        assert table[f"{name}_X"].notna().all(), name


def _first_seconds(trial: Trial, seconds: float) -> Trial:
    """The first ``seconds`` of a trial, with its events (a cheap trial for the fuzzy analysis)."""
    n = int(seconds * trial.rate)
    return dataclasses.replace(trial, markers=trial.markers[:n], outputs={}, output_kinds={},
                               events=[e for e in trial.events if e.time < n / trial.rate])  # fmt: skip


@pytest.mark.slow  # the fuzzy analysis of one angle and a report page: about 6 s
def test_uncertainty_dataset_and_report_page_name_the_model(tmp_path: Path) -> None:
    short = tmp_path / "short.c3d"
    write_c3d(_first_seconds(read_c3d(SAMPLE_DATA / "walking.c3d"), 1.3), short)
    settings = MarkerErrorSettings(alphas=(0.0,), angles=("LKneeAngles",), workers=1)
    analysis = analyse_to_files(MarkerErrorRequest(TrialInputs(short, **SAMPLE), settings), tmp_path / "fuzzy.nc")
    assert analysis.fuzzy.attrs["model"] == "cgm1.0"
    assert load_result(tmp_path / "fuzzy.nc").attrs["model"] == "cgm1.0"
    write_report([ReportItem(short, analysis)], tmp_path / "report")
    page = (tmp_path / "report" / "short.html").read_text()
    header = page[page.index("<header>") : page.index("</header>")]
    assert "CGM 1.0 (Plug-in Gait)" in header
    assert "Angles: CGM 1.0 (Plug-in Gait) lower body" in page[page.index("<footer>") :]
