"""The kinetics in a trial's Rerun recording (viz.rerun_kinetics), read back with rerun's
chunk API: the GRF arrows at the centres of pressure, the moment and power series."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.workflows.angles import AnglesRun, Preprocessing, run_angles
from support import shared_file

rr = pytest.importorskip("rerun")
pa = pytest.importorskip("pyarrow")

from fuzzygait.viz.rerun_kinetics import GRF_MM_PER_N  # noqa: E402
from fuzzygait.workflows.rerun_recordings import write_recording  # noqa: E402


@pytest.fixture(scope="module")
def movement() -> AnglesRun:
    return run_angles(shared_file("vicon", "Movement_trial.c3d"), preprocessing=Preprocessing(filter=False))


@pytest.fixture(scope="module")
def rrd(movement: AnglesRun, tmp_path_factory: pytest.TempPathFactory) -> Path:
    assert movement.kinetics is not None
    path = tmp_path_factory.mktemp("rrd") / "movement.rrd"
    return write_recording(path, movement.trial, movement.result, kinetics=movement.kinetics.data)


def _rows(path: Path, entity: str) -> pa.Table:
    stream = rr.chunk.RrdReader(path).stream().filter(content=entity, is_static=False)
    batches = [chunk.to_record_batch() for chunk in stream.to_chunks()]
    return pa.concat_tables([pa.Table.from_batches([b]) for b in batches], promote_options="default").sort_by("frame")


def test_grf_arrows_start_at_the_cop_one_mm_per_newton(rrd: Path, movement: AnglesRun) -> None:
    assert movement.kinetics is not None and GRF_MM_PER_N == 1.0
    data = movement.kinetics.data
    paths = set(rr.chunk.RrdReader(rrd).store().schema().entity_paths())
    assert {"/world/force_plates/grf", "/world/force_plates/outlines", "/kinetics/moment/Knee/X/L",
            "/kinetics/power/Ankle/R"} <= paths  # fmt: skip
    rows = _rows(rrd, "/world/force_plates/grf")
    assert rows.num_rows == movement.trial.n_frames
    frames = rows.column("frame").to_numpy()
    origins, vectors = rows.column("Arrows3D:origins").to_pylist(), rows.column("Arrows3D:vectors").to_pylist()
    labels = rows.column("Arrows3D:labels").to_pylist()
    checked = 0
    for frame, origin, vector, label in zip(frames, origins, vectors, labels, strict=True):
        cop = data["plate_cop"].sel(frame=frame).values  # (plate, axis)
        on = np.flatnonzero(np.all(np.isfinite(cop), axis=1))
        assert (label or []) == [f"plate {int(data['plate'][i])}" for i in on]
        if len(on):
            np.testing.assert_allclose(origin, cop[on], rtol=1e-6, atol=1e-3)
            force = data["plate_force"].sel(frame=frame).values[on]
            np.testing.assert_allclose(vector, force * GRF_MM_PER_N, rtol=1e-6, atol=1e-3)
            checked += 1
    assert checked > 200  # frames with a foot on a plate


def test_moment_and_power_series_are_the_dataset(rrd: Path, movement: AnglesRun) -> None:
    assert movement.kinetics is not None
    data = movement.kinetics.data
    for entity, expected in (("/kinetics/moment/Knee/X/L", data["moment"].sel(side="L", joint="Knee", axis="X")),
                             ("/kinetics/power/Ankle/R", data["power"].sel(side="R", joint="Ankle"))):  # fmt: skip
        rows = _rows(rrd, entity)
        values = np.array([row[0] for row in rows.column("Scalars:scalars").to_pylist()], dtype=float)
        np.testing.assert_allclose(values, expected.values, rtol=1e-12, equal_nan=True)
        assert np.nanmax(np.abs(values)) > 0.5  # N·m/kg or W/kg: a real gait curve


def test_kinetics_of_another_trial_are_refused(tmp_path: Path, movement: AnglesRun, angles_run: AnglesRun) -> None:
    assert movement.kinetics is not None
    with pytest.raises(ParameterError, match="the kinetics have 323 frames"):
        write_recording(tmp_path / "x.rrd", angles_run.trial, angles_run.result, kinetics=movement.kinetics.data)
    assert not (tmp_path / "x.rrd").exists()
