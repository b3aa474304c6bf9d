"""The per-source bands in the marker-error workflow (issue 15 Deliver 4): computed by
default after the fuzzy analysis and the allowable refinement on the same evaluator, off
with ``per_source=False``, skipped with a note when one source is selected; one notes line;
progress through every stage (fuzzy angles, allowable error, per-source bands); saved.

Speed: the sample trial cut to 6 frames (markers NaN elsewhere), left knee, α = 0 and 0.5,
one worker (as test_marker_uncertainty_allowable.py).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from fuzzygait.core.findings import messages
from fuzzygait.markererror.per_source import source_components, source_names, widest_source_bands
from fuzzygait.markererror.result import read_marker_result
from fuzzygait.workflows import trial_inputs
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.marker_uncertainty import (
    MarkerErrorRequest,
    MarkerErrorSettings,
    analyse_run,
    analyse_to_files,
)
from fuzzygait.workflows.progress import Prefixed
from fuzzygait.workflows.trial_inputs import TrialInputs
from support import sparse_angles_run

N_FRAMES = 6
SETTINGS = MarkerErrorSettings(alphas=(0.0, 0.5), angles=("LKneeAngles",), workers=1)


@pytest.fixture(scope="module")
def sparse_run(angles_run: AnglesRun) -> AnglesRun:
    """The sample run with every marker NaN outside 6 frames spread over the trial."""
    return sparse_angles_run(angles_run, N_FRAMES)


class Recorder:
    """A StageProgress that keeps every call."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, object, object]] = []

    def stage(self, description: str, total: int | None = None) -> None:
        self.calls.append(("stage", description, total))

    def update(self, completed: int, total: int | None = None) -> None:
        self.calls.append(("update", completed, total))

    def stages(self) -> list[str]:
        return [str(d) for kind, d, _ in self.calls if kind == "stage"]

    def updates(self, stage: str) -> list[tuple[int, int]]:
        """The updates of one stage."""
        out, current = [], None
        for kind, a, b in self.calls:
            if kind == "stage":
                current = a
            elif current == stage:
                out.append((int(a), int(b)))  # type: ignore[call-overload]
        return out


def test_default_per_source_with_progress_through_every_stage(sparse_run: AnglesRun) -> None:
    assert MarkerErrorSettings().per_source and MarkerErrorSettings.create().per_source
    recorder, components = Recorder(), []
    analysis = analyse_run(sparse_run, SETTINGS, lambda done, total: components.append((done, total)),
                           stages=recorder)  # fmt: skip
    fuzzy = analysis.result
    assert fuzzy is not None and fuzzy.bands is analysis.fuzzy
    assert source_names(fuzzy) == ["measurement", "placement", "sta"]
    assert source_components(fuzzy) == ["LKneeAngles_X"]  # the analysed flexion only
    assert fuzzy.allowable is not None  # the refinement still ran, before
    assert recorder.stages() == ["fuzzy angles", "allowable marker error", "per-source bands"]
    # per angle: the knee's three components are optimised together
    assert recorder.updates("fuzzy angles")[-1] == (1, 1) and components[-1] == (1, 1)
    runs = fuzzy.allowable.attrs["runs"]
    assert recorder.updates("allowable marker error")[-1] == (runs, runs)
    assert recorder.updates("per-source bands") == [(3, 3)]  # the three sources of the one component side by side
    (note,) = [n for n in messages(analysis.notes) if n.startswith("per-source bands")]
    assert note.startswith("per-source bands (Fig. 5.9): measurement, placement, sta each alone for 1 flexion "
                           "components at α = 0: 3 runs, ")  # fmt: skip
    assert analysis.notes[-1].message.startswith("allowable marker error")  # its line stays last
    table = widest_source_bands(fuzzy)
    assert table.width("LKneeAngles_X", "measurement") < table.width("LKneeAngles_X", "sta")


def test_per_source_off_or_one_source(sparse_run: AnglesRun) -> None:
    off = analyse_run(sparse_run, dataclasses.replace(SETTINGS, per_source=False, tolerance=None))
    assert off.result is not None and off.result.sources is None
    assert not [n for n in messages(off.notes) if n.startswith("per-source")]
    assert not MarkerErrorSettings.create(per_source=False).per_source
    recorder = Recorder()
    one = analyse_run(sparse_run, dataclasses.replace(SETTINGS, sources=("sta",), tolerance=None), stages=recorder)
    assert one.result is not None and one.result.sources is None and recorder.stages() == ["fuzzy angles"]
    assert "per-source bands: not computed (a single error source is selected)" in messages(one.notes)
    frontal = analyse_run(sparse_run, dataclasses.replace(SETTINGS, angles=("LPelvisAngles",), tolerance=None))
    assert "per-source bands: not computed (no hip/knee/ankle flexion analysed)" in messages(frontal.notes)


def test_saved_with_the_per_source_bands(sparse_run: AnglesRun, tmp_path: Path,
                                         monkeypatch: pytest.MonkeyPatch) -> None:  # fmt: skip
    monkeypatch.setattr(trial_inputs, "run_angles", lambda *args, **kwargs: sparse_run)
    recorder = Recorder()
    out = tmp_path / "fuzzy.nc"
    request = MarkerErrorRequest(TrialInputs(sparse_run.trial), dataclasses.replace(SETTINGS, tolerance=None))
    analysis = analyse_to_files(request, out, stages=Prefixed(recorder, "walking.c3d: "))
    assert recorder.stages() == ["walking.c3d: fuzzy angles", "walking.c3d: per-source bands"]
    again = read_marker_result(out)
    assert again.sources is not None and analysis.result is not None and analysis.result.sources is not None
    np.testing.assert_array_equal(again.sources["hull"], analysis.result.sources["hull"])
    assert widest_source_bands(again).widths.equals(widest_source_bands(analysis.result).widths)
