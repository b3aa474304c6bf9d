"""Gap-filling accuracy on real walking data, and pre-processing speed.

Run:  .venv/bin/python benchmarks/preprocess.py

1. Accuracy: gaps of 1..10 frames (every 25 valid frames) are cut into the complete
   markers of the Vicon walking trials in ../shared/data/vicon (120 Hz and 50 Hz) and
   refilled with ``fuzzygait.mocap.fill_gaps`` by each method (spline, pattern, auto);
   RMS and max error (mm) against the cut samples.  Two cut protocols:

   (i)  every complete marker cut at the same frames: no donor is visible during a gap,
        so pattern and auto fall back to the spline (the worst case for them);
   (ii) one marker at a time, the others intact: the realistic single occlusion.
2. Speed: a 10-minute, 120 Hz, 60-marker trial with ~2,400 gaps; windowed spline fill
   against a baseline global-spline fill run in the same process, the pattern and auto
   methods, and the zero-lag Butterworth.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from _setup import VICON
from scipy.interpolate import CubicSpline

from fuzzygait.io import read_c3d
from fuzzygait.mocap import butterworth_lowpass, fill_gaps

METHODS = ("spline", "pattern", "auto")
LENGTHS = (1, 2, 3, 5, 7, 10)
TRIALS = ("Movement_trial.c3d", "gait-pig.c3d", "gait-raw.c3d")


def gap_starts(n_frames: int, length: int, spacing: int = 25) -> range:
    """Starts of gaps of ``length`` frames, ``spacing`` valid frames apart."""
    return range(15, n_frames - length - 15, length + spacing)


def cut(markers: np.ndarray, length: int, columns: list[int]) -> np.ndarray:
    """Copy of ``markers`` with gaps of ``length`` frames cut into ``columns``."""
    out = markers.copy()
    for start in gap_starts(markers.shape[0], length):
        out[start : start + length, columns] = np.nan
    return out


def refill_errors(
    markers: np.ndarray, labels: list[str], length: int, method: str, one_at_a_time: bool
) -> tuple[np.ndarray, int, int]:
    """Errors (mm) at the cut samples, and how many gaps the pattern filled of all."""
    cuts = [[m] for m in range(markers.shape[1])] if one_at_a_time else [
        list(range(markers.shape[1]))
    ]
    errors, by_pattern, n_gaps = [], 0, 0
    for columns in cuts:
        holes = cut(markers, length, columns)
        filled, gaps = fill_gaps(holes, labels, max_gap=10, method=method)
        missing = np.isnan(holes[..., 0])
        errors.append(np.linalg.norm(filled[missing] - markers[missing], axis=1))
        by_pattern += sum(g.method == "pattern" for g in gaps)
        n_gaps += len(gaps)
    return np.concatenate(errors), by_pattern, n_gaps


def accuracy() -> None:
    if not VICON.is_dir():
        print(f"## Gap-filling accuracy\nskipped: {VICON} is absent")
        return
    trials = {}
    for name in TRIALS:
        trial = read_c3d(VICON / name)
        complete = [m for m in trial.marker_labels if np.isfinite(trial.marker(m)).all()]
        trials[name] = (trial.rate, trial.select_markers(complete).markers, complete)
    for title, one_at_a_time in (
        ("(i) every complete marker cut at the same frames (no donors)", False),
        ("(ii) one marker at a time, the other complete markers intact", True),
    ):
        print(f"\n### Gap-filling accuracy, protocol {title}")
        print(
            "| trial | rate Hz | gap frames | samples | RMS spline | RMS pattern | RMS auto "
            "| max spline | max pattern | max auto | auto: gaps by pattern |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for name, (rate, markers, labels) in trials.items():
            for length in LENGTHS:
                results = {
                    m: refill_errors(markers, labels, length, m, one_at_a_time) for m in METHODS
                }
                rms = " | ".join(f"{np.sqrt(np.mean(r[0] ** 2)):.3f}" for r in results.values())
                peak = " | ".join(f"{r[0].max():.3f}" for r in results.values())
                _, by_pattern, n_gaps = results["auto"]
                print(
                    f"| {name} | {rate:g} | {length} | {results['spline'][0].size} | {rms} "
                    f"| {peak} | {by_pattern} of {n_gaps} |"
                )


def global_spline_fill(markers: np.ndarray, max_gap: int) -> np.ndarray:
    """Baseline: one spline through every valid sample of a marker."""
    out = markers.copy()
    t = np.arange(markers.shape[0])
    for m in range(markers.shape[1]):
        valid = np.isfinite(markers[:, m]).all(axis=1)
        spline = CubicSpline(t[valid], markers[valid, m])
        out[~valid, m] = spline(t[~valid])  # (ignores max_gap and edges: timing only)
    return out


def speed() -> None:
    print("\n## Speed: 10 min at 120 Hz, 60 markers")
    rng = np.random.default_rng(1)
    n, k = 72_000, 60
    t = np.arange(n) / 120.0
    markers = 300 * np.sin(2 * np.pi * 0.9 * t)[:, None, None] + rng.normal(0, 1, (n, k, 3))
    for m in range(k):
        for start in rng.choice(n - 20, 40, replace=False):
            markers[start : start + rng.integers(1, 12), m] = np.nan
    labels = [f"M{i}" for i in range(k)]
    timings = {}
    for label, func in (
        ("baseline global spline fill", lambda: global_spline_fill(markers, 10)),
        ("fuzzygait windowed spline fill", lambda: fill_gaps(markers, labels, 10, "spline")),
        ("fuzzygait pattern fill", lambda: fill_gaps(markers, labels, 10, "pattern")),
        ("fuzzygait auto fill (default)", lambda: fill_gaps(markers, labels, 10, "auto")),
    ):
        start = time.perf_counter()
        func()
        timings[label] = time.perf_counter() - start
        print(f"{label}: {timings[label]:.2f} s")
    ratio = timings["fuzzygait windowed spline fill"] / timings["baseline global spline fill"]
    print(f"ratio windowed / global: {ratio:.2f}")
    filled, _ = fill_gaps(markers, labels, 10, "spline")
    start = time.perf_counter()
    with warnings.catch_warnings():  # a few gaps > 10 frames leave short runs: expected
        warnings.simplefilter("ignore")
        butterworth_lowpass(filled, 120.0)
    print(f"Butterworth 6 Hz zero-lag on the filled trial: {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    accuracy()
    speed()
