"""Plug-in Gait kinetics on CGM 2.3 against pyCGM2's CGM 2.3 kinetics of the shared
Qualisys session (issue 39, acceptance "the same for pyCGM2 ... where its inputs allow").

Run:  .venv/bin/python benchmarks/kinetics_pycgm2.py      (needs ../shared/data/cgm2)

The model: fuzzygait's ``cgm2.3`` on pyCGM2's fitted markers with pyCGM2's own calibrated
geometry and foot offsets (``benchmarks/cgm2_pycgm2.py``, its run (B): thigh and shank
angles within 1e-3 deg of pyCGM2's), body mass 70 kg (session.xml).  The ground: the
plates stored in pyCGM2's output (its 25 Hz low-passed type-2 channels, 2000 Hz), each
marker frame the analog sample at ``20 i`` (checked below against pyCGM2's stored ground
reaction), the whole plate on one foot throughout as pyCGM2 applied it.

Printed: the ground reaction check; per knee and hip moment component the RMS of ours
minus pyCGM2's in Plug-in Gait's distal frames and in the joint coordinate system
(pyCGM2's ``MomentProjection.JCS``: X on the proximal segment's flexion axis (y), Z on
the distal segment's long axis (z), Y on the floating axis ``z_d x y_p``; moments as dot
products, the sign of each component matched); the frame-free magnitudes of the joint
forces and moments; the powers (W/kg).
"""

from __future__ import annotations

from _setup import one_thread

one_thread()

import cgm2_pycgm2 as cgm2  # noqa: E402
import numpy as np  # noqa: E402

from fuzzygait.core.names import Side  # noqa: E402
from fuzzygait.kinetics.inverse_dynamics import ComDerivative, Load  # noqa: E402
from fuzzygait.kinetics.plates import read_force_plates  # noqa: E402
from fuzzygait.kinetics.plug_in_gait import plug_in_gait_kinetics  # noqa: E402

MASS = 70.0
#: plate number -> the foot pyCGM2 put on it (found below: its GRF equals that plate's).
PLATE_FOOT = {1: Side.RIGHT, 2: Side.LEFT}
#: joint -> (distal, proximal) segment frame names (side-prefixed but the pelvis).
FRAMES = {"Knee": ("tibia", "thigh"), "Hip": ("thigh", "pelvis")}


def rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(x**2, axis=0))


def main() -> None:
    if not cgm2.PYCGM2.is_file():
        print(f"reference data {cgm2.PYCGM2} absent")
        return
    session = cgm2.load()
    output, n = session.output, session.output.n_frames
    subject, _ = cgm2.pycgm2_foot_offsets(session, session.subject)
    result = cgm2.run_b(session, subject)
    ground = {}
    print("## pyCGM2's ground reaction: the stored plate force at analog sample 20 i (N, RMS of the difference)")
    for plate in read_force_plates(cgm2.PYCGM2, threshold_n=0.0):
        side = PLATE_FOOT[plate.number]
        force, cop, free = (a[::20][:n] for a in (plate.force, plate.cop, plate.free_moment))
        stored = output.outputs[side.value + "GroundReactionForce"] * MASS
        print(f"plate {plate.number} -> {side.word.lower()} foot: {rms(force - stored).round(6)} on all {n} frames; "
              f"least normal force {force[:, 2].min():.1f} N (an offset pyCGM2 applied in swing too)")  # fmt: skip
        ground[side] = Load(np.zeros((n, 3)), force, np.cross(cop * 1e-3, force) + free * 1e-3)
    kinetics = plug_in_gait_kinetics(result, session.fitted, subject, ground, ComDerivative.GCV_SPLINE)
    print()
    print("| output | unit | pyCGM2 RMS | distal frames (X, Y, Z) | JCS (X, Y, Z) | magnitude |")
    print("|---|---|---|---|---|---|")
    for side in Side:
        long = side.word.lower()
        for joint, (distal, proximal) in FRAMES.items():
            name = side.value + joint + "Moment"
            moment = kinetics.loads[side.value + joint].moment / MASS
            theirs = output.outputs[name] * 1e-3
            ok = np.all(np.isfinite(moment) & np.isfinite(theirs), axis=1)
            e1 = result.segment_frames[proximal if proximal == "pelvis" else f"{long}_{proximal}"][:, :, 1]
            e3 = result.segment_frames[f"{long}_{distal}"][:, :, 2]
            e2 = np.cross(e3, e1)
            e2 /= np.linalg.norm(e2, axis=1)[:, None]
            jcs = np.stack([np.einsum("ni,ni->n", moment, e) for e in (e1, e2, e3)], axis=1)
            signs = [min((1.0, -1.0), key=lambda s: rms(s * jcs[ok, c] - theirs[ok, c])) for c in range(3)]
            distal_rms = rms(kinetics.outputs[name][ok] * 1e-3 - theirs[ok])
            jcs_rms = rms(jcs[ok] * signs - theirs[ok])
            size = rms(np.linalg.norm(moment[ok], axis=1) - np.linalg.norm(theirs[ok], axis=1))
            cells = [", ".join(f"{v:.4f}" for v in values) for values in (rms(theirs[ok]), distal_rms, jcs_rms)]
            print(f"| {name} | N·m/kg | {' | '.join(cells)} | {size:.4f} |")
        for joint in ("Ankle", "Knee", "Hip"):
            name = side.value + joint + "Force"
            ours, theirs = kinetics.outputs[name], output.outputs[name]
            ok = np.all(np.isfinite(ours) & np.isfinite(theirs), axis=1)
            size = rms(np.linalg.norm(ours[ok], axis=1) - np.linalg.norm(theirs[ok], axis=1))
            print(f"| {name} | N/kg | {rms(np.linalg.norm(theirs[ok], axis=1)):.3f} (magnitude) | | | {size:.4f} |")
        for joint in ("Ankle", "Knee", "Hip"):
            name = side.value + joint + "Power"
            ours, theirs = kinetics.outputs[name][:, 2], output.outputs[name][:, 2]
            ok = np.isfinite(ours) & np.isfinite(theirs)
            print(f"| {name} | W/kg | {rms(theirs[ok]):.3f} | Z {rms(ours[ok] - theirs[ok]):.4f} | | |")


if __name__ == "__main__":
    main()
