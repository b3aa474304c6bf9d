"""Where the marker-error analysis' work goes (issue 40, item 1): counts, not wall times.

Run:  .venv/bin/python benchmarks/markererror_work.py [--trial walking|cgm24] [--frames N] [--profile] [--row-costs]
      .venv/bin/python benchmarks/markererror_work.py --scaling [--trial walking|cgm24] [--repeats 3]

The default analysis of ``fuzzygait uncertainty sample_data/walking.c3d`` (Table 3.1,
all sources, α = 0, 0.25, 0.5, 0.75, 1, the allowable error for ±2.5°, the per-source
bands of the flexion angles; :func:`~fuzzygait.workflows.marker_uncertainty.analyse_run`)
in this process (one worker, so every Graph Follower run is counted here); ``--frames N``:
on the trial's first N frames.  Per stage (main bands, allowable refinement,
per-source bands): the Graph Follower runs, the nodes (components x frames) and α-levels
< 1 they optimise, the model rows (values, exact gradients) per node and α-level and
bound, the solver's iterations (:func:`~fuzzygait.uncertainty.gfa.spectral.maximise_spectral`,
or :func:`~fuzzygait.uncertainty.gfa.batched.maximise`: calls, starting points, point-iterations per point, points still active after the
last iteration, iterations without gain, the step fractions taken), how many starts per
node end at the same optimum (within 1e-3°) and which start wins, and the frames that
flip (undetermined).  ``--profile``: a cProfile of the whole analysis, the functions by
own time (proportions; the machine is shared, so only the proportions mean something).
CPU seconds (``time.process_time``) are printed for reference.  ``--row-costs``: the
angle model's CPU per call and per row (values, exact gradients).

``--scaling``: the cost per frame and the fixed cost per trial as a batch pays them
(issue 40, item 4: start-up and imports once per batch): in this one process, after one
analysis of another cut of the trial (its last 64 frames: the modules imported, the
compiled models loaded), the default analysis of the trial's first 128 frames and of the
whole trial (512 frames) alternated ``--repeats`` times; medians of the CPU seconds, their
ratio, and the line through them (seconds per frame; the fixed cost per trial, its
intercept).  The first analysis in a fresh process (what one ``fuzzygait uncertainty``
pays on top) is the default mode's CPU, ``--frames 128`` and without.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import cProfile  # noqa: E402
import pstats  # noqa: E402
import time  # noqa: E402
from collections import defaultdict  # noqa: E402
from dataclasses import dataclass, field, replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.io.c3d import read_c3d  # noqa: E402
from fuzzygait.uncertainty.gfa import batched  # noqa: E402
from fuzzygait.workflows.angles import AnglesRun, run_angles  # noqa: E402
from fuzzygait.workflows.marker_uncertainty import MarkerErrorSettings, analyse_run  # noqa: E402

DATA = ROOT / "sample_data"
STAGES = ("fuzzy angles", "allowable marker error", "per-source bands")


@dataclass
class Stage:
    """The counts of one stage's Graph Follower runs."""

    runs: int = 0
    node_levels: int = 0  # nodes x α-levels < 1 x bounds
    counts: list[batched.BatchCounts] = field(default_factory=list)
    cpu: float = 0.0


class Recorder:
    """Stage progress that labels the Graph Follower runs with the current stage."""

    def __init__(self) -> None:
        self.stages: dict[str, Stage] = defaultdict(Stage)
        self.current = "before"
        self.started = time.process_time()

    def stage(self, description: str, total: int | None = None) -> None:
        now = time.process_time()
        self.stages[self.current].cpu += now - self.started
        self.current, self.started = description, now

    def update(self, completed: int, total: int | None = None) -> None:
        pass

    def finish(self) -> None:
        self.stage("after")


def instrument(recorder: Recorder) -> None:
    """Record every batched run's counts and size in ``recorder`` (level by level,
    ``run_batched``, and all levels together, ``run_levels_together``)."""
    import fuzzygait.uncertainty.gfa.api as api

    def counting(original):  # type: ignore[no-untyped-def]
        def counted(model, params, levels, strategy, progress):  # type: ignore[no-untyped-def]
            made: list[batched.BatchCounts] = []
            factory = batched.BatchCounts

            def make() -> batched.BatchCounts:
                made.append(factory())
                return made[-1]

            batched.BatchCounts = make  # type: ignore[assignment,misc]
            try:
                out = original(model, params, levels, strategy, progress)
            finally:
                batched.BatchCounts = factory  # type: ignore[misc]
            stage = recorder.stages[recorder.current]
            stage.runs += 1
            stage.node_levels += int(model.n_time) * (np.asarray(levels).size - 1) * 2
            stage.counts += made
            return out

        return counted

    api.run_batched = counting(api.run_batched)  # type: ignore[assignment]
    api.run_levels_together = counting(api.run_levels_together)  # type: ignore[assignment]


