"""C3D write-back of the input's points: a file the package writes from an input keeps
every point of the input it does not change as the input stores it -- coordinates,
residuals, cameras, descriptions, units -- and never replaces the input itself.

* ``angles --c3d-out`` writes the markers as measured (the model saw them filled and
  filtered; a second run on the written file then filters once, not twice);
* ``preprocess`` writes the processed markers: a changed or filled sample is valid with
  residual 0 (C3D's mark of a computed point) and keeps the cameras of the sample it
  replaces;
* a file in metres is written in metres, so that its force plates' corners (in the
  same unit) still fit;
* the input's zero-marked gaps (Nexus' outputs where it computed none) come back as
  they were.
"""

from __future__ import annotations

import struct
from dataclasses import replace
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from fuzzygait.core.errors import C3DError
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.c3d_params import read_section
from fuzzygait.io.c3d_writeback import splice
from fuzzygait.workflows.angles import AngleOutputs, Preprocessing, model_output_trial, replaced_outputs, run_angles
from support import SAMPLE_DATA, assert_points_kept, run_here, stored_points, write_cut

#: Descriptions given to the source's points and to its ``POINT:RATE`` record.
RATE_DESCRIPTION = b"* Point data rate (Hz)"


def point_source(path: Path, *, metres: bool = False) -> Path:
    """``sample_data/walking.c3d`` (two force plates) with measured residuals (0.3-2.5),
    every camera mask set at random, a description per point, 3 % of the marker samples
    invalid, ``LTOE`` marked missing by zeros at frames 10-19 (coordinates 0, residual 0,
    as some writers mark gaps), a ``POINT:SCALAR_UNITS`` without scalars and a
    description of ``POINT:RATE``; ``metres``: every length in metres (points, the force
    plates' corners and origin)."""
    c = ezc3d.c3d(str(SAMPLE_DATA / "walking.c3d"))
    rng = np.random.default_rng(7)
    points = c["data"]["points"]
    n_points, n_frames = points.shape[1:]
    labels = [str(label).strip() for label in c["parameters"]["POINT"]["LABELS"]["value"]]
    residuals = rng.uniform(0.3, 2.5, (1, n_points, n_frames))
    invalid = rng.random((n_points, n_frames)) < 0.03
    residuals[0][invalid] = -1.0
    points[:3][:, invalid] = 0.0
    toe = labels.index("LTOE")
    points[:3, toe, 9:19], residuals[0, toe, 9:19] = 0.0, 0.0
    if metres:
        points[:3] /= 1000.0
        c["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
        for name in ("CORNERS", "ORIGIN"):
            c["parameters"]["FORCE_PLATFORM"][name]["value"] = c["parameters"]["FORCE_PLATFORM"][name]["value"] / 1000
    c["data"]["points"] = points
    c["data"]["meta_points"]["residuals"] = residuals
    c["data"]["meta_points"]["camera_masks"] = rng.random((7, n_points, n_frames)) < 0.5
    c["parameters"]["POINT"]["DESCRIPTIONS"]["value"] = [f"the {label} marker" for label in labels]
    c.add_parameter("POINT", "SCALAR_UNITS", ["mm"])
    c.write(str(path))
    data = path.read_bytes()
    section = read_section(data)
    point = section["POINT"].parameters
    point["RATE"] = replace(point["RATE"], description=RATE_DESCRIPTION)
    path.write_bytes(splice(data, section))
    return path


def test_angles_c3d_out_keeps_what_it_does_not_change(tmp_path: Path) -> None:
    """The written markers are the ones the model saw (filled and filtered, as Nexus saves
    a processed trial): every changed sample is marked computed, the rest as stored."""
    src = point_source(tmp_path / "in.c3d")
    out = tmp_path / "out.c3d"
    result = run_here("angles", src, "--c3d-out", out, "--subject", SAMPLE_DATA / "subject.toml")
    assert result.returncode == 0, result.stderr
    assert assert_points_kept(src, out) > 0
    after = stored_points(out)
    for name in ("LKneeAngles", "LHJC"):  # ours: computed points (residual 0 where valid), no description
        residual = after[name][1]
        assert (residual == 0.0).sum() > 400 and np.all((residual == 0.0) | (residual == -1.0)), name
        assert not after[name][2].any() and after[name][3] == "", name
    section = read_section(out.read_bytes())["POINT"].parameters
    assert section["RATE"].description == RATE_DESCRIPTION
    assert section["SCALAR_UNITS"].strings() == ["mm"]


def test_preprocess_without_a_filter_keeps_the_measured_samples(tmp_path: Path) -> None:
    src = point_source(tmp_path / "in.c3d")
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", src, "--out", out, "--no-filter")
    assert result.returncode == 0, result.stderr
    assert assert_points_kept(src, out) >= 10  # the gaps filled, LTOE's zero-marked one among them
    before, after = stored_points(src), stored_points(out)
    label = read_c3d(src).marker_labels[0]
    measured = before[label][1] >= 0
    assert np.array_equal(after[label][1][measured], before[label][1][measured])  # untouched: as stored
    assert np.array_equal(after[label][2][:, measured], before[label][2][:, measured])


def test_zero_marked_gaps_the_reader_keeps_are_written_back_as_they_were(tmp_path: Path) -> None:
    src = point_source(tmp_path / "in.c3d")
    out = tmp_path / "out.c3d"
    result = run_here("preprocess", src, "--out", out, "--no-filter", "--max-gap", "0")
    assert result.returncode == 0, result.stderr
    before, after = stored_points(src), stored_points(out)
    for label in read_c3d(src).marker_labels:
        for kind, a, b in zip(("coordinates", "residuals", "cameras", "description"), before[label], after[label]):
            assert np.array_equal(a, b), f"{label}: {kind}"
    toe = after["LTOE"]
    assert np.all(toe[0][:, 9:19] == 0.0) and np.all(toe[1][9:19] == 0.0)


def test_a_file_in_metres_is_written_in_metres_and_its_kinetics_still_fit(tmp_path: Path) -> None:
    src = point_source(tmp_path / "in.c3d", metres=True)
    out = tmp_path / "out.c3d"
    subject = SAMPLE_DATA / "subject.toml"
    first = run_angles(src, subject_file=subject)
    assert first.kinetics is not None
    AngleOutputs(c3d=out).write(first)
    assert ezc3d.c3d(str(out))["parameters"]["POINT"]["UNITS"]["value"] == ["m"]
    after = stored_points(out)
    for i, label in enumerate(first.trial.marker_labels):  # the processed markers, in m
        assert np.allclose(after[label][0], np.nan_to_num(first.trial.markers[:, i].T / 1000.0), atol=1e-6), label
    expected = np.nan_to_num(first.result.virtual_markers["LHJC"].T / 1000.0)  # written in m, 0 where missing
    assert np.allclose(after["LHJC"][0], expected, atol=1e-6)
    second = run_angles(out, subject_file=subject, preprocessing=Preprocessing(filter=False, max_gap=0))
    assert second.kinetics is not None  # the plates, in m as the markers, still under the feet
    moment_a, moment_b = first.kinetics.data["moment"], second.kinetics.data["moment"]
    assert np.isfinite(moment_a).any()
    assert np.allclose(moment_a, moment_b, atol=0.02, equal_nan=True)  # N·m/kg: the file's markers are float32


def test_the_output_never_replaces_its_input(tmp_path: Path) -> None:
    src = point_source(tmp_path / "in.c3d")
    before = src.read_bytes()
    with pytest.raises(C3DError, match="is the input file"):
        write_c3d(read_c3d(src), tmp_path / "." / "in.c3d", source=src)
    link = tmp_path / "link.c3d"
    link.symlink_to(src)
    with pytest.raises(C3DError, match="is the input file"):
        write_c3d(read_c3d(src), link, source=src)
    assert src.read_bytes() == before
    for argv in (["preprocess", src, "--out", tmp_path / "in.c3d"],
                 ["angles", src, "--c3d-out", src, "--subject", SAMPLE_DATA / "subject.toml"],
                 ["angles", SAMPLE_DATA / "walking.c3d", "--static", src, "--c3d-out", src,
                  "--subject", SAMPLE_DATA / "subject.toml"]):  # fmt: skip
        result = run_here(*argv)
        assert result.returncode == 1 and "is the input file" in result.stderr, result.stderr
        assert len(result.stderr.strip().splitlines()) == 1
    assert src.read_bytes() == before


def test_a_name_that_is_no_c3d_file_is_refused(tmp_path: Path) -> None:
    with pytest.raises(C3DError, match=r"out\.txt: the output must name a \.c3d file"):
        write_c3d(read_c3d(SAMPLE_DATA / "walking.c3d"), tmp_path / "out.txt")
    assert not list(tmp_path.iterdir())


def test_with_a_suffix_the_input_outputs_are_all_kept(tmp_path: Path) -> None:
    """Without a suffix ours replace the input's own outputs (a note names them); with
    one, every output of the input is kept as stored, the virtual markers too."""
    src = point_source(tmp_path / "in.c3d")
    subject = SAMPLE_DATA / "subject.toml"
    ours = tmp_path / "ours.c3d"
    AngleOutputs(c3d=ours).write(run_angles(src, subject_file=subject))
    again = run_angles(ours, subject_file=subject, preprocessing=Preprocessing(filter=False))
    names = replaced_outputs(again, model_output_trial(again))
    assert {"LKneeAngles", "PELO", "LHJC"} <= set(names)
    replaced = tmp_path / "replaced.c3d"
    AngleOutputs(c3d=replaced).write(again)
    note = [n.message for n in again.notes if "ours replace the input's own" in n.message]
    assert note == [f"replaced.c3d: ours replace the input's own {', '.join(names[:6])} and {len(names) - 6} more "
                    "(suffix= keeps them beside ours)"]  # fmt: skip
    kept = tmp_path / "kept.c3d"
    beside = run_angles(ours, subject_file=subject, preprocessing=Preprocessing(filter=False))
    AngleOutputs(c3d=kept, suffix="_FG").write(beside)
    assert not [n for n in beside.notes if "ours replace" in n.message]
    before, after = stored_points(ours), stored_points(kept)
    for label in read_c3d(ours).outputs:
        assert np.array_equal(before[label][0], after[label][0]), label
    assert {"PELO_FG", "LHJC_FG", "LKneeAngles_FG"} <= set(after)


def test_a_folder_the_system_refuses_is_one_line(tmp_path: Path) -> None:
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    result = run_here("angles", SAMPLE_DATA / "walking.c3d", "--subject", SAMPLE_DATA / "subject.toml",
                      "--out", blocker / "sub" / "angles.csv")  # fmt: skip
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip().splitlines() == [
        f"fuzzygait: error: {blocker / 'sub'}: Not a directory; check the path, its folder and its permissions"
    ]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def test_points_of_a_cut_trial_keep_their_residuals(tmp_path: Path) -> None:
    src = point_source(tmp_path / "in.c3d")
    out = tmp_path / "cut.c3d"
    first, count = 101, 200
    trial = write_cut(src, out, first, count)
    before, after = stored_points(src), stored_points(out)
    for label in trial.marker_labels:
        assert np.array_equal(before[label][1][first - 1 : first - 1 + count], after[label][1]), label
    assert struct.unpack("<H", out.read_bytes()[6:8])[0] == first  # header: first frame


def test_ground_reaction_outside_the_plates_is_missing_as_nexus_leaves_it(tmp_path: Path) -> None:
    """The foot's ground reaction is known only where a plate carries it: elsewhere (swing,
    the floor between plates) the output is missing, not a valid zero."""
    run = run_angles(SAMPLE_DATA / "walking.c3d", subject_file=SAMPLE_DATA / "subject.toml")
    assert run.kinetics is not None
    outputs = run.kinetics.nexus_outputs()
    for side in "LR":
        grf = outputs[side + "GroundReactionForce"][0]
        carried = np.any(run.kinetics.data["ground_force"].sel(side=side).values != 0.0, axis=0)
        assert 30 < carried.sum() < 100  # one plate contact of the five stances
        assert np.all(np.isfinite(grf[carried])) and np.all(np.isnan(grf[~carried]))
    out = tmp_path / "out.c3d"
    AngleOutputs(c3d=out).write(run)
    residuals = stored_points(out)["LGroundReactionForce"][1]
    assert np.array_equal(residuals >= 0, np.isfinite(outputs["LGroundReactionForce"][0]).all(axis=1))
