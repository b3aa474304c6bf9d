"""Soundness of the fuzzy joint-angle hulls (issue 15): does every Monte Carlo angle lie
inside the Graph Follower hull, or at a frame marked undetermined?

Run:  .venv/bin/python benchmarks/markererror_soundness.py [--workers 2] [--frames 20]
      [--samples 10000] [--starts 3] [--iterations 25] [--stride 8] [--follow 5]
      [--only-checked-frames] [--trials NAME ...] [--angles NAME ...]

Trials (:mod:`_sessions`): the synthetic CGM 2.4 session and the real CGM 2.4 session with
model ``cgm2.4`` (static cluster calibration fixed), Movement_trial with ``cgm1.0``; per
trial ``--frames`` frames spread evenly over the frames where every angle is computed.
The hulls are those of :func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles` (Table
3.1 radii, all three sources, Cartesian, ``BatchedDirect``, the default α-levels 0, 0.25,
0.5, 0.75, 1) on the whole trial — as a user runs it: between its full optimisations at
every ``--stride``-th frame the Graph Follower follows the optima from frame to frame —
(``--only-checked-frames``: on a copy of the trial holding only the checked frames, each
then optimised in full), for every angle component the model computes (both sides;
cgm2.4 with ForeFootAngles).  The Monte Carlo uses the very models the analysis optimised
(:func:`~fuzzygait.markererror.analysis.component_tasks`: the same markers, fixed subject
and calibration, ``reference`` = the measured angle, so every sample is unwrapped onto the
branch through the measured angle as the hull is):
:func:`~fuzzygait.markererror.comparison.monte_carlo_envelope`, ``--samples`` independent
uniform deviations per frame in the balls of radius (1 − α)·Σ for α = 0 and 0.5.

Per component and α: the largest excursion of a sample beyond the hull over the determined
frames (deg; 0 = sound) and where (C3D frame, which bound), the undetermined frames and at
how many of them a sample lies outside the hull, and the hull / MC width ratio over the
determined frames (median, min).
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import zlib  # noqa: E402

import numpy as np  # noqa: E402
from _sessions import Case, cases, load, movement_case, sparse_run  # noqa: E402

from fuzzygait.kinematics.angles import ANGLE_TABLE  # noqa: E402
from fuzzygait.markererror.analysis import (  # noqa: E402
    DEFAULT_ALPHAS,
    ComponentTask,
    FuzzyAngleOptions,
    component_tasks,
    fuzzy_joint_angles,
)
from fuzzygait.markererror.angle_model import AXES  # noqa: E402
from fuzzygait.markererror.comparison import monte_carlo_envelope  # noqa: E402
from fuzzygait.markererror.result import component_hull, component_undetermined  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402

#: The α-levels checked (their balls: radius (1 − α)·Σ).
CHECKED = (0.0, 0.5)
#: An excursion below this (deg) is round-off, not a miss.
TOLERANCE = 1e-6


def trials() -> list[tuple[Case, str]]:
    """(session, model version) of the three trials."""
    out = [(case, "cgm2.4") for case in cases()]
    movement = movement_case()
    return out + ([(movement, "cgm1.0")] if movement is not None else [])


def spread_frames(angles: dict[str, np.ndarray], n: int) -> np.ndarray:
    """``n`` samples spread evenly over those where every angle is finite."""
    valid = np.flatnonzero(np.all([np.all(np.isfinite(a), axis=1) for a in angles.values()], axis=0))
    return valid[np.linspace(0, valid.size - 1, min(n, valid.size)).round().astype(int)]


def sample(job: tuple[ComponentTask, int, int]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Monte Carlo envelope ``(lower, upper)`` on the task's frames per checked α."""
    task, n_samples, seed = job
    model = task.angle_model()
    return [monte_carlo_envelope(model, (1.0 - alpha) * task.radii, n_samples, seed=seed + k)
            for k, alpha in enumerate(CHECKED)]  # fmt: skip


