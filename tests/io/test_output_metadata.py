"""What produced a file travels with it: table metadata (CSV column, Parquet schema and
attrs), C3D text parameters, nested TOML tables and the calibration table of a subject
file or a .vsk's sidecar."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from support import SAMPLE_DATA

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.calibration_table import read_calibration_table, sidecar_path, write_calibration_sidecar
from fuzzygait.io.subject import read_subject, write_subject
from fuzzygait.io.tables import write_table
from fuzzygait.io.tomlfile import toml_text

METADATA = {"model": "cgm2.3", "fuzzygait": "9.9"}


def _table() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    return pd.DataFrame({"frame": np.arange(1, 6), "LKneeAngles_X": rng.normal(size=5) * 30})


def test_csv_carries_the_model_as_a_last_column_plain_read_csv_reads(tmp_path: Path) -> None:
    table = _table()
    path = write_table(table, tmp_path / "a.csv", metadata=METADATA, columns=("model",))
    back = pd.read_csv(path)  # no comment= or skiprows= needed
    assert list(back.columns) == [*table.columns, "model"]
    assert set(back["model"]) == {"cgm2.3"}
    np.testing.assert_allclose(back["LKneeAngles_X"], table["LKneeAngles_X"], atol=5e-7)
    assert "model" not in table.columns  # the caller's table is left alone


def test_parquet_carries_the_model_in_column_schema_and_attrs(tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    table = _table()
    path = write_table(table, tmp_path / "a.parquet", metadata=METADATA, columns=("model",))
    back = pd.read_parquet(path)
    assert back.attrs["model"] == "cgm2.3" and back.attrs["fuzzygait"] == "9.9"
    assert set(back["model"]) == {"cgm2.3"}
    pd.testing.assert_frame_equal(back.drop(columns="model"), table, check_exact=True, check_dtype=False)
    schema = pq.read_schema(path).metadata
    assert schema[b"fuzzygait.model"] == b"cgm2.3" and schema[b"fuzzygait.fuzzygait"] == b"9.9"
    assert json.loads(schema[b"PANDAS_ATTRS"])["model"] == "cgm2.3"


def test_metadata_columns_must_be_metadata_and_new(tmp_path: Path) -> None:
    with pytest.raises(FuzzyGaitError, match="not in the metadata"):
        write_table(_table(), tmp_path / "a.csv", metadata=METADATA, columns=("static",))
    with pytest.raises(FuzzyGaitError, match="already table columns"):
        write_table(_table(), tmp_path / "a.csv", metadata={"frame": "x"}, columns=("frame",))
    assert not list(tmp_path.iterdir())


def test_without_metadata_tables_are_written_as_before(tmp_path: Path) -> None:
    table = _table()
    assert list(pd.read_csv(write_table(table, tmp_path / "a.csv")).columns) == list(table.columns)
    assert list(pd.read_parquet(write_table(table, tmp_path / "a.parquet")).columns) == list(table.columns)


def test_c3d_text_parameters_are_read_by_both_backends(tmp_path: Path) -> None:
    import c3d
    import ezc3d

    trial = read_c3d(SAMPLE_DATA / "walking.c3d")
    path = tmp_path / "t.c3d"
    write_c3d(trial, path, text_parameters={"fuzzygait": {"MODEL": "cgm2.3", "suffix": "_CGM_2.3"}})
    group = ezc3d.c3d(str(path))["parameters"]["FUZZYGAIT"]  # names upper case, as C3D has them
    assert group["MODEL"]["value"] == ["cgm2.3"] and group["SUFFIX"]["value"] == ["_CGM_2.3"]
    with path.open("rb") as handle, pytest.warns(UserWarning, match="analog"):
        assert c3d.Reader(handle).get("FUZZYGAIT:MODEL").string_value.strip() == "cgm2.3"
    back = read_c3d(path)  # our reader: the group does not disturb the trial
    np.testing.assert_allclose(back.markers, trial.markers, atol=1e-3, equal_nan=True)
    assert back.parameters == trial.parameters


def test_toml_text_writes_nested_tables_and_arrays_that_read_back_equal() -> None:
    document = {
        "LLegLength": 900.0,
        "calibration": {
            "model": "cgm2.3",
            "clusters": {"LThigh": {"markers": ["LTHI", "LKNE", "LTHAP"],
                                    "local": [[0.1 + 0.2, -2.5e-17, 205.0], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]}},
            "forefoot_joint_centres": {"L": [1.0, -2.0, 3.0]},
        },
        "odd key": {"empty": {}},
    }  # fmt: skip
    text = toml_text(document, ["made here"])
    assert tomllib.loads(text) == document
    assert "[calibration.clusters.LThigh]" in text and "\n\n\n" not in text
    with pytest.raises(ParameterError, match="cannot write"):
        toml_text({"a": [1.0, float("nan")]})


def test_calibration_table_of_a_toml_file_and_of_a_vsk_sidecar(tmp_path: Path) -> None:
    subject = read_subject(SAMPLE_DATA / "subject.toml")
    table = {"model": "cgm2.3", "clusters": {"LThigh": {"markers": ["A", "B", "C"], "local": [[0.0] * 3] * 3}}}
    toml = write_subject(subject, tmp_path / "cal.toml", metadata=table)
    assert read_calibration_table(toml) == (table, toml)
    assert read_subject(toml) == subject  # the subject parameters read as before
    vsk = write_subject(subject, tmp_path / "cal.vsk", metadata={"model": "cgm2.3", "clusters": {"x": {}}})
    assert read_calibration_table(vsk) == ({}, None)  # no sidecar yet; tables stay out of the .vsk
    assert "clusters" not in vsk.read_text()
    assert write_calibration_sidecar(vsk, table) == sidecar_path(vsk) == tmp_path / "cal.clusters.toml"
    assert read_calibration_table(vsk) == (table, tmp_path / "cal.clusters.toml")
    # a plain subject file (no [calibration] table) and one of the older flat tables
    assert read_calibration_table(SAMPLE_DATA / "subject.toml") == ({}, SAMPLE_DATA / "subject.toml")
    old = write_subject(subject, tmp_path / "old.toml", metadata={"static": "s.c3d", "method": "plain"})
    assert read_calibration_table(old)[0] == {"static": "s.c3d", "method": "plain"}
    bad = tmp_path / "bad.toml"
    bad.write_text((SAMPLE_DATA / "subject.toml").read_text() + '\ncalibration = "x"\n')
    with pytest.raises(ParameterError, match="must be a table"):
        read_calibration_table(bad)
