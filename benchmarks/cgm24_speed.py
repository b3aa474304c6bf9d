"""Speed of CGM 2.4 (cluster and forefoot least-squares tracking) against CGM 1.0.

Run:  .venv/bin/python benchmarks/cgm24_speed.py

Tiles the markers of ``sample_data/cgm24_walking.c3d`` (the synthetic CGM 2.4 session,
30 markers) to at least 30,000 frames and times ``fuzzygait.kinematics.compute_lower_body``
on it (both sides: pelvis, joint centres, all segment frames, every angle output and the
virtual markers) with ``model="cgm2.4"`` (clusters + forefoot calibrated on
``cgm24_static.c3d``), ``"cgm2.3"`` and ``"cgm1.0"`` (Plug-in Gait, calibrated on the same
static trial), best of 5 after a warm-up, in the same process, on one core (BLAS and
OpenMP threads pinned to 1).  Target (issue 14): cgm2.4 >= 50,000 frames/s.  Static
calibration is not timed (once per session).
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.io.subject import read_subject  # noqa: E402
from fuzzygait.kinematics import compute_lower_body  # noqa: E402
from fuzzygait.workflows.angles import calibrate_static  # noqa: E402

MIN_FRAMES = 30_000
REPEATS = 5
MODELS = ("cgm1.0", "cgm2.3", "cgm2.4")
TARGET = 50_000


def tiled(trial: Trial, n_min: int) -> Trial:
    reps = -(-n_min // trial.n_frames)
    markers = np.tile(trial.markers, (reps, 1, 1))
    return replace(trial, markers=markers, outputs={}, output_kinds={}, events=[])


def main() -> None:
    data = ROOT / "sample_data"
    walking, static = read_c3d(data / "cgm24_walking.c3d"), read_c3d(data / "cgm24_static.c3d")
    subject = read_subject(data / "cgm24_subject.toml")
    big = tiled(walking, MIN_FRAMES)
    rates = {}
    rows = []
    for model in MODELS:
        calibration = calibrate_static(static, subject, model=model)
        args = dict(model=model, clusters=calibration.clusters)
        result = compute_lower_body(big, calibration.subject, **args)  # warm-up
        assert not result.unavailable, result.unavailable
        times = []
        for _ in range(REPEATS):
            start = time.perf_counter()
            compute_lower_body(big, calibration.subject, **args)
            times.append(time.perf_counter() - start)
        best = min(times)
        rates[model] = big.n_frames / best
        rows.append((model, len(result.angles), best, rates[model]))

    print(f"## CGM 2.4 lower body speed (sample_data/cgm24_walking.c3d tiled to {big.n_frames} frames, "
          f"{walking.n_markers} markers, one core, best of {REPEATS})")  # fmt: skip
    print("| model | angle outputs | seconds | frames/s | vs cgm1.0 |")
    print("|---|---|---|---|---|")
    for model, n_angles, best, rate in rows:
        print(f"| `{model}` | {n_angles} | {best:.3f} | {rate:,.0f} | {rate / rates['cgm1.0']:.2f}x |")
    verdict = "met" if rates["cgm2.4"] >= TARGET else "NOT met"
    print(f"(target cgm2.4 both sides >= {TARGET:,} frames/s: {verdict})")


if __name__ == "__main__":
    main()
