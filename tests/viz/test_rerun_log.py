"""Rerun recordings of the sample walking trial, read back with rerun's own chunk API.

rerun-sdk 0.41 has no ``rerun.dataframe`` module any more (``load_recording`` /
``Recording.view`` were deprecated in 0.28-0.32 and removed); the supported reader of an
``.rrd`` is ``rerun.chunk.RrdReader``, whose chunks convert to pyarrow record batches.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import FuzzyGaitError, ParameterError
from fuzzygait.kinematics.model import CGMResult
from fuzzygait.markererror.result import AngleAxes, component_hull, fuzzy_angles_dataset

rr = pytest.importorskip("rerun")
pa = pytest.importorskip("pyarrow")
xr = pytest.importorskip("xarray")

from fuzzygait.viz import rerun_log  # noqa: E402
from fuzzygait.workflows.rerun_recordings import write_recording  # noqa: E402

ALPHAS = np.array([0.0, 0.25, 0.5, 1.0])


@pytest.fixture(scope="module")
def fuzzy(angles_run):
    """A fuzzy result of the lead's layout: deterministic ± (1 − α)·2°."""
    trial, result = angles_run.trial, angles_run.result
    half = (1.0 - ALPHAS)[:, None] * 2.0
    hulls, deviations = {}, {}
    for name, values in result.angles.items():
        for k, axis in enumerate("XYZ"):
            centre = values[None, :, k]
            hulls[f"{name}_{axis}"] = np.stack([centre - half, centre + half], axis=1)
            deviations[f"{name}_{axis}"] = np.ones((len(ALPHAS), 2, trial.n_frames, trial.n_markers))
    return fuzzy_angles_dataset(hulls, AngleAxes(alphas=ALPHAS, frames=trial.frames, times=trial.times,
                                markers=trial.marker_labels, ball_radius=4.0 + np.arange(trial.n_markers) * 0.5),
                                deviations=deviations, attrs={"trial": trial.name})  # fmt: skip


