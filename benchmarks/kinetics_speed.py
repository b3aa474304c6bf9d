"""Speed of the Plug-in Gait kinetics of both legs, against the angles in the same process.

Run:  .venv/bin/python benchmarks/kinetics_speed.py [--repeats N]

On ``../shared/data/vicon/Movement_trial.c3d`` (323 frames at 120 Hz, 4 plates at
1080 Hz; or, when the reference data is absent, ``sample_data/walking.c3d`` and its
plates if it has any), one core (BLAS and OpenMP threads pinned to 1), best of
``--repeats`` (default 30) after a warm-up:

* ``angles``: :func:`fuzzygait.kinematics.compute_lower_body` (the model: joint centres,
  segment frames, every angle of both sides), the reference;
* ``plates read``: :func:`fuzzygait.kinetics.plates.read_force_plates` at the analog rate,
  once per trial (file reading included);
* ``assignment + inverse dynamics``: from the plates read and the model's result, the
  automatic foot-plate assignment
  (:func:`~fuzzygait.kinetics.assignment.automatic_assignment`), each foot's ground load
  (:func:`~fuzzygait.kinetics.assignment.contact_ground`) and the joint forces, moments
  and powers of both legs (:func:`~fuzzygait.kinetics.plug_in_gait.plug_in_gait_kinetics`);
* ``inverse dynamics alone``: ``plug_in_gait_kinetics`` with the ground loads made;
  — both with the centres of mass differentiated as Nexus does (``ComDerivative.GCV_SPLINE``,
  the quintic GCV smoothing spline: the pipeline's default), and the same two with the
  five-point differences (``ComDerivative.FIVE_POINT``);
* the spline alone: one centre-of-mass-like trajectory of the trial (the left knee joint
  centre, 3 components), the six centres of mass of both legs together
  (:func:`~fuzzygait.kinetics.gcv_spline.spline_second_derivatives`, as the kinetics
  call it), and a synthetic 6,000-frame one (a 1 Hz swing with 0.1 mm noise:
  banded, ``O(n)``, nothing cached per trial length).

Prints seconds, marker frames per second and the ratio of each time to the angles'.
The issue's target: both sides' kinetics >= 20,000 frames/s on one core.
"""

from __future__ import annotations

from _setup import ROOT, VICON, best_of, one_thread

one_thread()

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.names import Side  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.io.subject import read_subject, subject_from_processing  # noqa: E402
from fuzzygait.kinematics import compute_lower_body  # noqa: E402
from fuzzygait.kinetics.assignment import Foot, automatic_assignment, contact_ground  # noqa: E402
from fuzzygait.kinetics.gcv_spline import spline_second_derivative, spline_second_derivatives  # noqa: E402
from fuzzygait.kinetics.inverse_dynamics import ComDerivative  # noqa: E402
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N, read_force_plates  # noqa: E402
from fuzzygait.kinetics.plug_in_gait import foot_length, plug_in_gait_kinetics  # noqa: E402
from fuzzygait.kinetics.segments import leg_segments  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30, help="timed calls per row (best taken)")
    repeats = parser.parse_args().repeats
    path = VICON / "Movement_trial.c3d"
    if path.is_file():
        trial = read_c3d(path)
        subject = subject_from_processing(trial.parameters)
    else:
        path = Path(ROOT / "sample_data" / "walking.c3d")
        print(f"(reference data {VICON} is absent: using {path.relative_to(ROOT)})")
        trial = read_c3d(path)
        subject = read_subject(ROOT / "sample_data" / "subject.toml")
    result = compute_lower_body(trial, subject)
    plates = read_force_plates(path)
    if not plates:
        print(f"{path.name} has no force plates: nothing to time")
        return
    feet = {side: Foot(*(trial.marker(side.value + m) for m in ("HEE", "TOE", "ANK"))) for side in Side}

    def assigned(method: ComDerivative = ComDerivative.GCV_SPLINE) -> object:
        contacts = automatic_assignment(plates, feet, trial.rate, DEFAULT_THRESHOLD_N)
        ground = {side: contact_ground(plates, contacts, side, trial.n_frames, trial.rate) for side in Side}
        return plug_in_gait_kinetics(result, trial, subject, ground, method)

    rng = np.random.default_rng(0)
    t = np.arange(6000) / trial.rate
    long_run = 50.0 * np.sin(2 * np.pi * t)[:, None] + rng.normal(0.0, 0.1, (t.size, 3))

    coms = [segment.com for side in Side for segment in leg_segments(
        result, side, subject.body_mass, foot_length(trial, side, subject.marker_radius))]  # fmt: skip
    contacts = automatic_assignment(plates, feet, trial.rate, DEFAULT_THRESHOLD_N)
    ground = {side: contact_ground(plates, contacts, side, trial.n_frames, trial.rate) for side in Side}
    rows = [
        ("angles: compute_lower_body", best_of(lambda: compute_lower_body(trial, subject), repeats)),
        ("plates read: read_force_plates (once per trial)", best_of(lambda: read_force_plates(path), repeats)),
        ("assignment + inverse dynamics, both sides (GCV spline)", best_of(assigned, repeats)),
        ("inverse dynamics alone, both sides (GCV spline)", best_of(lambda: plug_in_gait_kinetics(
            result, trial, subject, ground), repeats)),
        ("assignment + inverse dynamics, five-point", best_of(lambda: assigned(ComDerivative.FIVE_POINT), repeats)),
        ("inverse dynamics alone, five-point", best_of(lambda: plug_in_gait_kinetics(
            result, trial, subject, ground, ComDerivative.FIVE_POINT), repeats)),
        ("GCV spline alone: one trajectory (LKJC)", best_of(
            lambda: spline_second_derivative(result.joint_centres["LKJC"], trial.rate), repeats)),
        ("GCV spline alone: both legs' six centres of mass together", best_of(
            lambda: spline_second_derivatives(coms, trial.rate), repeats)),
    ]  # fmt: skip
    long_seconds = best_of(lambda: spline_second_derivative(long_run, trial.rate), max(1, repeats // 10))
    frames = trial.n_frames
    angles = rows[0][1]
    print(f"## Kinetics speed: {path.name}, {frames} frames at {trial.rate:g} Hz, {len(plates)} plates; "
          f"one core, best of {repeats}")  # fmt: skip
    print("| what | ms | frames/s | time / angles' time |")
    print("|---|---|---|---|")
    for what, seconds in rows:
        print(f"| {what} | {seconds * 1e3:.2f} | {frames / seconds:,.0f} | {seconds / angles:.2f} |")
    print(f"| GCV spline alone: a 6,000-frame trajectory | {long_seconds * 1e3:.2f} | {6000 / long_seconds:,.0f} | |")


if __name__ == "__main__":
    main()
