"""The marker diameter recovered from a file's own Plug-in Gait outputs
(:mod:`fuzzygait.kinematics.marker_size`) and how a run settles it
(:func:`fuzzygait.workflows.subject_resolution.settle_marker_diameter`).

Truth: synthetic trials generated with 10, 14, 16 and 25 mm markers, their Nexus-style
outputs (pelvis axis markers, femur axis markers) written to C3D in float32 and read back,
and the reference files whose marker size is known (the FlatFoot session 16 mm, every
other Nexus file 14 mm: ``../shared/data/README.md``).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.io.subject import subject_from_processing
from fuzzygait.kinematics import ANGLE_NAMES
from fuzzygait.kinematics.marker_size import recover_marker_diameter
from fuzzygait.synthetic.generate import make_static_trial, make_walking_trial
from fuzzygait.synthetic.leg_model import SubjectGeometry
from fuzzygait.workflows.angles import Preprocessing, model_output_trial, run_angles
from fuzzygait.workflows.subject_resolution import settle_marker_diameter
from support import SAMPLE_DATA, needs_shared, nexus_angle_errors, shared_file


def _nexus_style_file(tmp_path: Path, diameter: float) -> tuple[Path, object]:
    """A synthetic walking trial made with ``diameter`` mm markers, written with the
    Plug-in Gait outputs of that diameter and a PROCESSING group without
    ``MarkerDiameter`` (as Nexus writes it); returns the file and the truth angles."""
    geometry = SubjectGeometry(marker_diameter=diameter)
    walking, truth = make_walking_trial(n_cycles=1, geometry=geometry)
    run = run_angles(walking, preprocessing=Preprocessing(filter=False))
    assert run.subject.marker_diameter == diameter  # the generator's PROCESSING states it
    out = model_output_trial(run)
    out.parameters.pop("MarkerDiameter")
    path = tmp_path / f"walking_{diameter:g}mm.c3d"
    write_c3d(out, path)
    return path, truth


@pytest.mark.parametrize("diameter", [10.0, 14.0, 16.0, 25.0])
def test_the_diameter_is_recovered_from_nexus_style_outputs(tmp_path: Path, diameter: float) -> None:
    path, truth = _nexus_style_file(tmp_path, diameter)
    trial = read_c3d(path)
    subject = subject_from_processing(trial.parameters)
    assert not subject.marker_diameter_stated
    found = recover_marker_diameter(trial, subject)
    assert found.diameter is not None and abs(found.diameter - diameter) <= 0.01
    assert len(found.estimates) == 4 and found.spread < 0.01
    # the run uses it, says so, and gets the generator's angles
    run = run_angles(path, preprocessing=Preprocessing(filter=False))
    assert run.subject.marker_diameter == pytest.approx(diameter, abs=0.01)
    assert any(n.startswith(f"marker diameter {found.diameter:g} mm, recovered from") for n in messages(run.notes))
    for name in ("LHipAngles", "RKneeAngles", "LAnkleAngles"):
        for k, axis in enumerate("XYZ"):
            error = np.abs(run.result.angles[name][:, k] - truth[f"{name}_{axis}"].to_numpy())
            assert error.max() < 2e-3, (name, axis, error.max())  # float32 markers


def test_a_stated_diameter_that_contradicts_the_file_is_a_warning(tmp_path: Path) -> None:
    path, _ = _nexus_style_file(tmp_path, 16.0)
    run = run_angles(path, marker_diameter=14.0)
    assert run.subject.marker_diameter == 14.0
    assert len(run.warnings) == 1
    assert "marker diameter 14 mm (as given) contradicts" in run.warnings[0] and "16.00 mm" in run.warnings[0]
    # within 0.5 mm: agreement, no warning
    close = run_angles(path, marker_diameter=16.4)
    assert close.warnings == [] and any("own Plug-in Gait outputs agree (16.00 mm)" in n for n in messages(close.notes))


def test_a_file_without_outputs_notes_the_assumed_diameter() -> None:
    walking = read_c3d(SAMPLE_DATA / "walking.c3d")
    params = {k: v for k, v in walking.parameters.items() if k != "MarkerDiameter"}
    run = run_angles(replace(walking, parameters=params))
    assert run.subject.marker_diameter == 14.0
    note = next(n for n in messages(run.notes) if n.startswith("marker diameter"))
    assert note.startswith("marker diameter 14 mm assumed") and "no Plug-in Gait hip joint centres" in note


def test_a_stated_diameter_without_evidence_is_used_and_named() -> None:
    run = run_angles(SAMPLE_DATA / "walking.c3d", subject_file=SAMPLE_DATA / "subject.toml")
    assert "marker diameter 14 mm (from subject.toml)" in messages(run.notes)


def test_other_subject_values_make_the_estimates_disagree(tmp_path: Path) -> None:
    """Leg lengths other than the file's: no diameter is recovered (the default, and why)."""
    path, _ = _nexus_style_file(tmp_path, 16.0)
    trial = read_c3d(path)
    subject = subject_from_processing({**trial.parameters, "LLegLength": 950.0, "RLegLength": 950.0,
                                       "LAsisTrocanterDistance": 0.0, "RAsisTrocanterDistance": 0.0})  # fmt: skip
    choice = settle_marker_diameter(subject, None, (trial,))
    assert choice.subject.marker_diameter == 14.0 and choice.recovered is not None
    assert choice.recovered.diameter is None and "inconsistent diameters" in choice.note.message


