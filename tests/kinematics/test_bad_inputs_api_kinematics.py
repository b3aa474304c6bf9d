"""Bad input to the static calibration and the model versions gets one clear error naming
the marker or value and what to do (audit items 7, 9)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from fuzzygait.core.errors import ParameterError
from fuzzygait.core.trial import Trial
from fuzzygait.io import read_c3d
from fuzzygait.kinematics import static_calibration
from fuzzygait.kinematics.versions import model_version
from support import SAMPLE_DATA


@pytest.fixture(scope="module")
def static() -> Trial:
    return read_c3d(SAMPLE_DATA / "static.c3d")


def _blanked(static: Trial, label: str, frames: slice) -> Trial:
    markers = static.markers.copy()
    markers[frames, static.marker_labels.index(label)] = np.nan
    return static.with_markers(markers)


# ------------------------------------------------------------------ 7: static calibration
def test_a_marker_missing_in_every_static_frame_is_named_alone(static, subject) -> None:
    needle = r"static\.c3d: no frame shows every calibration marker: LTOE is missing in every frame; label or " \
             r"gap-fill them in the static trial$"  # fmt: skip
    with pytest.raises(ParameterError, match=needle):
        static_calibration(_blanked(static, "LTOE", slice(None)), subject)


def test_markers_never_seen_together_are_named_with_their_frames(static, subject) -> None:
    half = static.n_frames // 2
    trial = _blanked(_blanked(static, "LTOE", slice(None, half)), "RHEE", slice(half, None))
    with pytest.raises(ParameterError, match=rf"never all at once; seen least: (LTOE|RHEE) in \d+ of "
                                             rf"{static.n_frames} frames, (RHEE|LTOE) in"):  # fmt: skip
        static_calibration(trial, subject)
    assert static_calibration(_blanked(static, "LTOE", slice(None, half)), subject).left.static_plant_flex is not None


def test_an_unknown_knee_ankle_rule_is_called_unknown_first(static, subject) -> None:
    with pytest.raises(ParameterError, match=r"^unknown knee/ankle centre rule 'bogus'; choose one of medial, chord, "
                                             r"pycgm2$"):  # fmt: skip
        static_calibration(static, subject, knee_ankle_centres="bogus")
    with pytest.raises(ParameterError, match=r"cgm1\.0 places the knee and ankle centres by the chord"):
        static_calibration(static, subject, knee_ankle_centres="medial")


# ------------------------------------------------------------------ 9: model that is no string
@pytest.mark.parametrize("model", [None, 2.3, ["cgm1.0"]])
def test_a_model_that_is_not_a_string_gets_the_unknown_model_line(model) -> None:
    with pytest.raises(ParameterError, match=rf"^unknown model {re.escape(repr(model))}; choose one of auto, cgm1\.0"):
        model_version(model)  # type: ignore[arg-type]
    assert model_version("2.3").name == "cgm2.3"


def test_run_angles_refuses_model_none(walking) -> None:
    from fuzzygait.workflows.angles import run_angles

    with pytest.raises(ParameterError, match=r"^unknown model None; choose one of auto, cgm1\.0"):
        run_angles(walking, static=SAMPLE_DATA / "static.c3d", subject_file=SAMPLE_DATA / "subject.toml",
                   model=None)  # type: ignore[arg-type]  # fmt: skip