def table(recorder: Recorder) -> list[str]:
    rows = ["| stage | runs | node·levels·bounds | value rows / node-level | gradient rows / node-level | "
            "maximise iterations | starting points | point-iterations / point | still active at the end | "
            "iterations without gain | full steps (FW 1 / PG 1) | same optimum / node | "
            "winner (det., higher, scaled, random…) | CPU s |",  # fmt: skip
            "|---" * 14 + "|"]
    for name in STAGES:
        if name not in recorder.stages:
            continue
        s = recorder.stages[name]
        c = s.counts
        total = {k: sum(getattr(x, k) for x in c) for k in ("node_evaluations", "node_gradients", "iterations",
                                                           "points", "point_iterations", "unconverged", "no_gain",
                                                           "same_optimum")}  # fmt: skip
        steps = sum((x.steps for x in c), np.zeros(10, dtype=int))
        winner = sum((x.winner for x in c), np.zeros(16, dtype=int))
        taken = max(int(steps.sum()), 1)
        multistart = max(int(winner.sum()), 1)
        rows.append(
            f"| {name} | {s.runs} | {s.node_levels} | {total['node_evaluations'] / s.node_levels:.1f} | "
            f"{total['node_gradients'] / s.node_levels:.1f} | {total['iterations']} | {total['points']} | "
            f"{total['point_iterations'] / max(total['points'], 1):.1f} | "
            f"{100 * total['unconverged'] / max(total['points'], 1):.0f} % | "
            f"{100 * total['no_gain'] / max(total['point_iterations'], 1):.0f} % | "
            f"{100 * steps[0] / taken:.0f} % / {100 * steps[5] / taken:.0f} % | "
            f"{total['same_optimum'] / multistart:.2f} | "
            f"{' '.join(str(int(w)) for w in winner[:6])} | {s.cpu:.1f} |"
        )
        rows.append(f"|  step histogram FW 1..1/16, PG 1..1/16: {' '.join(str(int(v)) for v in steps)} |")
    return rows


def trial_run(name: str, frames: int | None = None, first: int = 0) -> AnglesRun:
    """The sample trial's joint-angle run (``frames``: its ``frames`` frames from ``first``
    only, the events outside them dropped, without its force plates)."""
    prefix = "" if name == "walking" else "cgm24_"
    model = "cgm1.0" if name == "walking" else "cgm2.4"
    dynamic: Path | Trial = DATA / f"{prefix}walking.c3d"
    if frames is not None:
        trial = read_c3d(dynamic)
        t0, t1 = first / trial.rate, (first + frames) / trial.rate
        dynamic = replace(trial, markers=trial.markers[first:first + frames], source=None,
                          events=[replace(e, time=e.time - t0) for e in trial.events if t0 <= e.time < t1])  # fmt: skip
    return run_angles(dynamic, static=DATA / f"{prefix}static.c3d", subject_file=DATA / f"{prefix}subject.toml",
                      model=model)  # fmt: skip


def row_costs(run: AnglesRun) -> None:
    """CPU per model call and per row of the left knee's angle model, values and exact
    gradients, at 10 … 10,000 rows a call (what a node-level costs besides the calls)."""
    from fuzzygait.markererror.analysis import FuzzyAngleOptions, component_tasks

    options = FuzzyAngleOptions(alphas=(0.0, 1.0))
    tasks, _ = component_tasks(run.trial, run.subject, run.result, options, ["LKneeAngles"])
    model = tasks[0].angle_model()
    rng = np.random.default_rng(0)
    print("\nLKneeAngles model, CPU per call (per row): rows | values | exact gradients")
    for k in (10, 100, 1000, 10000):
        nodes, P = rng.integers(0, model.frames.size, k), rng.normal(0.0, 3.0, (k, model.n_parameters))
        cost = []
        for function in (model.evaluate_nodes, model.evaluate_nodes_gradients):
            start, calls = time.process_time(), 0
            while time.process_time() - start < 1.0:
                function(P, nodes)
                calls += 1
            cost.append((time.process_time() - start) / calls)
        print(f"  {k:6d} | {1e3 * cost[0]:.2f} ms ({1e6 * cost[0] / k:.2f} µs) | "
              f"{1e3 * cost[1]:.2f} ms ({1e6 * cost[1] / k:.2f} µs)")  # fmt: skip


