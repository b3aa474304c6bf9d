"""Leg model on Dask workers: build time and 4 runs on 2 workers (was printed and asserted,
``build_seconds < 2``, by the parallel-evaluation test; the test now checks only that no
worker recompiles and that results are bit-identical).

Run:  .venv/bin/python benchmarks/parallel_leg_build.py

The test's case: swing, 6 blade nodes, total deformation energy as a function of E
(4 values, 0.05 s simulated, with sensitivities). The baseline, in this process, is one
build of the same recipe from the on-disk compiled library (a load, no compilation) and
the 4 runs done serially. Then a local pool of 2 worker processes: its first call (the
pool starts, each worker builds once) and a second, warm call; each worker's own build
time is shown against the in-process build. Starts a 2-process Dask cluster; about 10 s.
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import time  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.mechanics.scenarios import LegSimulator  # noqa: E402
from fuzzygait.mechanics.solver import SolverSettings  # noqa: E402
from fuzzygait.mechanics.targets import LegModelRecipe  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402

P = np.array([[4.0e5], [5.0e5], [6.0e5], [7.0e5]])


def timed(func):
    start = time.perf_counter()
    out = func()
    return time.perf_counter() - start, out


def main() -> None:
    base = tuple(LegSimulator("swing", nodes=6).parameters(eta=1e5))  # compiles once if not cached
    recipe = LegModelRecipe("swing", "total_deformation_energy", ("E",), base=base, nodes=6,
                            settings=SolverSettings(duration=0.05))
    build, _ = timed(recipe.build)
    with Evaluator() as serial:
        batch = serial.batch(recipe, sensitivities=True)
        batch(P)  # the serial batch builds its model on the first call
        runs_serial, expected = timed(lambda: batch(P))
    with Evaluator(workers=2) as pool:
        batch = pool.batch(recipe, sensitivities=True)
        first, values = timed(lambda: batch(P))
        warm, _ = timed(lambda: batch(P))
        builds = list(batch.builds)
    assert all(np.array_equal(a, b) for a, b in zip(values, expected, strict=True))
    print("## Leg model on 2 Dask workers (swing, 6 nodes, 4 values of E, 0.05 s, sensitivities)")
    print("| step | seconds | ratio to baseline |")
    print("|---|---|---|")
    print(f"| baseline: build from the compiled library, this process | {build:.2f} | 1.00 |")
    for b in builds:
        print(f"| build in worker pid {b['pid']} | {b['build_seconds']:.2f} | {b['build_seconds'] / build:.2f} |")
    print(f"| baseline: 4 runs, serial | {runs_serial:.2f} | 1.00 |")
    print(f"| 4 runs, 2 workers, first call (starts the pool; the builds) | {first:.2f} | {first / runs_serial:.2f} |")
    print(f"| 4 runs, 2 workers, warm | {warm:.2f} | {warm / runs_serial:.2f} |")


if __name__ == "__main__":
    main()
