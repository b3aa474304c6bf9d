"""Speed of the vectorised Plug-in Gait lower body against a per-frame loop.

Run:  .venv/bin/python benchmarks/cgm_speed.py

Tiles the markers of ``../shared/data/vicon/Movement_trial.c3d`` (or, when the reference
data is absent, of ``sample_data/walking.c3d``) to at least 30,000 frames and times
``fuzzygait.kinematics.compute_lower_body`` (pelvis, joint centres, all segment frames,
all ten angle outputs of both sides and the virtual markers).  For scale, the same maths
is run frame by frame in a Python loop (the per-frame style of e.g. pyCGM) on a subset of
frames, checked to give identical angles, and extrapolated to frames per second.  Both
run on one core (BLAS threads pinned to 1).  The vectorised model is timed again with every
Plug-in Gait option on (the KAD + medial malleolus offsets of ``PiGKadMed_Motion.c3d``:
thigh and shank wand rotations, tibial torsion, ankle ab/adduction), target >= 100,000
frames/s.
"""

from __future__ import annotations

from _setup import ROOT, VICON, one_thread

one_thread()

import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from fuzzygait.core.trial import Trial  # noqa: E402
from fuzzygait.io import read_c3d  # noqa: E402
from fuzzygait.io.subject import SubjectParameters, read_subject, subject_from_processing  # noqa: E402
from fuzzygait.kinematics import ANGLE_NAMES, compute_lower_body  # noqa: E402
from fuzzygait.kinematics.angles import joint_angles  # noqa: E402
from fuzzygait.kinematics.joint_centres import chord_joint_centre, davis_hjc_local  # noqa: E402
from fuzzygait.kinematics.pelvis import pelvis_frame  # noqa: E402
from fuzzygait.kinematics.segments import (  # noqa: E402
    corrected_foot,
    long_bone_frame,
    uncorrected_foot,
    untorsioned_tibia,
)
from fuzzygait.kinematics.vectors import to_lab  # noqa: E402

MIN_FRAMES = 30_000
#: Offsets (rad) with every option on: those Nexus calibrated for PiGKadMed (left / right).
ALL_OPTIONS = {
    "L": dict(thigh_rotation=0.156355, shank_rotation=0.068011, tibial_torsion=-0.209494, ankle_abadd=0.201038),
    "R": dict(thigh_rotation=-0.175377, shank_rotation=0.009645, tibial_torsion=-0.309535, ankle_abadd=0.151991),
}
LOOP_FRAMES = 600
REPEATS = 5


def load() -> tuple[Trial, SubjectParameters, str]:
    path = VICON / "Movement_trial.c3d"
    if path.is_file():
        trial = read_c3d(path)
        return trial, subject_from_processing(trial.parameters), path.name
    print(f"(reference data {VICON} is absent: using the synthetic sample_data/walking.c3d)")
    trial = read_c3d(ROOT / "sample_data" / "walking.c3d")
    return trial, read_subject(ROOT / "sample_data" / "subject.toml"), "sample_data/walking.c3d"


