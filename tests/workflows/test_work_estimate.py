"""Work estimates of the heavy workflows (issue 37 point 6), through a progress that takes
them (:class:`~fuzzygait.workflows.progress.Announced`): the line said before the work,
the labels on the stages' bars, and the counts against what the work then did.

Speed: the marker-error analysis on the sample trial cut to 6 frames (as
test_marker_uncertainty_per_source.py), the fuzzy simulation of 100 steps of a 6-node blade.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from fuzzygait.uncertainty.frv import FRVSpec
from fuzzygait.workflows.angles import AnglesRun
from fuzzygait.workflows.fuzzy_dynamics import (
    FuzzySimOutputs,
    FuzzySimRequest,
    command_setup,
    command_strategy,
    fuzzy_simulation,
)
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run
from fuzzygait.workflows.progress import SILENT, Announced, Prefixed, announce, takes_estimates
from fuzzygait.workflows.work_estimate import (
    AT_MOST,
    EXACTLY,
    WorkEstimate,
    duration_text,
    frv_work,
    fuzzy_sim_work,
)
from support import sparse_angles_run


class Recorder:
    """A StageProgress that keeps every stage and the last total of each."""

    def __init__(self) -> None:
        self.stages: list[tuple[str, int | None]] = []

    def stage(self, description: str, total: int | None = None) -> None:
        self.stages.append((description, total))

    def update(self, completed: int, total: int | None = None) -> None:
        pass


def test_only_a_progress_that_takes_estimates_gets_them() -> None:
    said: list[str] = []
    recorder = Recorder()
    estimate = WorkEstimate(7, "forward simulations", EXACTLY, "7 forward simulations", {"FRV (20 samples)": "7 runs",
                                                                                          "work": "≤ 3 runs"})
    assert not takes_estimates(SILENT) and not takes_estimates(recorder)  # type: ignore[arg-type]
    announce(SILENT, estimate)  # ignored
    announced = Announced(recorder, said.append)
    prefixed = Prefixed(announced, "walk.c3d: ")
    assert takes_estimates(announced) and takes_estimates(prefixed)
    announce(prefixed, estimate)
    assert said == ["estimate: 7 forward simulations"]
    prefixed.stage("FRV (20 samples)", 3)
    prefixed.stage("work")
    prefixed.stage("other")
    assert recorder.stages == [("walk.c3d: FRV (20 samples, 7 runs)", 3), ("walk.c3d: work (≤ 3 runs)", None),
                               ("walk.c3d: other", None)]  # fmt: skip


def test_durations_read_as_a_person_says_them() -> None:
    assert [duration_text(s) for s in (0.0712, 6.91, 42.4, 1140, 9000)] == ["0.071 s", "6.9 s", "42 s", "19.0 min",
                                                                             "2.5 h"]  # fmt: skip


def test_fuzzy_sim_bound_and_frv_counts_without_running() -> None:
    work = fuzzy_sim_work("stance", 2001, 100, (0.0, 0.5, 1.0), 4, "stance: α-level optimisations")
    assert (work.count, work.certainty) == (1 + 2 * 2 * 21 * 4, AT_MOST)  # 21 nodes: 0, 100, …, 2000
    assert work.stages == {"stance: α-level optimisations": "≤ 337 forward simulations"}
    one = frv_work("stance", [FRVSpec("E", 6e10)], 100, 10000, "s")
    assert (one.count, one.certainty) == (99, EXACTLY) and one.text.startswith("99 forward simulations")
    two = frv_work("stance", [FRVSpec("E", 6e10), FRVSpec("rho", 8550.0)], (60, 30), 10000, "s")
    assert two.certainty == AT_MOST and two.count >= 59 * 29 and "≤ 1,711 grid points" in two.text


def test_marker_error_estimate_and_what_the_analysis_did(angles_run: AnglesRun) -> None:
    sparse = sparse_angles_run(angles_run, 6)
    said: list[str] = []
    recorder = Recorder()
    settings = MarkerErrorSettings(alphas=(0.0, 0.5), angles=("LKneeAngles",), workers=1)
    analysis = analyse_run(sparse, settings, stages=Announced(recorder, said.append))
    fuzzy, result = analysis.fuzzy, analysis.result
    assert said == ["estimate: 36 α-level optimisations of the fuzzy angles (6 frames × 2 α-levels × 3 angle "
                    "components, each for the upper and the lower bound), then at most 36 allowable-error refinement "
                    "runs (≤ 12 per component) and 3 per-source runs (3 sources × 1 flexion component), each one "
                    "α-level over the frames"]  # fmt: skip
    assert [d for d, _ in recorder.stages] == ["fuzzy angles (36 α-level optimisations)",
                                               "allowable marker error (≤ 36 runs)", "per-source bands (3 runs)"]
    analysed = fuzzy["hull"].sel(alpha=[0.0, 0.5]).notnull().all("bound").sum().item()
    assert analysed == 36  # component × α-level × frame
    assert result is not None and result.allowable is not None and result.sources is not None
    assert 0 < result.allowable.attrs["runs"] <= 36 and result.sources.attrs["runs"] == 3


def test_fuzzy_simulation_labels_its_bar_and_keeps_to_its_bound(tmp_path: Path) -> None:
    setup, _ = command_setup("swing", 6, None, 0.1, {}, None)
    said: list[str] = []
    recorder = Recorder()
    request = FuzzySimRequest({"E": 0.1, "rho": 0.05}, strategy=command_strategy(20, 1e-4))
    result, _ = fuzzy_simulation(setup, request, FuzzySimOutputs(tmp_path / "f.nc"),
                                 progress=Announced(recorder, said.append))  # fmt: skip
    (line,) = said
    assert line.startswith("estimate: at most 97 forward simulations of the swing (24 α-level optimisations")
    assert "≈" in line and "each (extrapolated from its first 10 of 100 steps, timed here)" in line
    assert ("swing: timing a forward simulation", None) in recorder.stages
    assert recorder.stages[-1] == ("swing: α-level optimisations (≤ 97 forward simulations)", 24)
    assert result.attrs["optimisations"] == 24 and result.attrs["forward_simulations"] <= 97
    plain = Recorder()  # a progress without estimates: nothing timed
    fuzzy_simulation(setup, FuzzySimRequest({"E": 0.1}, strategy=command_strategy(20, 1e-4)),
                     FuzzySimOutputs(tmp_path / "g.nc"), progress=plain)
    assert [d for d, _ in plain.stages] == ["swing: building the model", "swing: α-level optimisations"]


@pytest.mark.parametrize("levels", [20, 21])
def test_the_alpha_limit(levels: int) -> None:
    from fuzzygait.core.errors import FuzzyGaitError
    from fuzzygait.workflows.work_estimate import check_alpha_count

    alphas = [i / levels for i in range(levels)] + [1.0]
    if levels <= 20:
        check_alpha_count(alphas)
    else:
        with pytest.raises(FuzzyGaitError, match="alphas= gives 21 α-levels below 1; at most 20"):
            check_alpha_count(alphas)


def test_the_estimate_counts_the_fuzzy_kinetics() -> None:
    """With kinetics the estimate names their components and their cost relative to an
    angle component's, and labels their progress stage."""
    from fuzzygait.workflows.work_estimate import FUZZY_KINETICS_STAGE, KINETIC_COMPONENTS, marker_error_work

    frames = {"LKneeAngles_X": 40}
    plain = marker_error_work(frames, MarkerErrorSettings(alphas=(0.0, 0.5), tolerance=None, per_source=False))
    with_kinetics = marker_error_work(frames, MarkerErrorSettings(alphas=(0.0, 0.5), tolerance=None, per_source=False,
                                                                  kinetics=True))  # fmt: skip
    assert "fuzzy kinetics" not in plain.text
    assert with_kinetics.text.startswith(plain.text)
    assert f"the fuzzy kinetics of {KINETIC_COMPONENTS} moment or power components" in with_kinetics.text
    assert with_kinetics.stages[FUZZY_KINETICS_STAGE] == f"{KINETIC_COMPONENTS} components"