def compare(fuzzy, task: ComponentTask, envelopes: list, frame_numbers: np.ndarray) -> dict:  # noqa: ANN001
    """Excursion beyond the hull, undetermined frames and width ratios of one component."""
    component = f"{task.name}_{AXES[task.axis]}"
    row: dict = {"component": component}
    for alpha, (mc_lo, mc_up) in zip(CHECKED, envelopes, strict=True):
        hull = component_hull(fuzzy, component).sel(alpha=alpha)
        lo = hull.sel(bound="lower").to_numpy()[task.frames]
        up = hull.sel(bound="upper").to_numpy()[task.frames]
        undet = component_undetermined(fuzzy, component).sel(alpha=alpha).to_numpy()[task.frames]
        beyond = np.maximum(mc_up - up, lo - mc_lo)  # > 0: a sample outside the hull
        det = ~undet
        if det.any():
            i = int(np.flatnonzero(det)[np.argmax(beyond[det])])
            worst = float(beyond[i])
            bound = "upper" if mc_up[i] - up[i] >= lo[i] - mc_lo[i] else "lower"
            where = f"frame {frame_numbers[task.frames[i]]} {bound}"
            ratio = (up - lo)[det] / (mc_up - mc_lo)[det]
            median, low = float(np.median(ratio)), float(np.min(ratio))
        else:
            worst, where, median, low = float("nan"), "-", float("nan"), float("nan")
        missed = np.flatnonzero(det & (beyond > TOLERANCE))
        row[alpha] = {"beyond": worst, "where": where, "undetermined": int(undet.sum()),
                      "misses": [(int(task.frames[i]), float(beyond[i])) for i in missed],
                      "outside_at_undetermined": int(np.sum(undet & (beyond > TOLERANCE))),
                      "median": median, "min": low, "frames": int(task.frames.size)}  # fmt: skip
    return row


def run_trial(case: Case, model: str, args: argparse.Namespace, evaluator: Evaluator) -> dict:
    run = load(case, model)
    names = [n for n in run.result.angles if not args.angles or n in args.angles]
    frames = spread_frames(run.result.angles, args.frames)
    sparse = sparse_run(run, frames)
    options = FuzzyAngleOptions(alphas=DEFAULT_ALPHAS, starts=args.starts, iterations=args.iterations,
                                stride=args.stride, follow=args.follow)  # fmt: skip
    analysed = sparse if args.only_checked_frames else run
    start = time.perf_counter()
    fuzzy = fuzzy_joint_angles(analysed.trial, analysed.subject, analysed.result, options, names,
                               evaluator=evaluator, clusters=analysed.clusters)  # fmt: skip
    gfa_seconds = time.perf_counter() - start
    tasks, _ = component_tasks(sparse.trial, sparse.subject, sparse.result, options, names, sparse.clusters)
    start = time.perf_counter()
    # seeds per component name: a rerun of some angles (--angles) draws the same samples
    jobs = [(t, args.samples, zlib.crc32(f"{t.name}_{t.axis}".encode()) % 2**20) for t in tasks]
    envelopes = evaluator.map(sample, jobs)
    mc_seconds = time.perf_counter() - start
    rows = [compare(fuzzy, t, e, run.trial.frames) for t, e in zip(tasks, envelopes, strict=True)]
    return {"case": case, "model": model, "frame_numbers": run.trial.frames[frames], "rows": rows, "fuzzy": fuzzy,
            "frame_of": run.trial.frames,
            "gfa_seconds": gfa_seconds, "mc_seconds": mc_seconds, "evaluations": int(fuzzy.attrs["node_evaluations"]),
            "mc_evaluations": args.samples * len(CHECKED) * sum(t.frames.size for t in tasks)}  # fmt: skip


def number(x: float, digits: int = 2) -> str:
    return "-" if not np.isfinite(x) else f"{x:.{digits}f}"


def middle_axis(component: str) -> str:
    """The output axis holding the middle Cardan angle (asin, ±90° at gimbal lock) of the
    component's angle."""
    order = ANGLE_TABLE[component[1:-2].removesuffix("Angles")][0]
    return component[:-1] + AXES[order.index(1)]


def print_misses(res: dict) -> None:
    """Every determined (component, α, frame) with a sample beyond the hull, and how close
    the angle's middle Cardan component comes to gimbal lock (±90°) there."""
    for row in res["rows"]:
        for alpha in CHECKED:
            for frame, excursion in row[alpha]["misses"]:
                middle = middle_axis(row["component"])
                hull = component_hull(res["fuzzy"], middle).sel(alpha=alpha).to_numpy()[:, frame]
                print(f"  - {row['component']} α = {alpha:g} frame {res['frame_of'][frame]}: {excursion:.2f} deg "
                      f"beyond; middle Cardan angle {middle} hull [{hull[0]:.1f}, {hull[1]:.1f}]")  # fmt: skip


