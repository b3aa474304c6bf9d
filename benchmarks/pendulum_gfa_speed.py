"""Graph Follower vs dense sampling on the pendulum: time (was printed by tests/test_gfa.py).

Run:  .venv/bin/python benchmarks/pendulum_gfa_speed.py [--repeat 3]

The case of ``tests/test_gfa.py::test_pendulum_against_dense_sampling`` (which checks the
hull and the evaluation count): length L triangular ±10 % about 1 m, α = 0, 0.5, 1,
201 time nodes over 2 s. The baseline, run in the same process, is the test's dense
reference: 201 lengths across each α-cut (α = 0, 0.5) plus the deterministic run, min/max
per node. Shown: seconds (best of ``--repeat``), forward simulations, and the GFA's time as
a fraction of the baseline's. Takes a few seconds.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.mechanics.pendulum import Pendulum  # noqa: E402
from fuzzygait.uncertainty import FuzzyVector, graph_follower, triangular_relative  # noqa: E402

LENGTH = triangular_relative(1.0, 0.1, "L")


def dense(model: Pendulum) -> int:
    """The test's dense reference; returns the number of forward simulations."""
    runs, bounds = 0, []
    for alpha in (0.0, 0.5):
        lo, hi = LENGTH.alpha_cut(alpha)
        values = np.array([model.evaluate(np.array([v])).values for v in np.linspace(lo, hi, 201)])
        bounds.append((values.min(axis=0), values.max(axis=0)))
        runs += values.shape[0]
    model.evaluate(np.array([1.0]))
    return runs + 1


def gfa(model: Pendulum) -> int:
    result = graph_follower(model, FuzzyVector([LENGTH]), (0.0, 0.5, 1.0))
    return int(result.attrs["forward_simulations"])


def best_of(func: Callable[[], int], repeat: int) -> tuple[float, int]:
    times, count = [], 0
    for _ in range(repeat):
        start = time.perf_counter()
        count = func()
        times.append(time.perf_counter() - start)
    return min(times), count


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each; the best is shown")
    args = parser.parse_args()
    model = Pendulum()
    baseline, dense_runs = best_of(lambda: dense(model), args.repeat)
    seconds, gfa_runs = best_of(lambda: gfa(model), args.repeat)
    print("## Pendulum: Graph Follower vs dense sampling (L ±10 %, α = 0, 0.5, 1, 201 nodes)")
    print(f"| method | seconds (best of {args.repeat}) | forward simulations | ratio to baseline |")
    print("|---|---|---|---|")
    print(f"| baseline: dense sampling, 201 lengths per α-cut | {baseline:.2f} | {dense_runs} | 1.00 |")
    print(f"| graph_follower (defaults) | {seconds:.2f} | {gfa_runs} | {seconds / baseline:.2f} |")


if __name__ == "__main__":
    main()
