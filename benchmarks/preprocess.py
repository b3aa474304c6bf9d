"""Gap-filling accuracy on real walking data, and pre-processing speed.

Run:  .venv/bin/python benchmarks/preprocess.py

1. Accuracy: gaps of 1..10 frames are cut into every complete marker of the Vicon
   walking trials in ../shared/data/vicon (120 Hz and 50 Hz) and filled with
   ``fuzzygait.mocap.fill_gaps``; RMS and max error (mm) against the cut samples.
2. Speed: a 10-minute, 120 Hz, 60-marker trial with ~2,400 gaps; windowed spline fill
   against a baseline global-spline fill run in the same process, and the zero-lag
   Butterworth.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path

import numpy as np
from scipy.interpolate import CubicSpline

from fuzzygait.io import read_c3d
from fuzzygait.mocap import butterworth_lowpass, fill_gaps

VICON = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vicon"


def cut(markers: np.ndarray, length: int, spacing: int = 25) -> np.ndarray:
    out = markers.copy()
    for start in range(15, markers.shape[0] - length - 15, length + spacing):
        out[start : start + length] = np.nan
    return out


def accuracy() -> None:
    print("## Gap-filling accuracy (cubic spline, gaps cut into complete markers)")
    if not VICON.is_dir():
        print(f"skipped: {VICON} is absent")
        return
    print("| trial | rate Hz | gap frames | RMS mm | max mm | samples |")
    print("|---|---|---|---|---|---|")
    for name in ("Movement_trial.c3d", "gait-pig.c3d", "gait-raw.c3d"):
        trial = read_c3d(VICON / name)
        complete = [m for m in trial.marker_labels if np.isfinite(trial.marker(m)).all()]
        markers = trial.select_markers(complete).markers
        for length in (1, 2, 3, 5, 7, 10):
            holes_cut = cut(markers, length)
            filled, _ = fill_gaps(holes_cut, complete, max_gap=10)
            holes = np.isnan(holes_cut[..., 0])
            err = np.linalg.norm(filled[holes] - markers[holes], axis=1)
            print(
                f"| {name} | {trial.rate:g} | {length} | {np.sqrt(np.mean(err**2)):.3f} "
                f"| {err.max():.3f} | {holes.sum()} |"
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
        ("fuzzygait windowed spline fill", lambda: fill_gaps(markers, labels, 10)),
    ):
        start = time.perf_counter()
        func()
        timings[label] = time.perf_counter() - start
        print(f"{label}: {timings[label]:.2f} s")
    ratio = timings["fuzzygait windowed spline fill"] / timings["baseline global spline fill"]
    print(f"ratio windowed / global: {ratio:.2f}")
    filled, _ = fill_gaps(markers, labels, 10)
    start = time.perf_counter()
    with warnings.catch_warnings():  # a few gaps > 10 frames leave short runs: expected
        warnings.simplefilter("ignore")
        butterworth_lowpass(filled, 120.0)
    print(f"Butterworth 6 Hz zero-lag on the filled trial: {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    accuracy()
    speed()