def tiled(trial: Trial, n_min: int) -> Trial:
    reps = -(-n_min // trial.n_frames)
    markers = np.tile(trial.markers, (reps, 1, 1))
    return replace(trial, markers=markers, outputs={}, output_kinds={}, events=[])


def per_frame(
    trial: Trial, subject: SubjectParameters, progression: np.ndarray, frame: int
) -> dict[str, np.ndarray]:
    """The model's maths on one frame (``(1, 3)`` arrays), as a per-frame pipeline would."""

    def m(label: str) -> np.ndarray:
        return trial.markers[frame : frame + 1, trial.marker_labels.index(label), :]

    origin, pelvis = pelvis_frame(m("LASI"), m("RASI"), 0.5 * (m("LPSI") + m("RPSI")))
    mean_leg = 0.5 * (subject.left.leg_length + subject.right.leg_length)
    out = {}
    for side in "LR":
        p = subject.side(side)
        r = subject.marker_radius
        local = davis_hjc_local(mean_leg, p.asis_trochanter, subject.inter_asis_distance, r, side)
        hjc = to_lab(pelvis, origin, local)
        kjc = chord_joint_centre(m(side + "THI"), hjc, m(side + "KNE"), p.knee_width / 2 + r)
        ajc = chord_joint_centre(m(side + "TIB"), kjc, m(side + "ANK"), p.ankle_width / 2 + r)
        thigh = long_bone_frame(hjc, kjc, m(side + "KNE"), side)
        tibia_t = long_bone_frame(kjc, ajc, m(side + "ANK"), side)
        tibia = untorsioned_tibia(tibia_t, p.tibial_torsion, side)
        foot = corrected_foot(uncorrected_foot(ajc, m(side + "TOE"), tibia_t[:, :, 1]),
                              p.static_plant_flex, p.static_rot_off, side)  # fmt: skip
        out[side + "PelvisAngles"] = joint_angles(progression, pelvis, "Pelvis", side)
        out[side + "HipAngles"] = joint_angles(pelvis, thigh, "Hip", side)
        out[side + "KneeAngles"] = joint_angles(thigh, tibia, "Knee", side)
        out[side + "AnkleAngles"] = joint_angles(tibia_t, foot, "Ankle", side)
        out[side + "FootProgressAngles"] = joint_angles(progression, foot, "FootProgress", side)
    return out


def best_time(big: Trial, subject: SubjectParameters) -> float:
    """Best of :data:`REPEATS` runs of ``compute_lower_body`` after a warm-up, s."""
    compute_lower_body(big, subject)
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        compute_lower_body(big, subject)
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    trial, subject, name = load()
    big = tiled(trial, MIN_FRAMES)
    vec_s = best_time(big, subject)
    result = compute_lower_body(big, subject)
    every_option = subject.with_side("L", **ALL_OPTIONS["L"]).with_side("R", **ALL_OPTIONS["R"])
    options_s = best_time(big, every_option)

    frames = np.linspace(0, big.n_frames - 1, LOOP_FRAMES).astype(int)
    start = time.perf_counter()
    looped = [per_frame(big, subject, result.progression, i) for i in frames]
    loop_s = time.perf_counter() - start
    worst = max(
        np.abs(looped[k][n][0] - result.angles[n][i]).max() for k, i in enumerate(frames) for n in ANGLE_NAMES
    )
    assert worst < 1e-9, f"per-frame loop differs from the vectorised model by {worst} deg"

    vec_rate = big.n_frames / vec_s
    loop_rate = LOOP_FRAMES / loop_s
    print(f"## Plug-in Gait lower body speed ({name} tiled to {big.n_frames} frames, one core)")
    print("| implementation | frames timed | seconds | frames/s |")
    print("|---|---|---|---|")
    label = f"vectorised `compute_lower_body` (best of {REPEATS})"
    print(f"| {label} | {big.n_frames} | {vec_s:.3f} | {vec_rate:,.0f} |")
    options_rate = big.n_frames / options_s
    print(f"| the same, every option on (KAD + MED offsets) | {big.n_frames} | {options_s:.3f} | {options_rate:,.0f} |")
    print(f"| per-frame loop, same maths (extrapolated) | {LOOP_FRAMES} | {loop_s:.3f} | {loop_rate:,.0f} |")
    print(f"| ratio vectorised / loop | | | {vec_rate / loop_rate:,.0f}x |")
    print(f"(per-frame loop agrees with the vectorised angles to {worst:.1e} deg; target >= 50,000 frames/s: "
          f"{'met' if vec_rate >= 50_000 else 'NOT met'}; every option on >= 100,000 frames/s: "
          f"{'met' if options_rate >= 100_000 else 'NOT met'})")  # fmt: skip


if __name__ == "__main__":
    main()
