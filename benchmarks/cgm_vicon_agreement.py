"""Agreement of fuzzygait's Plug-in Gait lower body with Vicon Nexus's stored outputs.

Run:  .venv/bin/python benchmarks/cgm_vicon_agreement.py

Prints Markdown tables (degrees; frames where both values are finite):

1. ``Movement_trial.c3d``: RMS and max difference of every angle component, with the
   subject parameters of the file's PROCESSING group and with ``Test.vsk`` + our static
   calibration of ``Static_trial.c3d``;
2. the static offsets of that calibration against the ones Nexus stored;
3. ``gait-pig.c3d``: pelvis, hip and knee angles decomposed from its segment virtual
   markers (integer-scaled points, so ~0.1 deg is the storage resolution);
4. the synthetic ``sample_data/walking.c3d`` against its truth (always available).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from _setup import ROOT, VICON

from fuzzygait.io import read_c3d
from fuzzygait.io.subject import read_subject, read_vsk, subject_from_processing
from fuzzygait.kinematics import (
    ANGLE_NAMES,
    angles_from_virtual_markers,
    compute_lower_body,
    static_calibration,
)


def stats(ours: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    diff = ours - reference
    diff = diff[np.all(np.isfinite(diff), axis=1)]
    return np.sqrt(np.mean(diff**2, axis=0)), np.abs(diff).max(axis=0)


def agreement_table(title: str, columns: dict[str, dict[str, np.ndarray]], reference: dict[str, np.ndarray],
                    names: list[str]) -> None:  # fmt: skip
    print(f"## {title}")
    head = " | ".join(f"{label} RMS | {label} max" for label in columns)
    print(f"| angle | axis | {head} |")
    print("|---|---|" + "---|---|" * len(columns))
    worst = {label: 0.0 for label in columns}
    for name in names:
        per_source = {label: stats(angles[name], reference[name]) for label, angles in columns.items()}
        for i, axis in enumerate("XYZ"):
            cells = " | ".join(f"{rms[i]:.1e} | {mx[i]:.1e}" for rms, mx in per_source.values())
            print(f"| {name} | {axis} | {cells} |")
        for label, (_, mx) in per_source.items():
            worst[label] = max(worst[label], float(mx.max()))
    print("worst max: " + ", ".join(f"{label} {value:.1e} deg" for label, value in worst.items()))
    print()


def vicon() -> None:
    movement = read_c3d(VICON / "Movement_trial.c3d")
    static = read_c3d(VICON / "Static_trial.c3d")
    calibrated = static_calibration(static, read_vsk(VICON / "Test.vsk"))
    columns = {
        "PROCESSING": compute_lower_body(movement, subject_from_processing(movement.parameters)).angles,
        "VSK+static": compute_lower_body(movement, calibrated).angles,
    }
    agreement_table("Movement_trial.c3d vs Nexus (deg)", columns, movement.outputs, list(ANGLE_NAMES))

    print("## Static calibration of Static_trial.c3d + Test.vsk vs Nexus (rad)")
    print("| parameter | ours | Nexus | difference |")
    print("|---|---|---|---|")
    for side in "LR":
        p = calibrated.side(side)
        for name, value in (("StaticPlantFlex", p.static_plant_flex), ("StaticRotOff", p.static_rot_off)):
            ref = movement.parameters[side + name]
            print(f"| {side}{name} | {value:.9f} | {ref:.9f} | {value - ref:.1e} |")
    print()

    gait = read_c3d(VICON / "gait-pig.c3d")
    names = [f"{s}{j}Angles" for j in ("Pelvis", "Hip", "Knee") for s in "LR"]
    decomposed = {"decomposition": angles_from_virtual_markers(gait.outputs)}
    title = "gait-pig.c3d: angles from its virtual markers vs its outputs (deg)"
    agreement_table(title, decomposed, gait.outputs, names)


def synthetic() -> None:
    sample = ROOT / "sample_data"
    subject = read_subject(sample / "subject.toml")
    for side in "LR":
        subject = subject.with_side(side, static_plant_flex=0.0, static_rot_off=0.0)
    calibrated = static_calibration(read_c3d(sample / "static.c3d"), subject)
    result = compute_lower_body(read_c3d(sample / "walking.c3d"), calibrated)
    truth = pd.read_csv(sample / "walking_truth_angles.csv")
    names = [f"{s}{j}Angles" for j in ("Pelvis", "Hip", "Knee", "Ankle") for s in "LR"]
    reference = {n: truth[[f"{n}_{a}" for a in "XYZ"]].to_numpy() for n in names}
    agreement_table("sample_data/walking.c3d (static calibration of static.c3d) vs truth (deg)",
                    {"synthetic": result.angles}, reference, names)  # fmt: skip


def main() -> None:
    if VICON.is_dir():
        vicon()
    else:
        print(f"Vicon comparison skipped: {VICON} is absent\n")
    synthetic()


if __name__ == "__main__":
    main()
