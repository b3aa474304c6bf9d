"""Marker labels as labs write them (:mod:`fuzzygait.kinematics.marker_names`) and a trial
where no angle can be computed (:func:`fuzzygait.workflows.uncomputed.refuse_empty`).

Truth: the sample walking trial's own angles; its sacrum as the PSIS midpoint (what
Plug-in Gait uses when there is no SACR marker) relabelled ``VSAC`` must give the same
angles to rounding."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.errors import MarkerError
from fuzzygait.core.findings import messages
from fuzzygait.io import read_c3d, write_c3d
from fuzzygait.kinematics.marker_names import canonical_labels, canonical_name
from fuzzygait.workflows.angles import run_angles
from support import SAMPLE_DATA, assert_one_line_error, run_here


def _without_psis(sacrum: str | None) -> object:
    """walking.c3d with LPSI/RPSI replaced by one sacrum marker labelled ``sacrum`` at
    their midpoint (None: no sacrum at all)."""
    walking = read_c3d(SAMPLE_DATA / "walking.c3d")
    left, right = walking.marker_labels.index("LPSI"), walking.marker_labels.index("RPSI")
    keep = [k for k in range(walking.n_markers) if k not in (left, right)]
    markers, labels = walking.markers[:, keep], [walking.marker_labels[k] for k in keep]
    if sacrum is not None:
        midpoint = 0.5 * (walking.markers[:, left] + walking.markers[:, right])
        markers, labels = np.concatenate([markers, midpoint[:, None]], axis=1), [*labels, sacrum]
    return replace(walking, markers=markers, marker_labels=labels)


def test_names() -> None:
    assert canonical_name("VSAC") == "SACR" and canonical_name("vsac") == "SACR"
    assert canonical_name("lasi") == "LASI" and canonical_name("LASI") is None
    assert canonical_name("LFHD") is None and canonical_name("C_12") is None


@pytest.mark.parametrize("label", ["SACR", "VSAC", "sacr"])
def test_a_sacrum_under_any_of_its_labels_gives_the_psis_angles(label: str) -> None:
    reference = run_angles(SAMPLE_DATA / "walking.c3d")
    run = run_angles(_without_psis(label))
    for name, values in reference.result.angles.items():
        np.testing.assert_allclose(run.result.angles[name], values, atol=1e-9, err_msg=name)
    relabelled = [n for n in messages(run.notes) if n.startswith("marker labels read as the model's")]
    assert relabelled == ([] if label == "SACR" else [f"marker labels read as the model's: {label} as SACR"])


def test_an_alias_never_overwrites_the_model_label() -> None:
    trial = _without_psis("SACR")
    extra = replace(trial, markers=np.concatenate([trial.markers, trial.markers[:, :1] + 50.0], axis=1),
                    marker_labels=[*trial.marker_labels, "VSAC"])  # fmt: skip
    renamed, notes = canonical_labels(extra)
    assert renamed.marker_labels == extra.marker_labels and notes == []


def test_a_trial_without_any_angle_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(MarkerError, match="no joint angle can be computed by cgm1.0: markers LPSI, RPSI missing"):
        run_angles(_without_psis(None))
    path = tmp_path / "nosacrum.c3d"
    write_c3d(_without_psis(None), path)
    result = run_here("angles", path, "--out", tmp_path / "angles.csv")
    assert_one_line_error(result, "nosacrum.c3d", "no joint angle can be computed", "SACR (or LPSI and RPSI)")
    assert not (tmp_path / "angles.csv").exists()
