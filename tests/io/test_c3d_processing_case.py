"""C3D parameter names are case-insensitive: a PROCESSING group written in capitals (as
the ``c3d`` package reads every name) gives the same subject values as Vicon's spelling."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fuzzygait.io import read_c3d
from fuzzygait.io.subject import subject_from_processing
from support import SAMPLE_DATA


def test_processing_names_in_capitals(tmp_path: Path) -> None:
    import ezc3d

    source = read_c3d(SAMPLE_DATA / "walking.c3d")
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = np.array([source.rate])
    c["parameters"]["POINT"]["LABELS"]["value"] = list(source.marker_labels)
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    block = np.ones((4, source.n_markers, source.n_frames))
    block[:3] = source.markers.transpose(2, 1, 0)
    c["data"]["points"] = block
    for name, value in source.parameters.items():
        c.add_parameter("PROCESSING", name.upper(), np.array([float(value)]))
    path = tmp_path / "capitals.c3d"
    c.write(str(path))
    trial = read_c3d(path)
    assert trial.parameters.keys() == source.parameters.keys()
    assert subject_from_processing(trial.parameters) == subject_from_processing(source.parameters)