@pytest.fixture(scope="module")
def fuzzy_rrd(angles_run, fuzzy, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rrd") / "walking.rrd"
    assert write_recording(path, angles_run.trial, angles_run.result, fuzzy) == path
    return path


@pytest.fixture(scope="module")
def plain_rrd(angles_run, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("rrd") / "walking_plain.rrd"
    write_recording(path, angles_run.trial, angles_run.result)
    return path


def entity_paths(path: Path) -> set[str]:
    return set(rr.chunk.RrdReader(path).store().schema().entity_paths())


def temporal_rows(path: Path, entity: str) -> pa.Table:
    """All time-varying rows of ``entity``, sorted by frame."""
    stream = rr.chunk.RrdReader(path).stream().filter(content=entity, is_static=False)
    batches = [chunk.to_record_batch() for chunk in stream.to_chunks()]
    assert batches, f"no temporal rows for {entity}"
    table = pa.Table.from_batches(batches) if len(batches) == 1 else pa.concat_tables(
        [pa.Table.from_batches([b]) for b in batches], promote_options="default"
    )
    return table.sort_by("frame")


def scalars(table: pa.Table) -> np.ndarray:
    return np.array([row[0] for row in table.column("Scalars:scalars").to_pylist()], dtype=float)


# ----------------------------------------------------------------------------- content
def test_entity_paths_with_fuzzy(fuzzy_rrd, angles_run):
    paths = entity_paths(fuzzy_rrd)
    expected = {"/world", "/world/markers", "/world/marker_balls", "/world/joint_centres"}
    expected |= {f"/world/segments/{name}" for name in angles_run.result.segment_frames}
    for angle in angles_run.result.angles:
        for axis in "XYZ":
            expected.add(f"/angles/{angle}/{axis}/deterministic")
            for alpha in ("0", "0.25", "0.5"):
                expected |= {f"/angles/{angle}/{axis}/alpha_{alpha}/{bound}" for bound in ("lower", "upper")}
    assert expected <= paths, sorted(expected - paths)
    assert not any("alpha_1" in p or "deviation" in p for p in paths)
    reader = rr.chunk.RrdReader(fuzzy_rrd)
    assert len(reader.recordings()) == 1
    assert reader.recordings()[0].application_id == "fuzzygait"


def test_frames_timeline_and_values(fuzzy_rrd, angles_run, fuzzy):
    trial, result = angles_run.trial, angles_run.result
    markers = temporal_rows(fuzzy_rrd, "/world/markers")
    assert markers.num_rows == trial.n_frames
    np.testing.assert_array_equal(markers.column("frame").to_numpy(), trial.frames)
    first = np.array(markers.column("Points3D:positions").to_pylist()[0])
    np.testing.assert_allclose(first, trial.markers[0], rtol=1e-6, atol=1e-3)  # float32 in Rerun
    assert markers.column("Points3D:labels").to_pylist()[0] == trial.marker_labels

    knee = temporal_rows(fuzzy_rrd, "/angles/LKneeAngles/X/deterministic")
    assert knee.num_rows == trial.n_frames
    np.testing.assert_array_equal(knee.column("frame").to_numpy(), trial.frames)
    seconds = knee.column("time").cast(pa.int64()).to_numpy() / 1e9
    np.testing.assert_allclose(seconds, trial.times, atol=1e-9)
    np.testing.assert_allclose(scalars(knee), result.angles["LKneeAngles"][:, 0].astype(np.float32), rtol=1e-6)

    upper = temporal_rows(fuzzy_rrd, "/angles/LKneeAngles/X/alpha_0.5/upper")
    assert upper.num_rows == trial.n_frames
    expected = component_hull(fuzzy, "LKneeAngles_X").sel(alpha=0.5, bound="upper").values
    np.testing.assert_allclose(scalars(upper), expected, rtol=1e-6)
    lower = temporal_rows(fuzzy_rrd, "/angles/RHipAngles/Z/alpha_0/lower")
    np.testing.assert_allclose(scalars(lower), angles_run.result.angles["RHipAngles"][:, 2] - 2.0, rtol=1e-6)


def test_balls_and_segments(fuzzy_rrd, angles_run, fuzzy):
    trial, result = angles_run.trial, angles_run.result
    balls = temporal_rows(fuzzy_rrd, "/world/marker_balls")
    assert balls.num_rows == trial.n_frames
    half_sizes = np.array(balls.column("Ellipsoids3D:half_sizes").to_pylist()[0])
    np.testing.assert_allclose(half_sizes[:, 0], fuzzy["ball_radius"].values)
    knee_frame = temporal_rows(fuzzy_rrd, "/world/segments/left_thigh")
    assert knee_frame.num_rows == trial.n_frames
    origins = np.array(knee_frame.column("Arrows3D:origins").to_pylist()[10])
    vectors = np.array(knee_frame.column("Arrows3D:vectors").to_pylist()[10])
    np.testing.assert_allclose(origins, np.repeat(result.joint_centres["LKJC"][10][None], 3, 0), atol=1e-3)
    np.testing.assert_allclose(vectors, 100.0 * result.segment_frames["left_thigh"][10].T, atol=1e-3)


def test_series_style_and_blueprint(fuzzy_rrd):
    reader = rr.chunk.RrdReader(fuzzy_rrd)
    style = reader.stream().filter(content="/angles/LKneeAngles/X/alpha_0.5/upper", is_static=True)
    (chunk,) = style.to_chunks()
    assert chunk.to_record_batch().column("SeriesLines:names").to_pylist() == [["Left α=0.5 upper"]]

    (blueprint,) = reader.blueprints()
    store = reader.store(store=blueprint)
    wanted = ["ViewBlueprint:class_identifier", "ContainerBlueprint:active_tab"]
    views, active = [], []
    for c in store.stream().filter(components=wanted).to_chunks():
        batch = c.to_record_batch()
        if "ViewBlueprint:class_identifier" in batch.schema.names:
            views += [v[0] for v in batch.column("ViewBlueprint:class_identifier").to_pylist()]
        if "ContainerBlueprint:active_tab" in batch.schema.names:
            active += batch.column("ContainerBlueprint:active_tab").to_pylist()
    assert views.count("TimeSeries") == 15 and views.count("3D") == 1
    assert len(active) == 1  # the Tabs container, opened on the angle grid


def test_without_fuzzy_no_balls_or_envelopes(plain_rrd, angles_run):
    paths = entity_paths(plain_rrd)
    assert "/world/markers" in paths and "/angles/LKneeAngles/X/deterministic" in paths
    assert not any("marker_balls" in p or "/alpha_" in p for p in paths)
    assert temporal_rows(plain_rrd, "/angles/RAnkleAngles/Y/deterministic").num_rows == angles_run.trial.n_frames
    # a dedicated stream: nothing leaks into rerun's global / thread-local recording
    assert rr.get_global_data_recording() is None
    assert rr.get_thread_local_data_recording() is None


def test_alphas_to_show(angles_run, fuzzy, tmp_path):
    path = write_recording(tmp_path / "a.rrd", angles_run.trial, angles_run.result, fuzzy, alphas_to_show=[0.5, 1.0])
    paths = entity_paths(path)
    assert "/angles/LKneeAngles/X/alpha_0.5/upper" in paths
    assert not any("alpha_0/" in p or "alpha_0.25" in p for p in paths)
    with pytest.raises(ParameterError, match="0.3"):
        write_recording(tmp_path / "b.rrd", angles_run.trial, angles_run.result, fuzzy, alphas_to_show=[0.3])
    assert not (tmp_path / "b.rrd").exists()


# ----------------------------------------------------------------------------- errors
def test_folder_that_is_a_file(angles_run, tmp_path):
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    target = blocker / "walking.rrd"
    with pytest.raises(FuzzyGaitError, match=str(target).replace("\\", "\\\\")):
        write_recording(target, angles_run.trial, angles_run.result)
    assert sorted(os.listdir(tmp_path)) == ["not_a_folder"]


def test_read_only_folder(angles_run, tmp_path):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        if os.access(folder, os.W_OK):
            pytest.skip("running with rights that ignore folder permissions (root)")
        target = folder / "walking.rrd"
        with pytest.raises(FuzzyGaitError, match=str(target)):
            write_recording(target, angles_run.trial, angles_run.result)
        assert os.listdir(folder) == []
    finally:
        folder.chmod(0o700)


def test_failure_mid_write_leaves_nothing(angles_run, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("simulated failure")

    monkeypatch.setattr(rerun_log, "_log_angles", broken)
    target = tmp_path / "walking.rrd"
    with pytest.raises(FuzzyGaitError, match="simulated failure") as info:
        write_recording(target, angles_run.trial, angles_run.result)
    assert str(target) in str(info.value)
    assert os.listdir(tmp_path) == []


def test_bad_suffix_and_missing_folder(angles_run, tmp_path):
    with pytest.raises(ParameterError, match=r"\.rrd"):
        write_recording(tmp_path / "walking.txt", angles_run.trial, angles_run.result)
    with pytest.raises(FuzzyGaitError, match="does not exist"):
        write_recording(tmp_path / "nope" / "walking.rrd", angles_run.trial, angles_run.result)
    assert os.listdir(tmp_path) == []


def test_missing_samples(angles_run, tmp_path):
    """NaN markers are left out of their frame's row; a NaN segment frame gives an empty
    row; NaN angles stay NaN (one row per frame everywhere)."""
    trial = angles_run.trial.with_markers(angles_run.trial.markers.copy())
    trial.markers[5, trial.marker_labels.index("LTOE")] = np.nan
    result = CGMResult(
        angles={k: v.copy() for k, v in angles_run.result.angles.items()},
        joint_centres=dict(angles_run.result.joint_centres),
        segment_frames={k: v.copy() for k, v in angles_run.result.segment_frames.items()},
    )
    result.segment_frames["left_foot"][7] = np.nan
    result.angles["LKneeAngles"][9] = np.nan
    path = write_recording(tmp_path / "gaps.rrd", trial, result)

    markers = temporal_rows(path, "/world/markers")
    assert markers.num_rows == trial.n_frames
    labels = markers.column("Points3D:labels").to_pylist()
    assert "LTOE" not in labels[5] and len(labels[5]) == trial.n_markers - 1 and "LTOE" in labels[6]
    assert len(markers.column("Points3D:positions").to_pylist()[5]) == trial.n_markers - 1
    foot = temporal_rows(path, "/world/segments/left_foot")
    assert foot.num_rows == trial.n_frames
    assert foot.column("Arrows3D:vectors").to_pylist()[7] == [] and len(foot.column("Arrows3D:vectors")[8]) == 3
    knee = scalars(temporal_rows(path, "/angles/LKneeAngles/X/deterministic"))
    assert np.isnan(knee[9]) and np.isfinite(knee[8])


def test_undetermined_frames(angles_run, tmp_path):
    """An undetermined alpha-cut: its bounds are gaps (NaN) there, and an
    ``undetermined`` point series marks those frames at the measured angle."""
    trial, result = angles_run.trial, angles_run.result
    knee = result.angles["LKneeAngles"][:, 0]
    alphas = np.array([0.0, 0.5, 1.0])
    flag = np.zeros((alphas.size, trial.n_frames), dtype=bool)
    flag[0, 20:30] = True
    half = np.where(flag, 175.0, (1.0 - alphas)[:, None] * 2.0)  # the frame flipped there
    axes = AngleAxes(alphas=alphas, frames=trial.frames, times=trial.times, markers=trial.marker_labels,
                     ball_radius=np.full(trial.n_markers, 20.0))  # fmt: skip
    fuzzy = fuzzy_angles_dataset({"LKneeAngles_X": np.stack([knee - half, knee + half], axis=1)}, axes,
                                 attrs={"trial": trial.name}, undetermined={"LKneeAngles_X": flag})  # fmt: skip
    path = write_recording(tmp_path / "undetermined.rrd", trial, result, fuzzy)
    upper = scalars(temporal_rows(path, "/angles/LKneeAngles/X/alpha_0/upper"))
    assert upper.size == trial.n_frames
    assert np.isnan(upper[20:30]).all() and np.isfinite(upper[:20]).all() and np.isfinite(upper[30:]).all()
    assert np.isfinite(scalars(temporal_rows(path, "/angles/LKneeAngles/X/alpha_0.5/lower"))).all()
    points = temporal_rows(path, "/angles/LKneeAngles/X/alpha_0/undetermined")
    np.testing.assert_array_equal(points.column("frame").to_numpy(), trial.frames[20:30])
    np.testing.assert_allclose(scalars(points), knee[20:30], rtol=1e-6)
    (style,) = rr.chunk.RrdReader(path).stream().filter(
        content="/angles/LKneeAngles/X/alpha_0/undetermined", is_static=True).to_chunks()  # fmt: skip
    batch = style.to_record_batch()
    assert batch.column("SeriesPoints:names").to_pylist() == [["Left α=0 undetermined"]]
    assert "SeriesPoints:markers" in batch.schema.names
    assert "/angles/LKneeAngles/X/alpha_0.5/undetermined" not in entity_paths(path)
