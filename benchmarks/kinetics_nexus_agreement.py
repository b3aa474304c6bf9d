"""Agreement of fuzzygait's Plug-in Gait kinetics with the kinetics Vicon Nexus stored.

Run:  .venv/bin/python benchmarks/kinetics_nexus_agreement.py

For each shared Nexus trial with stored kinetics and a body mass: the model on the
file's own ``PROCESSING`` parameters (its angles then equal Nexus'), the plates read by
:func:`fuzzygait.kinetics.plates.read_force_plates` at the analog rate, and on each foot
the plate Nexus put there frame by frame (:func:`fuzzygait.kinetics.assignment.stored_assignment`).
Runs:

* ``all samples``: every analog sample of the assigned plate (threshold 0 N), as Nexus,
  the centres of mass differentiated as Nexus does (quintic GCV smoothing spline,
  ``ComDerivative.GCV_SPLINE``);
* ``five-point``: the same with the five-point differences (``ComDerivative.FIVE_POINT``,
  local, as the fuzzy kinetics' nine-frame windows);
* ``contact``: only the samples above the reader's contact threshold (10 N);
* ``automatic assignment``: the contacts (10 N) assigned by our own rule
  (:func:`fuzzygait.kinetics.assignment.automatic_assignment`), as the pipeline will run.

Prints per trial, output and component the RMS and max difference over the frames where
Nexus has an output (moments N·m/kg, powers W/kg, GRF % body weight), and the RMS without
Nexus' first and last three output frames (``inner``).  ``gait-pig.c3d`` is listed but not
compared: it stores no body mass, and its moments are per kilogram.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from _setup import VICON, one_thread

one_thread()

import numpy as np  # noqa: E402

from fuzzygait.core.names import Side  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.io.subject import subject_from_processing  # noqa: E402
from fuzzygait.kinematics import compute_lower_body  # noqa: E402
from fuzzygait.kinetics.assignment import (  # noqa: E402
    Foot,
    assigned_ground,
    automatic_assignment,
    contact_ground,
    stored_assignment,
)
from fuzzygait.kinetics.inverse_dynamics import ComDerivative  # noqa: E402
from fuzzygait.kinetics.plates import DEFAULT_THRESHOLD_N, read_force_plates  # noqa: E402
from fuzzygait.kinetics.plug_in_gait import JOINTS, plug_in_gait_kinetics  # noqa: E402

DATA = VICON.parent


@dataclass(frozen=True)
class Case:
    name: str
    path: str
    marker_diameter: float | None = None


CASES = (
    Case("Movement_trial (Nexus 1.8)", "vicon/Movement_trial.c3d"),
    Case("PiGKad (Nexus 2.3)", "pig-options/PiGKad_Motion.c3d"),
    Case("PiGKadMed (Nexus 2.3)", "pig-options/PiGKadMed_Motion.c3d"),
    Case("FlatFoot (Nexus 1.4, 16 mm)", "pig-options/PiG_Motion-FlatFoot-Full.c3d", 16.0),
)
#: output suffix -> (unit, factor from Nexus' unit, components compared)
QUANTITIES = {"Moment": ("N·m/kg", 1e-3, (0, 1, 2)), "Power": ("W/kg", 1.0, (2,)), "Force": ("N/kg", 1.0, (0, 1, 2))}
EDGE = 3  # Nexus output frames left out at each end for the "inner" column


def kinetics(case: Case, threshold_n: float, automatic: bool = False,
             method: ComDerivative = ComDerivative.GCV_SPLINE) -> tuple[dict[str, np.ndarray],
                                                                        dict[str, np.ndarray], str]:  # fmt: skip
    """Our outputs, Nexus', and a note on the plates used (``automatic``: our own
    assignment, :func:`~fuzzygait.kinetics.assignment.automatic_assignment`; ``method``:
    how the centres of mass are differentiated)."""
    path = DATA / case.path
    trial = read_c3d(path)
    subject = subject_from_processing(trial.parameters)
    if case.marker_diameter is not None:
        subject = replace(subject, marker_diameter=case.marker_diameter)
    result = compute_lower_body(trial, subject)
    every_sample = read_force_plates(path, threshold_n=0.0)
    plates = read_force_plates(path, threshold_n=threshold_n)
    ground, notes = {}, []
    if automatic:
        feet = {side: Foot(*(trial.marker(side.value + m) for m in ("HEE", "TOE", "ANK"))) for side in Side}
        contacts = automatic_assignment(plates, feet, trial.rate, threshold_n)
        ground = {side: contact_ground(plates, contacts, side, trial.n_frames, trial.rate) for side in Side}
        ours = plug_in_gait_kinetics(result, trial, subject, ground, method).outputs
        used = [f"plate {c.plate} frames {c.first}-{c.last}: {c.describe()}" for c in contacts]
        return ours, trial.outputs, "; ".join(used)
    for side in Side:
        assigned = stored_assignment(every_sample, trial.outputs, side, subject.body_mass, trial.rate)
        ground[side] = assigned_ground(plates, assigned.plate, trial.rate)
        used = sorted(set(assigned.plate[assigned.plate > 0].tolist()))
        unmatched = f", {int(assigned.unmatched.sum())} unmatched" if assigned.unmatched.any() else ""
        frames = int((assigned.plate > 0).sum())
        notes.append(f"{side.value}: plate {'+'.join(map(str, used))}, {frames} frames{unmatched}")
    ours = plug_in_gait_kinetics(result, trial, subject, ground, method).outputs
    return ours, trial.outputs, "; ".join(notes)


def stats(ours: np.ndarray, nexus: np.ndarray) -> tuple[float, float, float]:
    """RMS, max over the frames Nexus has; RMS without its EDGE first and last frames."""
    frames = np.flatnonzero(np.isfinite(nexus))
    diff = ours[frames] - nexus[frames]
    inner = diff[(frames >= frames[0] + EDGE) & (frames <= frames[-1] - EDGE)]
    return float(np.sqrt(np.mean(diff**2))), float(np.abs(diff).max()), float(np.sqrt(np.mean(inner**2)))


#: summary rows: (case, run, quantity) -> (worst RMS, its output, worst inner RMS)
SUMMARY: dict[tuple[str, str, str], tuple[float, str, float]] = {}
#: (output, axis, unit) -> case -> (RMS, inner RMS, five-point RMS) with every sample (the compact table)
COMPACT: dict[tuple[str, str, str], dict[str, tuple[float, float, float]]] = {}
ALL, FIVE = "all samples", "all samples, five-point"


def note_worst(key: tuple[str, str, str], label: str, rms: float, inner: float) -> None:
    worst, name, worst_inner = SUMMARY.get(key, (0.0, "", 0.0))
    SUMMARY[key] = (rms, label, max(worst_inner, inner)) if rms > worst else (worst, name, max(worst_inner, inner))


def table(case: Case) -> None:
    spline, five = ComDerivative.GCV_SPLINE, ComDerivative.FIVE_POINT
    runs = {label: kinetics(case, threshold, automatic, method) for label, threshold, automatic, method in
            ((ALL, 0.0, False, spline), (FIVE, 0.0, False, five),
             (f"contact > {DEFAULT_THRESHOLD_N:g} N", DEFAULT_THRESHOLD_N, False, spline),
             ("automatic assignment", DEFAULT_THRESHOLD_N, True, spline))}  # fmt: skip
    print(f"## {case.name}: {case.path}")
    print("plates (from Nexus' stored GRF): " + next(iter(runs.values()))[2])
    print("automatic assignment: " + runs["automatic assignment"][2])
    print()
    head = " | ".join(f"{label} RMS | max | inner RMS" for label in runs)
    print(f"| output | unit | axis | {head} |")
    print("|---|---|---|" + "---|---|---|" * len(runs))
    for side in "LR":
        rows = [(f"{side}{joint}{q}", unit, factor, axes) for q, (unit, factor, axes) in QUANTITIES.items()
                for joint in JOINTS]  # fmt: skip
        rows.append((f"{side}NormalisedGRF", "% BW", 1.0, (0, 1, 2)))
        for name, unit, factor, axes in rows:
            for axis in axes:
                cells = []
                for label, (ours, nexus, _) in runs.items():
                    if name not in nexus:
                        cells.append("- | - | -")
                        continue
                    rms, worst, inner = stats(ours[name][:, axis] * factor, nexus[name][:, axis] * factor)
                    cells.append(f"{rms:.4f} | {worst:.4f} | {inner:.4f}")
                    if "Force" not in name:
                        note_worst((case.name, label, unit), f"{name} {'XYZ'[axis]}", rms, inner)
                        if label in (ALL, FIVE):
                            cell = COMPACT.setdefault((name, "XYZ"[axis], unit), {})
                            old = cell.get(case.name, (0.0, 0.0, 0.0))
                            cell[case.name] = (rms, inner, old[2]) if label == ALL else (old[0], old[1], rms)
                print(f"| {name} | {unit} | {'XYZ'[axis]} | {' | '.join(cells)} |")
    print()


def main() -> None:
    if not DATA.is_dir():
        print(f"reference data {DATA} absent")
        return
    for case in CASES:
        table(case)
    print("gait-pig.c3d: not compared (no Bodymass stored; its kinetics are per kilogram).")
    print()
    print("## Summary: the worst component RMS of each kind (inner: without Nexus' 3 edge frames)")
    print("| trial | ground load | unit | worst RMS | output | worst inner RMS |")
    print("|---|---|---|---|---|---|")
    for (name, label, unit), (rms, output, inner) in SUMMARY.items():
        print(f"| {name} | {label} | {unit} | {rms:.4f} | {output} | {inner:.4f} |")
    print()
    print("## Every component, every analog sample, GCV spline: RMS (inner RMS where it differs by more than "
          "0.001) [five-point differences' RMS]")
    print("| output | axis | unit | " + " | ".join(case.name for case in CASES) + " |")
    print("|---|---|---|" + "---|" * len(CASES))
    for (name, axis, unit), per_case in COMPACT.items():
        cells = []
        for case in CASES:
            rms, inner, five = per_case.get(case.name, (float("nan"),) * 3)
            cells.append(f"{rms:.4f}" + (f" ({inner:.4f})" if abs(rms - inner) > 1e-3 else "") + f" [{five:.4f}]")
        print(f"| {name} | {axis} | {unit} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