def test_the_static_trial_inter_asis_distance_replaces_the_processing_value() -> None:
    """With a static trial the inter-ASIS distance is measured on it, not taken from the
    walking trial's PROCESSING group (an earlier calibration's), and a difference is named."""
    walking = read_c3d(SAMPLE_DATA / "walking.c3d")
    static = make_static_trial()
    stale = replace(walking, parameters={**walking.parameters, "InterAsisDistance": 260.0})
    run = run_angles(stale, static=static)
    measured = float(np.linalg.norm(static.marker("LASI")[0] - static.marker("RASI")[0]))
    assert run.subject.inter_asis_distance == pytest.approx(measured, abs=1e-6)
    assert any("not walking.c3d PROCESSING group's 260.00 mm" in n for n in messages(run.notes))
    # the user's own subject file keeps its non-zero value
    own = run_angles(stale, static=static, subject_file=SAMPLE_DATA / "subject.toml")
    assert own.subject.inter_asis_distance == 250.0


# --------------------------------------------------------------------- reference files
NEXUS_FILES = [("pig-options", "PiGKad_Calibration.c3d", 14.0), ("pig-options", "PiGKad_Motion.c3d", 14.0),
               ("pig-options", "PiGKadMed_Calibration.c3d", 14.0), ("pig-options", "PiGKadMed_Motion.c3d", 14.0),
               ("pig-options", "PiG_Calibration-FlatFoot-Full.c3d", 16.0),
               ("pig-options", "PiG_Motion-FlatFoot-Full.c3d", 16.0),
               ("vicon", "Movement_trial.c3d", 14.0), ("vicon", "Static_trial.c3d", 14.0)]  # fmt: skip


@needs_shared
@pytest.mark.parametrize(("folder", "name", "diameter"), NEXUS_FILES)
def test_every_nexus_file_gives_its_marker_size(folder: str, name: str, diameter: float) -> None:
    trial = read_c3d(shared_file(folder, name))
    found = recover_marker_diameter(trial, subject_from_processing(trial.parameters))
    assert found.diameter == pytest.approx(diameter, abs=0.01)
    assert found.spread < 1e-3  # four independent estimates


@needs_shared
def test_the_flat_foot_session_matches_nexus_without_a_diameter() -> None:
    """16 mm markers, not stated anywhere in the file: recovered, and every angle within
    0.01° of Nexus (with 14 mm they were 0.6° off)."""
    motion = shared_file("pig-options", "PiG_Motion-FlatFoot-Full.c3d")
    run = run_angles(motion, preprocessing=Preprocessing(max_gap=0, filter=False))  # the markers Nexus used
    assert run.subject.marker_diameter == 16.0 and run.warnings == []
    errors = nexus_angle_errors(run.result.angles, run.raw, ANGLE_NAMES)
    assert max(float(e[0].max()) for e in errors.values()) <= 0.01
