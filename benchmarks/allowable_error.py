"""Allowable marker error (issue 15, Deliver 3; thesis §5.5.2): how small the marker errors
must be for hip/knee/ankle flexion to be known within ±2.5°, checked by Monte Carlo, and
what the refinement costs next to the plain fuzzy run.

Run:  OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/allowable_error.py [--frames N]

For each session — ``sample_data/walking.c3d`` (Plug-in Gait, cgm1.0) and, when the
marker-error model per version is available (``fuzzy_joint_angles(clusters=)``), the
synthetic CGM 2.4 session ``sample_data/cgm24_*`` (cgm2.4):

1. plain run: both sides, hip/knee/ankle × X/Y/Z = 18 components, every frame (or
   ``--frames N`` spread over the trial), α = 0, 0.25, 0.5, 0.75, 1, Table 3.1 with all
   three sources, 2 workers; wall time and node evaluations;
2. refinement: :func:`fuzzygait.markererror.allowable.allowable_errors` on that run, all
   18 components, tolerance ±2.5°, resolution 0.1 mm, same evaluator; wall time, runs and
   node evaluations, as a fraction of the plain run's (issue target: ≤ 50 % added);
3. the allowable table (flexion rows);
4. independent check per flexion component: at the allowable scale a Monte Carlo
   (2,000 uniform deviations per frame inside those balls plus 1,000 whole perturbed
   curves) never leaves the tolerance; at 1.2× that scale a fresh Graph Follower run of
   that component does.
"""

from __future__ import annotations

from _setup import ROOT, one_thread

one_thread()

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import inspect  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.markererror.allowable import AllowableRequest, allowable_errors, band_excursion  # noqa: E402
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles  # noqa: E402
from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject  # noqa: E402
from fuzzygait.markererror.comparison import monte_carlo_envelope  # noqa: E402
from fuzzygait.markererror.sources import ErrorModel  # noqa: E402
from fuzzygait.uncertainty.execution import Evaluator  # noqa: E402
from fuzzygait.workflows.angles import AnglesRun, Preprocessing, run_angles  # noqa: E402

DATA = ROOT / "sample_data"
ANGLES = [f"{side}{joint}Angles" for side in "LR" for joint in ("Hip", "Knee", "Ankle")]
FLEXION = [f"{name}_X" for name in ANGLES]
ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
TOLERANCE = 2.5
RESOLUTION = 0.1
WORKERS = 2
MC_PER_FRAME, MC_CURVES = 2_000, 1_000
HAS_VERSIONS = "clusters" in inspect.signature(fuzzy_joint_angles).parameters


def _model(run: AnglesRun, name: str, frames: np.ndarray) -> JointAngleModel:
    fixed = fixed_subject(run.trial, run.subject)
    reference = run.result.angles[name][frames, 0]
    extra = {"model": run.result.model, "clusters": run.clusters} if HAS_VERSIONS else {}
    return JointAngleModel(run.trial, fixed, run.result.progression, name, 0, frames, reference=reference, **extra)


def _monte_carlo_task(args: tuple) -> tuple[str, float, int]:
    """Largest |MC angle − measured| (deg) over the frames at scale ``scale`` of Σ."""
    run, component, frames, scale, seed = args
    model = _model(run, component[:-2], frames)
    radii = scale * np.array([ErrorModel().radius(m) for m in model.markers])
    measured = run.result.angles[component[:-2]][frames, 0]
    largest = 0.0
    for per_frame, n in ((True, MC_PER_FRAME), (False, MC_CURVES)):
        lower, upper = monte_carlo_envelope(model, radii, n, seed=seed, per_frame=per_frame)
        largest = max(largest, float(np.max(np.maximum(upper - measured, measured - lower))))
    return component, largest, (MC_PER_FRAME + MC_CURVES) * frames.size


def _sparse(run: AnglesRun, n_frames: int | None) -> AnglesRun:
    if n_frames is None:
        return run
    frames = np.linspace(0, run.trial.n_frames - 1, n_frames).round().astype(int)
    markers = np.full_like(run.trial.markers, np.nan)
    markers[frames] = run.trial.markers[frames]
    return dataclasses.replace(run, trial=run.trial.with_markers(markers))


