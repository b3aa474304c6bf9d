"""Soundness of the fuzzy joint moments (issue 39 item 5): does every Monte Carlo moment lie
inside the Graph Follower hull?  And their cost beside the fuzzy angles'.

Run:  .venv/bin/python benchmarks/fuzzy_moments_soundness.py [--frames 20] [--samples 10000]
      [--first 1000] [--skip-angles] [--allowable-only] [--sample [--repeats N]]

Trial: ``Movement_trial.c3d`` (Vicon Nexus 2, four plates) with its own PROCESSING subject;
each foot gets the plate Nexus put under it (read back from its stored ground reaction,
:func:`~fuzzygait.kinetics.assignment.stored_assignment`).  The trial is cut to
``--frames`` consecutive frames of the right foot's stance on plate 4 (from C3D frame
``--first``; default: the contact's middle) plus the four frames either side the
derivatives need, and analysed as a user runs it
(:func:`~fuzzygait.markererror.fuzzy_kinetics.fuzzy_joint_moments`, default options:
Table 3.1 radii, a 10 mm COP ball on each loaded plate, α = 0, 0.25, 0.5, 0.75, 1,
``BatchedDirect`` with its stride and following): every moment component of both legs
(the left leg swings: markers only).

Monte Carlo: ``--samples`` independent uniform deviations in the balls of radius
(1 − α)·Σ (markers) and (1 − α)·10 mm (COP, in the plate's plane) for α = 0 and 0.5, the
same deviation at every frame, through the very model the analysis optimised.  Printed per
leg and α: samples × frames × components checked, how many lie outside the hull
(determined and undetermined frames apart), the largest excess (N·m/kg), and the hull / MC
width ratio (median, min) over the determined frames (pairs whose Monte Carlo range is
below 1e-9 N·m/kg left out: the swinging foot's ankle moment about its long axis is zero
whatever the deviation).

Cost: the wall time of the fuzzy moments (both legs, nine components each) and of the fuzzy
angles (:func:`~fuzzygait.markererror.analysis.fuzzy_joint_angles`, every angle, the same
α-levels) on the same cut trial, one process; the issue's speed line asks for ≤ 2×.

``--sample``: only the cost, on the whole sample trial (``sample_data/walking.c3d``, its two
plates, the automatic foot-plate assignment, calibrated on ``static.c3d``): the issue's speed
line, fuzzy moments of both legs against the fuzzy angles of every angle, CPU time, in one
process after a small fuzzy-angle run that pays the process's one-time costs for neither;
``--repeats N``: N runs of each, the order alternating, and the medians.

Allowable error: the right leg's sagittal moments at the α-levels :data:`FINE_ALPHAS`
(small balls), and :func:`~fuzzygait.markererror.fuzzy_kinetics.allowable_kinetic_error`'s
answer for ±0.1 N·m/kg.
"""

from __future__ import annotations

from _setup import VICON, one_thread

one_thread()

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.names import Side  # noqa: E402
from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.io.subject import subject_from_processing  # noqa: E402
from fuzzygait.kinematics import compute_lower_body  # noqa: E402
from fuzzygait.kinetics.assignment import stored_assignment  # noqa: E402
from fuzzygait.kinetics.plates import read_force_plates  # noqa: E402
from fuzzygait.kinetics.plug_in_gait import JOINTS  # noqa: E402
from fuzzygait.markererror.analysis import FuzzyAngleOptions, fuzzy_joint_angles  # noqa: E402
from fuzzygait.markererror.fuzzy_kinetics import (  # noqa: E402
    FootGround,
    FuzzyKineticsOptions,
    allowable_kinetic_error,
    foot_ground,
    fuzzy_joint_moments,
    leg_model,
    requested_components,
)
from fuzzygait.markererror.moment_model import HALF_WINDOW, PlateShare  # noqa: E402

CHECKED = (0.0, 0.5)
#: α-levels of the allowable-error answer (scales 20 % down to 1 % of the full balls).
FINE_ALPHAS = (0.8, 0.9, 0.95, 0.97, 0.99)
#: Samples evaluated per model call.
CHUNK = 500


def cut(trial: Trial, ground: dict[Side, FootGround], lo: int, hi: int) -> tuple[Trial, dict[Side, FootGround]]:
    """The trial and the feet's loads on samples ``lo … hi - 1``."""
    part = replace(trial, markers=trial.markers[lo:hi], first_frame=trial.first_frame + lo,
                   outputs={k: v[lo:hi] for k, v in trial.outputs.items()}, events=[])  # fmt: skip
    feet = {side: FootGround(g.force[lo:hi], g.moment[lo:hi],
                             tuple(PlateShare(p.number, p.force[lo:hi], p.axes) for p in g.plates))
            for side, g in ground.items()}  # fmt: skip
    return part, feet


def uniform_in_balls(rng: np.random.Generator, radii: np.ndarray, n: int) -> np.ndarray:
    """``(n, 3 × balls)`` deviations uniformly distributed in the balls of ``radii``."""
    direction = rng.standard_normal((n, radii.size, 3))
    direction /= np.linalg.norm(direction, axis=2, keepdims=True)
    return (direction * (radii * rng.random((n, radii.size)) ** (1.0 / 3.0))[..., None]).reshape(n, -1)