def print_trial(res: dict) -> None:
    case, rows = res["case"], res["rows"]
    print(f"\n### {case.name} ({res['model']}): {len(rows)} components, frames "
          f"{', '.join(str(f) for f in res['frame_numbers'])}")  # fmt: skip
    print(f"fuzzy_joint_angles {res['gfa_seconds']:.1f} s ({res['evaluations']:,} node evaluations); Monte Carlo "
          f"{res['mc_seconds']:.1f} s ({res['mc_evaluations']:,})")  # fmt: skip
    print()
    head = " | ".join(f"α = {a:g}: max MC − hull (deg) | where | undet. frames (MC outside) | ratio median | min"
                      for a in CHECKED)  # fmt: skip
    print(f"| component | {head} |")
    print("|---|" + "---|" * 5 * len(CHECKED))
    for row in rows:
        cells = []
        for alpha in CHECKED:
            c = row[alpha]
            cells += [number(c["beyond"]), c["where"], f"{c['undetermined']} ({c['outside_at_undetermined']})",
                      number(c["median"]), number(c["min"])]  # fmt: skip
        print(f"| {row['component']} | " + " | ".join(cells) + " |")
    print("(max MC − hull: the largest amount by which a sample lies beyond the hull over the determined frames, "
          "< 0: every sample inside by at least that much; where: that frame and bound; undet. frames: frames marked "
          "undetermined, in brackets those with a sample outside the hull; ratio: hull width / MC width per "
          "determined frame)")  # fmt: skip
    print()
    for alpha in CHECKED:
        cells = [r[alpha] for r in rows]
        beyond = [c["beyond"] for c in cells]
        k = int(np.nanargmax(beyond)) if np.isfinite(beyond).any() else 0
        misses = [r["component"] for r, c in zip(rows, cells) if c["beyond"] > TOLERANCE]
        listed = f" ({', '.join(misses)})" if misses else ""
        undet = sum(c["undetermined"] for c in cells)
        outside = sum(c["outside_at_undetermined"] for c in cells)
        print(f"summary α = {alpha:g}: largest excursion beyond the hull (determined frames) "
              f"{number(max(0.0, np.nanmax(beyond)))} deg ({rows[k]['component']}, {cells[k]['where']}); "
              f"components with an excursion > {TOLERANCE:g} deg: {len(misses)}{listed}; "
              f"undetermined (component, frame) {undet} of {sum(c['frames'] for c in cells)}, MC outside the hull "
              f"there {outside}; hull/MC width ratio median {number(np.nanmedian([c['median'] for c in cells]))}, "
              f"min {number(np.nanmin([c['min'] for c in cells]))}")  # fmt: skip
    print_misses(res)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--starts", type=int, default=FuzzyAngleOptions.starts)
    parser.add_argument("--iterations", type=int, default=FuzzyAngleOptions.iterations)
    parser.add_argument("--stride", type=int, default=FuzzyAngleOptions.stride)
    parser.add_argument("--follow", type=int, default=FuzzyAngleOptions.follow)
    parser.add_argument("--only-checked-frames", action="store_true",
                        help="analyse only the checked frames (each optimised in full), not the whole trial")
    parser.add_argument("--trials", nargs="*", default=[], help="substrings of the trial names to run")
    parser.add_argument("--angles", nargs="*", default=[], help="angle names (default: all the model computes)")
    args = parser.parse_args()
    print(f"command: .venv/bin/python benchmarks/markererror_soundness.py {' '.join(sys.argv[1:])}   "
          f"({os.cpu_count()} cores, Python {sys.version.split()[0]}, load {os.getloadavg()[0]:.2f}); "
          f"starts={args.starts}, iterations={args.iterations}, stride={args.stride}, follow={args.follow}, "
          f"{'checked frames only' if args.only_checked_frames else 'whole trials'}, {args.samples:,} MC samples "
          "per frame")  # fmt: skip
    total = time.perf_counter()
    with Evaluator(workers=args.workers) as evaluator:
        for case, model in trials():
            if args.trials and not any(t.lower() in case.name.lower() for t in args.trials):
                continue
            print_trial(run_trial(case, model, args, evaluator))
    print(f"\ntotal {time.perf_counter() - total:.0f} s (load at the end {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    main()
