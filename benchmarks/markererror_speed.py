"""Fuzzy joint angles of the synthetic walking trial: Graph Follower speed, and the hull
against Monte Carlo sampling given the same wall time (thesis §5.5, Fig. 5.11, Table 5.2).

Run:  OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/markererror_speed.py [--joints] [--model auto]
          [--trial walking|cgm24] [--starts N] [--compare-gradients | --compare-starts N | --compare-grouping]

``--compare-gradients`` first runs the same analysis with forward-difference gradients
(``gradients="differences"``), ``--compare-starts N`` with N multistart points,
``--compare-grouping`` one angle component per task (``run_component_task``, instead of
an angle's components in shared calls), in the same process, and prints the wall ratio
and how the bands differ; ``--trial cgm24`` runs
on the synthetic CGM 2.4 session instead.

1. Graph Follower (``BatchedDirect`` strategy, Cartesian deviations, Table 3.1 radii with all
   three sources): ``sample_data/walking.c3d`` (static calibration of ``static.c3d``; the
   model version ``--model``, default auto = cgm1.0 on these markers), both sides, every
   angle component the model computes (``--joints``: hip/knee/ankle x X/Y/Z = 18 components
   only, the set of the first measurement), every frame, α = 0, 0.25, 0.5, 0.75, 1,
   ``workers=2``. Target (issue 15): <= 20 s on 2 cores for every component.
2. Monte Carlo with the same wall time: the same components on 2 processes, each
   given ``wall x 2 / n_components`` seconds; per sample and frame an independent deviation
   uniform in every marker's ball (random noise); as many samples per frame as fit. The
   models are those the analysis optimised (``component_tasks``: the measured angle as
   reference, so the samples are on the hull's continuous branch).
3. Per component at α = 0: hull width (upper − lower) mean and max over frames, GFA vs
   Monte Carlo, their ratio, and at how many frames the GFA hull contains the sampled
   range. Both are inner bounds of the true range (local optimisation / sampling); the
   wider one is the better estimate.
4. ΔΦ (Eq. 5.3, %) per component and α-level (Table 5.2 analogue).
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.markererror.analysis import (  # noqa: E402
    ComponentTask,
    FuzzyAngleOptions,
    component_tasks,
    fuzzy_joint_angles,
    relative_envelope_width,
    run_component_task,
    undetermined_levels,
)
from fuzzygait.markererror.angle_model import AXES  # noqa: E402
from fuzzygait.markererror.comparison import monte_carlo_timed  # noqa: E402
from fuzzygait.markererror.result import component_hull, component_undetermined  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402
from fuzzygait.workflows.angles import run_angles  # noqa: E402

DATA = ROOT / "sample_data"
JOINT_ANGLES = [f"{side}{joint}Angles" for side in "LR" for joint in ("Hip", "Knee", "Ankle")]
ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
WORKERS = 2
#: Table 5.2 of the thesis (flexion, %), for orientation only (a real subject, left side).
THESIS_TABLE_5_2 = {"Hip": (27, 54, 81, 107), "Knee": (17, 35, 51, 68), "Ankle": (96, 199, 303, 425)}


def _monte_carlo_task(args: tuple[ComponentTask, float, int]) -> tuple[str, np.ndarray, np.ndarray, int, int, float]:
    task, seconds, seed = args
    model = task.angle_model()
    start = time.perf_counter()
    lower, upper, samples = monte_carlo_timed(model, task.radii, seconds, seed=seed, per_frame=True)
    return (f"{task.name}_{AXES[task.axis]}", lower, upper, samples, samples * task.frames.size,
            time.perf_counter() - start)  # fmt: skip


def _compare_runs(baseline, fuzzy, components: list[str], label: str, baseline_wall: float, wall: float) -> None:
    """The run against a baseline run of the same components (``label``: what differs):
    wall time, work and the α < 1 hulls (both are inner approximations of the true range:
    the wider band is the better one)."""
    ratios, wider, narrower, largest = [], 0, 0, (0.0, "", 0.0)
    for name in components:
        old, new = component_hull(baseline, name), component_hull(fuzzy, name)
        keep = ~(component_undetermined(baseline, name) | component_undetermined(fuzzy, name))
        keep = keep.sel(alpha=keep.alpha < 1).to_numpy()
        w_old = (old.sel(bound="upper") - old.sel(bound="lower")).sel(alpha=old.alpha < 1).to_numpy()[keep]
        w_new = (new.sel(bound="upper") - new.sel(bound="lower")).sel(alpha=new.alpha < 1).to_numpy()[keep]
        ok = np.isfinite(w_old) & np.isfinite(w_new)
        change = w_new[ok] - w_old[ok]
        ratios.append(np.median(w_new[ok] / np.maximum(w_old[ok], 1e-12)))
        wider, narrower = wider + int(np.sum(change > 0.01)), narrower + int(np.sum(change < -0.01))
        if change.size and np.abs(change).max() > abs(largest[0]):
            at = int(np.argmax(np.abs(change)))
            largest = (float(change[at]), name, float(w_old[ok][at]))

    def work(run) -> str:
        return (f"node evaluations {int(run.attrs['node_evaluations']):,} + gradient rows "
                f"{int(run.attrs.get('node_gradients', 0)):,}")  # fmt: skip

    print()
    print(f"## Against {label} (same process, same options otherwise)")
    print(f"baseline: wall {baseline_wall:.1f} s, {work(baseline)}; this run: wall {wall:.1f} s, {work(fuzzy)}; "
          f"speed-up {baseline_wall / wall:.2f}x")  # fmt: skip
    print(f"band width this run / baseline over determined (α < 1, frame): median per component "
          f"{np.median(ratios):.4f} (range {min(ratios):.4f}-{max(ratios):.4f}); wider by > 0.01 deg at {wider}, "
          f"narrower at {narrower} (α, frame) points; largest change {largest[0]:+.3f} deg ({largest[1]}, "
          f"baseline width there {largest[2]:.3f} deg)")  # fmt: skip


def _compare_grouping(fuzzy, tasks: list[ComponentTask], separate: list, separate_wall: float,
                      wall: float) -> None:  # noqa: ANN001
    """One component per task against the components of an angle in shared calls (the
    raw hulls: where the dataset closes a middle Cardan band at ±90° near gimbal lock,
    ``gimbal_undetermined``, the capped values are left out)."""
    same, largest, deviation, capped = 0, 0.0, 0.0, 0
    for task, (column, hull, norms, _) in zip(tasks, separate, strict=True):
        grouped = component_hull(fuzzy, column).to_numpy()[:, :, task.frames]
        cap = np.abs(grouped) == 90.0
        capped += int(cap.sum())
        grouped, hull = np.where(cap, np.nan, grouped), np.where(cap, np.nan, hull)
        same += int(np.array_equal(grouped, hull, equal_nan=True))
        largest = max(largest, float(np.nanmax(np.abs(grouped - hull))))
        stored = fuzzy["deviation"].sel(component=column, marker=task.markers).to_numpy()[:, :, task.frames]
        deviation = max(deviation, float(np.nanmax(np.abs(stored - norms))))
    print()
    print("## Against one component per task (same process, same pool size)")
    print(f"one component per task: wall {separate_wall:.1f} s; an angle's components in shared calls: wall "
          f"{wall:.1f} s; ratio {wall / separate_wall:.2f}; hulls bit-identical for {same} of {len(tasks)} components "
          f"(largest difference {largest:.1e} deg; {capped} values capped at ±90° left out), deviation norms "
          f"within {deviation:.1e} mm")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--joints", action="store_true", help="hip/knee/ankle only (18 components)")
    parser.add_argument("--model", default="auto", help="model version (default: auto)")
    parser.add_argument("--trial", choices=("walking", "cgm24"), default="walking",
                        help="sample_data/walking.c3d (Plug-in Gait markers) or cgm24_walking.c3d (CGM 2.4 set)")
    parser.add_argument("--starts", type=int, default=FuzzyAngleOptions.starts, help="multistart points per frame")
    parser.add_argument("--compare-gradients", action="store_true",
                        help="first run the optimiser with forward differences in the same process: wall ratio and "
                             "how the hulls differ")  # fmt: skip
    parser.add_argument("--compare-starts", type=int, default=0, metavar="N",
                        help="first run with N multistart points instead (exact gradients): wall ratio and hulls")
    parser.add_argument("--compare-grouping", action="store_true",
                        help="first run one angle component per task (run_component_task, as before the components "
                             "of an angle shared the calls) on the same pool: wall ratio, and whether the hulls are "
                             "the same")  # fmt: skip
    args = parser.parse_args()
    print(f"command: OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']} .venv/bin/python "
          f"benchmarks/markererror_speed.py {' '.join(sys.argv[1:])}  ({os.cpu_count()} cores, Python "
          f"{sys.version.split()[0]}, load {os.getloadavg()[0]:.2f})")  # fmt: skip
    prefix = "" if args.trial == "walking" else "cgm24_"
    run = run_angles(DATA / f"{prefix}walking.c3d", static=DATA / f"{prefix}static.c3d",
                     subject_file=DATA / f"{prefix}subject.toml", model=args.model)  # fmt: skip
    trial, result = run.trial, run.result
    angles = [n for n in result.angles if not args.joints or n in JOINT_ANGLES]

    # ------------------------------------------------------------------ Graph Follower
    options = FuzzyAngleOptions(alphas=ALPHAS, workers=WORKERS, starts=args.starts)
    components = [f"{n}_{a}" for n in angles for a in AXES]
    baseline, label = None, ""
    if args.compare_gradients or args.compare_starts:
        changes = {"gradients": "differences"} if args.compare_gradients else {"starts": args.compare_starts}
        label = "forward differences" if args.compare_gradients else f"starts={args.compare_starts}"
        start = time.perf_counter()
        baseline = fuzzy_joint_angles(trial, run.subject, result, dataclasses.replace(options, **changes), angles,
                                      clusters=run.clusters)  # fmt: skip
        baseline_wall = time.perf_counter() - start
    separate = None
    if args.compare_grouping:
        tasks, _ = component_tasks(trial, run.subject, result, options, angles, run.clusters)
        start = time.perf_counter()
        with Evaluator(workers=WORKERS) as evaluator:
            separate = evaluator.map(run_component_task, tasks)
        baseline_wall = time.perf_counter() - start
    start = time.perf_counter()
    fuzzy = fuzzy_joint_angles(trial, run.subject, result, options, angles, clusters=run.clusters)
    wall = time.perf_counter() - start
    if separate is not None:
        _compare_grouping(fuzzy, tasks, separate, baseline_wall, wall)
    if baseline is not None:
        _compare_runs(baseline, fuzzy, components, label, baseline_wall, wall)
    print()
    print(f"## Fuzzy joint angles, {trial.n_frames} frames at {trial.rate:g} Hz, {len(components)} components, "
          f"α = {', '.join(f'{a:g}' for a in ALPHAS)}")  # fmt: skip
    evaluations = int(fuzzy.attrs["node_evaluations"])
    print(f"Graph Follower ({run.model}, batched direct, Cartesian, starts={options.starts}, iterations="
          f"{options.iterations}, workers={WORKERS}): wall {wall:.1f} s (target <= 20 s), node evaluations "
          f"{evaluations:,} ({evaluations / wall:,.0f} per s wall)")  # fmt: skip

    # ------------------------------------------------------------------ Monte Carlo, same wall time
    budget = wall * WORKERS / len(components)
    component_list, _ = component_tasks(trial, run.subject, result, options, angles, run.clusters)
    tasks = [(task, budget, 1000 + i) for i, task in enumerate(component_list)]
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=WORKERS) as pool:
        sampled = {out[0]: out for out in pool.map(_monte_carlo_task, tasks)}
    mc_wall = time.perf_counter() - start
    samples = np.array([out[3] for out in sampled.values()])
    rows = int(sum(out[4] for out in sampled.values()))
    print(f"Monte Carlo (uniform in the balls, fresh deviation per frame, {WORKERS} processes, "
          f"{budget:.2f} s per component): wall {mc_wall:.1f} s, node evaluations {rows:,}, "
          f"samples per frame {samples.min():,}-{samples.max():,}")  # fmt: skip

    # ------------------------------------------------------------------ widths at α = 0
    print()
    print("### Hull width at α = 0 (deg): Graph Follower vs Monte Carlo with the same wall time")
    print("| component | MC samples/frame | GFA mean | MC mean | ratio mean | GFA max | MC max | ratio max "
          "| min ratio per frame | frames GFA ⊇ MC | MC beyond GFA max | undetermined frames |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    ratios = []
    for name in components:
        hull = component_hull(fuzzy, name).sel(alpha=0.0)
        valid = np.isfinite(hull.sel(bound="upper").to_numpy())
        det = ~component_undetermined(fuzzy, name).sel(alpha=0.0).to_numpy()[valid]
        _, m_lo, m_up, n, _, _ = sampled[name]
        if not det.any():
            print(f"| {name} | {n:,} | " + " | ".join(["-"] * 9) + f" | {det.size} |")
            continue
        g_lo, g_up = hull.sel(bound="lower").to_numpy()[valid][det], hull.sel(bound="upper").to_numpy()[valid][det]
        m_lo, m_up = m_lo[det], m_up[det]
        g_w, m_w = g_up - g_lo, m_up - m_lo
        contains = np.mean((g_up >= m_up - 1e-9) & (g_lo <= m_lo + 1e-9))
        beyond = max(0.0, float(np.max(m_up - g_up)), float(np.max(g_lo - m_lo)))
        per_frame = g_w / m_w
        ratios.append(g_w.mean() / m_w.mean())
        print(f"| {name} | {n:,} | {g_w.mean():.1f} | {m_w.mean():.1f} | {g_w.mean() / m_w.mean():.2f} | "
              f"{g_w.max():.1f} | {m_w.max():.1f} | {g_w.max() / m_w.max():.2f} | {per_frame.min():.2f} | "
              f"{100 * contains:.1f}% | {beyond:.2f} | {int((~det).sum())} |")  # fmt: skip
    print(f"(over the determined frames; ratio of mean widths GFA/MC: median {np.median(ratios):.2f}, range "
          f"{min(ratios):.2f}-{max(ratios):.2f}; > 1: the Graph Follower hull reaches further than the equally "
          "expensive sample. 'MC beyond GFA max': the largest amount (deg) by which a sample fell outside the GFA "
          "hull, where the local optimiser missed the global extreme; undetermined frames (a bound more than 90° "
          "from the measured angle) are left out)")  # fmt: skip

    # ------------------------------------------------------------------ ΔΦ
    table, undetermined = relative_envelope_width(fuzzy), undetermined_levels(fuzzy)
    print()
    print("### ΔΦ (Eq. 5.3, %): max_t (upper − lower) / max_t |Φ| per α-level (Table 5.2 analogue; undet.: "
          "undetermined at some frame, the determined frames' value in brackets)")
    levels = list(table.columns)
    print("| component | " + " | ".join(f"α = {a:g}" for a in levels) + " | MC α = 0 | max |Φ| deg |")
    print("|---|" + "---|" * (len(levels) + 2))
    for name in components:
        measured = component_hull(fuzzy, name).sel(alpha=1.0, bound="upper")
        reference = float(np.nanmax(np.abs(measured)))
        _, m_lo, m_up, _, _, _ = sampled[name]
        det = ~component_undetermined(fuzzy, name).sel(alpha=0.0).to_numpy()[np.isfinite(measured.to_numpy())]
        mc = f"{100.0 * float(np.max((m_up - m_lo)[det])) / reference:.0f}" if det.any() else "-"
        cells = " | ".join((f"undet. ({table.loc[name, a]:.0f})" if undetermined.loc[name, a]
                            else f"{table.loc[name, a]:.0f}") for a in levels)  # fmt: skip
        print(f"| {name} | {cells} | {mc} | {reference:.1f} |")
    print("thesis Table 5.2 (left flexion, a real subject; α = 0.75, 0.5, 0.25, 0): "
          + "; ".join(f"{j} {', '.join(map(str, v))}" for j, v in THESIS_TABLE_5_2.items()))


if __name__ == "__main__":
    main()