def check_leg(ds: object, trial: Trial, subject: object, side: Side, ground: FootGround, samples: int) -> None:
    """The Monte Carlo of one leg against the dataset's hulls (printed)."""
    components = requested_components(None, "Moment")[side]
    model = leg_model(trial, subject, side, components, ground, "Moment", "cgm1.0")  # type: ignore[arg-type]
    labels = model.component_labels()
    frames = model.frames
    radii = np.array([float(ds["ball_radius"].sel(marker=b)) for b in model.ball_names])  # type: ignore[index]
    columns = [(JOINTS.index(j), a) for j, a in model.components]
    rng = np.random.default_rng(7 if side is Side.LEFT else 11)
    for alpha in CHECKED:
        hull = ds["hull"].sel(component=labels, alpha=alpha).isel(frame=frames).to_numpy()  # type: ignore[index]
        flags = ds["undetermined"].sel(component=labels, alpha=alpha).isel(frame=frames).to_numpy()  # type: ignore[index]
        low, high = np.full(hull[:, 0].shape, np.inf), np.full(hull[:, 0].shape, -np.inf)
        excess = np.full(hull[:, 0].shape, -np.inf)
        for start in range(0, samples, CHUNK):
            P = uniform_in_balls(rng, (1.0 - alpha) * radii, min(CHUNK, samples - start))
            rows = np.repeat(P, frames.size, axis=0)
            out = np.asarray(model.outputs(rows, np.tile(frames, len(P))), dtype=float)
            out = out.reshape(len(P), frames.size, 3, 3)
            values = np.stack([out[:, :, j, a] for j, a in columns], axis=1)  # (samples, components, frames)
            low, high = np.minimum(low, values.min(axis=0)), np.maximum(high, values.max(axis=0))
            beyond = np.maximum(hull[None, :, 0] - values, values - hull[None, :, 1]).max(axis=0)
            excess = np.maximum(excess, beyond)
        outside = excess > 1e-9 * np.nanmax(np.abs(hull))
        spread = high - low  # a component that is zero whatever the deviation (the swinging ankle's Y) has none
        ratio = ((hull[:, 1] - hull[:, 0]) / np.where(spread > 1e-9, spread, np.nan))[~flags]
        ratio = ratio[np.isfinite(ratio)]
        median, smallest = (np.median(ratio), ratio.min()) if ratio.size else (np.nan, np.nan)
        print(f"  {side.word:5s} α = {alpha:.1f}: {samples} samples x {frames.size} frames x {len(labels)} components; "
              f"outside the hull at {int(outside[~flags].sum())} of {int((~flags).sum())} determined and "
              f"{int(outside[flags].sum())} of {int(flags.sum())} undetermined (component, frame) pairs; "
              f"largest excess {max(float(excess.max()), 0.0):.2e} N·m/kg; hull/MC width median "
              f"{median:.2f}, min {smallest:.2f}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--samples", type=int, default=10000)
    parser.add_argument("--first", type=int, default=None, help="C3D frame of the first checked frame")
    parser.add_argument("--skip-angles", action="store_true", help="no fuzzy-angle timing")
    parser.add_argument("--allowable-only", action="store_true", help="only the allowable-error answer")
    parser.add_argument("--sample", action="store_true", help="only the cost on the whole sample trial")
    parser.add_argument("--repeats", type=int, default=1, help="--sample: runs of each, alternated, in one process")
    args = parser.parse_args()
    if args.sample:
        sample_cost(args.repeats)
        return
    path = VICON / "Movement_trial.c3d"
    if not path.is_file():
        print(f"(skipped: {path} is absent)")
        return
    trial = read_c3d(path)
    subject = subject_from_processing(trial.parameters)
    plates = read_force_plates(path, threshold_n=0.0)
    ground = {side: foot_ground(plates, stored_assignment(plates, trial.outputs, side, subject.body_mass,
                                                          trial.rate).plate, trial.rate) for side in Side}  # fmt: skip
    stance = np.flatnonzero(np.abs(ground[Side.RIGHT].force[:, 2]) > 20.0)
    first = (int(np.median(stance)) - args.frames // 2) if args.first is None else args.first - trial.first_frame
    lo, hi = first - HALF_WINDOW, first + args.frames + HALF_WINDOW
    part, feet = cut(trial, ground, lo, hi)
    result = compute_lower_body(part, subject)
    if args.allowable_only:
        allowable(part, subject, result, feet)
        return
    shown = (part.first_frame + HALF_WINDOW, part.first_frame + hi - lo - 1 - HALF_WINDOW)
    print(f"Movement_trial.c3d, C3D frames {shown[0]}-{shown[1]} (right foot on plate(s) "
          f"{[p.number for p in feet[Side.RIGHT].plates]}), body mass {subject.body_mass} kg")  # fmt: skip
    start, cpu = time.perf_counter(), time.process_time()
    ds = fuzzy_joint_moments(part, subject, result, feet, FuzzyKineticsOptions())
    moments, moments_cpu = time.perf_counter() - start, time.process_time() - cpu
    print(f"fuzzy moments, both legs, 18 components: {moments:.1f} s wall, {moments_cpu:.1f} s CPU "
          f"({ds.attrs['node_evaluations']} node evaluations, {ds.attrs['node_gradients']} gradient rows)")  # fmt: skip
    print("ΔΦ (%), determined frames:\n" + ds.fuzzy.delta_phi().to_pandas().round(1).to_string())
    widths = ds.fuzzy.width().isel(frame=slice(HALF_WINDOW, -HALF_WINDOW))
    print("median band width (N·m/kg):\n" + widths.median("frame").to_pandas().round(3).to_string())
    print("undetermined frames:\n" + ds.fuzzy.undetermined().sum("frame").to_pandas().to_string())
    if not args.skip_angles:
        start, cpu = time.perf_counter(), time.process_time()
        fuzzy_joint_angles(part, subject, result, FuzzyAngleOptions())
        angles, angles_cpu = time.perf_counter() - start, time.process_time() - cpu
        print(f"fuzzy angles, every angle (30 components): {angles:.1f} s wall, {angles_cpu:.1f} s CPU; "
              f"moments / angles = {moments / angles:.2f} (wall), {moments_cpu / angles_cpu:.2f} (CPU)")  # fmt: skip
    print("Monte Carlo:")
    for side in Side:
        check_leg(ds, part, subject, side, feet[side], args.samples)
    allowable(part, subject, result, feet)


def sample_cost(repeats: int) -> None:
    """Fuzzy moments against fuzzy angles on the whole sample trial (printed, CPU time)."""
    from _setup import ROOT

    from fuzzygait.markererror.fuzzy_kinetics import contacts_ground
    from fuzzygait.workflows.angles import run_angles
    from fuzzygait.workflows.kinetics import trial_kinetics

    data = ROOT / "sample_data"
    run = run_angles(data / "walking.c3d", static=data / "static.c3d", subject_file=data / "subject.toml")
    kinetics = trial_kinetics(run)
    if kinetics is None:
        print("(the sample trial has no force plates)")
        return
    plates = read_force_plates(data / "walking.c3d")
    trial = run.trial
    feet = {side: contacts_ground(plates, kinetics.contacts, side, trial.n_frames, trial.rate) for side in Side}
    print(f"walking.c3d: {trial.n_frames} frames, contacts "
          f"{[(c.plate, c.side.value if c.side else None, c.first, c.last) for c in kinetics.contacts]}")  # fmt: skip
    # the process's one-time costs (xarray's first dataset imports dask.array, 0.4 s) paid by
    # neither: a small fuzzy-angle run of a joint neither side times (the pelvis' tilt, α = 0, 1)
    warm = np.full_like(trial.markers, np.nan)
    warm[:40] = trial.markers[:40]
    fuzzy_joint_angles(trial.with_markers(warm), run.subject, run.result, FuzzyAngleOptions(alphas=(0.0, 1.0)),
                       ["LPelvisAngles"])  # fmt: skip
    times: dict[str, list[float]] = {"moments": [], "angles": []}
    ds = None
    for repeat in range(repeats):  # the order alternates: what a process pays first falls on both
        for kind in ("moments", "angles") if repeat % 2 == 0 else ("angles", "moments"):
            cpu = time.process_time()
            if kind == "moments":
                ds = fuzzy_joint_moments(trial, run.subject, run.result, feet, FuzzyKineticsOptions())
            else:
                fuzzy_joint_angles(trial, run.subject, run.result, FuzzyAngleOptions())
            times[kind].append(time.process_time() - cpu)
        moments, angles = times["moments"][-1], times["angles"][-1]
        print(f"run {repeat + 1}: fuzzy moments (18 components) {moments:.1f} s CPU; fuzzy angles (every angle) "
              f"{angles:.1f} s CPU; moments / angles = {moments / angles:.2f}")  # fmt: skip
    moments, angles = statistics.median(times["moments"]), statistics.median(times["angles"])
    ratios = [m / a for m, a in zip(times["moments"], times["angles"], strict=True)]
    print(f"medians: fuzzy moments {moments:.1f} s CPU, fuzzy angles {angles:.1f} s CPU, moments / angles = "
          f"{moments / angles:.2f} (per run {min(ratios):.2f}-{max(ratios):.2f}); undetermined (component, α, frame): "
          f"{int(ds['undetermined'].sum()) if ds is not None else 0}")  # fmt: skip


def allowable(part: Trial, subject: object, result: object, feet: dict[Side, FootGround]) -> None:
    """The allowable-error answer (±0.1 N·m/kg) of the right leg's sagittal moments."""
    names = ["RAnkleMoment_X", "RKneeMoment_X", "RHipMoment_X"]
    fine = fuzzy_joint_moments(part, subject, result, feet, FuzzyKineticsOptions(alphas=FINE_ALPHAS),  # type: ignore[arg-type]
                               outputs=names)  # fmt: skip
    for name in names:
        print(allowable_kinetic_error(fine, name, 0.1).sentence)


if __name__ == "__main__":
    main()
