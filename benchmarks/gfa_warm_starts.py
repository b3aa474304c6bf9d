"""Graph Follower warm starts in the batched optimiser: evaluations and hull quality per
configuration ``stride : follow : starts`` (``BatchedDirect``), issue 15.

Run:  .venv/bin/python benchmarks/gfa_warm_starts.py [--angles LKneeAngles,LAnkleAngles]
      [--model auto] [CONFIG ...]        (CONFIG = stride:follow:starts, e.g. 8:5:3)

``sample_data/walking.c3d`` (static calibration of ``static.c3d``), every frame, the
default α-levels and Table 3.1 radii, one process.  Per angle component and
configuration: wall time, node evaluations, and how far each bound stays inside the best
bound any configuration found (the union of the runs: both are inner bounds of the true
range, so the widest is the best estimate), as median / 99th percentile / maximum over the
(α, frame) pairs determined by that best hull, and the undetermined (α, frame) pairs
against the best hull's.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.markererror.analysis import FuzzyAngleOptions, component_tasks  # noqa: E402
from fuzzygait.markererror.angle_model import AXES  # noqa: E402
from fuzzygait.markererror.undetermined import undetermined  # noqa: E402
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower  # noqa: E402
from fuzzygait.workflows.angles import run_angles  # noqa: E402

DATA = ROOT / "sample_data"
DEFAULT_CONFIGS = ("1:0:3", "1:0:10", "8:5:3", "8:5:6", "8:5:10", "16:5:10")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("configs", nargs="*", default=list(DEFAULT_CONFIGS))
    parser.add_argument("--angles", default="LKneeAngles,LAnkleAngles")
    parser.add_argument("--model", default="auto")
    args = parser.parse_args()
    configs = [tuple(int(x) for x in c.split(":")) for c in args.configs]
    run = run_angles(DATA / "walking.c3d", static=DATA / "static.c3d", subject_file=DATA / "subject.toml",
                     model=args.model)  # fmt: skip
    tasks, _ = component_tasks(run.trial, run.subject, run.result, FuzzyAngleOptions(), args.angles.split(","),
                               clusters=run.clusters)  # fmt: skip
    print(f"command: .venv/bin/python benchmarks/gfa_warm_starts.py {' '.join(args.configs)} --angles {args.angles}")
    print("| component | stride : follow : starts | wall s | node evaluations | shortfall median / p99 / max (deg) "
          "| undetermined (α, frame) / best's |")
    print("|---|---|---|---|---|---|")
    for task in tasks:
        model = task.angle_model()
        params = FuzzyBalls(np.zeros((len(task.markers), 3)), task.radii, tuple(task.markers))
        runs = []
        for stride, follow, starts in configs:
            strategy = BatchedDirect(starts=starts, iterations=task.options.iterations, stride=stride, follow=follow)
            start = time.perf_counter()
            result = graph_follower(model, params, task.options.alphas, strategy=strategy)
            runs.append((time.perf_counter() - start, int(result.attrs["node_evaluations"]), result.hull.to_numpy()))
        hulls = np.stack([h for *_, h in runs])  # (config, alpha, bound, frame)
        best_lower, best_upper = hulls[:, :, 0].min(axis=0), hulls[:, :, 1].max(axis=0)
        measured = hulls[0, -1, 0]
        best_undetermined = undetermined(best_lower, best_upper, measured)
        for (stride, follow, starts), (wall, evaluations, hull) in zip(configs, runs, strict=True):
            short = np.fmax(best_upper - hull[:, 1], hull[:, 0] - best_lower)[~best_undetermined]
            flags = undetermined(hull[:, 0], hull[:, 1], measured)
            stats = " / ".join(f"{v:.2f}" for v in np.percentile(short, [50, 99, 100])) if short.size else "-"
            print(f"| {task.name}_{AXES[task.axis]} | {stride} : {follow} : {starts} | {wall:.2f} | "
                  f"{evaluations / 1e6:.2f} M | {stats} | {int(flags.sum())} / {int(best_undetermined.sum())} |")


if __name__ == "__main__":
    main()
