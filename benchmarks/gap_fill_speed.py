"""Gap-filling speed on a long trial with many gaps (was a timed test in tests/test_gap_filling.py).

Run:  .venv/bin/python benchmarks/gap_fill_speed.py [--repeat 3]

The trial of the former ``test_ten_minute_trial_is_fast`` (it asserted < 3 s for the
default fill): 10 minutes at 120 Hz, 60 random-walk markers, 40 random gaps of 1-29
frames per marker (seed 1). Each method of ``fill_gaps`` (max_gap=10) is timed against a
baseline run in the same process on the same array: one global cubic spline through every
valid sample of each marker (what a naive fill costs). Figures are the best of
``--repeat`` runs; the ratios to the baseline are what to compare between machines.
Takes about 20 s on 2 cores.
"""

from __future__ import annotations

from _setup import best_of, one_thread

one_thread()

import argparse  # noqa: E402

import numpy as np  # noqa: E402
from scipy.interpolate import CubicSpline  # noqa: E402

from fuzzygait.mocap import fill_gaps  # noqa: E402


def random_walk_trial(seconds: float = 600.0, rate: float = 120.0, n_markers: int = 60) -> np.ndarray:
    """(frames, n_markers, 3) random walks with 40 random NaN runs of 1-29 frames per marker."""
    rng = np.random.default_rng(1)
    n = int(rate * seconds)
    markers = np.cumsum(rng.normal(size=(n, n_markers, 3)), axis=0)
    for m in range(n_markers):
        for start in rng.integers(1, n - 40, size=40):
            markers[start : start + rng.integers(1, 30), m] = np.nan
    return markers


def global_spline_fill(markers: np.ndarray) -> np.ndarray:
    """Baseline: one spline through every valid sample of a marker (no max_gap, timing only)."""
    out = markers.copy()
    t = np.arange(markers.shape[0])
    for m in range(markers.shape[1]):
        valid = np.isfinite(markers[:, m]).all(axis=1)
        out[~valid, m] = CubicSpline(t[valid], markers[valid, m])(t[~valid])
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per method; the best is shown")
    args = parser.parse_args()
    markers = random_walk_trial()
    labels = [f"M{i}" for i in range(markers.shape[1])]
    _, gaps = fill_gaps(markers, labels)
    filled = sum(g.filled for g in gaps)
    print(f"## Gap-filling speed: 10 min at 120 Hz, 60 markers, {len(gaps)} gaps, {filled} filled (max_gap=10)")
    baseline = best_of(lambda: global_spline_fill(markers), args.repeat, warm_up=False)
    print(f"| fill | seconds (best of {args.repeat}) | ratio to baseline |")
    print("|---|---|---|")
    print(f"| baseline: global cubic spline per marker | {baseline:.2f} | 1.00 |")
    for method in ("spline", "pattern", "auto"):
        seconds = best_of(lambda m=method: fill_gaps(markers, labels, 10, m), args.repeat, warm_up=False)
        default = " (default)" if method == "auto" else ""
        print(f"| fill_gaps method={method}{default} | {seconds:.2f} | {seconds / baseline:.2f} |")


if __name__ == "__main__":
    main()
