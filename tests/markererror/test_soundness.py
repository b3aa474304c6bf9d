"""Soundness of the fuzzy joint-angle hulls (issue 15): every Monte Carlo angle inside the
α-level balls lies inside the hull of :func:`fuzzy_joint_angles`, or at a frame the dataset
marks undetermined.

The Monte Carlo evaluates the very models the analysis optimised
(:func:`~fuzzygait.markererror.analysis.component_tasks`, with the measured angle as
``reference``, so the samples are on the hull's continuous branch).  Speed: 3 frames
(a copy of the trial whose markers are NaN elsewhere) and 2,000 samples per frame; the
full check (20 frames of three trials, 10,000 samples) is
``benchmarks/markererror_soundness.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from fuzzygait.markererror.analysis import FuzzyAngleOptions, component_tasks, fuzzy_joint_angles
from fuzzygait.markererror.angle_model import AXES
from fuzzygait.markererror.comparison import monte_carlo_envelope
from fuzzygait.markererror.result import component_hull, component_undetermined
from fuzzygait.workflows.angles import run_angles
from support import SAMPLE_DATA

FRAMES = np.array([40, 200, 360])
ALPHAS = (0.0, 0.5)
SAMPLES = 2000
#: model version: (dynamic, static, subject file, angles checked)
CASES = {
    "cgm2.4": ("cgm24_walking.c3d", "cgm24_static.c3d", "cgm24_subject.toml", ["LKneeAngles", "LAnkleAngles"]),
    "cgm1.0": ("walking.c3d", "static.c3d", "subject.toml", ["LKneeAngles"]),
}


@pytest.mark.parametrize("version", list(CASES))
def test_monte_carlo_lies_in_the_hull_or_at_an_undetermined_frame(version: str) -> None:
    dynamic, static, subject, names = CASES[version]
    run = run_angles(SAMPLE_DATA / dynamic, static=SAMPLE_DATA / static, subject_file=SAMPLE_DATA / subject,
                     model=version)  # fmt: skip
    markers = np.full_like(run.trial.markers, np.nan)
    markers[FRAMES] = run.trial.markers[FRAMES]
    trial = run.trial.with_markers(markers)
    options = FuzzyAngleOptions(alphas=(*ALPHAS, 1.0))
    fuzzy = fuzzy_joint_angles(trial, run.subject, run.result, options, names, clusters=run.clusters)
    tasks, _ = component_tasks(trial, run.subject, run.result, options, names, run.clusters)
    assert len(tasks) == 3 * len(names)
    determined = 0
    for i, task in enumerate(tasks):
        np.testing.assert_array_equal(task.frames, FRAMES)
        component = f"{task.name}_{AXES[task.axis]}"
        model = task.angle_model()
        for k, alpha in enumerate(ALPHAS):
            lower, upper = monte_carlo_envelope(model, (1.0 - alpha) * task.radii, SAMPLES, seed=150 + 2 * i + k)
            hull = component_hull(fuzzy, component).sel(alpha=alpha).to_numpy()[:, FRAMES]
            undetermined = component_undetermined(fuzzy, component).sel(alpha=alpha).to_numpy()[FRAMES]
            inside = (hull[0] <= lower + 1e-9) & (upper <= hull[1] + 1e-9)
            assert np.all(inside | undetermined), (component, alpha, hull, lower, upper, undetermined)
            determined += int(np.sum(~undetermined))
    # not vacuous: knee flexion is a band at α = 0.5 (at α = 0 the Plug-in Gait thigh can flip)
    assert not component_undetermined(fuzzy, "LKneeAngles_X").sel(alpha=0.5).to_numpy()[FRAMES].any()
    assert determined >= len(tasks) * len(ALPHAS) * FRAMES.size // 2