def scaling(trial: str, repeats: int) -> None:
    """Per-trial CPU of the default analysis on 128 and all frames in a warm process
    (``--scaling``, see the module docstring)."""
    whole = trial_run(trial)
    n = whole.trial.n_frames
    settings = MarkerErrorSettings(workers=1)
    start = time.process_time()
    analyse_run(trial_run(trial, 64, n - 64), settings)
    print(f"{trial}: warm-up analysis of frames {n - 64}-{n - 1} (the first in this process): "
          f"{time.process_time() - start:.2f} s CPU")  # fmt: skip
    runs = {128: trial_run(trial, 128), n: whole}
    cpu: dict[int, list[float]] = {128: [], n: []}
    for _ in range(repeats):
        for frames, run in runs.items():
            start = time.process_time()
            analyse_run(run, settings)
            cpu[frames].append(time.process_time() - start)
    small, large = (float(np.median(cpu[f])) for f in (128, n))
    per_frame = (large - small) / (n - 128)
    print(f"  128 frames: {small:.2f} s CPU (runs {', '.join(f'{c:.2f}' for c in cpu[128])})")
    print(f"  {n} frames: {large:.2f} s CPU (runs {', '.join(f'{c:.2f}' for c in cpu[n])})")
    print(f"  time({n})/time(128) = {large / small:.2f}; {1e3 * per_frame:.1f} ms per frame; "
          f"fixed cost per trial {small - 128 * per_frame:.2f} s")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trial", default="walking", choices=("walking", "cgm24"))
    parser.add_argument("--profile", action="store_true")
    parser.add_argument("--frames", type=int, default=None, help="the trial's first N frames only")
    parser.add_argument("--row-costs", action="store_true", help="also the model's CPU per call and per row")
    parser.add_argument("--scaling", action="store_true", help="per-trial cost on 128 and all frames, warm process")
    parser.add_argument("--repeats", type=int, default=3, help="alternations of --scaling")
    args = parser.parse_args()
    if args.scaling:
        scaling(args.trial, args.repeats)
        return
    run = trial_run(args.trial, args.frames)
    if args.row_costs:
        row_costs(run)
    recorder = Recorder()
    instrument(recorder)
    settings = MarkerErrorSettings(workers=1)
    profiler = cProfile.Profile() if args.profile else None
    start = time.process_time()
    if profiler is not None:
        profiler.enable()
    analysis = analyse_run(run, settings, stages=recorder)
    if profiler is not None:
        profiler.disable()
    recorder.finish()
    cpu = time.process_time() - start
    fuzzy = analysis.fuzzy
    flags = fuzzy["undetermined"].to_numpy()
    print(f"{args.trial}: {run.trial.n_frames} frames, {fuzzy.sizes['component']} components, α "
          f"{', '.join(f'{a:g}' for a in fuzzy['alpha'].to_numpy())}; CPU {cpu:.1f} s (one process)")  # fmt: skip
    print(f"frames that flip (undetermined, component x α x frame): {int(flags.sum())} of {flags.size}; "
          f"components with any: {int(flags.any(axis=(1, 2)).sum())}")  # fmt: skip
    print("\n".join(table(recorder)))
    if profiler is not None:
        stats = pstats.Stats(profiler)
        total = sum(v[2] for v in stats.stats.values())  # type: ignore[attr-defined]
        rows = sorted(stats.stats.items(), key=lambda kv: -kv[1][2])[:15]  # type: ignore[attr-defined]
        print("\ncProfile, own time (share of the profiled total):")
        for (file, line, func), (_cc, nc, tt, ct, _callers) in rows:
            print(f"  {100 * tt / total:5.1f} %  {100 * ct / total:5.1f} % cum  {nc:8d} calls  "
                  f"{file.split('src/')[-1]}:{line} {func}")  # fmt: skip


if __name__ == "__main__":
    main()
