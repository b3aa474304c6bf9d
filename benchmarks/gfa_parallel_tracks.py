"""The linearised Graph Follower with its (α, bound) tracks side by side (issue 18,
Deliver 3): the 11-fuzzy-parameter swing of thesis §5.3 (E, ν, ρ, thigh and shank mass
and J1–J3, ±10 %, η = 1e5 Pa s) followed one track after another (the thesis' order,
in this process: the baseline) and side by side on 1 and on 2 worker processes.

Prints the wall times, the 1-vs-2-worker speed-up, the forward simulations, whether the
side-by-side hulls are bit-identical on 1 and 2 workers, and how they compare with the
one-by-one hulls (the Graph Follower's hulls are inner approximations: wider is closer
to the true range).

    .venv/bin/python benchmarks/gfa_parallel_tracks.py [--duration 2] [--workers 2]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np

from fuzzygait.mechanics.fuzzy_dynamics import DEFAULT_STRATEGY, ELEVEN_PARAMETERS, LegTarget, fuzzy_forward_dynamics
from fuzzygait.mechanics.scenarios import LegSimulator
from fuzzygait.mechanics.solver import SolverSettings
from fuzzygait.uncertainty.execution import Evaluator

SWING_DAMPING = 1e5  # Pa s: the swing's command default (README "Defaults that run")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated time (s)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--skip-baseline", action="store_true", help="only the side-by-side runs")
    parser.add_argument("--skip-one-worker", action="store_true", help="no side-by-side run in this process")
    args = parser.parse_args()
    sim = LegSimulator("swing")
    base = sim.parameters(eta=SWING_DAMPING)
    spreads = {name: 0.1 for name in ELEVEN_PARAMETERS}
    common = dict(target=LegTarget(base=base, settings=SolverSettings(duration=args.duration)), alphas=(0.0, 0.5, 1.0))
    side_by_side = replace(DEFAULT_STRATEGY, tracks="side-by-side")
    runs = {}
    if not args.skip_baseline:
        runs["one-by-one, this process"] = fuzzy_forward_dynamics(sim, spreads, **common)
    if not args.skip_one_worker:
        runs["side-by-side, 1 worker (this process)"] = fuzzy_forward_dynamics(sim, spreads, strategy=side_by_side,
                                                                               **common)  # fmt: skip
    started = time.perf_counter()
    with Evaluator(workers=args.workers) as pool:
        pool.map(abs, [0] * args.workers)  # the pool's start-up is not the algorithm's
        start_up = time.perf_counter() - started
        runs[f"side-by-side, {args.workers} workers"] = fuzzy_forward_dynamics(
            sim, spreads, strategy=side_by_side, evaluator=pool, **common)
    print(f"swing, 11 fuzzy parameters ±10 %, {args.duration:g} s, α = 0, 0.5 (pool start-up {start_up:.1f} s, "
          "not counted)")
    print("| run | wall (s) | forward simulations | optimisations | library |\n|---|---:|---:|---:|---:|")
    for name, r in runs.items():
        print(f"| {name} | {r.attrs['wall_time_s']:.1f} | {r.attrs['forward_simulations']} | "
              f"{r.attrs['optimisations']} | {r.attrs['library_size']} |")
    many = runs[f"side-by-side, {args.workers} workers"]
    one = runs.get("side-by-side, 1 worker (this process)")
    if one is not None:
        print(f"speed-up {args.workers} workers vs 1: {one.attrs['wall_time_s'] / many.attrs['wall_time_s']:.2f}×")
        identical = np.array_equal(one.hull.values, many.hull.values) and np.array_equal(
            one.extremiser.values, many.extremiser.values)
        print(f"side-by-side hulls and extremisers bit-identical on 1 and {args.workers} workers: {identical}")
    if "one-by-one, this process" in runs:
        ref, new = runs["one-by-one, this process"].hull, many.hull
        for alpha in (0.0, 0.5):
            a = ref.sel(alpha=alpha, bound=["lower", "upper"]).values  # (bound, time)
            b = new.sel(alpha=alpha, bound=["lower", "upper"]).values
            width = float(np.max(a[1] - a[0]))
            further = np.concatenate([a[0] - b[0], b[1] - a[1]])  # > 0: side-by-side reaches further
            print(f"α = {alpha:g}, side-by-side vs one-by-one over every bound and time node: reaches further by up "
                  f"to {np.max(further) / width:.3%} of the widest one-by-one hull ({np.mean(further > 0):.1%} of the "
                  f"nodes), less far by up to {np.max(-further) / width:.3%} ({np.mean(further < 0):.1%}); hull area "
                  f"ratio {np.sum(b[1] - b[0]) / np.sum(a[1] - a[0]):.5f}")


if __name__ == "__main__":
    main()
