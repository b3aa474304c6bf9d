"""What the engine's Evaluator costs on the marker-error analysis: the demo's knee
angles (6 components, α = 0, 0.5) on the sample trial, serially in this process against
a local pool of 2 Dask workers — as the Evaluator starts it (glibc's default trim
threshold) and with Dask's own worker setting ``MALLOC_TRIM_THRESHOLD_=65536``.

    python benchmarks/evaluator_overhead.py

Prints wall seconds and their ratios to the serial run (same process, same data; the
cluster start is not timed); the hulls of all three runs are checked to be bit-identical.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import logging  # noqa: E402
import time  # noqa: E402

import dask  # noqa: E402
import numpy as np  # noqa: E402

from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402
from fuzzygait.uncertainty.execution.workers import WORKER_ENV  # noqa: E402
from fuzzygait.workflows.angles import run_angles  # noqa: E402

SAMPLE = ROOT / "sample_data"
ANGLES = ["LKneeAngles", "RKneeAngles"]


def timed(run, evaluator: Evaluator) -> tuple[float, np.ndarray]:
    start = time.perf_counter()
    fuzzy = fuzzy_joint_angles(run.trial, run.subject, run.result, FuzzyAngleOptions(alphas=(0.0, 0.5)), ANGLES,
                               evaluator=evaluator)  # fmt: skip
    return time.perf_counter() - start, fuzzy["hull"].to_numpy()


def main() -> None:
    from distributed import LocalCluster

    run = run_angles(SAMPLE / "walking.c3d", static=SAMPLE / "static.c3d", subject_file=SAMPLE / "subject.toml")
    serial, reference = timed(run, Evaluator())
    print(f"serial (this process): {serial:.1f} s")
    with Evaluator(workers=2) as pool:
        pool.n_workers()  # start the cluster outside the timing
        wall, hull = timed(run, pool)
    assert np.array_equal(hull, reference, equal_nan=True)
    print(f"Evaluator(workers=2): {wall:.1f} s ({wall / serial:.2f}x serial)")
    trimmed = dict(dask.config.get("distributed.nanny.pre-spawn-environ"))
    trimmed["MALLOC_TRIM_THRESHOLD_"] = 65536
    with dask.config.set({"distributed.nanny.pre-spawn-environ": trimmed}), LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, silence_logs=logging.ERROR, env=dict(WORKER_ENV),
        dashboard_address=None,
    ) as cluster, Evaluator(scheduler=cluster.scheduler_address) as dask_default:
        wall, hull = timed(run, dask_default)
    assert np.array_equal(hull, reference, equal_nan=True)
    print(f"2 workers with Dask's MALLOC_TRIM_THRESHOLD_=65536: {wall:.1f} s ({wall / serial:.2f}x serial)")
    print("hulls bit-identical in all three runs")


if __name__ == "__main__":
    main()