def study(title: str, run: AnglesRun, evaluator: Evaluator) -> None:
    trial, result = run.trial, run.result
    extra = {"clusters": run.clusters} if HAS_VERSIONS else {}
    options = FuzzyAngleOptions(alphas=ALPHAS, workers=WORKERS)
    start = time.perf_counter()
    plain = fuzzy_joint_angles(trial, run.subject, result, options, ANGLES, evaluator=evaluator, **extra)
    wall = time.perf_counter() - start
    start = time.perf_counter()
    request = AllowableRequest(options, TOLERANCE, None, RESOLUTION)
    table, refined = allowable_errors(trial, run.subject, result, request, fuzzy=plain, evaluator=evaluator,
                                      **extra)  # fmt: skip
    refine_wall = time.perf_counter() - start
    n_frames = int(np.isfinite(trial.markers[:, 0, 0]).sum())
    assert refined.allowable is not None  # the refinement group
    plain_ev, refine_ev = int(plain.attrs["node_evaluations"]), int(refined.allowable.attrs["node_evaluations"])
    runs = int(refined.allowable.attrs["runs"])
    print()
    print(f"## {title}: model {result.model}, {n_frames} frames, 18 components, α = {', '.join(map(str, ALPHAS))}")
    print(f"plain run: wall {wall:.1f} s, node evaluations {plain_ev:,}")
    print(f"refinement (±{TOLERANCE}°, resolution {RESOLUTION} mm, all 18 components): wall {refine_wall:.1f} s "
          f"= +{100 * refine_wall / wall:.0f} % of the plain run, node evaluations {refine_ev:,} "
          f"= +{100 * refine_ev / plain_ev:.0f} %, {runs} single-level runs "
          f"({runs / len(table):.1f} per component, max {int(table['evaluations'].max())})")  # fmt: skip

    frames = {c: np.flatnonzero(np.isfinite(result.angles[c[:-2]][:, 0]) &
                                np.isfinite(plain["hull"].sel(component=c, alpha=1.0, bound="upper").to_numpy()))
              for c in FLEXION}  # fmt: skip
    tasks = [(run, c, frames[c], float(table.loc[c, "allowable_scale"]), 15 + i) for i, c in enumerate(FLEXION)
             if 0 < table.loc[c, "allowable_scale"] < 1]  # fmt: skip
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=WORKERS) as pool:
        sampled = {c: (largest, rows) for c, largest, rows in pool.map(_monte_carlo_task, tasks)}
    mc_wall = time.perf_counter() - start
    beyond = {}
    for c in FLEXION:
        scale = float(table.loc[c, "allowable_scale"])
        if 0 < scale < 1 / 1.2:
            alpha = 1.0 - 1.2 * scale
            fuzzy = fuzzy_joint_angles(trial, run.subject, result, FuzzyAngleOptions(alphas=(alpha,)), [c[:-2]],
                                       evaluator=evaluator, **extra)  # fmt: skip
            beyond[c] = float(band_excursion(fuzzy, c).loc[alpha])
    print()
    print(f"### Allowable marker error for ±{TOLERANCE}° (flexion), with the independent check")
    print("| component | scale (of Table 3.1) | mm (largest ball) | per segment (mm) | GFA excursion at it (deg) "
          "| MC excursion at it (deg) | GFA excursion at 1.2x (deg) | runs |")
    print("|---|---|---|---|---|---|---|---|")
    for c in FLEXION:
        row = table.loc[c]
        segments = ", ".join(f"{s[:-3]} {row[s]:.1f}" for s in table.columns if s.endswith("_mm")
                             and s != "allowable_mm" and np.isfinite(row[s]))  # fmt: skip
        mc = f"{sampled[c][0]:.3f}" if c in sampled else "—"
        at_12 = f"{beyond[c]:.3f}" if c in beyond else "—"
        print(f"| {c} | {row['allowable_scale']:.4f} | {row['allowable_mm']:.2f} | {segments} | "
              f"{row['excursion_deg']:.3f} | {mc} | {at_12} | {row['evaluations']} |")  # fmt: skip
    ok_mc = all(v[0] <= TOLERANCE for v in sampled.values())
    ok_12 = all(v > TOLERANCE for v in beyond.values())
    print(f"Monte Carlo ({MC_PER_FRAME:,} per-frame deviations + {MC_CURVES:,} whole curves per frame, "
          f"{sum(v[1] for v in sampled.values()):,} angle evaluations, {mc_wall:.1f} s on {WORKERS} processes): "
          f"within ±{TOLERANCE}° everywhere: {ok_mc}; Graph Follower at 1.2x outside: {ok_12}")  # fmt: skip
    print()
    print("sentences:")
    for c in FLEXION:
        print(f"- {table.loc[c, 'text']}")
    others = [c for c in table.index if c not in FLEXION]
    print()
    print("other components (allowable mm on the largest ball): "
          + ", ".join(f"{c} {table.loc[c, 'allowable_mm']:.2f}" for c in others))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=None, help="frames spread over the trial (default: all)")
    args = parser.parse_args()
    command = "benchmarks/allowable_error.py" + (f" --frames {args.frames}" if args.frames else "")
    print(f"command: OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']} .venv/bin/python {command}   "
          f"({os.cpu_count()} cores, Python {sys.version.split()[0]})")  # fmt: skip
    pig = run_angles(DATA / "walking.c3d", static=DATA / "static.c3d", subject_file=DATA / "subject.toml")
    with Evaluator(workers=WORKERS) as evaluator:
        study("Plug-in Gait sample (walking.c3d)", _sparse(pig, args.frames), evaluator)
        if HAS_VERSIONS:
            cgm24 = run_angles(DATA / "cgm24_walking.c3d", static=DATA / "cgm24_static.c3d",
                               subject_file=DATA / "cgm24_subject.toml", preprocessing=Preprocessing(filter=False),
                               model="cgm2.4")  # fmt: skip
            study("synthetic CGM 2.4 session (cgm24_walking.c3d)", _sparse(cgm24, args.frames), evaluator)
        else:
            print("\n(CGM 2.4 session skipped: fuzzy_joint_angles has no per-version marker model yet)")


if __name__ == "__main__":
    main()
