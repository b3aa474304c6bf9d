"""Table 5.2 analogue (issue 15): hip/knee/ankle flexion ΔΦ (Eq. 5.3) by model version on
the CGM 2.4 marker set, beside the thesis' values, and where a band is undetermined.

Run:  .venv/bin/python benchmarks/markererror_table52.py [--workers 2] [--quick]

Trials (Table 3.1 radii, all three sources, Cartesian deviations, BatchedDirect starts=3,
iterations=25, α = 0, 0.25, 0.5, 0.75, 1):

* synthetic: ``sample_data/cgm24_walking.c3d`` calibrated on ``cgm24_static.c3d`` with
  ``cgm24_subject.toml``, every 4th frame (128 of 512);
* real: ``../shared/data/cgm2/qualisys-cgm24-input`` (``Gait - CGM2 1.c3d``, static
  ``Static - CGM2 1.c3d``, session.xml's subject: LL 1000 mm, KW 95, AW 65, 14 mm markers,
  70 kg, 1800 mm; foot flat on as session.xml), every 2nd frame (136 of 272); skipped
  when the shared data is absent.

For each, ``cgm2.4`` (the thesis' marker set and the cluster model; its static cluster
calibration fixed) and ``cgm1.0`` (Plug-in Gait on the same markers) run through
:func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles` on every hip, knee, ankle (and
cgm2.4 forefoot) component of both sides.  Printed: ΔΦ of the flexion components per
α-level (``relative_envelope_width``: max over determined frames of the band width over
max |Φ|; "undet." where ``undetermined_levels`` says an α-level is undetermined
somewhere, the determined-frames value beside it), max Φ and the α = 0 width in degrees,
a Monte Carlo check (2,000 uniform deviations per frame in the α = 0 balls: sampled width
and the largest excursion beyond the hull), the undetermined table of every component,
for every undetermined flexion band which segment frame turns by how much at the
extremising deviation, and for cgm2.4 flexion at α = 0 the ΔΦ with one segment's markers
perturbed alone (the others held at their measured positions).
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import argparse  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from _sessions import Case, cases, load, subset  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.kinematics.model import angle_segments, model_chain  # noqa: E402
from fuzzygait.markererror.analysis import (  # noqa: E402
    FuzzyAngleOptions,
    fuzzy_joint_angles,
    relative_envelope_width,
    undetermined_levels,
)
from fuzzygait.markererror.angle_model import JointAngleModel, fixed_subject  # noqa: E402
from fuzzygait.markererror.comparison import monte_carlo_envelope  # noqa: E402
from fuzzygait.markererror.result import component_hull, component_undetermined  # noqa: E402
from fuzzygait.markererror.sources import ErrorModel, marker_segment  # noqa: E402
from fuzzygait.uncertainty import BatchedDirect, FuzzyBalls, graph_follower  # noqa: E402
from fuzzygait.workflows.angles import AnglesRun  # noqa: E402

ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)
LEVELS = (0.75, 0.5, 0.25, 0.0)
JOINTS = ("Hip", "Knee", "Ankle")
#: Thesis Table 5.2: left flexion ΔΦ (%) at α = 0.75, 0.5, 0.25, 0 (a real subject, CGM 2.4 markers).
THESIS = {"Hip": (27, 54, 81, 107), "Knee": (17, 35, 51, 68), "Ankle": (96, 199, 303, 425)}
MODELS = ("cgm2.4", "cgm1.0")
MC_SAMPLES = 2000


def model_of(run: AnglesRun, name: str, axis: int, frames: np.ndarray, **kwargs) -> JointAngleModel:
    return JointAngleModel(run.trial, fixed_subject(run.trial, run.subject), run.result.progression, name, axis,
                           frames, model=run.model, clusters=run.clusters,
                           reference=run.result.angles[name][frames, axis], **kwargs)  # fmt: skip


def rotation_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (deg) of the rotation between frames ``a`` and ``b`` (n, 3, 3)."""
    cos = (np.einsum("nij,nij->n", a, b) - 1.0) / 2.0
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def axis_tilt(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (deg) between the z axes of frames ``a`` and ``b``."""
    return np.degrees(np.arccos(np.clip(np.einsum("ni,ni->n", a[:, :, 2], b[:, :, 2]), -1.0, 1.0)))


def flip_diagnosis(run: AnglesRun, fuzzy_hull: np.ndarray, component: str, alpha: float,
                   analysed: np.ndarray, flagged: np.ndarray) -> str:  # fmt: skip
    """Where the band of ``component`` is undetermined at ``alpha`` (``flagged``: trial
    frame indices): how far the far bound is from the measured angle, how much the angle's
    proximal and distal segment frames turn at the extremising deviation (the same Graph
    Follower run as the dataset's, checked), and for the ankle the AJC shift and the
    ankle's middle Cardan angle (gimbal lock at 90°)."""
    name, axis = component[:-2], "XYZ".index(component[-1])
    model = model_of(run, name, axis, analysed)
    radii = np.array([ErrorModel().radius(m) for m in model.markers])
    result = graph_follower(model, FuzzyBalls(np.zeros((len(model.markers), 3)), radii, tuple(model.markers)),
                            ALPHAS, strategy=BatchedDirect(starts=3, iterations=25, seed=0))  # fmt: skip
    k = ALPHAS.index(alpha)
    hull = result["hull"].to_numpy()[k]
    same = np.allclose(hull, fuzzy_hull[:, analysed], rtol=0, atol=1e-9)
    extremiser = result["extremiser"].to_numpy()[k].reshape(2, analysed.size, len(model.markers), 3)
    where = np.flatnonzero(np.isin(analysed, flagged))
    bound = np.argmax(np.abs(hull[:, where] - model.reference[None, where]), axis=0)  # the far bound
    P = extremiser[bound, where]
    rows = [*model.markers, *model.fixed_markers]

    def chain(deviation: np.ndarray):  # noqa: ANN202
        full = np.concatenate([model._base[where] + deviation, model._fixed[where]], axis=1)
        return model_chain(Trial(full, rows, run.trial.rate), model.subject, model.model, model.clusters)

    measured, moved = chain(np.zeros_like(P)), chain(P)
    p0, d0 = angle_segments(measured, name, run.result.progression)
    p1, d1 = angle_segments(moved, name, run.result.progression)
    p0, p1 = (np.broadcast_to(p, d0.shape) for p in (p0, p1))
    excursion = np.abs(hull[bound, where] - model.reference[where])
    text = (f"far bound {excursion.min():.0f}-{excursion.max():.0f} deg from the measured angle; at its deviation "
            f"the proximal frame turns {rotation_deg(p0, p1).max():.0f} deg at most (its z axis "
            f"{axis_tilt(p0, p1).max():.0f}), the distal {rotation_deg(d0, d1).max():.0f} deg (z "
            f"{axis_tilt(d0, d1).max():.0f})" + ("" if same else " (rerun hull differs from the dataset's)"))
    if name[1:] == "AnkleAngles":
        side = name[0]
        shift = np.linalg.norm(moved.ajc(side) - measured.ajc(side), axis=1)
        lever = np.linalg.norm(measured.ajc(side) - measured.marker(side + "TOE"), axis=1)
        def middle(c) -> np.ndarray:  # noqa: ANN001
            cos = np.abs(np.einsum("ni,ni->n", c.ankle_tibia(side)[:, :, 1], c.foot(side)[:, :, 2]))
            return 90.0 - np.degrees(np.arccos(np.clip(cos, 0, 1)))

        text += (f"; AJC moves {shift.min():.0f}-{shift.max():.0f} mm (AJC-TOE {lever.mean():.0f} mm); |ankle middle "
                 f"Cardan angle| (hindfoot long axis out of the tibia's sagittal plane) {middle(measured).max():.0f} "
                 f"deg measured, {middle(moved).min():.0f}-{middle(moved).max():.0f} deg at the bound")  # fmt: skip
    return text


def segment_attribution(run: AnglesRun, frames: np.ndarray) -> list[str]:
    """ΔΦ (%) at α = 0 of the left flexions with one Table 3.1 segment's markers perturbed."""
    lines = []
    for joint in JOINTS:
        name = f"L{joint}Angles"
        full = model_of(run, name, 0, frames)
        reference = float(np.nanmax(np.abs(run.result.angles[name][:, 0])))
        groups: dict[str, list[str]] = {}
        for m in full.markers:
            groups.setdefault(marker_segment(m), []).append(m)
        groups["all"] = list(full.markers)
        parts = []
        for segment, markers in groups.items():
            model = model_of(run, name, 0, frames, markers=markers)
            radii = np.array([ErrorModel().radius(m) for m in markers])
            result = graph_follower(model, FuzzyBalls(np.zeros((len(markers), 3)), radii, tuple(markers)), (0.0, 1.0),
                                    strategy=BatchedDirect())  # fmt: skip
            hull = result["hull"].to_numpy()[0]
            flips = np.abs(hull - model.reference[None, :]).max() > 90.0
            width = 100.0 * float(np.max(hull[1] - hull[0])) / reference
            label = f"{segment} ({', '.join(m[1:] for m in markers)})"
            parts.append(f"{label} " + ("undet." if flips else f"{width:.0f}"))
        lines.append(f"| {name}_X | " + " | ".join(parts) + " |")
    return lines


def analyse(case: Case, model: str, workers: int, quick: bool) -> dict:
    run = load(case, model)
    step = case.step * (4 if quick else 1)
    sparse, keep = subset(run, step)
    names = [f"{s}{j}Angles" for s in "LR" for j in JOINTS] + (
        [f"{s}ForeFootAngles" for s in "LR"] if model == "cgm2.4" else [])
    options = FuzzyAngleOptions(alphas=ALPHAS, workers=workers)
    start = time.perf_counter()
    fuzzy = fuzzy_joint_angles(sparse.trial, sparse.subject, sparse.result, options, names, clusters=sparse.clusters)
    seconds = time.perf_counter() - start
    return {"run": run, "sparse": sparse, "frames": keep, "fuzzy": fuzzy, "seconds": seconds,
            "delta": relative_envelope_width(fuzzy), "undetermined": undetermined_levels(fuzzy)}  # fmt: skip


def flexion_table(case: Case, results: dict[str, dict]) -> list[str]:
    lines = ["| model | component | α = 0.75 | α = 0.5 | α = 0.25 | α = 0 | max Φ (deg) | max |Φ| | width α = 0 (deg) "
             "| MC α = 0 ΔΦ | MC beyond hull (deg) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for joint in JOINTS:
        lines.append(f"| thesis Table 5.2 | left {joint.lower()} flexion | "
                     + " | ".join(str(v) for v in THESIS[joint]) + " | | | | | |")  # fmt: skip
    for model, res in results.items():
        run, fuzzy, delta, undet = res["sparse"], res["fuzzy"], res["delta"], res["undetermined"]
        for side in "LR":
            for joint in (*JOINTS, *(("ForeFoot",) if model == "cgm2.4" else ())):
                component = f"{side}{joint}Angles_X"
                cells = []
                for alpha in LEVELS:
                    value = delta.loc[component, alpha]
                    cells.append(f"undet. ({value:.0f})" if undet.loc[component, alpha] else f"{value:.0f}")
                measured = run.result.angles[component[:-2]][:, 0]
                hull = component_hull(fuzzy, component).sel(alpha=0.0)
                flags = component_undetermined(fuzzy, component).sel(alpha=0.0).to_numpy()
                width = (hull.sel(bound="upper") - hull.sel(bound="lower")).to_numpy()
                frames = res["frames"]
                model_x = model_of(run, component[:-2], 0, frames)
                radii = np.array([ErrorModel().radius(m) for m in model_x.markers])
                lo, up = monte_carlo_envelope(model_x, radii, MC_SAMPLES, seed=52)
                g_lo, g_up = hull.sel(bound="lower").to_numpy()[frames], hull.sel(bound="upper").to_numpy()[frames]
                det = ~flags[frames]
                beyond = float(np.max(np.concatenate([(up - g_up)[det], (g_lo - lo)[det]]), initial=0.0))
                reference = float(np.nanmax(np.abs(measured)))
                mc = f"{100.0 * float(np.max((up - lo)[det])) / reference:.0f}" if det.any() else "-"
                hull_width = f"{np.max(width[frames][det]):.1f}" if det.any() else "-"
                lines.append(f"| {model} | {component} | " + " | ".join(cells)
                             + f" | {np.nanmax(measured):.1f} | {reference:.1f} | {hull_width} | {mc} "
                             f"| {beyond:.2f} |")  # fmt: skip
    return lines


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="4x fewer frames (a smoke run)")
    args = parser.parse_args()
    print(f"command: .venv/bin/python benchmarks/markererror_table52.py --workers {args.workers}"
          + (" --quick" if args.quick else "") + f"   ({os.cpu_count()} cores, Python {sys.version.split()[0]}, "
          f"load {os.getloadavg()[0]:.2f})")  # fmt: skip
    total = time.perf_counter()
    for case in cases():
        results = {model: analyse(case, model, args.workers, args.quick) for model in MODELS}
        first = results["cgm2.4"]
        print(f"\n### {case.name}: {first['frames'].size} of {first['run'].trial.n_frames} frames "
              f"(every {case.step * (4 if args.quick else 1)}th); fuzzy analysis "
              + ", ".join(f"{m} {r['seconds']:.0f} s ({r['fuzzy'].sizes['component']} components)"
                          for m, r in results.items()) + f"; workers={args.workers}")  # fmt: skip
        print()
        print("\n".join(flexion_table(case, results)))
        print()
        print("Undetermined (component: α-levels where some frame's band is undetermined, frames at the lowest):")
        for model, res in results.items():
            table = res["undetermined"]
            flagged = [(c, [a for a in table.columns if table.loc[c, a]])
                       for c in table.index if table.loc[c].any()]  # fmt: skip
            counts = [int(component_undetermined(res["fuzzy"], c).sel(alpha=min(a)).sum()) for c, a in flagged]
            print(f"* {model}: " + ("none" if not flagged else "; ".join(
                f"{c} α = {', '.join(f'{x:g}' for x in a)} ({n} frames)" for (c, a), n in zip(flagged, counts))))
        for model, res in results.items():
            table = res["undetermined"]
            for component in [c for c in table.index if c.endswith("_X") and table.loc[c].any()]:
                alpha = max(a for a in table.columns if table.loc[component, a])
                mask = component_undetermined(res["fuzzy"], component).sel(alpha=alpha).to_numpy()
                hull = component_hull(res["fuzzy"], component).sel(alpha=alpha).to_numpy()
                print(f"  - {model} {component}, highest undetermined α = {alpha:g} ({int(mask.sum())} frames): "
                      + flip_diagnosis(res["sparse"], hull, component, alpha, res["frames"], np.flatnonzero(mask)))
        print()
        print("cgm2.4 left flexion ΔΦ (%) at α = 0 with one segment's markers perturbed (others at their measured "
              "positions), every 4th analysed frame:")  # fmt: skip
        print("\n".join(segment_attribution(first["sparse"], first["frames"][::4])))
    print(f"\ntotal {time.perf_counter() - total:.0f} s")
    pd.set_option("display.width", 200)


if __name__ == "__main__":
    main()
