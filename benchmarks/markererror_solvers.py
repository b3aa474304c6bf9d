"""How close each solver's fuzzy joint-angle bands come to the widest band any run found,
and at what CPU (issue 40): the batched Graph Follower's local solvers compared.

Run:  .venv/bin/python benchmarks/markererror_solvers.py [--trial walking|cgm24] [--heavy-frank-wolfe]
          [--angles LKneeAngles RPelvisAngles ...]

Every band is an inner approximation of the true range — each bound is the angle at an
admissible deviation the optimiser found —, so the widest value any run found at a
frame, α-level and bound is the best known, and a run's distance to it ("gap", degrees)
is how much of the range it missed.  Runs, in this process, one worker, same angles:

* ``frank-wolfe, before``: the solver and settings before issue 40 (Frank–Wolfe and
  projected-gradient steps with a ten-point line search, level by level; 5 starts, 25
  iterations, 5 at the followed frames);
* ``spectral, defaults``: today's defaults (spectral projected gradient, every α-level in
  one optimisation; 5 starts, 50 model calls, 10 at the followed frames);
* ``spectral, reference``: 40 starts (the best of 64 screened random points), 100 calls,
  25 at the followed frames — a heavy run that only serves as the best known;
* ``frank-wolfe, reference`` (``--heavy-frank-wolfe``): the same with the old solver (slow).

Printed per run: CPU seconds (``time.process_time``), and over every determined bound
value at α < 1 (frames where any run flags the angle undetermined are left out) the
share more than 0.01°, 0.1° and 1° inside the widest, the 99th percentile and the
largest gap; and how often the defaults are narrower / wider than before by more than
0.01° (the issue's "identical or wider").  Default angles: the left knee and ankle, the
right hip and pelvis and the left foot progression of ``sample_data/walking.c3d`` (cgm1.0);
``--trial cgm24``: the synthetic CGM 2.4 session, its left forefoot instead of the foot
progression.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles  # noqa: E402
from fuzzygait.workflows.angles import AnglesRun  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from markererror_work import trial_run  # noqa: E402

ANGLES = {
    "walking": ["LKneeAngles", "RPelvisAngles", "LFootProgressAngles", "RHipAngles", "LAnkleAngles"],
    "cgm24": ["LKneeAngles", "RPelvisAngles", "LForeFootAngles", "RHipAngles", "LAnkleAngles"],
}
BEFORE = "frank-wolfe, before"
DEFAULTS = "spectral, defaults"
RUNS = {
    BEFORE: FuzzyAngleOptions(solver="frank-wolfe", starts=5, iterations=25, follow=5),
    DEFAULTS: FuzzyAngleOptions(),
    "spectral, reference": FuzzyAngleOptions(starts=40, iterations=100, follow=25),
}
HEAVY_FRANK_WOLFE = FuzzyAngleOptions(solver="frank-wolfe", starts=40, iterations=100, follow=25)


@dataclass
class Bands:
    hull: np.ndarray  # (component, alpha < 1, bound, frame), degrees
    undetermined: np.ndarray  # (component, alpha < 1, frame)
    cpu: float


def run_bands(run: AnglesRun, options: FuzzyAngleOptions, angles: list[str]) -> Bands:
    start = time.process_time()
    fuzzy = fuzzy_joint_angles(run.trial, run.subject, run.result, options, angles, clusters=run.clusters)
    cpu = time.process_time() - start
    below_one = fuzzy["alpha"].to_numpy() < 1.0
    hull = fuzzy["hull"].transpose("component", "alpha", "bound", "frame").to_numpy()[:, below_one]
    flags = fuzzy["undetermined"].transpose("component", "alpha", "frame").to_numpy()[:, below_one]
    return Bands(hull, flags, cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trial", default="walking", choices=tuple(ANGLES))
    parser.add_argument("--angles", nargs="+", default=None)
    parser.add_argument("--heavy-frank-wolfe", action="store_true", help="also the old solver with the heavy settings")
    args = parser.parse_args()
    angles = args.angles or ANGLES[args.trial]
    run = trial_run(args.trial)
    runs = dict(RUNS)
    if args.heavy_frank_wolfe:
        runs["frank-wolfe, reference"] = HEAVY_FRANK_WOLFE
    bands = {name: run_bands(run, options, angles) for name, options in runs.items()}
    outward = np.array([-1.0, 1.0])[None, None, :, None]  # lower, upper: larger = wider
    undetermined = np.any([b.undetermined for b in bands.values()], axis=0)[:, :, None, :]
    widest = np.max([b.hull * outward for b in bands.values()], axis=0)
    compared = ~undetermined & np.all([np.isfinite(b.hull) for b in bands.values()], axis=0)
    print(f"{args.trial}: {', '.join(angles)}; {int(compared.sum())} determined bound values at α < 1")
    print("| run | CPU s | > 0.01° inside the widest | > 0.1° | > 1° | 99th percentile, ° | largest, ° |")
    print("|---|---|---|---|---|---|---|")
    for name, b in bands.items():
        gap = (widest - b.hull * outward)[compared]
        print(f"| {name} | {b.cpu:.1f} | {100 * np.mean(gap > 0.01):.1f} % | {100 * np.mean(gap > 0.1):.1f} % | "
              f"{100 * np.mean(gap > 1.0):.2f} % | {np.percentile(gap, 99):.2f} | {gap.max():.2f} |")  # fmt: skip
    change = ((bands[DEFAULTS].hull - bands[BEFORE].hull) * outward)[compared]
    print(f"defaults against before: narrower by > 0.01° at {100 * np.mean(change < -0.01):.1f} %, wider by "
          f"> 0.01° at {100 * np.mean(change > 0.01):.1f} % of the values; CPU ratio "
          f"{bands[BEFORE].cpu / bands[DEFAULTS].cpu:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
